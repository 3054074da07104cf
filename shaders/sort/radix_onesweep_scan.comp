#version 460
// Radix sort, Onesweep variant, step 2: turns each pass's 256 digit counts into the digit's
// first output position (their exclusive sum), in place. One workgroup per pass; each
// invocation owns 256 / WORKGROUP_SIZE consecutive digits (the workgroup size is a power of
// two of at most 256).
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "radix_common.glsl"
#include "../common/workgroup_scan.glsl"

layout(std430, binding = 0) buffer DigitCounts { uint digit_counts[]; }; // [pass][digit]

const uint DIGITS_PER_INVOCATION = RADIX / WORKGROUP_SIZE;

void main() {
    uint pass = flat_workgroup_id();
    if (pass * RADIX_BITS >= params.bits) {
        return; // Past the end of a folded grid.
    }
    uint first = pass * RADIX + gl_LocalInvocationID.x * DIGITS_PER_INVOCATION;
    uint sum = 0u;
    for (uint k = 0u; k < DIGITS_PER_INVOCATION; k++) {
        sum += digit_counts[first + k];
    }
    uint total;
    uint running = workgroup_exclusive_add(sum, total);
    for (uint k = 0u; k < DIGITS_PER_INVOCATION; k++) {
        uint count = digit_counts[first + k];
        digit_counts[first + k] = running;
        running += count;
    }
}
