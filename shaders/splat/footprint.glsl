// Which tiles a projected Gaussian reaches: the ellipse sigma(u) <= extent, sigma(u) =
// 0.5 (u - m)^T Q (u - m), tested against the pixel centres of each tile (project.comp counts,
// emit_intersections.comp writes, both through these functions so they always agree).
#ifndef SPLAT_FOOTPRINT_GLSL
#define SPLAT_FOOTPRINT_GLSL

#include "frame.glsl"

// A hair of slack so f32 rounding never drops a tile the f64 maths would keep: an extra tile
// costs a skipped Gaussian, a missing one a wrong pixel.
const float EXTENT_SLACK = 1e-5;

float sigma_at(vec3 conic, vec2 d) {
    return 0.5 * (conic.x * d.x * d.x + conic.z * d.y * d.y) + conic.y * d.x * d.y;
}

// Tiles [x0, x1) x [y0, y1) of the pixels whose centres lie in the ellipse's bounding box.
uvec4 tile_rect(Splat s, vec2 half_extent) {
    vec2 size = vec2(frame.size.xy);
    // First and last pixel whose centre (i + 0.5) is inside; clamped as floats before the
    // conversion so huge means cannot overflow it.
    vec2 first = clamp(ceil(s.mean - half_extent - 0.5), vec2(0.0), size);
    vec2 last = clamp(floor(s.mean + half_extent - 0.5), vec2(-1.0), size - 1.0);
    if (any(greaterThan(first, last))) {
        return uvec4(0u);
    }
    uvec2 lo = uvec2(first) / TILE_SIZE;
    uvec2 hi = uvec2(last) / TILE_SIZE + 1u;
    return uvec4(lo.x, hi.x, lo.y, hi.y);
}

// Whether the minimum of sigma over the tile's pixel-centre rectangle is within the extent.
bool touches_tile(Splat s, uvec2 tile) {
    vec2 lo = vec2(tile * TILE_SIZE) + 0.5 - s.mean;
    vec2 hi = vec2(min((tile + 1u) * TILE_SIZE, frame.size.xy)) - 0.5 - s.mean;
    if (all(lessThanEqual(lo, vec2(0.0))) && all(greaterThanEqual(hi, vec2(0.0)))) {
        return true;
    }
    vec3 q = s.conic;
    float best = 1.0 / 0.0;
    // Edges x = const: sigma is a convex parabola in y, minimised at y = -Q01 x / Q11.
    for (uint e = 0u; e < 2u; e++) {
        float x = e == 0u ? lo.x : hi.x;
        best = min(best, sigma_at(q, vec2(x, clamp(-q.y * x / q.z, lo.y, hi.y))));
        float y = e == 0u ? lo.y : hi.y;
        best = min(best, sigma_at(q, vec2(clamp(-q.y * y / q.x, lo.x, hi.x), y)));
    }
    return best <= s.extent * (1.0 + EXTENT_SLACK) + EXTENT_SLACK;
}

#endif
