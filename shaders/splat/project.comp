#version 460
// Projection, forward: one invocation per Gaussian. Writes its Splat (culled ones get an empty
// tile rectangle) and how many tiles it touches, for the scan that places its intersections.
#include "gaussian.glsl"
#include "footprint.glsl"
#include "../common/grid.glsl"

layout(local_size_x_id = 0) in;

layout(std430, binding = 5) writeonly buffer Splats { Splat splats[]; };
layout(std430, binding = 6) writeonly buffer TileCounts { uint tile_counts[]; };

void main() {
    uint i = flat_workgroup_id() * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
    if (i >= gaussian_count()) {
        return;
    }
    Projection p;
    Splat s;
    uint touched = 0u;
    if (project(i, p, s)) {
        s.tile_rect = tile_rect(s, sqrt(2.0 * s.extent * vec2(p.cov2[0][0], p.cov2[1][1])));
        for (uint ty = s.tile_rect.z; ty < s.tile_rect.w; ty++) {
            for (uint tx = s.tile_rect.x; tx < s.tile_rect.y; tx++) {
                touched += touches_tile(s, uvec2(tx, ty)) ? 1u : 0u;
            }
        }
    } else {
        s = Splat(vec2(0.0), 0.0, 0.0, vec3(0.0), 0.0, vec4(0.0), uvec4(0u));
    }
    splats[i] = s;
    tile_counts[i] = touched;
}
