/*
 * Incremental Delaunay triangulation (see delaunay.h).
 */
#include "delaunay.h"

#include "predicates.h"

#include "kernels/hash.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define P(d, v) ((d)->xy + 2 * (size_t)(v))

/* ---- storage ------------------------------------------------------------------------------------ */

static bool reserve_vertices(fb_dt *d, uint32_t need)
{
    if (need <= d->capv) return true;
    size_t c = d->capv ? d->capv : 64;
    while (c < need) c *= 2;
    if (c > UINT32_MAX - 8) return false;
    double *xy = realloc(d->xy, 2 * c * sizeof *xy);
    if (!xy) return false;
    d->xy = xy;
    uint32_t *vt = realloc(d->vt, c * sizeof *vt);
    if (!vt) return false;
    d->vt = vt;
    uint32_t *nt = realloc(d->newt_of, (c + 1) * sizeof *nt);
    if (!nt) return false;
    d->newt_of = nt;
    d->capv = (uint32_t)c;
    return true;
}

static inline uint32_t vslot(const fb_dt *d, uint32_t v)
{
    return v == DT_INF ? d->capv : v;
}

/* The mark array lives after the neighbour array's capacity: tn holds 3 * capt + capt words. */
static inline uint32_t *tmark(fb_dt *d)
{
    return d->tn + 3 * (size_t)d->capt;
}

static bool reserve_triangles(fb_dt *d, size_t need)
{
    if (need <= d->capt) return true;
    size_t c = d->capt ? d->capt : 64;
    while (c < need) c *= 2;
    if (c > UINT32_MAX - 8) return false;
    uint32_t *tv = realloc(d->tv, 3 * c * sizeof *tv);
    if (!tv) return false;
    d->tv = tv;
    uint32_t *tn = malloc(4 * c * sizeof *tn);
    if (!tn) return false;
    if (d->tn) {
        memcpy(tn, d->tn, 3 * (size_t)d->capt * sizeof *tn);
        memcpy(tn + 3 * c, d->tn + 3 * (size_t)d->capt, d->capt * sizeof *tn);
    }
    memset(tn + 3 * c + d->capt, 0, (c - d->capt) * sizeof *tn);
    free(d->tn);
    d->tn = tn;
    d->capt = (uint32_t)c;
    return true;
}

static uint32_t new_triangle(fb_dt *d)
{
    return d->nt++;
}

static bool reserve_scratch(fb_dt *d, size_t need)
{
    if (need <= d->cap_scratch) return true;
    size_t c = d->cap_scratch ? d->cap_scratch : 256;
    while (c < need) c *= 2;
    uint32_t *s = realloc(d->stack, c * sizeof *s), *cv, *b;
    if (!s) return false;
    d->stack = s;
    if (!(cv = realloc(d->cavity, c * sizeof *cv))) return false;
    d->cavity = cv;
    if (!(b = realloc(d->bnd, 3 * c * sizeof *b))) return false;
    d->bnd = b;
    d->cap_scratch = c;
    return true;
}

void fb_dt_free(fb_dt *d)
{
    if (!d) return;
    free(d->xy);
    free(d->vt);
    free(d->tv);
    free(d->tn);
    free(d->stack);
    free(d->cavity);
    free(d->bnd);
    free(d->newt_of);
    memset(d, 0, sizeof *d);
}

/* ---- predicates on triangles ------------------------------------------------------------------ */

/* The finite edge (a, b) of ghost t, oriented so that the hull's outside is to its left. */
static inline void ghost_edge(const fb_dt *d, uint32_t t, uint32_t *a, uint32_t *b)
{
    const uint32_t *v = d->tv + 3 * (size_t)t;
    if (v[0] == DT_INF)
        *a = v[1], *b = v[2];
    else if (v[1] == DT_INF)
        *a = v[2], *b = v[0];
    else
        *a = v[0], *b = v[1];
}

static inline int inf_index(const uint32_t *v)
{
    return v[0] == DT_INF ? 0 : v[1] == DT_INF ? 1 : v[2] == DT_INF ? 2 : -1;
}

/* p strictly inside the segment a-b, knowing the three are collinear (coordinate comparisons are
 * exact). */
static bool strictly_between(const double *a, const double *b, const double *p)
{
    if (a[0] != b[0]) return (a[0] < p[0] && p[0] < b[0]) || (b[0] < p[0] && p[0] < a[0]);
    return (a[1] < p[1] && p[1] < b[1]) || (b[1] < p[1] && p[1] < a[1]);
}

