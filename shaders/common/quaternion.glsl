// Quaternion maths shared by the splatting and regularizer kernels. Quaternions are stored
// (w, x, y, z) in a vec4; GLSL matrices are column-major, so g[j][i] is row i, column j.
#ifndef COMMON_QUATERNION_GLSL
#define COMMON_QUATERNION_GLSL

// Rotation of a unit quaternion.
mat3 rotation_of(vec4 q) {
    float w = q.x, x = q.y, y = q.z, z = q.w;
    // Columns of R.
    return mat3(vec3(1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y + w * z), 2.0 * (x * z - w * y)),
                vec3(2.0 * (x * y - w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z + w * x)),
                vec3(2.0 * (x * z + w * y), 2.0 * (y * z - w * x), 1.0 - 2.0 * (x * x + y * y)));
}

// Gradient of the unit quaternion from the gradient of its rotation.
vec4 rotation_backward(vec4 q, mat3 g) {
    float w = q.x, x = q.y, y = q.z, z = q.w;
    float g00 = g[0][0], g01 = g[1][0], g02 = g[2][0];
    float g10 = g[0][1], g11 = g[1][1], g12 = g[2][1];
    float g20 = g[0][2], g21 = g[1][2], g22 = g[2][2];
    return vec4(2.0 * (z * (g10 - g01) + y * (g02 - g20) + x * (g21 - g12)),
                2.0 * (y * (g01 + g10) + z * (g02 + g20) + w * (g21 - g12)) - 4.0 * x * (g11 + g22),
                2.0 * (x * (g01 + g10) + w * (g02 - g20) + z * (g12 + g21)) - 4.0 * y * (g00 + g22),
                2.0 * (w * (g10 - g01) + x * (g02 + g20) + y * (g12 + g21)) - 4.0 * z * (g00 + g11));
}

// Hamilton product.
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

#endif
