// Shared by the camera colour-map kernels. Mirrors engine/loss/colour_map/mod.rs
// (ColourMapParams).
//
// A camera's own exposure and white balance, as an affine map of the subject's premultiplied
// colour p: the camera sees  A p + b α + (1 − α) background,  where a render over the
// background is c = p + (1 − α) background. Scaling b by α keeps the background as it is, so
// the map changes only what the subject covers. A camera's map is three vec4 rows, row k being
// (A_k0, A_k1, A_k2, b_k).
#ifndef LOSS_COLOUR_MAP_GLSL
#define LOSS_COLOUR_MAP_GLSL

#include "../common/wide_vec4.glsl"

layout(push_constant, std430) uniform ColourMapParams {
    vec4 background;   // rgb, unused
    uvec4 size;        // pixels, camera, add the fit's moments (forward only), unused
} params;

uint pixel_count() { return params.size.x; }
uint camera() { return params.size.y; }

// The subject's premultiplied colour and coverage of a render over the background.
vec4 subject_of(vec4 c) {
    return vec4(c.rgb - (1.0 - c.a) * params.background.rgb, c.a);
}

#endif
