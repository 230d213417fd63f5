/*
 * The FBM constraint model. See constrain.h and docs/constrain.md.
 *
 * Grid: (2^k + 1) nodes per side covering the image (node (x, y) is pixel (x, y)); 1D profiles use
 * one row. Node generation order: the corners (ends), then for each step s = 2^k, ..., 2 with
 * h = s / 2: in 2D the diamond step (square centres from their 4 corners) and the square step (edge
 * midpoints from their 3 or 4 axis neighbours); in 1D the midpoints. The displacement of a node whose
 * parents are at distance r (pixels) has variance sigma^2 (1 - 2^(2H-2)) (r / (N - 1))^(2H), which is
 * the paper's A_n in 1D (r = 2^-n of the span) and the same law of distance in 2D; H is the node's.
 */
#include "constrain.h"

#include "pool.h"

#include "../kernels/hash.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---- continuous constraints: equations 13 to 15 ------------------------------------------------ */

static int l1(const fb_constrain_desc *d, int x0, int y0, int x1, int y1)
{
    int dx = abs(x1 - x0), dy = d->height > 1 ? abs(y1 - y0) : 0;
    return dx + dy;
}

double fb_constrain_field(const fb_constrain_desc *d, bool is_h, int x, int y)
{
    double f0 = is_h ? d->hurst : d->T, sum = 0;
    int cnt = 0, reach = 1 << d->domain;
    for (int i = 0; i < d->nregions; i++) {
        const fb_cregion *r = &d->regions[i];
        if (r->is_h != is_h) continue;
        int dist = l1(d, r->x, r->y, x, y);
        if (dist > reach) continue;
        sum += (r->value - f0) / (1.0 + d->falloff * (double)dist * (double)dist);
        cnt++;
    }
    return cnt ? f0 + sum / cnt : f0;
}

/* The field over the image, region by region over its diamond, in bands of rows (the same sums in
 * the same order as fb_constrain_field, so the same values; memory for one band only). */
static fb_result field(const fb_constrain_desc *d, bool is_h, float *out)
{
    enum { BAND = 64 };
    size_t n = (size_t)d->width * d->height;
    double f0 = is_h ? d->hurst : d->T;
    int reach = 1 << d->domain, any = 0;
    for (int i = 0; i < d->nregions; i++) any += d->regions[i].is_h == is_h;
    if (!any) {
        for (size_t i = 0; i < n; i++) out[i] = (float)f0;
        return FB_OK;
    }
    size_t bn = (size_t)d->width * BAND;
    double *sum = malloc(bn * sizeof *sum);
    int *cnt = malloc(bn * sizeof *cnt);
    if (!sum || !cnt) {
        free(sum);
        free(cnt);
        return fb_fail(FB_ERR_NOMEM, "out of memory for the constraint fields");
    }
    for (int b0 = 0; b0 < d->height; b0 += BAND) {
        int b1 = b0 + BAND < d->height ? b0 + BAND : d->height;
        memset(sum, 0, bn * sizeof *sum);
        memset(cnt, 0, bn * sizeof *cnt);
        for (int i = 0; i < d->nregions; i++) {
            const fb_cregion *r = &d->regions[i];
            if (r->is_h != is_h) continue;
            int ylo = d->height > 1 ? r->y - reach : 0, yhi = d->height > 1 ? r->y + reach : 0;
            ylo = ylo < b0 ? b0 : ylo;
            yhi = yhi > b1 - 1 ? b1 - 1 : yhi;
            for (int y = ylo; y <= yhi; y++) {
                int left = reach - abs(y - r->y);
                for (int x = r->x - left < 0 ? 0 : r->x - left; x <= r->x + left && x < d->width; x++) {
                    int dist = l1(d, r->x, r->y, x, y);
                    size_t at = (size_t)(y - b0) * d->width + x;
                    sum[at] += (r->value - f0) / (1.0 + d->falloff * (double)dist * (double)dist);
                    cnt[at]++;
                }
            }
        }
        for (size_t i = 0; i < (size_t)(b1 - b0) * d->width; i++)
            out[(size_t)b0 * d->width + i] = (float)(cnt[i] ? f0 + sum[i] / cnt[i] : f0);
    }
    free(sum);
    free(cnt);
    return FB_OK;
}

/* ---- the midpoint recursion -------------------------------------------------------------------- */