static bool conflict(const fb_dt *d, uint32_t t, const double *p)
{
    const uint32_t *v = d->tv + 3 * (size_t)t;
    if (v[0] != DT_INF && v[1] != DT_INF && v[2] != DT_INF)
        return fb_incircle(P(d, v[0]), P(d, v[1]), P(d, v[2]), p) > 0;
    uint32_t a, b;
    ghost_edge(d, t, &a, &b);
    double o = fb_orient2d(P(d, a), P(d, b), p);
    if (o != 0) return o > 0;
    return strictly_between(P(d, a), P(d, b), p);
}

/* ---- location ------------------------------------------------------------------------------------ */

uint32_t fb_dt_locate(fb_dt *d, const double *p, uint32_t t)
{
    if (t >= d->nt) t = d->last; /* DT_NONE included */
    int k = inf_index(d->tv + 3 * (size_t)t);
    if (k >= 0) t = d->tn[3 * (size_t)t + k];
    uint32_t prev = DT_NONE;
    for (uint64_t step = 0;; step++) {
        const uint32_t *v = d->tv + 3 * (size_t)t;
        uint32_t next = DT_NONE;
        for (int j = 0; j < 3; j++) {
            int i = (int)((step + (uint64_t)j) % 3);
            uint32_t n = d->tn[3 * (size_t)t + i];
            if (n == prev) continue;
            if (fb_orient2d(P(d, v[(i + 1) % 3]), P(d, v[(i + 2) % 3]), p) < 0) {
                next = n;
                break;
            }
        }
        d->walk_steps++;
        if (next == DT_NONE) return t;
        prev = t;
        t = next;
        if (fb_dt_is_ghost(d, t)) return t;
    }
}

/* ---- insertion ----------------------------------------------------------------------------------- */

static void set_neighbour(fb_dt *d, uint32_t t, uint32_t u, uint32_t w, uint32_t nb)
{
    /* In triangle t, the edge (w, u) is opposite the vertex that is neither. */
    uint32_t *v = d->tv + 3 * (size_t)t;
    for (int i = 0; i < 3; i++)
        if (v[i] != u && v[i] != w) {
            d->tn[3 * (size_t)t + i] = nb;
            return;
        }
}

/* Inserts p as a new vertex, starting the cavity at t (which must conflict with p). Returns the
 * vertex index, or DT_NONE when out of memory. */
static uint32_t insert_at(fb_dt *d, const double *p, uint32_t t0)
{
    if (!reserve_vertices(d, d->nv + 1)) return DT_NONE;
    uint32_t s = ++d->stamp;
    if (!s) { /* wrapped: forget every old mark */
        memset(tmark(d), 0, d->capt * sizeof(uint32_t));
        s = d->stamp = 1;
    }
    uint32_t *tm = tmark(d);
    size_t ncav = 0, nstack = 0, nb = 0;
    if (!reserve_scratch(d, 16)) return DT_NONE;
    d->cavity[ncav++] = t0;
    d->stack[nstack++] = t0;
    tm[t0] = s;
    while (nstack) {
        uint32_t t = d->stack[--nstack];
        const uint32_t *v = d->tv + 3 * (size_t)t;
        for (int i = 0; i < 3; i++) {
            uint32_t n = d->tn[3 * (size_t)t + i];
            if (tm[n] == s) continue;
            if (!reserve_scratch(d, ncav + nb + 4)) return DT_NONE;
            if (conflict(d, n, p)) {
                tm[n] = s;
                d->cavity[ncav++] = n;
                d->stack[nstack++] = n;
            } else {
                uint32_t *b = d->bnd + 3 * nb++;
                b[0] = v[(i + 1) % 3], b[1] = v[(i + 2) % 3], b[2] = n;
            }
        }
    }
    /* nb new triangles replace ncav old ones: the cavity is a disc whose boundary has nb edges
     * and no inner vertex, so nb = ncav + 2 and no slot is ever freed. */
    if (!reserve_triangles(d, (size_t)d->nt + nb)) return DT_NONE;
    tm = tmark(d);
    for (size_t i = 0; i < ncav; i++) {
        uint32_t t = d->cavity[i];
        if (fb_dt_is_ghost(d, t))
            d->nghost--;
        else
            d->nfinite--;
    }
    uint32_t pv = d->nv++;
    d->xy[2 * (size_t)pv] = p[0], d->xy[2 * (size_t)pv + 1] = p[1];
    for (size_t j = 0; j < nb; j++) {
        uint32_t *b = d->bnd + 3 * j;
        uint32_t t = j < ncav ? d->cavity[j] : new_triangle(d);
        uint32_t *v = d->tv + 3 * (size_t)t;
        v[0] = b[0], v[1] = b[1], v[2] = pv;
        d->tn[3 * (size_t)t + 2] = b[2];
        set_neighbour(d, b[2], b[0], b[1], t);
        tm[t] = 0;
        d->newt_of[vslot(d, b[0])] = t;
        b[2] = t; /* from here on: the new triangle of this boundary edge */
        if (b[0] == DT_INF || b[1] == DT_INF)
            d->nghost++;
        else
            d->nfinite++;
    }
    for (size_t j = 0; j < nb; j++) {
        uint32_t *b = d->bnd + 3 * j, t = b[2];
        uint32_t t2 = d->newt_of[vslot(d, b[1])];
        d->tn[3 * (size_t)t + 0] = t2;
        d->tn[3 * (size_t)t2 + 1] = t;
        if (b[0] != DT_INF) d->vt[b[0]] = t;
        if (b[1] != DT_INF) d->vt[b[1]] = t;
    }
    d->vt[pv] = d->bnd[2];
    d->last = d->bnd[2];
    return pv;
}

