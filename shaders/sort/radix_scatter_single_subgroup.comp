#version 460
// Radix sort, step 3 of 3 per pass, for workgroups of one subgroup (chosen on CPU devices,
// where a workgroup runs on one core and more subgroups would only add bookkeeping).
//
// The subgroup walks its whole tile gl_SubgroupSize keys at a time, in order. Its digit
// counters start at the tile's scanned offsets; each step finds the lanes with equal digits,
// writes every key to counter + rank among those lanes, and the lowest of them advances the
// counter. Input order is kept among equal digits: the sort is stable.
#include "radix_common.glsl"

layout(std430, binding = 0) readonly buffer KeysIn { uint keys_in[]; };
layout(std430, binding = 1) readonly buffer ValuesIn { uint values_in[]; };
layout(std430, binding = 2) readonly buffer TileOffsets { uint tile_offsets[]; };
layout(std430, binding = 3) writeonly buffer KeysOut { uint keys_out[]; };
layout(std430, binding = 4) writeonly buffer ValuesOut { uint values_out[]; };

shared uint next_position[RADIX];

void main() {
    uint tile = flat_workgroup_id();
    if (tile >= params.tile_count) {
        return;
    }
    uint digits = 1u << params.digit_bits;
    for (uint d = gl_SubgroupInvocationID; d < digits; d += gl_SubgroupSize) {
        next_position[d] = tile_offsets[d * params.tile_count + tile];
    }
    subgroupMemoryBarrierShared();
    subgroupBarrier();
    uint end = min((tile + 1u) * TILE_LEN, params.len);
    for (uint first = tile * TILE_LEN; first < end; first += gl_SubgroupSize) {
        uint i = first + gl_SubgroupInvocationID;
        bool valid = i < end;
        uint lo = 0u, hi = 0u, value = 0u;
        if (valid) {
            lo = keys_in[i * KEY_WORDS];
            hi = KEY_WORDS == 2u ? keys_in[i * 2u + 1u] : 0u;
            value = values_in[i];
        }
        uint digit = digit_of(params.word == 0u ? lo : hi);
        uvec4 peers = lanes_with_digit(digit, valid);
        uint rank = count_lanes(peers & gl_SubgroupLtMask);
        uint base = valid ? next_position[digit] : 0u;
        subgroupMemoryBarrierShared();
        subgroupBarrier(); // Every lane has read `base` before the lowest lane moves it on.
        if (valid) {
            if (rank == 0u) {
                next_position[digit] = base + count_lanes(peers);
            }
            uint dst = base + rank;
            keys_out[dst * KEY_WORDS] = lo;
            if (KEY_WORDS == 2u) {
                keys_out[dst * 2u + 1u] = hi;
            }
            values_out[dst] = value;
        }
        subgroupMemoryBarrierShared();
        subgroupBarrier();
    }
}
