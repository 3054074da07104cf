#version 460
// SSIM forward, pass 2 of 2, fused with the loss value and the first half of the backward:
// the vertical filter completes the moments; S of each render and its partial derivatives
// with respect to the filtered μx, E[x²], E[xy] (scaled by dL/dS) go to the backward; each
// render's SSIM terms are summed per channel (the first pass summed the L1 terms).
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_EXT_control_flow_attributes : require
#include "loss.glsl"
#include "../common/fixed_sum.glsl"
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer Weight { float weight[]; };
layout(std430, binding = 1) readonly buffer MeanY { u64vec2 mean_y[]; };
layout(std430, binding = 2) readonly buffer MeanYY { u64vec2 mean_yy[]; };
// One plane per render (loss.glsl `plane`).
layout(std430, binding = 3) readonly buffer MeanX { u64vec2 mean_x[]; };
layout(std430, binding = 4) readonly buffer MeanXX { u64vec2 mean_xx[]; };
layout(std430, binding = 5) readonly buffer MeanXY { u64vec2 mean_xy[]; };
layout(std430, binding = 6) writeonly buffer DMeanX { u64vec2 d_mean_x[]; };
layout(std430, binding = 7) writeonly buffer DMeanXX { u64vec2 d_mean_xx[]; };
layout(std430, binding = 8) writeonly buffer DMeanXY { u64vec2 d_mean_xy[]; };
// Per render and channel: [0..4) the mean absolute error, [4..8) the mean of 1 − S
// (unweighted by λ); fixed_sum.glsl, 8 sums each.
layout(std430, binding = 9) buffer TermSumsA { int64_t term_sums_a[]; };
layout(std430, binding = 10) buffer TermSumsB { int64_t term_sums_b[]; };  // RENDERS = 2 only

// Row `i` of the run's span in column x, clamped into the image: a clamped value reaches only
// outputs outside the SSIM region.
uint span_pixel(uint x, uint y0, int i) {
    return uint(clamp(int(y0) - RADIUS + i, 0, int(height()) - 1)) * width() + x;
}

// The vertical filter of output j of the run from a span of moments.
#define FILTER(span, j, out_) {                                                  \
    out_ = vec4(0.0);                                                            \
    [[unroll]] for (int k_ = 0; k_ < TAPS; k_++) out_ += params.window[k_] * span[(j) + k_]; \
}

void main() {
    uint x, y0;
    bool inside = column_run(gl_GlobalInvocationID.x, x, y0);
    bool column_valid = inside && x >= uint(RADIUS) && x + uint(RADIUS) < width();
    vec4 ssim_sum[2] = vec4[2](vec4(0.0), vec4(0.0));
    // The target's filtered moments, shared by the renders.
    vec4 b[RUN], yy[RUN];
    if (column_valid) {
        vec4 span_y[SPAN], span_yy[SPAN];
        [[unroll]] for (int i = 0; i < SPAN; i++) {
            uint p = span_pixel(x, y0, i);
            span_y[i] = unpack_vec4(mean_y[p]);
            span_yy[i] = unpack_vec4(mean_yy[p]);
        }
        [[unroll]] for (int j = 0; j < RUN; j++) {
            FILTER(span_y, j, b[j]);
            FILTER(span_yy, j, yy[j]);
        }
    }
    [[unroll]] for (uint r = 0u; r < RENDERS; r++) {
        if (!inside) break;
        vec4 a[RUN], xx[RUN], xy[RUN];
        if (column_valid) {
            vec4 span_x[SPAN], span_xx[SPAN], span_xy[SPAN];
            [[unroll]] for (int i = 0; i < SPAN; i++) {
                uint p = plane(r) + span_pixel(x, y0, i);
                span_x[i] = unpack_vec4(mean_x[p]);
                span_xx[i] = unpack_vec4(mean_xx[p]);
                span_xy[i] = unpack_vec4(mean_xy[p]);
            }
            [[unroll]] for (int j = 0; j < RUN; j++) {
                FILTER(span_x, j, a[j]);
                FILTER(span_xx, j, xx[j]);
                FILTER(span_xy, j, xy[j]);
            }
        }
        vec4 lambda = params.channel_weights[r];
        [[unroll]] for (int j = 0; j < RUN; j++) {
            if (y0 + uint(j) >= height()) break;
            uint y = y0 + uint(j);
            uint p = y * width() + x;
            float w = 1.0;
            if (has_weight()) w = weight[p];
            vec4 da = vec4(0.0), dxx = vec4(0.0), dxy = vec4(0.0);
            if (column_valid && ssim_valid(x, y)) {
                vec4 n1 = 2.0 * a[j] * b[j] + C1;
                vec4 n2 = 2.0 * (xy[j] - a[j] * b[j]) + C2;
                vec4 d1 = a[j] * a[j] + b[j] * b[j] + C1;
                vec4 d2 = (xx[j] - a[j] * a[j]) + (yy[j] - b[j] * b[j]) + C2;
                // Two divisions where the quotient rule has six (C1, C2 > 0 keep d1, d2 > 0).
                vec4 inverse_d1 = 1.0 / d1, inverse_d2 = 1.0 / d2;
                vec4 inverse_d = inverse_d1 * inverse_d2;
                vec4 s = n1 * n2 * inverse_d;
                ssim_sum[r] += w * (1.0 - s);
                // dL/dS of this pixel (the SSIM term is λ · share · mean(w (1 − S))); the
                // quotient rule is written so no factor divides by n1 or n2, which may be zero.
                vec4 ds = -lambda * params.scales.y * params.scales.w * w;
                da = ds * (2.0 * b[j] * (n2 - n1) * inverse_d
                           - 2.0 * a[j] * s * (inverse_d1 - inverse_d2));
                dxx = ds * (-s * inverse_d2);
                dxy = ds * (2.0 * n1 * inverse_d);
            }
            uint q = plane(r) + p;
            d_mean_x[q] = pack_vec4(da);
            d_mean_xx[q] = pack_vec4(dxx);
            d_mean_xy[q] = pack_vec4(dxy);
        }
    }
    ADD_TERMS(4u, ssim_sum, params.scales.w);
}
