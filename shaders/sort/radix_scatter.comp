#version 460
// Radix sort, step 3 of 3 per pass: moves every key and value to its place. A key's place is
// the scanned start of its (digit, tile), plus the keys with that digit in earlier subgroups
// of the tile, plus those earlier in its own subgroup's walk: input order is kept.
#include "radix_common.glsl"

layout(std430, binding = 1) readonly buffer ValuesIn { uint values_in[]; };
layout(std430, binding = 2) readonly buffer TileOffsets { uint tile_offsets[]; };
layout(std430, binding = 3) writeonly buffer KeysOut { uint keys_out[]; };
layout(std430, binding = 4) writeonly buffer ValuesOut { uint values_out[]; };

// Turns the counts into each subgroup's first output position per digit.
void counts_to_offsets(uint tile) {
    uint digits = 1u << params.digit_bits;
    for (uint d = gl_LocalInvocationID.x; d < digits; d += WORKGROUP_SIZE) {
        uint running = tile_offsets[d * params.tile_count + tile];
        for (uint s = 0u; s < gl_NumSubgroups; s++) {
            uint count = subgroup_counts[s * RADIX + d];
            subgroup_counts[s * RADIX + d] = running;
            running += count;
        }
    }
}

void main() {
    uint tile = flat_workgroup_id();
    if (tile >= params.tile_count) {
        return;
    }
    uint row = gl_SubgroupID * RADIX;
    count_segment(tile, row);
    barrier();
    counts_to_offsets(tile);
    barrier();
    for (uint step = 0u; step < KEYS_PER_THREAD; step++) {
        uint i = segment_key_index(tile, step);
        bool valid = i < params.len;
        uint lo = 0u, hi = 0u, value = 0u;
        if (valid) {
            lo = keys[i * params.key_words];
            hi = params.key_words == 2u ? keys[i * 2u + 1u] : 0u;
            value = values_in[i];
        }
        uint digit = digit_of(params.word == 0u ? lo : hi);
        uvec4 peers = lanes_with_digit(digit, valid);
        uint rank = count_lanes(peers & gl_SubgroupLtMask);
        uint base = valid ? subgroup_counts[row + digit] : 0u;
        subgroupMemoryBarrierShared();
        subgroupBarrier(); // Every lane has read `base` before the leader moves it on.
        if (valid && rank == 0u) {
            subgroup_counts[row + digit] = base + count_lanes(peers);
        }
        if (valid) {
            uint dst = base + rank;
            keys_out[dst * params.key_words] = lo;
            if (params.key_words == 2u) {
                keys_out[dst * 2u + 1u] = hi;
            }
            values_out[dst] = value;
        }
        subgroupMemoryBarrierShared();
        subgroupBarrier();
    }
}
