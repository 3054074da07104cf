#version 460
// Radix sort, step 3 of 3 per pass: moves every key and value to its place, keeping input
// order among equal digits (the sort is stable). Ranks keys within each subgroup by ballot
// matching (radix_rank.glsl), then every subgroup's first position per digit is the tile's
// scanned start of the digit plus the counts of earlier subgroups.
#include "radix_common.glsl"
#include "radix_rank.glsl"

layout(std430, binding = 2) readonly buffer TileOffsets { uint tile_offsets[]; };

void main() {
    uint tile = flat_workgroup_id();
    if (tile >= params.tile_count) {
        return;
    }
    rank_tile(tile);
    barrier();
    uint digits = 1u << params.digit_bits;
    for (uint d = gl_LocalInvocationID.x; d < digits; d += WORKGROUP_SIZE) {
        counts_to_offsets(d, tile_offsets[d * params.tile_count + tile]);
    }
    barrier();
    scatter_tile(tile);
}