int fb_dt_insert(fb_dt *d, double x, double y, uint32_t hint, uint32_t *vertex)
{
    double p[2] = {x, y};
    uint32_t t = fb_dt_locate(d, p, hint);
    const uint32_t *v = d->tv + 3 * (size_t)t;
    for (int i = 0; i < 3; i++)
        if (v[i] != DT_INF && P(d, v[i])[0] == x && P(d, v[i])[1] == y) {
            *vertex = v[i];
            d->duplicates++;
            return 1;
        }
    uint32_t pv = insert_at(d, p, t);
    if (pv == DT_NONE) return -1;
    *vertex = pv;
    return 0;
}

/* ---- batch construction ------------------------------------------------------------------------- */

/* The Hilbert index of (x, y) on a 2^16 x 2^16 grid. */
static uint32_t hilbert(uint32_t x, uint32_t y)
{
    const uint32_t n = 1u << 16;
    uint32_t h = 0;
    for (uint32_t s = n >> 1; s; s >>= 1) {
        uint32_t rx = (x & s) != 0, ry = (y & s) != 0;
        h += s * s * ((3 * rx) ^ ry);
        if (!ry) {
            if (rx) {
                x = n - 1 - x;
                y = n - 1 - y;
            }
            uint32_t t = x;
            x = y;
            y = t;
        }
    }
    return h;
}

/* Stable LSD radix sort of (key, index) pairs on the low 48 bits of the keys. */
static bool radix_sort(uint64_t *key, uint32_t *idx, size_t n)
{
    uint64_t *k2 = malloc(n * sizeof *k2);
    uint32_t *i2 = malloc(n * sizeof *i2);
    size_t *count = calloc(65536, sizeof *count);
    if (!k2 || !i2 || !count) {
        free(k2), free(i2), free(count);
        return false;
    }
    for (int pass = 0; pass < 3; pass++) {
        int shift = 16 * pass;
        memset(count, 0, 65536 * sizeof *count);
        for (size_t i = 0; i < n; i++) count[(key[i] >> shift) & 0xffff]++;
        size_t sum = 0;
        for (size_t b = 0; b < 65536; b++) {
            size_t c = count[b];
            count[b] = sum;
            sum += c;
        }
        for (size_t i = 0; i < n; i++) {
            size_t o = count[(key[i] >> shift) & 0xffff]++;
            k2[o] = key[i];
            i2[o] = idx[i];
        }
        memcpy(key, k2, n * sizeof *key);
        memcpy(idx, i2, n * sizeof *idx);
    }
    free(k2), free(i2), free(count);
    return true;
}

/* The insertion order: BRIO rounds (a point is in the last round with probability 1/2, in the one
 * before with 1/4, ...; a hash of its index decides, so the order is reproducible), each round in
 * Hilbert order over the bounding box. */
