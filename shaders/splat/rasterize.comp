#version 460
// Rasterization, forward: front-to-back compositing of the tile's depth-sorted Gaussians.
// Besides colour, alpha and expected depth, it keeps per pixel what the backward pass needs to
// walk the same Gaussians back to front: the final transmittance and how many it walked.
#include "raster_common.glsl"

layout(std430, binding = 3) writeonly buffer Rgba { vec4 out_rgba[]; };        // colour, alpha
layout(std430, binding = 4) writeonly buffer Depth { float out_depth[]; };
layout(std430, binding = 5) writeonly buffer PixelState { uvec2 pixel_state[]; }; // T bits, walked

void main() {
    Pixel px = this_pixel();
    uvec2 range = tile_ranges[px.tile];
    float transmittance = 1.0;
    vec3 color = vec3(0.0);
    float depth = 0.0;
    uint walked = 0u;
    bool done = !px.inside;
    for (uint start = range.x; start < range.y && !subgroupAll(done); start += gl_SubgroupSize) {
        Chunk mine = load_chunk(start, range.y);
        // A constant trip count (see SUBGROUP_SIZE); lanes past the range hold zero opacity.
        for (uint g = 0u; g < SUBGROUP_SIZE; g++) {
            Chunk c = broadcast(mine, g);
            float falloff;
            vec2 d;
            float alpha = alpha_at(c, px.center, falloff, d);
            float next = transmittance * (1.0 - alpha);
            if (done || alpha < ALPHA_MIN || g >= gl_SubgroupSize) {
                continue;
            }
            if (next < TRANSMITTANCE_MIN) {
                done = true;
                continue;
            }
            float weight = alpha * transmittance;
            color += c.color * weight;
            depth += c.mean_opacity_depth.w * weight;
            transmittance = next;
            walked = start - range.x + g + 1u;
        }
    }
    if (px.inside) {
        float alpha = 1.0 - transmittance;
        out_rgba[px.index] = vec4(color + transmittance * frame.background_far.rgb, alpha);
        out_depth[px.index] = alpha >= DEPTH_ALPHA_MIN ? depth / alpha : 0.0;
        pixel_state[px.index] = uvec2(floatBitsToUint(transmittance), walked);
    }
}
