#version 460
// SSIM forward, pass 2 of 2, fused with the loss value and the first half of the backward:
// the vertical filter completes the moments; S and its partial derivatives with respect to
// the filtered moments μx, E[x²], E[xy] (scaled by dL/dS) go to the backward; the L1 and SSIM
// terms of the loss are summed per channel, one fixed-point add per subgroup (order-independent,
// so runs repeat bit for bit).
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "loss.glsl"
#include "../common/fixed_sum.glsl"
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer Render { vec4 render[]; };
layout(std430, binding = 1) readonly buffer Target { vec4 target[]; };
layout(std430, binding = 2) readonly buffer Weight { float weight[]; };
layout(std430, binding = 3) readonly buffer MeanX { vec4 mean_x[]; };
layout(std430, binding = 4) readonly buffer MeanY { vec4 mean_y[]; };
layout(std430, binding = 5) readonly buffer MeanXX { vec4 mean_xx[]; };
layout(std430, binding = 6) readonly buffer MeanYY { vec4 mean_yy[]; };
layout(std430, binding = 7) readonly buffer MeanXY { vec4 mean_xy[]; };
layout(std430, binding = 8) writeonly buffer DMeanX { vec4 d_mean_x[]; };
layout(std430, binding = 9) writeonly buffer DMeanXX { vec4 d_mean_xx[]; };
layout(std430, binding = 10) writeonly buffer DMeanXY { vec4 d_mean_xy[]; };
// Per channel: [0..4) the mean absolute error, [4..8) the mean of 1 − S (unweighted by λ).
layout(std430, binding = 11) buffer TermSums { int64_t term_sums[]; };  // fixed_sum.glsl: 8 sums

void main() {
    uint p = gl_GlobalInvocationID.x;
    bool inside = p < pixel_count();
    uint x = inside ? p % width() : 0u;
    uint y = inside ? p / width() : 0u;
    float w = (inside && has_weight()) ? weight[p] : 1.0;
    vec4 l1 = inside ? w * abs(render[p] - target[p]) : vec4(0.0);
    vec4 dissimilarity = vec4(0.0);
    vec4 da = vec4(0.0), dxx = vec4(0.0), dxy = vec4(0.0);
    if (inside && ssim_valid(x, y)) {
        vec4 a = vec4(0.0), b = vec4(0.0), xx = vec4(0.0), yy = vec4(0.0), xy = vec4(0.0);
        for (int k = -RADIUS; k <= RADIUS; k++) {
            float g = params.window[k + RADIUS];
            uint q = uint(int(p) + k * int(width()));
            a += g * mean_x[q];
            b += g * mean_y[q];
            xx += g * mean_xx[q];
            yy += g * mean_yy[q];
            xy += g * mean_xy[q];
        }
        vec4 n1 = 2.0 * a * b + C1;
        vec4 n2 = 2.0 * (xy - a * b) + C2;
        vec4 d1 = a * a + b * b + C1;
        vec4 d2 = (xx - a * a) + (yy - b * b) + C2;
        vec4 d = d1 * d2;
        vec4 s = n1 * n2 / d;
        dissimilarity = w * (1.0 - s);
        // dL/dS of this pixel (the SSIM term is λ · share · mean(w (1 − S))); the quotient
        // rule is written so no factor divides by n1 or n2, which may be zero.
        vec4 ds = -params.channel_weights * params.scales.y * params.scales.w * w;
        da = ds * ((2.0 * b * n2 - 2.0 * b * n1) / d - s * (2.0 * a / d1 - 2.0 * a / d2));
        dxx = ds * (-s / d2);
        dxy = ds * (2.0 * n1 / d);
    }
    if (inside) {
        d_mean_x[p] = da;
        d_mean_xx[p] = dxx;
        d_mean_xy[p] = dxy;
    }
    vec4 l1_sum = subgroupAdd(l1);
    vec4 ssim_sum = subgroupAdd(dissimilarity);
    if (subgroupElect()) {
        for (int c = 0; c < 4; c++) {
            FIXED_ADD_TOTAL(term_sums, uint(c), l1_sum[c] * params.scales.z);
            FIXED_ADD_TOTAL(term_sums, uint(4 + c), ssim_sum[c] * params.scales.w);
        }
    }
}