static uint32_t *brio_order(const double *xy, size_t n)
{
    uint64_t *key = malloc(n * sizeof *key);
    uint32_t *idx = malloc(n * sizeof *idx);
    if (!key || !idx) {
        free(key), free(idx);
        return NULL;
    }
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        x0 = fmin(x0, xy[2 * i]), x1 = fmax(x1, xy[2 * i]);
        y0 = fmin(y0, xy[2 * i + 1]), y1 = fmax(y1, xy[2 * i + 1]);
    }
    double sx = x1 > x0 ? 65535.0 / (x1 - x0) : 0, sy = y1 > y0 ? 65535.0 / (y1 - y0) : 0;
    const int rounds = 12;
    for (size_t i = 0; i < n; i++) {
        uint32_t h = k_hash3(0x5eedu, 7u, (uint32_t)i);
        int r = h ? __builtin_ctz(h) : 31; /* round from the end: P(r) = 2^-(r+1) */
        if (r > rounds - 1) r = rounds - 1;
        uint32_t hx = (uint32_t)((xy[2 * i] - x0) * sx), hy = (uint32_t)((xy[2 * i + 1] - y0) * sy);
        key[i] = ((uint64_t)(rounds - 1 - r) << 32) | hilbert(hx > 65535 ? 65535 : hx, hy > 65535 ? 65535 : hy);
        idx[i] = (uint32_t)i;
    }
    bool ok = radix_sort(key, idx, n);
    free(key);
    if (!ok) {
        free(idx);
        return NULL;
    }
    return idx;
}

static void make_first_triangle(fb_dt *d, uint32_t a, uint32_t b, uint32_t c)
{
    /* (a, b, c) counter-clockwise; the ghosts (c, b, inf), (a, c, inf), (b, a, inf) close it. */
    uint32_t T = new_triangle(d), g1 = new_triangle(d), g2 = new_triangle(d), g3 = new_triangle(d);
    uint32_t *v = d->tv, *n = d->tn;
    v[3 * T] = a, v[3 * T + 1] = b, v[3 * T + 2] = c;
    v[3 * g1] = c, v[3 * g1 + 1] = b, v[3 * g1 + 2] = DT_INF;
    v[3 * g2] = a, v[3 * g2 + 1] = c, v[3 * g2 + 2] = DT_INF;
    v[3 * g3] = b, v[3 * g3 + 1] = a, v[3 * g3 + 2] = DT_INF;
    n[3 * T] = g1, n[3 * T + 1] = g2, n[3 * T + 2] = g3;
    n[3 * g1] = g3, n[3 * g1 + 1] = g2, n[3 * g1 + 2] = T;
    n[3 * g2] = g1, n[3 * g2 + 1] = g3, n[3 * g2 + 2] = T;
    n[3 * g3] = g2, n[3 * g3 + 1] = g1, n[3 * g3 + 2] = T;
    d->vt[a] = d->vt[b] = d->vt[c] = T;
    d->nfinite = 1;
    d->nghost = 3;
    d->last = T;
}

