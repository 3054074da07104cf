// Real spherical harmonics of degree 0..3 (the constants of the 3DGS reference), forward and
// backward side by side. Coefficients are read through sh_coefficient(k), which the including
// kernel defines for its Gaussian.
#ifndef SPLAT_SH_GLSL
#define SPLAT_SH_GLSL

const float SH_C0 = 0.28209479177387814;
const float SH_C1 = 0.4886025119029199;
const float SH_C2[5] = float[](1.0925484305920792, -1.0925484305920792, 0.31539156525252005, -1.0925484305920792, 0.5462742152960396);
const float SH_C3[7] = float[](-0.5900435899266435, 2.890611442640554, -0.4570457994644658, 0.3731763325901154,
                               -0.4570457994644658, 1.445305721320277, -0.5900435899266435);

// The 16 basis values at unit direction d (unused bands are still computed: they are cheap).
void sh_basis(vec3 d, out float b[16]) {
    float x = d.x, y = d.y, z = d.z;
    float xx = x * x, yy = y * y, zz = z * z;
    b[0] = SH_C0;
    b[1] = -SH_C1 * y;
    b[2] = SH_C1 * z;
    b[3] = -SH_C1 * x;
    b[4] = SH_C2[0] * x * y;
    b[5] = SH_C2[1] * y * z;
    b[6] = SH_C2[2] * (2.0 * zz - xx - yy);
    b[7] = SH_C2[3] * x * z;
    b[8] = SH_C2[4] * (xx - yy);
    b[9] = SH_C3[0] * y * (3.0 * xx - yy);
    b[10] = SH_C3[1] * x * y * z;
    b[11] = SH_C3[2] * y * (4.0 * zz - xx - yy);
    b[12] = SH_C3[3] * z * (2.0 * zz - 3.0 * xx - 3.0 * yy);
    b[13] = SH_C3[4] * x * (4.0 * zz - xx - yy);
    b[14] = SH_C3[5] * z * (xx - yy);
    b[15] = SH_C3[6] * x * (xx - 3.0 * yy);
}

// Gradient of sum_k g_k * basis_k(d) with respect to d (not projected onto the sphere).
vec3 sh_basis_backward(vec3 d, float g[16], uint coefficients) {
    float x = d.x, y = d.y, z = d.z;
    float xx = x * x, yy = y * y, zz = z * z;
    vec3 grad = vec3(0.0);
    if (coefficients > 1u) {
        grad += SH_C1 * vec3(-g[3], -g[1], g[2]);
    }
    if (coefficients > 4u) {
        grad += SH_C2[0] * g[4] * vec3(y, x, 0.0);
        grad += SH_C2[1] * g[5] * vec3(0.0, z, y);
        grad += SH_C2[2] * g[6] * vec3(-2.0 * x, -2.0 * y, 4.0 * z);
        grad += SH_C2[3] * g[7] * vec3(z, 0.0, x);
        grad += SH_C2[4] * g[8] * vec3(2.0 * x, -2.0 * y, 0.0);
    }
    if (coefficients > 9u) {
        grad += SH_C3[0] * g[9] * vec3(6.0 * x * y, 3.0 * xx - 3.0 * yy, 0.0);
        grad += SH_C3[1] * g[10] * vec3(y * z, x * z, x * y);
        grad += SH_C3[2] * g[11] * vec3(-2.0 * x * y, 4.0 * zz - xx - 3.0 * yy, 8.0 * y * z);
        grad += SH_C3[3] * g[12] * vec3(-6.0 * x * z, -6.0 * y * z, 6.0 * zz - 3.0 * xx - 3.0 * yy);
        grad += SH_C3[4] * g[13] * vec3(4.0 * zz - 3.0 * xx - yy, -2.0 * x * y, 8.0 * x * z);
        grad += SH_C3[5] * g[14] * vec3(2.0 * x * z, -2.0 * y * z, xx - yy);
        grad += SH_C3[6] * g[15] * vec3(3.0 * xx - 3.0 * yy, -6.0 * x * y, 0.0);
    }
    return grad;
}

#endif
