/*
 * Stream-power erosion with uplift (rivers.h). A time step:
 *
 *   1. the outlets: the open edges and the sea (cells below the sea level), held at their heights;
 *   2. receivers: each other cell drains to its steepest lower neighbour of the 8 (D8);
 *   3. depressions: a cell with no lower neighbour (a pit) is filled as water would fill it, by
 *      priority-flood (Barnes, Lehman and Mulla 2014) from the pit up to where the water leaves its
 *      basin, then back from there with their epsilon: each cell under the water rises one
 *      representable value above the cell it is flooded from, so that the filled surface drains.
 *      The surface is the bed itself (lakes "fill": sediment fills the depression), or a water
 *      surface over it (lakes "keep"). The filled cells and their neighbours drain anew; a
 *      depression that spills into another is filled in a further round;
 *   4. the order: every donor before its receiver (Kahn's, from the cells no other drains to), the
 *      stack of Braun and Willett 2013 read backwards, and the drainage area A summed along it;
 *   5. h += U dt and the stream power law K A^m S^n solved implicitly in stack order, each cell's
 *      receiver already at its new height: for n = 1, h = (h0 + F h_r) / (1 + F) with
 *      F = K dt A^m / L^n; otherwise Newton's iteration on h - h0 + F (h - h_r)^n = 0, bracketed
 *      in (h_r, h0). A cell already at or below its receiver only rises by U dt (no incision), as
 *      does a cell under a kept lake (no incision under water);
 *   6. hillslope diffusion, implicit: a tridiagonal solve along every row, then along every column
 *      (held cells fixed, closed edges without flux).
 *
 * Steps 2, 6 and the outlets run on row bands (or blocks of lines), each cell or line computed from
 * the previous state alone, so the bits do not depend on the thread count; 3 to 5 are sequential, in
 * a fixed order. At the end the heights are rounded to single precision and filled once more with
 * single-precision epsilons, so that the stored surface itself drains: every cell but the outlets
 * (and, with kept lakes, the lakes' cells) has a strictly lower neighbour.
 */
#include "rivers.h"

#include "kernels/hash.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { FIXED = 1, REACHED = 2, QUEUED = 4, LAKE = 8, DIAG = 16, BELOW = 32 };

/* A^m from a table below this many cells (most cells drain few others), from pow above. */
#define POW_TABLE 65536
/* Columns solved together by the diffusion's column pass. */
#define LANES 16
/* Row bands (and blocks of lines) a pass is cut into at the most: four a thread. */
#define MAX_TASKS 64

/* The neighbours: the four sides first, then the diagonals (ties go to the first). */
static const int DX[8] = {0, -1, 1, 0, -1, 1, -1, 1}, DY[8] = {-1, 0, 0, 1, -1, -1, 1, 1};

typedef struct model {
    const fb_rivers_desc *d;
    int W, H;
    size_t N;
    double *h;                   /* the bed */
    double *z;                   /* kept lakes: the water surface where there is a lake, else the bed */
    int32_t *rcv;                /* receiver (itself for an outlet) */
    uint32_t *cnt;               /* donors not yet ordered */
    int32_t *order;              /* every donor before its receiver (the stack, read backwards) */
    uint32_t *acc;               /* drainage area in cells */
    uint8_t *flag;               /* FIXED, REACHED, QUEUED, LAKE, DIAG, BELOW */
    int32_t *heap;               /* the priority-flood's queue */
    int32_t *aux;                /* its first-in first-out queue of raised cells, or a walk down the receivers */
    size_t task_pits[MAX_TASKS]; /* the pits each task of the receivers' pass found */
    double *powA;                /* c^m for c < POW_TABLE */
    double F[2];                 /* K dt cell^(2m) / L^n for a side and a diagonal receiver */
    double ud;                   /* U dt */
    double r;                    /* kd dt / cell^2 */
    double *lines;               /* the diffusion's scratch: per task, LANES x max(W, H) + 2 x LANES doubles */
    size_t line_stride;
    fb_pool *pool;
    int tasks; /* row bands (and column blocks) a pass is cut into */
} model;

/* ---- passes over row bands ---------------------------------------------------------------------- */

typedef struct job {
    model *M;
    void (*fn)(model *M, int task, const void *arg);
    const void *arg;
} job;

static void job_task(void *ctx, int task)
{
    const job *j = ctx;
    j->fn(j->M, task, j->arg);
}

