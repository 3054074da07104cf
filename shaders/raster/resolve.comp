#version 460
// Resolve: one invocation per pixel. From the visibility buffer: triangle id, perspective-
// correct barycentrics, interpolated vertex colour with coverage (rgb, mask), view depth and
// the world-space unit face normal. Uncovered pixels get id NO_TRIANGLE and zeros.
#include "raster.glsl"

layout(local_size_x = 16, local_size_y = 16) in;

layout(std430, binding = 0) readonly buffer Visibility { uvec2 visibility[]; };
layout(std430, binding = 1) readonly buffer Faces { uint faces[]; };
layout(std430, binding = 2) readonly buffer CameraPositions { vec4 camera_positions[]; };
layout(std430, binding = 3) readonly buffer Colors { float colors[]; };
layout(std430, binding = 4) writeonly buffer Ids { uint ids_out[]; };
layout(std430, binding = 5) writeonly buffer Barycentrics { vec4 barycentrics[]; };
layout(std430, binding = 6) writeonly buffer Rgba { vec4 rgba[]; };
layout(std430, binding = 7) writeonly buffer Depth { float depth[]; };
layout(std430, binding = 8) writeonly buffer Normals { vec4 normals[]; };

#include "triangle.glsl"

vec3 vertex_color(uint v) {
    return vec3(colors[3u * v], colors[3u * v + 1u], colors[3u * v + 2u]);
}

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= image_width() || pixel.y >= image_height()) {
        return;
    }
    uint i = pixel_index(ivec2(pixel));
    // Little-endian: the low word (.x) of the 64-bit key is the triangle id.
    uint t = visibility[i].x;
    if (t == NO_TRIANGLE) {
        ids_out[i] = NO_TRIANGLE;
        barycentrics[i] = vec4(0.0);
        rgba[i] = vec4(0.0);
        depth[i] = 0.0;
        normals[i] = vec4(0.0);
        return;
    }
    uvec3 v;
    vec3 v0, v1, v2;
    triangle_corners(t, v, v0, v1, v2);
    vec3 d = pixel_ray(pixel);
    RayHit hit = ray_hit(d, v0, v1, v2);
    // Covered pixels have screen area, so the sum is non-zero but for rounding.
    vec3 b = hit.sum != 0.0 ? hit.s / hit.sum : vec3(1.0 / 3.0);
    vec3 point = b.x * v0 + b.y * v1 + b.z * v2;
    vec3 n = transpose(view_rotation()) * face_normal(v0, v1, v2);
    ids_out[i] = t;
    barycentrics[i] = vec4(b, 0.0);
    rgba[i] = vec4(b.x * vertex_color(v.x) + b.y * vertex_color(v.y) + b.z * vertex_color(v.z), 1.0);
    depth[i] = point.z;
    normals[i] = vec4(n / max(length(n), 1e-30), 0.0);
}
