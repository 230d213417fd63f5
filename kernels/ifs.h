/*
 * The chaos game (random iteration algorithm) for iterated function systems, SPEC.md section 3.
 *
 * Many independent chains: chain i at step t picks its map from k_hash3(seed, i, t), so a chain's
 * path is a pure function of (seed, i, t) and the histogram (integer sums) is the same whatever
 * the scheduling, the device or the number of steps per dispatch. Every affine map is evaluated
 * with `precise` arithmetic so that lavapipe, a GPU and the C backend follow the same orbits.
 *
 * The map table is a storage buffer in GLSL and a pointer in C. A shader defines K_IFS_MAPS_BUFFER
 * (the buffer's declaration, emitted here once K_IfsMap exists) and k_ifs_maps (its array) before
 * including this header; C functions take the table as a parameter through K_IFS_MAPS_DECL.
 */
#ifndef FB_KERNELS_IFS_H
#define FB_KERNELS_IFS_H

#include "hash.h"

#define K_IFS_MAX_MAPS 64u
#define K_IFS_NONE     0xffffffffu

/* A histogram cell of 64 bits (shaders/ifs64.comp): its hits in the low K_IFS_HIT_BITS bits and the
 * colour sum above them, one atomic add of (q << K_IFS_HIT_BITS) + 1 a point. Exact while fewer than
 * 2^K_IFS_HIT_BITS points are played into it: the hits then fit their bits and the colour sum (at
 * most 255 a hit) the other 36. The host folds the cells into wider totals before more are played
 * (shaders/ifs_fold.comp). */
#define K_IFS_HIT_BITS 28u
#define K_IFS_HIT_MASK 0x0fffffffu

/* What the last step did with the chain's point. */
#define K_IFS_PLOT    0u /* the point is on the attractor: plot it (or count it outside the frame) */
#define K_IFS_SKIP    1u /* transient: one of the first `skip` points after a (re)start */
#define K_IFS_RESTART 2u /* the point left the finite range (NaN, Inf, |x| > limit): chain restarted */

/* x' = a x + b y + e, y' = c x + d y + f (Barnsley's and Fractint's convention). */
K_STRUCT(K_IfsMap)
{
    float a, b, c, d, e, f;
    float colour; /* colour coordinate in [0, 1] toward which the point's colour moves */
    uint thr;     /* the map is picked when thr <= r < the next map's thr (r uniform in 32 bits) */
}
K_END(K_IfsMap)

/* The push constants of a dispatch. */
K_STRUCT(K_IfsParams)
{
    uint seed;
    uint chains; /* number of chains */
    uint nmaps;  /* maps w1..wN at table index 0..nmaps-1 */
    uint cmaps;  /* condensation: the maps of C's IFS follow at nmaps..nmaps+cmaps-1 (0: none) */
    uint skip;   /* transient steps discarded after every (re)start */
    uint step0;  /* first step of this dispatch */
    uint nsteps; /* steps per chain in this dispatch (fewer where a chain's total ends) */
    uint base;   /* total steps of chain i: base + (i < extra ? 1 : 0) */
    uint extra;
    uint hist_w, hist_h; /* histogram size (image size times the oversampling factor) */
    uint csegs;          /* condensation onto an L-system drawing: its segments follow at nmaps..nmaps+csegs-1
                            (0: none), segment k as the map of (u, 0) to its point at parameter u */
    float x0, y0;        /* frame: column (x - x0) sx, row (y0 - y) sy (y up in the plane, down in the image) */
    float sx, sy;
    float limit; /* a chain whose |x| or |y| exceeds this restarts */
    uint chain0; /* chains below it are not run (a points part of a split bake runs [chain0, dispatch end)) */
}
K_END(K_IfsParams)

/* A chain's state between dispatches: its point, colour and condensation point, and the steps of
 * transient left before it plots. */
K_STRUCT(K_IfsChain)
{
    float x, y, c;
    float cx, cy, cc; /* condensation: the point and colour of the chain on C's IFS */
    uint left;
    uint status; /* K_IFS_PLOT, K_IFS_SKIP or K_IFS_RESTART: what the last step did */
}
K_END(K_IfsChain)

#ifdef K_GLSL
K_IFS_MAPS_BUFFER
#define K_IFS_MAPS_DECL
#define K_IFS_MAPS
#else
#define K_IFS_MAPS_DECL , const K_IfsMap *k_ifs_maps
#define K_IFS_MAPS      , k_ifs_maps
#endif

/* Index (from `first`) of the map among n whose threshold interval holds r: the number of maps
 * after the first whose threshold is <= r. */
K_FN uint k_ifs_pick(uint r, uint first, uint n K_IFS_MAPS_DECL)
{
    uint k = 0u;
    for (uint i = 1u; i < n; i++) k += r >= k_ifs_maps[first + i].thr ? 1u : 0u;
    return first + k;
}

/* A random starting point in [-1, 1)^2 for a (re)start at step t (t = K_IFS_NONE: the first). */
K_FN K_IfsChain k_ifs_restart(K_IfsParams p, K_IfsChain s, uint chain, uint t)
{
    uint h = k_hash3(p.seed ^ 0xa511e9b3u, chain, t);
    s.x = k_u01(h) * 2.0f - 1.0f;
    s.y = k_u01(k_hash(h ^ 0x3c6ef372u)) * 2.0f - 1.0f;
    s.c = 0.5f;
    s.cx = k_u01(k_hash(h ^ 0x78dde6e4u)) * 2.0f - 1.0f;
    s.cy = k_u01(k_hash(h ^ 0x1f83d9abu)) * 2.0f - 1.0f;
    s.cc = 0.5f;
    s.left = p.skip;
    return s;
}

