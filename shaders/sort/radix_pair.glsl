// Pairs and records of the CPU-device radix sort (radix_lanes_common.glsl,
// radix_bucket_lanes.comp).
#ifndef SORT_RADIX_PAIR_GLSL
#define SORT_RADIX_PAIR_GLSL
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

// One key and its value. `hi` is 0 for 32-bit keys.
struct Pair {
    uint lo;
    uint hi;
    uint value;
};

// The digit of `digit_bits` bits from bit `shift` of the key. For 64-bit keys it may straddle
// the two words: the bucket path's top digit sits just under `bits`, wherever that is.
uint digit_at(Pair p, uint shift, uint digit_bits) {
    uint mask = (1u << digit_bits) - 1u;
    if (KEY_WORDS == 1u) {
        return (p.lo >> shift) & mask;
    }
    return uint(packUint2x32(uvec2(p.lo, p.hi)) >> shift) & mask;
}

// Record i is KEY_WORDS 64-bit words: (lo, value) for 32-bit keys; (lo, hi), (value, 0) for
// 64-bit keys.
Pair record_from(uint64_t first, uint64_t second) {
    uvec2 a = unpackUint2x32(first);
    if (KEY_WORDS == 1u) {
        return Pair(a.x, 0u, a.y);
    }
    return Pair(a.x, a.y, unpackUint2x32(second).x);
}

uint64_t record_word(Pair p, uint w) {
    if (KEY_WORDS == 1u) {
        return packUint2x32(uvec2(p.lo, p.value));
    }
    return packUint2x32(w == 0u ? uvec2(p.lo, p.hi) : uvec2(p.value, 0u));
}

// Pair LOAD(uint i): record i of the uint64_t array ARRAY.
#define DEFINE_RECORD_LOAD(LOAD, ARRAY)                                                      \
    Pair LOAD(uint i) {                                                                      \
        return record_from(ARRAY[i * KEY_WORDS], KEY_WORDS == 2u ? ARRAY[i * 2u + 1u] : 0ul); \
    }

// void STORE(uint i, Pair p): record i of the uint64_t array ARRAY.
#define DEFINE_RECORD_STORE(STORE, ARRAY)             \
    void STORE(uint i, Pair p) {                      \
        ARRAY[i * KEY_WORDS] = record_word(p, 0u);    \
        if (KEY_WORDS == 2u) {                        \
            ARRAY[i * 2u + 1u] = record_word(p, 1u);  \
        }                                             \
    }

#ifdef PAIRS_OUT_BINDING
// The caller's keys (binding PAIRS_OUT_BINDING) and values (the next binding), for the kernels
// that write pairs back.
layout(std430, binding = PAIRS_OUT_BINDING) writeonly buffer KeyWordsOut { uint key_words_out[]; };
layout(std430, binding = PAIRS_OUT_BINDING) writeonly buffer KeysOut { uint64_t keys_out[]; }; // 64-bit keys
layout(std430, binding = PAIRS_OUT_BINDING + 1) writeonly buffer ValuesOut { uint values_out[]; };

void store_pair(uint i, Pair p) {
    if (KEY_WORDS == 1u) {
        key_words_out[i] = p.lo;
    } else {
        keys_out[i] = packUint2x32(uvec2(p.lo, p.hi));
    }
    values_out[i] = p.value;
}
#endif

// Which path of the sort a kernel belongs to (params.gate), against the plan's choice.
const uint GATE_ALWAYS = 0u;
const uint GATE_BUCKET_PATH = 1u; // runs only when every top-digit bucket fits
const uint GATE_LSD_PATH = 2u;    // runs only when one does not

bool gate_open(uint bucket_path) {
    return params.gate == GATE_ALWAYS || (params.gate == GATE_BUCKET_PATH) == (bucket_path != 0u);
}

#endif
