// vec4 buffers declared as u64vec2 and moved as two 64-bit words. llvmpipe loads and stores a
// storage buffer one component per lane at a time (a bounds-checked scalar access each), so a
// u64vec2 costs half the operations of the same 16 bytes as a vec4: the loss's horizontal
// adjoint pass went from 1.19 to 0.94 ms. A GPU moves either as one 16-byte access. The
// layout is a vec4's (std430, 16-byte aligned, x in the low word of the first element).
#ifndef COMMON_WIDE_VEC4_GLSL
#define COMMON_WIDE_VEC4_GLSL

#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

vec4 unpack_vec4(u64vec2 words) {
    return vec4(uintBitsToFloat(unpackUint2x32(words.x)), uintBitsToFloat(unpackUint2x32(words.y)));
}

u64vec2 pack_vec4(vec4 v) {
    return u64vec2(packUint2x32(floatBitsToUint(v.xy)), packUint2x32(floatBitsToUint(v.zw)));
}

#endif
