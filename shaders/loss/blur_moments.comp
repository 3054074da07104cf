#version 460
// SSIM forward, pass 1 of 2: the horizontal Gaussian filter of the five moments
// x, y, x², y², xy of every channel, at the columns where a whole window fits.
#include "loss.glsl"
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer Render { vec4 render[]; };
layout(std430, binding = 1) readonly buffer Target { vec4 target[]; };
layout(std430, binding = 2) writeonly buffer MeanX { vec4 mean_x[]; };
layout(std430, binding = 3) writeonly buffer MeanY { vec4 mean_y[]; };
layout(std430, binding = 4) writeonly buffer MeanXX { vec4 mean_xx[]; };
layout(std430, binding = 5) writeonly buffer MeanYY { vec4 mean_yy[]; };
layout(std430, binding = 6) writeonly buffer MeanXY { vec4 mean_xy[]; };

void main() {
    uint p = gl_GlobalInvocationID.x;
    if (p >= pixel_count()) return;
    uint x = p % width();
    if (x < uint(RADIUS) || x + uint(RADIUS) >= width()) return;
    vec4 mx = vec4(0.0), my = vec4(0.0), mxx = vec4(0.0), myy = vec4(0.0), mxy = vec4(0.0);
    for (int k = -RADIUS; k <= RADIUS; k++) {
        float w = params.window[k + RADIUS];
        vec4 a = render[p + k];
        vec4 b = target[p + k];
        mx += w * a;
        my += w * b;
        mxx += w * a * a;
        myy += w * b * b;
        mxy += w * a * b;
    }
    mean_x[p] = mx;
    mean_y[p] = my;
    mean_xx[p] = mxx;
    mean_yy[p] = myy;
    mean_xy[p] = mxy;
}
