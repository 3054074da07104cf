#version 460
// Binning: one invocation per sorted intersection marks where its tile's run starts and ends.
// Tiles without intersections keep the (0, 0) the host filled in. Unfilled slots past the
// intersections carry an all-ones key: a tile past every real one, sorted last.
#include "../common/grid.glsl"
#include "intersection_key.glsl"

layout(local_size_x_id = 0) in;

layout(push_constant) uniform RangeParams {
    uint intersections;  // slots, filled or not
    uint tile_count;
} params;

layout(std430, binding = 0) readonly buffer Keys { uint keys[]; };
layout(std430, binding = 1) buffer TileRanges { uvec2 tile_ranges[]; };

void main() {
    uint i = flat_workgroup_id() * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
    if (i >= params.intersections) {
        return;
    }
    uint tile = key_tile(keys[i], params.tile_count);
    if (tile >= params.tile_count) {
        return;
    }
    if (i == 0u || key_tile(keys[i - 1u], params.tile_count) != tile) {
        tile_ranges[tile].x = i;
    }
    if (i + 1u == params.intersections || key_tile(keys[i + 1u], params.tile_count) != tile) {
        tile_ranges[tile].y = i + 1u;
    }
}
