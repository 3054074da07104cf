#version 460
// Regularizers, pass 1: one invocation per Gaussian i. L_2d (value and s_z gradient), the
// Laplacian offset δ_i (stored for pass 2) and its loss, the normal consistency loss with its
// rotation gradient and g_i = dL_n/dN_i, the gradient with respect to the unnormalised mesh
// normal N_i (stored for pass 2, which turns it into position gradients).
#include "common.glsl"
#include "../common/grid.glsl"

layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer Positions { float positions[]; };
layout(std430, binding = 1) readonly buffer LogScales { float log_scales[]; };
layout(std430, binding = 2) readonly buffer Rotations { vec4 rotations[]; };
layout(std430, binding = 3) readonly buffer Ranges { uvec2 ranges[]; };
layout(std430, binding = 4) readonly buffer Ring { uint ring[]; };
layout(std430, binding = 5) buffer GradLogScales { float grad_log_scales[]; };
layout(std430, binding = 6) buffer GradRotations { vec4 grad_rotations[]; };
layout(std430, binding = 7) writeonly buffer Deltas { vec4 deltas[]; };
layout(std430, binding = 8) writeonly buffer NormalGrads { vec4 normal_grads[]; };
layout(std430, binding = 9) buffer LossSums { int64_t loss_sums[]; };

vec3 position(uint i) {
    return vec3(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u]);
}

void main() {
    uint i = flat_workgroup_id() * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
    float scale_2d = 0.0, laplacian = 0.0, normal = 0.0;
    if (i < pc.count) {
        scale_2d = exp(log_scales[3u * i + 2u]);
        grad_log_scales[3u * i + 2u] += pc.w_scale_2d * scale_2d;

        uint start = ranges[i].x, count = ranges[i].y & ~BOUNDARY_BIT;
        uint faces = count == 0u ? 0u : ((ranges[i].y & BOUNDARY_BIT) != 0u ? count - 1u : count);
        vec3 p = position(i);
        vec3 sum = vec3(0.0), area = vec3(0.0);
        for (uint k = 0u; k < count; k++) {
            sum += position(ring[start + k]);
        }
        for (uint k = 0u; k < faces; k++) {
            area += cross(position(ring[start + k]) - p, position(ring[start + (k + 1u) % count]) - p);
        }
        vec3 delta = count > 0u ? p - sum / float(count) : vec3(0.0);
        deltas[i] = vec4(delta, 0.0);
        laplacian = dot(delta, delta) * pc.inv_count;

        vec4 g = vec4(0.0);
        float len = length(area);
        if (len > 0.0) {
            vec3 n_mesh = area / len;
            vec4 q = unit_quat(rotations[i]);
            vec3 r = rotation_of(q)[2] - n_mesh;
            normal = length(r);
            if (normal > 0.0) {
                vec3 u = pc.w_normal * r / normal;
                vec4 g_unit = rotation_backward(q, mat3(vec3(0.0), vec3(0.0), u));
                grad_rotations[i] += normalize_backward(rotations[i], g_unit);
                g.xyz = -(u - n_mesh * dot(n_mesh, u)) / len;
            }
        }
        normal_grads[i] = g;
    }
    ADD_LOSS(LOSS_SCALE_2D, scale_2d);
    ADD_LOSS(LOSS_LAPLACIAN, laplacian);
    ADD_LOSS(LOSS_NORMAL, normal);
}
