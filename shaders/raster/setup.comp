#version 460
// Triangle setup and small-triangle raster: one invocation per triangle. Clips against the
// near plane (up to two sub-triangles), snaps to 1/256 pixel, orients counter-clockwise,
// stores the sub-triangles, rasterizes small ones here into the visibility buffer, and bins
// large ones: appended to the list of every tile their bounds touch (and to the list of all
// large ones, which a tile whose list overflowed walks instead).
#extension GL_EXT_shader_atomic_int64 : require
#include "raster.glsl"
#include "../common/grid.glsl"

layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer Faces { uint faces[]; };
layout(std430, binding = 1) readonly buffer CameraPositions { vec4 camera_positions[]; };
layout(std430, binding = 2) writeonly buffer SubTriangles { SubTriangle subs[]; };
layout(std430, binding = 3) buffer Visibility { uint64_t visibility[]; };
layout(std430, binding = 4) writeonly buffer LargeList { uint large_list[]; };
// [0] large sub-triangles, [1] sub-triangles dropped outside the guard band.
layout(std430, binding = 5) buffer Counters { uint counters[]; };
layout(std430, binding = 6) buffer WriteCounts { uint write_counts[]; };
layout(std430, binding = 7) buffer TileCounts { uint tile_counts[]; };
layout(std430, binding = 8) writeonly buffer TileLists { uint tile_lists[]; };

// Where edge (a, b) meets the near plane, always interpolated from the lower vertex index so
// the two triangles sharing the edge get the same bits.
vec3 near_crossing(vec3 pa, uint ia, vec3 pb, uint ib) {
    if (ib < ia) {
        vec3 swap = pa; pa = pb; pb = swap;
    }
    float s = (near_plane() - pa.z) / (pb.z - pa.z);
    return vec3(mix(pa.xy, pb.xy, s), near_plane());
}

bool snap(vec3 c, out ivec2 fixed_point) {
    vec2 s = project_point(c);
    vec2 centre = 0.5 * vec2(image_width(), image_height());
    if (any(greaterThan(abs(s - centre), vec2(GUARD_BAND_PIXELS)))) {
        return false;
    }
    fixed_point = ivec2(round(s * float(SUBPIXEL)));
    return true;
}

SubTriangle empty_sub() {
    return SubTriangle(ivec4(0), ivec4(0, 0, int(NO_TRIANGLE), 0), vec4(0.0));
}

// The sub-triangle (a, b, c) of triangle `id`, or an empty one when it has zero area or
// leaves the guard band.
SubTriangle make_sub(vec3 a, vec3 b, vec3 c, uint id) {
    ivec2 s0, s1, s2;
    if (!snap(a, s0) || !snap(b, s1) || !snap(c, s2)) {
        atomicAdd(counters[1], 1u);
        return empty_sub();
    }
    int64_t area = edge_function(s0, s1, s2);
    if (area == 0L) {
        return empty_sub();
    }
    vec3 inv_depth = 1.0 / vec3(a.z, b.z, c.z);
    if (area < 0L) {
        return SubTriangle(ivec4(s0, s2), ivec4(s1, int(id), 0), vec4(inv_depth.xzy, 0.0));
    }
    return SubTriangle(ivec4(s0, s1), ivec4(s2, int(id), 0), vec4(inv_depth, 0.0));
}

void rasterize_small(SubTriangle t, ivec4 bounds) {
    bool count = (params.counts.z & FLAG_COUNT_WRITES) != 0u;
    for (int y = bounds.y; y <= bounds.w; y++) {
        for (int x = bounds.x; x <= bounds.z; x++) {
            uint64_t key = coverage_key(t, ivec2(x, y));
            if (key != EMPTY_PIXEL) {
                uint i = pixel_index(ivec2(x, y));
                atomicMin(visibility[i], key);
                if (count) {
                    atomicAdd(write_counts[i], 1u);
                }
            }
        }
    }
}

// Appends `slot` to the list of every tile that pixel bounds b touch (one thread walks tiles,
// 256 times fewer than pixels).
void bin_by_tile(uint slot, ivec4 b) {
    uvec4 tiles = uvec4(b) / TILE_SIZE;
    for (uint ty = tiles.y; ty <= tiles.w; ty++) {
        for (uint tx = tiles.x; tx <= tiles.z; tx++) {
            uint tile = ty * params.size.z + tx;
            uint at = atomicAdd(tile_counts[tile], 1u);
            if (at < TILE_LIST_CAPACITY) {
                tile_lists[tile * TILE_LIST_CAPACITY + at] = slot;
            }
        }
    }
}

void emit(uint slot, SubTriangle t) {
    subs[slot] = t;
    if (uint(t.xy2_id.z) == NO_TRIANGLE) {
        return;
    }
    ivec4 b = pixel_bounds(t);
    if (b.x > b.z || b.y > b.w) {
        return;
    }
    uint pixels = uint(b.z - b.x + 1) * uint(b.w - b.y + 1);
    if (pixels <= SMALL_TRIANGLE_PIXELS) {
        rasterize_small(t, b);
    } else {
        large_list[atomicAdd(counters[0], 1u)] = slot;
        bin_by_tile(slot, b);
    }
}

void main() {
    uint t = flat_workgroup_id() * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
    if (t >= triangle_count()) {
        return;
    }
    uint ids[3] = uint[3](faces[3u * t], faces[3u * t + 1u], faces[3u * t + 2u]);
    vec3 p[3];
    uint in_front = 0u;
    bool finite = true;
    for (int k = 0; k < 3; k++) {
        p[k] = camera_positions[ids[k]].xyz;
        finite = finite && !any(isnan(p[k])) && !any(isinf(p[k]));
        in_front += p[k].z >= near_plane() ? 1u : 0u;
    }
    if (!finite || in_front == 0u) {
        emit(2u * t, empty_sub());
        emit(2u * t + 1u, empty_sub());
        return;
    }
    // Sutherland-Hodgman against z >= near: 3 or 4 corners.
    vec3 poly[4];
    uint n = 0u;
    for (int k = 0; k < 3; k++) {
        int j = (k + 1) % 3;
        bool kin = p[k].z >= near_plane();
        bool jin = p[j].z >= near_plane();
        if (kin) {
            poly[n++] = p[k];
        }
        if (kin != jin) {
            poly[n++] = near_crossing(p[k], ids[k], p[j], ids[j]);
        }
    }
    emit(2u * t, make_sub(poly[0], poly[1], poly[2], t));
    emit(2u * t + 1u, n == 4u ? make_sub(poly[0], poly[2], poly[3], t) : empty_sub());
}