K_FN K_IfsChain k_ifs_init(K_IfsParams p, uint chain)
{
    K_IfsChain s;
    s.status = K_IFS_SKIP;
    return k_ifs_restart(p, s, chain, K_IFS_NONE);
}

K_FN bool k_ifs_escaped(K_IfsParams p, float x, float y)
{
    return k_isnan(x) || k_isnan(y) || k_abs(x) > p.limit || k_abs(y) > p.limit;
}

K_STRUCT(K_IfsPoint)
{
    float x, y, c;
}
K_END(K_IfsPoint)

/* Map m applied to a point, and its colour coordinate moved halfway toward the map's. */
K_FN K_IfsPoint k_ifs_apply(K_IfsMap m, float x, float y, float c)
{
    K_IfsPoint q;
    K_PRECISE float nx = m.a * x + m.b * y + m.e;
    K_PRECISE float ny = m.c * x + m.d * y + m.f;
    K_PRECISE float nc = (c + m.colour) * 0.5f;
    q.x = nx;
    q.y = ny;
    q.c = nc;
    return q;
}

/* One step of chain `chain` at its step index t. With condensation (cmaps > 0) the chain also
 * walks C's IFS, and the condensation map w0 (picked when r < the first map's threshold) sends
 * the point to the chain's current point of C. */
K_FN K_IfsChain k_ifs_step(K_IfsParams p, K_IfsChain s, uint chain, uint t K_IFS_MAPS_DECL)
{
    uint r = k_hash3(p.seed, chain, t);
    bool escaped = false;
    if (p.cmaps > 0u) {
        K_IfsPoint q =
            k_ifs_apply(k_ifs_maps[k_ifs_pick(k_hash(r ^ 0x5bd1e995u), p.nmaps, p.cmaps K_IFS_MAPS)], s.cx, s.cy, s.cc);
        s.cx = q.x;
        s.cy = q.y;
        s.cc = q.c;
        escaped = k_ifs_escaped(p, q.x, q.y);
    }
    if (r < k_ifs_maps[0].thr) { /* w0: onto the condensation set */
        if (p.csegs > 0u) {
            /* a point uniform on the drawing: its segments are equally long (one turtle step) */
            uint h = k_hash(r ^ 0x5bd1e995u);
            K_IfsMap m = k_ifs_maps[p.nmaps + h % p.csegs];
            K_IfsPoint q = k_ifs_apply(m, k_u01(k_hash(h ^ 0x27d4eb2du)), 0.0f, m.colour);
            s.x = q.x;
            s.y = q.y;
            s.c = q.c;
        } else {
            s.x = s.cx;
            s.y = s.cy;
            s.c = s.cc;
        }
    } else {
        K_IfsPoint q = k_ifs_apply(k_ifs_maps[k_ifs_pick(r, 0u, p.nmaps K_IFS_MAPS)], s.x, s.y, s.c);
        s.x = q.x;
        s.y = q.y;
        s.c = q.c;
        escaped = escaped || k_ifs_escaped(p, q.x, q.y);
    }
    if (escaped) {
        s = k_ifs_restart(p, s, chain, t);
        s.status = K_IFS_RESTART;
    } else if (s.left > 0u) {
        s.left -= 1u;
        s.status = K_IFS_SKIP;
    } else {
        s.status = K_IFS_PLOT;
    }
    return s;
}

/* The histogram cell of a plotted point, or K_IFS_NONE outside the frame. */
K_FN uint k_ifs_cell(K_IfsParams p, float x, float y)
{
    K_PRECISE float px = (x - p.x0) * p.sx;
    K_PRECISE float py = (p.y0 - y) * p.sy;
    if (!(px >= 0.0f && py >= 0.0f && px < K_F(p.hist_w) && py < K_F(p.hist_h))) return K_IFS_NONE;
    return K_U(py) * p.hist_w + K_U(px);
}

/* Where one step's point goes: its histogram cell, or K_IFS_NONE when nothing is plotted (a transient
 * or restarting step, or a point outside the frame). With the three counters below, the one splat
 * decision of the shader, of the native backend and (as its specification) of the AVX2 loop. */
K_FN uint k_ifs_target(K_IfsParams p, K_IfsChain s)
{
    return s.status == K_IFS_PLOT ? k_ifs_cell(p, s.x, s.y) : K_IFS_NONE;
}

/* 1 for a plotted point outside the frame (counted, for the density), else 0. */
K_FN uint k_ifs_outside(K_IfsChain s, uint cell)
{
    return s.status == K_IFS_PLOT && cell == K_IFS_NONE ? 1u : 0u;
}

/* 1 for a step that plots nothing (transient or restart), else 0. */
K_FN uint k_ifs_discarded(K_IfsChain s)
{
    return s.status != K_IFS_PLOT ? 1u : 0u;
}

/* 1 for a step that restarted its chain (escaped or NaN), else 0. */
K_FN uint k_ifs_restarted(K_IfsChain s)
{
    return s.status == K_IFS_RESTART ? 1u : 0u;
}

/* The colour coordinate quantised to 0..255, the unit of the colour sums. */
K_FN uint k_ifs_quant(float c)
{
    return K_U(k_clamp(c, 0.0f, 1.0f) * 255.0f + 0.5f);
}

/* Steps of chain i in the whole run. */
K_FN uint k_ifs_total(K_IfsParams p, uint chain)
{
    return p.base + (chain < p.extra ? 1u : 0u);
}

#endif
