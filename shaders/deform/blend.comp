#version 460
// Deformation graph, forward: one invocation per vertex i writes its position and rotation
// from its bound nodes (weights w_ik summing to 1):
//   p_i = Σ_k w_ik (R_k (x_i − g_k) + g_k + t_k),   q_i = normalize(Σ_k w_ik q̂_k) ⊗ q̄_i,
// x_i and q̄_i the start pose. Blending unit quaternions linearly is accurate while the nodes
// turn by less than a right angle between neighbours, which a frame's step never approaches.
#include "common.glsl"
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer RestPositions { float rest_positions[]; };
layout(std430, binding = 1) readonly buffer RestRotations { vec4 rest_rotations[]; };
layout(std430, binding = 2) readonly buffer BoundNodes { uint bound_nodes[]; };
layout(std430, binding = 3) readonly buffer BoundWeights { float bound_weights[]; };
layout(std430, binding = 4) readonly buffer NodeRest { vec4 node_rest[]; };
layout(std430, binding = 5) readonly buffer NodeTranslations { float node_translations[]; };
layout(std430, binding = 6) readonly buffer NodeRotations { vec4 node_rotations[]; };
layout(std430, binding = 7) writeonly buffer Positions { float positions[]; };
layout(std430, binding = 8) writeonly buffer Rotations { vec4 rotations[]; };

void main() {
    uint i = flat_workgroup_id() * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
    if (i >= pc.vertices) {
        return;
    }
    vec3 x = vec3(rest_positions[3u * i], rest_positions[3u * i + 1u], rest_positions[3u * i + 2u]);
    vec3 p = vec3(0.0);
    vec4 q = vec4(0.0);
    for (uint s = 0u; s < NODES_PER_VERTEX; s++) {
        float w = bound_weights[NODES_PER_VERTEX * i + s];
        if (w > 0.0) {
            uint k = bound_nodes[NODES_PER_VERTEX * i + s];
            vec4 qk = unit_quat(node_rotations[k]);
            vec3 g = node_rest[k].xyz;
            vec3 t = vec3(node_translations[3u * k], node_translations[3u * k + 1u], node_translations[3u * k + 2u]);
            p += w * (rotation_of(qk) * (x - g) + g + t);
            q += w * qk;
        }
    }
    positions[3u * i] = p.x;
    positions[3u * i + 1u] = p.y;
    positions[3u * i + 2u] = p.z;
    rotations[i] = quat_mul(unit_quat(q), rest_rotations[i]);
}
