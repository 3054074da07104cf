// Finding the crossing of a pixel pair (the rule is in blend.glsl). Expects buffers `ids`,
// `depth`, `faces`, `camera_positions`, `outline_flags` (outline.comp) and the include of
// triangle.glsl.
#ifndef RASTER_AA_GLSL
#define RASTER_AA_GLSL

#include "blend.glsl"

// The first outline edge of triangle t leaving pixel a towards pixel b, if any. Triangles
// with a corner behind the near plane are skipped (their edges do not project to lines).
Crossing crossing_from(uint t, ivec2 a, ivec2 b) {
    Crossing c = Crossing(false, t, 0u, a, b, 2.0);
    uint flags = outline_flags[t];
    if ((flags & FLAG_IN_FRONT) == 0u || (flags & 7u) == 0u) {
        return c;
    }
    uvec3 v;
    vec3 p[3];
    triangle_corners(t, v, p[0], p[1], p[2]);
    vec2 s[3] = vec2[3](project_point(p[0]), project_point(p[1]), project_point(p[2]));
    float orientation = sign(screen_edge(s[0], s[1], s[2]));
    for (uint k = 0u; k < 3u; k++) {
        vec2 e0 = s[k], e1 = s[(k + 1u) % 3u];
        float ea = orientation * screen_edge(e0, e1, pixel_centre(a));
        float eb = orientation * screen_edge(e0, e1, pixel_centre(b));
        if (ea >= 0.0 && eb < 0.0 && (flags & (1u << k)) != 0u) {
            float t_cross = ea / (ea - eb);
            if (t_cross < c.t) {
                c.found = true;
                c.edge = k;
                c.t = t_cross;
            }
        }
    }
    return c;
}

// Whether triangle t can produce a crossing at all: drawn, in front, with an outline edge.
bool has_outline(uint t) {
    uint flags = t == NO_TRIANGLE ? 0u : outline_flags[t];
    return (flags & FLAG_IN_FRONT) != 0u && (flags & 7u) != 0u;
}

float depth_or_far(ivec2 p, uint t) {
    return t == NO_TRIANGLE ? 1.0 / 0.0 : depth[pixel_index(p)];
}

// The crossing between neighbours p0 and p1 (p1 right of or below p0: each pair has one
// answer whichever pixel asks). The nearer pixel's triangle is tried first.
Crossing pair_crossing(ivec2 p0, ivec2 p1) {
    uint t0 = ids[pixel_index(p0)], t1 = ids[pixel_index(p1)];
    Crossing none = Crossing(false, 0u, 0u, p0, p1, 0.0);
    if (t0 == t1 || !(has_outline(t0) || has_outline(t1))) {
        return none;
    }
    bool first0 = depth_or_far(p0, t0) <= depth_or_far(p1, t1);
    ivec2 near_p = first0 ? p0 : p1, far_p = first0 ? p1 : p0;
    uint near_t = first0 ? t0 : t1, far_t = first0 ? t1 : t0;
    if (near_t != NO_TRIANGLE) {
        Crossing c = crossing_from(near_t, near_p, far_p);
        if (c.found) {
            return c;
        }
    }
    if (far_t != NO_TRIANGLE) {
        return crossing_from(far_t, far_p, near_p);
    }
    return none;
}

#endif
