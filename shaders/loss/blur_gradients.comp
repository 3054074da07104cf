#version 460
// SSIM backward, pass 1 of 2: the horizontal Gaussian filter of dL/dμx, dL/dE[x²], dL/dE[xy].
// The window is symmetric, so the adjoint of the forward filter is the same filter; the
// derivatives are zero outside the SSIM region, so the image edge needs no special case.
#include "loss.glsl"
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer DMeanX { vec4 d_mean_x[]; };
layout(std430, binding = 1) readonly buffer DMeanXX { vec4 d_mean_xx[]; };
layout(std430, binding = 2) readonly buffer DMeanXY { vec4 d_mean_xy[]; };
layout(std430, binding = 3) writeonly buffer BlurX { vec4 blur_x[]; };
layout(std430, binding = 4) writeonly buffer BlurXX { vec4 blur_xx[]; };
layout(std430, binding = 5) writeonly buffer BlurXY { vec4 blur_xy[]; };

void main() {
    uint p = gl_GlobalInvocationID.x;
    if (p >= pixel_count()) return;
    int x = int(p % width());
    vec4 a = vec4(0.0), xx = vec4(0.0), xy = vec4(0.0);
    for (int k = -RADIUS; k <= RADIUS; k++) {
        // Phrased as "inside" so the clamp never reads a neighbouring row.
        if (x + k >= 0 && x + k < int(width())) {
            float g = params.window[k + RADIUS];
            uint q = uint(int(p) + k);
            a += g * d_mean_x[q];
            xx += g * d_mean_xx[q];
            xy += g * d_mean_xy[q];
        }
    }
    blur_x[p] = a;
    blur_xx[p] = xx;
    blur_xy[p] = xy;
}
