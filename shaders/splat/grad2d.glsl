// Per-Gaussian gradients of the 2D quantities, written by rasterize_backward.comp and read by
// project_backward.comp. Mirrors engine/splat/frame.rs (GRAD2D_STRIDE).
#ifndef SPLAT_GRAD2D_GLSL
#define SPLAT_GRAD2D_GLSL

const uint GRAD2D_MEAN = 0u;     // 2
const uint GRAD2D_CONIC = 2u;    // 3: Q00, Q01, Q11
const uint GRAD2D_OPACITY = 5u;  // 1
const uint GRAD2D_COLOR = 6u;    // 3
const uint GRAD2D_DEPTH = 9u;    // 1
const uint GRAD2D_STRIDE = 10u;

#endif
