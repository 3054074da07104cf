#version 460
// Gathers rows of an old array into a new one through a remap (the new row's old index, or
// 0xFFFFFFFF for a new row, which starts at zero). Used on optimizer moments after the
// Gaussian set changes.
layout(local_size_x_id = 0) in;

layout(push_constant, std430) uniform RemapParams {
    uint new_rows;
    uint old_rows;
    uint row_width;   // vec2 elements per row
    uint unused;
} params;

layout(std430, binding = 0) readonly buffer OldRows { vec2 old_rows[]; };
layout(std430, binding = 1) readonly buffer OldOfNew { uint old_of_new[]; };
layout(std430, binding = 2) writeonly buffer NewRows { vec2 new_rows[]; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint row = i / params.row_width;
    if (row >= params.new_rows) return;
    uint old = old_of_new[row];
    // Phrased as "inside" so a bad index reads nothing rather than out of bounds.
    bool kept = old < params.old_rows;
    new_rows[i] = kept ? old_rows[old * params.row_width + i % params.row_width] : vec2(0.0);
}
