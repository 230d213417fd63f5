#version 450
// The Julia layer's escape loop as a GPU programmer writes it first, one pixel an invocation: the
// rect grid's starting point, z <- z^2 + c until |z|^2 reaches the bailout or max-iter steps, the
// count stored. The minimal shader a layer storing only `iter` is measured against in `fractalbake
// bench` (host/gen/julia/bench.c). Without the layer's generality (no allpass warp, turbulence,
// other mappings, samples or second pixel per invocation); for the bench's scene (alpha 0, rect)
// its counts are the layer's to the bit: the bench checks it.
#extension GL_GOOGLE_include_directive : require
#define K_GLSL 1
#include "../../kernels/julia.h"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

layout(push_constant) uniform Push
{
    K_JuliaParams p;
    uint y0, rows;
}
pc;

layout(std430, set = 0, binding = 0) writeonly buffer Iter
{
    uint v[];
}
o_iter;

void main()
{
    uint x = gl_GlobalInvocationID.x, r = gl_GlobalInvocationID.y;
    if (x >= pc.p.width || r >= pc.rows) return;
    float u = (float(x) + 0.5) * pc.p.inv_width, v = 1.0 - (float(pc.y0 + r) + 0.5) * pc.p.inv_height;
    float gx = pc.p.scale_u * (u - 0.5), gy = pc.p.scale_v * (v - 0.5);
    float zr = pc.p.center_re + (pc.p.rot_c * gx - pc.p.rot_s * gy);
    float zi = pc.p.center_im + (pc.p.rot_s * gx + pc.p.rot_c * gy);
    uint n = 0u;
    for (; n < pc.p.max_iter; n++) {
        if (zr * zr + zi * zi >= pc.p.bailout2) break;
        float t = zr * zr - zi * zi + pc.p.c_re;
        zi = 2.0 * zr * zi + pc.p.c_im;
        zr = t;
    }
    o_iter.v[r * pc.p.width + x] = n;
}
