#version 450
// Warped Julia sets: one invocation per pixel of a strip. The math is kernels/julia.h.
#extension GL_GOOGLE_include_directive : require
#define K_GLSL 1
#include "../kernels/julia.h"
#include "../kernels/palette.h"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

// The mapping, fixed per pipeline so that the compiler folds the other one away.
layout(constant_id = 0) const uint MAPPING = 0u;

layout(push_constant) uniform Push
{
    K_JuliaParams p;
    uint y0;   // first image row of this strip
    uint rows; // rows in this strip
}
pc;

layout(std430, set = 0, binding = 0) writeonly buffer Iter { uint v[]; } o_iter;
layout(std430, set = 0, binding = 1) writeonly buffer Smooth { float v[]; } o_n;
layout(std430, set = 0, binding = 2) writeonly buffer Inside { float v[]; } o_inside;
layout(std430, set = 0, binding = 3) writeonly buffer De { float v[]; } o_de;
layout(std430, set = 0, binding = 4) writeonly buffer Red { float v[]; } o_r;
layout(std430, set = 0, binding = 5) writeonly buffer Green { float v[]; } o_g;
layout(std430, set = 0, binding = 6) writeonly buffer Blue { float v[]; } o_b;
layout(std430, set = 0, binding = 7) readonly buffer Palette
{
    K_SkyColour colour;
    K_FbmParams turb;
    float pad0, pad1, pad2;
    vec4 entries[K_PALETTE_SIZE];
}
pal;

void main()
{
    uint x = gl_GlobalInvocationID.x;
    uint r = gl_GlobalInvocationID.y;
    if (x >= pc.p.width || r >= pc.rows) return;
    K_JuliaParams p = pc.p;
    p.mapping = MAPPING;
    K_JuliaResult res = k_julia_pixel(p, pal.turb, x, pc.y0 + r);
    uint i = r * p.width + x;
    o_iter.v[i] = res.iter;
    o_n.v[i] = res.nsmooth;
    o_inside.v[i] = float(res.inside);
    o_de.v[i] = res.de;
    K_SkyColour c = pal.colour;
    if (res.inside != 0u) {
        o_r.v[i] = c.inside_r;
        o_g.v[i] = c.inside_g;
        o_b.v[i] = c.inside_b;
        return;
    }
    // the same table lookup as host/gen/julia.c
    float pos = k_palette_pos(c, res.nsmooth);
    uint i0 = uint(pos), i1 = min(i0 + 1u, K_PALETTE_SIZE - 1u);
    float f = pos - float(i0), w = k_sky_weight(c, res.nsmooth);
    vec4 e0 = pal.entries[i0], e1 = pal.entries[i1];
    o_r.v[i] = k_sky_channel(c, k_mix(e0.r, e1.r, f), w);
    o_g.v[i] = k_sky_channel(c, k_mix(e0.g, e1.g, f), w);
    o_b.v[i] = k_sky_channel(c, k_mix(e0.b, e1.b, f), w);
}
