#version 460
// The backward of mesh_colors.comp: adds C0 · dL/dcolour to each Gaussian's SH DC gradient.
#include "bridge.glsl"
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer ColorGrads { float color_grads[]; };   // 3 per vertex
layout(std430, binding = 1) buffer ShGrads { float sh_grads[]; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= items()) return;
    for (uint c = 0u; c < 3u; c++) {
        sh_grads[i * sh_stride() + c] += SH_C0 * color_grads[3u * i + c];
    }
}