static void run_tasks(model *M, int n, void (*fn)(model *M, int task, const void *arg), const void *arg)
{
    job j = {M, fn, arg};
    if (M->pool && n > 1)
        fb_pool_run(M->pool, n, job_task, &j);
    else
        for (int t = 0; t < n; t++) fn(M, t, arg);
}

static void band(const model *M, int task, int *y0, int *y1)
{
    int per = (M->H + M->tasks - 1) / M->tasks;
    *y0 = task * per < M->H ? task * per : M->H;
    *y1 = *y0 + per < M->H ? *y0 + per : M->H;
}

/* The outlets of a step: open edges, and the sea (cells below its level). */
static void outlets_task(model *M, int task, const void *arg)
{
    (void)arg;
    const fb_rivers_desc *d = M->d;
    int y0, y1;
    band(M, task, &y0, &y1);
    for (int y = y0; y < y1; y++) {
        bool row_open = (y == 0 && (d->outlets & FB_RIVERS_NORTH)) || (y == M->H - 1 && (d->outlets & FB_RIVERS_SOUTH));
        for (int x = 0; x < M->W; x++) {
            size_t i = (size_t)y * M->W + x;
            bool open = row_open || (x == 0 && (d->outlets & FB_RIVERS_WEST)) ||
                        (x == M->W - 1 && (d->outlets & FB_RIVERS_EAST)) || (d->has_sea && M->h[i] < d->sea_level);
            M->flag[i] = open ? FIXED : 0;
        }
    }
}

/* Cell i = (x, y) drains to its steepest lower neighbour on surface s (itself when it has none);
 * `inside`: no neighbour is off the grid. Returns whether it is a pit (no outlet, no lower neighbour). */
static inline bool receiver(model *M, const double *s, int x, int y, bool inside)
{
    size_t i = (size_t)y * M->W + x;
    uint8_t f = M->flag[i] & (uint8_t)~DIAG;
    int32_t r = (int32_t)i;
    if (!(f & FIXED)) {
        double si = s[i], best = 0;
        int bk = -1;
        for (int k = 0; k < 8; k++) {
            int nx = x + DX[k], ny = y + DY[k];
            if (!inside && (nx < 0 || ny < 0 || nx >= M->W || ny >= M->H)) continue;
            double dz = si - s[(size_t)ny * M->W + nx];
            double sl = k < 4 ? dz : dz * M_SQRT1_2;
            if (sl > best) best = sl, bk = k;
        }
        if (bk >= 0) {
            r = (int32_t)((size_t)(y + DY[bk]) * M->W + x + DX[bk]);
            if (bk >= 4) f |= DIAG;
        }
    }
    M->rcv[i] = r;
    M->flag[i] = f;
    return r == (int32_t)i && !(f & FIXED);
}

typedef struct rcv_arg {
    const double *s;
    bool only_unreached; /* the cells a flood routed: those the walk did not reach */
    size_t *pits;        /* per task: the cells that drain nowhere and are no outlet */
} rcv_arg;

/* Two doubles and two 64-bit masks (GCC's vector extensions: SSE2 on x86-64, NEON on Arm). */
typedef double v2d __attribute__((vector_size(16)));
typedef long long v2l __attribute__((vector_size(16)));

/* The steepest of the 8 neighbours for the interior cells of row y, direction by direction, two
 * cells at a time: best[x] the steepest drop (0: none lower), dir[x] its direction (-1: none). The
 * same comparisons, in the same order, as receiver(). */
static void steepest_row(const model *M, const double *s, int y, double *restrict best, long long *restrict dir)
{
    const int W = M->W;
    const double *c = s + (size_t)y * W;
    for (int x = 1; x < W - 1; x++) best[x] = 0, dir[x] = -1;
    for (int k = 0; k < 8; k++) {
        const double *nb = s + (size_t)(y + DY[k]) * W + DX[k];
        const double w = k < 4 ? 1.0 : M_SQRT1_2; /* dz * 1.0 is dz */
        const v2d wv = {w, w};
        const v2l kv = {k, k};
        int x = 1;
        for (; x + 2 <= W - 1; x += 2) {
            v2d cv, nv, b;
            v2l d;
            memcpy(&cv, c + x, sizeof cv), memcpy(&nv, nb + x, sizeof nv);
            memcpy(&b, best + x, sizeof b), memcpy(&d, dir + x, sizeof d);
            v2d sl = (cv - nv) * wv;
            v2l up = sl > b;
            b = (v2d)(((v2l)sl & up) | ((v2l)b & ~up));
            d = (kv & up) | (d & ~up);
            memcpy(best + x, &b, sizeof b), memcpy(dir + x, &d, sizeof d);
        }
        for (; x < W - 1; x++) {
            double sl = (c[x] - nb[x]) * w;
            if (sl > best[x]) best[x] = sl, dir[x] = k;
        }
    }
}

