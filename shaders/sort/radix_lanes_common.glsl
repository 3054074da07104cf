// Shared by radix_histogram_lanes.comp and radix_scatter_lanes.comp, the radix-sort variant
// for CPU devices (lavapipe). There a workgroup runs on one core and every memory access is a
// loop over the SIMD lanes, so cross-lane matching and shared atomics are what costs. Instead,
// each invocation owns a contiguous run of the tile and its own row of 256 digit counters:
// the tile's order is run 0, run 1, …, so ranks follow input order without any matching.
#include "radix_common.glsl"

const uint RUN_LEN = TILE_LEN / WORKGROUP_SIZE; // KEYS_PER_THREAD

shared uint run_digits[WORKGROUP_SIZE * RADIX]; // [invocation][digit]

// Key range [begin, end) of this invocation's run of `tile`, and the end of its whole groups
// of 4 keys (runs start on multiples of 4, so those groups are whole 16-byte vectors).
uvec3 run_range(uint tile) {
    uint begin = min(tile * TILE_LEN + gl_LocalInvocationID.x * RUN_LEN, params.len);
    uint end = min(begin + RUN_LEN, params.len);
    return uvec3(begin, end, begin + ((end - begin) & ~3u));
}
