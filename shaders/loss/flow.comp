#version 460
// Optical-flow term: where each visible vertex's pixel of frame t − 1 moved in frame t's image
// (engine/train/flow_targets.rs, by Lucas–Kanade), its projection is pulled. One invocation per
// vertex i sums over views v with a target (u, w > 0)
//   E = s Σ_v w_iv τ² ln(1 + |π_v(x_i) − u_iv|² / τ²) / max(W_v, H_v)²,
// pixels in index coordinates (centres at integers), s = weight / (targets). The Cauchy loss
// keeps a wrong flow vector (an occlusion the visibility test missed) from dragging a vertex
// far: beyond τ pixels its pull falls off. Each invocation writes only its own gradient row.
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "../common/grid.glsl"
#include "../common/fixed_sum.glsl"
#include "../common/pinhole.glsl"
layout(local_size_x_id = 0) in;

// Mirrors engine/loss/flow/mod.rs (`GpuView`).
struct View {
    mat4 world_to_camera;
    vec4 intrinsics;  // fx, fy, cx, cy (pixel centres at +0.5)
    uvec4 dims;       // width, height, unused, unused
};

layout(push_constant) uniform Push {
    uint vertices;
    uint views;
    float scale;  // s above
    float near;
    float tau;    // τ, pixels
} pc;

layout(std430, binding = 0) readonly buffer Positions { float positions[]; };
layout(std430, binding = 1) readonly buffer Views { View views[]; };
// Per vertex, per view (vertex-major): target pixel (u, v) and its confidence w (0: none).
layout(std430, binding = 2) readonly buffer Targets { vec4 targets[]; };
layout(std430, binding = 3) buffer GradPositions { float grad_positions[]; };
layout(std430, binding = 4) buffer LossSum { int64_t loss_sum[]; };

void main() {
    uint i = flat_workgroup_id() * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
    float energy = 0.0;
    if (i < pc.vertices) {
        vec3 x = vec3(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u]);
        vec3 grad = vec3(0.0);
        float tau2 = pc.tau * pc.tau;
        for (uint v = 0u; v < pc.views; v++) {
            vec4 target = targets[i * pc.views + v];
            View view = views[v];
            vec3 c = (view.world_to_camera * vec4(x, 1.0)).xyz;
            // Phrased as positive so a NaN position or weight is skipped too.
            if (!(target.z > 0.0) || !(c.z > pc.near)) {
                continue;
            }
            vec4 k = view.intrinsics;
            vec2 q = vec2(k.x * c.x / c.z + k.z, k.y * c.y / c.z + k.w) - 0.5;
            vec2 r = q - target.xy;
            float r2 = dot(r, r);
            float inv_size = 1.0 / float(max(view.dims.x, view.dims.y));
            float s = pc.scale * target.z * inv_size * inv_size;
            energy += s * tau2 * log(1.0 + r2 / tau2);
            vec2 dq = 2.0 * s * r / (1.0 + r2 / tau2);
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