/* A standard normal deviate for node `index` (Box-Muller on two hashes: the same on any machine). */
static double gauss(uint32_t seed, uint32_t index)
{
    uint32_t h1 = k_hash3(seed, 0x9e3779b9u, index), h2 = k_hash3(seed, 0x7f4a7c15u, index);
    double u1 = ((double)(h1 >> 8) + 0.5) * (1.0 / 16777216.0), u2 = (double)(h2 >> 8) * (1.0 / 16777216.0);
    return sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2);
}

typedef struct grid {
    const fb_constrain_desc *d;
    int N; /* nodes per side */
    bool two_d;
    float *P;
    const float *Hf;  /* H per pixel */
    const char *is_c; /* per node: a discrete constraint */
    double span;      /* N - 1 */
} grid;

static double node_h(const grid *g, int x, int y)
{
    const fb_constrain_desc *d = g->d;
    /* the fields are floats: the base H outside the image is rounded the same way */
    return x < d->width && y < d->height ? (double)g->Hf[(size_t)y * d->width + x] : (double)(float)d->hurst;
}

/* The standard deviation of the displacement of a node of roughness H whose parents are r away. */
static double scale_of(const grid *g, double H, double r)
{
    double s = g->d->sigma;
    return sqrt(s * s * (1.0 - pow(2.0, 2 * H - 2)) * pow(r / g->span, 2 * H));
}

/* The displacement of node (x, y) whose parents are r away; base_sd: scale_of at the base H (the
 * same for most nodes of a step, so computed once). */
static double displacement(const grid *g, int x, int y, double r, double base_sd)
{
    double H = node_h(g, x, y);
    double sd = H == (double)(float)g->d->hurst ? base_sd : scale_of(g, H, r);
    return sd * gauss(g->d->seed, (uint32_t)((size_t)y * g->N + x));
}

/* One half-step of the 2D recursion over a share of its rows (nodes of a step are independent). */
typedef struct step_job {
    grid *g;
    int s, h;
    bool square, live;
    double base_sd;
    int ntasks;
} step_job;

static void step_task(void *ctx, int task)
{
    const step_job *j = ctx;
    grid *g = j->g;
    const int N = g->N, s = j->s, h = j->h;
    if (!j->square) { /* diamond: square centres from their 4 corners; rows h, h + s, ... */
        int rows = (N - 1) / s, r0 = rows * task / j->ntasks, r1 = rows * (task + 1) / j->ntasks;
        for (int r = r0; r < r1; r++) {
            int y = h + r * s;
            for (int x = h; x < N; x += s) {
                double a = (double)g->P[(size_t)(y - h) * N + x - h] + g->P[(size_t)(y - h) * N + x + h] +
                           g->P[(size_t)(y + h) * N + x - h] + g->P[(size_t)(y + h) * N + x + h];
                size_t at = (size_t)y * N + x;
                g->P[at] = (float)(0.25 * a + displacement(g, x, y, h * 1.4142135623730951, j->base_sd));
                if (j->live && g->is_c[at]) g->P[at] = 0.0f;
            }
        }
        return;
    }
    /* square: edge midpoints from their axis neighbours; rows 0, h, 2h, ... */
    int rows = (N - 1) / h + 1, r0 = rows * task / j->ntasks, r1 = rows * (task + 1) / j->ntasks;
    for (int r = r0; r < r1; r++) {
        int y = r * h;
        for (int x = (r % 2 == 0) ? h : 0; x < N; x += s) {
            double a = 0;
            int m = 0;
            if (x >= h) a += g->P[(size_t)y * N + x - h], m++;
            if (x + h < N) a += g->P[(size_t)y * N + x + h], m++;
            if (y >= h) a += g->P[(size_t)(y - h) * N + x], m++;
            if (y + h < N) a += g->P[(size_t)(y + h) * N + x], m++;
            size_t at = (size_t)y * N + x;
            g->P[at] = (float)(a / m + displacement(g, x, y, h, j->base_sd));
            if (j->live && g->is_c[at]) g->P[at] = 0.0f;
        }
    }
}

static void run_tasks(fb_pool *pool, int ntasks, fb_task_fn fn, void *ctx)
{
    if (pool)
        fb_pool_run(pool, ntasks, fn, ctx);
    else
        for (int t = 0; t < ntasks; t++) fn(ctx, t);
}

