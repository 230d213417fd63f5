/*
 * The IFS plant generator: the chaos game of kernels/ifs.h on the GPU (shaders/ifs.comp) or on
 * the native thread pool, into integer histograms of hits and quantised colour, then box-filtered
 * to the image and tone-mapped on the host (docs/plants.md).
 *
 * Channels: NAME.count (uint hits), NAME.density (hits / plotted points per pixel), NAME.colour
 * (mean colour coordinate), NAME.R, .G, .B (premultiplied) and .A.
 */
#include "bake.h"
#include "gen_ifs.h"
#include "ifs.h"
#include "ifs_avx2.h"
#include "instances.h"
#include "lsys.h"
#include "palette.h"
#include "pool.h"
#include "progress.h"

#include "kernels/ifs.h"
#include "ifs64_comp.h"
#include "ifs_comp.h"
#include "ifs_fold_comp.h"

#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- the layer --------------------------------------------------------------------------------- */

_Static_assert(sizeof(K_IfsMap) == 32, "std430 struct of 8 words");
_Static_assert(sizeof(K_IfsChain) == 32, "std430 struct of 8 words");
_Static_assert(sizeof(K_IfsParams) == 72 && sizeof(K_IfsParams) <= FB_GEN_MAX_PUSH, "push constants");

/* Points per dispatch (all chains together): a few hundred ms on lavapipe, so that the progress bar
 * moves and no single submission runs for long. */
#define POINTS_PER_DISPATCH (1u << 25)

typedef struct ifs_state {
    K_IfsParams p;
    K_IfsMap *table; /* w1..wN, then C's maps or its segments */
    uint32_t ntable;
    uint32_t k;        /* oversampling */
    uint64_t points;   /* this bake's: all of them, or a points part's share */
    uint32_t cr0, cr1; /* the chains this bake runs: all, or a points part's range */
    bool part;         /* a points part: the colour sums are output too, for fractalbake merge */
    fb_ifs_stats stats;
    /* the image-resolution results (prepare) */
    uint32_t *count;
    float *density, *colour;
    uint64_t *sum; /* a points part: each pixel's colour sum (channels colour_sum_lo/hi) */
    fb_ifs_tone tone;
    /* plant instances (instances.h): the population's plants, and the height layer they stand on */
    fb_ifs_plant *plants;
    size_t nplants;
    const fb_gen *surface;
    int surface_plane, surface_channel;
    const fb_gen *avoid; /* the mask the plants keep away from, or NULL */
    int avoid_plane;
} ifs_state;

static ifs_state *state(const fb_gen *g)
{
    return g->owned;
}

/* ---- setup ---------------------------------------------------------------------------------- */

/* Thresholds of one map list in [lo, 2^32): map k is picked when thr_k <= r < thr_k+1. */
static void fill_table(const fb_ifs *ifs, const double *colors, uint64_t lo, K_IfsMap *out)
{
    double p[FB_IFS_MAX_MAPS], cum = 0;
    fb_ifs_probabilities(ifs, p);
    for (int k = 0; k < ifs->n; k++) {
        const fb_ifs_map *m = &ifs->m[k];
        double t = (double)lo + ((double)(1ull << 32) - (double)lo) * cum;
        uint64_t thr = t >= 4294967295.0 ? 0xffffffffu : (uint64_t)llround(t);
        out[k] = (K_IfsMap){(float)m->a, (float)m->b, (float)m->c,      (float)m->d,
                            (float)m->e, (float)m->f, (float)colors[k], (uint32_t)thr};
        cum += p[k];
    }
}

/* A bound on the attractor's distance from the origin (and of a start in [-1, 1]^2). */
static double attractor_radius(const fb_ifs *ifs)
{
    double r = 1.5;
    for (int k = 0; k < ifs->n; k++) {
        const fb_ifs_map *m = &ifs->m[k];
        double s = fb_ifs_contraction(m), t = hypot(m->e, m->f);
        double rk = t / (1 - s);
        if (rk > r) r = rk;
    }
    return r;
}

/* The frame of `auto` bounds: a short deterministic pre-run on the host (the same kernel), its
 * points' extent padded by 3% and widened to the image's aspect ratio (square units). */
static void auto_bounds(const ifs_state *st, int width, int height, double b[4])
{
    K_IfsParams p = st->p;
    const uint32_t chains = 256, steps = 2048;
    p.skip = p.skip > 200 ? p.skip : 200;
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    for (uint32_t i = 0; i < chains; i++) {
        K_IfsChain s = k_ifs_init(p, 0x80000000u + i);
        for (uint32_t t = 0; t < p.skip + steps; t++) {
            s = k_ifs_step(p, s, 0x80000000u + i, t, st->table);
            if (s.status != K_IFS_PLOT) continue;
            x0 = fmin(x0, s.x), x1 = fmax(x1, s.x), y0 = fmin(y0, s.y), y1 = fmax(y1, s.y);
        }
    }
    if (!(x1 >= x0)) x0 = -1, x1 = 1, y0 = -1, y1 = 1; /* every chain restarted: cannot happen for valid maps */
    double w = x1 - x0, h = y1 - y0, cx = (x0 + x1) / 2, cy = (y0 + y1) / 2;
    double span = fmax(w, h) * 1e-3 + 1e-9; /* a point set or a line still gets a frame */
    w = fmax(w, span) * 1.06;
    h = fmax(h, span) * 1.06;
    double aspect = (double)width / height;
    if (w / h < aspect)
        w = h * aspect;
    else
        h = w / aspect;
    b[0] = cx - w / 2, b[1] = cx + w / 2, b[2] = cy - h / 2, b[3] = cy + h / 2;
}

/* An L-system condensation set: the turtle's drawing with its start at the origin, scaled so that
 * its largest extent is cond_height, each segment as the map (u, 0) -> its point at parameter u,
 * coloured by bracket depth (0 at the base, 1 at the deepest branches). */
#define MAX_COND_SEGMENTS (1u << 20)

