/*
 * The FBM constraint model. See constrain.h and docs/constrain.md.
 *
 * Grid: (2^k + 1) nodes per side covering the image (node (x, y) is pixel (x, y)); 1D profiles use
 * one row. Node generation order: the corners (ends), then for each step s = 2^k, ..., 2 with
 * h = s / 2: in 2D the diamond step (square centres) and the square step (edge midpoints); in 1D the
 * midpoints. With `linear` (the paper's reading) a node is the mean of its 4 corners, 3 or 4 axis
 * neighbours, or 2 ends, and its displacement, parents r pixels away, has variance
 * sigma^2 (1 - 2^(2H-2)) (r / (N - 1))^(2H): the paper's A_n in 1D (r = 2^-n of the span) and the
 * same law of distance in 2D. By default the smooth stencils (16 parents; 6 in 1D; see "the smooth
 * recursion" below) with the variance that fBm gives their prediction error. H is the node's.
 */
#include "constrain.h"

#include "pool.h"

#include "kernels/hash.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

/* ---- continuous constraints: equations 13 to 15 ------------------------------------------------ */

static int l1(const fb_constrain_desc *d, int x0, int y0, int x1, int y1)
{
    int dx = abs(x1 - x0), dy = d->height > 1 ? abs(y1 - y0) : 0;
    return dx + dy;
}

/* Equation 14's falloff, 1 + f_d |p_j - p*|^2, with the Euclidean distance: smooth everywhere. The
 * L1 distance of the domain (equation 13, a diamond) squared has a kink along the row and the
 * column through p* (|dx| + |dy| is not differentiable where dy or dx is 0), and a region's T or H
 * with that kink drew a crease along them (the row of a region's centre, measured: its second
 * differences 1.66 times the median of the rows). The domain stays the diamond. */
static double falloff(const fb_constrain_desc *d, int x0, int y0, int x1, int y1)
{
    double dx = x1 - x0, dy = d->height > 1 ? y1 - y0 : 0;
    return 1.0 + d->falloff * (dx * dx + dy * dy);
}

double fb_constrain_field(const fb_constrain_desc *d, bool is_h, int x, int y)
{
    double f0 = is_h ? d->hurst : d->T, sum = 0;
    int cnt = 0, reach = 1 << d->domain;
    for (int i = 0; i < d->nregions; i++) {
        const fb_cregion *r = &d->regions[i];
        if (r->is_h != is_h) continue;
        if (l1(d, r->x, r->y, x, y) > reach) continue;
        sum += (r->value - f0) / falloff(d, r->x, r->y, x, y);
        cnt++;
    }
    return cnt ? f0 + sum / cnt : f0;
}

/* The field over the image (the same sums in the same order as fb_constrain_field, so the same
 * values), row by row: a row's work is the width of the domains that cross it, so the cost is the
 * domains' area plus one write per pixel. Rows are shared among tasks. */
typedef struct field_job {
    const fb_constrain_desc *d;
    bool is_h;
    float *out;
    double *sum; /* width per task */
    int *cnt;
    int ntasks;
} field_job;

static void field_task(void *ctx, int task)
{
    const field_job *j = ctx;
    const fb_constrain_desc *d = j->d;
    const int W = d->width, reach = 1 << d->domain;
    const double f0 = j->is_h ? d->hurst : d->T;
    double *sum = j->sum + (size_t)task * W;
    int *cnt = j->cnt + (size_t)task * W;
    int y0 = (int)((int64_t)d->height * task / j->ntasks), y1 = (int)((int64_t)d->height * (task + 1) / j->ntasks);
    for (int y = y0; y < y1; y++) {
        float *row = j->out + (size_t)y * W;
        int lo = W, hi = -1;
        for (int pass = 0; pass < 2; pass++) {
            if (pass == 1 && lo <= hi) {
                memset(sum + lo, 0, (size_t)(hi - lo + 1) * sizeof *sum);
                memset(cnt + lo, 0, (size_t)(hi - lo + 1) * sizeof *cnt);
            }
            for (int i = 0; i < d->nregions; i++) {
                const fb_cregion *r = &d->regions[i];
                int left = reach - (d->height > 1 ? abs(y - r->y) : 0);
                if (r->is_h != j->is_h || left < 0) continue;
                int xa = r->x - left < 0 ? 0 : r->x - left, xb = r->x + left >= W ? W - 1 : r->x + left;
                if (pass == 0) {
                    lo = xa < lo ? xa : lo;
                    hi = xb > hi ? xb : hi;
                    continue;
                }
                for (int x = xa; x <= xb; x++) {
                    sum[x] += (r->value - f0) / falloff(d, r->x, r->y, x, y);
                    cnt[x]++;
                }
            }
        }
        for (int x = 0; x < W; x++) row[x] = (float)(x >= lo && x <= hi && cnt[x] ? f0 + sum[x] / cnt[x] : f0);
    }
}