/* Regional buffering (our reading of equations 11 and 12; docs/constrain.md): after every level,
 * while a constraint p* is not a node yet, the value the current grid interpolates at p* (linearly
 * in its cell of spacing h) is removed by shifting the free nodes of that cell, so the field passes
 * through 0 at p* at every scale. Each correction is of the size of that level's displacements, so
 * the increments near p* keep the field's statistics; when p* is finally made it is small, and is set
 * to 0 exactly. Nodes that are constraints are never moved. */
static void buffer_level(grid *g, int h)
{
    const fb_constrain_desc *d = g->d;
    int N = g->N;
    for (int i = 0; i < d->npoints; i++) {
        int px = d->points[i].x, py = g->two_d ? d->points[i].y : 0;
        if (px % h == 0 && py % h == 0) continue; /* a node already: set to 0 when it was made */
        int x0 = px / h * h, y0 = py / h * h;
        int xs[2] = {x0, x0 + h < N ? x0 + h : x0}, ys[2] = {y0, g->two_d && y0 + h < N ? y0 + h : y0};
        double tx = (double)(px - x0) / h, ty = g->two_d ? (double)(py - y0) / h : 0.0;
        double w[4] = {(1 - tx) * (1 - ty), tx * (1 - ty), (1 - tx) * ty, tx * ty}, v = 0, wfree = 0;
        size_t at[4];
        for (int c = 0; c < 4; c++) {
            at[c] = (size_t)ys[c / 2] * (g->two_d ? N : 0) + xs[c % 2];
            v += w[c] * g->P[at[c]];
            if (!g->is_c[at[c]]) wfree += w[c];
        }
        /* exact when the free corners carry at least half the weight; else a partial correction
         * (rather than pinning a free node to an extreme value) */
        double shift = wfree >= 0.5 ? -v / wfree : -v;
        for (int c = 0; c < 4; c++) {
            bool dup = false; /* a cell on the image edge repeats a corner */
            for (int e = 0; e < c; e++) dup = dup || at[e] == at[c];
            if (!dup && !g->is_c[at[c]] && w[c] > 0) g->P[at[c]] = (float)(g->P[at[c]] + shift);
        }
    }
}

