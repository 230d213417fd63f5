#version 450
// A lat-long star field written the plain way: one invocation a pixel, the records binned to its
// tile read in turn, each one's tent mass over the pixel's footprint (the product of two
// differences of the tent's CDF, kernels/stars.h's k_stars_cdf) added to the pixel's sums, then the
// sums divided by the row's solid angle. The minimal shader the stars layer is measured against in
// `fractalbake bench` (host/gen/stars/bench.c): without the layer's other mappings (the cube's
// faces, corners and in-kernel solid angles, the polar grid), so its values are the layer's to the
// bit for a lat-long sky (the bench's): the bench checks it.
#extension GL_GOOGLE_include_directive : require
#define K_GLSL 1
#include "../../kernels/stars.h"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

layout(push_constant) uniform Push
{
    K_StarsParams p;
    uint y0, rows;
}
pc;

layout(std430, set = 0, binding = 0) writeonly buffer Red { float v[]; } o_r;
layout(std430, set = 0, binding = 1) writeonly buffer Green { float v[]; } o_g;
layout(std430, set = 0, binding = 2) writeonly buffer Blue { float v[]; } o_b;
layout(std430, set = 0, binding = 3) writeonly buffer Mag { float v[]; } o_m;
// the layer's input: tile starts, records (8 words each) from rec_off, rows' 1/omega from row_off
layout(std430, set = 0, binding = 4) readonly buffer Input { uint w[]; } inp;

void main()
{
    uint x = gl_GlobalInvocationID.x, r = gl_GlobalInvocationID.y;
    if (x >= pc.p.width || r >= pc.rows) return;
    uint y = pc.y0 + r;
    float fx = float(x), fy = float(y), rad = pc.p.radius, k = pc.p.inv_2r2, reach = rad + 0.5;
    float last = float(pc.p.height - 1u);
    // the pixel's footprint: its box clipped to the image, a pole row's reaching beyond
    float xlo = max(fx - 0.5, pc.p.x_lo), xhi = min(fx + 0.5, pc.p.x_hi);
    float ylo = max(fy - 0.5, 0.0), yhi = min(fy + 0.5, last);
    float ylo_c = fy == 0.0 ? -1.0e30 : ylo, yhi_c = fy == last ? 1.0e30 : yhi;
    uint tile = (y >> pc.p.tile_shift) * pc.p.tiles_x + (x >> pc.p.tile_shift);
    float sr = 0.0, sg = 0.0, sb = 0.0, mag = K_STARS_NONE_MAG;
    for (uint i = inp.w[tile]; i < inp.w[tile + 1u]; i++) {
        uint o = pc.p.rec_off + i * K_STARS_REC_WORDS;
        float rx = uintBitsToFloat(inp.w[o]), ry = uintBitsToFloat(inp.w[o + 1u]);
        if (abs(fx - rx) >= reach || abs(fy - ry) >= reach) continue;
        bool clamp_y = (inp.w[o + 6u] & K_STARS_CLAMP_Y) != 0u;
        float wx = k_stars_cdf(xhi, rx, rad, k) - k_stars_cdf(xlo, rx, rad, k);
        float wy = k_stars_cdf(clamp_y ? yhi_c : yhi, ry, rad, k) - k_stars_cdf(clamp_y ? ylo_c : ylo, ry, rad, k);
        float wt = wx * wy;
        if (wt > 0.0) {
            sr = sr + uintBitsToFloat(inp.w[o + 2u]) * wt;
            sg = sg + uintBitsToFloat(inp.w[o + 3u]) * wt;
            sb = sb + uintBitsToFloat(inp.w[o + 4u]) * wt;
            mag = min(mag, uintBitsToFloat(inp.w[o + 5u]));
        }
    }
    float inv = uintBitsToFloat(inp.w[pc.p.row_off + y]) * (x == 0u || x == pc.p.width - 1u ? 2.0 : 1.0);
    uint at = r * pc.p.width + x;
    o_r.v[at] = sr * inv;
    o_g.v[at] = sg * inv;
    o_b.v[at] = sb * inv;
    o_m.v[at] = mag;
}
