#version 460
// SSIM backward, pass 1 of 2: the horizontal Gaussian filter of each render's dL/dμx,
// dL/dE[x²] and dL/dE[xy]. The window is symmetric, so the adjoint of the forward filter is
// the same filter; the derivatives are zero outside the SSIM region, and taps past the row
// read zero.
#extension GL_EXT_control_flow_attributes : require
#include "loss.glsl"
layout(local_size_x_id = 0) in;

// One plane per render (loss.glsl `plane`).
layout(std430, binding = 0) readonly buffer DMeanX { u64vec2 d_mean_x[]; };
layout(std430, binding = 1) readonly buffer DMeanXX { u64vec2 d_mean_xx[]; };
layout(std430, binding = 2) readonly buffer DMeanXY { u64vec2 d_mean_xy[]; };
layout(std430, binding = 3) writeonly buffer BlurX { u64vec2 blur_x[]; };
layout(std430, binding = 4) writeonly buffer BlurXX { u64vec2 blur_xx[]; };
layout(std430, binding = 5) writeonly buffer BlurXY { u64vec2 blur_xy[]; };

void main() {
    uint y, x0;
    if (!row_run(gl_GlobalInvocationID.x, y, x0)) return;
    [[unroll]] for (uint r = 0u; r < RENDERS; r++) {
        uint row = plane(r) + y * width();
        vec4 a[SPAN], xx[SPAN], xy[SPAN];
        [[unroll]] for (int i = 0; i < SPAN; i++) {
            int x = int(x0) - RADIUS + i;
            // Phrased as "inside" so that no tap reads a neighbouring row.
            bool inside = x >= 0 && x < int(width());
            uint p = row + uint(clamp(x, 0, int(width()) - 1));
            a[i] = inside ? unpack_vec4(d_mean_x[p]) : vec4(0.0);
            xx[i] = inside ? unpack_vec4(d_mean_xx[p]) : vec4(0.0);
            xy[i] = inside ? unpack_vec4(d_mean_xy[p]) : vec4(0.0);
        }
        [[unroll]] for (int j = 0; j < RUN; j++) {
            if (x0 + uint(j) >= width()) break;
            vec4 fa = vec4(0.0), fxx = vec4(0.0), fxy = vec4(0.0);
            [[unroll]] for (int k = 0; k < TAPS; k++) {
                float w = params.window[k];
                fa += w * a[j + k];
                fxx += w * xx[j + k];
                fxy += w * xy[j + k];
            }
            uint q = row + x0 + uint(j);
            blur_x[q] = pack_vec4(fa);
            blur_xx[q] = pack_vec4(fxx);
            blur_xy[q] = pack_vec4(fxy);
        }
    }
}