fb_result fb_dt_build(fb_dt *d, const double *xy, size_t n, uint32_t *perm_out, const char *who)
{
    memset(d, 0, sizeof *d);
    if (n > (size_t)UINT32_MAX / 4) return fb_fail(FB_ERR_INPUT, "%s: %zu points are too many", who, n);
    uint32_t *order = n ? brio_order(xy, n) : NULL;
    if (n && !order) return fb_fail(FB_ERR_NOMEM, "%s: out of memory sorting %zu points", who, n);
    /* Three points in general position, the first of them the first in the order. */
    size_t i1 = 0, i2 = 0;
    const double *p0 = n ? xy + 2 * (size_t)order[0] : NULL;
    for (i1 = 1; i1 < n; i1++) {
        const double *q = xy + 2 * (size_t)order[i1];
        if (q[0] != p0[0] || q[1] != p0[1]) break;
    }
    for (i2 = i1 + 1; i1 < n && i2 < n; i2++)
        if (fb_orient2d(p0, xy + 2 * (size_t)order[i1], xy + 2 * (size_t)order[i2]) != 0) break;
    if (i1 >= n || i2 >= n) {
        free(order);
        return fb_fail(FB_ERR_INPUT, "%s: %s", who,
                       i1 >= n ? "fewer than three distinct points" : "all points are collinear");
    }
    fb_result rc = FB_ERR_NOMEM;
    if (!reserve_vertices(d, (uint32_t)(n < 16 ? 16 : n)) || !reserve_triangles(d, 2 * n + 16)) goto fail;
    uint32_t tri[3] = {order[0], order[i1], order[i2]};
    if (fb_orient2d(xy + 2 * (size_t)tri[0], xy + 2 * (size_t)tri[1], xy + 2 * (size_t)tri[2]) < 0) {
        uint32_t t = tri[1];
        tri[1] = tri[2], tri[2] = t;
    }
    for (int k = 0; k < 3; k++) {
        d->xy[2 * k] = xy[2 * (size_t)tri[k]], d->xy[2 * k + 1] = xy[2 * (size_t)tri[k] + 1];
        if (perm_out) perm_out[k] = tri[k];
    }
    d->nv = 3;
    make_first_triangle(d, 0, 1, 2);
    for (size_t k = 1; k < n; k++) {
        if (k == i1 || k == i2) continue;
        uint32_t src = order[k], v;
        int r = fb_dt_insert(d, xy[2 * (size_t)src], xy[2 * (size_t)src + 1], DT_NONE, &v);
        if (r < 0) goto fail;
        if (r == 0 && perm_out) perm_out[v] = src;
    }
    free(order);
    return FB_OK;
fail:
    free(order);
    fb_dt_free(d);
    return fb_fail(rc, "%s: out of memory building the triangulation of %zu points", who, n);
}

/* ---- the oracle ------------------------------------------------------------------------------------ */

static int find_back(const fb_dt *d, uint32_t n, uint32_t t)
{
    for (int i = 0; i < 3; i++)
        if (d->tn[3 * (size_t)n + i] == t) return i;
    return -1;
}

uint64_t fb_dt_check(const fb_dt *d, fb_dt_check_report *rep)
{
    fb_dt_check_report r = {0};
    for (uint32_t t = 0; t < d->nt; t++) {
        const uint32_t *v = d->tv + 3 * (size_t)t;
        bool ghost = fb_dt_is_ghost(d, t);
        if (ghost)
            r.hull++;
        else
            r.triangles++;
        for (int i = 0; i < 3; i++) {
            uint32_t n = d->tn[3 * (size_t)t + i];
            uint32_t a = v[(i + 1) % 3], b = v[(i + 2) % 3];
            int k = n < d->nt ? find_back(d, n, t) : -1;
            const uint32_t *w = k >= 0 ? d->tv + 3 * (size_t)n : NULL;
            /* the neighbour must hold the edge reversed: (b, a) after its vertex k */
            if (k < 0 || w[(k + 1) % 3] != b || w[(k + 2) % 3] != a) {
                r.adjacency++;
                continue;
            }
            if (ghost || fb_dt_is_ghost(d, n) || n < t) continue;
            if (fb_incircle(P(d, v[0]), P(d, v[1]), P(d, v[2]), P(d, w[k])) > 0) r.empty_circle++;
        }
        if (!ghost) {
            if (fb_orient2d(P(d, v[0]), P(d, v[1]), P(d, v[2])) <= 0) r.orientation++;
        } else {
            uint32_t a, b, b2, c;
            ghost_edge(d, t, &a, &b);
            /* the next hull edge (b, c) is the ghost across the edge (b, inf) */
            int ia = v[0] == a ? 0 : v[1] == a ? 1 : 2;
            uint32_t g = d->tn[3 * (size_t)t + ia];
            if (g < d->nt && fb_dt_is_ghost(d, g)) {
                ghost_edge(d, g, &b2, &c);
                if (b2 != b)
                    r.adjacency++;
                else if (fb_orient2d(P(d, a), P(d, b), P(d, c)) > 0)
                    r.hull_convexity++;
            } else {
                r.adjacency++;
            }
        }
    }
    for (uint32_t v = 0; v < d->nv; v++) {
        uint32_t t = d->vt[v];
        const uint32_t *w = d->tv + 3 * (size_t)t;
        if (t >= d->nt || (w[0] != v && w[1] != v && w[2] != v)) r.adjacency++;
    }
    if (r.triangles != d->nfinite || r.hull != d->nghost) r.adjacency++;
    if (rep) *rep = r;
    return r.orientation + r.empty_circle + r.hull_convexity + r.adjacency;
}