static fb_result lsystem_condensation(const fb_gen *g, K_IfsMap **out, uint32_t *n)
{
    const fb_ifs_params *f = fb_layer_params(g->layer);
    char who[96], *str = NULL;
    size_t len = 0, nsegs = 0;
    fb_lsys_seg *segs = NULL;
    int depth = 0;
    snprintf(who, sizeof who, "layer %s: condensation", g->layer->name);
    fb_result rc =
        fb_lsys_derive(&f->cond_sys, g->scene->seed, f->cond_max_symbols, 0, &g->run.budget, who, &str, &len);
    if (rc) return rc;
    size_t nf = 0;
    for (size_t i = 0; i < len; i++) nf += str[i] == 'F';
    if (nf == 0 || nf > MAX_COND_SEGMENTS) {
        free(str);
        return fb_fail(FB_ERR_INPUT, "%s: the L-system draws %zu segments; a condensation set needs 1 to %u", who, nf,
                       MAX_COND_SEGMENTS);
    }
    rc = fb_lsys_turtle(str, len, f->cond_sys.angle, f->cond_heading, 1.0, who, &segs, &nsegs, &depth);
    free(str);
    if (rc) return rc;
    double x0 = 0, x1 = 0, y0 = 0, y1 = 0;
    for (size_t i = 0; i < nsegs; i++) {
        x0 = fmin(x0, fmin(segs[i].x0, segs[i].x1)), x1 = fmax(x1, fmax(segs[i].x0, segs[i].x1));
        y0 = fmin(y0, fmin(segs[i].y0, segs[i].y1)), y1 = fmax(y1, fmax(segs[i].y0, segs[i].y1));
    }
    double k = f->cond_height / fmax(x1 - x0, y1 - y0);
    K_IfsMap *m = malloc(nsegs * sizeof *m);
    if (!m) {
        free(segs);
        return fb_fail(FB_ERR_NOMEM, "out of memory");
    }
    for (size_t i = 0; i < nsegs; i++) {
        const fb_lsys_seg *q = &segs[i];
        m[i] = (K_IfsMap){(float)((q->x1 - q->x0) * k),
                          0.0f,
                          (float)((q->y1 - q->y0) * k),
                          0.0f,
                          (float)(q->x0 * k),
                          (float)(q->y0 * k),
                          (float)(depth ? (double)q->depth / depth : 0.0),
                          0u};
    }
    free(segs);
    *out = m;
    *n = (uint32_t)nsegs;
    return FB_OK;
}

/* ---- the chaos game, natively --------------------------------------------------------------- */

typedef struct native_hist {
    uint32_t *hits; /* cells */
    uint64_t *sum;  /* colour sums */
} native_hist;

typedef struct native_run {
    const ifs_state *st;
    K_IfsParams p;
    K_IfsChain *chains;
    uint32_t (*counts)[4];
    native_hist *hist; /* one per task when `private`, else one shared (atomic adds) */
    bool private_hist;
    int ntasks;
} native_run;

static void native_task(void *ctx, int task)
{
    native_run *r = ctx;
    const K_IfsParams p = r->p;
    uint64_t span = r->st->cr1 - r->st->cr0;
    uint32_t c0 = r->st->cr0 + (uint32_t)(span * (uint64_t)task / (uint64_t)r->ntasks);
    uint32_t c1 = r->st->cr0 + (uint32_t)(span * (uint64_t)(task + 1) / (uint64_t)r->ntasks);
    native_hist *h = r->private_hist ? &r->hist[task] : &r->hist[0];
    for (uint32_t i = c0; i < c1; i++) {
        uint32_t total = k_ifs_total(p, i), end = total < p.step0 + p.nsteps ? total : p.step0 + p.nsteps;
        uint32_t n[4] = {0, 0, 0, 0};
        if (p.step0 < end) {
            K_IfsChain s = p.step0 == 0 ? k_ifs_init(p, i) : r->chains[i];
            for (uint32_t t = p.step0; t < end; t++) {
                s = k_ifs_step(p, s, i, t, r->st->table);
                uint32_t cell = k_ifs_target(p, s);
                n[0] += k_ifs_outside(s, cell);
                n[1] += k_ifs_discarded(s);
                n[2] += k_ifs_restarted(s);
                if (cell == K_IFS_NONE) continue;
                if (r->private_hist) {
                    h->hits[cell]++;
                    h->sum[cell] += k_ifs_quant(s.c);
                } else {
                    atomic_fetch_add_explicit((_Atomic uint32_t *)&h->hits[cell], 1u, memory_order_relaxed);
                    atomic_fetch_add_explicit((_Atomic uint64_t *)&h->sum[cell], k_ifs_quant(s.c),
                                              memory_order_relaxed);
                }
            }
            r->chains[i] = s;
        }
        memcpy(r->counts[i], n, sizeof n);
    }
}

typedef struct merge_ctx {
    native_hist *hist;
    int nhist;
    size_t cells;
    int ntasks;
} merge_ctx;

static void merge_task(void *ctx, int task)
{
    merge_ctx *m = ctx;
    size_t c0 = m->cells * (size_t)task / (size_t)m->ntasks, c1 = m->cells * (size_t)(task + 1) / (size_t)m->ntasks;
    for (int h = 1; h < m->nhist; h++)
        for (size_t c = c0; c < c1; c++) {
            m->hist[0].hits[c] += m->hist[h].hits[c];
            m->hist[0].sum[c] += m->hist[h].sum[c];
        }
}

/* ---- from histogram cells to image pixels ----------------------------------------------------- */

/* A histogram in whichever layout a backend left it: the hits and the colour sum of a cell. */
typedef struct cells_view {
    const uint32_t *hits;    /* 32-bit layouts (with packed: the folded totals, or NULL) */
    const uint64_t *sum;     /* native: the colour sums */
    const uint32_t *lo, *hi; /* vulkan: colour sum words */
    const uint64_t *packed;  /* vulkan, 64-bit atomics: hits | colour sum << K_IFS_HIT_BITS since the last fold */
} cells_view;

