// Mirrors engine/optim/adam.rs (AdamParams).
#ifndef ADAM_GLSL
#define ADAM_GLSL

layout(push_constant, std430) uniform AdamParams {
    vec4 lr_a;       // positions, log-scales, rotations, opacity logits
    vec4 lr_b;       // SH DC, SH rest, ε, unused
    vec4 betas;      // β1, β2, 1 − β1, 1 − β2 (each rounded from f64, so no f32 cancellation)
    vec4 bias;       // 1 − β1^t, 1 − β2^t (from f64), unused, unused
    uvec4 counts;    // Gaussians, SH coefficients per Gaussian, unused, unused
} params;

#endif
