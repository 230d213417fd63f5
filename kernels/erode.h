/*
 * Erosion on a height grid: hydraulic erosion with virtual pipes (Mei, Decaudin and Hu, "Fast
 * Hydraulic Erosion Simulation and Visualization on GPU", Pacific Graphics 2007) and thermal erosion
 * by talus angle (Musgrave, Kolb and Mace, "The Synthesis and Rendering of Eroded Fractal Terrains",
 * SIGGRAPH 1989).
 *
 * One iteration is three passes over the grid, each a pure function of the previous pass's grids
 * (Jacobi style: every cell reads its own and its four neighbours' values and writes only its own),
 * so any split over threads, workgroups or devices gives the same bits:
 *   1. flux:   rain, then the outflow flux of the four pipes from the water surface's differences,
 *              scaled so that no cell sends more water than it has;
 *   2. water:  the water's new depth from the fluxes in and out, its velocity, the transport capacity
 *              C = Kc sin(alpha) |v|, dissolution (C > s) or deposition (C < s), evaporation;
 *   3. settle: the suspended sediment moves with the water (each pipe carries the fraction of the
 *              cell's water it carries), and material above the talus slope slides to the lower
 *              neighbour.
 * Every transfer between two cells (sediment carried, material slid) is computed by the same
 * expression from the same values in both cells, so bed plus sediment is conserved up to the
 * rounding of the additions. Mei et al. move sediment semi-Lagrangian (back-tracing the velocity);
 * that does not conserve mass, so it is replaced here by this upwind, flux-proportional transport.
 *
 * The grid is 4-connected; a neighbour outside the grid is a closed wall (no pipe). Cells are
 * K_ErodeCell = (b: bed height, d: water depth, s: suspended sediment, w: spare) in world units.
 */
#ifndef FB_KERNELS_ERODE_H
#define FB_KERNELS_ERODE_H

#include "common.h"
#include "exact.h"

/* Everything in world units per iteration, computed once on the host (host/gen/erode/erode.c). */
K_STRUCT(K_ErodeParams)
{
    uint width;
    uint height;
    uint pass; /* K_ERODE_PASS_*: the shader's pass */
    uint pad;
    float rain;       /* water added per iteration (height units) */
    float pipe;       /* dt g l: a pipe's flux gained per unit height difference (pipe section l^2, length l) */
    float vol;        /* l^2 / dt: a depth turned into the flux that empties it in one iteration */
    float dt_area;    /* dt / l^2: a flux turned into the depth it moves in one iteration */
    float inv_l;      /* 1 / l */
    float half_inv_l; /* 1 / (2 l): central differences */
    float kc;         /* sediment capacity constant Kc */
    float ks;         /* fraction of the capacity deficit dissolved per iteration, min(1, Ks dt) */
    float kd;         /* fraction of the capacity excess deposited per iteration, min(1, Kd dt) */
    float keep;       /* water kept after evaporation per iteration, 1 - Ke dt */
    float dmin;       /* the depth below which the velocity is taken over this depth (no division by 0) */
    float talus;      /* tan(talus angle) l: the largest height step between neighbours that stays */
    float kt;         /* fraction of the excess over the talus step moved per iteration (<= 0.5) */
    float flow_w;     /* dt / duration: the flow mask is the time average of the discharge */
    float inv_depth;  /* 1 / the depth that carries the full capacity (shallower: proportionally less) */
    float pad2;
}
K_END(K_ErodeParams)

#define K_ERODE_PASS_FLUX   0u
#define K_ERODE_PASS_WATER  1u
#define K_ERODE_PASS_SETTLE 2u

/* A cell's water surface after this iteration's rain: b + (d + rain). */
K_FN float k_erode_surface(K_ErodeParams p, k_vec4 c)
{
    K_PRECISE float h = c.x + (c.y + p.rain);
    return h;
}

/* Pass 1. The outflow fluxes (left, right, top, bottom as x, y, z, w) of a cell with water surface
 * hc = b + d + rain and depth d1 = d + rain, from its previous fluxes f and its neighbours' surfaces
 * hn; inside: 1 for a neighbour in the grid, 0 for a wall. */
K_FN k_vec4 k_erode_flux(K_ErodeParams p, k_vec4 f, float d1, float hc, k_vec4 hn, k_vec4 inside)
{
    K_PRECISE float fl = k_max(0.0f, f.x + p.pipe * (hc - hn.x)) * inside.x;
    K_PRECISE float fr = k_max(0.0f, f.y + p.pipe * (hc - hn.y)) * inside.y;
    K_PRECISE float ft = k_max(0.0f, f.z + p.pipe * (hc - hn.z)) * inside.z;
    K_PRECISE float fb = k_max(0.0f, f.w + p.pipe * (hc - hn.w)) * inside.w;
    K_PRECISE float sum = ((fl + fr) + ft) + fb;
    K_PRECISE float k = 1.0f;
    if (sum > 0.0f) k = k_min(1.0f, kx_div(d1 * p.vol, sum));
    K_PRECISE float ol = fl * k;
    K_PRECISE float orr = fr * k;
    K_PRECISE float ot = ft * k;
    K_PRECISE float ob = fb * k;
    return k_vec4(ol, orr, ot, ob);
}