static void run_tasks(fb_pool *pool, int ntasks, fb_task_fn fn, void *ctx)
{
    if (pool)
        fb_pool_run(pool, ntasks, fn, ctx);
    else
        for (int t = 0; t < ntasks; t++) fn(ctx, t);
}

static fb_result field(const fb_constrain_desc *d, bool is_h, float *out, fb_pool *pool, int ntasks)
{
    field_job j = {d,
                   is_h,
                   out,
                   malloc((size_t)ntasks * d->width * sizeof(double)),
                   malloc((size_t)ntasks * d->width * sizeof(int)),
                   ntasks};
    if (!j.sum || !j.cnt) {
        free(j.sum);
        free(j.cnt);
        return fb_fail(FB_ERR_NOMEM, "out of memory for the constraint fields");
    }
    run_tasks(pool, ntasks, field_task, &j);
    free(j.sum);
    free(j.cnt);
    return FB_OK;
}

/* ---- the midpoint recursion -------------------------------------------------------------------- */

/* The key of the node hashes: fb_constrain_normal(seed, i) draws from k_hash(i ^ key), which is
 * k_hash3(seed, stream, i) with its two index-free rounds done once. */
static uint32_t normal_key(uint32_t seed)
{
    return k_hash(0x9e3779b9u ^ k_hash(seed ^ 0x9e3779b9u));
}

/* The standard normal quantile of u in (0, 1): Acklam's rational approximations (relative error
 * below 1.2e-9): one rational function on the central 95%, sqrt(-2 ln) of the tails outside it. */
static double normal_quantile(double u)
{
    static const double a[6] = {-3.969683028665376e+01, 2.209460984245205e+02,  -2.759285104469687e+02,
                                1.383577518672690e+02,  -3.066479806614716e+01, 2.506628277459239e+00};
    static const double b[5] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                                6.680131188771972e+01, -1.328068155288572e+01};
    static const double c[6] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                                -2.549732539343734e+00, 4.374664141464968e+00,  2.938163982698783e+00};
    static const double e[4] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                                3.754408661907416e+00};
    double q = u - 0.5;
    if (fabs(q) <= 0.5 - 0.02425) {
        double r = q * q;
        return (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
               (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1.0);
    }
    double t = sqrt(-2.0 * log(q < 0 ? u : 1.0 - u));
    double x = (((((c[0] * t + c[1]) * t + c[2]) * t + c[3]) * t + c[4]) * t + c[5]) /
               ((((e[0] * t + e[1]) * t + e[2]) * t + e[3]) * t + 1.0);
    return q < 0 ? x : -x;
}

static double normal_of(uint32_t key, uint32_t index)
{
    return normal_quantile(((double)k_hash(index ^ key) + 0.5) * (1.0 / 4294967296.0));
}

double fb_constrain_normal(uint32_t seed, uint32_t index)
{
    return normal_of(normal_key(seed), index);
}

typedef struct grid {
    const fb_constrain_desc *d;
    int N; /* nodes per side */
    bool two_d;
    float *P;
    const float *Hf; /* H per pixel */
    uint32_t key;    /* normal_key(seed) */
    float H0;        /* the base H, rounded as the field is */
    size_t *cnodes;  /* the discrete constraints' node indices, sorted */
    double *ktab;    /* K per stencil kind over H (smooth_sd), when some region sets H; else NULL */
    int ncnodes;
    double span; /* N - 1 */
} grid;

static bool is_constraint(const grid *g, size_t at)
{
    int lo = 0, hi = g->ncnodes - 1;
    while (lo <= hi) {
        int m = (lo + hi) / 2;
        if (g->cnodes[m] == at) return true;
        if (g->cnodes[m] < at)
            lo = m + 1;
        else
            hi = m - 1;
    }
    return false;
}

/* The standard deviation of the displacement of a node of roughness H whose parents are r away. */
static double scale_of(const grid *g, double H, double r)
{
    double s = g->d->sigma;
    return sqrt(s * s * (1.0 - pow(2.0, 2 * H - 2)) * pow(r / g->span, 2 * H));
}

