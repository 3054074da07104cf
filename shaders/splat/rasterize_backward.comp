#version 460
// Rasterization, backward: each pixel walks the Gaussians it composited back to front,
// recovering the transmittance before each by division, and forms the gradients of its
// colour, alpha and expected depth with respect to every Gaussian's 2D mean, conic, opacity,
// colour and depth. Per Gaussian, the subgroup sums its pixels' gradients and the sum is kept
// by the lane that loaded that Gaussian; after each chunk every lane adds its Gaussian's sums
// to the global row in fixed point (order-independent, so runs repeat bit for bit), all lanes
// in one instruction. fixed_resolve.comp turns the rows into floats.
#include "raster_common.glsl"
#include "grad2d.glsl"
#include "../common/fixed_sum.glsl"

layout(std430, binding = 4) readonly buffer Depth { float depth_out[]; };
layout(std430, binding = 5) readonly buffer PixelState { uvec2 pixel_state[]; };
layout(std430, binding = 6) readonly buffer GradRgba { vec4 grad_rgba[]; };    // dL/dcolour, dL/dalpha
layout(std430, binding = 7) readonly buffer GradDepth { float grad_depth[]; };
layout(std430, binding = 8) buffer Grad2dSums { int64_t grad2d_sums[]; };       // GRAD2D_STRIDE sums per Gaussian

// What a pixel's back-to-front walk knows: its loss gradients and its own compositing.
struct PixelGrads {
    vec3 color;       // dL/dcolour
    float alpha;      // dL/dalpha, with the depth term's share
    float depth_sum;  // dL/d(weighted depth sum)
    float final_t;    // transmittance after every Gaussian it walked
    vec2 center;
    uint walked;      // Gaussians it composited (the forward's count)
};

// What the walk carries from one Gaussian to the one in front of it.
struct Behind {
    float transmittance; // before the Gaussians behind
    vec3 color;          // what they and the background show, weighted
    float depth;
};

// Steps back over Gaussian `lane` of the chunk (at `offset` into the tile's list): this pixel's
// gradients with respect to it, summed over the subgroup into `sums` of the lane that loaded it.
void step_back(Chunk mine, uint lane, uint offset, PixelGrads p, inout Behind behind, inout float sums[GRAD2D_STRIDE]) {
    Chunk c = broadcast(mine, lane);
    float falloff;
    vec2 d;
    float alpha = alpha_at(c, p.center, falloff, d);
    bool contributes = offset + lane < p.walked && alpha >= ALPHA_MIN && lane < gl_SubgroupSize;
    if (!subgroupAny(contributes)) {
        return;
    }
    float values[GRAD2D_STRIDE];
    for (uint k = 0u; k < GRAD2D_STRIDE; k++) {
        values[k] = 0.0;
    }
    if (contributes) {
        float opacity = c.mean_opacity_depth.z;
        float depth = c.mean_opacity_depth.w;
        vec3 conic = c.conic_id.xyz;
        float one_minus = 1.0 - alpha;
        behind.transmittance /= one_minus;
        float t = behind.transmittance;
        float weight = alpha * t;
        float g_a = dot(p.color, c.color * t - behind.color / one_minus)
                  + p.alpha * p.final_t / one_minus
                  + p.depth_sum * (depth * t - behind.depth / one_minus);
        behind.color += c.color * weight;
        behind.depth += depth * weight;
        // alpha = min(0.99, o G): the cap passes no gradient.
        if (opacity * falloff < ALPHA_MAX) {
            float g_sigma = -g_a * opacity * falloff;
            vec2 g_mean = -g_sigma * vec2(conic.x * d.x + conic.y * d.y, conic.y * d.x + conic.z * d.y);
            values[GRAD2D_MEAN] = g_mean.x;
            values[GRAD2D_MEAN + 1u] = g_mean.y;
            values[GRAD2D_CONIC] = g_sigma * 0.5 * d.x * d.x;
            values[GRAD2D_CONIC + 1u] = g_sigma * d.x * d.y;
            values[GRAD2D_CONIC + 2u] = g_sigma * 0.5 * d.y * d.y;
            values[GRAD2D_OPACITY] = g_a * falloff;
        }
        values[GRAD2D_COLOR] = p.color.r * weight;
        values[GRAD2D_COLOR + 1u] = p.color.g * weight;
        values[GRAD2D_COLOR + 2u] = p.color.b * weight;
        values[GRAD2D_DEPTH] = p.depth_sum * weight;
    }
    // Three vector reductions rather than ten scalar ones.
    vec4 a = subgroupAdd(vec4(values[0], values[1], values[2], values[3]));
    vec4 b = subgroupAdd(vec4(values[4], values[5], values[6], values[7]));
    vec2 e = subgroupAdd(vec2(values[8], values[9]));
    if (gl_SubgroupInvocationID == lane) {
        sums = float[GRAD2D_STRIDE](a.x, a.y, a.z, a.w, b.x, b.y, b.z, b.w, e.x, e.y);
    }
}

