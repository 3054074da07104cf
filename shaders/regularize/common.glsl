// Shared by vertex.comp and gather.comp: push constants (engine/regularize/kernels.rs
// `Push`), the loss slots, quaternion maths and the loss reduction.
#ifndef REGULARIZE_COMMON_GLSL
#define REGULARIZE_COMMON_GLSL

#extension GL_EXT_shader_atomic_float : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require

layout(push_constant) uniform Push {
    uint count;          // Gaussians
    uint temporal;       // 1: previous-frame buffers are bound, evaluate the temporal terms
    float inv_count;     // 1 / count (Laplacian normalisation)
    float omega_scale;   // lambda_w / mean edge length
    float w_scale_2d;
    float w_laplacian;
    float w_normal;
    float w_edge_length;
    float w_rigidity;
    float w_rotation;
} pc;

const uint LOSS_SCALE_2D = 0u;
const uint LOSS_LAPLACIAN = 1u;
const uint LOSS_NORMAL = 2u;
const uint LOSS_EDGE_LENGTH = 3u;
const uint LOSS_RIGIDITY = 4u;
const uint LOSS_ROTATION = 5u;

const uint BOUNDARY_BIT = 0x80000000u;

// Rotation of a unit quaternion (w, x, y, z); columns of R.
mat3 rotation_matrix(vec4 q) {
    float w = q.x, x = q.y, y = q.z, z = q.w;
    return mat3(vec3(1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y + w * z), 2.0 * (x * z - w * y)),
                vec3(2.0 * (x * y - w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z + w * x)),
                vec3(2.0 * (x * z + w * y), 2.0 * (y * z - w * x), 1.0 - 2.0 * (x * x + y * y)));
}

// dL/d(unit q) from dL/dR, where g[c][r] = dL/dR[r][c] (GLSL column-major).
vec4 rotation_matrix_backward(vec4 q, mat3 g) {
    float w = q.x, x = q.y, y = q.z, z = q.w;
    float e00 = g[0][0], e01 = g[1][0], e02 = g[2][0];
    float e10 = g[0][1], e11 = g[1][1], e12 = g[2][1];
    float e20 = g[0][2], e21 = g[1][2], e22 = g[2][2];
    return 2.0 * vec4(-z * e01 + y * e02 + z * e10 - x * e12 - y * e20 + x * e21,
                      y * e01 + z * e02 + y * e10 - 2.0 * x * e11 - w * e12 + z * e20 + w * e21 - 2.0 * x * e22,
                      -2.0 * y * e00 + x * e01 + w * e02 + x * e10 + z * e12 - w * e20 + z * e21 - 2.0 * y * e22,
                      -2.0 * z * e00 - w * e01 + x * e02 + w * e10 - 2.0 * z * e11 + y * e12 + x * e20 + y * e21);
}

// Hamilton product of (w, x, y, z) quaternions.
vec4 quat_mul(vec4 a, vec4 b) {
    return vec4(a.x * b.x - dot(a.yzw, b.yzw), a.x * b.yzw + b.x * a.yzw + cross(a.yzw, b.yzw));
}

vec4 quat_conj(vec4 q) {
    return vec4(q.x, -q.yzw);
}

// q / |q|; identity for a zero or non-finite quaternion (such a Gaussian gets no rotation
// gradient: see normalize_backward).
vec4 unit_quat(vec4 q) {
    float n = length(q);
    return (n > 0.0 && !isinf(n)) ? q / n : vec4(1.0, 0.0, 0.0, 0.0);
}

// dL/dq from dL/d(q / |q|).
vec4 normalize_backward(vec4 q, vec4 g) {
    float n = length(q);
    if (!(n > 0.0) || isinf(n)) {
        return vec4(0.0);
    }
    vec4 u = q / n;
    return (g - u * dot(u, g)) / n;
}

// Adds `value` (0 from inactive invocations) to losses[slot]: one atomic per subgroup.
// Must be reached by every invocation of the subgroup.
#define ADD_LOSS(slot, value)                         \
    {                                                 \
        float total_ = subgroupAdd(value);            \
        if (subgroupElect() && total_ != 0.0) {       \
            atomicAdd(losses[slot], total_);          \
        }                                             \
    }

#endif
