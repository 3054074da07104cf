#version 460
// Outline flags, forward: one invocation per triangle, after transform. Bit k: edge k (corner
// k to k + 1) is on the outline (no triangle across it, or one facing the other way); bit 3:
// every corner is in front of the near plane. The anti-aliasing then skips the many pixel
// pairs whose triangles have no outline edge with two loads instead of a geometry test.
#include "raster.glsl"
#include "../common/grid.glsl"

layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer Faces { uint faces[]; };
layout(std430, binding = 1) readonly buffer CameraPositions { vec4 camera_positions[]; };
layout(std430, binding = 2) readonly buffer Adjacency { int adjacency[]; };
layout(std430, binding = 3) writeonly buffer OutlineFlags { uint outline_flags[]; };

#include "triangle.glsl"

bool faces_camera(uint t) {
    uvec3 v;
    vec3 v0, v1, v2;
    triangle_corners(t, v, v0, v1, v2);
    return dot(face_normal(v0, v1, v2), v0) < 0.0;
}

void main() {
    uint t = flat_workgroup_id() * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
    if (t >= triangle_count()) {
        return;
    }
    uvec3 v;
    vec3 v0, v1, v2;
    triangle_corners(t, v, v0, v1, v2);
    bool facing = faces_camera(t);
    uint flags = min(v0.z, min(v1.z, v2.z)) >= near_plane() ? FLAG_IN_FRONT : 0u;
    for (uint k = 0u; k < 3u; k++) {
        int across = adjacency[3u * t + k];
        if (across < 0 || faces_camera(uint(across)) != facing) {
            flags |= 1u << k;
        }
    }
    outline_flags[t] = flags;
}
