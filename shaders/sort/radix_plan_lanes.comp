#version 460
// Radix sort, CPU-device variant, bucket path step 1b (after the histogram and scan of the
// top digit): chooses the path. The bucket path needs every bucket to fit one invocation's
// loop budget (params.max_bucket_len, see radix_bucket_lanes.comp); otherwise the LSD passes
// run. One invocation does it all: 256 reads.
#include "radix_common.glsl"

layout(std430, binding = 0) readonly buffer TopDigitOffsets { uint tile_offsets[]; }; // scanned, digit-major
layout(std430, binding = 1) writeonly buffer Plan { uint plan[]; };

void main() {
    if (gl_GlobalInvocationID.x != 0u) {
        return;
    }
    // Tile 0 of each digit starts that digit's bucket; the scan starts at 0.
    uint largest = 0u;
    uint begin = 0u;
    for (uint d = 1u; d <= RADIX; d++) {
        uint end = d < RADIX ? tile_offsets[d * params.tile_count] : params.len;
        largest = max(largest, end - begin);
        begin = end;
    }
    plan[0] = largest <= params.max_bucket_len ? 1u : 0u;
}
