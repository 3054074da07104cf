#version 460
// Interior backward: one invocation per covered pixel. From dL/d(resolved rgb) adds vertex
// colour gradients (b_k g) and vertex position gradients through the perspective-correct
// barycentrics b_k = s_k / sum(s), s_0 = d.(v1 x v2) and cyclic (the mask is 1 inside, so
// it has no interior gradient).
#extension GL_EXT_shader_atomic_float : require
#include "raster.glsl"

layout(local_size_x = 16, local_size_y = 16) in;

layout(std430, binding = 0) readonly buffer Faces { uint faces[]; };
layout(std430, binding = 1) readonly buffer CameraPositions { vec4 camera_positions[]; };
layout(std430, binding = 2) readonly buffer Colors { float colors[]; };
layout(std430, binding = 3) readonly buffer Ids { uint ids[]; };
layout(std430, binding = 4) readonly buffer GradRgba { vec4 grad_rgba[]; };
layout(std430, binding = 5) buffer GradPositions { float grad_positions[]; };
layout(std430, binding = 6) buffer GradColors { float grad_colors[]; };

#include "triangle.glsl"

vec3 vertex_color(uint v) {
    return vec3(colors[3u * v], colors[3u * v + 1u], colors[3u * v + 2u]);
}

void add3(uint v, vec3 g, bool to_colors) {
    for (uint k = 0u; k < 3u; k++) {
        if (to_colors) {
            atomicAdd(grad_colors[3u * v + k], g[k]);
        } else {
            atomicAdd(grad_positions[3u * v + k], g[k]);
        }
    }
}

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= image_width() || pixel.y >= image_height()) {
        return;
    }
    uint i = pixel_index(ivec2(pixel));
    uint t = ids[i];
    if (t == NO_TRIANGLE) {
        return;
    }
    uvec3 v;
    vec3 v0, v1, v2;
    triangle_corners(t, v, v0, v1, v2);
    vec3 d = pixel_ray(pixel);
    RayHit hit = ray_hit(d, v0, v1, v2);
    if (hit.sum == 0.0) {
        return;
    }
    vec3 b = hit.s / hit.sum;
    vec3 g = grad_rgba[i].rgb;
    add3(v.x, b.x * g, true);
    add3(v.y, b.y * g, true);
    add3(v.z, b.z * g, true);
    vec3 g_b = vec3(dot(g, vertex_color(v.x)), dot(g, vertex_color(v.y)), dot(g, vertex_color(v.z)));
    vec3 g_s = (g_b - dot(g_b, b)) / hit.sum;
    mat3 to_world = transpose(view_rotation());
    add3(v.x, to_world * (g_s.y * cross(d, v2) + g_s.z * cross(v1, d)), false);
    add3(v.y, to_world * (g_s.x * cross(v2, d) + g_s.z * cross(d, v0)), false);
    add3(v.z, to_world * (g_s.x * cross(d, v1) + g_s.y * cross(v0, d)), false);
}
