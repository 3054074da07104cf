#version 460
// Adds fixed-point sums (fixed_sum.glsl) to a float buffer: target[i] += sum i, or NaN when
// any contribution was dropped. The host zeroes the sums after this pass.
#include "fixed_sum.glsl"
#include "grid.glsl"
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer Sums { int64_t sums[]; };
layout(std430, binding = 1) buffer Target { float target[]; };

layout(push_constant) uniform Push {
    uint count;
} pc;

void main() {
    uint i = flat_workgroup_id() * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
    if (i >= pc.count) {
        return;
    }
    bool dropped = sums[sums.length() - 1] != 0;
    float sum = fixed_value(sums[i]);
    target[i] += dropped ? uintBitsToFloat(0x7fc00000u) : sum;
}
