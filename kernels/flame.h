/*
 * Fractal flames (Scott Draves and Erik Reckase, "The Fractal Flame Algorithm", 2003/2008): one
 * iteration of a flame's chaos game, as flam3 3.1.1 runs it, in the common subset of C11 and GLSL.
 *
 * A chain starts at a random point of [-1, 1]^2 with a random colour, runs `fuse` iterations that
 * are not plotted, then `len` that are. An iteration picks an xform by its weight (or, with xaos,
 * by the row of the xform used last), applies its affine coefficients, pre_blur, the weighted sum
 * of its variations (kernels/flame_var.h: one function each, picked by number in one switch) and
 * its post transform; a result that is NaN or beyond 1e10 is replaced by a random point and the
 * iteration retried, up to five times in a row (flam3's rule). The final xform, when there is one,
 * is applied to what is plotted, not to the chain.
 *
 * Randomness is counter-based: the n-th draw of chain i is k_hash(n ^ key_i), key_i a hash of the
 * seed and i, so a chain gives the same points on any thread, points part or device.
 *
 * The xform, variation and xform-choice tables are buffers in GLSL and pointers in C: a shader
 * defines K_FLAME_BUFFERS (their declarations, k_flame_xf[], k_flame_var[] and k_flame_dist[],
 * emitted here once the structs exist) before including this header; C functions take them through
 * K_FLAME_TABLES_DECL.
 *
 * Exact arithmetic: the same bits in C and on every conformant Vulkan device. Division and square
 * root go through kernels/exact.h, the transcendentals are kernels/kmath.h's float-only ones, C is
 * built with -ffp-contract=off and the build's SPIR-V pass marks every float operation NoContraction
 * (tests/spirv_audit.py holds the shaders to it).
 */
#ifndef FB_KERNELS_FLAME_H
#define FB_KERNELS_FLAME_H

#include "flame_var.h"

/* (K_FLAME_INLINE, kernels/flame_var.h: the step inlined into its caller in C: returned through
 * memory, its state is otherwise stored field by field and read back whole, which the processor
 * cannot forward, a stall a point.) */

#define K_FLAME_GRAIN         16384u /* entries of one row of the xform choice table (flam3's CHOOSE_XFORM_GRAIN) */
#define K_FLAME_NONE          0xffffffffu
#define K_FLAME_ATAN_XY       1u  /* flags: the xform's variations read atan2(x, y) */
#define K_FLAME_ATAN_YX       2u  /* ... atan2(y, x) */
#define K_FLAME_HAS_POST      4u  /* it has a post transform */
#define K_FLAME_SQRT          8u  /* ... the length of (tx, ty) */
#define K_FLAME_ANGLES        16u /* ... flam3's sina and cosa (tx and ty over the length) */
#define K_FLAME_PREBLUR_DRAWS 5u

/* An xform: tx = ax x + bx y + cx, ty = ay x + by y + cy (flam3's coefs c00 c01 c10 c11 c20 c21 are
 * ax ay bx by cx cy), its post transform the same way, colour, colour speed, adjusted opacity, its
 * variations k_flame_var[var0 .. var0 + nvar) in ascending order of their numbers, pre_blur's weight
 * (0: none; pre_blur is not among the variations). */
K_STRUCT(K_FlameXform)
{
    float ax, bx, cx, ay, by, cy;
    float pax, pbx, pcx, pay, pby, pcy;
    float color, speed, vis;
    uint var0, nvar, flags;
    uint visq; /* vis in units of 2^-15 (the fixed-point weight of its points) */
    float preblur;
}
K_END(K_FlameXform)

K_STRUCT(K_FlameParams)
{
    uint seed;
    uint nxf;      /* ordinary xforms: k_flame_xf[0 .. nxf) */
    uint final_xf; /* the final xform's index, or K_FLAME_NONE */
    uint chaos;    /* 1: xaos, the choice table has a row per xform after the plain row 0 */
    uint fuse;     /* iterations not plotted at a chain's start */
    uint len;      /* iterations plotted per chain */
    uint chains;   /* chains in all */
    uint last_len; /* the last chain's iterations (the points need not divide evenly) */
    uint hist_w, hist_h;
    uint rotate; /* 1: the plotted point is rotated about (rcx, rcy) */
    uint final_always;
    float final_opacity;
    float rot00, rot01, rot10, rot11, rcx, rcy;
    float b0, b1, b2, b3; /* the histogram's frame: xmin, ymin, xmax, ymax */
    float ws0, wb0s0, hs1, hb1s1;
}
K_END(K_FlameParams)

