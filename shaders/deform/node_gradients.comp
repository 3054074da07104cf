#version 460
// Deformation graph, backward: one invocation per node k gathers every gradient that lands on
// its own rows (no atomics, a fixed order):
// - from its vertices (CSR members, weight w_ik): dL/dt_k = Σ_i w_ik ∂L/∂p_i and
//   dL/dR_k = Σ_i w_ik ∂L/∂p_i (x_i − g_k)ᵀ, then through R(q̂) and the normalisation;
// - as-rigid-as-possible between neighbours, E = c Σ_k Σ_{j∈N(k)} ‖r_kj‖²,
//   r_kj = R_k (g_j − g_k) + g_k + t_k − (g_j + t_j): k's own terms and, since N is symmetric,
//   the terms of its neighbours in which k is the neighbour (−2c r_jk on t_k).
// Vertex rotation gradients do not reach the nodes: a Gaussian's rotation follows its nodes.
#include "common.glsl"
#include "../common/fixed_sum.glsl"
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer RestPositions { float rest_positions[]; };
layout(std430, binding = 1) readonly buffer NodeRest { vec4 node_rest[]; };
layout(std430, binding = 2) readonly buffer NodeTranslations { float node_translations[]; };
layout(std430, binding = 3) readonly buffer NodeRotations { vec4 node_rotations[]; };
layout(std430, binding = 4) readonly buffer MemberRanges { uvec2 member_ranges[]; };
layout(std430, binding = 5) readonly buffer Members { uint members[]; };
layout(std430, binding = 6) readonly buffer MemberWeights { float member_weights[]; };
layout(std430, binding = 7) readonly buffer NeighbourRanges { uvec2 neighbour_ranges[]; };
layout(std430, binding = 8) readonly buffer Neighbours { uint neighbours[]; };
layout(std430, binding = 9) readonly buffer GradPositions { float grad_positions[]; };
layout(std430, binding = 10) writeonly buffer NodeGradTranslations { float node_grad_translations[]; };
layout(std430, binding = 11) writeonly buffer NodeGradRotations { vec4 node_grad_rotations[]; };
layout(std430, binding = 12) buffer LossSum { int64_t loss_sum[]; };

vec3 translation(uint k) {
    return vec3(node_translations[3u * k], node_translations[3u * k + 1u], node_translations[3u * k + 2u]);
}

void main() {
    uint k = flat_workgroup_id() * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
    float energy = 0.0;
    if (k < pc.nodes) {
        vec3 g = node_rest[k].xyz, t = translation(k);
        vec4 q = unit_quat(node_rotations[k]);
        mat3 r = rotation_of(q);
        vec3 gt = vec3(0.0);
        mat3 gr = mat3(0.0);
        uvec2 range = member_ranges[k];
        for (uint m = range.x; m < range.x + range.y; m++) {
            uint i = members[m];
            vec3 gp = member_weights[m] * vec3(grad_positions[3u * i], grad_positions[3u * i + 1u], grad_positions[3u * i + 2u]);
            vec3 x = vec3(rest_positions[3u * i], rest_positions[3u * i + 1u], rest_positions[3u * i + 2u]);
            gt += gp;
            gr += outerProduct(gp, x - g);
        }
        range = neighbour_ranges[k];
        for (uint n = range.x; n < range.x + range.y; n++) {
            uint j = neighbours[n];
            vec3 d = node_rest[j].xyz - g, tj = translation(j);
            vec3 own = r * d - d + t - tj;
            vec3 theirs = rotation_of(unit_quat(node_rotations[j])) * -d + d + tj - t;
            energy += pc.arap_scale * dot(own, own);
            gt += 2.0 * pc.arap_scale * (own - theirs);
            gr += outerProduct(2.0 * pc.arap_scale * own, d);
        }
        node_grad_translations[3u * k] = gt.x;
        node_grad_translations[3u * k + 1u] = gt.y;
        node_grad_translations[3u * k + 2u] = gt.z;
        node_grad_rotations[k] = normalize_backward(node_rotations[k], rotation_backward(q, gr));
    }
    float total = subgroupAdd(energy);
    if (subgroupElect()) {
        FIXED_ADD_TOTAL(loss_sum, 0u, total); // order-independent, so runs repeat bit for bit
    }
}
