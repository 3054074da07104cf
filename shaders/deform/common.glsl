// Shared by the deformation-graph kernels: push constants (engine/deform/kernels.rs `Push`)
// and the node transform. A node k is a rest position g_k (its vertex in the frame's start
// pose) with a rotation q_k and a translation t_k; it moves a point x to R(q̂_k)(x − g_k) + g_k + t_k.
#ifndef DEFORM_COMMON_GLSL
#define DEFORM_COMMON_GLSL

#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require

#include "../common/quaternion.glsl"
#include "../common/grid.glsl"

layout(push_constant) uniform Push {
    uint vertices;
    uint nodes;
    // w_arap / (directed node edges · node spacing²): the ARAP sum's weight per squared residual.
    float arap_scale;
    uint unused;
} pc;

// Bound nodes per vertex (unused slots have weight 0).
const uint NODES_PER_VERTEX = 4u;

#endif
