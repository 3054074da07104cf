#version 460
// Radix sort, step 1 of 3 per pass, CPU-device variant (see radix_lanes_common.glsl): digit
// counts per tile (digit-major, for the scan) and per invocation run (for the scatter).
#include "radix_lanes_common.glsl"

// The key buffer twice: 16-byte vectors for whole groups of 4 keys, words for the rest.
layout(std430, binding = 0) readonly buffer KeyVectors { uvec4 key_vectors[]; };
layout(std430, binding = 0) readonly buffer KeyWords { uint key_words[]; };
layout(std430, binding = 1) writeonly buffer TileCounts { uint tile_counts[]; };
layout(std430, binding = 2) writeonly buffer RunCounts { uint run_counts[]; }; // [tile][invocation][digit]

void count(uint row, uint word) {
    run_digits[row + digit_of(word)] += 1u;
}

void main() {
    uint tile = flat_workgroup_id();
    if (tile >= params.tile_count) {
        return;
    }
    uint row = gl_LocalInvocationID.x * RADIX;
    for (uint d = 0u; d < RADIX; d++) {
        run_digits[row + d] = 0u;
    }
    uvec3 range = run_range(tile);
    for (uint i = range.x; i < range.z; i += 4u) {
        if (KEY_WORDS == 1u) {
            uvec4 k = key_vectors[i / 4u];
            count(row, k.x);
            count(row, k.y);
            count(row, k.z);
            count(row, k.w);
        } else {
            uvec4 a = key_vectors[i / 2u];
            uvec4 b = key_vectors[i / 2u + 1u];
            count(row, params.word == 0u ? a.x : a.y);
            count(row, params.word == 0u ? a.z : a.w);
            count(row, params.word == 0u ? b.x : b.y);
            count(row, params.word == 0u ? b.z : b.w);
        }
    }
    for (uint i = range.z; i < range.y; i++) {
        count(row, key_words[i * KEY_WORDS + params.word]);
    }
    uint digits = 1u << params.digit_bits;
    uint run_base = (tile * WORKGROUP_SIZE + gl_LocalInvocationID.x) * RADIX;
    for (uint d = 0u; d < digits; d++) {
        run_counts[run_base + d] = run_digits[row + d];
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
