#version 450
// L-system segments rasterised with anti-aliased coverage: one invocation per pixel of a strip,
// summing the segments binned to its tile. The math is kernels/lsys.h.
#extension GL_GOOGLE_include_directive : require
#define K_GLSL 1
#include "../kernels/lsys.h"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

layout(push_constant) uniform Push
{
    K_LsysParams p;
    uint y0;   // first image row of this strip
    uint rows; // rows in this strip
}
pc;

layout(std430, set = 0, binding = 0) writeonly buffer Alpha { float v[]; } o_a;
layout(std430, set = 0, binding = 1) writeonly buffer Red { float v[]; } o_r;
layout(std430, set = 0, binding = 2) writeonly buffer Green { float v[]; } o_g;
layout(std430, set = 0, binding = 3) writeonly buffer Blue { float v[]; } o_b;
// tile_start[tiles + 1], then the index list at idx_off, then the segments at seg_off (9 words each)
layout(std430, set = 0, binding = 4) readonly buffer Input { uint w[]; } inp;

K_LsysSeg segment(uint i)
{
    uint o = pc.p.seg_off + i * K_LSYS_SEG_WORDS;
    K_LsysSeg s;
    s.ax = uintBitsToFloat(inp.w[o]);
    s.ay = uintBitsToFloat(inp.w[o + 1u]);
    s.ux = uintBitsToFloat(inp.w[o + 2u]);
    s.uy = uintBitsToFloat(inp.w[o + 3u]);
    s.len = uintBitsToFloat(inp.w[o + 4u]);
    s.hw = uintBitsToFloat(inp.w[o + 5u]);
    s.r = uintBitsToFloat(inp.w[o + 6u]);
    s.g = uintBitsToFloat(inp.w[o + 7u]);
    s.b = uintBitsToFloat(inp.w[o + 8u]);
    return s;
}

void main()
{
    uint x = gl_GlobalInvocationID.x;
    uint r = gl_GlobalInvocationID.y;
    if (x >= pc.p.width || r >= pc.rows) return;
    uint y = pc.y0 + r;
    uint tile = (y >> pc.p.tile_shift) * pc.p.tiles_x + (x >> pc.p.tile_shift);
    float px = float(x) + 0.5f, py = float(y) + 0.5f;
    K_LsysAcc acc;
    acc.a = 0.0f;
    acc.r = 0.0f;
    acc.g = 0.0f;
    acc.b = 0.0f;
    uint k1 = inp.w[tile + 1u];
    for (uint k = inp.w[tile]; k < k1; k++) acc = k_lsys_add(acc, segment(inp.w[pc.p.idx_off + k]), px, py);
    acc = k_lsys_finish(acc);
    uint i = r * pc.p.width + x;
    o_r.v[i] = acc.r;
    o_g.v[i] = acc.g;
    o_b.v[i] = acc.b;
    o_a.v[i] = acc.a;
}