fb_result fb_constrain_run(const fb_constrain_desc *d, bool want_p, fb_constrain_out *out)
{
    memset(out, 0, sizeof *out);
    bool two_d = d->height > 1;
    int side = d->width > d->height ? d->width : d->height, N = 2;
    while (N - 1 < side - 1 || N < 3) N = 2 * (N - 1) + 1;
    size_t nodes = two_d ? (size_t)N * N : (size_t)N, npx = (size_t)d->width * d->height;
    if (nodes > (size_t)UINT32_MAX) return fb_fail(FB_ERR_INPUT, "constrain: the %d x %d grid is too large", N, N);
    grid g = {.d = d, .N = N, .two_d = two_d, .span = N - 1};
    int threads = d->threads > 0 ? d->threads : fb_cpu_count(), ntasks = threads * 4;
    fb_pool *pool = NULL;
    if (threads > 1 && two_d && fb_pool_create(threads, &pool) != FB_OK) pool = NULL; /* then one thread */
    bool live = d->buffering != FB_BUFFER_NAIVE; /* constraints applied as nodes are made */
    bool regional = d->buffering == FB_BUFFER_REGIONAL;
    float *Hf = malloc(npx * sizeof *Hf), *Tf = malloc(npx * sizeof *Tf);
    g.P = malloc(nodes * sizeof *g.P);
    char *is_c = calloc(nodes, 1);
    fb_result rc = Hf && Tf && g.P && is_c ? FB_OK : fb_fail(FB_ERR_NOMEM, "out of memory for a %d-node grid", N);
    if (!rc) rc = field(d, true, Hf);
    if (!rc) rc = field(d, false, Tf);
    g.Hf = Hf;
    g.is_c = is_c;
    for (int i = 0; i < d->npoints && !rc; i++) is_c[(size_t)d->points[i].y * (two_d ? N : 0) + d->points[i].x] = 1;
    if (!rc) {
        /* level 0: the corners (ends) */
        int cs[4][2] = {{0, 0}, {N - 1, 0}, {0, N - 1}, {N - 1, N - 1}};
        for (int c = 0; c < (two_d ? 4 : 2); c++) {
            int x = cs[c][0], y = cs[c][1];
            g.P[(size_t)y * N + x] = (float)(d->sigma * gauss(d->seed, (uint32_t)((size_t)y * N + x)));
        }
        for (int c = 0; c < (two_d ? 4 : 2) && live; c++) {
            size_t at = (size_t)cs[c][1] * N + cs[c][0];
            if (is_c[at]) g.P[at] = 0.0f;
        }
        if (regional) buffer_level(&g, N - 1);
    }
    for (int s = N - 1; s >= 2 && !rc; s /= 2) {
        int h = s / 2;
        if (!two_d) {
            double base_sd = scale_of(&g, (double)(float)d->hurst, h);
            for (int x = h; x < N; x += s) {
                size_t i = (size_t)x;
                g.P[i] = (float)(0.5 * ((double)g.P[x - h] + (double)g.P[x + h]) + displacement(&g, x, 0, h, base_sd));
                if (live && is_c[i]) g.P[i] = 0.0f;
            }
            if (regional) buffer_level(&g, h);
            continue;
        }
        double H0 = (double)(float)d->hurst;
        step_job dj = {&g, s, h, false, live, scale_of(&g, H0, h * 1.4142135623730951), ntasks};
        run_tasks(pool, ntasks, step_task, &dj);
        step_job sj = {&g, s, h, true, live, scale_of(&g, H0, h), ntasks};
        run_tasks(pool, ntasks, step_task, &sj);
        if (regional) buffer_level(&g, h); /* the grid is regular again, of spacing h */
    }
    if (!rc && !live) /* the naive reading: forced to zero after the fact */
        for (int i = 0; i < d->npoints; i++) g.P[(size_t)d->points[i].y * (two_d ? N : 0) + d->points[i].x] = 0.0f;
    if (!rc) {
        out->D = malloc(npx * sizeof *out->D);
        out->P = want_p ? malloc(npx * sizeof *out->P) : NULL;
        if (!out->D || (want_p && !out->P)) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    }
    if (!rc) {
        const double lim = sqrt(6.0) * d->sigma, Z = 1.0 / (lim + d->delta);
        for (int y = 0; y < d->height; y++)
            for (int x = 0; x < d->width; x++) {
                size_t at = (size_t)y * d->width + x;
                double p = g.P[(size_t)y * (two_d ? N : 0) + x];
                if (out->P) out->P[at] = (float)p;
                p = p < -lim ? -lim : p > lim ? lim : p;
                float dm = d->macro[at];
                if (p == 0) { /* fully constrained: D = d to the last bit */
                    out->D[at] = dm;
                    continue;
                }
                double zpd = 1.0 - Z * fabs(p); /* Z P_d with P_d = 1/Z - |P| (equation 9) */
                double amp = sqrt(-2.0 * Tf[at] * log(zpd));
                out->D[at] = (float)(p < 0 ? (double)dm - amp : (double)dm + amp);
            }
        out->T = Tf, out->H = Hf;
        Tf = Hf = NULL;
    }
    if (rc) {
        free(out->D);
        free(out->P);
        memset(out, 0, sizeof *out);
    }
    free(Tf);
    free(Hf);
    free(g.P);
    free(is_c);
    fb_pool_destroy(&pool);
    return rc;
}

bool fb_constrain_macro(const char *name, int width, int height, double h, float *out)
{
    int kind = !strcmp(name, "cone")    ? 0
               : !strcmp(name, "ridge") ? 1
               : !strcmp(name, "boss")  ? 2
               : !strcmp(name, "bowl")  ? 3
                                        : -1;
    if (kind < 0) return false;
    double L = height > 1 ? (width < height ? width : height) : width;
    double cx = 0.5 * width, cy = 0.5 * height;
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++) {
            double dx = (x + 0.5 - cx) / L, dy = height > 1 ? (y + 0.5 - cy) / L : 0.0, r = sqrt(dx * dx + dy * dy), v;
            switch (kind) {
            case 0:
                v = fmax(0.0, 1.0 - r / 0.45);
                break; /* cone */
            case 1:
                v = fmax(0.0, 1.0 - fabs(height > 1 ? dy : dx) / 0.3);
                break; /* ridge along x */
            case 2:
                v = exp(-r * r / (2 * 0.15 * 0.15));
                break; /* boss: a round bump */
            default:
                v = fmin(1.0, (r / 0.45) * (r / 0.45));
                break; /* bowl */
            }
            out[(size_t)y * width + x] = (float)(h * v);
        }
    return true;
}
