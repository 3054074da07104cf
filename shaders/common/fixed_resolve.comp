#version 460
// Adds fixed-point sums (fixed_sum.glsl) to a float buffer: target[i] += sum i, or NaN when the
// sum dropped a contribution. The host zeroes the sums after this pass.
#include "fixed_sum.glsl"
#include "grid.glsl"
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer Sums { int64_t sums[]; };
layout(std430, binding = 1) buffer Target { float target[]; };

layout(push_constant) uniform Push {
    uint count;
    float one;   // 2^fraction bits of the sums' precision
} pc;

void main() {
    uint i = flat_workgroup_id() * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
    if (i >= pc.count) {
        return;
    }
    bool dropped = sums[uint(sums.length()) / 2u + i] != int64_t(0);
    float sum = float(sums[i]) / pc.one;
    target[i] += dropped ? uintBitsToFloat(0x7fc00000u) : sum;
}