static void receivers_task(model *M, int task, const void *arg)
{
    const rcv_arg *a = arg;
    const int W = M->W;
    int y0, y1;
    band(M, task, &y0, &y1);
    double *best = M->lines + (size_t)task * M->line_stride;
    long long *dir = (long long *)(best + W);
    size_t pits = 0;
    for (int y = y0; y < y1; y++) {
        size_t row = (size_t)y * W;
        bool mid = y > 0 && y < M->H - 1 && W > 2;
        if (mid && !a->only_unreached) {
            steepest_row(M, a->s, y, best, dir);
            for (int x = 1; x < W - 1; x++) {
                size_t i = row + x;
                uint8_t f = M->flag[i] & (uint8_t)~DIAG;
                int k = f & FIXED ? -1 : (int)dir[x];
                M->rcv[i] = k < 0 ? (int32_t)i : (int32_t)(i + (ptrdiff_t)DY[k] * W + DX[k]);
                M->flag[i] = k >= 4 ? f | DIAG : f;
                pits += k < 0 && !(f & FIXED);
            }
            pits += receiver(M, a->s, 0, y, false) + receiver(M, a->s, W - 1, y, false);
            continue;
        }
        for (int x = 0; x < W; x++) {
            if (a->only_unreached && (M->flag[row + x] & REACHED)) continue;
            pits += receiver(M, a->s, x, y, mid && x > 0 && x < W - 1);
        }
    }
    a->pits[task] = pits;
}

/* Receivers on surface s; returns the pits (among the cells computed). */
static size_t receivers(model *M, const double *s, bool only_unreached)
{
    rcv_arg a = {s, only_unreached, M->task_pits};
    run_tasks(M, M->tasks, receivers_task, &a);
    size_t pits = 0;
    for (int t = 0; t < M->tasks; t++) pits += M->task_pits[t];
    return pits;
}

/* ---- the order, the drainage area and depressions -------------------------------------------------- */

/* The order (Kahn's: the cells no other drains to first, then each receiver once its last donor is
 * placed) and the drainage area summed along it. Returns the pits: cells that drain nowhere and are
 * not outlets. */
static size_t order_area(model *M)
{
    const size_t N = M->N;
    const int32_t *rcv = M->rcv;
    uint32_t *cnt = M->cnt, *acc = M->acc;
    int32_t *order = M->order;
    memset(cnt, 0, N * sizeof *cnt);
    for (size_t i = 0; i < N; i++)
        if (rcv[i] != (int32_t)i) cnt[rcv[i]]++;
    size_t tail = 0, pits = 0;
    for (size_t i = 0; i < N; i++) { /* branch-free: a leaf is as likely as not */
        acc[i] = 1;
        order[tail] = (int32_t)i;
        tail += !cnt[i];
        pits += rcv[i] == (int32_t)i && !(M->flag[i] & FIXED);
    }
    for (size_t head = 0; head < tail; head++) {
        int32_t i = order[head], r = rcv[i];
        if (r == i) continue;
        acc[r] += acc[i];
        order[tail] = r;
        tail += !--cnt[r];
    }
    return pits;
}

/* The flood's queue: cells by surface height, ties by index. */
static inline bool before(const double *s, int32_t a, int32_t b)
{
    return s[a] < s[b] || (s[a] == s[b] && a < b);
}

static void heap_push(int32_t *heap, size_t *n, const double *s, int32_t v)
{
    size_t k = (*n)++;
    while (k > 0) {
        size_t p = (k - 1) / 2;
        if (!before(s, v, heap[p])) break;
        heap[k] = heap[p];
        k = p;
    }
    heap[k] = v;
}

static int32_t heap_pop(int32_t *heap, size_t *n, const double *s)
{
    int32_t top = heap[0], v = heap[--*n];
    size_t k = 0, m = *n;
    for (;;) {
        size_t c = 2 * k + 1;
        if (c >= m) break;
        if (c + 1 < m && before(s, heap[c + 1], heap[c])) c++;
        if (!before(s, heap[c], v)) break;
        heap[k] = heap[c];
        k = c;
    }
    if (m) heap[k] = v;
    return top;
}

/* The next value above v on the surface's grid: double, or single precision (the final fill). */
static inline double above(double v, bool single)
{
    return single ? (double)nextafterf((float)v, INFINITY) : nextafter(v, INFINITY);
}