static inline void cell_at(const cells_view *v, size_t cell, uint64_t *hits, uint64_t *sum)
{
    if (v->packed) {
        uint64_t x = v->packed[cell];
        *hits = (x & K_IFS_HIT_MASK) + (v->hits ? v->hits[cell] : 0);
        *sum = (x >> K_IFS_HIT_BITS) + (v->hits ? (uint64_t)v->hi[cell] << 32 | v->lo[cell] : 0);
    } else {
        *hits = v->hits[cell];
        *sum = v->sum ? v->sum[cell] : (uint64_t)v->hi[cell] << 32 | v->lo[cell];
    }
}

/* Count, mean colour and density of every pixel from its hits and colour sum (also what merge
 * calls, with the points parts' sums added). */
static fb_result finish_pixels(ifs_state *st, size_t n, const uint64_t *hits, const uint64_t *sums)
{
    st->count = malloc(n * sizeof *st->count);
    st->density = malloc(n * sizeof *st->density);
    st->colour = malloc(n * sizeof *st->colour);
    if (!st->count || !st->density || !st->colour) return fb_fail(FB_ERR_NOMEM, "out of memory for the plant layer");
    uint64_t total = 0;
    for (size_t at = 0; at < n; at++) {
        uint64_t c = hits[at], sm = sums[at];
        total += c;
        if (c > 0xffffffffu) {
            st->stats.saturated++;
            c = 0xffffffffu;
        }
        st->count[at] = (uint32_t)c;
        st->colour[at] = c ? (float)((double)sm / (255.0 * (double)c)) : 0.0f;
    }
    st->stats.hits = total;
    /* density: hits per pixel relative to the plotted points spread evenly over the frame */
    uint64_t plotted = st->stats.hits + st->stats.outside;
    double inv_mean = plotted ? (double)n / (double)plotted : 0;
    for (size_t i = 0; i < n; i++) st->density[i] = (float)(st->count[i] * inv_mean);
    st->tone.dref = fb_ifs_density_ref(st->density, n);
    return FB_OK;
}

/* Sums the K x K cells of each pixel. */
static fb_result reduce(ifs_state *st, int width, int height, const cells_view *view)
{
    size_t n = (size_t)width * height;
    uint32_t k = st->k, hw = st->p.hist_w;
    uint64_t *hits = malloc(n * sizeof *hits), *sums = malloc(n * sizeof *sums);
    if (!hits || !sums) {
        free(hits);
        free(sums);
        return fb_fail(FB_ERR_NOMEM, "out of memory for the plant layer");
    }
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++) {
            uint64_t c = 0, sm = 0;
            for (uint32_t j = 0; j < k; j++)
                for (uint32_t i = 0; i < k; i++) {
                    size_t cell = ((size_t)y * k + j) * hw + (size_t)x * k + i;
                    uint64_t hc, sc;
                    cell_at(view, cell, &hc, &sc);
                    c += hc;
                    sm += sc;
                }
            hits[(size_t)y * width + x] = c;
            sums[(size_t)y * width + x] = sm;
        }
    fb_result rc = finish_pixels(st, n, hits, sums);
    free(hits);
    if (st->part && !rc)
        st->sum = sums;
    else
        free(sums);
    return rc;
}

fb_result fb_gen_ifs_from_sums(fb_gen *g, const uint64_t *hits, const uint64_t *sums, uint64_t outside)
{
    ifs_state *st = state(g);
    st->stats.outside = outside;
    return finish_pixels(st, (size_t)g->scene->width * g->scene->height, hits, sums);
}

/* ---- prepare: the whole chaos game ------------------------------------------------------------ */

static uint32_t max_total(const K_IfsParams *p)
{
    return p->base + (p->extra ? 1u : 0u);
}

static void add_counts(ifs_state *st, const uint32_t (*counts)[4])
{
    for (uint32_t i = st->cr0; i < st->cr1; i++) {
        st->stats.outside += counts[i][0];
        st->stats.discarded += counts[i][1];
        st->stats.restarts += counts[i][2];
    }
}

typedef struct avx2_round {
    const ifs_state *st;
    native_hist *hist;
    K_IfsChain *chains;
    uint32_t t0, t1;
    int ntasks;
    uint64_t counts[64][3];
} avx2_round;

/* One task's share of a round: a contiguous run of chains (a multiple of 16, the loop's vector
 * width) for the round's steps, into the task's own histogram. */
static void avx2_task(void *ctx, int task)
{
    avx2_round *r = ctx;
    uint64_t span = r->st->cr1 - r->st->cr0, per = (span / (uint64_t)r->ntasks + 15) / 16 * 16;
    uint64_t c0 = r->st->cr0 + per * (uint64_t)task, c1 = c0 + per;
    if (c1 > r->st->cr1) c1 = r->st->cr1;
    if (c0 < c1)
        fb_ifs_avx2_chains(&r->st->p, r->st->table, (uint32_t)c0, (uint32_t)c1, r->t0, r->t1, r->chains,
                           r->hist[task].hits, r->hist[task].sum, r->counts[task]);
}