/* The displacement of node (x, y) whose parents are r away; base_sd: scale_of at the base H (the
 * same for most nodes of a step, so computed once). Nodes outside the image have the base H. */
static double displacement(const grid *g, int x, int y, double r, double base_sd)
{
    const fb_constrain_desc *d = g->d;
    float H = x < d->width && y < d->height ? g->Hf[(size_t)y * d->width + x] : g->H0;
    double sd = H == g->H0 ? base_sd : scale_of(g, H, r);
    return sd * normal_of(g->key, (uint32_t)((size_t)y * g->N + x));
}

/* ---- the smooth recursion (the default): no creases where levels meet ------------------------------
 *
 * Averaging 2 or 4 parents makes the coarse field piecewise linear, so every node of a coarse level
 * stays a kink: for H > 1/2 the rows and columns where coarse levels meet show as creases, their
 * second differences rising with the level (1D, H 0.9: 1.77 times the finest nodes' after 10
 * levels). The smooth recursion predicts a node from more parents, with weights whose limit is
 * smooth:
 * - 1D: the 6-point stencil of Deslauriers and Dubuc (1989), (3, -25, 150, 150, -25, 3) / 256, C2
 *   (1.00 in the measure above; the 4-point (-1, 9, 9, -1) / 16 of Dyn, Levin and Gregory, C1,
 *   leaves 1.09). Near the ends the 4-point, the quadratic (3, 6, -1) / 8, the mean of 2.
 * - 2D: the diamond-square order, each step by the tensor product of the 4-point weights: the centre
 *   of a coarse cell from the 16 coarse nodes at offsets (a, b) h, a, b in {-3, -1, 1, 3}; an edge
 *   midpoint from the 16 nodes of the lattice rotated by 45 degrees, at offsets ((a + b) / 2,
 *   (a - b) / 2) h. Both steps treat x and y alike, so rows and columns are alike. Within 3 h of the
 *   grid's edge, the paper's means.
 * A node's displacement has the variance that makes its increment from its stencil that of fBm:
 * sigma^2 (h / span)^(2H) K(H), K = -1/2 sum_ij w_i w_j |p_i - p_j|^(2H) over the node (weight 1, at
 * 0) and its stencil's points (weights -w, positions in units of h). For the mean of 2 in 1D,
 * K = 1 - 2^(2H - 2): the paper's A_n. Nodes whose H is not the base H look K up in a table over H
 * (257 entries, linear in between). */
enum { ST_SYM6, ST_SYM4, ST_LEFT, ST_RIGHT, ST_LINEAR, ST_DIAMOND, ST_SQUARE, ST_KINDS };
static const int st_n[5] = {6, 4, 3, 3, 2};
static const double st_t[5][6] = {
    {-5, -3, -1, 1, 3, 5}, {-3, -1, 1, 3}, {-1, 1, 3}, {-3, -1, 1}, {-1, 1},
};
static const double st_w[5][6] = {
    {3.0 / 256, -25.0 / 256, 150.0 / 256, 150.0 / 256, -25.0 / 256, 3.0 / 256},
    {-1.0 / 16, 9.0 / 16, 9.0 / 16, -1.0 / 16},
    {3.0 / 8, 6.0 / 8, -1.0 / 8},
    {-1.0 / 8, 6.0 / 8, 3.0 / 8},
    {0.5, 0.5},
};
static const int o4[4] = {-3, -1, 1, 3};
static const double w4[4] = {-1.0 / 16, 9.0 / 16, 9.0 / 16, -1.0 / 16};

/* A stencil's points (x, y) in units of h and weights; n points. */
static int stencil_points(int kind, double *px, double *py, double *w)
{
    if (kind < ST_DIAMOND) {
        for (int i = 0; i < st_n[kind]; i++) px[i] = st_t[kind][i], py[i] = 0, w[i] = st_w[kind][i];
        return st_n[kind];
    }
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            int a = o4[i], b = o4[j], k = 4 * i + j;
            px[k] = kind == ST_DIAMOND ? a : (a + b) / 2, py[k] = kind == ST_DIAMOND ? b : (a - b) / 2;
            w[k] = w4[i] * w4[j];
        }
    return 16;
}

