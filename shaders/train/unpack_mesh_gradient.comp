#version 460
// The backward of pack_mesh_render.comp: dL/drgb and dL/dmask of the rasterizer's images
// (the composite adds (1 − m)·background, so dL/dm gains −background · dL/drgb).
#include "bridge.glsl"
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer PackedGrad { vec4 packed_grad[]; };
layout(std430, binding = 1) writeonly buffer ColorGrad { float color_grad[]; };   // 3 per pixel
layout(std430, binding = 2) writeonly buffer MaskGrad { float mask_grad[]; };

void main() {
    uint p = gl_GlobalInvocationID.x;
    if (p >= items()) return;
    vec4 g = packed_grad[p];
    color_grad[3u * p] = g.r;
    color_grad[3u * p + 1u] = g.g;
    color_grad[3u * p + 2u] = g.b;
    mask_grad[p] = g.a - dot(g.rgb, params.background.rgb);
}