/* REACHED on every cell that drains to an outlet (receivers first along the order). */
static void mark_reached(model *M)
{
    uint8_t *flag = M->flag;
    for (size_t i = 0; i < M->N; i++) flag[i] &= (uint8_t) ~(REACHED | QUEUED | BELOW);
    for (size_t k = M->N; k-- > 0;) {
        int32_t i = M->order[k], r = M->rcv[i];
        if (r == i ? flag[i] & FIXED : flag[r] & REACHED) flag[i] |= REACHED;
    }
}

/* The priority-flood proper, from the n cells in the heap over the cells marked BELOW (each taken
 * once, its mark cleared): a cell rises to just above the cell it is flooded from where it lies no
 * higher (marked LAKE). A raised cell is then the lowest left, so it waits in a plain first-in
 * first-out queue rather than the heap (Barnes et al.'s pit queue). Returns the cells taken. */
static uint64_t spread(model *M, double *s, bool single, size_t n)
{
    const int W = M->W, H = M->H;
    uint8_t *flag = M->flag;
    int32_t *pit = M->aux;
    size_t head = 0, tail = 0;
    uint64_t count = 0;
    while (n || head < tail) {
        int32_t c = head < tail ? pit[head++] : heap_pop(M->heap, &n, s);
        int x = c % W, y = c / W;
        double up = above(s[c], single);
        for (int k = 0; k < 8; k++) {
            int nx = x + DX[k], ny = y + DY[k];
            if (nx < 0 || ny < 0 || nx >= W || ny >= H) continue;
            size_t j = (size_t)ny * W + nx;
            if (!(flag[j] & BELOW)) continue;
            flag[j] &= (uint8_t)~BELOW;
            count++;
            if (s[j] < up) {
                s[j] = up, flag[j] |= LAKE;
                pit[tail++] = (int32_t)j;
            } else {
                heap_push(M->heap, &n, s, (int32_t)j);
            }
        }
    }
    return count;
}

/* Priority-flood over every cell not marked REACHED, seeded by their REACHED neighbours. */
static uint64_t flood(model *M, double *s, bool single)
{
    const int W = M->W, H = M->H;
    uint8_t *flag = M->flag;
    for (size_t i = 0; i < M->N; i++)
        if (!(flag[i] & REACHED)) flag[i] |= BELOW;
    size_t n = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            if (!(flag[(size_t)y * W + x] & BELOW)) continue;
            for (int k = 0; k < 8; k++) {
                int nx = x + DX[k], ny = y + DY[k];
                if (nx < 0 || ny < 0 || nx >= W || ny >= H) continue;
                size_t j = (size_t)ny * W + nx;
                if ((flag[j] & (REACHED | QUEUED)) == REACHED) {
                    flag[j] |= QUEUED;
                    heap_push(M->heap, &n, s, (int32_t)j);
                }
            }
        }
    return spread(M, s, single, n);
}

#define OUT UINT32_MAX

/* The root cell c drains to (a pit's index, or OUT for an outlet), by walking down its receivers
 * until a cell whose root is known; the walk's cells learn it too (lab[]: UNSET where not yet
 * known; aux holds the walk). */
#define UNSET (OUT - 1)
static uint32_t root_of(model *M, uint32_t *lab, int32_t c)
{
    int32_t *walk = M->aux;
    size_t n = 0;
    int32_t j = c;
    while (lab[j] == UNSET && M->rcv[j] != j) walk[n++] = j, j = M->rcv[j];
    uint32_t L = lab[j] != UNSET ? lab[j] : M->flag[j] & FIXED ? OUT : (uint32_t)j;
    lab[j] = L;
    while (n) lab[walk[--n]] = L;
    return L;
}

/* Fills the depression of pit p (a cell that drains nowhere; lab[]: the roots known, root_of)
 * locally, in two priority-floods (Barnes et al.):
 *   1. from the pit up, the lowest cell around the region first, until the cell taken is outside the
 *      pit's basin: that is where the water leaves (the region's lowest exit), the region R the cells
 *      taken before it;
 *   2. from that exit back over R with the epsilon (spread).
 * Then R and its neighbours drain by steepest descent on the new surface, so that every receiver
 * still lies strictly lower. Returns the cells of R; list[] holds R. */
