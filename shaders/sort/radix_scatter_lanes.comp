#version 460
// Radix sort, step 3 of 3 per pass, CPU-device variant (see radix_lanes_common.glsl): every
// invocation walks its run in order and writes each key to its counter for the key's digit,
// which starts at the tile's scanned offset plus the counts of the earlier runs. Stable.
#include "radix_lanes_common.glsl"

// Inputs twice: 16-byte vectors for whole groups of 4 keys, words for the rest.
layout(std430, binding = 0) readonly buffer KeyVectors { uvec4 key_vectors[]; };
layout(std430, binding = 0) readonly buffer KeyWords { uint key_words[]; };
layout(std430, binding = 1) readonly buffer ValueVectors { uvec4 value_vectors[]; };
layout(std430, binding = 1) readonly buffer ValueWords { uint value_words[]; };
layout(std430, binding = 2) readonly buffer TileOffsets { uint tile_offsets[]; };
layout(std430, binding = 3) readonly buffer RunCounts { uint run_counts[]; };
layout(std430, binding = 4) writeonly buffer KeysOut { uint keys_out[]; };
layout(std430, binding = 5) writeonly buffer ValuesOut { uint values_out[]; };

void place(uint row, uint lo, uint hi, uint value) {
    uint digit = digit_of(params.word == 0u ? lo : hi);
    uint dst = run_digits[row + digit];
    run_digits[row + digit] = dst + 1u;
    keys_out[dst * KEY_WORDS] = lo;
    if (KEY_WORDS == 2u) {
        keys_out[dst * 2u + 1u] = hi;
    }
    values_out[dst] = value;
}

void main() {
    uint tile = flat_workgroup_id();
    if (tile >= params.tile_count) {
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
    uvec3 range = run_range(tile);
    for (uint i = range.x; i < range.z; i += 4u) {
        uvec4 v = value_vectors[i / 4u];
        if (KEY_WORDS == 1u) {
            uvec4 k = key_vectors[i / 4u];
            place(row, k.x, 0u, v.x);
            place(row, k.y, 0u, v.y);
            place(row, k.z, 0u, v.z);
            place(row, k.w, 0u, v.w);
        } else {
            uvec4 a = key_vectors[i / 2u];
            uvec4 b = key_vectors[i / 2u + 1u];
            place(row, a.x, a.y, v.x);
            place(row, a.z, a.w, v.y);
            place(row, b.x, b.y, v.z);
            place(row, b.z, b.w, v.w);
        }
    }
    for (uint i = range.z; i < range.y; i++) {
        place(row, key_words[i * KEY_WORDS], KEY_WORDS == 2u ? key_words[i * 2u + 1u] : 0u, value_words[i]);
    }
}
