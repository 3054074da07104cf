#version 460
// Binning: one invocation per Gaussian writes a (key, Gaussian) pair for every tile it touches,
// from its scanned offset, keyed by tile, then depth (intersection_key.glsl). The buffers
// hold a capacity the host chose before the count was known: pairs past it are dropped (the
// host sees the count, grows the buffers and renders again), and slots no pair fills keep the
// all-ones key the host filled in, which sorts last and names no tile.
#include "footprint.glsl"
#include "../common/grid.glsl"
#include "intersection_key.glsl"

layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer Splats { Splat splats[]; };
layout(std430, binding = 1) readonly buffer TileOffsets { uint tile_offsets[]; };
layout(std430, binding = 2) writeonly buffer Keys { uint keys[]; };
layout(std430, binding = 3) writeonly buffer Ids { uint gaussian_ids[]; };
layout(std430, binding = 4) readonly buffer DepthRange { uvec2 depth_range; };

void main() {
    uint i = flat_workgroup_id() * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
    if (i >= gaussian_count()) {
        return;
    }
    Splat s = splats[i];
    uint at = tile_offsets[i];
    uint tile_count = frame.size.z * frame.size.w;
    for (uint ty = s.tile_rect.z; ty < s.tile_rect.w; ty++) {
        for (uint tx = s.tile_rect.x; tx < s.tile_rect.y; tx++) {
            if (touches_tile(s, uvec2(tx, ty)) && at < keys.length()) {
                keys[at] = intersection_key(ty * frame.size.z + tx, s.depth, depth_range, tile_count);
                gaussian_ids[at] = i;
                at++;
            }
        }
    }
}
