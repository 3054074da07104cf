#version 460
// dst = src, 16 bytes per invocation per step: the bandwidth bound that other memory-bound
// kernels are measured against.
layout(local_size_x_id = 0) in;
layout(constant_id = 0) const uint WORKGROUP_SIZE = 256;

layout(push_constant) uniform CopyParams {
    uint len;           // uvec4 elements
    uint total_threads; // invocations in the grid (grid-stride loop)
} params;

layout(std430, binding = 0) readonly buffer Src { uvec4 src[]; };
layout(std430, binding = 1) writeonly buffer Dst { uvec4 dst[]; };

#include "../common/grid.glsl"

void main() {
    uint first = flat_workgroup_id() * WORKGROUP_SIZE + gl_LocalInvocationID.x;
    for (uint i = first; i < params.len; i += params.total_threads) {
        dst[i] = src[i];
    }
}