static fb_result prepare_native(fb_gen *g, fb_engine *e, fb_progress *prog)
{
    ifs_state *st = state(g);
    const fb_scene *s = g->scene;
    size_t cells = (size_t)st->p.hist_w * st->p.hist_h;
    int threads = e->pool ? fb_pool_threads(e->pool) : 1;
    if (threads > 64) threads = 64;
    /* Private histograms per task (plain adds) when they fit in 1 GiB, else one with atomic adds:
     * the sums, and so the result, are the same either way. */
    bool priv = threads > 1 && (uint64_t)threads * cells * 12 <= (1ull << 30);
    int nhist = priv ? threads : 1;
    native_hist *hist = calloc((size_t)nhist, sizeof *hist);
    K_IfsChain *chains = malloc(st->p.chains * sizeof *chains);
    uint32_t(*counts)[4] = malloc(st->p.chains * sizeof *counts);
    fb_result rc = FB_OK;
    if (!hist || !chains || !counts) rc = fb_fail(FB_ERR_NOMEM, "out of memory for the chaos game");
    for (int h = 0; h < nhist && !rc; h++) {
        hist[h].hits = calloc(cells, sizeof *hist[h].hits);
        hist[h].sum = calloc(cells, sizeof *hist[h].sum);
        if (!hist[h].hits || !hist[h].sum) rc = fb_fail(FB_ERR_NOMEM, "out of memory for the histogram");
    }
    native_run run = {.st = st,
                      .p = st->p,
                      .chains = chains,
                      .counts = counts,
                      .hist = hist,
                      .private_hist = priv,
                      .ntasks = priv ? threads : threads * 8};
    uint32_t last = max_total(&st->p);
    double t0 = fb_now();
    /* The hand-vectorised loop (bit-exact with the kernel, tests/test_avx2.c) where it applies: one
     * task per histogram, in rounds of the dispatch's steps (POINTS_PER_DISPATCH points, a fraction
     * of a second) so that the bar moves at any point count. */
    bool avx2 = !rc && !g->run.scalar && (priv || threads == 1) && fb_ifs_avx2_supported(&st->p);
    for (uint32_t step0 = 0; avx2 && step0 < last; step0 += st->p.nsteps) {
        uint32_t t1 = last - step0 > st->p.nsteps ? step0 + st->p.nsteps : last;
        avx2_round r = {st, hist, chains, step0, t1, nhist, {{0}}};
        if (e->pool)
            fb_pool_run(e->pool, nhist, avx2_task, &r);
        else
            avx2_task(&r, 0);
        for (int t = 0; t < nhist; t++) {
            st->stats.outside += r.counts[t][0];
            st->stats.discarded += r.counts[t][1];
            st->stats.restarts += r.counts[t][2];
        }
        uint64_t done = (uint64_t)t1 * (st->cr1 - st->cr0);
        fb_progress_update(prog, done < st->points ? done : st->points, st->points);
    }
    for (uint32_t step0 = 0; !avx2 && step0 < last && !rc; step0 += st->p.nsteps) {
        run.p.step0 = step0;
        if (e->pool)
            fb_pool_run(e->pool, run.ntasks, native_task, &run);
        else
            for (int t = 0; t < run.ntasks; t++) native_task(&run, t);
        add_counts(st, (const uint32_t(*)[4])counts);
        uint64_t done = (uint64_t)(step0 + st->p.nsteps < last ? step0 + st->p.nsteps : last) * (st->cr1 - st->cr0);
        fb_progress_update(prog, done < st->points ? done : st->points, st->points);
    }
    if (!rc && nhist > 1) {
        merge_ctx m = {hist, nhist, cells, threads * 4};
        fb_pool_run(e->pool, m.ntasks, merge_task, &m);
    }
    st->stats.game_seconds = fb_now() - t0;
    if (!rc) rc = reduce(st, s->width, s->height, &(cells_view){.hits = hist[0].hits, .sum = hist[0].sum});
    for (int h = 0; hist && h < nhist; h++) {
        free(hist[h].hits);
        free(hist[h].sum);
    }
    free(hist);
    free(chains);
    free(counts);
    return rc;
}

enum { B_MAPS, B_CHAINS, B_COUNTS, B_HITS, B_LO, B_HI, NBUF };
enum { F_HITS, F_LO, F_HI, F_FLAGS, NFOLD }; /* the folded totals of the 64-bit histogram */

/* The points one fold interval of the 64-bit histogram may take (kernels/ifs.h). */
#define FOLD_POINTS ((1ull << K_IFS_HIT_BITS) - 1)

/* One 64-bit atomic a point where the device has them, the packed histogram fits one buffer and a
 * dispatch of one step a chain fits a fold interval; else two 32-bit ones and a carry. The sums, and
 * so the result, are the same. */
static bool wide_histogram(const ifs_state *st, vkc_context *vk)
{
    uint64_t cells = (uint64_t)st->p.hist_w * st->p.hist_h;
    return vkc_info(vk)->int64_atomics && cells * 8 <= vkc_info(vk)->max_storage_buffer_range &&
           st->cr1 - st->cr0 <= FOLD_POINTS;
}

/* The 64-bit histogram is folded into totals when the run plays more points than a fold interval. */
static bool folds(const ifs_state *st)
{
    return st->points > FOLD_POINTS;
}

/* Steps a chain per dispatch: on a CPU device a few hundred ms (POINTS_PER_DISPATCH, init's); on a
 * GPU as many as a fold interval holds (2^28 points: milliseconds), since each job's end costs a
 * round trip and, on a discrete GPU, vkc's copy of its buffers back to the host. */
static uint32_t steps_per_dispatch(const ifs_state *st, const vkc_context *vk)
{
    if (!strcmp(vkc_info(vk)->type, "cpu")) return st->p.nsteps;
    uint64_t n = FOLD_POINTS / (st->cr1 > st->cr0 ? st->cr1 - st->cr0 : 1); /* < 2^28 */
    return n > st->p.nsteps ? (uint32_t)n : st->p.nsteps;
}

uint32_t fb_ifs_steps_per_dispatch(const fb_gen *g, const vkc_context *vk)
{
    return steps_per_dispatch(state(g), vk);
}

/* Adds the 64-bit cells into the totals and clears them (shaders/ifs_fold.comp). */
static fb_result fold(vkc_context *vk, vkc_pipeline *pipe, vkc_buffer *packed, vkc_buffer *const *totals, size_t cells,
                      double *gpu_seconds)
{
    vkc_job *job = NULL;
    fb_result rc = vkc_job_create(vk, pipe, &job);
    uint64_t groups = (cells + 63) / 64, gx = groups < 65535 ? groups : 65535;
    struct {
        uint32_t cells, stride;
    } push = {(uint32_t)cells, (uint32_t)gx * 64};
    vkc_buffer *bufs[1 + NFOLD] = {packed, totals[F_HITS], totals[F_LO], totals[F_HI], totals[F_FLAGS]};
    double t = -1;
    if (!rc) rc = vkc_job_submit(vk, job, bufs, 1 + NFOLD, &push, (const uint32_t[3]){gx, (groups + gx - 1) / gx, 1});
    if (!rc) rc = vkc_job_wait(vk, job, &t);
    if (t > 0) *gpu_seconds += t;
    vkc_job_destroy(vk, &job);
    return rc;
}

