#version 460
// The mesh render as the loss reads it: rgb composited over the background with the coverage
// (the rasterizer draws on black), coverage in alpha, one vec4 per pixel.
#include "bridge.glsl"
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer Color { float color[]; };   // 3 per pixel
layout(std430, binding = 1) readonly buffer Mask { float mask[]; };
layout(std430, binding = 2) writeonly buffer Packed { vec4 packed[]; };

void main() {
    uint p = gl_GlobalInvocationID.x;
    if (p >= items()) return;
    float m = mask[p];
    vec3 rgb = vec3(color[3u * p], color[3u * p + 1u], color[3u * p + 2u]);
    packed[p] = vec4(rgb + (1.0 - m) * params.background.rgb, m);
}