static uint64_t fill_pit(model *M, double *s, bool single, uint32_t *lab, uint32_t p, int32_t *list)
{
    const int W = M->W, H = M->H;
    uint8_t *flag = M->flag;
    int32_t *heap = M->heap;
    size_t n = 0, nr = 0;
    heap_push(heap, &n, s, (int32_t)p);
    flag[p] |= QUEUED;
    int32_t exit = -1;
    while (n) {
        int32_t c = heap_pop(heap, &n, s);
        if (c != (int32_t)p && (s[c] <= s[p] || root_of(M, lab, c) != p)) { /* a basin's cells lie above its pit */
            exit = c;
            break;
        }
        list[nr++] = c;
        flag[c] |= BELOW;
        int x = c % W, y = c / W;
        for (int k = 0; k < 8; k++) {
            int nx = x + DX[k], ny = y + DY[k];
            if (nx < 0 || ny < 0 || nx >= W || ny >= H) continue;
            size_t j = (size_t)ny * W + nx;
            if (flag[j] & QUEUED) continue;
            flag[j] |= QUEUED;
            heap_push(heap, &n, s, (int32_t)j);
        }
    }
    while (n) flag[heap[--n]] &= (uint8_t)~QUEUED; /* what was left around the region */
    if (!ALWAYS(exit >= 0)) exit = (int32_t)p;     /* the grid has an outlet: a basin has an exit */
    flag[exit] &= (uint8_t)~QUEUED;
    heap_push(heap, &n, s, exit);
    spread(M, s, single, n);
    for (size_t k = 0; k < nr; k++) { /* R and its neighbours drain anew */
        int32_t c = list[k];
        int x = c % W, y = c / W;
        flag[c] &= (uint8_t)~QUEUED;
        receiver(M, s, x, y, false);
        for (int d = 0; d < 8; d++) {
            int nx = x + DX[d], ny = y + DY[d];
            if (nx >= 0 && ny >= 0 && nx < W && ny < H) receiver(M, s, nx, ny, false);
        }
    }
    return nr;
}

/* One round over the pits: every pit's depression filled in index order. Returns the pits left (a
 * depression that spilt into one filled before it, or a tie at an exit); *filled: cells filled. */
static size_t fill_pits(model *M, double *s, bool single, uint64_t *filled)
{
    const size_t N = M->N;
    uint32_t *lab = M->cnt, *pits = M->acc; /* free until the order is built */
    size_t npits = 0;
    for (size_t i = 0; i < N; i++) {
        lab[i] = UNSET;
        if (M->rcv[i] == (int32_t)i && !(M->flag[i] & FIXED)) pits[npits++] = (uint32_t)i;
    }
    for (size_t k = 0; k < npits; k++)
        if (M->rcv[pits[k]] == (int32_t)pits[k]) /* not drained by an earlier fill of this round */
            *filled += fill_pit(M, s, single, lab, pits[k], M->order);
    size_t left = 0;
    for (size_t i = 0; i < N; i++) left += M->rcv[i] == (int32_t)i && !(M->flag[i] & FIXED);
    return left;
}

/* Receivers, the order and the drainage area on surface s, with depressions filled first where
 * there are any: pit by pit (fill_pits), a few rounds while fills uncover new pits, then, should any
 * remain, by one priority-flood over every cell that drains into a pit. *flooded: the cells filled. */
static fb_result route(model *M, double *s, bool single, uint64_t *flooded)
{
    *flooded = 0;
    size_t pits = receivers(M, s, false);
    for (int round = 0; pits && round < 8; round++) pits = fill_pits(M, s, single, flooded);
    if (pits) {
        order_area(M);
        mark_reached(M);
        *flooded += flood(M, s, single);
        receivers(M, s, true);
    }
    if (!ALWAYS(order_area(M) == 0)) return fb_fail(FB_ERR_INTERNAL, "rivers: a cell drains nowhere after the fill");
    return FB_OK;
}

/* ---- the stream power law ------------------------------------------------------------------------ */

/* x^y, exactly where it can be: the exponents of the defaults (m = 1/2, n = 1) by a square root and
 * nothing, correctly rounded on every machine; others by libm's pow. */
static double power(double x, double y)
{
    return y == 1 ? x : y == 0.5 ? sqrt(x) : y == 2 ? x * x : pow(x, y);
}

/* The root of g(x) = x - h0 + F (x - b)^n in (b, h0) (g(b) < 0 < g(h0)): Newton's iteration from
 * h0, falling back to bisection whenever a step would leave the bracket. */
static double newton(double h0, double b, double F, double n)
{
    double lo = b, hi = h0, x = h0;
    for (int it = 0; it < 100; it++) {
        double dx = x - b, p = pow(dx, n - 1), g = x - h0 + F * dx * p;
        if (g > 0)
            hi = x;
        else if (g < 0)
            lo = x;
        else
            return x;
        double nx = x - g / (1 + n * F * p);
        if (!(nx > lo && nx < hi)) nx = 0.5 * (lo + hi);
        if (nx == x || hi - lo <= 4 * DBL_EPSILON * fabs(x)) return nx;
        x = nx;
    }
    return x;
}

