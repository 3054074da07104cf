#version 460
// SSIM backward, pass 2 of 2, fused with the L1 gradient: the vertical filter completes the
// adjoint, and dL/dx = Ḡ[dμx] + 2x·Ḡ[dE[x²]] + y·Ḡ[dE[xy]] + L1 term, written per pixel in the
// layout the renderers' backward passes read (vec4: colour, alpha).
#include "loss.glsl"
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer Render { vec4 render[]; };
layout(std430, binding = 1) readonly buffer Target { vec4 target[]; };
layout(std430, binding = 2) readonly buffer Weight { float weight[]; };
layout(std430, binding = 3) readonly buffer BlurX { vec4 blur_x[]; };
layout(std430, binding = 4) readonly buffer BlurXX { vec4 blur_xx[]; };
layout(std430, binding = 5) readonly buffer BlurXY { vec4 blur_xy[]; };
layout(std430, binding = 6) writeonly buffer Gradient { vec4 gradient[]; };

void main() {
    uint p = gl_GlobalInvocationID.x;
    if (p >= pixel_count()) return;
    int y = int(p / width());
    vec4 a = vec4(0.0), xx = vec4(0.0), xy = vec4(0.0);
    for (int k = -RADIUS; k <= RADIUS; k++) {
        if (y + k >= 0 && y + k < int(height())) {
            float g = params.window[k + RADIUS];
            uint q = uint(int(p) + k * int(width()));
            a += g * blur_x[q];
            xx += g * blur_xx[q];
            xy += g * blur_xy[q];
        }
    }
    vec4 x = render[p];
    vec4 t = target[p];
    float w = has_weight() ? weight[p] : 1.0;
    vec4 l1 = params.channel_weights * params.scales.x * params.scales.z * w * sign(x - t);
    gradient[p] = a + 2.0 * x * xx + t * xy + l1;
}
