#version 460
// Radix sort, step 3 of 3 per pass, CPU-device variant (see radix_lanes_common.glsl): every
// invocation walks its run in order and writes each pair to its counter for the pair's digit,
// which starts at the tile's scanned offset plus the counts of the earlier runs. Stable.
#define PLAN_BINDING 6
#define PAIRS_OUT_BINDING 4
#include "radix_lanes_common.glsl"

// 1: the pass writes records; 0: the caller's separate keys and values (the last pass).
layout(constant_id = 5) const uint RECORDS_OUT = 0;

layout(std430, binding = 2) readonly buffer TileOffsets { uint tile_offsets[]; };
layout(std430, binding = 3) readonly buffer RunCounts { uint run_counts[]; };
// The output: records (binding 4, binding 5 unused), or keys (binding 4) and values (binding 5,
// see PAIRS_OUT_BINDING).
layout(std430, binding = 4) writeonly buffer RecordsOut { uint64_t records_out[]; };
DEFINE_RECORD_STORE(store_record, records_out)

// This invocation's next output position per digit; private for the reason in the histogram.
uint next_position[RADIX];

void store(uint dst, Pair p) {
    if (RECORDS_OUT == 1u) {
        store_record(dst, p);
    } else {
        store_pair(dst, p);
    }
}

void place(Pair p) {
    uint digit = digit_of_pair(p);
    uint dst = next_position[digit];
    next_position[digit] = dst + 1u;
    store(dst, p);
}

void main() {
    uint tile = flat_workgroup_id();
    if (tile >= params.tile_count || !gate_open()) {
        return;
    }
    uint digits = 1u << params.digit_bits;
    uint runs_base = tile * WORKGROUP_SIZE * RADIX;
    for (uint d = gl_LocalInvocationID.x; d < digits; d += WORKGROUP_SIZE) {
        uint next = tile_offsets[d * params.tile_count + tile];
        for (uint r = 0u; r < WORKGROUP_SIZE; r++) {
            run_digits[r * RADIX + d] = next;
            next += run_counts[runs_base + r * RADIX + d];
        }
    }
    barrier();
    uint row = gl_LocalInvocationID.x * RADIX;
    for (uint d = 0u; d < digits; d++) {
        next_position[d] = run_digits[row + d];
    }
    uvec3 range = run_range(tile);
    for (uint i = range.x; i < range.z; i += 2u) {
        Pair a, b;
        load_couple(i, a, b);
        place(a);
        place(b);
    }
    if (range.z < range.y) {
        place(load_one(range.z));
    }
}