static double stencil_k(int kind, double H)
{
    double px[17] = {0}, py[17] = {0}, w[17] = {1};
    int n = stencil_points(kind, px + 1, py + 1, w + 1);
    for (int i = 1; i <= n; i++) w[i] = -w[i];
    double sum = 0;
    for (int i = 0; i <= n; i++)
        for (int j = i + 1; j <= n; j++) sum += 2 * w[i] * w[j] * pow(hypot(px[i] - px[j], py[i] - py[j]), 2 * H);
    return -0.5 * sum;
}

#define KTAB 256
/* K over H = 0, 1/256, ..., 1 for every kind (only when some region sets H). */
static double *ktable_make(void)
{
    double *t = malloc((size_t)ST_KINDS * (KTAB + 1) * sizeof *t);
    if (!t) return NULL;
    for (int k = 0; k < ST_KINDS; k++)
        for (int i = 0; i <= KTAB; i++) t[k * (KTAB + 1) + i] = stencil_k(k, (double)i / KTAB);
    return t;
}

/* The displacement's standard deviation at node (x, y) of a smooth step. */
static double smooth_sd(const grid *g, const double *base, int h, int x, int y, int kind)
{
    const fb_constrain_desc *d = g->d;
    float H = x < d->width && y < d->height ? g->Hf[(size_t)y * d->width + x] : g->H0;
    if (H == g->H0) return base[kind];
    double f = H * KTAB;
    int i = (int)f;
    if (i >= KTAB) i = KTAB - 1;
    const double *t = g->ktab + kind * (KTAB + 1);
    double K = t[i] + (f - i) * (t[i + 1] - t[i]);
    return d->sigma * sqrt(K * pow(h / g->span, 2 * (double)H));
}

/* The stencil for the node at i (between i - h and i + h) on a line of n nodes. */
static int stencil_kind(int i, int h, int n)
{
    bool left = i - 3 * h >= 0, right = i + 3 * h <= n - 1;
    if (i - 5 * h >= 0 && i + 5 * h <= n - 1) return ST_SYM6;
    return left && right ? ST_SYM4 : !left && right ? ST_LEFT : left && !right ? ST_RIGHT : ST_LINEAR;
}

/* One level of the smooth 1D recursion. */
static void smooth_1d(grid *g, int s, int h, const double *base)
{
    float *P = g->P;
    const int N = g->N;
    const double *ws = st_w[ST_SYM6];
    for (int x = h; x < N; x += s) {
        double v = 0;
        int kind = stencil_kind(x, h, N);
        if (kind == ST_SYM6)
            v = ws[0] * P[x - 5 * h] + ws[1] * P[x - 3 * h] + ws[2] * P[x - h] + ws[3] * P[x + h] +
                ws[4] * P[x + 3 * h] + ws[5] * P[x + 5 * h];
        else
            for (int j = 0; j < st_n[kind]; j++) v += st_w[kind][j] * P[x + (int)st_t[kind][j] * h];
        P[x] = (float)(v + smooth_sd(g, base, h, x, 0, kind) * normal_of(g->key, (uint32_t)x));
    }
}

/* The 4-point weights along x of row `row` at x + o4[i] h, for i = 0..3 */
static inline double row4(const float *row, int x, int h)
{
    return w4[0] * row[x - 3 * h] + w4[1] * row[x - h] + w4[2] * row[x + h] + w4[3] * row[x + 3 * h];
}

/* One half-step of the 2D recursion over a share of its rows (nodes of a step are independent). */
typedef struct step_job {
    grid *g;
    int s, h;
    bool square;
    double base_sd;
    int ntasks;
    bool smooth;               /* the 16-point stencils away from the edges */
    const double *smooth_base; /* their sd at the base H, per kind */
} step_job;