/* A chain's state: the point (x, y, c), the last xform used (+1; 0 before the first), the next
 * draw's counter, and what the iteration plots: (px, py, pc) with xform `vis`'s opacity. */
K_STRUCT(K_FlameChain)
{
    float x, y, c;
    uint last;
    uint n;
    uint vis;
    float px, py, pc;
    uint bad; /* iterations that produced a bad value (flam3's badvals) */
}
K_END(K_FlameChain)

#ifdef K_GLSL
K_FLAME_BUFFERS
#define K_FLAME_TABLES_DECL
#define K_FLAME_TABLES
#else
#define K_FLAME_TABLES_DECL , const K_FlameXform *k_flame_xf, const K_FlameVar *k_flame_var, const uint *k_flame_dist
#define K_FLAME_TABLES      , k_flame_xf, k_flame_var, k_flame_dist
#endif

K_FN bool k_flame_bad(float v)
{
    return k_isnan(v) || v > 1e10f || v < -1e10f;
}

/* The result of one xform: the point and colour, and whether it was a bad value (then the point
 * is random, as flam3 does). */
K_STRUCT(K_FlameOut)
{
    float x, y, c;
    uint n;
    bool bad;
}
K_END(K_FlameOut)

/* Whether the final xform's code is there: a shader may define it false for a genome without one
 * (lavapipe runs the code of an if whose condition no lane meets, under a mask). */
#ifndef K_FLAME_FINAL
#define K_FLAME_FINAL true
#endif

/* Draws inside k_flame_apply: n is its local counter. */
#define K_FLAME_RAND() k_flame_u01(key, n++)

/* flam3's precalcs of the point (tx, ty) for the variations of an xform with these flags. */
K_FN K_FlamePt k_flame_point(float tx, float ty, uint flags)
{
    K_FlamePt t;
    t.tx = tx;
    t.ty = ty;
    t.sumsq = tx * tx + ty * ty;
    t.sq = 0.0f;
    t.sina = 0.0f;
    t.cosa = 0.0f;
    t.atxy = 0.0f;
    t.atyx = 0.0f;
    if ((flags & (K_FLAME_SQRT | K_FLAME_ANGLES)) != 0u) t.sq = kx_sqrt(t.sumsq);
    if ((flags & K_FLAME_ANGLES) != 0u) {
        t.sina = kx_div(tx, t.sq);
        t.cosa = kx_div(ty, t.sq);
    }
    if ((flags & K_FLAME_ATAN_XY) != 0u) t.atxy = k_xatan2(tx, ty);
    if ((flags & K_FLAME_ATAN_YX) != 0u) t.atyx = k_xatan2(ty, tx);
    return t;
}

#ifdef K_FLAME_ONCE
/* Variation vc of a shader's pass (below): taken by the lanes whose xform has it next, compiled only
 * where the genome has it. */
#define K_FLAME_ONCE_CASE(vc, call, nd)                                                                                \
    if (K_FLAME_HAS(vc) && k < X.nvar) {                                                                               \
        K_FlameVar V = k_flame_var[X.var0 + k];                                                                        \
        if (V.id == vc) {                                                                                              \
            float w = V.w;                                                                                             \
            k_vec2 dv = call;                                                                                          \
            p0 += dv.x;                                                                                                \
            p1 += dv.y;                                                                                                \
            n += nd;                                                                                                   \
            k++;                                                                                                       \
        }                                                                                                              \
    }
#endif

/* Applies xform `fn` to (x, y, c): flam3's apply_xform. In C (and GLSL by default) a loop over the
 * xform's variations, each through the switch. A shader that defines K_FLAME_ONCE makes a pass over
 * the genome's variations instead, the same for every lane: straight code from K_FLAME_VARIATIONS,
 * each variation behind a constant test and taken by the lanes whose xform has it next (an xform's
 * variations are in ascending order, the order of the pass). lavapipe runs every branch any of its 8
 * lanes takes, so a loop over an xform's slots ran each of the genome's variations once a slot, and a
 * loop with the switch inside every compiled case each time round; this runs each once a step. The
 * terms are added in the same order, so the sums are the same bits. */
