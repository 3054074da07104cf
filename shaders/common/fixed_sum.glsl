// Order-independent sums. Float atomics add in whatever order the device schedules them, so
// two runs round differently and an optimisation amplifies the difference. Here a value is
// rounded to 64-bit fixed point (40 fraction bits: steps of 2^-40 ≈ 9.1e-13, totals within
// ±2^23) and added with a 64-bit integer atomic; integer addition is associative, so a sum has
// the same bits whatever the order. Sum i is element i of its buffer; the buffer's last
// element counts the contributions dropped for being NaN, infinite or beyond ±FIXED_LIMIT, so
// that the reader can report NaN (engine/gpu/fixed_sum.rs decodes and resolves).
#ifndef COMMON_FIXED_SUM_GLSL
#define COMMON_FIXED_SUM_GLSL

#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require

const float FIXED_ONE = 1099511627776.0;  // 2^40
const float FIXED_LIMIT = 4194304.0;      // 2^22, one contribution's bound

// The float nearest a sum.
float fixed_value(int64_t sum) {
    return float(sum) / FIXED_ONE;
}

// Adds `value` to sum `i` of the int64_t array `sums` (a macro: GLSL cannot pass a buffer).
// Scaling by 2^40 is exact and the product stays within ±2^62; phrased as positive so that
// NaN lands in the dropped count.
#define FIXED_ADD(sums, i, value) {                                             \
    float value_ = (value);                                                      \
    if (!(abs(value_) <= FIXED_LIMIT)) {                                         \
        atomicAdd(sums[sums.length() - 1], int64_t(1));                          \
    } else if (value_ != 0.0) {                                                  \
        atomicAdd(sums[i], int64_t(roundEven(value_ * FIXED_ONE)));              \
    }                                                                            \
}

#endif
