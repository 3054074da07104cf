#version 460
// Radix sort, CPU-device variant, bucket path step 2. The global pass on the top digit left
// each bucket contiguous in records A, none longer than params.max_bucket_len. One invocation
// sorts one bucket alone by the low bits under the top digit: LSD passes that ping-pong
// between records A and B while the bucket stays in cache, each counting the next pass's
// digits as it scatters; the last writes the caller's keys and values. No counter is shared,
// so there is no barrier and no atomic. Stable.
//
// Loops are unrolled by UNROLL: lavapipe ends an invocation's loops after 65535 iterations in
// all, and radix.rs sizes max_bucket_len so that every loop here stays under that.
#define PAIRS_OUT_BINDING 2
#include "radix_common.glsl"
#include "radix_pair.glsl"

layout(std430, binding = 0) buffer RecordsA { uint64_t records_a[]; };
layout(std430, binding = 1) buffer RecordsB { uint64_t records_b[]; };
// Bindings 2 and 3: the caller's keys and values (PAIRS_OUT_BINDING).
layout(std430, binding = 4) readonly buffer TopDigitOffsets { uint tile_offsets[]; }; // scanned, digit-major
layout(std430, binding = 5) readonly buffer Plan { uint plan[]; };

const uint UNROLL = 8u;

// [pass parity][digit]: this pass's next output positions, then the next pass's counts.
uint counters[2 * RADIX];

DEFINE_RECORD_LOAD(load_a, records_a)
DEFINE_RECORD_LOAD(load_b, records_b)
DEFINE_RECORD_STORE(store_a, records_a)
DEFINE_RECORD_STORE(store_b, records_b)

// Shift and width of local pass k's digit within the `low_bits` under the top digit; a pass
// past the last has a zero-bit digit.
uvec2 pass_digit(uint k, uint low_bits) {
    uint shift = k * RADIX_BITS;
    return uvec2(shift, low_bits > shift ? min(RADIX_BITS, low_bits - shift) : 0u);
}

void count(Pair p, uint base, uvec2 digit) {
    counters[base + digit_at(p, digit.x, digit.y)] += 1u;
}

// The pair's output position in this pass (counters[cur + digit]), counting its digit of the
// next pass (counters[next + digit]).
uint next_slot(Pair p, uint cur, uint next, uvec2 digit, uvec2 next_digit) {
    uint d = digit_at(p, digit.x, digit.y);
    uint slot = counters[cur + d];
    counters[cur + d] = slot + 1u;
    count(p, next, next_digit);
    return slot;
}

// Counts of the first pass's digit, records A [range.x, range.y), into counters[0, RADIX).
void count_first(uvec2 range, uvec2 digit) {
    uint i = range.x;
    for (; i + UNROLL <= range.y; i += UNROLL) {
        count(load_a(i), 0u, digit);
        count(load_a(i + 1u), 0u, digit);
        count(load_a(i + 2u), 0u, digit);
        count(load_a(i + 3u), 0u, digit);
        count(load_a(i + 4u), 0u, digit);
        count(load_a(i + 5u), 0u, digit);
        count(load_a(i + 6u), 0u, digit);
        count(load_a(i + 7u), 0u, digit);
    }
    for (; i < range.y; i++) {
        count(load_a(i), 0u, digit);
    }
}

// One pass over records [range.x, range.y) from LOAD to STORE, UNROLL pairs at a time: their
// loads, then their stores.
#define DEFINE_PASS(NAME, LOAD, STORE)                                                   \
    void NAME(uvec2 range, uint cur, uint next, uvec2 digit, uvec2 next_digit) {         \
        uint i = range.x;                                                                \
        for (; i + UNROLL <= range.y; i += UNROLL) {                                     \
            Pair p0 = LOAD(i), p1 = LOAD(i + 1u), p2 = LOAD(i + 2u), p3 = LOAD(i + 3u);  \
            Pair p4 = LOAD(i + 4u), p5 = LOAD(i + 5u), p6 = LOAD(i + 6u), p7 = LOAD(i + 7u); \
            STORE(next_slot(p0, cur, next, digit, next_digit), p0);                      \
            STORE(next_slot(p1, cur, next, digit, next_digit), p1);                      \
            STORE(next_slot(p2, cur, next, digit, next_digit), p2);                      \
            STORE(next_slot(p3, cur, next, digit, next_digit), p3);                      \
            STORE(next_slot(p4, cur, next, digit, next_digit), p4);                      \
            STORE(next_slot(p5, cur, next, digit, next_digit), p5);                      \
            STORE(next_slot(p6, cur, next, digit, next_digit), p6);                      \
            STORE(next_slot(p7, cur, next, digit, next_digit), p7);                      \
        }                                                                                \
        for (; i < range.y; i++) {                                                       \
            Pair p = LOAD(i);                                                            \
            STORE(next_slot(p, cur, next, digit, next_digit), p);                        \
        }                                                                                \
    }

DEFINE_PASS(pass_a_to_b, load_a, store_b)
DEFINE_PASS(pass_b_to_a, load_b, store_a)
DEFINE_PASS(pass_a_to_pairs, load_a, store_pair)
DEFINE_PASS(pass_b_to_pairs, load_b, store_pair)

void main() {
    uint bucket = flat_workgroup_id() * WORKGROUP_SIZE + gl_LocalInvocationID.x;
    if (bucket >= RADIX || plan[0] == 0u) {
        return;
    }
    uint begin = tile_offsets[bucket * params.tile_count];
    uint end = bucket + 1u < RADIX ? tile_offsets[(bucket + 1u) * params.tile_count] : params.len;
    uvec2 range = uvec2(begin, end);
    uvec2 none = uvec2(begin, begin);
    uint low_bits = params.bits - RADIX_BITS;
    uint passes = (low_bits + RADIX_BITS - 1u) / RADIX_BITS;

    for (uint d = 0u; d < RADIX; d++) {
        counters[d] = 0u;
    }
    count_first(range, pass_digit(0u, low_bits));
    for (uint k = 0u; k < passes; k++) {
        uint cur = (k & 1u) * RADIX;
        uint next = RADIX - cur;
        uint position = begin;
        for (uint d = 0u; d < RADIX; d++) {
            uint c = counters[cur + d];
            counters[cur + d] = position;
            position += c;
            counters[next + d] = 0u;
        }
        uvec2 digit = pass_digit(k, low_bits);
        uvec2 next_digit = pass_digit(k + 1u, low_bits);
        bool from_a = (k & 1u) == 0u;
        bool last = k + 1u == passes;
        // gallivm runs an `if` body masked even when no lane takes it, so the three passes
        // not taken get empty ranges (a loop that no lane enters ends at once).
        pass_a_to_b(from_a && !last ? range : none, cur, next, digit, next_digit);
        pass_b_to_a(!from_a && !last ? range : none, cur, next, digit, next_digit);
        pass_a_to_pairs(from_a && last ? range : none, cur, next, digit, next_digit);
        pass_b_to_pairs(!from_a && last ? range : none, cur, next, digit, next_digit);
    }
}
