#version 460
// Interior backward: one invocation per pixel. From dL/d(resolved rgb) of a covered pixel:
// vertex colour gradients b_k g and vertex position gradients through the perspective-correct
// barycentrics b_k = s_k / sum(s), s_0 = d.(v1 x v2) and cyclic (the mask is 1 inside, so it
// has no interior gradient). Lanes of a subgroup on the same triangle sum their gradients
// first and one of them adds them, so a large triangle does not serialize on its 18 sums
// (fixed point: order-independent, so runs repeat bit for bit).
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_shuffle : require
#include "raster.glsl"
#include "../common/fixed_sum.glsl"

layout(local_size_x = 16, local_size_y = 16) in;

layout(std430, binding = 0) readonly buffer Faces { uint faces[]; };
layout(std430, binding = 1) readonly buffer CameraPositions { vec4 camera_positions[]; };
layout(std430, binding = 2) readonly buffer Colors { float colors[]; };
layout(std430, binding = 3) readonly buffer Ids { uint ids[]; };
layout(std430, binding = 4) readonly buffer GradRgba { vec4 grad_rgba[]; };
layout(std430, binding = 5) buffer GradPositionSums { int64_t grad_position_sums[]; };
layout(std430, binding = 6) buffer GradColorSums { int64_t grad_color_sums[]; };

#include "triangle.glsl"

vec3 vertex_color(uint v) {
    return vec3(colors[3u * v], colors[3u * v + 1u], colors[3u * v + 2u]);
}

void add3(uint v, vec3 g, bool to_colors) {
    for (uint k = 0u; k < 3u; k++) {
        if (to_colors) {
            FIXED_ADD_GRADIENT(grad_color_sums, 3u * v + k, g[k]);
        } else {
            FIXED_ADD_GRADIENT(grad_position_sums, 3u * v + k, g[k]);
        }
    }
}

// This pixel's triangle and its gradients: colours (per corner) and world positions (per
// corner); false when the pixel contributes nothing.
bool pixel_gradients(out uint t, out uvec3 v, out vec3 g_color[3], out vec3 g_position[3]) {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= image_width() || pixel.y >= image_height()) {
        return false;
    }
    uint i = pixel_index(ivec2(pixel));
    t = ids[i];
    if (t == NO_TRIANGLE) {
        return false;
    }
    vec3 v0, v1, v2;
    triangle_corners(t, v, v0, v1, v2);
    vec3 d = pixel_ray(pixel);
    RayHit hit = ray_hit(d, v0, v1, v2);
    if (hit.sum == 0.0) {
        return false;
    }
    vec3 b = hit.s / hit.sum;
    vec3 g = grad_rgba[i].rgb;
    g_color = vec3[3](b.x * g, b.y * g, b.z * g);
    vec3 g_b = vec3(dot(g, vertex_color(v.x)), dot(g, vertex_color(v.y)), dot(g, vertex_color(v.z)));
    vec3 g_s = (g_b - dot(g_b, b)) / hit.sum;
    mat3 to_world = transpose(view_rotation());
    g_position[0] = to_world * (g_s.y * cross(d, v2) + g_s.z * cross(v1, d));
    g_position[1] = to_world * (g_s.x * cross(v2, d) + g_s.z * cross(d, v0));
    g_position[2] = to_world * (g_s.x * cross(d, v1) + g_s.y * cross(v0, d));
    return true;
}

void main() {
    uint t = NO_TRIANGLE;
    uvec3 v = uvec3(0u);
    vec3 g_color[3] = vec3[3](vec3(0.0), vec3(0.0), vec3(0.0));
    vec3 g_position[3] = g_color;
    bool pending = pixel_gradients(t, v, g_color, g_position);
    // One round per distinct triangle in the subgroup (control flow stays uniform).
    for (;;) {
        uvec4 waiting = subgroupBallot(pending);
        if (waiting == uvec4(0u)) {
            break;
        }
        uint leader = subgroupBallotFindLSB(waiting);
        bool mine = pending && t == subgroupShuffle(t, leader);
        vec3 sum_color[3], sum_position[3];
        for (uint k = 0u; k < 3u; k++) {
            sum_color[k] = subgroupAdd(mine ? g_color[k] : vec3(0.0));
            sum_position[k] = subgroupAdd(mine ? g_position[k] : vec3(0.0));
        }
        if (gl_SubgroupInvocationID == leader) {
            for (uint k = 0u; k < 3u; k++) {
                add3(v[k], sum_color[k], true);
                add3(v[k], sum_position[k], false);
            }
        }
        pending = pending && !mine;
    }
}
