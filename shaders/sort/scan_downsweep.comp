#version 460
// Exclusive scan, step 2 of 2: scans each block of data in place and adds the block's offset
// (the exclusive scan of block_sums, done by recursion on the host side).
#include "scan_common.glsl"

layout(std430, binding = 0) buffer Data { uint data[]; };
layout(std430, binding = 1) readonly buffer BlockOffsets { uint block_offsets[]; };

void main() {
    uint block = flat_workgroup_id();
    if (block * BLOCK_LEN >= params.len) {
        return;
    }
    uint first = block * BLOCK_LEN + gl_LocalInvocationID.x * ITEMS_PER_THREAD;
    uint items[ITEMS_PER_THREAD];
    uint sum = 0u;
    for (uint k = 0u; k < ITEMS_PER_THREAD; k++) {
        uint i = first + k;
        items[k] = i < params.len ? data[i] : 0u;
        sum += items[k];
    }
    uint total;
    uint running = workgroup_exclusive_add(sum, total);
    if (params.has_block_offsets != 0u) {
        running += block_offsets[block];
    }
    for (uint k = 0u; k < ITEMS_PER_THREAD; k++) {
        uint i = first + k;
        if (i < params.len) {
            data[i] = running;
        }
        running += items[k];
    }
}
