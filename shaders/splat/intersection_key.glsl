// The 32-bit key of a (tile, Gaussian) intersection: the tile in the high bits, the Gaussian's
// depth in the low bits as its place within the frame's depth range, so one 4-pass radix sort
// orders by tile, then front to back (as VkSplat packs them; a 64-bit tile | depth key took
// 6 passes of 12-byte records at 1080²).
//
// The tile field holds 0..tile_count: the all-ones key of an unfilled slot then names tile
// 2^tile_bits - 1 >= tile_count, no tile, and sorts last. The depth field is the depth's float
// bits (positive floats order like their bits) less the nearest visible depth's, shifted right
// until the frame's span fits: at 1920 x 1080 (8160 tiles, 19 depth bits) two depths tie only
// when they are within 2^-18 of the span apart. Ties keep the emission order (Gaussian index),
// the sort being stable.
#ifndef SPLAT_INTERSECTION_KEY_GLSL
#define SPLAT_INTERSECTION_KEY_GLSL

uint key_tile_bits(uint tile_count) {
    return uint(findMSB(tile_count)) + 1u;
}

uint key_depth_bits(uint tile_count) {
    return 32u - key_tile_bits(tile_count);
}

// `range`: the visible splats' smallest depth bits and the complement of the largest
// (project.comp's atomic minima).
uint intersection_key(uint tile, float depth, uvec2 range, uint tile_count) {
    uint depth_bits = key_depth_bits(tile_count);
    uint span = ~range.y - range.x;
    int shift = max(findMSB(span) + 1 - int(depth_bits), 0);
    return (tile << depth_bits) | ((floatBitsToUint(depth) - range.x) >> uint(shift));
}

uint key_tile(uint key, uint tile_count) {
    return key >> key_depth_bits(tile_count);
}

#endif