static fb_result prepare_vulkan(fb_gen *g, fb_engine *e, fb_progress *prog, double *gpu_seconds)
{
    ifs_state *st = state(g);
    vkc_context *vk = e->vk;
    size_t cells = (size_t)st->p.hist_w * st->p.hist_h;
    uint64_t range = vkc_info(vk)->max_storage_buffer_range;
    bool wide = wide_histogram(st, vk), folding = wide && folds(st);
    if ((uint64_t)cells * 4 > range)
        return fb_fail(FB_ERR_INPUT,
                       "layer %s: a histogram of %zu cells needs %zu MiB per buffer; this device allows %llu MiB "
                       "(lower --oversample or the size, or use --backend native)",
                       g->layer->name, cells, cells * 4 >> 20, (unsigned long long)(range >> 20));
    vkc_pipeline *pipe = NULL, *fold_pipe = NULL;
    vkc_job *job = NULL;
    vkc_buffer *buf[NBUF] = {0}, *tot[NFOLD] = {0};
    uint32_t spec[1] = {st->p.cmaps > 0};
    fb_result rc = vkc_pipeline_create(vk,
                                       &(vkc_pipeline_desc){.spv = wide ? ifs64_comp : ifs_comp,
                                                            .spv_size = wide ? sizeof ifs64_comp : sizeof ifs_comp,
                                                            .push_size = sizeof(K_IfsParams),
                                                            .buffers = NBUF,
                                                            .spec = spec,
                                                            .nspec = 1,
                                                            .name = g->layer->name},
                                       &pipe);
    /* wide: the packed cells, and two unused bindings */
    const uint64_t sizes[NBUF] = {sizeof(K_IfsMap) * st->ntable, sizeof(K_IfsChain) * (uint64_t)st->p.chains,
                                  16ull * st->p.chains,          (wide ? 8ull : 4ull) * cells,
                                  wide ? 16ull : 4ull * cells,   wide ? 16ull : 4ull * cells};
    for (int b = 0; b < NBUF && !rc; b++) rc = vkc_buffer_create(vk, sizes[b], &buf[b]);
    for (int b = 0; b < NFOLD && folding && !rc; b++)
        rc = vkc_buffer_create(vk, b == F_FLAGS ? 16 : 4ull * cells, &tot[b]);
    if (!rc && folding)
        rc = vkc_pipeline_create(
            vk,
            &(vkc_pipeline_desc){FB_SPV(ifs_fold_comp), .push_size = 8, .buffers = 1 + NFOLD, .name = g->layer->name},
            &fold_pipe);
    if (!rc) rc = vkc_buffer_upload(vk, buf[B_MAPS], st->table, sizes[B_MAPS]);
    void *zero = rc ? NULL : calloc(cells, wide ? 8 : 4);
    if (!rc && !zero) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    for (int b = B_HITS; b <= B_HI && !rc; b++) rc = vkc_buffer_upload(vk, buf[b], zero, sizes[b]);
    for (int b = 0; b < NFOLD && folding && !rc; b++)
        rc = vkc_buffer_upload(vk, tot[b], zero, b == F_FLAGS ? 16 : 4ull * cells);
    free(zero);
    if (!rc) rc = vkc_job_create(vk, pipe, &job);
    /* a job of no steps first: the uploads above, outside the game's timestamps */
    K_IfsParams p0 = st->p;
    p0.nsteps = 0;
    if (!rc) rc = vkc_job_submit(vk, job, buf, NBUF, &p0, (const uint32_t[3]){(st->cr1 + 63) / 64, 1, 1});
    if (!rc) rc = vkc_job_wait(vk, job, NULL);
    uint32_t last = max_total(&st->p), nsteps = steps_per_dispatch(st, vk);
    uint64_t since = 0, per = (uint64_t)(st->cr1 - st->cr0) * nsteps; /* points since the last fold, a dispatch's */
    double t0 = fb_now();
    for (uint32_t step0 = 0; step0 < last && !rc; step0 += nsteps) {
        K_IfsParams p = st->p;
        p.step0 = step0;
        p.nsteps = nsteps;
        p.chain0 = st->cr0;
        if (folding && since + per > FOLD_POINTS) {
            rc = fold(vk, fold_pipe, buf[B_HITS], tot, cells, gpu_seconds);
            since = 0;
        }
        uint32_t groups[3] = {(st->cr1 + 63) / 64, 1, 1};
        double t = -1;
        if (!rc) rc = vkc_job_submit(vk, job, buf, NBUF, &p, groups);
        if (!rc) rc = vkc_job_wait(vk, job, &t);
        if (t > 0) *gpu_seconds += t;
        since += per;
        if (!rc) add_counts(st, vkc_buffer_data(buf[B_COUNTS]));
        uint64_t done = (uint64_t)(last - step0 > nsteps ? step0 + nsteps : last) * (st->cr1 - st->cr0);
        fb_progress_update(prog, done < st->points ? done : st->points, st->points);
    }
    st->stats.game_seconds = fb_now() - t0;
    if (!rc) {
        cells_view v = {
            .hits = vkc_buffer_data(buf[B_HITS]), .lo = vkc_buffer_data(buf[B_LO]), .hi = vkc_buffer_data(buf[B_HI])};
        if (wide) {
            v = (cells_view){.packed = vkc_buffer_data(buf[B_HITS])};
            if (folding) {
                v.hits = vkc_buffer_data(tot[F_HITS]), v.lo = vkc_buffer_data(tot[F_LO]),
                v.hi = vkc_buffer_data(tot[F_HI]);
                if (*(const uint32_t *)vkc_buffer_data(tot[F_FLAGS])) st->stats.saturated++;
            }
        }
        rc = reduce(st, g->scene->width, g->scene->height, &v);
    }
    vkc_job_destroy(vk, &job);
    for (int b = 0; b < NBUF; b++) vkc_buffer_destroy(vk, &buf[b]);
    for (int b = 0; b < NFOLD; b++) vkc_buffer_destroy(vk, &tot[b]);
    vkc_pipeline_destroy(vk, &pipe);
    vkc_pipeline_destroy(vk, &fold_pipe);
    return rc;
}

/* ---- plant instances --------------------------------------------------------------------------- */

