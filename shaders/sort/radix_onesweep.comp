#version 460
// Radix sort, Onesweep variant (Adinets & Merrill 2022), one dispatch per pass: every key and
// value moves to its place, stably. A workgroup takes the next tile from a counter, so
// a tile only waits on tiles that started before it. It ranks its tile's keys
// (radix_rank.glsl) and publishes its count per digit ("aggregate"; tile 0's count is
// already its "inclusive" prefix). It then looks back over the earlier tiles' status
// words (look_back), publishes its inclusive prefix, and scatters to the digit's first
// position (radix_onesweep_scan.comp) + its exclusive prefix + its rank.
//
// The look-back must end on lavapipe, which ends every loop of an invocation after 65535
// iterations in all: a predecessor whose word stays empty for LOOKBACK_POLLS reads is counted
// from its keys by the waiting workgroup ("decoupled fallback"). The look-back then steps
// back past the earlier tiles still running and one more (a finished tile has published its
// inclusive prefix), each step at most LOOKBACK_POLLS reads and KEYS_PER_THREAD keys per
// invocation.
#define STATUS_BINDING 5
#include "radix_common.glsl"
#include "radix_rank.glsl"
#include "radix_onesweep_common.glsl"

layout(std430, binding = 2) readonly buffer DigitStarts { uint digit_starts[]; }; // [pass][digit]
// [pass]: the next tile of the pass; [MAX_PASSES]: fallbacks taken (for tests, benches).
layout(std430, binding = 6) coherent buffer Progress { uint progress[]; };

// Reads of an empty status word before the waiting workgroup counts that tile itself.
layout(constant_id = 4) const uint LOOKBACK_POLLS = 64;

const uint FLAG_AGGREGATE = 1u << 30; // the word holds the tile's own count
const uint FLAG_INCLUSIVE = 2u << 30; // the word holds the count of tiles 0 to this one
const uint COUNT_MASK = FLAG_AGGREGATE - 1u;
// Invocation t owns digits t, t + WORKGROUP_SIZE, … (a power of two of at most 256).
const uint DIGITS_PER_INVOCATION = RADIX / WORKGROUP_SIZE;

shared uint tile_taken;
shared uint fallback_counts[RADIX]; // digit counts of the tile being counted, else 0
shared uint need_fallback;          // some digit of this step's tile had no word
shared uint still_looking;          // some digit has not reached an inclusive prefix yet

uint own_digit(uint k) {
    return gl_LocalInvocationID.x + k * WORKGROUP_SIZE;
}

// The next tile of this pass, the same for the whole workgroup.
uint take_tile() {
    if (gl_LocalInvocationID.x == 0u) {
        tile_taken = atomicAdd(progress[pass_index()], 1u);
    }
    barrier();
    return tile_taken;
}

// Status words of `q` for the owned digits not yet `done`, read until each has a flag or
// LOOKBACK_POLLS reads have been made; sets need_fallback when one is still empty.
void poll(uint q, bool done[DIGITS_PER_INVOCATION], out uint seen[DIGITS_PER_INVOCATION]) {
    [[unroll]] for (uint k = 0u; k < DIGITS_PER_INVOCATION; k++) {
        seen[k] = done[k] ? FLAG_INCLUSIVE : 0u;
    }
    bool waiting = true;
    for (uint reads = 0u; reads < LOOKBACK_POLLS && waiting; reads++) {
        waiting = false;
        [[unroll]] for (uint k = 0u; k < DIGITS_PER_INVOCATION; k++) {
            if (seen[k] == 0u) {
                seen[k] = status[status_index(pass_index(), q, own_digit(k))];
                waiting = waiting || seen[k] == 0u;
            }
        }
    }
    if (waiting) {
        need_fallback = 1u;
    }
}

// Adds the digit counts of tile q's keys into fallback_counts. When `wanted` is false
// the loop has an empty range: on lavapipe an `if` would run its body anyway.
void count_tile(uint q, bool wanted) {
    uint begin = q * TILE_LEN;
    uint end = wanted ? min(begin + TILE_LEN, params.len) : begin;
    for (uint i = begin + gl_LocalInvocationID.x; i < end; i += WORKGROUP_SIZE) {
        atomicAdd(fallback_counts[digit_of(keys_in[i * KEY_WORDS + params.word])], 1u);
    }
}

// Sum of the counts of the tiles before `tile`, per owned digit. The workgroup
// steps back one tile at a time, all digits together, so that a fallback counts a
// tile once for every digit. Every shared word is written and read in distinct phases
// between the three barriers of a step.
void look_back(uint tile, out uint prefix[DIGITS_PER_INVOCATION]) {
    bool done[DIGITS_PER_INVOCATION];
    [[unroll]] for (uint k = 0u; k < DIGITS_PER_INVOCATION; k++) {
        prefix[k] = 0u;
        done[k] = false;
    }
    bool looking = tile > 0u;
    for (uint q = tile; looking;) {
        q--;
        uint seen[DIGITS_PER_INVOCATION];
        poll(q, done, seen);
        barrier();
        bool fallback = need_fallback != 0u;
        if (gl_LocalInvocationID.x == 0u) {
            still_looking = 0u;
        }
        count_tile(q, fallback);
        barrier();
        if (gl_LocalInvocationID.x == 0u) {
            need_fallback = 0u;
        }
        if (gl_LocalInvocationID.x == 0u && fallback) {
            atomicAdd(progress[MAX_PASSES], 1u);
        }
        [[unroll]] for (uint k = 0u; k < DIGITS_PER_INVOCATION; k++) {
            uint counted = fallback_counts[own_digit(k)];
            fallback_counts[own_digit(k)] = 0u;
            if (!done[k]) {
                prefix[k] += seen[k] != 0u ? seen[k] & COUNT_MASK : counted;
                done[k] = (seen[k] & FLAG_INCLUSIVE) != 0u || q == 0u;
            }
            if (!done[k]) {
                still_looking = 1u;
            }
        }
        barrier();
        looking = still_looking != 0u;
    }
}

void main() {
    if (gl_LocalInvocationID.x == 0u) {
        need_fallback = 0u;
    }
    for (uint d = gl_LocalInvocationID.x; d < RADIX; d += WORKGROUP_SIZE) {
        fallback_counts[d] = 0u;
    }
    uint tile = take_tile();
    if (tile >= params.tile_count) {
        return; // Past the end of a folded grid.
    }
    uint pass = pass_index();
    clear_status(pass + 1u, tile);
    rank_tile(tile);
    barrier();
    uint count[DIGITS_PER_INVOCATION];
    uint flag = tile == 0u ? FLAG_INCLUSIVE : FLAG_AGGREGATE;
    [[unroll]] for (uint k = 0u; k < DIGITS_PER_INVOCATION; k++) {
        count[k] = tile_digit_count(own_digit(k));
        atomicExchange(status[status_index(pass, tile, own_digit(k))], flag | count[k]);
    }
    uint prefix[DIGITS_PER_INVOCATION];
    look_back(tile, prefix);
    [[unroll]] for (uint k = 0u; k < DIGITS_PER_INVOCATION; k++) {
        uint d = own_digit(k);
        uint inclusive = prefix[k] + count[k];
        atomicExchange(status[status_index(pass, tile, d)], FLAG_INCLUSIVE | inclusive);
        counts_to_offsets(d, digit_starts[pass * RADIX + d] + prefix[k]);
    }
    barrier();
    scatter_tile(tile);
}
