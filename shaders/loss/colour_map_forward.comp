#version 460
// A render seen through its camera's colour map (colour_map.glsl), and, when asked, the
// moments the host fits the camera's next map from (engine/loss/colour_map/affine.rs): with
// z = (p, α) the render's subject and y = target − (1 − α) background what the camera saw of
// it, the 10 sums Σ z_i z_j (i ≤ j) and the 12 sums Σ y_k z_j, over the pixels that both the
// render and the target cover (coverage ≥ INTERIOR).
//
// The moments steer the optimisation, so their sum must not depend on the device's order:
// each invocation sums its run of pixels in order, the workgroup adds those in a fixed tree
// in shared memory (the same on every device and subgroup size), and one fixed-point add per
// workgroup and moment makes the total order-independent.
#include "colour_map.glsl"
#include "../common/fixed_sum.glsl"
#include "../common/grid.glsl"

layout(local_size_x_id = 0) in;
layout(constant_id = 0) const uint WORKGROUP = 64;  // a power of two (the tree halves it)
const uint RUN = 16u;          // pixels per invocation (RUN in engine/loss/colour_map/mod.rs)
const uint MOMENTS = 22u;      // per camera: 10 of z zᵀ, 12 of y zᵀ
const float INTERIOR = 0.99;   // the coverage of render and target a pixel's moments need

layout(std430, binding = 0) readonly buffer Maps { vec4 maps[]; };
layout(std430, binding = 1) readonly buffer Render { u64vec2 render[]; };
layout(std430, binding = 2) readonly buffer Target { u64vec2 target[]; };
layout(std430, binding = 3) writeonly buffer Mapped { u64vec2 mapped[]; };
layout(std430, binding = 4) buffer Moments { int64_t moments[]; };

shared float partial[MOMENTS][WORKGROUP];

void main() {
    uint cam = camera();
    vec4 rows[3] = vec4[3](maps[3u * cam], maps[3u * cam + 1u], maps[3u * cam + 2u]);
    bool accumulate = params.size.z != 0u;
    float sums[MOMENTS];
    for (uint m = 0u; m < MOMENTS; m++) sums[m] = 0.0;
    uint first = (flat_workgroup_id() * WORKGROUP + gl_LocalInvocationID.x) * RUN;
    for (uint i = first; i < min(first + RUN, pixel_count()); i++) {
        vec4 c = unpack_vec4(render[i]);
        vec4 z = subject_of(c);
        vec3 seen;
        for (uint k = 0u; k < 3u; k++) seen[k] = dot(rows[k], z);
        mapped[i] = pack_vec4(vec4(seen + (1.0 - c.a) * params.background.rgb, c.a));
        vec4 t = unpack_vec4(target[i]);
        // Only where render and target both say subject: along the outline a pixel's colour
        // says more about the coverage than about the camera.
        if (accumulate && min(c.a, t.a) >= INTERIOR) {
            vec3 y = t.rgb - (1.0 - c.a) * params.background.rgb;
            uint m = 0u;
            for (uint a = 0u; a < 4u; a++) {
                for (uint b = a; b < 4u; b++) sums[m++] += z[a] * z[b];
            }
            for (uint k = 0u; k < 3u; k++) {
                for (uint b = 0u; b < 4u; b++) sums[m++] += y[k] * z[b];
            }
        }
    }
    if (!accumulate) return;  // uniform over the dispatch: no barrier is skipped by part of it
    uint lane = gl_LocalInvocationID.x;
    for (uint m = 0u; m < MOMENTS; m++) partial[m][lane] = sums[m];
    barrier();
    for (uint half_width = WORKGROUP / 2u; half_width > 0u; half_width /= 2u) {
        if (lane < half_width) {
            for (uint m = 0u; m < MOMENTS; m++) partial[m][lane] += partial[m][lane + half_width];
        }
        barrier();
    }
    if (lane < MOMENTS) FIXED_ADD_TOTAL(moments, cam * MOMENTS + lane, partial[lane][0]);
}
