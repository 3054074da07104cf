#version 460
// Anti-aliasing crossings, forward: one invocation per pixel; finds the crossing (aa.glsl) of
// the pair with its right and with its lower neighbour and stores both, so the blend and its
// backward read each pair once instead of recomputing it from both pixels.
#include "raster.glsl"

layout(local_size_x = 16, local_size_y = 16) in;

layout(std430, binding = 0) readonly buffer Faces { uint faces[]; };
layout(std430, binding = 1) readonly buffer CameraPositions { vec4 camera_positions[]; };
layout(std430, binding = 2) readonly buffer OutlineFlags { uint outline_flags[]; };
layout(std430, binding = 3) readonly buffer Ids { uint ids[]; };
layout(std430, binding = 4) readonly buffer Depth { float depth[]; };

#include "triangle.glsl"
#include "aa.glsl"

layout(std430, binding = 5) writeonly buffer Pairs { PairRecord pairs[]; };

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (!in_image(p)) {
        return;
    }
    uint i = pixel_index(p);
    for (uint k = 0u; k < 2u; k++) {
        ivec2 q = p + (k == 0u ? ivec2(1, 0) : ivec2(0, 1));
        PairRecord r = PairRecord(0.0, 0u, 0u, 0u);
        if (in_image(q)) {
            r = pack_crossing(pair_crossing(p, q), p);
        }
        pairs[2u * i + k] = r;
    }
}