/* Pass 2. A cell (bed b, depth after rain d1, sediment s) with outflows f and inflows fin (from the
 * left, right, top and bottom neighbours), and the beds bn of its neighbours (its own b for a wall):
 * returns (b', d', s', q): the bed after dissolution or deposition, the depth after evaporation, the
 * suspended sediment, and the discharge per unit width |q| (world units^2 per time unit). */
K_FN k_vec4 k_erode_water(K_ErodeParams p, float b, float d1, float s, k_vec4 f, k_vec4 fin, k_vec4 bn)
{
    K_PRECISE float fout = ((f.x + f.y) + f.z) + f.w;
    K_PRECISE float fsum = ((fin.x + fin.y) + fin.z) + fin.w;
    K_PRECISE float d2 = d1 + (fsum - fout) * p.dt_area;
    K_PRECISE float dm = (d1 + d2) * 0.5f;
    K_PRECISE float wx = ((fin.x - f.x) + (f.y - fin.y)) * 0.5f;
    K_PRECISE float wy = ((fin.z - f.z) + (f.w - fin.w)) * 0.5f;
    K_PRECISE float q = kx_sqrt(wx * wx + wy * wy) * p.inv_l;
    K_PRECISE float speed = kx_div(q, k_max(dm, p.dmin));
    K_PRECISE float gx = (bn.y - bn.x) * p.half_inv_l;
    K_PRECISE float gy = (bn.w - bn.z) * p.half_inv_l;
    K_PRECISE float g2 = gx * gx + gy * gy;
    K_PRECISE float sina = kx_sqrt(kx_div(g2, 1.0f + g2));
    K_PRECISE float cap = ((p.kc * sina) * speed) * k_min(1.0f, dm * p.inv_depth);
    K_PRECISE float nb = b;
    K_PRECISE float ns = s;
    if (cap > s) {
        K_PRECISE float amt = p.ks * (cap - s);
        nb = b - amt;
        ns = s + amt;
    } else {
        K_PRECISE float amt = p.kd * (s - cap);
        nb = b + amt;
        ns = s - amt;
    }
    K_PRECISE float nd = k_max(0.0f, d2) * p.keep;
    return k_vec4(nb, nd, ns, q);
}

/* The sediment a cell (sediment s, depth after rain d1) sends down a pipe carrying flux fk: the
 * fraction of its water the pipe takes in one iteration. Both cells of the pipe evaluate it alike. */
K_FN float k_erode_carry(K_ErodeParams p, float s, float fk, float d1)
{
    K_PRECISE float c = 0.0f;
    if (d1 > 0.0f) c = s * kx_div(fk * p.dt_area, d1);
    return c;
}

/* The material that slides from a cell of height a to a neighbour of height z: a fraction of the
 * step's excess over the talus step, half of it (the two then differ by less). */
K_FN float k_erode_slide(K_ErodeParams p, float a, float z)
{
    K_PRECISE float m = (p.kt * k_max(0.0f, (a - z) - p.talus)) * 0.5f;
    return m;
}

/* Pass 3. The sediment after transport: the cell's own (s, d1, outflows f) less what it sends, plus
 * what the neighbours (sn, d1n, their fluxes towards this cell fin: 0 across a wall) send. */
K_FN float k_erode_sediment(K_ErodeParams p, float s, float d1, k_vec4 f, k_vec4 sn, k_vec4 d1n, k_vec4 fin)
{
    K_PRECISE float gone =
        ((k_erode_carry(p, s, f.x, d1) + k_erode_carry(p, s, f.y, d1)) + k_erode_carry(p, s, f.z, d1)) +
        k_erode_carry(p, s, f.w, d1);
    K_PRECISE float got = ((k_erode_carry(p, sn.x, fin.x, d1n.x) + k_erode_carry(p, sn.y, fin.y, d1n.y)) +
                           k_erode_carry(p, sn.z, fin.z, d1n.z)) +
                          k_erode_carry(p, sn.w, fin.w, d1n.w);
    K_PRECISE float r = (s - gone) + got;
    return r;
}

/* Pass 3. The bed after thermal erosion: b less what slides to each lower neighbour (bn: a wall is
 * given as b itself), plus what slides in from each higher one. */
K_FN float k_erode_thermal(K_ErodeParams p, float b, k_vec4 bn)
{
    K_PRECISE float gone = ((k_erode_slide(p, b, bn.x) + k_erode_slide(p, b, bn.y)) + k_erode_slide(p, b, bn.z)) +
                           k_erode_slide(p, b, bn.w);
    K_PRECISE float got = ((k_erode_slide(p, bn.x, b) + k_erode_slide(p, bn.y, b)) + k_erode_slide(p, bn.z, b)) +
                          k_erode_slide(p, bn.w, b);
    K_PRECISE float r = (b - gone) + got;
    return r;
}

/* The masks (flow, wear, deposition, spare) after a pass moved the bed from b0 to b1 with
 * discharge q (0 for the thermal pass). */
K_FN k_vec4 k_erode_masks(K_ErodeParams p, k_vec4 m, float b0, float b1, float q)
{
    K_PRECISE float flow = m.x + q * p.flow_w;
    K_PRECISE float wear = m.y + k_max(0.0f, b0 - b1);
    K_PRECISE float dep = m.z + k_max(0.0f, b1 - b0);
    return k_vec4(flow, wear, dep, m.w);
}

#endif