static void erode(model *M)
{
    const fb_rivers_desc *d = M->d;
    const bool keep = d->keep_lakes, unit = d->n == 1;
    double *h = M->h;
    for (size_t k = M->N; k-- > 0;) { /* receivers before donors */
        int32_t i = M->order[k];
        uint8_t f = M->flag[i];
        if (f & FIXED) continue;
        double h0 = h[i] + (d->uplift_map ? M->ud * d->uplift_map[i] : M->ud);
        if (keep && (f & LAKE)) {
            h[i] = h0;
            continue;
        }
        int32_t r = M->rcv[i];
        double b = h[r];
        if (keep && (M->flag[r] & LAKE) && M->z[r] > b) b = M->z[r]; /* a lake's surface is the base */
        if (!(h0 > b)) {
            h[i] = h0;
            continue;
        }
        uint32_t c = M->acc[i];
        double F = M->F[(f & DIAG) != 0] * (c < POW_TABLE ? M->powA[c] : power((double)c, d->m));
        h[i] = unit ? (h0 + F * b) / (1 + F) : newton(h0, b, F, d->n);
    }
}

/* ---- hillslope diffusion ----------------------------------------------------------------------- */

/* Implicit diffusion along `lanes` lines of L cells: cell j of lane l at v[j * step + l * lane], with
 * (1 + r nb) x_j - r (x_{j-1} + x_{j+1}) = v_j for a free cell (nb: its neighbours on the line) and
 * x_j = v_j for a held one. Thomas's algorithm; cp holds L x lanes factors, pc and pd lanes each. */
static void solve_lines(const model *M, double *v, const uint8_t *flag, size_t step, size_t lane, int L, int lanes,
                        double *cp)
{
    const double r = M->r;
    double pc[LANES], pd[LANES];
    for (int l = 0; l < lanes; l++) pc[l] = 0, pd[l] = 0;
    for (int j = 0; j < L; j++)
        for (int l = 0; l < lanes; l++) {
            size_t i = j * step + l * lane;
            bool held = flag[i] & FIXED;
            double a = held || j == 0 ? 0 : -r, c = held || j == L - 1 ? 0 : -r, b = 1 - a - c;
            double inv = 1 / (b - a * pc[l]);
            double cj = c * inv, dj = (v[i] - a * pd[l]) * inv;
            cp[(size_t)j * lanes + l] = cj;
            v[i] = dj;
            pc[l] = cj, pd[l] = dj;
        }
    for (int j = L - 2; j >= 0; j--)
        for (int l = 0; l < lanes; l++) {
            size_t i = j * step + l * lane;
            v[i] -= cp[(size_t)j * lanes + l] * v[i + step];
        }
}

static void rows_task(model *M, int task, const void *arg)
{
    (void)arg;
    int y0, y1;
    band(M, task, &y0, &y1);
    double *cp = M->lines + (size_t)task * M->line_stride;
    for (int y = y0; y < y1; y += LANES) {
        size_t at = (size_t)y * M->W;
        int lanes = y1 - y < LANES ? y1 - y : LANES;
        solve_lines(M, M->h + at, M->flag + at, 1, (size_t)M->W, M->W, lanes, cp);
    }
}

static void columns_task(model *M, int task, const void *arg)
{
    (void)arg;
    int blocks = (M->W + LANES - 1) / LANES, per = (blocks + M->tasks - 1) / M->tasks;
    double *cp = M->lines + (size_t)task * M->line_stride;
    for (int b = task * per; b < blocks && b < (task + 1) * per; b++) {
        int x0 = b * LANES, lanes = M->W - x0 < LANES ? M->W - x0 : LANES;
        solve_lines(M, M->h + x0, M->flag + x0, (size_t)M->W, 1, M->H, lanes, cp);
    }
}

/* ---- the run ------------------------------------------------------------------------------------ */

