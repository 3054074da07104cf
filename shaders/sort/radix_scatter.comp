#version 460
// Radix sort, step 3 of 3 per pass: moves every key and value to its place, keeping input
// order among equal digits (the sort is stable).
//
// Each subgroup owns a contiguous segment of the tile and walks it gl_SubgroupSize keys at a
// time, in order, holding its keys in registers. Keys with equal digits within one step are
// found with one ballot per digit bit (warp-level multi-split); the lowest lane of each group
// advances the subgroup's count of that digit, so counting needs no atomics and ranks follow
// input order. Then the subgroups' counts become offsets (tile start of the digit + counts of
// earlier subgroups) and every key is written to offset + rank.
#extension GL_EXT_control_flow_attributes : require
#include "radix_common.glsl"

layout(std430, binding = 0) readonly buffer KeysIn { uint keys_in[]; };
layout(std430, binding = 1) readonly buffer ValuesIn { uint values_in[]; };
layout(std430, binding = 2) readonly buffer TileOffsets { uint tile_offsets[]; };
layout(std430, binding = 3) writeonly buffer KeysOut { uint keys_out[]; };
layout(std430, binding = 4) writeonly buffer ValuesOut { uint values_out[]; };

// Per subgroup and digit ([subgroup][digit]): first the count, then the output position.
shared uint subgroup_digits[MAX_SUBGROUPS * RADIX];

// Index of this lane's key at `step` of its subgroup's walk over `tile`.
uint segment_key_index(uint tile, uint step) {
    uint segment_len = gl_SubgroupSize * KEYS_PER_THREAD;
    return tile * TILE_LEN + gl_SubgroupID * segment_len + step * gl_SubgroupSize + gl_SubgroupInvocationID;
}

// Turns the per-subgroup counts into each subgroup's first output position per digit.
void counts_to_offsets(uint tile) {
    uint digits = 1u << params.digit_bits;
    for (uint d = gl_LocalInvocationID.x; d < digits; d += WORKGROUP_SIZE) {
        uint running = tile_offsets[d * params.tile_count + tile];
        for (uint s = 0u; s < gl_NumSubgroups; s++) {
            uint count = subgroup_digits[s * RADIX + d];
            subgroup_digits[s * RADIX + d] = running;
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
    for (uint d = gl_SubgroupInvocationID; d < RADIX; d += gl_SubgroupSize) {
        subgroup_digits[row + d] = 0u;
    }
    subgroupMemoryBarrierShared();
    subgroupBarrier();

    uint lo[KEYS_PER_THREAD], hi[KEYS_PER_THREAD], value[KEYS_PER_THREAD];
    // Digit in the top 8 bits, rank within the subgroup's segment below (< 2^24).
    uint digit_rank[KEYS_PER_THREAD];
    [[unroll]] for (uint step = 0u; step < KEYS_PER_THREAD; step++) {
        uint i = segment_key_index(tile, step);
        bool valid = i < params.len;
        lo[step] = valid ? keys_in[i * KEY_WORDS] : 0u;
        hi[step] = valid && KEY_WORDS == 2u ? keys_in[i * 2u + 1u] : 0u;
        value[step] = valid ? values_in[i] : 0u;
        uint digit = digit_of(params.word == 0u ? lo[step] : hi[step]);
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
        digit_rank[step] = (digit << 24) | (base + rank);
    }
    barrier();
    counts_to_offsets(tile);
    barrier();
    [[unroll]] for (uint step = 0u; step < KEYS_PER_THREAD; step++) {
        if (segment_key_index(tile, step) < params.len) {
            uint dst = subgroup_digits[row + (digit_rank[step] >> 24)] + (digit_rank[step] & 0xFFFFFFu);
            keys_out[dst * KEY_WORDS] = lo[step];
            if (KEY_WORDS == 2u) {
                keys_out[dst * 2u + 1u] = hi[step];
            }
            values_out[dst] = value[step];
        }
    }
}
