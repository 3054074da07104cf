// The silhouette blend (the idea of nvdiffrast's antialias), shared by the kernels that find
// crossings (aa_pairs.comp), apply them (aa_forward.comp) and differentiate them
// (aa_backward.comp). For two neighbouring pixel centres a and b with different triangle ids,
// the outline edge of the nearer triangle that crosses the segment at fraction t from a (the
// covered side) blends the pair:
//   t >= 1/2: out_b += (t - 1/2) (c_a - c_b)      t < 1/2: out_a += (1/2 - t) (c_b - c_a)
// so the output moves continuously as the edge sweeps over pixel centres.
#ifndef RASTER_BLEND_GLSL
#define RASTER_BLEND_GLSL

struct Crossing {
    bool found;
    uint triangle;
    uint edge;       // edge k runs from corner k to corner k + 1
    ivec2 covered;   // pixel a, inside the triangle
    ivec2 other;     // pixel b
    float t;         // where the edge crosses, from a (0) to b (1)
};

// A stored crossing (aa_pairs.comp writes one per pixel and direction, right then down).
struct PairRecord {
    float t;
    uint triangle;
    uint bits;     // 1: found, 2: the covered pixel is the second (right/down) one, edge << 2
    uint unused;
};

PairRecord pack_crossing(Crossing c, ivec2 first) {
    if (!c.found) {
        return PairRecord(0.0, 0u, 0u, 0u);
    }
    uint second_covered = c.covered == first ? 0u : 2u;
    return PairRecord(c.t, c.triangle, 1u | second_covered | (c.edge << 2), 0u);
}

Crossing unpack_crossing(PairRecord r, ivec2 first, ivec2 second) {
    bool second_covered = (r.bits & 2u) != 0u;
    ivec2 covered = second_covered ? second : first, other = second_covered ? first : second;
    return Crossing((r.bits & 1u) != 0u, r.triangle, r.bits >> 2, covered, other, r.t);
}

// The pixel a crossing blends into and its weight (see the top of this file).
ivec2 blend_target(Crossing c, out float w) {
    w = abs(c.t - 0.5);
    return c.t >= 0.5 ? c.other : c.covered;
}

bool in_image(ivec2 p) {
    return p.x >= 0 && p.y >= 0 && p.x < int(image_width()) && p.y < int(image_height());
}

#endif