static void step_task(void *ctx, int task)
{
    const step_job *j = ctx;
    grid *g = j->g;
    float *P = g->P;
    const int N = g->N, s = j->s, h = j->h;
    const double r = j->square ? h : h * 1.4142135623730951;
    if (!j->square) { /* diamond: square centres from their 4 corners; rows h, h + s, ... */
        int rows = (N - 1) / s, r0 = rows * task / j->ntasks, r1 = rows * (task + 1) / j->ntasks;
        for (int k = r0; k < r1; k++) {
            int y = h + k * s;
            const float *up = P + (size_t)(y - h) * N, *dn = P + (size_t)(y + h) * N;
            float *row = P + (size_t)y * N;
            bool rows_in = j->smooth && y >= 3 * h && y + 3 * h <= N - 1;
            for (int x = h; x < N; x += s) {
                if (rows_in && x >= 3 * h && x + 3 * h <= N - 1) { /* the 16 nodes around */
                    double v = 0;
                    for (int b = 0; b < 4; b++) v += w4[b] * row4(P + (size_t)(y + o4[b] * h) * N, x, h);
                    row[x] = (float)(v + smooth_sd(g, j->smooth_base, h, x, y, ST_DIAMOND) *
                                             normal_of(g->key, (uint32_t)((size_t)y * N + x)));
                    continue;
                }
                double a = (double)up[x - h] + up[x + h] + dn[x - h] + dn[x + h];
                row[x] = (float)(0.25 * a + displacement(g, x, y, r, j->base_sd));
            }
        }
        return;
    }
    /* square: edge midpoints from their axis neighbours; rows 0, h, 2h, ... The smooth stencil's 16
     * lattice nodes, as offsets from the node: ((a + b) / 2, (a - b) / 2) h. */
    ptrdiff_t off[4][4];
    for (int a = 0; a < 4; a++)
        for (int b = 0; b < 4; b++)
            off[a][b] = (ptrdiff_t)((o4[a] - o4[b]) / 2) * h * N + (ptrdiff_t)((o4[a] + o4[b]) / 2) * h;
    int rows = (N - 1) / h + 1, r0 = rows * task / j->ntasks, r1 = rows * (task + 1) / j->ntasks;
    for (int k = r0; k < r1; k++) {
        int y = k * h;
        float *row = P + (size_t)y * N;
        const float *up = y >= h ? row - (size_t)h * N : NULL, *dn = y + h < N ? row + (size_t)h * N : NULL;
        int x = (k % 2 == 0) ? h : 0;
        if (x == 0) { /* the left edge: 3 neighbours */
            double a = (double)row[h] + (up ? up[0] : 0.0) + (dn ? dn[0] : 0.0);
            row[0] = (float)(a / (1 + !!up + !!dn) + displacement(g, 0, y, r, j->base_sd));
            x = s;
        }
        bool rows_in = j->smooth && y >= 3 * h && y + 3 * h <= N - 1;
        if (up && dn) /* interior rows: 4 neighbours but at the right edge */
            for (; x < N - 1; x += s) {
                if (rows_in && x >= 3 * h && x + 3 * h <= N - 1) { /* the 16 lattice nodes around */
                    const float *c = row + x;
                    double v = 0;
                    for (int a = 0; a < 4; a++) {
                        const ptrdiff_t *o = off[a];
                        v += w4[a] * (w4[0] * c[o[0]] + w4[1] * c[o[1]] + w4[2] * c[o[2]] + w4[3] * c[o[3]]);
                    }
                    row[x] = (float)(v + smooth_sd(g, j->smooth_base, h, x, y, ST_SQUARE) *
                                             normal_of(g->key, (uint32_t)((size_t)y * N + x)));
                    continue;
                }
                double a = (double)row[x - h] + row[x + h] + up[x] + dn[x];
                row[x] = (float)(0.25 * a + displacement(g, x, y, r, j->base_sd));
            }
        for (; x < N; x += s) {
            double a = 0;
            int m = 0;
            if (x >= h) a += row[x - h], m++;
            if (x + h < N) a += row[x + h], m++;
            if (up) a += up[x], m++;
            if (dn) a += dn[x], m++;
            row[x] = (float)(a / m + displacement(g, x, y, r, j->base_sd));
        }
    }
}

/* The discrete constraints made at this half-step are set to 0, before anything is interpolated
 * from them: with spacing h, the diamond step makes the nodes at odd multiples of h in both axes
 * (centre), the square step those odd in one axis only (and the 1D step the odd ones). */
