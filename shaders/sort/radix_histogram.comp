#version 460
// Radix sort, step 1 of 3 per pass: digit counts of every tile, stored digit-major
// (tile_counts[digit * tile_count + tile]) so that their exclusive scan gives every
// (digit, tile) its first output position.
#include "radix_common.glsl"

layout(std430, binding = 1) writeonly buffer TileCounts { uint tile_counts[]; };

void main() {
    uint tile = flat_workgroup_id();
    if (tile >= params.tile_count) {
        return;
    }
    count_segment(tile, gl_SubgroupID * RADIX);
    barrier();
    uint digits = 1u << params.digit_bits;
    for (uint d = gl_LocalInvocationID.x; d < digits; d += WORKGROUP_SIZE) {
        uint sum = 0u;
        for (uint s = 0u; s < gl_NumSubgroups; s++) {
            sum += subgroup_counts[s * RADIX + d];
        }
        tile_counts[d * params.tile_count + tile] = sum;
    }
}