// Steps back over chunk `chunk` (1-based) of the walk, `steps` Gaussians per loop iteration
// (1, or 4 unrolled by hand), then adds each Gaussian's sums to its global row, all lanes at once.
void walk_chunk(uint chunk, uint steps, uvec2 range, uint walked, PixelGrads p, inout Behind behind) {
    uint offset = (chunk - 1u) * gl_SubgroupSize;
    uint start = range.x + offset;
    uint end = range.x + walked;
    Chunk mine = load_chunk(start, end);
    float sums[GRAD2D_STRIDE]; // of the Gaussian this lane loaded
    for (uint k = 0u; k < GRAD2D_STRIDE; k++) {
        sums[k] = 0.0;
    }
    // Back to front; lanes past `end` hold zero opacity.
    for (uint lane = SUBGROUP_SIZE; lane > 0u; lane -= steps) {
        step_back(mine, lane - 1u, offset, p, behind, sums);
        if (steps == 4u) {
            step_back(mine, lane - 2u, offset, p, behind, sums);
            step_back(mine, lane - 3u, offset, p, behind, sums);
            step_back(mine, lane - 4u, offset, p, behind, sums);
        }
    }
    if (start + gl_SubgroupInvocationID < end) {
        uint id = floatBitsToUint(mine.conic_id.w);
        for (uint k = 0u; k < GRAD2D_STRIDE; k++) {
            FIXED_ADD_GRADIENT(grad2d_sums, id * GRAD2D_STRIDE + k, sums[k]);
        }
    }
}

// lavapipe ends an invocation's loops after 65 535 iterations in all, silently. A chunk costs
// 2 + SUBGROUP_SIZE / steps of them (measured: one more than the loops' back-edges); one step
// per iteration is the fastest code (four copies of the step run 20 % slower there), so only
// walks longer than SHORT_WALK_CHUNKS take four. Subgroups smaller than four always take one.
const uint SHORT_WALK_CHUNKS = 60000u / (2u + SUBGROUP_SIZE);
const uint LONG_WALK_STEPS = SUBGROUP_SIZE < 4u ? 1u : 4u;

void main() {
    Pixel px = this_pixel();
    uvec2 range = tile_ranges[px.tile];
    uvec2 state = px.inside ? pixel_state[px.index] : uvec2(floatBitsToUint(1.0), 0u);

    // Colour and alpha gradients as they are; depth is D / A, so its gradient splits into one
    // on D (the weighted depth sum) and one more on A.
    vec4 g_rgba = px.inside ? grad_rgba[px.index] : vec4(0.0);
    PixelGrads p = PixelGrads(g_rgba.rgb, g_rgba.a, 0.0, uintBitsToFloat(state.x), px.center, state.y);
    float alpha_out = 1.0 - p.final_t;
    if (px.inside && alpha_out >= DEPTH_ALPHA_MIN) {
        float g_depth = grad_depth[px.index];
        p.depth_sum = g_depth / alpha_out;
        p.alpha -= g_depth * depth_out[px.index] / alpha_out;
    }
    Behind behind = Behind(p.final_t, p.final_t * frame.background_far.rgb, 0.0);

    uint walked = subgroupMax(state.y);
    uint chunks = (walked + gl_SubgroupSize - 1u) / gl_SubgroupSize;
    // gallivm runs an untaken `if` body anyway (masked), so the walk not chosen gets no chunks.
    bool long_walk = chunks > SHORT_WALK_CHUNKS;
    for (uint chunk = long_walk ? 0u : chunks; chunk > 0u; chunk--) {
        walk_chunk(chunk, 1u, range, walked, p, behind);
    }
    for (uint chunk = long_walk ? chunks : 0u; chunk > 0u; chunk--) {
        walk_chunk(chunk, LONG_WALK_STEPS, range, walked, p, behind);
    }
}
