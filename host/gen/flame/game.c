/*
 * The flame's chaos game (game.h). Each thread computes a batch of a chain's points, turns them into
 * records (histogram cell, palette entry, opacity), then scatters the records with the cells
 * prefetched some records ahead: the histogram does not fit in the caches, and independent,
 * prefetched increments keep many misses in flight where plotting inside the chain's dependent loop
 * waits for each. Opaque genomes use 16-byte cells (one cache line holds four, none straddles two).
 */
#include "game.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

typedef struct cell16 {
    uint32_t c[3]; /* red, green, blue */
    uint32_t hits;
} cell16;

#define BATCH    1024 /* points computed before they are scattered */
#define AHEAD    64   /* records prefetched ahead of the one added */
#define OPAQUE_Q K_FLAME_OPAQUE
#define GROUP    128 /* chains on the lanes together: those whose step chose a non-linear xform regrouped by it */

static bool compact(const fb_flame_setup *S)
{
    if (S->linear_palette) return false;
    for (uint32_t i = 0; i < S->p.nxf; i++)
        if (S->xf[i].visq != 32768u) return false;
    for (int i = 0; i < 256; i++)
        if (S->palq[i][3] != OPAQUE_Q) return false;
    return true;
}

size_t fb_flame_cell_bytes(const fb_flame_setup *S)
{
    return compact(S) ? sizeof(cell16) : sizeof(fb_flame_cell32);
}

static void add64(uint64_t *to, uint64_t v)
{
    atomic_fetch_add_explicit((_Atomic uint64_t *)to, v, memory_order_relaxed);
}

/* A 16-byte cell into the 64-bit total (atomically: other threads may spill into it), cleared. */
static void spill16(fb_flame_cell *total, cell16 *h)
{
    for (int k = 0; k < 3; k++) add64(&total->c[k], h->c[k]);
    add64(&total->c[3], (uint64_t)OPAQUE_Q * h->hits);
    add64(&total->c[4], (uint64_t)OPAQUE_Q * h->hits);
    add64(&total->hits, h->hits);
    memset(h, 0, sizeof *h);
}

/* One batch's records: the cell of each plotted point (outside or invisible ones dropped) and its
 * colour (step mode: palette entry | visq << 8; linear mode: the point's index into pts). */
typedef struct records {
    uint32_t cell[BATCH];
    uint32_t col[BATCH];
    uint32_t n;
} records;

static void make_records(const fb_flame_setup *S, bool compact, const K_FlameChain *pts, uint32_t n, records *r)
{
    uint32_t m = 0;
    if (compact) { /* every xform visible (visq 32768), the palette entry alone: scatter16 reads no more */
        for (uint32_t t = 0; t < n; t++) {
            uint32_t cell = k_flame_cell(S->p, pts[t]);
            r->cell[m] = cell;
            r->col[m] = k_flame_index(pts[t].pc);
            m += cell != K_FLAME_NONE;
        }
        r->n = m;
        return;
    }
    for (uint32_t t = 0; t < n; t++) {
        uint32_t cell = k_flame_cell(S->p, pts[t]), visq = S->xf[pts[t].vis].visq;
        r->cell[m] = cell;
        r->col[m] = S->linear_palette ? t : k_flame_index(pts[t].pc) | visq << 8;
        m += cell != K_FLAME_NONE && visq != 0;
    }
    r->n = m;
}

static void scatter16(const fb_flame_setup *S, const records *r, cell16 *h, fb_flame_cell *total)
{
    for (uint32_t t = 0; t < r->n; t++) {
        if (t + AHEAD < r->n) __builtin_prefetch(&h[r->cell[t + AHEAD]], 1);
        cell16 *c = &h[r->cell[t]];
        const uint32_t *q = S->palq[r->col[t] & 255u];
        c->c[0] += q[0], c->c[1] += q[1], c->c[2] += q[2];
        if (++c->hits == 1u << 19) spill16(&total[r->cell[t]], c); /* 4080 x 2^19 < 2^31 */
    }
}

/* The linear palette's colour of a point (flam3's interpolation between entries, in the integer
 * steps of kernels/flame.h that the shader takes too), 2^-4 units times the opacity. */
static void linear_colour(const fb_flame_setup *S, float pc, uint32_t visq, uint32_t out[4])
{
    uint32_t i = k_flame_lin_index(pc), f = k_flame_lin_frac(pc);
    for (int k = 0; k < 4; k++) out[k] = k_flame_vis(k_flame_lerp(S->palq[i][k], S->palq[i + 1][k], f), visq);
}

static void scatter32(const fb_flame_setup *S, const records *r, const K_FlameChain *pts, fb_flame_cell32 *h,
                      fb_flame_cell *total)
{
    for (uint32_t t = 0; t < r->n; t++) {
        if (t + AHEAD < r->n) __builtin_prefetch(&h[r->cell[t + AHEAD]], 1);
        fb_flame_cell32 *c = &h[r->cell[t]];
        uint32_t add[4], visq;
        if (S->linear_palette) {
            const K_FlameChain *p = &pts[r->col[t]];
            visq = S->xf[p->vis].visq;
            linear_colour(S, p->pc, visq, add);
        } else {
            const uint32_t *q = S->palq[r->col[t] & 255u];
            visq = r->col[t] >> 8;
            for (int k = 0; k < 4; k++) add[k] = k_flame_vis(q[k], visq);
        }
        for (int k = 0; k < 4; k++) c->c[k] += add[k];
        c->c[4] += k_flame_vis(K_FLAME_OPAQUE, visq);
        c->hits++;
        if (c->c[4] >= 0x80000000u) fb_flame_spill(&total[r->cell[t]], c);
    }
}

