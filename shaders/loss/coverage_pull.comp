#version 460
// Coverage term, pass 2: one invocation per pixel p. Where the mask covers p (> 0.5) but the
// render does not (alpha < 0.5), the nearest seed vertex s within `radius` pixels is pulled
// towards p's centre:  E = scale Σ_p ‖uv_s − p‖²,  the gradient chained through the
// projection and added to s's position gradient (fixed-point atomics: pixels share vertices,
// and the sum must not depend on their order).
// The search walks square rings outwards and stops once no nearer seed can exist: a seed in
// ring r lies in its pixel, at least r − 0.5 pixels from p's centre. Ties go to the lower id.
#include "coverage_common.glsl"
#include "../common/fixed_sum.glsl"
#include "../common/pinhole.glsl"
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer Positions { float positions[]; };
layout(std430, binding = 1) readonly buffer Projected { vec2 projected[]; };
layout(std430, binding = 2) readonly buffer Seeds { uint seeds[]; };
layout(std430, binding = 3) readonly buffer Target { vec4 target[]; };
layout(std430, binding = 4) readonly buffer Render { vec4 render[]; };
layout(std430, binding = 5) buffer GradPositionSums { int64_t grad_position_sums[]; };
layout(std430, binding = 6) buffer LossSum { int64_t loss_sum[]; };

// Nearest seed to `centre` within the radius: (vertex, squared distance), NO_SEED if none.
uvec2 nearest_seed(ivec2 pixel, vec2 centre) {
    uint best = NO_SEED;
    float best_d2 = 1e30;
    for (int r = 0; r <= int(pc.radius); r++) {
        float reach = max(float(r) - 0.5, 0.0);
        if (best != NO_SEED && best_d2 < reach * reach) {
            break;
        }
        // The ring of Chebyshev radius r: 8r cells (one at r = 0).
        int cells = r == 0 ? 1 : 8 * r;
        for (int k = 0; k < cells; k++) {
            int side = r == 0 ? 0 : k / (2 * r), along = r == 0 ? 0 : k % (2 * r) - r;
            ivec2 offset = side == 0 ? ivec2(along, -r) : side == 1 ? ivec2(r, along) : side == 2 ? ivec2(-along, r) : ivec2(-r, -along);
            ivec2 q = pixel + offset;
            if (q.x < 0 || q.y < 0 || q.x >= int(pc.width) || q.y >= int(pc.height)) {
                continue;
            }
            uint s = seeds[uint(q.y) * pc.width + uint(q.x)];
            if (s == NO_SEED) {
                continue;
            }
            vec2 d = projected[s] - centre;
            float d2 = dot(d, d);
            if (d2 < best_d2 || (d2 == best_d2 && s < best)) {
                best = s;
                best_d2 = d2;
            }
        }
    }
    return uvec2(best, floatBitsToUint(best_d2));
}

void main() {
    uint p = flat_workgroup_id() * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
    float energy = 0.0;
    if (p < pc.width * pc.height && target[p].w > 0.5 && !(render[p].w >= 0.5)) {
        ivec2 pixel = ivec2(p % pc.width, p / pc.width);
        vec2 centre = vec2(pixel) + 0.5;
        uvec2 found = nearest_seed(pixel, centre);
        if (found.x != NO_SEED) {
            uint s = found.x;
            vec3 x = vec3(positions[3u * s], positions[3u * s + 1u], positions[3u * s + 2u]);
            vec3 c = to_camera(x);
            vec2 uv = project(c);
            energy = pc.scale * dot(uv - centre, uv - centre);
            vec2 g = 2.0 * pc.scale * (uv - centre);
            vec3 dx = pinhole_backward(pc.world_to_camera, pc.intrinsics, c, g);
            for (uint k = 0u; k < 3u; k++) {
                FIXED_ADD_GRADIENT(grad_position_sums, 3u * s + k, dx[k]);
            }
        }
    }
    float total = subgroupAdd(energy);
    if (subgroupElect()) {
        FIXED_ADD_TOTAL(loss_sum, 0u, total);
    }
}
