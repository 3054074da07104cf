#version 460
// Anti-aliasing, backward: one invocation per pixel, reading the crossings aa_pairs.comp
// stored. Writes dL/d(resolved rgb, mask) of its pixel (the identity plus the blends of its four pairs), and for the pairs it owns (right and
// down neighbour) adds dL/dt through the crossing edge to that edge's two vertex positions
// (fixed-point sums: order-independent, so runs repeat bit for bit).
#include "raster.glsl"
#include "../common/fixed_sum.glsl"

layout(local_size_x = 16, local_size_y = 16) in;

layout(std430, binding = 0) readonly buffer Faces { uint faces[]; };
layout(std430, binding = 1) readonly buffer CameraPositions { vec4 camera_positions[]; };
layout(std430, binding = 3) readonly buffer Rgba { vec4 rgba[]; };
layout(std430, binding = 4) readonly buffer GradColor { float grad_color[]; };
layout(std430, binding = 5) readonly buffer GradMask { float grad_mask[]; };
layout(std430, binding = 6) writeonly buffer GradRgba { vec4 grad_rgba[]; };
layout(std430, binding = 7) buffer GradPositionSums { int64_t grad_position_sums[]; };

#include "triangle.glsl"
#include "blend.glsl"

layout(std430, binding = 2) readonly buffer Pairs { PairRecord pairs[]; };

#include "pairs.glsl"

vec4 output_gradient(ivec2 p) {
    uint i = pixel_index(p);
    return vec4(grad_color[3u * i], grad_color[3u * i + 1u], grad_color[3u * i + 2u], grad_mask[i]);
}

// Adds dL/d(screen position) of camera-space vertex v to its world position gradient.
void add_screen_gradient(uint v, vec2 g) {
    vec3 c = camera_positions[v].xyz;
    vec2 gf = g * params.intrinsics.xy / c.z;
    vec3 g_camera = vec3(gf, -dot(gf, c.xy) / c.z);
    vec3 g_world = transpose(view_rotation()) * g_camera;
    for (uint k = 0u; k < 3u; k++) {
        FIXED_ADD_GRADIENT(grad_position_sums, 3u * v + k, g_world[k]);
    }
}

// dL/dt of crossing c spread over its edge's end points, t = E(a) / (E(a) - E(b)).
void edge_backward(Crossing c, float grad_t) {
    uvec3 v;
    vec3 p[3];
    triangle_corners(c.triangle, v, p[0], p[1], p[2]);
    uint k0 = c.edge, k1 = (c.edge + 1u) % 3u;
    vec2 e0 = project_point(p[k0]), e1 = project_point(p[k1]);
    vec2 a = pixel_centre(c.covered), b = pixel_centre(c.other);
    float ea = screen_edge(e0, e1, a), eb = screen_edge(e0, e1, b);
    float scale = grad_t / ((ea - eb) * (ea - eb));
    // dE(x)/de0 = (e1.y - x.y, x.x - e1.x), dE(x)/de1 = (x.y - e0.y, e0.x - x.x).
    vec2 de0_a = vec2(e1.y - a.y, a.x - e1.x), de0_b = vec2(e1.y - b.y, b.x - e1.x);
    vec2 de1_a = vec2(a.y - e0.y, e0.x - a.x), de1_b = vec2(b.y - e0.y, e0.x - b.x);
    add_screen_gradient(v[k0], scale * (ea * de0_b - eb * de0_a));
    add_screen_gradient(v[k1], scale * (ea * de1_b - eb * de1_a));
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (!in_image(p)) {
        return;
    }
    vec4 g_p = output_gradient(p);
    vec4 g_resolved = g_p;
    for (uint k = 0u; k < 4u; k++) {
        ivec2 q;
        Crossing c;
        if (!pair_around(p, k, q, c)) {
            continue;
        }
        float w;
        ivec2 target = blend_target(c, w);
        vec4 g_target = output_gradient(target);
        // out_target += w (c_other - c_target): p is the target or the other pixel.
        g_resolved += target == p ? -w * g_p : w * g_target;
        if (k < 2u) {
            vec4 jump = rgba[pixel_index(c.covered)] - rgba[pixel_index(c.other)];
            edge_backward(c, dot(jump, g_target));
        }
    }
    grad_rgba[pixel_index(p)] = g_resolved;
}
