#version 460
// Long-range silhouette term: every vertex must project inside every view's mask. One
// invocation per vertex i sums over views v
//   E = s Σ_v (D_v(π_v(x_i)) / max(W_v, H_v))²,
// D_v the mask's distance field (engine/loss/silhouette/distance.rs) sampled bilinearly at pixel
// centres, continued outside the image by the distance to its border; s = weight / (vertices ·
// views with a mask). The gradient pulls a vertex outside a mask towards it from any distance.
// Each invocation writes only its own gradient row (adds to it), so no atomics but the loss's
// (a fixed-point sum: order-independent, so runs repeat bit for bit). The views' fields may be
// split over several buffers (engine/loss/silhouette/mod.rs): one dispatch scores the views
// first_view .. first_view + views, whose fields are in the bound buffer.
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "../common/grid.glsl"
#include "../common/fixed_sum.glsl"
#include "../common/pinhole.glsl"
layout(local_size_x_id = 0) in;

// Mirrors engine/loss/pinhole_view.rs (`PinholeView`).
struct View {
    mat4 world_to_camera;
    vec4 intrinsics;  // fx, fy, cx, cy (pixel centres at +0.5)
    uvec4 dims;       // width, height, offset of its field in its buffer, 1 when it has a mask
};

layout(push_constant) uniform Push {
    uint vertices;
    uint first_view;
    uint views;
    float scale;  // s above
    float near;
} pc;

layout(std430, binding = 0) readonly buffer Positions { float positions[]; };
layout(std430, binding = 1) readonly buffer Views { View views[]; };
layout(std430, binding = 2) readonly buffer Fields { float fields[]; };
layout(std430, binding = 3) buffer GradPositions { float grad_positions[]; };
layout(std430, binding = 4) buffer LossSum { int64_t loss_sum[]; };

// D at index coordinates q (pixel centres at integers) and dD/dq.
vec3 field_at(View view, vec2 q) {
    uvec2 size = view.dims.xy;
    vec2 inside = clamp(q, vec2(0.0), vec2(size - 1u));
    vec2 base = min(floor(inside), vec2(size - 2u));
    vec2 f = inside - base;
    uint at = view.dims.z + uint(base.y) * size.x + uint(base.x);
    float d00 = fields[at], d10 = fields[at + 1u], d01 = fields[at + size.x], d11 = fields[at + size.x + 1u];
    float value = mix(mix(d00, d10, f.x), mix(d01, d11, f.x), f.y);
    vec2 slope = vec2(mix(d10 - d00, d11 - d01, f.y), mix(d01 - d00, d11 - d10, f.x));
    // Clamped axes have no slope inside; the way out adds the distance to the border.
    slope *= vec2(equal(inside, q));
    vec2 out_of = q - inside;
    float beyond = length(out_of);
    if (beyond > 0.0) {
        value += beyond;
        slope += out_of / beyond;
    }
    return vec3(value, slope);
}

void main() {
    uint i = flat_workgroup_id() * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
    float energy = 0.0;
    if (i < pc.vertices) {
        vec3 x = vec3(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u]);
        vec3 grad = vec3(0.0);
        for (uint v = pc.first_view; v < pc.first_view + pc.views; v++) {
            View view = views[v];
            vec3 c = (view.world_to_camera * vec4(x, 1.0)).xyz;
            // Phrased as positive so a NaN position is skipped too.
            if (view.dims.w == 0u || !(c.z > pc.near)) {
                continue;
            }
            vec4 k = view.intrinsics;
            vec2 q = vec2(k.x * c.x / c.z + k.z, k.y * c.y / c.z + k.w) - 0.5;
            vec3 d = field_at(view, q);
            float inv_size = 1.0 / float(max(view.dims.x, view.dims.y));
            energy += pc.scale * d.x * d.x * inv_size * inv_size;
            vec2 dq = 2.0 * pc.scale * d.x * inv_size * inv_size * d.yz;
            grad += pinhole_backward(view.world_to_camera, k, c, dq);
        }
        grad_positions[3u * i] += grad.x;
        grad_positions[3u * i + 1u] += grad.y;
        grad_positions[3u * i + 2u] += grad.z;
    }
    float total = subgroupAdd(energy);
    if (subgroupElect()) {
        FIXED_ADD_TOTAL(loss_sum, 0u, total);
    }
}
