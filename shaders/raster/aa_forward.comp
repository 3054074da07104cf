#version 460
// Anti-aliasing, forward: one invocation per pixel; gathers the blends of its four pairs
// (crossings from aa_pairs.comp, rule in blend.glsl) onto the resolved (rgb, mask) and writes the
// final colour and mask images.
#include "raster.glsl"

layout(local_size_x = 16, local_size_y = 16) in;

#include "blend.glsl"

layout(std430, binding = 0) readonly buffer Pairs { PairRecord pairs[]; };
layout(std430, binding = 1) readonly buffer Rgba { vec4 rgba[]; };
layout(std430, binding = 2) writeonly buffer Color { float color_out[]; };
layout(std430, binding = 3) writeonly buffer Mask { float mask_out[]; };

#include "pairs.glsl"

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (!in_image(p)) {
        return;
    }
    uint i = pixel_index(p);
    vec4 c_p = rgba[i];
    vec4 out_p = c_p;
    for (uint k = 0u; k < 4u; k++) {
        ivec2 q;
        Crossing c;
        float w;
        if (pair_around(p, k, q, c) && blend_target(c, w) == p) {
            out_p += w * (rgba[pixel_index(q)] - c_p);
        }
    }
    color_out[3u * i] = out_p.r;
    color_out[3u * i + 1u] = out_p.g;
    color_out[3u * i + 2u] = out_p.b;
    mask_out[i] = out_p.a;
}
