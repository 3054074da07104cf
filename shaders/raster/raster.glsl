// Shared by every mesh-raster kernel. Mirrors engine/raster/params.rs (RasterParams, SubTriangle).
#ifndef RASTER_RASTER_GLSL
#define RASTER_RASTER_GLSL

#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

const uint TILE_SIZE = 16u;
// Screen positions are snapped to 1/256 pixel so edge functions are exact 64-bit integers:
// two triangles sharing an edge evaluate it to exactly opposite values (no cracks, no overlap).
const int SUBPIXEL = 256;
// A triangle whose clamped bounding box holds at most this many pixels is rasterized by one
// thread; a larger one goes to the per-tile kernel.
const uint SMALL_TRIANGLE_PIXELS = 256u;
// Large sub-triangles listed per tile; a tile that gets more falls back to the whole list.
const uint TILE_LIST_CAPACITY = 256u;
// Sub-pixel coordinates must stay below 2^30 so edge products fit in 63 bits.
const float GUARD_BAND_PIXELS = 4194304.0;
const uint NO_TRIANGLE = 0xffffffffu;
const uint64_t EMPTY_PIXEL = 0xffffffffffffffffUL;
// Bit 3 of a triangle's outline flags (outline.comp): all corners in front of the near plane.
const uint FLAG_IN_FRONT = 8u;
// Bits of RasterParams.counts.z.
const uint FLAG_COUNT_WRITES = 1u;

// One camera and the mesh sizes, 112 bytes of push constants.
layout(push_constant, std430) uniform RasterParams {
    vec4 view_rows[3];   // world_to_camera rows: rotation | translation
    vec4 intrinsics;     // fx, fy, cx, cy
    vec4 clip;           // near, unused x3
    uvec4 size;          // width, height, tiles_x, tiles_y
    uvec4 counts;        // vertices, triangles, flags, unused
} params;

uint vertex_count() { return params.counts.x; }
uint triangle_count() { return params.counts.y; }
uint image_width() { return params.size.x; }
uint image_height() { return params.size.y; }
float near_plane() { return params.clip.x; }

mat3 view_rotation() {
    // GLSL matrices are column-major: build from rows, then transpose.
    return transpose(mat3(params.view_rows[0].xyz, params.view_rows[1].xyz, params.view_rows[2].xyz));
}

vec3 view_translation() {
    return vec3(params.view_rows[0].w, params.view_rows[1].w, params.view_rows[2].w);
}

// Pixel coordinates of a camera-space point in front of the camera.
vec2 project_point(vec3 c) {
    return params.intrinsics.xy * c.xy / c.z + params.intrinsics.zw;
}

// The camera ray through pixel centre `pixel`, scaled so its z is 1.
vec3 pixel_ray(uvec2 pixel) {
    return vec3((vec2(pixel) + 0.5 - params.intrinsics.zw) / params.intrinsics.xy, 1.0);
}

// A screen triangle after near clipping, counter-clockwise in sub-pixel units (positive
// edge functions inside). A clipped triangle yields up to two; unused slots have id NO_TRIANGLE.
struct SubTriangle {
    ivec4 xy01;      // x0, y0, x1, y1 (1/256 pixel)
    ivec4 xy2_id;    // x2, y2, triangle id, unused
    vec4 inv_depth;  // 1/z at the three corners, unused
};

// Pixels [x0, x1] x [y0, y1] (inclusive) whose centres may lie in the triangle, clamped to
// the image; empty when x0 > x1 or y0 > y1.
ivec4 pixel_bounds(SubTriangle t) {
    ivec2 lo = min(min(t.xy01.xy, t.xy01.zw), t.xy2_id.xy);
    ivec2 hi = max(max(t.xy01.xy, t.xy01.zw), t.xy2_id.xy);
    // Centre of pixel i is 256 i + 128: the first centre >= lo, the last <= hi.
    ivec2 first = (lo - SUBPIXEL / 2 + SUBPIXEL - 1) >> 8;
    ivec2 last = (hi - SUBPIXEL / 2) >> 8;
    ivec2 size = ivec2(image_width(), image_height());
    return ivec4(max(first, ivec2(0)), min(last, size - 1));
}

// Twice the signed area, in sub-pixel units squared, of (a, b, p).
int64_t edge_function(ivec2 a, ivec2 b, ivec2 p) {
    return int64_t(b.x - a.x) * int64_t(p.y - a.y) - int64_t(b.y - a.y) * int64_t(p.x - a.x);
}

// Top-left rule (y down): a sample exactly on an edge belongs to the triangle if the edge is a
// left edge (going up) or a top edge (horizontal, going right).
bool owns_edge(ivec2 a, ivec2 b) {
    return b.y < a.y || (b.y == a.y && b.x > a.x);
}

bool edge_covers(int64_t e, ivec2 a, ivec2 b) {
    return e > 0L || (e == 0L && owns_edge(a, b));
}

// Visibility key of `t` at `pixel`, or EMPTY_PIXEL if the pixel centre is not covered.
uint64_t coverage_key(SubTriangle t, ivec2 pixel) {
    ivec2 p = pixel * SUBPIXEL + SUBPIXEL / 2;
    ivec2 v0 = t.xy01.xy, v1 = t.xy01.zw, v2 = t.xy2_id.xy;
    int64_t e0 = edge_function(v1, v2, p);  // weight of v0
    int64_t e1 = edge_function(v2, v0, p);  // weight of v1
    int64_t e2 = edge_function(v0, v1, p);  // weight of v2
    if (!edge_covers(e0, v1, v2) || !edge_covers(e1, v2, v0) || !edge_covers(e2, v0, v1)) {
        return EMPTY_PIXEL;
    }
    // 1/z is affine in screen space.
    float area = float(e0 + e1 + e2);
    float inv_z = (float(e0) * t.inv_depth.x + float(e1) * t.inv_depth.y + float(e2) * t.inv_depth.z) / area;
    float depth = 1.0 / inv_z;
    // Positive floats order like their bits.
    return (uint64_t(floatBitsToUint(depth)) << 32) | uint64_t(uint(t.xy2_id.z));
}

// Twice the signed area of (a, b, p) in float pixels (the anti-aliasing's edge function).
float screen_edge(vec2 a, vec2 b, vec2 p) {
    return (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
}

vec2 pixel_centre(ivec2 p) {
    return vec2(p) + 0.5;
}

uint pixel_index(ivec2 pixel) {
    return uint(pixel.y) * image_width() + uint(pixel.x);
}

#endif
