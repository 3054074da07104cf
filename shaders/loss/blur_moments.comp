#version 460
// SSIM forward, pass 1 of 2: the horizontal Gaussian filter of every channel's moments at the
// columns where a whole window fits (the target's y and y² once, each render's x, x² and xy),
// and each render's L1 term, from the span's centre pixels this pass loads anyway.
#extension GL_EXT_control_flow_attributes : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "loss.glsl"
#include "../common/fixed_sum.glsl"
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer RenderA { u64vec2 render_a[]; };
layout(std430, binding = 1) readonly buffer RenderB { u64vec2 render_b[]; };  // RENDERS = 2 only
layout(std430, binding = 2) readonly buffer Target { u64vec2 target[]; };
layout(std430, binding = 3) writeonly buffer MeanY { u64vec2 mean_y[]; };
layout(std430, binding = 4) writeonly buffer MeanYY { u64vec2 mean_yy[]; };
// One plane per render (loss.glsl `plane`).
layout(std430, binding = 5) writeonly buffer MeanX { u64vec2 mean_x[]; };
layout(std430, binding = 6) writeonly buffer MeanXX { u64vec2 mean_xx[]; };
layout(std430, binding = 7) writeonly buffer MeanXY { u64vec2 mean_xy[]; };
layout(std430, binding = 8) readonly buffer Weight { float weight[]; };
// Per render and channel: [0..4) the mean absolute error, [4..8) the mean of 1 − S
// (unweighted by λ); fixed_sum.glsl, 8 sums each. This pass adds the first four.
layout(std430, binding = 9) buffer TermSumsA { int64_t term_sums_a[]; };
layout(std430, binding = 10) buffer TermSumsB { int64_t term_sums_b[]; };  // RENDERS = 2 only

// Pixel `i` of the run's span, clamped into the row: a clamped value reaches only outputs
// outside the SSIM region, which are not written.
uint span_pixel(uint row, uint x0, int i) {
    return row + uint(clamp(int(x0) - RADIUS + i, 0, int(width()) - 1));
}

bool column_valid(uint x) { return x >= uint(RADIUS) && x + uint(RADIUS) < width(); }

// The run's moments, and its L1 terms added to `l1_sum`.
void moments(uint y, uint x0, inout vec4 l1_sum[2]) {
    uint row = y * width();
    float w[RUN];
    [[unroll]] for (int j = 0; j < RUN; j++) {
        w[j] = 1.0;
        if (has_weight() && x0 + uint(j) < width()) w[j] = weight[row + x0 + uint(j)];
    }
    vec4 t[SPAN];
    [[unroll]] for (int i = 0; i < SPAN; i++) t[i] = unpack_vec4(target[span_pixel(row, x0, i)]);
    [[unroll]] for (int j = 0; j < RUN; j++) {
        if (!column_valid(x0 + uint(j))) continue;
        vec4 my = vec4(0.0), myy = vec4(0.0);
        [[unroll]] for (int k = 0; k < TAPS; k++) {
            my += params.window[k] * t[j + k];
            myy += params.window[k] * t[j + k] * t[j + k];
        }
        mean_y[row + x0 + uint(j)] = pack_vec4(my);
        mean_yy[row + x0 + uint(j)] = pack_vec4(myy);
    }
    [[unroll]] for (uint r = 0u; r < RENDERS; r++) {
        vec4 v[SPAN];
        [[unroll]] for (int i = 0; i < SPAN; i++) {
            uint p = span_pixel(row, x0, i);
            v[i] = r == 0u ? unpack_vec4(render_a[p]) : unpack_vec4(render_b[p]);
        }
        [[unroll]] for (int j = 0; j < RUN; j++) {
            if (x0 + uint(j) < width()) l1_sum[r] += w[j] * abs(v[j + RADIUS] - t[j + RADIUS]);
        }
        [[unroll]] for (int j = 0; j < RUN; j++) {
            if (!column_valid(x0 + uint(j))) continue;
            vec4 mx = vec4(0.0), mxx = vec4(0.0), mxy = vec4(0.0);
            [[unroll]] for (int k = 0; k < TAPS; k++) {
                float w = params.window[k];
                mx += w * v[j + k];
                mxx += w * v[j + k] * v[j + k];
                mxy += w * v[j + k] * t[j + k];
            }
            uint q = plane(r) + row + x0 + uint(j);
            mean_x[q] = pack_vec4(mx);
            mean_xx[q] = pack_vec4(mxx);
            mean_xy[q] = pack_vec4(mxy);
        }
    }
}

void main() {
    uint y, x0;
    // Every invocation reaches the subgroup sums at the end.
    vec4 l1_sum[2] = vec4[2](vec4(0.0), vec4(0.0));
    if (row_run(gl_GlobalInvocationID.x, y, x0)) moments(y, x0, l1_sum);
    ADD_TERMS(0u, l1_sum, params.scales.z);
}
