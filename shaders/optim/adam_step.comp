#version 460
#extension GL_EXT_control_flow_attributes : require
// Adam over every parameter group in one dispatch. Each invocation updates a few chunks of four
// floats of one buffer (positions, log-scales, rotations, opacity logits, SH in turn), loaded as two
// 64-bit words: on CPU devices every buffer access is a loop over lanes and a scalar access
// per component, so four floats in two words is four times fewer loops and half the accesses.
// Moments (m, v) are interleaved beside each float; a buffer whose length is not a multiple of
// four ends in a chunk updated float by float.
#include "adam.glsl"
#include "../common/wide_vec4.glsl"
#include "../common/grid.glsl"
layout(local_size_x_id = 0) in;

// Each buffer is bound once and seen both as floats and as four floats in two 64-bit words
// (aliases of one binding; wide_vec4.glsl says why).
#define PARAMS(b, name) \
    layout(std430, binding = b) buffer name##_f { float name[]; }; \
    layout(std430, binding = b) buffer name##_v { u64vec2 name##4[]; };
PARAMS(0, positions)
PARAMS(1, log_scales)
PARAMS(2, rotations)
PARAMS(3, opacity_logits)
PARAMS(4, sh)
PARAMS(5, g_positions)
PARAMS(6, g_log_scales)
PARAMS(7, g_rotations)
PARAMS(8, g_opacity_logits)
PARAMS(9, g_sh)
#define MOMENTS(b, name) \
    layout(std430, binding = b) buffer name##_f { vec2 name[]; }; \
    layout(std430, binding = b) buffer name##_v { u64vec2 name##4[]; };
MOMENTS(10, m_positions)
MOMENTS(11, m_log_scales)
MOMENTS(12, m_rotations)
MOMENTS(13, m_opacity_logits)
MOMENTS(14, m_sh)
layout(std430, binding = 15) readonly buffer AdamSteps { AdamParams steps[]; };
// This step's parameters (main loads them from the ring slot).
AdamParams params;
// Set by engine/optim/adam.rs, which sizes the dispatch by it.
layout(constant_id = 1) const uint CHUNKS_PER_INVOCATION = 8u;

// Updates the moments and returns the step to subtract, for four floats.
vec4 adam(inout vec4 m, inout vec4 v, vec4 g, vec4 lr) {
    vec4 b = params.betas;
    m = b.x * m + b.z * g;
    v = b.y * v + b.w * g * g;
    return lr * (m / params.bias.x) / (sqrt(v / params.bias.y) + params.lr_b.z);
}

// Learning rates of SH floats j .. j + 3: SH is Gaussian-major, DC first. One modulo for the
// four, as integer division has no SIMD form on CPUs (one division per lane). A row holds at
// least 3 floats, so k + i wraps at most once.
vec4 sh_rates(uint j) {
    uint row = 3u * params.counts.y;
    uint k = j % row;
    vec4 rates;
    [[unroll]] for (uint i = 0u; i < 4u; i++) {
        uint ki = k + i >= row ? k + i - row : k + i;
        rates[i] = ki < 3u ? params.lr_b.x : params.lr_b.y;
    }
    return rates;
}

#define UPDATE(P, G, M, len, c, RATES) { \
    uint first = 4u * (c); \
    if (first + 4u <= (len)) { \
        vec4 lr = RATES(first); \
        vec4 m01 = unpack_vec4(M##4[2u * (c)]), m23 = unpack_vec4(M##4[2u * (c) + 1u]); \
        vec4 m = vec4(m01.xz, m23.xz), v = vec4(m01.yw, m23.yw); \
        vec4 step = adam(m, v, unpack_vec4(G##4[c]), lr); \
        P##4[c] = pack_vec4(unpack_vec4(P##4[c]) - step); \
        M##4[2u * (c)] = pack_vec4(vec4(m.x, v.x, m.y, v.y)); \
        M##4[2u * (c) + 1u] = pack_vec4(vec4(m.z, v.z, m.w, v.w)); \
    } else { \
        for (uint j = first; j < (len); j++) { \
            vec4 m = vec4(M[j].x), v = vec4(M[j].y); \
            P[j] -= adam(m, v, vec4(G[j]), RATES(j)).x; \
            M[j] = vec2(m.x, v.x); \
        } \
    } \
}

#define RATE_POSITIONS(j) vec4(params.lr_a.x)
#define RATE_SCALES(j) vec4(params.lr_a.y)
#define RATE_ROTATIONS(j) vec4(params.lr_a.z)
#define RATE_OPACITY(j) vec4(params.lr_a.w)
#define RATE_SH(j) sh_rates(j)

uint chunks(uint len) { return (len + 3u) / 4u; }

// Updates chunk c of the five buffers laid end to end.
void update(uint c, uint lens[5]) {
    if (c < chunks(lens[0])) { UPDATE(positions, g_positions, m_positions, lens[0], c, RATE_POSITIONS) return; }
    c -= chunks(lens[0]);
    if (c < chunks(lens[1])) { UPDATE(log_scales, g_log_scales, m_log_scales, lens[1], c, RATE_SCALES) return; }
    c -= chunks(lens[1]);
    if (c < chunks(lens[2])) { UPDATE(rotations, g_rotations, m_rotations, lens[2], c, RATE_ROTATIONS) return; }
    c -= chunks(lens[2]);
    if (c < chunks(lens[3])) { UPDATE(opacity_logits, g_opacity_logits, m_opacity_logits, lens[3], c, RATE_OPACITY) return; }
    c -= chunks(lens[3]);
    if (c < chunks(lens[4])) { UPDATE(sh, g_sh, m_sh, lens[4], c, RATE_SH) }
}

void main() {
    // The step's parameters, read once: on CPU devices every buffer read is a loop over lanes,
    // so each invocation updates CHUNKS_PER_INVOCATION chunks to share that read. A workgroup's
    // lanes take consecutive chunks in each round (coalesced on a GPU).
    params = steps[adam_slot.slot];
    uint n = params.counts.x;
    uint lens[5] = uint[5](3u * n, 3u * n, 4u * n, n, 3u * params.counts.y * n);
    uint width = gl_WorkGroupSize.x;
    uint first = flat_workgroup_id() * width * CHUNKS_PER_INVOCATION + gl_LocalInvocationID.x;
    [[unroll]] for (uint k = 0u; k < CHUNKS_PER_INVOCATION; k++) {
        update(first + k * width, lens);
    }
}