/* The population's plants at least instances-min-size pixels tall, in the frame (init). */
static fb_result enumerate_plants(const fb_gen *g, ifs_state *st)
{
    const fb_ifs_params *f = fb_layer_params(g->layer);
    const double *b = st->stats.bounds;
    double cond = f->cond_lsys ? f->cond_height : fb_ifs_cond_extent(&f->cond, g->scene->seed);
    double px = sqrt(g->scene->width / (b[1] - b[0]) * (g->scene->height / (b[3] - b[2]))); /* pixels a unit */
    return fb_ifs_plants(&f->maps, cond, b, f->inst_min_pixels / px, &st->plants, &st->nplants);
}

/* A float channel of a layer with native rows, for the instances: the height layer they stand on, or
 * the mask they keep away from. */
static fb_result instance_source(fb_gen *g, const fb_gen *const *gens, const fb_ref *r, const char *key,
                                 const char *kind, const fb_gen **src, int *channel)
{
    const fb_gen *l = gens[r->layer];
    int c = fb_gen_channel_of(l, r->channel, g->layer->name, key);
    if (c < 0) return FB_ERR_INPUT;
    if (l->compute.host_rows || !l->compute.native_rows || l->store.channel_types[c] == EXRIO_UINT)
        return fb_fail(FB_ERR_INPUT, "layer %s: %s %s is %s; name %s", g->layer->name, key, l->store.channel_names[c],
                       l->compute.host_rows ? "an op layer, computed strip by strip" : "not a height", kind);
    *src = l, *channel = c;
    return FB_OK;
}

static fb_result ifs_resolve(fb_gen *g, const fb_gen *const *gens, const int *plane_offset)
{
    (void)plane_offset;
    const fb_ifs_params *f = fb_layer_params(g->layer);
    ifs_state *st = state(g);
    fb_result rc = FB_OK;
    int c;
    if (f->has_surface && f->surface.layer >= 0 &&
        !(rc = instance_source(g, gens, &f->surface, "instances-surface",
                               "a height layer (terrain, fbm, constrain, rivers...)", &st->surface, &c)))
        st->surface_plane = fb_gen_plane_of(st->surface, c), st->surface_channel = c;
    if (!rc && f->has_avoid &&
        !(rc = instance_source(g, gens, &f->avoid, "instances-avoid", "a mask (rivers.river...)", &st->avoid, &c)))
        st->avoid_plane = fb_gen_plane_of(st->avoid, c);
    return rc;
}

/* Writes the instances (prepare, after the surface's own prepare: layers prepare in dependency order). */
static fb_result write_instances(fb_gen *g)
{
    const fb_ifs_params *f = fb_layer_params(g->layer);
    const ifs_state *st = state(g);
    if (!f->instances[0]) return FB_OK;
    fb_ifs_place pl = {.width = g->scene->width,
                       .height = g->scene->height,
                       .src = st->surface,
                       .plane = st->surface_plane,
                       .constant = f->has_surface && f->surface.layer < 0 ? f->surface.value : 0,
                       .up = f->inst_up,
                       .seed = g->scene->seed,
                       .max_slope = f->max_slope,
                       .avoid = st->avoid,
                       .avoid_plane = st->avoid_plane,
                       .avoid_distance = f->avoid_distance};
    memcpy(pl.frame, st->stats.bounds, sizeof pl.frame);
    if (st->surface && st->surface->prepared.has_world)
        pl.has_world = true, memcpy(pl.world, st->surface->prepared.world, sizeof pl.world);
    size_t written, skipped, avoided;
    fb_result rc = fb_ifs_write_instances(f->instances, &pl, st->plants, st->nplants, &written, &skipped, &avoided);
    if (rc) return rc;
    snprintf(g->prepared.summary, sizeof g->prepared.summary, "layer %s (ifs): %zu plant instances in %.200s%s%.80s%s",
             g->layer->name, written, f->instances, st->surface ? " on " : "",
             st->surface ? st->surface->store.channel_names[st->surface_channel] : "",
             avoided ? " (others left out by slope or mask)" : "");
    snprintf(g->prepared.summary_json, sizeof g->prepared.summary_json,
             "{\"layer\": \"%s\", \"generator\": \"ifs\", \"instances\": %zu, \"instances_left_out\": %zu, "
             "\"instances_avoided\": %zu}",
             g->layer->name, written, skipped, avoided);
    if (skipped)
        fb_log(FB_LOG_WARN, "%s: %zu plants stand where %s has no height (NaN) and are not written", g->layer->name,
               skipped, st->surface->store.channel_names[st->surface_channel]);
    return FB_OK;
}

static fb_result ifs_prepare(fb_gen *g, fb_engine *e, bool progress)
{
    ifs_state *st = state(g);
    fb_progress prog;
    char label[96];
    snprintf(label, sizeof label, "%s: chaos game", g->layer->name);
    fb_progress_init(&prog, progress, label, "pts");
    double t0 = fb_now(), gpu = -1;
    /* the run's counters start at zero; the frame, chains and skip chosen at init stay */
    fb_ifs_stats *x0 = &st->stats;
    x0->hits = x0->outside = x0->discarded = x0->restarts = x0->saturated = 0;
    x0->points = st->points;
    fb_result rc =
        e->kind == FB_BACKEND_VULKAN ? (gpu = 0, prepare_vulkan(g, e, &prog, &gpu)) : prepare_native(g, e, &prog);
    fb_progress_finish(&prog);
    st->stats.seconds = fb_now() - t0;
    st->stats.gpu_seconds = gpu;
    g->prepared.gpu_seconds = gpu;
    if (rc) return rc;
    const fb_ifs_stats *x = &st->stats;
    g->prepared.points_split = true; /* a game that render --points-part splits; merge needs its outside count */
    g->prepared.points_outside = x->outside;
    fb_log(FB_LOG_INFO,
           "%s: %llu points: %llu hits, %llu outside the frame, %llu discarded (transient), %llu restarts, %.3g "
           "Mpts/s",
           g->layer->name, (unsigned long long)x->points, (unsigned long long)x->hits, (unsigned long long)x->outside,
           (unsigned long long)x->discarded, (unsigned long long)x->restarts, (double)x->points / x->seconds * 1e-6);
    if (x->restarts)
        fb_log(FB_LOG_WARN, "%s: %llu chains left the finite range and were restarted", g->layer->name,
               (unsigned long long)x->restarts);
    if (x->saturated)
        fb_log(FB_LOG_WARN, "%s: %llu pixels had more than 2^32 hits; their count is saturated", g->layer->name,
               (unsigned long long)x->saturated);
    return write_instances(g);
}

