#version 460
// Transform, forward: one invocation per vertex, world to camera space (OpenCV axes).
#include "raster.glsl"
#include "../common/grid.glsl"

layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer Positions { float positions[]; };
layout(std430, binding = 1) writeonly buffer CameraPositions { vec4 camera_positions[]; };

void main() {
    uint v = flat_workgroup_id() * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
    if (v >= vertex_count()) {
        return;
    }
    vec3 world = vec3(positions[3u * v], positions[3u * v + 1u], positions[3u * v + 2u]);
    camera_positions[v] = vec4(view_rotation() * world + view_translation(), 0.0);
}