typedef struct game {
    const fb_flame_setup *S;
    void **hist; /* one per task */
    bool compact;
    fb_flame_cell *total;
    size_t cells;
    uint64_t *bad;
    uint32_t c0, c1; /* the chains of this round */
    int ntasks;
    const uint8_t *plain;            /* plain_linear of each xform */
    const struct lane_tables *lanes; /* the AVX2 lanes' tables, or NULL: scalar chains only */
} game;

static void scatter(const game *G, int task, const K_FlameChain *pts, uint32_t n, records *rec)
{
    make_records(G->S, G->compact, pts, n, rec);
    if (G->compact)
        scatter16(G->S, rec, G->hist[task], G->total);
    else
        scatter32(G->S, rec, pts, G->hist[task], G->total);
}

/* ---- the step, with a fast path for plain linear xforms -------------------------------------- */

/* Whether xform `fn` is plain linear: its one variation `linear`, no post transform, no pre_blur. A genome's
 * symmetry xforms are (most of `gold`'s steps): they skip the variations' loop and its chain of
 * tests, which the processor mispredicts whenever the random xform choice changes kind. */
static bool plain_linear(const fb_flame_setup *S, uint32_t fn)
{
    const K_FlameXform *X = &S->xf[fn];
    return X->nvar == 1u && S->var[X->var0].id == K_V_LINEAR && !(X->flags & K_FLAME_HAS_POST) && X->preblur == 0.0f;
}

/* k_flame_apply for a plain linear xform: the same operations in the same order (so the same bits:
 * the colour, the affine map, 0 + w t as the variations' sums start at 0, the bad-value rule). */
static inline __attribute__((always_inline)) K_FlameOut apply_linear(uint fn, float x, float y, float c, uint key,
                                                                     uint n0 K_FLAME_TABLES_DECL)
{
    K_FlameXform X = k_flame_xf[fn];
    uint n = n0;
    K_FlameOut o;
    o.c = X.speed * X.color + (1.0f - X.speed) * c;
    float tx = X.ax * x + X.bx * y + X.cx;
    float ty = X.ay * x + X.by * y + X.cy;
    float w = k_flame_var[X.var0].w;
    o.x = 0.0f + w * tx;
    o.y = 0.0f + w * ty;
    o.bad = k_flame_bad(o.x) || k_flame_bad(o.y);
    if (o.bad) {
        o.x = K_FLAME_RAND() * 2.0f - 1.0f;
        o.y = K_FLAME_RAND() * 2.0f - 1.0f;
    }
    o.n = n;
    return o;
}

/* k_flame_step (kernels/flame.h) up to its plot: the xform chosen and applied (by apply_linear where
 * plain[fn] says so, by k_flame_apply otherwise), retried on bad values; line for line the same. */
static inline __attribute__((always_inline)) K_FlameChain step_xform(K_FlameParams P, K_FlameChain s, uint key,
                                                                     const uint8_t *plain K_FLAME_TABLES_DECL)
{
    uint fn = 0u;
    K_FlameOut o;
    for (uint tries = 0u; tries < 5u; tries++) {
        uint row = P.chaos != 0u ? s.last : 0u;
        fn = k_flame_dist[row * K_FLAME_GRAIN + (k_hash(s.n ^ key) & (K_FLAME_GRAIN - 1u))];
        if (plain[fn])
            o = apply_linear(fn, s.x, s.y, s.c, key, s.n + 1u K_FLAME_TABLES);
        else
            o = k_flame_apply(fn, s.x, s.y, s.c, key, s.n + 1u K_FLAME_TABLES);
        s.n = o.n;
        s.x = o.x;
        s.y = o.y;
        s.c = o.c;
        if (!o.bad) break;
        s.bad++;
    }
    s.last = fn + 1u;
    s.vis = fn;
    return s;
}

/* k_flame_step: step_xform, then the final xform and the camera for the plot (k_flame_plot). */
static inline __attribute__((always_inline)) K_FlameChain step(K_FlameParams P, K_FlameChain s, uint key,
                                                               const uint8_t *plain K_FLAME_TABLES_DECL)
{
    return k_flame_plot(P, step_xform(P, s, key, plain K_FLAME_TABLES), key K_FLAME_TABLES);
}

/* Chain i, of length len. */
static uint64_t play(const game *G, int task, uint32_t i, uint32_t len, K_FlameChain *pts, records *rec)
{
    const fb_flame_setup *S = G->S;
    const K_FlameParams P = S->p;
    const K_FlameXform *k_flame_xf = S->xf;
    const K_FlameVar *k_flame_var = S->var;
    const uint *k_flame_dist = S->dist;
    const uint8_t *plain = G->plain;
    uint32_t key = k_flame_key(P.seed, i);
    K_FlameChain s = k_flame_init(key);
    for (uint32_t t = 0; t < P.fuse; t++) s = step(P, s, key, plain K_FLAME_TABLES);
    for (uint32_t t0 = 0; t0 < len; t0 += BATCH) {
        uint32_t n = len - t0 < BATCH ? len - t0 : BATCH;
        for (uint32_t t = 0; t < n; t++) pts[t] = s = step(P, s, key, plain K_FLAME_TABLES);
        scatter(G, task, pts, n, rec);
    }
    return s.bad;
}

/* ---- chains on AVX2 lanes ---------------------------------------------------------------------- */