/* ---- rows ------------------------------------------------------------------------------------- */

static void ifs_rows(const fb_gen *g, int y0, int n, void *const *planes)
{
    const ifs_state *st = state(g);
    size_t w = (size_t)g->scene->width, at = (size_t)y0 * w, len = (size_t)n * w;
    memcpy(planes[0], st->count + at, len * 4);
    memcpy(planes[1], st->density + at, len * 4);
    memcpy(planes[2], st->colour + at, len * 4);
    fb_ifs_tonemap_row(&st->tone, st->density + at, st->colour + at, len, planes[3], planes[4], planes[5], planes[6]);
    if (g->store.nchannels > 7) /* a points part: the colour sums, split into two uint words */
        for (size_t i = 0; i < len; i++) {
            uint64_t v = st->sum ? st->sum[at + i] : 0;
            ((uint32_t *)planes[7])[i] = (uint32_t)v;
            ((uint32_t *)planes[8])[i] = (uint32_t)(v >> 32);
        }
}

static void ifs_fini(fb_gen *g)
{
    ifs_state *st = state(g);
    if (!st) return;
    free(st->count);
    free(st->density);
    free(st->colour);
    free(st->sum);
    free(st->table);
    free(st->plants);
}

const fb_ifs_stats *fb_gen_ifs_stats(const fb_gen *g)
{
    return g->layer->cls == &fb_gen_ifs && g->owned ? &state(g)->stats : NULL;
}

/* The chaos game's memory: its histogram (12 bytes a cell: hits and colour sums; one per thread
 * where they fit in 1 GiB, as prepare_native decides; on a device with 64-bit atomics 8, and 12 more
 * for the totals when the run folds), the chains' state, and the reduction to pixels (16 bytes a
 * pixel, then the 12 kept: count, density, colour; 8 more for a points part). */
static uint64_t ifs_memory(const fb_gen *g, const struct fb_engine *e, uint64_t *hold)
{
    const ifs_state *st = state(g);
    uint64_t cells = (uint64_t)st->p.hist_w * st->p.hist_h, n = (uint64_t)g->scene->width * g->scene->height;
    uint64_t keep = 12 * n + (st->part ? 8 * n : 0), hist;
    if (e->kind == FB_BACKEND_VULKAN) {
        bool wide = e->vk && wide_histogram(st, e->vk);
        hist = (wide ? 8 + (folds(st) ? 12 : 0) : 12) * cells + 48ull * st->p.chains;
    } else {
        int threads = e->pool ? fb_pool_threads(e->pool) : 1;
        if (threads > 64) threads = 64;
        bool priv = threads > 1 && (uint64_t)threads * cells * 12 <= (1ull << 30);
        hist = (priv ? (uint64_t)threads : 1) * cells * 12 + 48ull * st->p.chains;
    }
    *hold = keep + 40 * (uint64_t)st->nplants;                 /* the plants */
    return hist + 16 * n + keep + 120 * (uint64_t)st->nplants; /* ... their instances as they are written */
}

