// Shared by rasterize.comp and rasterize_backward.comp: one workgroup per 16x16 tile, one
// invocation per pixel. Each subgroup walks the tile's depth-sorted Gaussians on its own, a
// chunk of gl_SubgroupSize at a time: lane l loads the chunk's l-th Gaussian, then every
// Gaussian of the chunk is broadcast to all lanes in turn. One load instruction thus fetches a
// whole chunk (on CPU devices every memory access is a loop over the lanes, so this matters
// most there), and no barrier or shared memory is needed.
#ifndef SPLAT_RASTER_COMMON_GLSL
#define SPLAT_RASTER_COMMON_GLSL

#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_vote : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_shuffle : require
#include "frame.glsl"

layout(local_size_x_id = 0) in; // TILE_SIZE * TILE_SIZE

// The device's subgroup size, as a constant: the loops over a chunk then have a constant trip
// count, which the compiler unrolls, so lavapipe's limit of 65 535 loop iterations per
// invocation (it ends loops silently) counts chunks, not Gaussians. Lanes past the real
// subgroup size, should a device run smaller subgroups, are skipped.
layout(constant_id = 1) const uint SUBGROUP_SIZE = 32;

layout(std430, binding = 0) readonly buffer Splats { Splat splats[]; };
layout(std430, binding = 1) readonly buffer TileRanges { uvec2 tile_ranges[]; };
layout(std430, binding = 2) readonly buffer Ids { uint gaussian_ids[]; };

struct Pixel {
    uint tile;
    uint index;   // y * width + x
    vec2 center;  // (x + 0.5, y + 0.5)
    bool inside;  // false for the tile's pixels past the image edge
};

Pixel this_pixel() {
    Pixel p;
    p.tile = gl_WorkGroupID.y * frame.size.z + gl_WorkGroupID.x;
    uint local = gl_LocalInvocationIndex;
    uvec2 xy = gl_WorkGroupID.xy * TILE_SIZE + uvec2(local % TILE_SIZE, local / TILE_SIZE);
    p.inside = xy.x < frame.size.x && xy.y < frame.size.y;
    p.index = xy.y * frame.size.x + xy.x;
    p.center = vec2(xy) + 0.5;
    return p;
}

// A Gaussian as the rasterizer sees it.
struct Chunk {
    vec4 mean_opacity_depth; // mean.xy, opacity, depth
    vec4 conic_id;           // conic, Gaussian id (bits)
    vec3 color;
};

// This lane's Gaussian of the chunk starting at `start` (zeros past `end`).
Chunk load_chunk(uint start, uint end) {
    uint at = start + gl_SubgroupInvocationID;
    Chunk c = Chunk(vec4(0.0), vec4(0.0), vec3(0.0));
    if (at < end) {
        uint id = gaussian_ids[at];
        Splat s = splats[id];
        c = Chunk(vec4(s.mean, s.opacity, s.depth), vec4(s.conic, uintBitsToFloat(id)), s.color.rgb);
    }
    return c;
}

// The chunk's g-th Gaussian, on every lane.
Chunk broadcast(Chunk c, uint g) {
    return Chunk(subgroupShuffle(c.mean_opacity_depth, g), subgroupShuffle(c.conic_id, g), subgroupShuffle(c.color, g));
}

// Alpha of Gaussian `c` at the pixel centre, with its falloff G = exp(-sigma) and offset d.
float alpha_at(Chunk c, vec2 center, out float falloff, out vec2 d) {
    vec3 conic = c.conic_id.xyz;
    d = center - c.mean_opacity_depth.xy;
    float sigma = 0.5 * (conic.x * d.x * d.x + conic.z * d.y * d.y) + conic.y * d.x * d.y;
    falloff = exp(-sigma);
    return min(ALPHA_MAX, c.mean_opacity_depth.z * falloff);
}

#endif