#if defined(__x86_64__) || defined(__i386__)
#include "flame_avx2.h"

#define LANES_AVX2 __attribute__((target("avx2")))

/* The xforms' coefficients for the lanes' gathers: colour (speed x colour and 1 - speed, the
 * products the step forms, made once), the affine map and the linear weight; plain: -1 or 0; vec:
 * whether the xform (not plain) is applied on the lanes (fl_xform_avx2). */
typedef struct lane_tables {
    float sc[FB_FLAME_MAX_XFORMS + 1], oms[FB_FLAME_MAX_XFORMS + 1];
    float ax[FB_FLAME_MAX_XFORMS + 1], bx[FB_FLAME_MAX_XFORMS + 1], cx[FB_FLAME_MAX_XFORMS + 1];
    float ay[FB_FLAME_MAX_XFORMS + 1], by[FB_FLAME_MAX_XFORMS + 1], cy[FB_FLAME_MAX_XFORMS + 1];
    float w[FB_FLAME_MAX_XFORMS + 1];
    int32_t plain[FB_FLAME_MAX_XFORMS + 1];
    uint8_t vec[FB_FLAME_MAX_XFORMS + 1];
    /* the choice table's row in ascending order of xform (as render.c builds it): the xform of an
     * entry is the number of edges (the first entry of xform k, less 1, for k = 1 .. nedge) below it,
     * compares instead of a gather */
    bool sorted;
    uint32_t nedge;
    int32_t edge[FB_FLAME_MAX_XFORMS];
    bool vfinal; /* the final xform (if any) on the lanes */
} lane_tables;

/* Whether the lanes play S: plain linear xforms or xforms of the variations flame_avx2.h has to
 * take (the other steps are the scalar step's, a lane at a time), AVX2. The xforms' tables are
 * registers of 8, looked up by permutations (AMD's gathers cost more than the scalar step saves). */
static bool lanes_ok(const fb_flame_setup *S, const uint8_t *plain)
{
    bool any = false;
    for (uint32_t f = 0; f < S->p.nxf; f++) any |= plain[f] != 0 || fl_xform_avx2(&S->xf[f], S->var);
    return any && S->p.nxf <= FB_FLAME_MAX_XFORMS && __builtin_cpu_supports("avx2");
}

static void lane_tables_init(const fb_flame_setup *S, const uint8_t *plain, lane_tables *T)
{
    memset(T, 0, sizeof *T);
    for (uint32_t f = 0; f < S->p.nxf; f++) {
        const K_FlameXform *X = &S->xf[f];
        T->sc[f] = X->speed * X->color, T->oms[f] = 1.0f - X->speed;
        T->ax[f] = X->ax, T->bx[f] = X->bx, T->cx[f] = X->cx;
        T->ay[f] = X->ay, T->by[f] = X->by, T->cy[f] = X->cy;
        T->w[f] = plain[f] ? S->var[X->var0].w : 0.0f;
        T->plain[f] = plain[f] ? -1 : 0;
        T->vec[f] = !plain[f] && fl_xform_avx2(X, S->var);
    }
    T->vfinal = S->p.final_xf != K_FLAME_NONE && fl_xform_avx2(&S->xf[S->p.final_xf], S->var);
    T->sorted = !S->p.chaos; /* xaos: a row a chain, gathered */
    for (uint32_t j = 1; j < K_FLAME_GRAIN; j++) T->sorted &= S->dist[j] >= S->dist[j - 1];
    T->nedge = S->p.nxf - 1u;
    for (uint32_t k = 1; k < S->p.nxf; k++) {
        uint32_t j = 0;
        while (j < K_FLAME_GRAIN && S->dist[j] < k) j++;
        T->edge[k - 1] = (int32_t)j - 1;
    }
}

/* k_flame_bad on the lanes: NaN or beyond +-1e10. */
LANES_AVX2 static inline __m256 bad8(__m256 v)
{
    __m256 nan = _mm256_cmp_ps(v, v, _CMP_UNORD_Q);
    __m256 hi = _mm256_cmp_ps(v, _mm256_set1_ps(1e10f), _CMP_GT_OQ);
    __m256 lo = _mm256_cmp_ps(v, _mm256_set1_ps(-1e10f), _CMP_LT_OQ);
    return _mm256_or_ps(nan, _mm256_or_ps(hi, lo));
}

/* A batch's plotted points as planes. */
typedef struct planes {
    float px[BATCH], py[BATCH], pc[BATCH];
    uint32_t vis[BATCH];
} planes;

/* make_records of a compact genome (every xform visible, step palette) from planes, eight points at a
 * time (n a multiple of 8): k_flame_cell and k_flame_index on the lanes, the same integers. */