K_FLAME_INLINE K_FlameOut k_flame_apply(uint fn, float x, float y, float c, uint key, uint n0 K_FLAME_TABLES_DECL)
{
    K_FlameXform X = k_flame_xf[fn];
    uint n = n0;
    K_FlameOut o;
    o.c = X.speed * X.color + (1.0f - X.speed) * c;
    float tx = X.ax * x + X.bx * y + X.cx;
    float ty = X.ay * x + X.by * y + X.cy;
    if (K_FLAME_HAS(K_V_PRE_BLUR) && X.preblur != 0.0f) {
        k_vec2 b = k_flame_preblur(tx, ty, X.preblur, key, n);
        n += K_FLAME_PREBLUR_DRAWS;
        tx = b.x;
        ty = b.y;
    }
    K_FlamePt t = k_flame_point(tx, ty, X.flags);
    float p0 = 0.0f, p1 = 0.0f;
#ifdef K_FLAME_ONCE
    uint k = 0u;
    K_FLAME_VARIATIONS(K_FLAME_ONCE_CASE)
#else
    for (uint k = 0u; k < X.nvar; k++) {
        K_FlameVar V = k_flame_var[X.var0 + k];
        K_FlameD d = k_flame_variation(V.id, t, V, key, n);
        p0 += d.x;
        p1 += d.y;
        n += d.draws;
    }
#endif
    if ((X.flags & K_FLAME_HAS_POST) != 0u) {
        o.x = X.pax * p0 + X.pbx * p1 + X.pcx;
        o.y = X.pay * p0 + X.pby * p1 + X.pcy;
    } else {
        o.x = p0;
        o.y = p1;
    }
    o.bad = k_flame_bad(o.x) || k_flame_bad(o.y);
    if (o.bad) {
        o.x = K_FLAME_RAND() * 2.0f - 1.0f;
        o.y = K_FLAME_RAND() * 2.0f - 1.0f;
    }
    o.n = n;
    return o;
}

/* A chain's start: a random point of [-1, 1]^2 and colour of [0, 1). */
K_FN K_FlameChain k_flame_init(uint key)
{
    K_FlameChain s;
    s.x = k_flame_u01(key, 0u) * 2.0f - 1.0f;
    s.y = k_flame_u01(key, 1u) * 2.0f - 1.0f;
    s.c = k_flame_u01(key, 2u);
    s.last = 0u;
    s.n = 3u;
    s.vis = 0u;
    s.px = s.x;
    s.py = s.y;
    s.pc = s.c;
    s.bad = 0u;
    return s;
}

/* The camera's rotation of a plotted point about (rcx, rcy). (A function of its own: glslang's
 * propagation of `precise` through k_flame_step's loops takes minutes.) */
K_FN k_vec2 k_flame_rotate(K_FlameParams P, float px, float py)
{
    K_PRECISE float qx = px - P.rcx;
    K_PRECISE float qy = py - P.rcy;
    K_PRECISE float rx = qx * P.rot00 + qy * P.rot01 + P.rcx;
    K_PRECISE float ry = qx * P.rot10 + qy * P.rot11 + P.rcy;
    return k_vec2(rx, ry);
}

/* A step's plotted point (px, py, pc), the camera's rotation applied. */
K_FN K_FlameChain k_flame_end(K_FlameParams P, K_FlameChain s, float px, float py, float pc)
{
    if (P.rotate != 0u) {
        k_vec2 r = k_flame_rotate(P, px, py);
        px = r.x;
        py = r.y;
    }
    s.px = px;
    s.py = py;
    s.pc = pc;
    return s;
}

/* The end of the native game's step (host/gen/flame/game.c, with its linear fast path), once its
 * xform is applied: the final xform (when the genome has one, at its opacity) and the camera's
 * rotation give the point plotted (px, py, pc); the chain goes on from (x, y, c). k_flame_step ends
 * the same way. */
K_FLAME_INLINE K_FlameChain k_flame_plot(K_FlameParams P, K_FlameChain s, uint key K_FLAME_TABLES_DECL)
{
    float px = s.x, py = s.y, pc = s.c;
    if (K_FLAME_FINAL && P.final_xf != K_FLAME_NONE) {
        bool apply = P.final_always != 0u;
        if (!apply) {
            apply = k_flame_u01(key, s.n) < P.final_opacity;
            s.n++;
        }
        if (apply) {
            K_FlameOut f = k_flame_apply(P.final_xf, s.x, s.y, s.c, key, s.n K_FLAME_TABLES);
            s.n = f.n;
            px = f.x;
            py = f.y;
            pc = f.c;
        }
    }
    return k_flame_end(P, s, px, py, pc);
}

/* One iteration of the chain (flam3_iterate's loop body): the xform chosen and applied, retried on
 * a bad value at most four times, then the final xform and the camera's rotation for the plot, as
 * k_flame_plot. One call of k_flame_apply serves the tries and the final xform: in a shader each
 * call is a copy of every variation the shader has, which lavapipe compiles before it drops those
 * the pipeline's specialisation leaves out (its time to create the pipeline). */
