// Shared by the fused image-loss kernels. Mirrors engine/loss/params.rs (LossParams).
// Images are vec4 per pixel (rgb + alpha/mask), row-major; every channel is one loss channel
// with its own weight, so one run scores colour and mask together.
#ifndef LOSS_GLSL
#define LOSS_GLSL

const int RADIUS = 5;            // the 11×11 SSIM window
const float C1 = 0.01 * 0.01;
const float C2 = 0.03 * 0.03;

layout(push_constant, std430) uniform LossParams {
    vec4 channel_weights;        // λ per channel
    uvec4 size;                  // width, height, has per-pixel weight, unused
    vec4 scales;                 // L1 share (0.8), SSIM share (0.2), 1 / pixels, 1 / SSIM pixels (0 if none)
    float window[2 * RADIUS + 1];// normalised 1D Gaussian, σ = 1.5
} params;

uint width() { return params.size.x; }
uint height() { return params.size.y; }
uint pixel_count() { return params.size.x * params.size.y; }
bool has_weight() { return params.size.z != 0u; }

// SSIM is defined where the whole window lies inside the image (scikit-image crops the border).
bool ssim_valid(uint x, uint y) {
    return x >= uint(RADIUS) && y >= uint(RADIUS) && x + uint(RADIUS) < width() && y + uint(RADIUS) < height();
}

#endif