LANES_AVX2 static void records8(const K_FlameParams *P, const planes *B, uint32_t n, records *r)
{
    const __m256 b0 = _mm256_set1_ps(P->b0), b1 = _mm256_set1_ps(P->b1), b2 = _mm256_set1_ps(P->b2),
                 b3 = _mm256_set1_ps(P->b3);
    const __m256 ws0 = _mm256_set1_ps(P->ws0), wb0s0 = _mm256_set1_ps(P->wb0s0), hs1 = _mm256_set1_ps(P->hs1),
                 hb1s1 = _mm256_set1_ps(P->hb1s1);
    const __m256i W = _mm256_set1_epi32((int)P->hist_w), H = _mm256_set1_epi32((int)P->hist_h);
    const __m256i neg1 = _mm256_set1_epi32(-1), top = _mm256_set1_epi32(255);
    uint32_t m = 0;
    for (uint32_t t = 0; t < n; t += 8) {
        __m256 px = _mm256_loadu_ps(B->px + t), py = _mm256_loadu_ps(B->py + t);
        __m256 in = _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(px, b0, _CMP_GE_OQ), _mm256_cmp_ps(py, b1, _CMP_GE_OQ)),
                                  _mm256_and_ps(_mm256_cmp_ps(px, b2, _CMP_LE_OQ), _mm256_cmp_ps(py, b3, _CMP_LE_OQ)));
        __m256i ix = _mm256_cvttps_epi32(_mm256_sub_ps(_mm256_mul_ps(ws0, px), wb0s0));
        __m256i iy = _mm256_cvttps_epi32(_mm256_sub_ps(_mm256_mul_ps(hs1, py), hb1s1));
        __m256i ok = _mm256_and_si256(_mm256_cmpgt_epi32(ix, neg1), _mm256_cmpgt_epi32(iy, neg1));
        ok = _mm256_and_si256(ok, _mm256_and_si256(_mm256_cmpgt_epi32(W, ix), _mm256_cmpgt_epi32(H, iy)));
        ok = _mm256_and_si256(ok, _mm256_castps_si256(in));
        __m256i cell = _mm256_add_epi32(_mm256_mullo_epi32(iy, W), ix);
        __m256i ci = _mm256_cvttps_epi32(_mm256_mul_ps(_mm256_loadu_ps(B->pc + t), _mm256_set1_ps(256.0f)));
        ci = _mm256_max_epi32(_mm256_min_epi32(ci, top), _mm256_setzero_si256());
        uint32_t cv[8], kv[8];
        _mm256_storeu_si256((__m256i *)cv, cell), _mm256_storeu_si256((__m256i *)kv, ci);
        unsigned valid = (unsigned)_mm256_movemask_ps(_mm256_castsi256_ps(ok));
        for (int l = 0; l < 8; l++) {
            r->cell[m] = cv[l];
            r->col[m] = kv[l];
            m += valid >> l & 1u;
        }
    }
    r->n = m;
}

/* A batch of planes scattered (n a multiple of 8): the camera's rotation (k_flame_rotate's operations
 * on the lanes), then compact genomes straight from them, the others through pts. */
LANES_AVX2 static void scatter_planes(const game *G, int task, planes *B, uint32_t n, K_FlameChain *pts, records *rec)
{
    const K_FlameParams *P = &G->S->p;
    if (P->rotate) {
        const __m256 rcx = _mm256_set1_ps(P->rcx), rcy = _mm256_set1_ps(P->rcy);
        const __m256 r00 = _mm256_set1_ps(P->rot00), r01 = _mm256_set1_ps(P->rot01);
        const __m256 r10 = _mm256_set1_ps(P->rot10), r11 = _mm256_set1_ps(P->rot11);
        for (uint32_t t = 0; t < n; t += 8) {
            __m256 qx = _mm256_sub_ps(_mm256_loadu_ps(B->px + t), rcx);
            __m256 qy = _mm256_sub_ps(_mm256_loadu_ps(B->py + t), rcy);
            _mm256_storeu_ps(B->px + t,
                             _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(qx, r00), _mm256_mul_ps(qy, r01)), rcx));
            _mm256_storeu_ps(B->py + t,
                             _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(qx, r10), _mm256_mul_ps(qy, r11)), rcy));
        }
    }
    if (G->compact) {
        records8(&G->S->p, B, n, rec);
        scatter16(G->S, rec, G->hist[task], G->total);
        return;
    }
    for (uint32_t t = 0; t < n; t++)
        pts[t].px = B->px[t], pts[t].py = B->py[t], pts[t].pc = B->pc[t], pts[t].vis = B->vis[t];
    scatter(G, task, pts, n, rec);
}

/* The final xform of one chain's step, as k_flame_plot: the opacity's draw (unless always), then the
 * xform from the chain's point into the point plotted. */
static void final_one(const fb_flame_setup *S, float x, float y, float c, uint32_t key, uint32_t *n, float *px,
                      float *py, float *pc)
{
    const K_FlameParams P = S->p;
    const K_FlameXform *k_flame_xf = S->xf;
    const K_FlameVar *k_flame_var = S->var;
    const uint *k_flame_dist = S->dist;
    bool apply = P.final_always != 0u;
    if (!apply) apply = k_flame_u01(key, (*n)++) < P.final_opacity;
    *px = x, *py = y, *pc = c;
    if (!apply) return;
    K_FlameOut f = k_flame_apply(P.final_xf, x, y, c, key, *n K_FLAME_TABLES);
    *n = f.n, *px = f.x, *py = f.y, *pc = f.c;
}

/* The final xform of a step of chains 0 .. g - 1 (their points x, y, c after the step's xform):
 * eight at a time on the lanes where vec (fl_apply8; a bad value, which takes random draws, through
 * final_one), else final_one a chain at a time. The points plotted into opx, opy, opc. */
