#version 460
// Rasterization, backward: each pixel walks the Gaussians it composited back to front,
// recovering the transmittance before each by division, and forms the gradients of its
// colour, alpha and expected depth with respect to every Gaussian's 2D mean, conic, opacity,
// colour and depth. Per Gaussian, the subgroup sums its pixels' gradients and the sum is kept
// by the lane that loaded that Gaussian; after each chunk every lane adds its Gaussian's sums
// to the global row with float atomics, all lanes in one instruction.
#extension GL_EXT_shader_atomic_float : require
#include "raster_common.glsl"
#include "grad2d.glsl"

layout(std430, binding = 3) readonly buffer Rgba { vec4 rgba[]; };
layout(std430, binding = 4) readonly buffer Depth { float depth_out[]; };
layout(std430, binding = 5) readonly buffer PixelState { uvec2 pixel_state[]; };
layout(std430, binding = 6) readonly buffer GradRgba { vec4 grad_rgba[]; };    // dL/dcolour, dL/dalpha
layout(std430, binding = 7) readonly buffer GradDepth { float grad_depth[]; };
layout(std430, binding = 8) buffer Grad2d { float grad2d[]; };                // GRAD2D_STRIDE per Gaussian

void main() {
    Pixel px = this_pixel();
    uvec2 range = tile_ranges[px.tile];
    uvec2 state = px.inside ? pixel_state[px.index] : uvec2(floatBitsToUint(1.0), 0u);

    // Colour and alpha gradients as they are; depth is D / A, so its gradient splits into one
    // on D (the weighted depth sum) and one more on A.
    vec4 g_rgba = px.inside ? grad_rgba[px.index] : vec4(0.0);
    float final_t = uintBitsToFloat(state.x);
    float alpha_out = 1.0 - final_t;
    float g_depth_sum = 0.0;
    float g_alpha = g_rgba.a;
    if (px.inside && alpha_out >= DEPTH_ALPHA_MIN) {
        float g_depth = grad_depth[px.index];
        g_depth_sum = g_depth / alpha_out;
        g_alpha -= g_depth * depth_out[px.index] / alpha_out;
    }
    vec3 behind_color = final_t * frame.background_far.rgb; // what lies behind, background included
    float behind_depth = 0.0;
    float transmittance = final_t;

    uint walked = subgroupMax(state.y);
    for (uint chunk = (walked + gl_SubgroupSize - 1u) / gl_SubgroupSize; chunk > 0u; chunk--) {
        uint start = range.x + (chunk - 1u) * gl_SubgroupSize;
        uint end = range.x + walked;
        Chunk mine = load_chunk(start, end);
        float sums[GRAD2D_STRIDE]; // of the Gaussian this lane loaded
        for (uint k = 0u; k < GRAD2D_STRIDE; k++) {
            sums[k] = 0.0;
        }
        for (uint g = min(gl_SubgroupSize, end - start); g > 0u; g--) {
            Chunk c = broadcast(mine, g - 1u);
            float falloff;
            vec2 d;
            float alpha = alpha_at(c, px.center, falloff, d);
            bool contributes = start - range.x + g - 1u < state.y && alpha >= ALPHA_MIN;
            if (!subgroupAny(contributes)) {
                continue;
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
                transmittance /= one_minus;
                float weight = alpha * transmittance;
                float g_a = dot(g_rgba.rgb, c.color * transmittance - behind_color / one_minus)
                          + g_alpha * final_t / one_minus
                          + g_depth_sum * (depth * transmittance - behind_depth / one_minus);
                behind_color += c.color * weight;
                behind_depth += depth * weight;
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
                values[GRAD2D_COLOR] = g_rgba.r * weight;
                values[GRAD2D_COLOR + 1u] = g_rgba.g * weight;
                values[GRAD2D_COLOR + 2u] = g_rgba.b * weight;
                values[GRAD2D_DEPTH] = g_depth_sum * weight;
            }
            // Three vector reductions rather than ten scalar ones.
            vec4 a = subgroupAdd(vec4(values[0], values[1], values[2], values[3]));
            vec4 b = subgroupAdd(vec4(values[4], values[5], values[6], values[7]));
            vec2 e = subgroupAdd(vec2(values[8], values[9]));
            if (gl_SubgroupInvocationID == g - 1u) {
                sums = float[GRAD2D_STRIDE](a.x, a.y, a.z, a.w, b.x, b.y, b.z, b.w, e.x, e.y);
            }
        }
        if (start + gl_SubgroupInvocationID < end) {
            uint id = floatBitsToUint(mine.conic_id.w);
            for (uint k = 0u; k < GRAD2D_STRIDE; k++) {
                if (sums[k] != 0.0) {
                    atomicAdd(grad2d[id * GRAD2D_STRIDE + k], sums[k]);
                }
            }
        }
    }
}