static void pin_step(grid *g, int h, bool centre)
{
    const fb_constrain_desc *d = g->d;
    for (int i = 0; i < d->npoints; i++) {
        int px = d->points[i].x, py = g->two_d ? d->points[i].y : 0;
        if (px % h || py % h) continue;
        bool ox = (px / h) % 2, oy = (py / h) % 2;
        if (centre ? (ox && oy) : (ox != oy)) g->P[(size_t)py * (g->two_d ? g->N : 0) + px] = 0.0f;
    }
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
        bool fixed[4];
        for (int c = 0; c < 4; c++) {
            at[c] = (size_t)ys[c / 2] * (g->two_d ? N : 0) + xs[c % 2];
            fixed[c] = is_constraint(g, at[c]);
            v += w[c] * g->P[at[c]];
            if (!fixed[c]) wfree += w[c];
        }
        /* exact when the free corners carry at least half the weight; else a partial correction
         * (rather than pinning a free node to an extreme value) */
        double shift = wfree >= 0.5 ? -v / wfree : -v;
        for (int c = 0; c < 4; c++) {
            bool dup = false; /* a cell on the image edge repeats a corner */
            for (int e = 0; e < c; e++) dup = dup || at[e] == at[c];
            if (!dup && !fixed[c] && w[c] > 0) g->P[at[c]] = (float)(g->P[at[c]] + shift);
        }
    }
}

/* D from P (equations 5 to 10) over a share of the rows. */
typedef struct final_job {
    const grid *g;
    const float *Tf;
    fb_constrain_out *out;
    int ntasks;
} final_job;

static void final_task(void *ctx, int task)
{
    const final_job *j = ctx;
    const fb_constrain_desc *d = j->g->d;
    const double lim = sqrt(6.0) * d->sigma, Z = 1.0 / (lim + d->delta);
    /* soften: within |P| < eps, |D - d| = sqrt(T) g(|P|), g(a) = sqrt(-2 ln(1 - Z a)), becomes
     * sqrt(T) (A a + B a^3), the odd cubic with g's value and slope at eps: C1 across the zero line
     * (g' is infinite at 0), monotone, 0 at P = 0, and equation 10 itself for |P| >= eps. */
    const double eps = d->soften * d->sigma;
    double A = 0, B = 0;
    if (eps > 0) {
        double g = sqrt(-2.0 * log(1.0 - Z * eps)), g1 = Z / ((1.0 - Z * eps) * g);
        A = (3 * g - g1 * eps) / (2 * eps), B = (g1 * eps - g) / (2 * eps * eps * eps);
    }
    int y0 = (int)((int64_t)d->height * task / j->ntasks), y1 = (int)((int64_t)d->height * (task + 1) / j->ntasks);
    for (int y = y0; y < y1; y++) {
        const float *prow = j->g->P + (size_t)y * (j->g->two_d ? j->g->N : 0);
        size_t at0 = (size_t)y * d->width;
        if (j->out->P) memcpy(j->out->P + at0, prow, (size_t)d->width * sizeof *prow);
        for (int x = 0; x < d->width; x++) {
            size_t at = at0 + x;
            double p = prow[x];
            p = p < -lim ? -lim : p > lim ? lim : p;
            float dm = d->macro[at];
            if (p == 0) { /* fully constrained: D = d to the last bit */
                j->out->D[at] = dm;
                continue;
            }
            double amp;
            if (fabs(p) < eps) /* the softened zero line: sqrt(T) (A |P| + B |P|^3) */
                amp = sqrt((double)j->Tf[at]) * (A + B * p * p) * fabs(p);
            else {
                double zpd = 1.0 - Z * fabs(p); /* Z P_d with P_d = 1/Z - |P| (equation 9) */
                amp = sqrt(-2.0 * j->Tf[at] * log(zpd));
            }
            j->out->D[at] = (float)(p < 0 ? (double)dm - amp : (double)dm + amp);
        }
    }
}

static int cmp_size(const void *a, const void *b)
{
    size_t x = *(const size_t *)a, y = *(const size_t *)b;
    return (x > y) - (x < y);
}

