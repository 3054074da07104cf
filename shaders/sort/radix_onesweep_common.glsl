// Shared by the Onesweep variant's kernels that touch status words
// (radix_onesweep_histogram.comp, radix_onesweep.comp). Include after radix_common.glsl.
//
// The variant reads the keys once to count the digits of every pass, then runs one kernel per
// pass. In it each workgroup takes the next tile (its partition) from an atomic counter, ranks
// its keys, publishes its digit counts in a status word per (tile, digit), looks back over
// earlier tiles' words for its exclusive prefix per digit, and scatters.
#ifndef SORT_RADIX_ONESWEEP_COMMON_GLSL
#define SORT_RADIX_ONESWEEP_COMMON_GLSL

// A u64 key has 8 passes of 8 bits.
const uint MAX_PASSES = 8u;

// Status words: [pass parity][tile][digit], a flag in the top 2 bits over a count. Two
// copies, so that each pass clears the next pass's words as it goes (the histogram kernel
// clears the first pass's); no fill of the whole buffer is needed between passes.
layout(std430, binding = STATUS_BINDING) coherent volatile buffer Status { uint status[]; };

// The LSD pass of params (its digit's lowest bit over 8).
uint pass_index() {
    return (params.word * 32u + params.shift) / RADIX_BITS;
}

uint status_index(uint pass, uint tile, uint digit) {
    return ((pass & 1u) * params.tile_count + tile) * RADIX + digit;
}

// Zeroes `tile`'s status words of pass `pass`, before any workgroup of that pass runs.
void clear_status(uint pass, uint tile) {
    for (uint d = gl_LocalInvocationID.x; d < RADIX; d += WORKGROUP_SIZE) {
        status[status_index(pass, tile, d)] = 0u;
    }
}

#endif
