// Shared by radix_histogram_lanes.comp and radix_scatter_lanes.comp, the radix-sort variant
// for CPU devices (lavapipe). There a workgroup runs on one core and every memory access is a
// loop over the SIMD lanes, so cross-lane matching and shared atomics are what costs. Instead,
// each invocation owns a contiguous run of the tile and its own digit counters: the tile's
// order is run 0, run 1, …, so ranks follow input order without any matching.
//
// Between passes the pairs travel as records, key and value side by side: one scattered
// output stream per digit instead of two halves the cache lines a scatter keeps open, which
// made the scatter 1.2x faster. Accesses are 64-bit: one lane-loop iteration moves two keys,
// or a whole record of a 32-bit key.
//
// With a sort of more than 8 bits these kernels first run one pass on the top digit (the
// bucket path, radix_bucket_lanes.comp); the usual LSD passes run only if a bucket is too
// large for it (params.gate).
//
// Every loop is bounded by the run length: lavapipe ends an invocation's loops after 65535
// iterations in all, so no loop may grow with the data.
#include "radix_common.glsl"
#include "radix_pair.glsl"

// 1: the pass reads records; 0: it reads the caller's separate keys and values.
layout(constant_id = 4) const uint RECORDS_IN = 0;

// The pass's input: the caller's keys and values, or records (binding 0, binding 1 unused).
layout(std430, binding = 0) readonly buffer KeyWordsIn { uint key_words_in[]; };
layout(std430, binding = 0) readonly buffer WideIn { uint64_t wide_in[]; }; // key couples, 64-bit keys or records
layout(std430, binding = 1) readonly buffer ValueWordsIn { uint value_words_in[]; };
layout(std430, binding = 1) readonly buffer ValueCouplesIn { uint64_t value_couples_in[]; };

DEFINE_RECORD_LOAD(load_record, wide_in)

// Pairs i and i + 1 (i even).
void load_couple(uint i, out Pair a, out Pair b) {
    if (RECORDS_IN == 1u) {
        a = load_record(i);
        b = load_record(i + 1u);
        return;
    }
    uvec2 values = unpackUint2x32(value_couples_in[i / 2u]);
    if (KEY_WORDS == 1u) {
        uvec2 keys = unpackUint2x32(wide_in[i / 2u]);
        a = Pair(keys.x, 0u, values.x);
        b = Pair(keys.y, 0u, values.y);
    } else {
        uvec2 key_a = unpackUint2x32(wide_in[i]);
        uvec2 key_b = unpackUint2x32(wide_in[i + 1u]);
        a = Pair(key_a.x, key_a.y, values.x);
        b = Pair(key_b.x, key_b.y, values.y);
    }
}

// Pair i alone: the odd one at the end of the sort.
Pair load_one(uint i) {
    if (RECORDS_IN == 1u) {
        return load_record(i);
    }
    Pair p = Pair(key_words_in[i * KEY_WORDS], 0u, value_words_in[i]);
    if (KEY_WORDS == 2u) {
        p.hi = key_words_in[i * 2u + 1u];
    }
    return p;
}

uint digit_of_pair(Pair p) {
    return digit_at(p, params.word * 32u + params.shift, params.digit_bits);
}

// The plan (radix_plan_lanes.comp): [0] is 1 when the sort takes the bucket path. Each kernel
// defines PLAN_BINDING, its binding after its own buffers.
layout(std430, binding = PLAN_BINDING) readonly buffer Plan { uint plan[]; };

// Whether this dispatch does work, or belongs to the path the plan did not take.
bool gate_open() {
    return gate_open(plan[0]);
}

// Key range [begin, end) of this invocation's run of `tile`, and the end of its whole
// couples of keys (runs start on even indices, so couples are whole 64-bit words).
uvec3 run_range(uint tile) {
    uint begin = min(tile * TILE_LEN + gl_LocalInvocationID.x * KEYS_PER_THREAD, params.len);
    uint end = min(begin + KEYS_PER_THREAD, params.len);
    return uvec3(begin, end, begin + ((end - begin) & ~1u));
}

shared uint run_digits[WORKGROUP_SIZE * RADIX]; // [invocation][digit]
