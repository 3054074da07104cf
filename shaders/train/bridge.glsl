// Shared by the kernels that connect the Gaussians to the mesh rasterizer (the Gaussians are
// the mesh's vertices; a vertex's colour is its Gaussian's SH DC colour). Mirrors
// engine/train/mesh_term.rs (BridgeParams).
#ifndef BRIDGE_GLSL
#define BRIDGE_GLSL

const float SH_C0 = 0.28209479177387814;

layout(push_constant, std430) uniform BridgeParams {
    vec4 background;   // rgb the targets are composited over, unused
    uvec4 sizes;       // items (vertices or pixels), SH floats per Gaussian, unused, unused
} params;

uint items() { return params.sizes.x; }
uint sh_stride() { return params.sizes.y; }

#endif
