#version 460
// Projection, backward: one invocation per Gaussian carries the gradients of its 2D mean,
// conic, opacity, colour and depth (from rasterize_backward.comp) back through the projection
// to its stored parameters, and adds them to the gradient buffers (so several views can
// accumulate before an optimizer step). It also accumulates the densification statistics:
// the norm of the 2D mean gradient (pixels) and how many renders had it on screen (a
// non-empty tile rectangle).
#include "gaussian.glsl"
#include "grad2d.glsl"
#include "footprint.glsl"
#include "../common/grid.glsl"

layout(local_size_x_id = 0) in;

layout(std430, binding = 5) readonly buffer Grad2d { float grad2d[]; };
layout(std430, binding = 6) buffer GradPositions { float grad_positions[]; };
layout(std430, binding = 7) buffer GradLogScales { float grad_log_scales[]; };
layout(std430, binding = 8) buffer GradRotations { vec4 grad_rotations[]; };
layout(std430, binding = 9) buffer GradOpacityLogits { float grad_opacity_logits[]; };
layout(std430, binding = 10) buffer GradSh { float grad_sh[]; };
layout(std430, binding = 11) buffer DensifyStats { vec2 densify_stats[]; }; // sum of |dL/dmean|, renders in view

float g2(uint i, uint k) {
    return grad2d[i * GRAD2D_STRIDE + k];
}

// dL/dview from the mean, the depth and the Jacobian (whose guard-band clamp passes nothing
// to the clamped coordinate).
vec3 view_gradient(Projection p, vec2 g_mean, float g_depth, mat3x2 g_j) {
    vec2 f = frame.intrinsics.xy;
    float z = p.view.z;
    vec3 g = vec3(f * g_mean / z, g_depth - dot(f * p.view.xy, g_mean) / (z * z));
    g.z -= (f.x * g_j[0][0] + f.y * g_j[1][1]) / (z * z);
    for (uint a = 0u; a < 2u; a++) {
        float g_edge = g_j[2][a]; // J[a][2] = -f_a * ray_a / z
        if (p.clamped[a]) {
            g.z += g_edge * f[a] * p.ray[a] / (z * z);
        } else {
            g[a] -= g_edge * f[a] / (z * z);
            g.z += g_edge * 2.0 * f[a] * p.view[a] / (z * z * z);
        }
    }
    return g;
}

// dL/dposition through the view direction of the SH colour, and the SH coefficient gradients.
vec3 color_backward(uint i, Projection p, vec3 g_color) {
    uint coefficients = (sh_degree() + 1u) * (sh_degree() + 1u);
    // The clamp at 0 passes no gradient; mask mode has a constant colour.
    vec3 g_sh_sum = mask_mode() ? vec3(0.0) : g_color * vec3(greaterThan(vec3(p.sh_sum[0], p.sh_sum[1], p.sh_sum[2]), vec3(0.0)));
    float basis[16];
    sh_basis(p.view_dir, basis);
    float g_basis[16];
    for (uint k = 0u; k < 16u; k++) {
        g_basis[k] = 0.0;
    }
    for (uint k = 0u; k < coefficients; k++) {
        uint at = (i * sh_stride() + k) * 3u;
        grad_sh[at] += g_sh_sum.r * basis[k];
        grad_sh[at + 1u] += g_sh_sum.g * basis[k];
        grad_sh[at + 2u] += g_sh_sum.b * basis[k];
        g_basis[k] = dot(g_sh_sum, sh_coefficient(i, k));
    }
    vec3 g_dir = sh_basis_backward(p.view_dir, g_basis, coefficients);
    return (g_dir - p.view_dir * dot(p.view_dir, g_dir)) / p.view_dist;
}

void main() {
    uint i = flat_workgroup_id() * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
    if (i >= gaussian_count()) {
        return;
    }
    Projection p;
    Splat s;
    if (!project(i, p, s)) {
        return; // culled: no gradient
    }
    vec2 g_mean = vec2(g2(i, GRAD2D_MEAN), g2(i, GRAD2D_MEAN + 1u));
    vec3 g_conic = vec3(g2(i, GRAD2D_CONIC), g2(i, GRAD2D_CONIC + 1u), g2(i, GRAD2D_CONIC + 2u));

    // Conic = inverse(cov2): dQ = -Q dcov2 Q, with Q01 standing for both off-diagonal entries.
    mat2 q = mat2(s.conic.x, s.conic.y, s.conic.y, s.conic.z);
    mat2 g_cov2 = -q * mat2(g_conic.x, 0.5 * g_conic.y, 0.5 * g_conic.y, g_conic.z) * q;
    mat3x2 g_jw = 2.0 * g_cov2 * p.jw * p.cov3;
    mat3 g_cov3 = transpose(p.jw) * g_cov2 * p.jw;
    mat3 w = view_rotation();
    mat3x2 g_j = g_jw * transpose(w);

    vec3 g_view = view_gradient(p, g_mean, g2(i, GRAD2D_DEPTH), g_j);
    vec3 g_position = transpose(w) * g_view + color_backward(i, p, vec3(g2(i, GRAD2D_COLOR), g2(i, GRAD2D_COLOR + 1u), g2(i, GRAD2D_COLOR + 2u)));

    // cov3 = M M^T with M = R S.
    mat3 m = p.rotation * mat3(p.scale.x, 0.0, 0.0, 0.0, p.scale.y, 0.0, 0.0, 0.0, p.scale.z);
    mat3 g_m = 2.0 * g_cov3 * m;
    vec3 g_scale = vec3(dot(g_m[0], p.rotation[0]), dot(g_m[1], p.rotation[1]), dot(g_m[2], p.rotation[2]));
    mat3 g_r = mat3(g_m[0] * p.scale.x, g_m[1] * p.scale.y, g_m[2] * p.scale.z);
    vec4 g_unit_q = rotation_backward(p.unit_q, g_r);
    vec4 g_q = (g_unit_q - p.unit_q * dot(p.unit_q, g_unit_q)) / p.q_norm;

    float g_opacity = mask_mode() ? 0.0 : g2(i, GRAD2D_OPACITY) * s.opacity * (1.0 - s.opacity);

    for (uint c = 0u; c < 3u; c++) {
        grad_positions[3u * i + c] += g_position[c];
        grad_log_scales[3u * i + c] += g_scale[c] * p.scale[c];
    }
    grad_rotations[i] += g_q;
    grad_opacity_logits[i] += g_opacity;
    uvec4 rect = tile_rect(s, sqrt(2.0 * s.extent * vec2(p.cov2[0][0], p.cov2[1][1])));
    if (rect.x < rect.y) {
        densify_stats[i] += vec2(length(g_mean), 1.0);
    }
}
