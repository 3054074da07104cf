#version 460
// Test oracle only: writes the triangle id (a flat varying, so no geometry-shader feature is
// needed for gl_PrimitiveID) into an R32_SFLOAT attachment (exact below 2^24; see
// tests/raster/oracle.rs for why not R32_UINT).
layout(location = 0) flat in float triangle_id;
layout(location = 0) out float id_out;

void main() {
    id_out = triangle_id;
}
