#version 460
// Test oracle only: writes the triangle id (a flat varying, so no geometry-shader feature is
// needed for gl_PrimitiveID) into an R32_UINT attachment.
layout(location = 0) flat in uint triangle_id;
layout(location = 0) out uint id_out;

void main() {
    id_out = triangle_id;
}
