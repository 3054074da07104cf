#version 460
// Radix sort, Onesweep variant, step 1: the digit counts of every pass in one read of the
// keys. Each workgroup counts its tile in shared memory, then adds each nonzero count to the
// global one (digit_counts[pass][digit], zeroed before), so global atomics number at most
// passes × 256 per tile whatever the keys. It also clears the first pass's status words of its
// tile (radix_onesweep_common.glsl).
#define STATUS_BINDING 2
#include "radix_common.glsl"
#include "radix_onesweep_common.glsl"

layout(std430, binding = 0) readonly buffer KeyWords { uint key_words[]; };
layout(std430, binding = 1) buffer DigitCounts { uint digit_counts[]; };

shared uint tile_counts[MAX_PASSES * RADIX];

// Counts the digits of every pass of the key (lo, hi).
void count_key(uint lo, uint hi, uint passes) {
    for (uint pass = 0u; pass < passes; pass++) {
        uint low = pass * RADIX_BITS;
        uint width = min(RADIX_BITS, params.bits - low);
        uint digit = ((low < 32u ? lo : hi) >> (low % 32u)) & ((1u << width) - 1u);
        atomicAdd(tile_counts[pass * RADIX + digit], 1u);
    }
}

void main() {
    uint tile = flat_workgroup_id();
    if (tile >= params.tile_count) {
        return;
    }
    clear_status(0u, tile);
    uint passes = (params.bits + RADIX_BITS - 1u) / RADIX_BITS;
    for (uint i = gl_LocalInvocationID.x; i < passes * RADIX; i += WORKGROUP_SIZE) {
        tile_counts[i] = 0u;
    }
    barrier();
    uint end = min((tile + 1u) * TILE_LEN, params.len);
    for (uint i = tile * TILE_LEN + gl_LocalInvocationID.x; i < end; i += WORKGROUP_SIZE) {
        count_key(key_words[i * KEY_WORDS], KEY_WORDS == 2u ? key_words[i * 2u + 1u] : 0u, passes);
    }
    barrier();
    for (uint i = gl_LocalInvocationID.x; i < passes * RADIX; i += WORKGROUP_SIZE) {
        uint count = tile_counts[i];
        if (count != 0u) {
            atomicAdd(digit_counts[i], count);
        }
    }
}
