#version 450
// A star field: one invocation per pixel of a strip, summing the star records binned to its tile.
// The math is kernels/stars.h.
#extension GL_GOOGLE_include_directive : require
#define K_GLSL 1
#include "../kernels/stars.h"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

layout(push_constant) uniform Push
{
    K_StarsParams p;
    uint y0;   // first image row of this strip
    uint rows; // rows in this strip
}
pc;

layout(std430, set = 0, binding = 0) writeonly buffer Red
{
    float v[];
}
o_r;
layout(std430, set = 0, binding = 1) writeonly buffer Green
{
    float v[];
}
o_g;
layout(std430, set = 0, binding = 2) writeonly buffer Blue
{
    float v[];
}
o_b;
layout(std430, set = 0, binding = 3) writeonly buffer Mag
{
    float v[];
}
o_m;
// tile_start[tiles + 1], the records from rec_off (8 words each), each row's 1/omega from row_off
layout(std430, set = 0, binding = 4) readonly buffer Input
{
    uint w[];
}
inp;

K_StarsRec record(uint i)
{
    uint o = pc.p.rec_off + i * K_STARS_REC_WORDS;
    K_StarsRec s;
    s.x = uintBitsToFloat(inp.w[o]);
    s.y = uintBitsToFloat(inp.w[o + 1u]);
    s.r = uintBitsToFloat(inp.w[o + 2u]);
    s.g = uintBitsToFloat(inp.w[o + 3u]);
    s.b = uintBitsToFloat(inp.w[o + 4u]);
    s.mag = uintBitsToFloat(inp.w[o + 5u]);
    s.flags = inp.w[o + 6u];
    s.pad = 0u;
    return s;
}

void main()
{
    uint x = gl_GlobalInvocationID.x;
    uint r = gl_GlobalInvocationID.y;
    if (x >= pc.p.width || r >= pc.rows) return;
    uint y = pc.y0 + r;
    uint tile = (y >> pc.p.tile_shift) * pc.p.tiles_x + (x >> pc.p.tile_shift);
    K_StarsAcc acc = k_stars_init();
    uint k1 = inp.w[tile + 1u];
    for (uint k = inp.w[tile]; k < k1; k++) acc = k_stars_add(acc, pc.p, record(k), x, y);
    float row_inv = pc.p.mapping == K_ENV_CUBE ? 0.0f : uintBitsToFloat(inp.w[pc.p.row_off + y]);
    acc = k_stars_finish(acc, pc.p, row_inv, x, y);
    uint i = r * pc.p.width + x;
    o_r.v[i] = acc.r;
    o_g.v[i] = acc.g;
    o_b.v[i] = acc.b;
    o_m.v[i] = acc.mag;
}
