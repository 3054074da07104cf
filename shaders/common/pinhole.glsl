// The pinhole projection's backward, shared by the terms that pull a vertex's pixel
// (silhouette, coverage); engine/camera.rs `Camera::pixel_gradient_to_world` is its reference.
#ifndef COMMON_PINHOLE_GLSL
#define COMMON_PINHOLE_GLSL

// dE/dx for a world point x with camera-space position c = world_to_camera · x, from dE/dq of
// its pixel q = (fx c.x / c.z + cx, fy c.y / c.z + cy) (any constant offset of q alike);
// k = (fx, fy, cx, cy).
vec3 pinhole_backward(mat4 world_to_camera, vec4 k, vec3 c, vec2 dq) {
    vec3 dc = vec3(dq.x * k.x / c.z, dq.y * k.y / c.z, -(dq.x * k.x * c.x + dq.y * k.y * c.y) / (c.z * c.z));
    return transpose(mat3(world_to_camera)) * dc;
}

#endif
