#version 450
// Erosion's three passes written the plain way: the pass a specialization constant (a pipeline
// each, no branch on it), 16 x 16 workgroups (a tile's neighbours shared in the cache), each cell's
// formulas from kernels/erode.h called directly. The minimal shader the erosion model
// (shaders/erode.comp) is measured against in `fractalbake bench` (host/gen/erode/bench.c), with the
// same buffers, dispatches and results: the bench checks them bit for bit.
#extension GL_GOOGLE_include_directive : require
#define K_GLSL 1
#include "../../kernels/erode.h"

layout(local_size_x = 16, local_size_y = 16, local_size_z = 1) in;
layout(constant_id = 0) const uint PASS = 0u;

layout(push_constant) uniform Push
{
    K_ErodeParams p;
}
pc;

layout(std430, set = 0, binding = 0) buffer SBuf { vec4 v[]; } S;
layout(std430, set = 0, binding = 1) buffer TBuf { vec4 v[]; } T;
layout(std430, set = 0, binding = 2) buffer FBuf { vec4 v[]; } F;
layout(std430, set = 0, binding = 3) buffer MBuf { vec4 v[]; } M;

// the flux into cell i from its neighbours (a wall: none)
vec4 inflow(uint i, uint w, bool l, bool r, bool t, bool b)
{
    return vec4(l ? F.v[i - 1u].y : 0.0, r ? F.v[i + 1u].x : 0.0, t ? F.v[i - w].w : 0.0, b ? F.v[i + w].z : 0.0);
}

void main()
{
    K_ErodeParams p = pc.p;
    uint x = gl_GlobalInvocationID.x, y = gl_GlobalInvocationID.y, w = p.width;
    if (x >= w || y >= p.height) return;
    uint i = y * w + x;
    bool l = x > 0u, r = x + 1u < w, t = y > 0u, b = y + 1u < p.height;
    if (PASS == K_ERODE_PASS_FLUX) {
        vec4 c = S.v[i];
        float hc = k_erode_surface(p, c);
        vec4 hn = vec4(l ? k_erode_surface(p, S.v[i - 1u]) : hc, r ? k_erode_surface(p, S.v[i + 1u]) : hc,
                       t ? k_erode_surface(p, S.v[i - w]) : hc, b ? k_erode_surface(p, S.v[i + w]) : hc);
        vec4 inside = vec4(l ? 1.0 : 0.0, r ? 1.0 : 0.0, t ? 1.0 : 0.0, b ? 1.0 : 0.0);
        F.v[i] = k_erode_flux(p, F.v[i], c.y + p.rain, hc, hn, inside);
    } else if (PASS == K_ERODE_PASS_WATER) {
        vec4 c = S.v[i];
        vec4 bn = vec4(l ? S.v[i - 1u].x : c.x, r ? S.v[i + 1u].x : c.x, t ? S.v[i - w].x : c.x, b ? S.v[i + w].x : c.x);
        float d1 = c.y + p.rain;
        vec4 o = k_erode_water(p, c.x, d1, c.z, F.v[i], inflow(i, w, l, r, t, b), bn);
        T.v[i] = vec4(o.x, o.y, o.z, d1);
        M.v[i] = k_erode_masks(p, M.v[i], c.x, o.x, o.w);
    } else {
        vec4 c = T.v[i], e = vec4(c.x, 0.0, 0.0, 0.0);
        vec4 cl = l ? T.v[i - 1u] : e, cr = r ? T.v[i + 1u] : e, ct = t ? T.v[i - w] : e, cb = b ? T.v[i + w] : e;
        float s = k_erode_sediment(p, c.z, c.w, F.v[i], vec4(cl.z, cr.z, ct.z, cb.z), vec4(cl.w, cr.w, ct.w, cb.w),
                                   inflow(i, w, l, r, t, b));
        float nb = k_erode_thermal(p, c.x, vec4(cl.x, cr.x, ct.x, cb.x));
        S.v[i] = vec4(nb, c.y, s, 0.0);
        M.v[i] = k_erode_masks(p, M.v[i], c.x, nb, 0.0);
    }
}
