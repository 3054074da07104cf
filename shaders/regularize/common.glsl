// Shared by vertex.comp and gather.comp: push constants (engine/regularize/kernels.rs
// `Push`), the loss slots, quaternion normalisation and the loss reduction.
#ifndef REGULARIZE_COMMON_GLSL
#define REGULARIZE_COMMON_GLSL

#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require

layout(push_constant) uniform Push {
    uint count;          // Gaussians
    uint temporal;       // 1: previous-frame buffers are bound, evaluate the temporal terms
    float inv_count;     // 1 / count (Laplacian normalisation)
    float omega_scale;   // lambda_w / mean edge length
    float w_scale_2d;
    float w_laplacian;
    float w_normal;
    float w_edge_length;
    float w_rigidity;
    float w_rotation;
    float huber;         // Huber δ of the edge-length and rigidity residuals, scene units
} pc;

const uint LOSS_SCALE_2D = 0u;
const uint LOSS_LAPLACIAN = 1u;
const uint LOSS_NORMAL = 2u;
const uint LOSS_EDGE_LENGTH = 3u;
const uint LOSS_RIGIDITY = 4u;
const uint LOSS_ROTATION = 5u;

const uint BOUNDARY_BIT = 0x80000000u;

#include "../common/quaternion.glsl"
#include "../common/fixed_sum.glsl"

// The Huber penalty of a residual length r ≥ 0: r²/(2δ) below δ, r − δ/2 beyond (δ = 0: r).
float huber(float r) {
    return r < pc.huber ? 0.5 * r * r / pc.huber : r - 0.5 * pc.huber;
}

// What h's gradient divides a residual vector of length r by: max(r, δ), so the gradient's
// length stays at most 1 either way.
float huber_divisor(float r) {
    return max(r, pc.huber);
}

// Adds `value` (0 from inactive invocations) to loss sum `slot`: one fixed-point add per
// subgroup (order-independent, so runs repeat bit for bit). Must be reached by every
// invocation of the subgroup.
#define ADD_LOSS(slot, value)                         \
    {                                                 \
        float total_ = subgroupAdd(value);            \
        if (subgroupElect()) {                        \
            FIXED_ADD_TOTAL(loss_sums, slot, total_);       \
        }                                             \
    }

#endif