const char *fb_rivers_check(const fb_rivers_desc *d)
{
    if (d->width < 1 || d->height < 1) return "the grid is empty";
    if ((uint64_t)d->width * d->height >= (uint64_t)INT32_MAX) return "the grid has 2^31 cells or more";
    if (!(d->cell > 0) || !isfinite(d->cell)) return "the cell size must be a positive number";
    if (d->steps < 1) return "at least one time step";
    if (!(d->dt > 0) || !isfinite(d->dt)) return "the time step must be a positive number";
    if (!(d->K >= 0) || !isfinite(d->K)) return "K must be a number, 0 or more";
    if (!(d->m > 0 && d->m <= 2)) return "m must be in (0, 2]";
    if (!(d->n > 0 && d->n <= 4)) return "n must be in (0, 4]";
    if (!(d->kd >= 0) || !isfinite(d->kd)) return "kd must be a number, 0 or more";
    if (!(d->uplift >= 0) || !isfinite(d->uplift)) return "the uplift must be a number, 0 or more";
    if (!(d->noise >= 0) || !isfinite(d->noise)) return "the noise must be a number, 0 or more";
    if (!d->outlets && !d->has_sea) return "no outlet: open an edge or set a sea level";
    return NULL;
}

/* The state (h, z: 8 bytes; rcv, cnt, order, acc, heap, aux: 4; flag: 1), the result (5 x 4), the
 * tables and the diffusion's scratch (LANES lines of each task). */
uint64_t fb_rivers_memory(int width, int height)
{
    uint64_t n = (uint64_t)width * height;
    return n * (2 * 8 + 6 * 4 + 1 + 5 * 4) + POW_TABLE * 8 +
           MAX_TASKS * 8 * LANES * (uint64_t)(width > height ? width : height);
}

void fb_rivers_out_free(fb_rivers_out *o)
{
    if (!o) return;
    free(o->height), free(o->area), free(o->river), free(o->lake), free(o->receiver);
    memset(o, 0, sizeof *o);
}

static void model_free(model *M)
{
    free(M->h), free(M->z), free(M->rcv), free(M->cnt), free(M->order), free(M->acc), free(M->flag);
    free(M->heap), free(M->aux), free(M->powA), free(M->lines);
    memset(M, 0, sizeof *M);
}

static fb_result model_init(model *M, const fb_rivers_desc *d, fb_pool *pool)
{
    memset(M, 0, sizeof *M);
    M->d = d, M->W = d->width, M->H = d->height, M->N = (size_t)d->width * d->height, M->pool = pool;
    int threads = pool ? fb_pool_threads(pool) : 1;
    M->tasks = threads == 1 ? 1 : 4 * threads < MAX_TASKS ? 4 * threads : MAX_TASKS;
    size_t N = M->N, L = (size_t)(M->W > M->H ? M->W : M->H);
    M->line_stride = LANES * L;
    M->h = fb_malloc_large(N * sizeof *M->h);
    M->z = d->keep_lakes ? fb_malloc_large(N * sizeof *M->z) : NULL;
    M->rcv = fb_malloc_large(N * sizeof *M->rcv);
    M->cnt = fb_malloc_large(N * sizeof *M->cnt);
    M->order = fb_malloc_large(N * sizeof *M->order);
    M->acc = fb_malloc_large(N * sizeof *M->acc);
    M->flag = fb_malloc_large(N);
    M->heap = fb_malloc_large(N * sizeof *M->heap);
    M->aux = fb_malloc_large(N * sizeof *M->aux);
    M->powA = malloc(POW_TABLE * sizeof *M->powA);
    M->lines = malloc((size_t)M->tasks * M->line_stride * sizeof *M->lines);
    if (!M->h || (d->keep_lakes && !M->z) || !M->rcv || !M->cnt || !M->order || !M->acc || !M->flag || !M->heap ||
        !M->aux || !M->powA || !M->lines) {
        model_free(M);
        return fb_fail(FB_ERR_NOMEM, "rivers: out of memory for %d x %d cells", d->width, d->height);
    }
    M->powA[0] = 0;
    for (int c = 1; c < POW_TABLE; c++) M->powA[c] = power((double)c, d->m);
    double a = power(d->cell * d->cell, d->m); /* A^m = (c cell^2)^m */
    M->F[0] = d->K * d->dt * a / power(d->cell, d->n);
    M->F[1] = d->K * d->dt * a / power(d->cell * M_SQRT2, d->n);
    M->ud = d->uplift * d->dt;
    M->r = d->kd * d->dt / (d->cell * d->cell);
    for (size_t i = 0; i < N; i++)
        M->h[i] = (d->initial ? d->initial[i] : d->base) +
                  d->noise * k_u01(k_hash3(d->seed, 0x72697672u /* rivr */, (uint32_t)i));
    return FB_OK;
}

