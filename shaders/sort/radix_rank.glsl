// Ranking a tile's keys by ballot matching, shared by the kernels that scatter whole tiles from
// registers (radix_scatter.comp, radix_onesweep.comp). Include after radix_common.glsl; the
// including kernel binds its own buffer at binding 2.
//
// Each subgroup owns a contiguous segment of the tile and walks it gl_SubgroupSize keys at a
// time, in order, holding its keys in registers. Keys with equal digits within one step are
// found with one ballot per digit bit (warp-level multi-split); the lowest lane of each group
// advances the subgroup's count of that digit, so counting needs no atomics and ranks follow
// input order. Once the kernel has turned the subgroups' counts into output positions
// (counts_to_offsets), every key goes to its subgroup's position for its digit plus its rank.
#ifndef SORT_RADIX_RANK_GLSL
#define SORT_RADIX_RANK_GLSL
#extension GL_EXT_control_flow_attributes : require

layout(std430, binding = 0) readonly buffer KeysIn { uint keys_in[]; };
layout(std430, binding = 1) readonly buffer ValuesIn { uint values_in[]; };
layout(std430, binding = 3) writeonly buffer KeysOut { uint keys_out[]; };
layout(std430, binding = 4) writeonly buffer ValuesOut { uint values_out[]; };

// Per subgroup and digit ([subgroup][digit]): first the count, then the output position.
shared uint subgroup_digits[MAX_SUBGROUPS * RADIX];

// This invocation's keys and values, and each key's digit (top 8 bits) and rank within its
// subgroup's segment (below, < 2^24).
uint tile_lo[KEYS_PER_THREAD], tile_hi[KEYS_PER_THREAD], tile_value[KEYS_PER_THREAD];
uint tile_digit_rank[KEYS_PER_THREAD];

// Index of this lane's key at `step` of its subgroup's walk over `tile`.
uint segment_key_index(uint tile, uint step) {
    uint segment_len = gl_SubgroupSize * KEYS_PER_THREAD;
    return tile * TILE_LEN + gl_SubgroupID * segment_len + step * gl_SubgroupSize + gl_SubgroupInvocationID;
}

// Loads the tile's keys into registers and ranks them; leaves each subgroup's digit counts in
// its row of subgroup_digits. The caller must barrier() before reading other subgroups' rows.
void rank_tile(uint tile) {
    uint row = gl_SubgroupID * RADIX;
    for (uint d = gl_SubgroupInvocationID; d < RADIX; d += gl_SubgroupSize) {
        subgroup_digits[row + d] = 0u;
    }
    subgroupMemoryBarrierShared();
    subgroupBarrier();
    [[unroll]] for (uint step = 0u; step < KEYS_PER_THREAD; step++) {
        uint i = segment_key_index(tile, step);
        bool valid = i < params.len;
        tile_lo[step] = valid ? keys_in[i * KEY_WORDS] : 0u;
        tile_hi[step] = valid && KEY_WORDS == 2u ? keys_in[i * 2u + 1u] : 0u;
        tile_value[step] = valid ? values_in[i] : 0u;
        uint digit = digit_of(params.word == 0u ? tile_lo[step] : tile_hi[step]);
        uvec4 peers = lanes_with_digit(digit, valid);
        uint rank = count_lanes(peers & gl_SubgroupLtMask);
        uint base = subgroup_digits[row + digit];
        subgroupMemoryBarrierShared();
        subgroupBarrier(); // Every lane has read `base` before the leader moves it on.
        if (valid && rank == 0u) {
            subgroup_digits[row + digit] = base + count_lanes(peers);
        }
        subgroupMemoryBarrierShared();
        subgroupBarrier();
        tile_digit_rank[step] = (digit << 24) | (base + rank);
    }
}

// The tile's count of `digit`: the sum of the subgroups' counts (after rank_tile).
uint tile_digit_count(uint digit) {
    uint sum = 0u;
    for (uint s = 0u; s < gl_NumSubgroups; s++) {
        sum += subgroup_digits[s * RADIX + digit];
    }
    return sum;
}

// Turns the subgroups' counts of `digit` into their first output positions, from `start` (the
// tile's first position for the digit) in subgroup order, which keeps the sort stable.
void counts_to_offsets(uint digit, uint start) {
    uint running = start;
    for (uint s = 0u; s < gl_NumSubgroups; s++) {
        uint count = subgroup_digits[s * RADIX + digit];
        subgroup_digits[s * RADIX + digit] = running;
        running += count;
    }
}

// Writes every key and value of the tile to its place (after counts_to_offsets and a barrier).
void scatter_tile(uint tile) {
    uint row = gl_SubgroupID * RADIX;
    [[unroll]] for (uint step = 0u; step < KEYS_PER_THREAD; step++) {
        if (segment_key_index(tile, step) < params.len) {
            uint dst = subgroup_digits[row + (tile_digit_rank[step] >> 24)] + (tile_digit_rank[step] & 0xFFFFFFu);
            keys_out[dst * KEY_WORDS] = tile_lo[step];
            if (KEY_WORDS == 2u) {
                keys_out[dst * 2u + 1u] = tile_hi[step];
            }
            values_out[dst] = tile_value[step];
        }
    }
}

#endif
