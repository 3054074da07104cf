#version 460
// Large-triangle raster: one workgroup per 16x16 tile, one invocation per pixel. The tile
// walks its own list of large sub-triangles (setup.comp binned them), or the list of all large
// ones if its own overflowed, in chunks: those whose bounds touch the tile go to shared
// memory, and each pixel tests only those; one atomicMin per pixel at the end.
#extension GL_EXT_shader_atomic_int64 : require
#include "raster.glsl"

layout(local_size_x = 16, local_size_y = 16) in;

layout(std430, binding = 0) readonly buffer SubTriangles { SubTriangle subs[]; };
layout(std430, binding = 1) buffer Visibility { uint64_t visibility[]; };
layout(std430, binding = 2) readonly buffer LargeList { uint large_list[]; };
layout(std430, binding = 3) readonly buffer Counters { uint counters[]; };
layout(std430, binding = 4) buffer WriteCounts { uint write_counts[]; };
layout(std430, binding = 5) readonly buffer TileCounts { uint tile_counts[]; };
layout(std430, binding = 6) readonly buffer TileLists { uint tile_lists[]; };

const uint CHUNK = TILE_SIZE * TILE_SIZE;
shared SubTriangle chunk[CHUNK];
shared uint chunk_count;

void main() {
    ivec2 tile_lo = ivec2(gl_WorkGroupID.xy * TILE_SIZE);
    ivec2 tile_hi = tile_lo + int(TILE_SIZE) - 1;
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    bool inside = pixel.x < int(image_width()) && pixel.y < int(image_height());
    bool count = (params.counts.z & FLAG_COUNT_WRITES) != 0u;
    uint local = gl_LocalInvocationIndex;
    uint tile = gl_WorkGroupID.y * params.size.z + gl_WorkGroupID.x;
    uint binned = tile_counts[tile];
    bool own_list = binned <= TILE_LIST_CAPACITY;
    uint total = own_list ? binned : counters[0];
    uint64_t best = EMPTY_PIXEL;
    uint writes = 0u;
    for (uint base = 0u; base < total; base += CHUNK) {
        if (local == 0u) {
            chunk_count = 0u;
        }
        barrier();
        if (base + local < total) {
            uint entry = base + local;
            SubTriangle t = subs[own_list ? tile_lists[tile * TILE_LIST_CAPACITY + entry] : large_list[entry]];
            ivec4 b = pixel_bounds(t);
            if (b.x <= tile_hi.x && b.z >= tile_lo.x && b.y <= tile_hi.y && b.w >= tile_lo.y) {
                chunk[atomicAdd(chunk_count, 1u)] = t;
            }
        }
        barrier();
        if (inside) {
            for (uint i = 0u; i < chunk_count; i++) {
                uint64_t key = coverage_key(chunk[i], pixel);
                writes += key != EMPTY_PIXEL ? 1u : 0u;
                best = min(best, key);
            }
        }
        barrier();
    }
    if (inside && best != EMPTY_PIXEL) {
        uint i = pixel_index(pixel);
        atomicMin(visibility[i], best);
        if (count) {
            atomicAdd(write_counts[i], writes);
        }
    }
}