LANES_AVX2 static void final_pass(const fb_flame_setup *S, bool vec, uint32_t g, const float *x, const float *y,
                                  const float *c, const uint32_t *key, uint32_t *n, float *opx, float *opy, float *opc)
{
    const K_FlameParams *P = &S->p;
    if (!vec) {
        for (uint32_t l = 0; l < g; l++) final_one(S, x[l], y[l], c[l], key[l], &n[l], &opx[l], &opy[l], &opc[l]);
        return;
    }
    for (uint32_t b = 0; b < g; b += 8) {
        __m256 vx = _mm256_loadu_ps(x + b), vy = _mm256_loadu_ps(y + b), vc = _mm256_loadu_ps(c + b);
        __m256i vn = _mm256_loadu_si256((const __m256i *)(n + b)),
                vkey = _mm256_loadu_si256((const __m256i *)(key + b));
        uint32_t n0[8];
        _mm256_storeu_si256((__m256i *)n0, vn);
        __m256 app = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
        if (!P->final_always) {
            app = _mm256_cmp_ps(fl_u01(vkey, vn), _mm256_set1_ps(P->final_opacity), _CMP_LT_OQ);
            vn = _mm256_add_epi32(vn, _mm256_set1_epi32(1));
        }
        fl_lanes p = {vx, vy, vc, vn};
        __m256 bad = _mm256_and_ps(fl_apply8(&S->xf[P->final_xf], S->var, vkey, &p), app);
        _mm256_storeu_ps(opx + b, _mm256_blendv_ps(vx, p.x, app));
        _mm256_storeu_ps(opy + b, _mm256_blendv_ps(vy, p.y, app));
        _mm256_storeu_ps(opc + b, _mm256_blendv_ps(vc, p.c, app));
        _mm256_storeu_si256((__m256i *)(n + b), _mm256_blendv_epi8(vn, p.n, _mm256_castps_si256(app)));
        /* a bad value (random draws) again through final_one, from the chain's counter before */
        for (unsigned m = (unsigned)_mm256_movemask_ps(bad); m; m &= m - 1u) {
            int l = __builtin_ctz(m);
            uint32_t k = b + (uint32_t)l;
            n[k] = n0[l];
            final_one(S, x[k], y[k], c[k], key[k], &n[k], &opx[k], &opy[k], &opc[k]);
        }
    }
}

/* Entry fn of a table of xforms held as registers of 8 (t[0]; t[1] and t[2] too where wide: m8 and
 * m16 mark the lanes whose fn is 8 or more, 16 or more). */
LANES_AVX2 static inline __m256 look(const __m256 *t, __m256i fn, __m256 m8, __m256 m16, bool wide)
{
    __m256 r = _mm256_permutevar8x32_ps(t[0], fn);
    if (!wide) return r;
    r = _mm256_blendv_ps(r, _mm256_permutevar8x32_ps(t[1], fn), m8);
    return _mm256_blendv_ps(r, _mm256_permutevar8x32_ps(t[2], fn), m16);
}

/* Chains i .. i + g - 1 (g a multiple of 8, at most GROUP), each of P.len points (none the last
 * chain), on the lanes. Each step: eight chains at a time, the lanes whose chosen xform is plain
 * linear and gives no bad value take apply_linear's operations (the same, in the same order: add and
 * multiply, no FMA); the chains whose xform has a form on the lanes (lane_tables.vec) are then
 * gathered eight at a time by xform and take fl_apply8 (k_flame_apply's operations); the rest, and
 * any whose result is a bad value, take the scalar step from their state before the step; then all
 * of them the final xform (final_pass), and a batch of points the camera (scatter_planes). So every
 * chain's points are the scalar path's. With xaos a chain's choice is gathered from the row of its
 * last xform. Points are scattered a batch at a time as play does (their order within a batch
 * changes no integer sum). */
