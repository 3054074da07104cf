#version 460
// Vertex colours of the mesh render from the Gaussians' SH DC term: 0.5 + C0 · DC, unclamped
// so the gradient passes everywhere (the loss pulls colours into [0, 1]).
#include "bridge.glsl"
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer Sh { float sh[]; };
layout(std430, binding = 1) writeonly buffer Colors { float colors[]; };   // 3 per vertex

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= items()) return;
    for (uint c = 0u; c < 3u; c++) {
        colors[3u * i + c] = 0.5 + SH_C0 * sh[i * sh_stride() + c];
    }
}
