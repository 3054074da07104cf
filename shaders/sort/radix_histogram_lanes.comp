#version 460
// Radix sort, step 1 of 3 per pass, CPU-device variant (see radix_lanes_common.glsl): digit
// counts per tile (digit-major, for the scan) and per invocation run (for the scatter).
#define PLAN_BINDING 4
#include "radix_lanes_common.glsl"

layout(std430, binding = 2) writeonly buffer TileCounts { uint tile_counts[]; };
layout(std430, binding = 3) writeonly buffer RunCounts { uint run_counts[]; }; // [tile][invocation][digit]

// Private, not shared: on a CPU an indexed private access is an unrolled gather, a shared
// one a branchy loop over the lanes (histogram 23 -> 15 ms over 4 passes of 4M keys).
uint run_counts_private[RADIX];

void count(Pair p) {
    run_counts_private[digit_of_pair(p)] += 1u;
}

void main() {
    uint tile = flat_workgroup_id();
    if (tile >= params.tile_count || !gate_open()) {
        return;
    }
    for (uint d = 0u; d < RADIX; d++) {
        run_counts_private[d] = 0u;
    }
    uvec3 range = run_range(tile);
    for (uint i = range.x; i < range.z; i += 2u) {
        Pair a, b;
        load_couple(i, a, b);
        count(a);
        count(b);
    }
    if (range.z < range.y) {
        count(load_one(range.z));
    }
    uint digits = 1u << params.digit_bits;
    uint row = gl_LocalInvocationID.x * RADIX;
    uint run_base = (tile * WORKGROUP_SIZE + gl_LocalInvocationID.x) * RADIX;
    for (uint d = 0u; d < digits; d++) {
        run_counts[run_base + d] = run_counts_private[d];
        run_digits[row + d] = run_counts_private[d];
    }
    barrier();
    for (uint d = gl_LocalInvocationID.x; d < digits; d += WORKGROUP_SIZE) {
        uint sum = 0u;
        for (uint r = 0u; r < WORKGROUP_SIZE; r++) {
            sum += run_digits[r * RADIX + d];
        }
        tile_counts[d * params.tile_count + tile] = sum;
    }
}
