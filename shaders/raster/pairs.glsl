// The four stored pairs around a pixel, for the blend and its backward. Expects a `pairs`
// buffer of PairRecord (blend.glsl).
#ifndef RASTER_PAIRS_GLSL
#define RASTER_PAIRS_GLSL

// Pair k of p (0 right, 1 down, 2 left, 3 up): the neighbour q and the crossing, if any.
bool pair_around(ivec2 p, uint k, out ivec2 q, out Crossing c) {
    const ivec2 steps[4] = ivec2[4](ivec2(1, 0), ivec2(0, 1), ivec2(-1, 0), ivec2(0, -1));
    q = p + steps[k];
    if (!in_image(q)) {
        return false;
    }
    // The record lives at the left/upper pixel of the pair, slot 0 horizontal, 1 vertical.
    ivec2 first = k < 2u ? p : q;
    ivec2 second = k < 2u ? q : p;
    c = unpack_crossing(pairs[2u * pixel_index(first) + (k & 1u)], first, second);
    return c.found;
}

#endif