LANES_AVX2 static inline __attribute__((always_inline)) uint64_t playg_body(const game *G, int task, uint32_t i,
                                                                            uint32_t g, const lane_tables *T,
                                                                            K_FlameChain *pts, records *rec,
                                                                            const bool wide)
{
    const fb_flame_setup *S = G->S;
    const K_FlameParams P = S->p;
    const K_FlameXform *k_flame_xf = S->xf;
    const K_FlameVar *k_flame_var = S->var;
    const uint *k_flame_dist = S->dist;
    const uint8_t *plain = G->plain;
    uint32_t key[GROUP];
    uint64_t bad = 0;
    /* the chains' state as planes */
    float x[GROUP], y[GROUP], c[GROUP];
    uint32_t n[GROUP], f[GROUP], last[GROUP];
    for (uint32_t l = 0; l < g; l++) {
        key[l] = k_flame_key(P.seed, i + l);
        K_FlameChain s = k_flame_init(key[l]);
        for (uint32_t t = 0; t < P.fuse; t++) s = step(P, s, key[l], plain K_FLAME_TABLES);
        bad += s.bad;
        x[l] = s.x, y[l] = s.y, c[l] = s.c, n[l] = s.n, last[l] = s.last;
    }
    const __m256i grain = _mm256_set1_epi32(K_FLAME_GRAIN - 1);
    const __m256 zero = _mm256_setzero_ps();
    /* the tables as registers of 8 xforms each (three where wide: up to 24) */
    __m256 t_sc[3], t_oms[3], t_w[3], t_ax[3], t_bx[3], t_cx[3], t_ay[3], t_by[3], t_cy[3], t_plain[3];
    for (int k = 0; k < (wide ? 3 : 1); k++) {
        t_sc[k] = _mm256_loadu_ps(T->sc + 8 * k), t_oms[k] = _mm256_loadu_ps(T->oms + 8 * k);
        t_w[k] = _mm256_loadu_ps(T->w + 8 * k), t_ax[k] = _mm256_loadu_ps(T->ax + 8 * k);
        t_bx[k] = _mm256_loadu_ps(T->bx + 8 * k), t_cx[k] = _mm256_loadu_ps(T->cx + 8 * k);
        t_ay[k] = _mm256_loadu_ps(T->ay + 8 * k), t_by[k] = _mm256_loadu_ps(T->by + 8 * k);
        t_cy[k] = _mm256_loadu_ps(T->cy + 8 * k), t_plain[k] = _mm256_loadu_ps((const float *)T->plain + 8 * k);
    }
#define LOOK(t) look(t, fn, m8, m16, wide)
    const uint32_t per = BATCH / g;
    uint32_t list[FB_FLAME_MAX_XFORMS][GROUP + 8], cnt[FB_FLAME_MAX_XFORMS], scal[GROUP];
    planes B;
    for (uint32_t t0 = 0; t0 < P.len; t0 += per) {
        uint32_t m = P.len - t0 < per ? P.len - t0 : per;
        for (uint32_t t = 0; t < m; t++) {
            float *opx = B.px + t * g, *opy = B.py + t * g, *opc = B.pc + t * g;
            uint32_t *ovis = B.vis + t * g;
            uint32_t nsc = 0;
            memset(cnt, 0, P.nxf * sizeof *cnt);
            for (uint32_t b = 0; b < g; b += 8) {
                __m256 vx = _mm256_loadu_ps(x + b), vy = _mm256_loadu_ps(y + b), vc = _mm256_loadu_ps(c + b);
                __m256i vn = _mm256_loadu_si256((const __m256i *)(n + b));
                __m256i h = fl_hash8(_mm256_xor_si256(vn, _mm256_loadu_si256((const __m256i *)(key + b))));
                __m256i at = _mm256_and_si256(h, grain), fn;
                if (T->sorted) {
                    fn = _mm256_setzero_si256();
                    for (uint32_t k = 0; k < T->nedge; k++)
                        fn = _mm256_sub_epi32(fn, _mm256_cmpgt_epi32(at, _mm256_set1_epi32(T->edge[k])));
                } else {
                    if (P.chaos) /* xaos: the row of the chain's last xform */
                        at = _mm256_add_epi32(at, _mm256_mullo_epi32(_mm256_loadu_si256((const __m256i *)(last + b)),
                                                                     _mm256_set1_epi32(K_FLAME_GRAIN)));
                    fn = _mm256_i32gather_epi32((const int *)k_flame_dist, at, 4);
                }
                __m256 m8 = _mm256_setzero_ps(), m16 = _mm256_setzero_ps();
                if (wide) {
                    m8 = _mm256_castsi256_ps(_mm256_cmpgt_epi32(fn, _mm256_set1_epi32(7)));
                    m16 = _mm256_castsi256_ps(_mm256_cmpgt_epi32(fn, _mm256_set1_epi32(15)));
                }
                __m256 ok = LOOK(t_plain);
                __m256 oc = _mm256_add_ps(LOOK(t_sc), _mm256_mul_ps(LOOK(t_oms), vc));
                __m256 tx = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(LOOK(t_ax), vx), _mm256_mul_ps(LOOK(t_bx), vy)),
                                          LOOK(t_cx));
                __m256 ty = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(LOOK(t_ay), vx), _mm256_mul_ps(LOOK(t_by), vy)),
                                          LOOK(t_cy));
                __m256 w = LOOK(t_w);
                __m256 p0 = _mm256_add_ps(zero, _mm256_mul_ps(w, tx)), p1 = _mm256_add_ps(zero, _mm256_mul_ps(w, ty));
                ok = _mm256_andnot_ps(_mm256_or_ps(bad8(p0), bad8(p1)), ok);
                vx = _mm256_blendv_ps(vx, p0, ok), vy = _mm256_blendv_ps(vy, p1, ok), vc = _mm256_blendv_ps(vc, oc, ok);
                _mm256_storeu_ps(x + b, vx), _mm256_storeu_ps(opx + b, vx);
                _mm256_storeu_ps(y + b, vy), _mm256_storeu_ps(opy + b, vy);
                _mm256_storeu_ps(c + b, vc), _mm256_storeu_ps(opc + b, vc);
                _mm256_storeu_si256((__m256i *)(n + b), _mm256_add_epi32(vn, _mm256_set1_epi32(1)));
                _mm256_storeu_si256((__m256i *)(f + b), fn);
                _mm256_storeu_si256((__m256i *)(ovis + b), fn);
                /* the other lanes (a few a step: no test a lane, which the random choice would
                 * mispredict), their state before this step kept by the blends (n was advanced
                 * above), into their xform's list or the scalar one */
                for (unsigned rest = ~(unsigned)_mm256_movemask_ps(ok) & 255u; rest; rest &= rest - 1u) {
                    uint32_t l = b + (uint32_t)__builtin_ctz(rest), fl = f[l];
                    if (T->vec[fl])
                        list[fl][cnt[fl]++] = l;
                    else
                        scal[nsc++] = l;
                }
            }
            /* the chains of each non-linear xform, eight at a time (a short last group padded with
             * its first chain, whose padding results are dropped) */
            for (uint32_t fl = 0; fl < P.nxf; fl++) {
                uint32_t k = cnt[fl];
                if (!k) continue;
                for (uint32_t j = k; j < k + 8; j++) list[fl][j] = list[fl][0];
                for (uint32_t j = 0; j < k; j += 8) {
                    __m256i vi = _mm256_loadu_si256((const __m256i *)&list[fl][j]);
                    fl_lanes p = {_mm256_i32gather_ps(x, vi, 4), _mm256_i32gather_ps(y, vi, 4),
                                  _mm256_i32gather_ps(c, vi, 4), _mm256_i32gather_epi32((const int *)n, vi, 4)};
                    __m256i vkey = _mm256_i32gather_epi32((const int *)key, vi, 4);
                    unsigned badm = (unsigned)_mm256_movemask_ps(fl_apply8(&k_flame_xf[fl], k_flame_var, vkey, &p));
                    float rx[8], ry[8], rc[8];
                    uint32_t rn[8];
                    _mm256_storeu_ps(rx, p.x), _mm256_storeu_ps(ry, p.y), _mm256_storeu_ps(rc, p.c);
                    _mm256_storeu_si256((__m256i *)rn, p.n);
                    uint32_t e = k - j < 8 ? k - j : 8;
                    for (uint32_t l = 0; l < e; l++) {
                        uint32_t ci = list[fl][j + l];
                        if (badm >> l & 1u) {
                            scal[nsc++] = ci;
                            continue;
                        }
                        x[ci] = rx[l], y[ci] = ry[l], c[ci] = rc[l], n[ci] = rn[l];
                        opx[ci] = rx[l], opy[ci] = ry[l], opc[ci] = rc[l];
                    }
                }
            }
            /* the scalar steps, each from the chain's state before this step */
            for (uint32_t q = 0; q < nsc; q++) {
                uint32_t l = scal[q];
                K_FlameChain s = {0};
                s.x = x[l], s.y = y[l], s.c = c[l];
                s.n = n[l] - 1u;
                s.last = last[l];
                s = step_xform(P, s, key[l], plain K_FLAME_TABLES);
                bad += s.bad;
                x[l] = s.x, y[l] = s.y, c[l] = s.c, n[l] = s.n;
                /* the point plotted, before the final xform and the camera */
                opx[l] = s.x, opy[l] = s.y, opc[l] = s.c, ovis[l] = s.vis;
                f[l] = s.vis; /* its xform after the retries */
            }
            for (uint32_t b = 0; P.chaos && b < g; b += 8)
                _mm256_storeu_si256(
                    (__m256i *)(last + b),
                    _mm256_add_epi32(_mm256_loadu_si256((const __m256i *)(f + b)), _mm256_set1_epi32(1)));
            if (P.final_xf != K_FLAME_NONE) final_pass(S, T->vfinal, g, x, y, c, key, n, opx, opy, opc);
        }
        scatter_planes(G, task, &B, m * g, pts, rec);
    }
