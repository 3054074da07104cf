#version 460
// Test oracle only (tests/raster/oracle.rs): the fixed-function rasterizer draws the mesh
// with triangles expanded to three vertices each, so triangle t is vertices 3t..3t+2.
layout(location = 0) in vec4 clip_position;
layout(location = 0) flat out float triangle_id;

void main() {
    gl_Position = clip_position;
    triangle_id = float(uint(gl_VertexIndex) / 3u);
}
