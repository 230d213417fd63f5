#version 450
// The Julia layer's whole formula written the plain way, one pixel an invocation: the rect grid's
// start and its derivative, the allpass warp, the orbit with its derivative to the bailout and on to
// the big radius, the smooth count, the distance estimate and the palette colour, each from
// kernels/julia.h and kernels/palette.h called directly, all seven planes stored. The minimal
// shader the layer with every channel is measured against in `fractalbake bench`
// (host/gen/julia/bench.c); without the layer's generality (turbulence, other mappings, samples,
// two pixels an invocation, channels left out). Its values are the layer's to the bit for a rect
// scene with one sample and no turbulence (the bench's): the bench checks it.
#extension GL_GOOGLE_include_directive : require
#define K_GLSL 1
#include "../../kernels/julia.h"
#include "../../kernels/palette.h"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

layout(push_constant) uniform Push
{
    K_JuliaParams p;
    uint y0, rows;
}
pc;

layout(std430, set = 0, binding = 0) writeonly buffer Iter { uint v[]; } o_iter;
layout(std430, set = 0, binding = 1) writeonly buffer Smooth { float v[]; } o_n;
layout(std430, set = 0, binding = 2) writeonly buffer Inside { float v[]; } o_inside;
layout(std430, set = 0, binding = 3) writeonly buffer De { float v[]; } o_de;
layout(std430, set = 0, binding = 4) writeonly buffer Red { float v[]; } o_r;
layout(std430, set = 0, binding = 5) writeonly buffer Green { float v[]; } o_g;
layout(std430, set = 0, binding = 6) writeonly buffer Blue { float v[]; } o_b;
// the layer's palette block (shaders/julia_body.glsl)
layout(std140, set = 0, binding = 7) uniform Palette
{
    K_SkyColour colour;
    K_FbmParams turb;
    vec4 entries[K_PALETTE_SIZE];
}
pal;

void main()
{
    uint x = gl_GlobalInvocationID.x, r = gl_GlobalInvocationID.y;
    if (x >= pc.p.width || r >= pc.rows) return;
    K_JuliaParams p = pc.p;
    p.mapping = K_JULIA_RECT;
    float u = (float(x) + 0.5) * p.inv_width, v = 1.0 - (float(pc.y0 + r) + 0.5) * p.inv_height;
    vec2 s = k_julia_start(p, u, v), d = k_julia_dstart(p, u, v);
    K_JuliaResult res = k_julia_run(p, k_julia_begin(p, s.x, s.y, d.x, d.y, 0.0, 0.0), K_JULIA_WANT_ALL);
    uint i0 = k_sky_i0(pal.colour, res.nsmooth);
    vec3 c = k_sky_rgb(pal.colour, res.inside, res.nsmooth, pal.entries[i0], pal.entries[k_sky_i1(i0)]);
    uint i = r * p.width + x;
    o_iter.v[i] = res.iter;
    o_n.v[i] = res.nsmooth;
    o_inside.v[i] = float(res.inside);
    o_de.v[i] = res.de;
    o_r.v[i] = c.r;
    o_g.v[i] = c.g;
    o_b.v[i] = c.b;
}
