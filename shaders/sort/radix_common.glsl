// Shared by every radix-sort kernel. Mirrors engine/sort/radix.rs
// (RadixParams).
//
// A workgroup owns a tile of TILE_LEN consecutive keys; the histogram and the scatter of one
// pass agree on the tiles.
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_ballot : require

layout(local_size_x_id = 0) in;
layout(constant_id = 0) const uint WORKGROUP_SIZE = 128;
layout(constant_id = 1) const uint SUBGROUP_SIZE = 32;
layout(constant_id = 2) const uint KEYS_PER_THREAD = 16;
layout(constant_id = 3) const uint KEY_WORDS = 1; // 32-bit words per key: 1 (u32) or 2 (u64)
const uint RADIX_BITS = 8u;
const uint RADIX = 1u << RADIX_BITS;
const uint MAX_SUBGROUPS = WORKGROUP_SIZE / SUBGROUP_SIZE;
const uint TILE_LEN = WORKGROUP_SIZE * KEYS_PER_THREAD;

layout(push_constant) uniform RadixParams {
    uint len;         // keys to sort
    uint word;        // which word holds this pass's digit
    uint shift;       // digit's lowest bit within that word
    uint digit_bits;  // bits in this pass's digit (8, fewer on the last pass)
    uint tile_count;  // tiles (workgroups) in the sort
    // Read only by the CPU-device variant (radix_lanes_common.glsl):
    uint bits;           // significant key bits of the whole sort
    uint max_bucket_len; // the bucket path's limit on one bucket (radix_plan_lanes.comp)
    uint gate;           // GATE_*: which path of the sort the kernel belongs to
} params;

#include "../common/grid.glsl"


// Lanes of this subgroup holding a valid key with the same digit as this lane: the
// intersection of one ballot per digit bit (warp-level multi-split).
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

uint digit_of(uint word) {
    return (word >> params.shift) & ((1u << params.digit_bits) - 1u);
}
