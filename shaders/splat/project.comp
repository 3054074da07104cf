#version 460
// Projection, forward: one invocation per Gaussian. Writes its Splat (culled ones get an empty
// tile rectangle) and how many tiles it touches, for the scan that places its intersections,
// and narrows the depth range of the splats that touch a tile (the intersection keys' scale).
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_basic : require
#include "gaussian.glsl"
#include "footprint.glsl"
#include "../common/grid.glsl"

layout(local_size_x_id = 0) in;

layout(std430, binding = 5) writeonly buffer Splats { Splat splats[]; };
layout(std430, binding = 6) writeonly buffer TileCounts { uint tile_counts[]; };
// The smallest depth bits and the complement of the largest; the host fills both with all ones.
layout(std430, binding = 7) buffer DepthRange { uint depth_range[2]; };

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
    // One atomic per subgroup: a million on one address would serialise on a GPU.
    uint bits = touched > 0u ? floatBitsToUint(s.depth) : 0xFFFFFFFFu;
    uint nearest = subgroupMin(bits);
    uint farthest = subgroupMin(touched > 0u ? ~bits : 0xFFFFFFFFu);
    if (subgroupElect() && nearest != 0xFFFFFFFFu) {
        atomicMin(depth_range[0], nearest);
        atomicMin(depth_range[1], farthest);
    }
}
