// Shared by the coverage term's kernels (engine/loss/silhouette/coverage.rs `Push`): one view's
// camera and the projection of a vertex into it.
#ifndef LOSS_COVERAGE_COMMON_GLSL
#define LOSS_COVERAGE_COMMON_GLSL

#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "../common/grid.glsl"

layout(push_constant) uniform Push {
    mat4 world_to_camera;
    vec4 intrinsics;  // fx, fy, cx, cy (pixel centres at +0.5)
    uint width;
    uint height;
    uint vertices;
    uint radius;      // search radius, pixels (Chebyshev)
    float scale;      // weight / pixels
    float near;
} pc;

const uint NO_SEED = 0xFFFFFFFFu;

// Camera-space position of world point x.
vec3 to_camera(vec3 x) {
    return (pc.world_to_camera * vec4(x, 1.0)).xyz;
}

// Pixel coordinates (centres at +0.5) of a camera-space point in front of the camera.
vec2 project(vec3 c) {
    return vec2(pc.intrinsics.x * c.x / c.z + pc.intrinsics.z, pc.intrinsics.y * c.y / c.z + pc.intrinsics.w);
}

#endif
