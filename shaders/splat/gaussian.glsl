// A Gaussian's parameters as stored, and the projection shared by project.comp (forward) and
// project_backward.comp. The includer binds the parameter buffers at 0..4 through the
// declarations below.
#ifndef SPLAT_GAUSSIAN_GLSL
#define SPLAT_GAUSSIAN_GLSL

#include "frame.glsl"
#include "sh.glsl"
#include "../common/quaternion.glsl"

layout(std430, binding = 0) readonly buffer Positions { float positions[]; };      // 3 per Gaussian
layout(std430, binding = 1) readonly buffer LogScales { float log_scales[]; };     // 3 per Gaussian
layout(std430, binding = 2) readonly buffer Rotations { vec4 rotations[]; };       // (w, x, y, z)
layout(std430, binding = 3) readonly buffer OpacityLogits { float opacity_logits[]; };
layout(std430, binding = 4) readonly buffer Coefficients { float sh[]; };          // [gaussian][k][rgb]

const float F32_MIN_NORMAL = 1.17549435e-38;

vec3 load3(uint i, uint which) {
    uint at = 3u * i;
    return which == 0u ? vec3(positions[at], positions[at + 1u], positions[at + 2u])
                       : vec3(log_scales[at], log_scales[at + 1u], log_scales[at + 2u]);
}

vec3 sh_coefficient(uint i, uint k) {
    uint at = (i * sh_stride() + k) * 3u;
    return vec3(sh[at], sh[at + 1u], sh[at + 2u]);
}

bool all_finite(vec4 v) {
    return !any(isnan(v)) && !any(isinf(v));
}

// Everything the projection of one Gaussian computes, kept for its backward.
struct Projection {
    vec3 view;        // v = W p + t
    vec4 unit_q;      // q / |q|
    float q_norm;     // |q|
    mat3 rotation;    // R
    vec3 scale;       // exp(log-scale)
    mat3 cov3;        // R S S^T R^T
    vec2 ray;         // guard-band-clamped (v.x / v.z, v.y / v.z)
    bvec2 clamped;    // whether the clamp was active
    mat3x2 jw;        // J W
    mat2 cov2;        // dilated 2D covariance
    vec3 view_dir;    // unit (p - camera centre)
    float view_dist;  // |p - camera centre|
    float sh_sum[3];  // 0.5 + SH, per channel, before the clamp
};

// Projects Gaussian i; false when it is culled (see engine/splat/mod.rs for every rule).
bool project(uint i, out Projection p, out Splat s) {
    vec3 position = load3(i, 0u);
    vec3 log_scale = load3(i, 1u);
    vec4 q = rotations[i];
    float logit = opacity_logits[i];
    if (!all_finite(vec4(position, logit)) || !all_finite(vec4(log_scale, 0.0)) || !all_finite(q)) {
        return false;
    }
    // Scale by the largest component first so tiny (normal) quaternions do not underflow.
    float largest = max(max(abs(q.x), abs(q.y)), max(abs(q.z), abs(q.w)));
    if (!(largest >= F32_MIN_NORMAL)) {
        return false;
    }
    vec4 q_scaled = q / largest;
    p.q_norm = length(q_scaled) * largest;
    p.unit_q = q_scaled / length(q_scaled);
    p.view = view_rotation() * position + view_translation();
    float z = p.view.z;
    if (!(z > frame.center_near.w && z < frame.background_far.w)) {
        return false;
    }
    p.rotation = rotation_of(p.unit_q);
    p.scale = exp(log_scale);
    mat3 m = p.rotation * mat3(p.scale.x, 0.0, 0.0, 0.0, p.scale.y, 0.0, 0.0, 0.0, p.scale.z);
    p.cov3 = m * transpose(m);

    vec4 k = frame.intrinsics; // fx, fy, cx, cy
    vec2 size = vec2(frame.size.xy);
    vec2 lim_neg = k.zw / k.xy + 0.3 * size / k.xy;
    vec2 lim_pos = (size - k.zw) / k.xy + 0.3 * size / k.xy;
    vec2 ray = p.view.xy / z;
    p.ray = clamp(ray, -lim_neg, lim_pos);
    p.clamped = bvec2(ray.x != p.ray.x, ray.y != p.ray.y);
    mat3x2 j = mat3x2(vec2(k.x / z, 0.0), vec2(0.0, k.y / z), -k.xy * p.ray / z);
    p.jw = j * view_rotation();
    p.cov2 = p.jw * p.cov3 * transpose(p.jw) + mat2(DILATION);
    float det = p.cov2[0][0] * p.cov2[1][1] - p.cov2[1][0] * p.cov2[1][0];
    s.conic = vec3(p.cov2[1][1], -p.cov2[1][0], p.cov2[0][0]) / det;
    s.mean = k.xy * p.view.xy / z + k.zw;
    s.depth = z;
    s.opacity = mask_mode() ? 1.0 : 1.0 / (1.0 + exp(-logit));
    // Phrased as positive tests, so NaN culls.
    if (!(det > 0.0 && s.opacity >= ALPHA_MIN && all_finite(vec4(s.conic, s.mean.x)) && all_finite(vec4(s.mean, 0.0, 0.0)))) {
        return false;
    }
    s.extent = log(255.0 * s.opacity);

    vec3 offset = position - frame.center_near.xyz;
    p.view_dist = length(offset);
    p.view_dir = offset / p.view_dist;
    float basis[16];
    sh_basis(p.view_dir, basis);
    vec3 color = vec3(0.5);
    uint coefficients = (sh_degree() + 1u) * (sh_degree() + 1u);
    for (uint c = 0u; c < coefficients; c++) {
        color += basis[c] * sh_coefficient(i, c);
    }
    p.sh_sum = float[3](color.r, color.g, color.b);
    s.color = vec4(mask_mode() ? vec3(1.0) : max(color, vec3(0.0)), 0.0);
    // Checked before the clamp: max(NaN, 0) may well be 0.
    return all_finite(vec4(color, p.view_dist));
}

#endif