static fb_result ifs_init(fb_gen *g)
{
    const fb_scene *s = g->scene;
    const fb_ifs_params *f = fb_layer_params(g->layer);
    ifs_state *st = calloc(1, sizeof *st);
    if (!st) return fb_fail(FB_ERR_NOMEM, "out of memory");
    g->owned = st;
    g->fini = ifs_fini;
    K_IfsParams *p = &st->p;
    st->k = (uint32_t)f->oversample;
    p->seed = s->seed;
    p->nmaps = (uint32_t)f->maps.n;
    bool cond_ifs = f->has_cond && !f->cond_lsys;
    p->cmaps = cond_ifs ? (uint32_t)f->cond.n : 0u;
    K_IfsMap *segs = NULL;
    if (f->cond_lsys) {
        fb_result rc = lsystem_condensation(g, &segs, &p->csegs);
        if (rc) return rc;
    }
    uint64_t lo = f->has_cond ? (uint64_t)llround(f->cond_p * 4294967296.0) : 0;
    if (lo > 0xffffffffu) lo = 0xffffffffu;
    st->ntable = p->nmaps + p->cmaps + p->csegs;
    st->table = calloc(st->ntable, sizeof *st->table);
    if (!st->table) {
        free(segs);
        return fb_fail(FB_ERR_NOMEM, "out of memory");
    }
    fill_table(&f->maps, f->colors, lo, st->table);
    if (cond_ifs) fill_table(&f->cond, f->cond_colors, 0, st->table + p->nmaps);
    if (p->csegs) memcpy(st->table + p->nmaps, segs, p->csegs * sizeof *segs);
    free(segs);
    st->table[0].thr = (uint32_t)lo; /* below it: the condensation map w0 */
    p->skip = (uint32_t)(f->skip ? f->skip : fb_ifs_auto_skip(&f->maps));
    if (cond_ifs && !f->skip) {
        uint32_t cs = (uint32_t)fb_ifs_auto_skip(&f->cond);
        if (cs > p->skip) p->skip = cs;
    }
    double radius = attractor_radius(&f->maps);
    if (cond_ifs) radius += attractor_radius(&f->cond);
    if (f->cond_lsys) radius += f->cond_height * 1.5;
    p->limit = (float)(radius * 1e3);
    p->hist_w = (uint32_t)s->width * st->k;
    p->hist_h = (uint32_t)s->height * st->k;

    uint64_t cells = (uint64_t)p->hist_w * p->hist_h;
    st->points = f->points > 0 ? (uint64_t)f->points : 64 * cells;
    uint64_t chains = (uint64_t)f->chains;
    if (!chains) {
        chains = st->points / (32ull * (p->skip ? p->skip : 1));
        chains = chains > 65536 ? 65536 : chains >= 64 ? chains - chains % 64 : chains ? chains : 1;
    }
    if (st->points / chains >= (1ull << 31))
        return fb_fail(FB_ERR_INPUT,
                       "layer %s: %llu points over %llu chains is more than 2^31 steps per chain; use "
                       "more chains",
                       g->layer->name, (unsigned long long)st->points, (unsigned long long)chains);
    p->chains = (uint32_t)chains;
    p->base = (uint32_t)(st->points / chains);
    p->extra = (uint32_t)(st->points % chains);
    p->nsteps = POINTS_PER_DISPATCH / p->chains ? POINTS_PER_DISPATCH / p->chains : 1;
    /* A points part K of N runs the K-th share of the chains, cut at multiples of 64 (a workgroup):
     * the parts' histograms add up to the whole game's exactly. */
    st->cr0 = 0, st->cr1 = p->chains;
    st->part = g->run.points_part[1] > 0;
    if (st->part) {
        uint64_t groups = (p->chains + 63) / 64, k = (uint64_t)g->run.points_part[0],
                 parts = (uint64_t)g->run.points_part[1];
        uint64_t c0 = groups * (k - 1) / parts * 64, c1 = groups * k / parts * 64;
        st->cr0 = (uint32_t)(c0 < p->chains ? c0 : p->chains);
        st->cr1 = (uint32_t)(c1 < p->chains ? c1 : p->chains);
        uint64_t extra = p->extra > st->cr0 ? (p->extra < st->cr1 ? p->extra : st->cr1) - st->cr0 : 0;
        st->points = (uint64_t)(st->cr1 - st->cr0) * p->base + extra;
    }

    double b[4];
    if (f->auto_bounds)
        auto_bounds(st, s->width, s->height, b);
    else
        memcpy(b, f->bounds, sizeof b);
    st->stats.bounds[0] = b[0], st->stats.bounds[1] = b[1], st->stats.bounds[2] = b[2], st->stats.bounds[3] = b[3];
    p->x0 = (float)b[0];
    p->y0 = (float)b[3];
    p->sx = (float)(p->hist_w / (b[1] - b[0]));
    p->sy = (float)(p->hist_h / (b[3] - b[2]));
    st->stats.chains = p->chains;
    st->stats.skip = p->skip;

    /* for the benchmark's references: the kernel parameters and the map table */
    _Static_assert(sizeof(K_IfsParams) <= sizeof(g->params), "params fit");
    memcpy(g->params, p, sizeof *p);
    g->compute.shader.input = st->table;
    g->compute.shader.input_size = (uint32_t)(st->ntable * sizeof(K_IfsMap));

    fb_ifs_tone *t = &st->tone;
    t->brightness = f->brightness;
    t->gamma = f->gamma;
    t->threshold = f->gamma_threshold;
    t->vibrancy = f->vibrancy;
    t->highlight = f->highlight_power;
    fb_palette_build(&f->palette, t->palette);

    static const char *const suffix[9] = {"count", "density",       "colour",       "R", "G", "B",
                                          "A",     "colour_sum_lo", "colour_sum_hi"};
    exrio_type colour = g->layer->half ? EXRIO_HALF : EXRIO_FLOAT;
    const exrio_type types[9] = {EXRIO_UINT, EXRIO_FLOAT, EXRIO_FLOAT, colour,    colour,
                                 colour,     colour,      EXRIO_UINT,  EXRIO_UINT};
    g->store.nchannels = st->part ? 9 : 7; /* a points part also carries the colour sums, which merge adds */
    for (int c = 0; c < g->store.nchannels; c++) {
        snprintf(g->store.channel_names[c], sizeof g->store.channel_names[c], "%s.%s", g->layer->name, suffix[c]);
        g->store.channel_types[c] = types[c];
    }
    g->store.preview_channel = 1;
    g->store.preview_rgb = 3;
    g->compute.native_rows = ifs_rows;
    g->prepare = ifs_prepare;
    g->memory = ifs_memory;
    g->resolve = ifs_resolve;
    return f->instances[0] ? enumerate_plants(g, st) : FB_OK;
}

static int ifs_refs(fb_layer *L, fb_ref_slot *out)
{
    fb_ifs_params *f = (void *)L->params;
    int n = 0;
    if (f->has_surface) out[n++] = (fb_ref_slot){&f->surface, "instances-surface", NULL};
    if (f->has_avoid) out[n++] = (fb_ref_slot){&f->avoid, "instances-avoid", NULL};
    return n;
}

static int ifs_outputs(const fb_layer *L, const char **paths, const char **what, int max)
{
    const fb_ifs_params *f = fb_layer_params(L);
    if (!f->instances[0] || max < 1) return 0;
    paths[0] = f->instances, what[0] = "instances";
    return 1;
}

/* The plan's cost model: seconds of one core of the reference machine (docs/scenes.md). */
#define IFS_POINT_SECONDS 5.0e-9 /* a chaos-game step */
#define IFS_PIXEL_SECONDS 1.0e-7 /* a pixel: its histogram, density and channels */
static fb_result ifs_cost(const fb_scene *s, int layer, double *rows, double *total)
{
    const fb_ifs_params *f = fb_layer_params(&s->layers[layer]);
    *total = f->points * IFS_POINT_SECONDS + (double)s->width * s->height * IFS_PIXEL_SECONDS;
    return FB_OK;
}

const fb_gen_class fb_gen_ifs = {
    .name = "ifs",
    .synopsis = "ifs [options] -o OUT.exr",
    .summary = "an IFS chaos game (plants: fern, tree, population...), one layer",
    .what = "an ifs layer",
    .keys = fb_ifs_keys,
    .nkeys = FB_IFS_NKEYS,
    .params_size = sizeof(fb_ifs_params),
    .parse = fb_ifs_parse,
    .refs = ifs_refs,
    .outputs = ifs_outputs,
    .init = ifs_init,
    .share = FB_SHARE_POINTS,
    .cost = ifs_cost,
    .part_pixel_seconds = IFS_PIXEL_SECONDS,
    .points = &fb_ifs_points_ops,
    .tone = &fb_ifs_tone_ops,
    .bench = fb_ifs_bench,
};
