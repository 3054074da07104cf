#version 460
// Regularizers, pass 2: one invocation per Gaussian v gathers every gradient that lands on
// its own rows, so no two invocations write the same row:
// - Laplacian: (2/n) w (δ_v − Σ_{i∈N(v)} δ_i / m_i) from pass 1's offsets;
// - normal consistency: Σ over faces (v, b, c) of (b − c) × (g_v + g_b + g_c), since each
//   face's area vector enters the mesh normal of its three corners;
// - temporal terms (previous frame bound): edge length, 1-ring rigidity (v's own terms and
//   the terms of its neighbours in which v is the neighbour), rotation consistency (ω is
//   symmetric, so dL/dp_v = 2 w Σ_j ω_vj (p_v − p_j) / |p_v − p_j|). Vertex i's stiffness
//   s_i scales its own rigidity terms; an edge's length term takes the mean of its ends'.
#include "common.glsl"
#include "../common/grid.glsl"

layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer Positions { float positions[]; };
layout(std430, binding = 1) readonly buffer Rotations { vec4 rotations[]; };
layout(std430, binding = 2) readonly buffer PrevPositions { float prev_positions[]; };
layout(std430, binding = 3) readonly buffer PrevRotations { vec4 prev_rotations[]; };
layout(std430, binding = 4) readonly buffer Ranges { uvec2 ranges[]; };
layout(std430, binding = 5) readonly buffer Ring { uint ring[]; };
layout(std430, binding = 6) readonly buffer Deltas { vec4 deltas[]; };
layout(std430, binding = 7) readonly buffer NormalGrads { vec4 normal_grads[]; };
layout(std430, binding = 8) buffer GradPositions { float grad_positions[]; };
layout(std430, binding = 9) buffer GradRotations { vec4 grad_rotations[]; };
layout(std430, binding = 10) buffer LossSums { int64_t loss_sums[]; };
layout(std430, binding = 11) readonly buffer Stiffness { float stiffness[]; };

vec3 position(uint i) {
    return vec3(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u]);
}

vec3 prev_position(uint i) {
    return vec3(prev_positions[3u * i], prev_positions[3u * i + 1u], prev_positions[3u * i + 2u]);
}

uint ring_count(uint i) {
    return ranges[i].y & ~BOUNDARY_BIT;
}

// ΔR_i = R'_i R_iᵀ (primes: previous frame).
mat3 delta_rotation(uint i) {
    return rotation_of(unit_quat(prev_rotations[i])) * transpose(rotation_of(unit_quat(rotations[i])));
}

void main() {
    uint v = flat_workgroup_id() * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
    float edge_length = 0.0, rigidity = 0.0, rotation = 0.0;
    if (v < pc.count) {
        uint start = ranges[v].x, count = ring_count(v);
        uint faces = count == 0u ? 0u : ((ranges[v].y & BOUNDARY_BIT) != 0u ? count - 1u : count);
        vec3 p = position(v);
        vec3 lap = deltas[v].xyz;
        for (uint k = 0u; k < count; k++) {
            uint i = ring[start + k];
            lap -= deltas[i].xyz / float(ring_count(i));
        }
        vec3 gp = 2.0 * pc.inv_count * pc.w_laplacian * lap;
        vec3 g_v = normal_grads[v].xyz;
        for (uint k = 0u; k < faces; k++) {
            uint b = ring[start + k], c = ring[start + (k + 1u) % count];
            gp += cross(position(b) - position(c), g_v + normal_grads[b].xyz + normal_grads[c].xyz);
        }
        vec4 gq = vec4(0.0);
        if (pc.temporal != 0u) {
            vec3 pp = prev_position(v);
            vec4 q = unit_quat(rotations[v]), q_prev = unit_quat(prev_rotations[v]);
            mat3 r_prev = rotation_of(q_prev);
            mat3 dr = r_prev * transpose(rotation_of(q));
            vec4 rel = quat_mul(q, quat_conj(q_prev));
            mat3 g_rot = mat3(0.0);
            vec4 g_rel = vec4(0.0);
            for (uint k = 0u; k < count; k++) {
                uint j = ring[start + k];
                vec3 d = position(j) - p, d_prev = prev_position(j) - pp;
                float l = length(d), l_prev = length(d_prev);
                float s_edge = 0.5 * (stiffness[v] + stiffness[j]);
                if (j > v) {
                    edge_length += s_edge * huber(abs(l - l_prev));
                }
                if (l > 0.0 && l != l_prev) {
                    gp -= pc.w_edge_length * s_edge * (l - l_prev) / huber_divisor(abs(l - l_prev)) * d / l;
                }
                float omega = exp(-pc.omega_scale * l_prev);
                // v's own rigidity term with neighbour j.
                vec3 e = d_prev - dr * d;
                float el = length(e);
                rigidity += stiffness[v] * omega * huber(el);
                if (el > 0.0) {
                    vec3 u = pc.w_rigidity * stiffness[v] * omega * e / huber_divisor(el);
                    gp += transpose(dr) * u;
                    g_rot -= outerProduct(d, transpose(r_prev) * u);
                }
                // j's rigidity term with neighbour v.
                mat3 dr_j = delta_rotation(j);
                vec3 e_j = -d_prev + dr_j * d;
                float el_j = length(e_j);
                if (el_j > 0.0) {
                    gp -= transpose(dr_j) * (pc.w_rigidity * stiffness[j] * omega * e_j / huber_divisor(el_j));
                }
                // Rotation consistency.
                vec4 diff = rel - quat_mul(unit_quat(rotations[j]), quat_conj(unit_quat(prev_rotations[j])));
                float dl = length(diff);
                rotation += omega * dl;
                if (dl > 0.0) {
                    g_rel += 2.0 * pc.w_rotation * omega * diff / dl;
                }
            }
            gq = rotation_backward(q, g_rot) + quat_mul(g_rel, q_prev);
        }
        grad_positions[3u * v] += gp.x;
        grad_positions[3u * v + 1u] += gp.y;
        grad_positions[3u * v + 2u] += gp.z;
        grad_rotations[v] += normalize_backward(rotations[v], gq);
    }
    ADD_LOSS(LOSS_EDGE_LENGTH, edge_length);
    ADD_LOSS(LOSS_RIGIDITY, rigidity);
    ADD_LOSS(LOSS_ROTATION, rotation);
}
