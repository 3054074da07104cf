// Shared by scan_reduce.comp and scan_downsweep.comp. Mirrors engine/sort/scan.rs (ScanParams).
// Each workgroup owns a block of WORKGROUP_SIZE * ITEMS_PER_THREAD consecutive elements;
// invocation t owns ITEMS_PER_THREAD consecutive elements of it.
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require

layout(local_size_x_id = 0) in;
layout(constant_id = 0) const uint WORKGROUP_SIZE = 256;
layout(constant_id = 1) const uint SUBGROUP_SIZE = 32;
layout(constant_id = 2) const uint ITEMS_PER_THREAD = 4;
const uint MAX_SUBGROUPS = WORKGROUP_SIZE / SUBGROUP_SIZE;
const uint BLOCK_LEN = WORKGROUP_SIZE * ITEMS_PER_THREAD;

layout(push_constant) uniform ScanParams {
    uint len;             // elements in `data`
    uint has_block_offsets; // downsweep: add block_offsets[block] (0 for a single-block scan)
} params;

#include "../common/grid.glsl"
#include "../common/workgroup_scan.glsl"
