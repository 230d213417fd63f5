#version 450
// A star field: one invocation per pixel of a strip, summing the star records binned to its tile.
// The math is kernels/stars.h.
#extension GL_GOOGLE_include_directive : require
#define K_GLSL 1
#include "../kernels/stars.h"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;
// the mapping (pc.p.mapping's value, host/gen/stars/layer.c), known when the pipeline is compiled
layout(constant_id = 0) const uint MAPPING = 0u;

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

void main()
{
    uint x = gl_GlobalInvocationID.x;
    uint r = gl_GlobalInvocationID.y;
    if (x >= pc.p.width || r >= pc.rows) return;
    uint y = pc.y0 + r;
    K_StarsParams p = pc.p;
    p.mapping = MAPPING;
    uint tile = (y >> p.tile_shift) * p.tiles_x + (x >> p.tile_shift);
    K_StarsPixel px = k_stars_pixel(p, x, y);
    K_StarsAcc acc = k_stars_init();
    uint k1 = inp.w[tile + 1u];
    // k_stars_add with each record read as it is needed: its centre, and the rest only when it is
    // within reach (most of a tile's records are not)
    for (uint k = inp.w[tile]; k < k1; k++) {
        uint o = p.rec_off + k * K_STARS_REC_WORDS;
        float rx = uintBitsToFloat(inp.w[o]), ry = uintBitsToFloat(inp.w[o + 1u]);
        if (!k_stars_near(p, px, rx, ry)) continue;
        float w = k_stars_share(p, px, rx, ry, inp.w[o + 6u]);
        acc = k_stars_accumulate(acc, w, uintBitsToFloat(inp.w[o + 2u]), uintBitsToFloat(inp.w[o + 3u]),
                                 uintBitsToFloat(inp.w[o + 4u]), uintBitsToFloat(inp.w[o + 5u]));
    }
    float row_inv = p.mapping == K_ENV_CUBE ? 0.0f : uintBitsToFloat(inp.w[p.row_off + y]);
    acc = k_stars_finish(acc, p, row_inv, x, y);
    uint i = r * p.width + x;
    o_r.v[i] = acc.r;
    o_g.v[i] = acc.g;
    o_b.v[i] = acc.b;
    o_m.v[i] = acc.mag;
}
