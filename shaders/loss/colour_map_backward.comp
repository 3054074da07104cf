#version 460
// The backward of colour_map_forward.comp: dL/d(render) from dL/d(seen), WRITTEN. The map is
// linear in the render, so the render itself is not read.
// With seen = A p + b α + (1 − α) background and p = c − (1 − α) background:
// dL/dc = Aᵀ g and dL/dα = g_α + g · (A background + b − background).
#include "colour_map.glsl"
#include "../common/grid.glsl"

layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer Maps { vec4 maps[]; };
layout(std430, binding = 1) readonly buffer SeenGradient { u64vec2 seen_gradient[]; };
layout(std430, binding = 2) writeonly buffer Gradient { u64vec2 gradient[]; };

void main() {
    uint i = flat_workgroup_id() * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
    if (i >= pixel_count()) return;
    uint cam = camera();
    vec4 rows[3] = vec4[3](maps[3u * cam], maps[3u * cam + 1u], maps[3u * cam + 2u]);
    vec4 g = unpack_vec4(seen_gradient[i]);
    vec3 background = params.background.rgb;
    vec3 d_colour = vec3(0.0);
    float d_alpha = g.a;
    for (uint k = 0u; k < 3u; k++) {
        d_colour += g[k] * rows[k].xyz;
        d_alpha += g[k] * (dot(rows[k].xyz, background) + rows[k].w - background[k]);
    }
    gradient[i] = pack_vec4(vec4(d_colour, d_alpha));
}
