// Shared by the fused image-loss kernels. Mirrors engine/loss/params.rs (LossParams).
// Images are vec4 per pixel (rgb + alpha/mask), row-major, declared as u64vec2 and moved as two
// 64-bit words (common/wide_vec4.glsl says why); every channel is one loss channel
// with its own weight, so one run scores colour and mask together. One run scores RENDERS
// renders (1 or 2: the Gaussian and the mesh render of a view) against one target, whose
// moments they share.
//
// Each invocation filters a RUN of consecutive pixels (along a row in the horizontal passes,
// down a column in the vertical ones): RUN + 2·RADIUS loads feed RUN outputs, where one output
// per invocation would load 2·RADIUS + 1 for each. Loads, not arithmetic, bound these passes on
// lavapipe, whose shared memory costs a load like any buffer's; on a GPU the column runs of the
// vertical passes stay coalesced.
#ifndef LOSS_GLSL
#define LOSS_GLSL

#include "../common/wide_vec4.glsl"

const int RADIUS = 5;            // the 11×11 SSIM window
const int TAPS = 2 * RADIUS + 1;
const int RUN = 8;               // outputs per invocation
const int SPAN = RUN + 2 * RADIUS;
const float C1 = 0.01 * 0.01;
const float C2 = 0.03 * 0.03;

layout(constant_id = 1) const uint RENDERS = 1;

layout(push_constant, std430) uniform LossParams {
    vec4 channel_weights[2];     // λ per channel of each render
    uvec4 size;                  // width, height, has per-pixel weight, unused
    vec4 scales;                 // L1 share (0.8), SSIM share (0.2), 1 / pixels, 1 / SSIM pixels (0 if none)
    float window[TAPS];          // normalised 1D Gaussian, σ = 1.5
} params;

uint width() { return params.size.x; }
uint height() { return params.size.y; }
uint pixel_count() { return params.size.x * params.size.y; }
bool has_weight() { return params.size.z != 0u; }

// SSIM is defined where the whole window lies inside the image (scikit-image crops the border).
bool ssim_valid(uint x, uint y) {
    return x >= uint(RADIUS) && y >= uint(RADIUS) && x + uint(RADIUS) < width() && y + uint(RADIUS) < height();
}

// The run an invocation of a horizontal pass filters: its row and first column; false when
// the invocation lies past the image.
bool row_run(uint invocation, out uint y, out uint x0) {
    uint runs = max((width() + uint(RUN) - 1u) / uint(RUN), 1u);
    y = invocation / runs;
    x0 = (invocation % runs) * uint(RUN);
    return x0 < width() && y < height();
}

// The run an invocation of a vertical pass filters: its column and first row.
bool column_run(uint invocation, out uint x, out uint y0) {
    x = invocation % max(width(), 1u);
    y0 = (invocation / max(width(), 1u)) * uint(RUN);
    return x < width() && y0 < height();
}

// Plane `r` of a scratch buffer holding one image per render.
uint plane(uint r) { return r * pixel_count(); }

// Adds each render's per-channel `totals[r] * scale` to sums [first, first + 4) of its term
// buffer, one fixed-point add per subgroup (order-independent, so runs repeat bit for bit). A
// channel whose λ is 0 adds nothing: a view whose colour is left out (a dark or saturated
// image) then adds no colour to its pass's loss, which the plateau test reads.
// A macro, as GLSL cannot pass a buffer: the kernel declares term_sums_a and term_sums_b and
// includes fixed_sum.glsl and subgroup arithmetic.
#define ADD_TERMS(first, totals, scale) {                                        \
    [[unroll]] for (uint r_ = 0u; r_ < RENDERS; r_++) {                           \
        vec4 counted_ = vec4(notEqual(params.channel_weights[r_], vec4(0.0)));   \
        vec4 total_ = subgroupAdd(totals[r_]) * (scale) * counted_;              \
        if (subgroupElect()) {                                                   \
            [[unroll]] for (int c_ = 0; c_ < 4; c_++) {                           \
                if (r_ == 0u) FIXED_ADD_TOTAL(term_sums_a, (first) + uint(c_), total_[c_]) \
                else FIXED_ADD_TOTAL(term_sums_b, (first) + uint(c_), total_[c_])          \
            }                                                                    \
        }                                                                        \
    }                                                                            \
}

#endif
