#version 460
// SSIM backward, pass 2 of 2, fused with the L1 gradient: the vertical filter completes the
// adjoint, and per render dL/dx = Ḡ[dμx] + 2x·Ḡ[dE[x²]] + y·Ḡ[dE[xy]] + L1 term, written per
// pixel in the layout the renderers' backward passes read (vec4: colour, alpha).
#extension GL_EXT_control_flow_attributes : require
#include "loss.glsl"
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer RenderA { u64vec2 render_a[]; };
layout(std430, binding = 1) readonly buffer RenderB { u64vec2 render_b[]; };  // RENDERS = 2 only
layout(std430, binding = 2) readonly buffer Target { u64vec2 target[]; };
layout(std430, binding = 3) readonly buffer Weight { float weight[]; };
// One plane per render (loss.glsl `plane`).
layout(std430, binding = 4) readonly buffer BlurX { u64vec2 blur_x[]; };
layout(std430, binding = 5) readonly buffer BlurXX { u64vec2 blur_xx[]; };
layout(std430, binding = 6) readonly buffer BlurXY { u64vec2 blur_xy[]; };
layout(std430, binding = 7) writeonly buffer GradientA { u64vec2 gradient_a[]; };
layout(std430, binding = 8) writeonly buffer GradientB { u64vec2 gradient_b[]; };  // RENDERS = 2 only

void main() {
    uint x, y0;
    if (!column_run(gl_GlobalInvocationID.x, x, y0)) return;
    // The target and weight of the run, loaded once for the renders.
    vec4 t[RUN];
    float w[RUN];
    [[unroll]] for (int j = 0; j < RUN; j++) {
        uint p = min(y0 + uint(j), height() - 1u) * width() + x;
        t[j] = unpack_vec4(target[p]);
        w[j] = 1.0;
        if (has_weight()) w[j] = weight[p];
    }
    [[unroll]] for (uint r = 0u; r < RENDERS; r++) {
        vec4 a[SPAN], xx[SPAN], xy[SPAN];
        [[unroll]] for (int i = 0; i < SPAN; i++) {
            int y = int(y0) - RADIUS + i;
            bool inside = y >= 0 && y < int(height());
            uint p = plane(r) + uint(clamp(y, 0, int(height()) - 1)) * width() + x;
            a[i] = inside ? unpack_vec4(blur_x[p]) : vec4(0.0);
            xx[i] = inside ? unpack_vec4(blur_xx[p]) : vec4(0.0);
            xy[i] = inside ? unpack_vec4(blur_xy[p]) : vec4(0.0);
        }
        vec4 lambda = params.channel_weights[r];
        [[unroll]] for (int j = 0; j < RUN; j++) {
            if (y0 + uint(j) >= height()) break;
            vec4 fa = vec4(0.0), fxx = vec4(0.0), fxy = vec4(0.0);
            [[unroll]] for (int k = 0; k < TAPS; k++) {
                float g = params.window[k];
                fa += g * a[j + k];
                fxx += g * xx[j + k];
                fxy += g * xy[j + k];
            }
            uint p = (y0 + uint(j)) * width() + x;
            vec4 render = r == 0u ? unpack_vec4(render_a[p]) : unpack_vec4(render_b[p]);
            vec4 l1 = lambda * params.scales.x * params.scales.z * w[j] * sign(render - t[j]);
            vec4 gradient = fa + 2.0 * render * fxx + t[j] * fxy + l1;
            if (r == 0u) gradient_a[p] = pack_vec4(gradient); else gradient_b[p] = pack_vec4(gradient);
        }
    }
}
