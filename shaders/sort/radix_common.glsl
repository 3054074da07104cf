// Shared by radix_histogram.comp and radix_scatter.comp. Mirrors engine/sort/radix.rs
// (RadixParams).
//
// A workgroup owns a tile of TILE_LEN consecutive keys. Each subgroup owns a contiguous
// segment of the tile and walks it gl_SubgroupSize keys at a time, in order. Keys with equal
// digits within one step are found with ballots (8 ballots, one per digit bit: "warp-level
// multi-split"), so the per-subgroup digit counts need no atomics and ranks keep the input
// order: the sort is stable.
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_ballot : require

layout(local_size_x_id = 0) in;
layout(constant_id = 0) const uint WORKGROUP_SIZE = 128;
layout(constant_id = 1) const uint SUBGROUP_SIZE = 32;
layout(constant_id = 2) const uint KEYS_PER_THREAD = 16;
const uint RADIX = 256u;
const uint MAX_SUBGROUPS = WORKGROUP_SIZE / SUBGROUP_SIZE;
const uint TILE_LEN = WORKGROUP_SIZE * KEYS_PER_THREAD;

layout(push_constant) uniform RadixParams {
    uint len;         // keys to sort
    uint key_words;   // 32-bit words per key: 1 or 2
    uint word;        // which word holds this pass's digit
    uint shift;       // digit's lowest bit within that word
    uint digit_bits;  // bits in this pass's digit (8, fewer on the last pass)
    uint tile_count;  // tiles (workgroups) in the sort
} params;

#include "../common/grid.glsl"

layout(std430, binding = 0) readonly buffer Keys { uint keys[]; };

// Digit counts of each subgroup's segment: [subgroup][digit].
shared uint subgroup_counts[MAX_SUBGROUPS * RADIX];

// Lanes of this subgroup holding a valid key with the same digit as this lane.
uvec4 lanes_with_digit(uint digit, bool valid) {
    uvec4 peers = subgroupBallot(valid);
    for (uint b = 0u; b < params.digit_bits; b++) {
        bool set = ((digit >> b) & 1u) != 0u;
        uvec4 lanes = subgroupBallot(set);
        peers &= set ? lanes : ~lanes;
    }
    return peers;
}

uint count_lanes(uvec4 lanes) {
    uvec4 c = bitCount(lanes);
    return uint(c.x + c.y + c.z + c.w);
}

// Index of the i-th key of this subgroup's segment walk (step, lane) in the whole sort.
uint segment_key_index(uint tile, uint step) {
    uint segment_len = gl_SubgroupSize * KEYS_PER_THREAD;
    return tile * TILE_LEN + gl_SubgroupID * segment_len + step * gl_SubgroupSize + gl_SubgroupInvocationID;
}

uint digit_of(uint word) {
    return (word >> params.shift) & ((1u << params.digit_bits) - 1u);
}

// Counts the digits of this subgroup's segment of `tile` into subgroup_counts[row..row + RADIX].
void count_segment(uint tile, uint row) {
    for (uint d = gl_SubgroupInvocationID; d < RADIX; d += gl_SubgroupSize) {
        subgroup_counts[row + d] = 0u;
    }
    subgroupMemoryBarrierShared();
    subgroupBarrier();
    for (uint step = 0u; step < KEYS_PER_THREAD; step++) {
        uint i = segment_key_index(tile, step);
        bool valid = i < params.len;
        uint digit = valid ? digit_of(keys[i * params.key_words + params.word]) : 0u;
        uvec4 peers = lanes_with_digit(digit, valid);
        // The lowest lane of each group of equal digits adds the group's size: no atomics.
        if (valid && count_lanes(peers & gl_SubgroupLtMask) == 0u) {
            subgroup_counts[row + digit] += count_lanes(peers);
        }
        subgroupMemoryBarrierShared();
        subgroupBarrier();
    }
}
