#version 460
// Adam over every parameter group in one dispatch: one invocation per parameter float, the
// flat index running through positions, log-scales, rotations, opacity logits and SH in turn.
// Each buffer has its moments (m, v) interleaved beside it, so the update reads and writes
// one place per float.
#include "adam.glsl"
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) buffer Positions { float positions[]; };
layout(std430, binding = 1) buffer LogScales { float log_scales[]; };
layout(std430, binding = 2) buffer Rotations { float rotations[]; };
layout(std430, binding = 3) buffer Opacity { float opacity_logits[]; };
layout(std430, binding = 4) buffer Sh { float sh[]; };
layout(std430, binding = 5) readonly buffer GPositions { float g_positions[]; };
layout(std430, binding = 6) readonly buffer GLogScales { float g_log_scales[]; };
layout(std430, binding = 7) readonly buffer GRotations { float g_rotations[]; };
layout(std430, binding = 8) readonly buffer GOpacity { float g_opacity_logits[]; };
layout(std430, binding = 9) readonly buffer GSh { float g_sh[]; };
layout(std430, binding = 10) buffer MPositions { vec2 m_positions[]; };
layout(std430, binding = 11) buffer MLogScales { vec2 m_log_scales[]; };
layout(std430, binding = 12) buffer MRotations { vec2 m_rotations[]; };
layout(std430, binding = 13) buffer MOpacity { vec2 m_opacity_logits[]; };
layout(std430, binding = 14) buffer MSh { vec2 m_sh[]; };

// The new moments from the old and the gradient; returns the step to subtract.
float adam(inout vec2 moments, float g, float lr) {
    vec4 b = params.betas;
    moments = vec2(b.x * moments.x + b.z * g, b.y * moments.y + b.w * g * g);
    float m_hat = moments.x / params.bias.x;
    float v_hat = moments.y / params.bias.y;
    return lr * m_hat / (sqrt(v_hat) + params.lr_b.z);
}

#define UPDATE(param, grad, moment, j, lr) { vec2 m = moment[j]; param[j] -= adam(m, grad[j], lr); moment[j] = m; }

void main() {
    uint n = params.counts.x;
    uint i = gl_GlobalInvocationID.x;
    if (i < 3u * n) { UPDATE(positions, g_positions, m_positions, i, params.lr_a.x); return; }
    i -= 3u * n;
    if (i < 3u * n) { UPDATE(log_scales, g_log_scales, m_log_scales, i, params.lr_a.y); return; }
    i -= 3u * n;
    if (i < 4u * n) { UPDATE(rotations, g_rotations, m_rotations, i, params.lr_a.z); return; }
    i -= 4u * n;
    if (i < n) { UPDATE(opacity_logits, g_opacity_logits, m_opacity_logits, i, params.lr_a.w); return; }
    i -= n;
    uint coefficients = params.counts.y;
    if (i < 3u * coefficients * n) {
        // SH is Gaussian-major, DC first: sh[(gaussian · coefficients + k) · 3 + channel].
        bool dc = (i / 3u) % coefficients == 0u;
        UPDATE(sh, g_sh, m_sh, i, dc ? params.lr_b.x : params.lr_b.y);
    }
}