/* One time step; *flooded: the cells a flood routed (0: no depression). */
static fb_result step(model *M, uint64_t *flooded)
{
    run_tasks(M, M->tasks, outlets_task, NULL);
    double *s = M->h;
    if (M->d->keep_lakes) { /* the water surface: the bed, then flooded where there are pits */
        memcpy(M->z, M->h, M->N * sizeof *M->z);
        s = M->z;
    }
    fb_result rc = route(M, s, false, flooded);
    if (rc) return rc;
    erode(M);
    if (M->r > 0) {
        run_tasks(M, M->tasks, rows_task, NULL);
        run_tasks(M, M->tasks, columns_task, NULL);
    }
    return FB_OK;
}

static fb_result out_alloc(size_t n, bool receivers, fb_rivers_out *o)
{
    memset(o, 0, sizeof *o);
    if (receivers && !(o->receiver = malloc(n * sizeof *o->receiver)))
        return fb_fail(FB_ERR_NOMEM, "rivers: out of memory for the result");
    float **p[4] = {&o->height, &o->area, &o->river, &o->lake};
    for (int k = 0; k < 4; k++)
        if (!(*p[k] = malloc(n * sizeof(float)))) {
            fb_rivers_out_free(o);
            return fb_fail(FB_ERR_NOMEM, "rivers: out of memory for the result");
        }
    return FB_OK;
}

/* The stored surface: the heights in single precision, filled once more so that it drains in single
 * precision, its drainage area, the river mask and the standing water. */
static fb_result finish(model *M, fb_rivers_out *o)
{
    const fb_rivers_desc *d = M->d;
    const size_t N = M->N;
    fb_result rc = out_alloc(N, d->receivers, o);
    if (rc) return rc;
    for (size_t i = 0; i < N; i++) o->height[i] = (float)M->h[i], M->h[i] = o->height[i];
    run_tasks(M, M->tasks, outlets_task, NULL);
    uint64_t raised = 0;
    if ((rc = route(M, M->h, true, &raised))) {
        fb_rivers_out_free(o);
        return rc;
    }
    const double cell2 = d->cell * d->cell;
    uint32_t top = 0;
    for (size_t i = 0; i < N; i++) {
        bool sea = d->has_sea && (double)o->height[i] < d->sea_level;
        float surface = (float)M->h[i]; /* exact: a single-precision value */
        if (M->flag[i] & FIXED) {
            o->outlets++;
            top = M->acc[i] > top ? M->acc[i] : top;
        }
        o->final_fill += (M->flag[i] & LAKE) != 0;
        o->area[i] = (float)(M->acc[i] * cell2);
        o->river[i] = !sea && M->acc[i] * cell2 >= d->river_area ? 1.0f : 0.0f;
        if (sea)
            o->lake[i] = fmaxf((float)(d->sea_level - o->height[i]), FLT_TRUE_MIN);
        else if (d->keep_lakes)
            o->lake[i] = surface - o->height[i]; /* > 0 exactly where the fill raised the surface */
        else
            o->lake[i] = 0;
        if (!d->keep_lakes) o->height[i] = surface;
    }
    if (o->receiver) memcpy(o->receiver, M->rcv, N * sizeof *o->receiver);
    o->largest_basin = (double)top / N;
    return FB_OK;
}

fb_result fb_rivers_run(const fb_rivers_desc *d, fb_pool *pool, fb_progress *prog, fb_rivers_out *out)
{
    const char *bad = fb_rivers_check(d);
    if (bad) return fb_fail(FB_ERR_INPUT, "rivers: %s", bad);
    model M;
    fb_result rc = model_init(&M, d, pool);
    if (rc) return rc;
    /* an outlet at the start: held cells stay held (the sea only grows) */
    run_tasks(&M, M.tasks, outlets_task, NULL);
    bool any = false;
    for (size_t i = 0; i < M.N && !any; i++) any = M.flag[i] & FIXED;
    if (!any)
        rc = fb_fail(FB_ERR_INPUT, "no outlet: every edge is closed and no cell lies below the sea level %g",
                     d->sea_level);
    uint64_t flooded = 0;
    int flood_steps = 0;
    for (int t = 0; t < d->steps && !rc; t++) {
        uint64_t f = 0;
        rc = step(&M, &f);
        flooded += f, flood_steps += f > 0;
        if (prog) fb_progress_update(prog, (uint64_t)(t + 1) * M.N, (uint64_t)d->steps * M.N);
    }
    fb_rivers_out o;
    if (!rc) rc = finish(&M, &o);
    model_free(&M);
    if (rc) return rc;
    o.flooded = flooded, o.flood_steps = flood_steps;
    *out = o;
    return FB_OK;
}
