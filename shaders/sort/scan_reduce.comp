#version 460
// Exclusive scan, step 1 of 2: block_sums[b] = sum of block b of data.
#include "scan_common.glsl"

layout(std430, binding = 0) readonly buffer Data { uint data[]; };
layout(std430, binding = 1) writeonly buffer BlockSums { uint block_sums[]; };

void main() {
    uint block = flat_workgroup_id();
    uint first = block * BLOCK_LEN + gl_LocalInvocationID.x * ITEMS_PER_THREAD;
    if (block * BLOCK_LEN >= params.len) {
        return; // Whole workgroup: past the end of a folded grid.
    }
    uint sum = 0u;
    for (uint k = 0u; k < ITEMS_PER_THREAD; k++) {
        uint i = first + k;
        sum += i < params.len ? data[i] : 0u;
    }
    uint total;
    workgroup_exclusive_add(sum, total);
    if (gl_LocalInvocationID.x == 0u) {
        block_sums[block] = total;
    }
}
