// Shared by rasterize.comp and rasterize_backward.comp: one workgroup per 16x16 tile, one
// invocation per pixel; the tile's Gaussians are staged through shared memory a batch at a time.
#ifndef SPLAT_RASTER_COMMON_GLSL
#define SPLAT_RASTER_COMMON_GLSL

#include "frame.glsl"

layout(local_size_x_id = 0) in; // TILE_SIZE * TILE_SIZE
const uint BATCH = TILE_SIZE * TILE_SIZE;

layout(std430, binding = 0) readonly buffer Splats { Splat splats[]; };
layout(std430, binding = 1) readonly buffer TileRanges { uvec2 tile_ranges[]; };
layout(std430, binding = 2) readonly buffer Ids { uint gaussian_ids[]; };

shared vec4 batch_mean_opacity_depth[BATCH]; // mean.xy, opacity, depth
shared vec4 batch_conic[BATCH];              // conic, Gaussian id (bits)
shared vec4 batch_color[BATCH];

struct Pixel {
    uint tile;
    uint index;   // y * width + x
    vec2 center;  // (x + 0.5, y + 0.5)
    bool inside;  // false for the tile's pixels past the image edge
};

Pixel this_pixel() {
    Pixel p;
    p.tile = gl_WorkGroupID.y * frame.size.z + gl_WorkGroupID.x;
    uvec2 xy = gl_WorkGroupID.xy * TILE_SIZE + uvec2(gl_LocalInvocationIndex % TILE_SIZE, gl_LocalInvocationIndex / TILE_SIZE);
    p.inside = xy.x < frame.size.x && xy.y < frame.size.y;
    p.index = xy.y * frame.size.x + xy.x;
    p.center = vec2(xy) + 0.5;
    return p;
}

// Stages sorted intersections [start, start + BATCH) ∩ [start, end) into shared memory.
void load_batch(uint start, uint end) {
    uint at = start + gl_LocalInvocationIndex;
    if (at < end) {
        uint id = gaussian_ids[at];
        Splat s = splats[id];
        batch_mean_opacity_depth[gl_LocalInvocationIndex] = vec4(s.mean, s.opacity, s.depth);
        batch_conic[gl_LocalInvocationIndex] = vec4(s.conic, uintBitsToFloat(id));
        batch_color[gl_LocalInvocationIndex] = s.color;
    }
}

// Alpha of staged Gaussian j at the pixel centre, and its Gaussian falloff G and offset d.
float alpha_at(uint j, vec2 center, out float falloff, out vec2 d) {
    vec4 mod_ = batch_mean_opacity_depth[j];
    vec3 conic = batch_conic[j].xyz;
    d = center - mod_.xy;
    float sigma = 0.5 * (conic.x * d.x * d.x + conic.z * d.y * d.y) + conic.y * d.x * d.y;
    falloff = exp(-sigma);
    return min(ALPHA_MAX, mod_.z * falloff);
}

#endif
