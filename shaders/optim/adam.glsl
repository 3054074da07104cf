// Mirrors engine/optim/adam.rs (AdamParams).
#ifndef ADAM_GLSL
#define ADAM_GLSL

// One step's parameters, written by the host into a ring slot before the step is submitted:
// a step recorded once and replayed reads its iteration's rates and bias corrections here.
struct AdamParams {
    vec4 lr_a;       // positions, log-scales, rotations, opacity logits
    vec4 lr_b;       // SH DC, SH rest, ε, unused
    vec4 betas;      // β1, β2, 1 − β1, 1 − β2 (each rounded from f64, so no f32 cancellation)
    vec4 bias;       // 1 − β1^t, 1 − β2^t (from f64), unused, unused
    uvec4 counts;    // Gaussians, SH coefficients per Gaussian, unused, unused
};

// Mirrors engine/optim/adam.rs (AdamSlot): which ring slot this recording reads.
layout(push_constant, std430) uniform AdamSlot {
    uint slot;
} adam_slot;

#endif
