#version 460
// Coverage term, pass 1: one invocation per vertex projects it into the view, stores its pixel
// coordinates (NaN when behind the near plane or off the image) and claims its pixel in the
// seed image with atomicMin, so each pixel keeps its lowest vertex id: a fixed choice.
#include "coverage_common.glsl"
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer Positions { float positions[]; };
layout(std430, binding = 1) writeonly buffer Projected { vec2 projected[]; };
layout(std430, binding = 2) buffer Seeds { uint seeds[]; };

void main() {
    uint i = flat_workgroup_id() * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
    if (i >= pc.vertices) {
        return;
    }
    vec3 c = to_camera(vec3(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u]));
    vec2 uv = project(c);
    // Phrased as positive so NaN positions are left out too.
    bool on_image = c.z > pc.near && uv.x >= 0.0 && uv.y >= 0.0 && uv.x < float(pc.width) && uv.y < float(pc.height);
    projected[i] = on_image ? uv : vec2(uintBitsToFloat(0x7FC00000u));
    if (on_image) {
        atomicMin(seeds[uint(uv.y) * pc.width + uint(uv.x)], i);
    }
}
