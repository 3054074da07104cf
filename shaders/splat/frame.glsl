// Shared by every splatting kernel. Mirrors engine/splat/frame.rs (FrameParams, Splat).
#ifndef SPLAT_FRAME_GLSL
#define SPLAT_FRAME_GLSL

const uint TILE_SIZE = 16u;
const float ALPHA_MIN = 1.0 / 255.0;
const float ALPHA_MAX = 0.99;
const float TRANSMITTANCE_MIN = 1e-4;
const float DILATION = 0.3;
const float DEPTH_ALPHA_MIN = 1e-6;

// One camera and the render settings, 128 bytes (the push-constant minimum of Vulkan).
layout(push_constant, std430) uniform FrameParams {
    vec4 view_rows[3];        // world_to_camera rows: rotation | translation
    vec4 intrinsics;          // fx, fy, cx, cy
    vec4 center_near;         // camera centre (world), near
    vec4 background_far;      // background rgb, far
    uvec4 size;               // width, height, tiles_x, tiles_y
    uvec4 options;            // gaussian count, active SH degree, stored SH coefficients, mask mode
} frame;

uint gaussian_count() { return frame.options.x; }
uint sh_degree() { return frame.options.y; }
uint sh_stride() { return frame.options.z; }
bool mask_mode() { return frame.options.w != 0u; }

mat3 view_rotation() {
    // GLSL matrices are column-major: build from rows, then transpose.
    return transpose(mat3(frame.view_rows[0].xyz, frame.view_rows[1].xyz, frame.view_rows[2].xyz));
}

vec3 view_translation() {
    return vec3(frame.view_rows[0].w, frame.view_rows[1].w, frame.view_rows[2].w);
}

// A projected Gaussian (64 bytes). Culled ones have an empty tile_rect and touch no tile.
struct Splat {
    vec2 mean;        // pixels
    float depth;      // view-space z
    float opacity;    // after the sigmoid (1 in mask mode)
    vec3 conic;       // inverse 2D covariance: Q00, Q01, Q11
    float extent;     // ln(255 opacity): the footprint is sigma <= extent
    vec4 color;       // rgb, unused
    uvec4 tile_rect;  // tiles [x0, x1) x [y0, y1)
};

#endif