K_FLAME_INLINE K_FlameChain k_flame_step(K_FlameParams P, K_FlameChain s, uint key K_FLAME_TABLES_DECL)
{
    uint fn = 0u, tries = 0u;
    bool fin = false; /* the next xform is the final one */
    float px = 0.0f, py = 0.0f, pc = 0.0f;
    for (uint it = 0u; it < 6u; it++) {
        uint f = P.final_xf, n = s.n;
        if (!fin) {
            uint row = P.chaos != 0u ? s.last : 0u;
            f = k_flame_dist[row * K_FLAME_GRAIN + (k_hash(s.n ^ key) & (K_FLAME_GRAIN - 1u))];
            n = s.n + 1u;
        }
        K_FlameOut o = k_flame_apply(f, s.x, s.y, s.c, key, n K_FLAME_TABLES);
        s.n = o.n;
        px = o.x;
        py = o.y;
        pc = o.c;
        if (fin) break;
        s.x = o.x;
        s.y = o.y;
        s.c = o.c;
        fn = f;
        if (o.bad) {
            s.bad++;
            tries++;
            if (tries < 5u) continue;
        }
        if (!K_FLAME_FINAL || P.final_xf == K_FLAME_NONE) break;
        fin = P.final_always != 0u;
        if (!fin) {
            fin = k_flame_u01(key, s.n) < P.final_opacity;
            s.n++;
        }
        if (!fin) break;
    }
    s.last = fn + 1u;
    s.vis = fn;
    return k_flame_end(P, s, px, py, pc);
}

/* The histogram cell the plotted point falls in, or K_FLAME_NONE outside the frame (or invisible). */
K_FN uint k_flame_cell(K_FlameParams P, K_FlameChain s)
{
    if (!(s.px >= P.b0 && s.py >= P.b1 && s.px <= P.b2 && s.py <= P.b3)) return K_FLAME_NONE;
    K_PRECISE float fx = P.ws0 * s.px - P.wb0s0;
    K_PRECISE float fy = P.hs1 * s.py - P.hb1s1;
    int ix = K_I(fx), iy = K_I(fy);
    if (ix < 0 || iy < 0 || ix >= K_I(P.hist_w) || iy >= K_I(P.hist_h)) return K_FLAME_NONE;
    return K_U(iy) * P.hist_w + K_U(ix);
}

/* The palette entry of colour coordinate c (flam3's step mode over 256 entries). */
K_FN uint k_flame_index(float c)
{
    int i = K_I(c * 256.0f);
    return K_U(i < 0 ? 0 : i > 255 ? 255 : i);
}

/* flam3's linear palette mode: colour coordinate c between entries i and i + 1 (i in 0 .. 254)
 * with the weight of i + 1 in units of 2^-16 (0 below the palette, all of it past its end). */
K_FN uint k_flame_lin_index(float c)
{
    int i = K_I(c * 256.0f);
    return K_U(i < 0 ? 0 : i >= 255 ? 254 : i);
}

K_FN uint k_flame_lin_frac(float c)
{
    float v = c * 256.0f;
    int i = K_I(v);
    if (i < 0) return 0u;
    if (i >= 255) return 65536u;
    return K_U((v - K_F(i)) * 65536.0f); /* both exact */
}

/* The interpolated palette value (a and b in 2^-4 units, up to 4080: the sum fits 32 bits). */
K_FN uint k_flame_lerp(uint a, uint b, uint frac)
{
    return (a * (65536u - frac) + b * frac + 32768u) >> 16u;
}

/* A palette value (up to 4080) times an opacity visq (2^-15 units), rounded. */
K_FN uint k_flame_vis(uint q, uint visq)
{
    return (q * visq + 16384u) >> 15u;
}

/* The opacity sum of a point: 255 (4080 in 2^-4 units) times its opacity. */
#define K_FLAME_OPAQUE 4080u

/* The histogram of a device with 64-bit atomics (shaders/flame_body.glsl, FB_FLAME_INT64): words a
 * cell, each point one add to each whose result is unused. Word 0 holds the hits in its low
 * K_FLAME_HIT_BITS bits and the red sum above them; the next green, blue and (translucent genomes,
 * not compact) alpha and opacity. A point adds at most 4080 to a colour, so every field is exact
 * while fewer than 2^K_FLAME_HIT_BITS points are played in between folds into wider totals
 * (shaders/flame_fold.comp): the hits fit their bits and each colour 38 bits. */
#define K_FLAME_HIT_BITS       26u
#define K_FLAME_WORDS(compact) ((compact) != 0u ? 3u : 5u)

#endif
