#version 460
// Radix sort, step 1 of 3 per pass: digit counts of every tile, stored digit-major
// (tile_counts[digit * tile_count + tile]) so that their exclusive scan gives every
// (digit, tile) its first output position.
//
// Order does not matter here, so keys are read 16 bytes at a time and counted with shared
// atomics (GPU variant; CPU devices run radix_histogram_lanes.comp).
#include "radix_common.glsl"

// The same buffer twice: whole 16-byte vectors, and single words for the tail.
layout(std430, binding = 0) readonly buffer KeyVectors { uvec4 key_vectors[]; };
layout(std430, binding = 0) readonly buffer KeyWords { uint key_words[]; };
layout(std430, binding = 1) writeonly buffer TileCounts { uint tile_counts[]; };

shared uint tile_digit_counts[RADIX];

void count_word(uint word) {
    atomicAdd(tile_digit_counts[digit_of(word)], 1u);
}

void main() {
    uint tile = flat_workgroup_id();
    if (tile >= params.tile_count) {
        return;
    }
    for (uint d = gl_LocalInvocationID.x; d < RADIX; d += WORKGROUP_SIZE) {
        tile_digit_counts[d] = 0u;
    }
    barrier();
    // Word range of this tile; a tile starts on a 16-byte boundary (TILE_LEN is a multiple of 4).
    uint words_begin = tile * TILE_LEN * KEY_WORDS;
    uint words_end = min((tile + 1u) * TILE_LEN, params.len) * KEY_WORDS;
    uint vectors_end = words_end / 4u;
    for (uint v = words_begin / 4u + gl_LocalInvocationID.x; v < vectors_end; v += WORKGROUP_SIZE) {
        uvec4 w = key_vectors[v];
        if (KEY_WORDS == 1u) {
            count_word(w.x);
            count_word(w.y);
            count_word(w.z);
            count_word(w.w);
        } else {
            count_word(params.word == 0u ? w.x : w.y);
            count_word(params.word == 0u ? w.z : w.w);
        }
    }
    // At most three keys are left past the last whole vector.
    uint tail_keys = (words_end - vectors_end * 4u) / KEY_WORDS;
    if (gl_LocalInvocationID.x < tail_keys) {
        count_word(key_words[vectors_end * 4u + gl_LocalInvocationID.x * KEY_WORDS + params.word]);
    }
    barrier();
    uint digits = 1u << params.digit_bits;
    for (uint d = gl_LocalInvocationID.x; d < digits; d += WORKGROUP_SIZE) {
        tile_counts[d * params.tile_count + tile] = tile_digit_counts[d];
    }
}
