// Order-independent sums. Float atomics add in whatever order the device schedules them, so
// two runs round differently and an optimisation amplifies the difference. Here a value is
// rounded to 64-bit fixed point and added with a 64-bit integer atomic; integer addition is
// associative, so a sum has the same bits whatever the order.
// Two precisions (engine/gpu/fixed_sum.rs `FixedPrecision`): gradients, which the next kernel
// reads, in steps of 2^-40 (≈ 9.1e-13) within ±2^23; loss totals, which the host reads, in
// steps of 2^-24 (≈ 6e-8) within ±2^39. A buffer of n sums holds 2n int64_t: the values, then
// per sum the count of contributions it dropped (NaN, infinite, beyond the range, or, for loss
// totals, an add that overflowed the total); the values stay dense, the counts rarely touched. Readers
// report a sum that dropped any as NaN.
#ifndef COMMON_FIXED_SUM_GLSL
#define COMMON_FIXED_SUM_GLSL

#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require

const float FIXED_GRADIENT_ONE = 1099511627776.0;        // 2^40
const float FIXED_TOTAL_ONE = 16777216.0;                // 2^24
const float FIXED_SCALED_LIMIT = 4611686018427387904.0;  // 2^62: one scaled contribution

// Adds `value` to sum `i` of the int64_t array `sums` in steps of 1 / `one` (a macro: GLSL
// cannot pass a buffer). Scaling by a power of two is exact; phrased as positive so that NaN
// lands in the dropped count. With `checked`, an add that overflows the total (the addends
// agree in sign and the result does not) is counted too; that needs the atomic's old value,
// which costs lavapipe 13 % of the mesh backward, so gradient sums, whose range no converging
// run approaches, go unchecked and loss totals, one add per subgroup, are checked.
#define FIXED_ADD(sums, i, value, one, checked) {                                   \
    float scaled_ = (value) * (one);                                                 \
    uint at_ = (i);                                                                  \
    uint dropped_at_ = uint(sums.length()) / 2u + at_;                               \
    if (!(abs(scaled_) <= FIXED_SCALED_LIMIT)) {                                     \
        atomicAdd(sums[dropped_at_], int64_t(1));                                    \
    } else if (scaled_ != 0.0) {                                                     \
        int64_t add_ = int64_t(roundEven(scaled_));                                  \
        if (checked) {                                                               \
            int64_t before_ = atomicAdd(sums[at_], add_);                            \
            int64_t after_ = before_ + add_;                                         \
            if (((before_ ^ after_) & (add_ ^ after_)) < int64_t(0)) {               \
                atomicAdd(sums[dropped_at_], int64_t(1));                            \
            }                                                                        \
        } else {                                                                     \
            atomicAdd(sums[at_], add_);                                              \
        }                                                                            \
    }                                                                                \
}
#define FIXED_ADD_GRADIENT(sums, i, value) FIXED_ADD(sums, i, value, FIXED_GRADIENT_ONE, false)
#define FIXED_ADD_TOTAL(sums, i, value) FIXED_ADD(sums, i, value, FIXED_TOTAL_ONE, true)

#endif
