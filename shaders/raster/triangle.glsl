// Perspective-correct barycentrics of a camera-space triangle along a pixel ray, shared by the
// resolve and the interior backward. Expects a `camera_positions` (vec4) buffer and `faces`.
#ifndef RASTER_TRIANGLE_GLSL
#define RASTER_TRIANGLE_GLSL

struct RayHit {
    vec3 s;      // signed volumes d.(v1 x v2), d.(v2 x v0), d.(v0 x v1)
    float sum;   // their sum; barycentrics are s / sum
};

void triangle_corners(uint t, out uvec3 ids, out vec3 v0, out vec3 v1, out vec3 v2) {
    ids = uvec3(faces[3u * t], faces[3u * t + 1u], faces[3u * t + 2u]);
    v0 = camera_positions[ids.x].xyz;
    v1 = camera_positions[ids.y].xyz;
    v2 = camera_positions[ids.z].xyz;
}

// Where ray d (from the camera centre) meets the plane of (v0, v1, v2), as barycentrics.
RayHit ray_hit(vec3 d, vec3 v0, vec3 v1, vec3 v2) {
    vec3 s = vec3(dot(d, cross(v1, v2)), dot(d, cross(v2, v0)), dot(d, cross(v0, v1)));
    return RayHit(s, s.x + s.y + s.z);
}

// Camera-space normal direction (not normalized); a triangle faces the camera when
// dot(normal, v0) < 0 (counter-clockwise seen from outside).
vec3 face_normal(vec3 v0, vec3 v1, vec3 v2) {
    return cross(v1 - v0, v2 - v0);
}

#endif