fb_result fb_constrain_run(const fb_constrain_desc *d, bool want_p, fb_constrain_out *out)
{
    memset(out, 0, sizeof *out);
    bool two_d = d->height > 1;
    int side = d->width > d->height ? d->width : d->height, N = 2;
    while (N - 1 < side - 1 || N < 3) N = 2 * (N - 1) + 1;
    size_t nodes = two_d ? (size_t)N * N : (size_t)N, npx = (size_t)d->width * d->height;
    if (nodes > (size_t)UINT32_MAX) return fb_fail(FB_ERR_INPUT, "constrain: the %d x %d grid is too large", N, N);
    grid g = {.d = d, .N = N, .two_d = two_d, .span = N - 1, .key = normal_key(d->seed), .H0 = (float)d->hurst};
    int threads = d->threads > 0 ? d->threads : fb_cpu_count(), ntasks = threads * 4;
    fb_pool *pool = NULL;
    if (threads > 1 && two_d && fb_pool_create(threads, &pool) != FB_OK) pool = NULL; /* then one thread */
    bool live = d->buffering != FB_BUFFER_NAIVE; /* constraints applied as nodes are made */
    bool regional = d->buffering == FB_BUFFER_REGIONAL;
    float *Hf = fb_malloc_large(npx * sizeof *Hf), *Tf = fb_malloc_large(npx * sizeof *Tf);
    g.P = fb_malloc_large(nodes * sizeof *g.P);
    g.cnodes = malloc(((size_t)d->npoints + 1) * sizeof *g.cnodes);
    bool h_varies = false;
    for (int i = 0; i < d->nregions; i++) h_varies = h_varies || d->regions[i].is_h;
    if (h_varies && !d->linear && !(g.ktab = ktable_make())) {
        free(g.cnodes);
        g.cnodes = NULL; /* reported as out of memory below */
    }
    fb_result rc = Hf && Tf && g.P && g.cnodes ? FB_OK : fb_fail(FB_ERR_NOMEM, "out of memory for a %d-node grid", N);
    if (!rc) rc = field(d, true, Hf, pool, ntasks);
    if (!rc) rc = field(d, false, Tf, pool, ntasks);
    g.Hf = Hf;
    for (int i = 0; i < d->npoints && !rc; i++) g.cnodes[i] = (size_t)d->points[i].y * (two_d ? N : 0) + d->points[i].x;
    if (!rc) {
        qsort(g.cnodes, (size_t)d->npoints, sizeof *g.cnodes, cmp_size);
        g.ncnodes = d->npoints;
        /* level 0: the corners (ends) */
        int cs[4][2] = {{0, 0}, {N - 1, 0}, {0, N - 1}, {N - 1, N - 1}};
        for (int c = 0; c < (two_d ? 4 : 2); c++) {
            size_t at = (size_t)cs[c][1] * N + cs[c][0];
            g.P[at] = live && is_constraint(&g, at) ? 0.0f : (float)(d->sigma * normal_of(g.key, (uint32_t)at));
        }
        if (regional) buffer_level(&g, N - 1);
    }
    double k0[ST_KINDS] = {0}; /* each smooth stencil's K at the base H */
    for (int k = 0; k < ST_KINDS && !d->linear; k++) k0[k] = stencil_k(k, g.H0);
    for (int s = N - 1; s >= 2 && !rc; s /= 2) {
        int h = s / 2;
        double sbase[ST_KINDS];
        for (int k = 0; k < ST_KINDS; k++) sbase[k] = d->sigma * sqrt(k0[k] * pow(h / g.span, 2 * (double)g.H0));
        if (!two_d && !d->linear) {
            smooth_1d(&g, s, h, sbase);
            if (live) pin_step(&g, h, false);
            if (regional) buffer_level(&g, h);
            continue;
        }
        if (!two_d) {
            double base_sd = scale_of(&g, g.H0, h);
            for (int x = h; x < N; x += s)
                g.P[x] = (float)(0.5 * ((double)g.P[x - h] + (double)g.P[x + h]) + displacement(&g, x, 0, h, base_sd));
            if (live) pin_step(&g, h, false);
            if (regional) buffer_level(&g, h);
            continue;
        }
        step_job dj = {&g, s, h, false, scale_of(&g, g.H0, h * 1.4142135623730951), ntasks, !d->linear, sbase};
        run_tasks(pool, ntasks, step_task, &dj);
        if (live) pin_step(&g, h, true);
        step_job sj = {&g, s, h, true, scale_of(&g, g.H0, h), ntasks, !d->linear, sbase};
        run_tasks(pool, ntasks, step_task, &sj);
        if (live) pin_step(&g, h, false);
        if (regional) buffer_level(&g, h); /* the grid is regular again, of spacing h */
    }
    if (!rc && !live) /* the naive reading: forced to zero after the fact */
        for (int i = 0; i < d->npoints; i++) g.P[g.cnodes[i]] = 0.0f;
    if (!rc) {
        out->D = fb_malloc_large(npx * sizeof *out->D);
        out->P = want_p ? fb_malloc_large(npx * sizeof *out->P) : NULL;
        if (!out->D || (want_p && !out->P)) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    }
    if (!rc) {
        final_job fj = {&g, Tf, out, two_d ? ntasks : 1};
        run_tasks(pool, fj.ntasks, final_task, &fj);
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
    free(g.cnodes);
    free(g.ktab);
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