#undef LOOK
    return bad;
}

/* playg_body for genomes of at most 8 xforms (one register a table) or more (three). */
LANES_AVX2 static uint64_t playg(const game *G, int task, uint32_t i, uint32_t g, const lane_tables *T,
                                 K_FlameChain *pts, records *rec)
{
    if (G->S->p.nxf <= 8) return playg_body(G, task, i, g, T, pts, rec, false);
    return playg_body(G, task, i, g, T, pts, rec, true);
}
#else
typedef struct lane_tables {
    int unused;
} lane_tables;
static bool lanes_ok(const fb_flame_setup *S, const uint8_t *plain)
{
    return false;
}
static void lane_tables_init(const fb_flame_setup *S, const uint8_t *plain, lane_tables *T) {}
static uint64_t playg(const game *G, int task, uint32_t i, uint32_t g, const lane_tables *T, K_FlameChain *pts,
                      records *rec)
{
    return 0;
}
#endif

/* Chains [c0, c1) of the round, the task's contiguous share, into its own histogram. */
static void game_task(void *ctx, int task)
{
    game *G = ctx;
    const K_FlameParams *P = &G->S->p;
    uint64_t span = G->c1 - G->c0;
    uint32_t a = G->c0 + (uint32_t)(span * (uint64_t)task / (uint64_t)G->ntasks);
    uint32_t b = G->c0 + (uint32_t)(span * (uint64_t)(task + 1) / (uint64_t)G->ntasks);
    uint64_t bad = 0;
    K_FlameChain pts[BATCH];
    records rec;
    uint32_t i = a;
    /* groups of up to GROUP chains, a multiple of 8, never the last chain (of another length) */
    while (G->lanes) {
        uint32_t g = b - i < P->chains - 1u - i ? b - i : P->chains - 1u - i;
        g = (g < GROUP ? g : GROUP) & ~7u;
        if (!g) break;
        bad += playg(G, task, i, g, G->lanes, pts, &rec);
        i += g;
    }
    for (; i < b; i++) bad += play(G, task, i, i + 1 == P->chains ? P->last_len : P->len, pts, &rec);
    G->bad[task] += bad;
}

/* The task's share of the cells of every task's histogram, folded into the total. */
static void fold_task(void *ctx, int task)
{
    game *G = ctx;
    size_t c0 = G->cells * (size_t)task / (size_t)G->ntasks, c1 = G->cells * (size_t)(task + 1) / (size_t)G->ntasks;
    for (int t = 0; t < G->ntasks; t++) {
        if (!G->compact) {
            fb_flame_hist_fold(G->total, G->hist[t], c0, c1);
            continue;
        }
        cell16 *h = G->hist[t];
        for (size_t i = c0; i < c1; i++) {
            fb_flame_cell *a = &G->total[i];
            for (int k = 0; k < 3; k++) a->c[k] += h[i].c[k];
            a->c[3] += (uint64_t)OPAQUE_Q * h[i].hits;
            a->c[4] += (uint64_t)OPAQUE_Q * h[i].hits;
            a->hits += h[i].hits;
        }
    }
}

static void run(fb_pool *pool, int threads, fb_task_fn fn, void *ctx)
{
    if (pool)
        fb_pool_run(pool, threads, fn, ctx);
    else
        fn(ctx, 0);
}

fb_result fb_flame_hists_init(fb_flame_hists *h, const fb_flame_setup *S, bool compact, fb_pool *pool, int threads,
                              fb_flame_cell *total)
{
    memset(h, 0, sizeof *h);
    h->cells = (size_t)S->p.hist_w * S->p.hist_h;
    h->compact = compact;
    size_t bytes = compact ? sizeof(cell16) : sizeof(fb_flame_cell32);
    if (threads > 64) threads = 64;
    if (!pool || threads < 1) threads = 1;
    while (threads > 1 && (uint64_t)threads * h->cells * bytes > (1ull << 30)) threads--;
    h->threads = threads, h->pool = pool, h->total = total;
    for (int t = 0; t < threads; t++)
        if (!(h->hist[t] = fb_flame_zalloc(h->cells * bytes, pool))) {
            fb_flame_hists_fini(h);
            return fb_fail(FB_ERR_NOMEM, "out of memory for the flame's histogram");
        }
    return FB_OK;
}

fb_result fb_flame_hists_play(fb_flame_hists *h, const fb_flame_setup *S, bool scalar, uint32_t cr0, uint32_t cr1,
                              fb_progress *prog)
{
    uint8_t plain[FB_FLAME_MAX_XFORMS + 1] = {0};
    for (uint32_t f = 0; f < S->p.nxf; f++) plain[f] = plain_linear(S, f);
    /* the AVX2 lanes where they apply, unless scalar */
    lane_tables tables;
    const lane_tables *lanes = NULL;
    if (!scalar && lanes_ok(S, plain)) lane_tables_init(S, plain, &tables), lanes = &tables;
    /* rounds of chains, for the progress bar; the 32-bit cells are folded once, at the end */
    uint32_t per_round = GROUP * (uint32_t)h->threads;
    double all = (double)(cr1 - cr0) * S->p.len;
    for (uint32_t c0 = cr0; c0 < cr1; c0 += per_round) {
        uint32_t c1 = cr1 - c0 > per_round ? c0 + per_round : cr1;
        game G = {S, h->hist, h->compact, h->total, h->cells, h->bad, c0, c1, h->threads, plain, lanes};
        run(h->pool, h->threads, game_task, &G);
        if (prog) fb_progress_update(prog, (uint64_t)fmin((double)(c1 - cr0) * S->p.len, all), (uint64_t)all);
    }
    return FB_OK;
}

typedef struct batch {
    game G[FB_FLAME_BATCH];
    int n;
} batch;

/* Each game of the batch in turn, the task's share of its chains (one wake-up of the pool for them
 * all). */
static void batch_task(void *ctx, int task)
{
    const batch *b = ctx;
    for (int i = 0; i < b->n; i++) game_task((void *)&b->G[i], task);
}

fb_result fb_flame_hists_play_batch(fb_flame_hists *h, const fb_flame_setup *const *S, const uint32_t (*cr)[2], int n,
                                    bool scalar)
{
    batch *b = calloc(1, sizeof *b);
    uint8_t(*plain)[FB_FLAME_MAX_XFORMS + 1] = calloc(FB_FLAME_BATCH, sizeof *plain);
    lane_tables *T = calloc(FB_FLAME_BATCH, sizeof *T);
    fb_result rc = b && plain && T ? FB_OK : fb_fail(FB_ERR_NOMEM, "out of memory");
    for (int i = 0; i < n && i < FB_FLAME_BATCH && !rc; i++) {
        for (uint32_t f = 0; f < S[i]->p.nxf; f++) plain[i][f] = plain_linear(S[i], f);
        const lane_tables *lanes = NULL;
        if (!scalar && lanes_ok(S[i], plain[i])) lane_tables_init(S[i], plain[i], &T[i]), lanes = &T[i];
        b->G[i] = (game){S[i],     h->hist,  h->compact, h->total, h->cells, h->bad,
                         cr[i][0], cr[i][1], h->threads, plain[i], lanes};
        b->n = i + 1;
    }
    if (!rc) run(h->pool, h->threads, batch_task, b);
    free(b);
    free(plain);
    free(T);
    return rc;
}

void fb_flame_hists_fold(fb_flame_hists *h, uint64_t *bad)
{
    game G = {NULL, h->hist, h->compact, h->total, h->cells, h->bad, 0, 0, h->threads};
    run(h->pool, h->threads, fold_task, &G);
    for (int t = 0; t < h->threads; t++) *bad += h->bad[t], h->bad[t] = 0;
}

void fb_flame_hists_fini(fb_flame_hists *h)
{
    for (int t = 0; t < 64; t++) free(h->hist[t]);
    memset(h, 0, sizeof *h);
}

fb_result fb_flame_play(const fb_flame_setup *S, fb_pool *pool, int threads, bool scalar, uint32_t cr0, uint32_t cr1,
                        fb_flame_cell *total, uint64_t *bad, fb_progress *prog)
{
    fb_flame_hists h;
    fb_result rc = fb_flame_hists_init(&h, S, fb_flame_cell_bytes(S) == sizeof(cell16), pool, threads, total);
    if (rc) return rc;
    rc = fb_flame_hists_play(&h, S, scalar, cr0, cr1, prog);
    if (!rc) fb_flame_hists_fold(&h, bad);
    fb_flame_hists_fini(&h);
    return rc;
}
