/*
 * Delaunay refinement of survey points (see terrain.h and SPEC.md section 4).
 */
#include "terrain.h"

#include "terrain_hull.h"

#include "kernels/hash.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define STREAM_SITE_X 0x51u
#define STREAM_SITE_Y 0x52u
#define STREAM_GAUSS  0x53u
#define STREAM_ADD    0x54u

void fb_terrain_free(fb_terrain *t)
{
    if (!t) return;
    fb_dt_free(&t->dt);
    free(t->z);
    memset(t, 0, sizeof *t);
}

static bool reserve_z(fb_terrain *t, size_t need)
{
    if (need <= t->capz) return true;
    size_t c = t->capz ? t->capz : 64;
    while (c < need) c *= 2;
    double *z = realloc(t->z, c * sizeof *z);
    if (!z) return false;
    t->z = z;
    t->capz = c;
    return true;
}

fb_result fb_terrain_build(fb_terrain *t, const double *xyz, size_t n, const char *who, fb_terrain_stats *st)
{
    memset(t, 0, sizeof *t);
    double t0 = fb_now();
    double *xy = malloc((n ? n : 1) * 2 * sizeof *xy);
    uint32_t *perm = malloc((n ? n : 1) * sizeof *perm);
    if (!xy || !perm) {
        free(xy), free(perm);
        return fb_fail(FB_ERR_NOMEM, "%s: out of memory for %zu points", who, n);
    }
    for (size_t i = 0; i < n; i++) xy[2 * i] = xyz[3 * i], xy[2 * i + 1] = xyz[3 * i + 1];
    fb_result rc = fb_dt_build(&t->dt, xy, n, perm, who);
    free(xy);
    if (rc) {
        free(perm);
        return rc;
    }
    if (!reserve_z(t, t->dt.capv)) {
        free(perm);
        fb_terrain_free(t);
        return fb_fail(FB_ERR_NOMEM, "%s: out of memory", who);
    }
    t->ninput = t->dt.nv;
    t->bbox[0] = t->bbox[2] = INFINITY, t->bbox[1] = t->bbox[3] = -INFINITY;
    for (uint32_t v = 0; v < t->dt.nv; v++) {
        t->z[v] = xyz[3 * (size_t)perm[v] + 2];
        const double *p = t->dt.xy + 2 * (size_t)v;
        t->bbox[0] = fmin(t->bbox[0], p[0]), t->bbox[1] = fmax(t->bbox[1], p[0]);
        t->bbox[2] = fmin(t->bbox[2], p[1]), t->bbox[3] = fmax(t->bbox[3], p[1]);
    }
    free(perm);
    if (st) {
        st->input = t->dt.nv;
        st->duplicates = t->dt.duplicates;
        st->build_seconds = fb_now() - t0;
    }
    return FB_OK;
}

double fb_terrain_sigma2_estimate(const fb_terrain *t, double hurst)
{
    const fb_dt *d = &t->dt;
    double sum = 0;
    uint64_t n = 0;
    for (uint32_t tr = 0; tr < d->nt; tr++) {
        if (fb_dt_is_ghost(d, tr)) continue;
        const uint32_t *v = d->tv + 3 * (size_t)tr;
        for (int i = 0; i < 3; i++) {
            uint32_t a = v[(i + 1) % 3], b = v[(i + 2) % 3], nb = d->tn[3 * (size_t)tr + i];
            if (a >= t->ninput || b >= t->ninput) continue;
            if (!fb_dt_is_ghost(d, nb) && nb < tr) continue; /* each edge once */
            double dist =
                hypot(d->xy[2 * (size_t)a] - d->xy[2 * (size_t)b], d->xy[2 * (size_t)a + 1] - d->xy[2 * (size_t)b + 1]);
            double dz = t->z[a] - t->z[b];
            sum += dz * dz / pow(dist, 2 * hurst);
            n++;
        }
    }
    return n ? sum / (double)n : 0.0;
}

double fb_terrain_gauss(uint32_t seed, uint64_t index)
{
    uint32_t lo = (uint32_t)index, hi = (uint32_t)(index >> 32);
    uint32_t h1 = k_hash3(seed ^ k_hash(hi), STREAM_GAUSS, 2 * lo);
    uint32_t h2 = k_hash3(seed ^ k_hash(hi), STREAM_GAUSS, 2 * lo + 1);
    double u1 = ((double)h1 + 0.5) * 0x1p-32, u2 = (double)h2 * 0x1p-32;
    return sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2);
}

/* The variance of z_abc - z_* over the finite triangles of a list. */
static double diff_variance(const fb_terrain *t, const uint32_t *tris, size_t n)
{
    double sum = 0;
    size_t m = 0;
    for (size_t k = 0; k < n; k++) {
        const uint32_t *v = t->dt.tv + 3 * (size_t)tris[k];
        double za = t->z[v[0]], zb = t->z[v[1]], zc = t->z[v[2]], mean = (za + zb + zc) / 3;
        sum += (mean - za) * (mean - za) + (mean - zb) * (mean - zb) + (mean - zc) * (mean - zc);
        m += 3;
    }
    return m ? sum / (double)m : 0.0;
}

/* Per stage: over the whole mesh. */
static double stage_variance(const fb_terrain *t)
{
    const fb_dt *d = &t->dt;
    double sum = 0;
    uint64_t m = 0;
    for (uint32_t tr = 0; tr < d->nt; tr++) {
        if (fb_dt_is_ghost(d, tr)) continue;
        sum += diff_variance(t, &tr, 1) * 3;
        m += 3;
    }
    return m ? sum / (double)m : 0.0;
}

/* Local: over the triangle's neighbourhood. */
static double local_variance(const fb_terrain *t, uint32_t tr)
{
    uint32_t list[16];
    size_t n = fb_terrain_neighbourhood(&t->dt, tr, list);
    return diff_variance(t, list, n);
}

/* A hint grid for locating random sites: each cell remembers the last vertex inserted in it. */
typedef struct hint_grid {
    uint32_t *cell;
    uint32_t side;
    double x0, y0, sx, sy;
} hint_grid;

static uint32_t grid_index(const hint_grid *g, double x, double y)
{
    double fx = (x - g->x0) * g->sx, fy = (y - g->y0) * g->sy;
    uint32_t ix = fx <= 0 ? 0 : fx >= g->side - 1 ? g->side - 1 : (uint32_t)fx;
    uint32_t iy = fy <= 0 ? 0 : fy >= g->side - 1 ? g->side - 1 : (uint32_t)fy;
    return iy * g->side + ix;
}

static bool grid_rebuild(hint_grid *g, const fb_terrain *t)
{
    uint32_t side = (uint32_t)ceil(sqrt(t->dt.nv / 2.0));
    if (side < 1) side = 1;
    if (side > 4096) side = 4096;
    uint32_t *c = malloc((size_t)side * side * sizeof *c);
    if (!c) return false;
    free(g->cell);
    g->cell = c;
    g->side = side;
    g->x0 = t->bbox[0], g->y0 = t->bbox[2];
    g->sx = t->bbox[1] > t->bbox[0] ? side / (t->bbox[1] - t->bbox[0]) : 0;
    g->sy = t->bbox[3] > t->bbox[2] ? side / (t->bbox[3] - t->bbox[2]) : 0;
    for (size_t i = 0; i < (size_t)side * side; i++) c[i] = DT_NONE;
    for (uint32_t v = 0; v < t->dt.nv; v++) c[grid_index(g, t->dt.xy[2 * (size_t)v], t->dt.xy[2 * (size_t)v + 1])] = v;
    /* Empty cells borrow a neighbour's vertex (along the row, then from the nearest filled row), so
     * that no walk starts far away. */
    for (uint32_t y = 0; y < side; y++) {
        uint32_t *row = c + (size_t)y * side, last = DT_NONE;
        for (uint32_t x = 0; x < side; x++) row[x] = row[x] == DT_NONE ? last : (last = row[x]);
        last = DT_NONE;
        for (uint32_t x = side; x-- > 0;) row[x] = row[x] == DT_NONE ? last : (last = row[x]);
    }
    for (uint32_t y = 1; y < side; y++)
        if (c[(size_t)y * side] == DT_NONE) memcpy(c + (size_t)y * side, c + (size_t)(y - 1) * side, side * sizeof *c);
    for (uint32_t y = side - 1; y-- > 0;)
        if (c[(size_t)y * side] == DT_NONE) memcpy(c + (size_t)y * side, c + (size_t)(y + 1) * side, side * sizeof *c);
    return true;
}

/* The area of the finite triangles: the hull's, which refinement does not change. */
static double mesh_area(const fb_terrain *t)
{
    const fb_dt *d = &t->dt;
    double sum = 0;
    for (uint32_t tr = 0; tr < d->nt; tr++) {
        if (fb_dt_is_ghost(d, tr)) continue;
        const uint32_t *v = d->tv + 3 * (size_t)tr;
        const double *a = d->xy + 2 * (size_t)v[0], *b = d->xy + 2 * (size_t)v[1], *c = d->xy + 2 * (size_t)v[2];
        sum += fabs((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])) / 2;
    }
    return sum;
}

/* ---- additions: a continuous fBm field plus the survey's residual, refined -------------------------
 *
 * F(p) = sum_i a_i cos(k_i . p + phi_i): random waves whose wavenumbers |k_i| are spread evenly in
 * log |k| (one stratum per wave, jittered) from KMIN_LAG / D (D the data's bounding-box diagonal)
 * to 4 waves per final vertex spacing h, directions stratified over a half turn within each octave,
 * phases uniform. With a_i^2 = w |k_i|^(-2H) L / M (L = ln(kmax / kmin), M waves) the structure
 * function is E (F(p) - F(q))^2 = sum a_i^2 (1 - J0(|k_i| l)) -> w l^(2H) I(H), l = |p - q|, with
 * I(H) = int_0^inf u^(-2H-1) (1 - J0(u)) du = 2^(-2H-1) Gamma(1 - H) / (H Gamma(1 + H)); so
 * w = sigma^2 / I(H) gives sigma^2 l^(2H). The scales finer than 1 / kmax are independent from one
 * vertex to the next: each inserted vertex adds one Gaussian of their variance, w kmax^(-2H) / (4H).
 *
 * A vertex's height is F plus the residual r = z - F: the input vertices' residual is their height
 * minus F there (so they keep their heights exactly), and an inserted vertex takes the mean residual
 * of its triangle's vertices. The survey fixes the large scales; F brings every scale below them
 * with the asked H, the earlier vertices' as well as the new one's. */
#define KMIN_LAG         1e-4
#define WAVES_PER_OCTAVE 12

typedef struct fbm_field {
    double *k;   /* kx, ky, phase per wave */
    double *amp; /* per wave, per centre (or the one global H and sigma) */
    double *nugget_sd;
    int nwaves;
    double origin[2]; /* the data's lower-left corner: phases stay small for large coordinates */
} fbm_field;

static double fbm_integral(double H)
{
    return pow(2, -2 * H - 1) * tgamma(1 - H) / (H * tgamma(1 + H));
}

static void fbm_field_free(fbm_field *f)
{
    free(f->k), free(f->amp), free(f->nugget_sd);
    memset(f, 0, sizeof *f);
}

/* hs: (H, sigma^2) pairs, n of them (the centres, or the one global pair). */
static bool fbm_field_init(fbm_field *f, uint32_t seed, const double *bbox, double hfinal, const double *hs, int n)
{
    memset(f, 0, sizeof *f);
    double diag = hypot(bbox[1] - bbox[0], bbox[3] - bbox[2]);
    f->origin[0] = bbox[0], f->origin[1] = bbox[2];
    double kmin = KMIN_LAG / diag, kmax = 8 * M_PI / hfinal, L = log(kmax / kmin);
    int octaves = (int)ceil(L / log(2.0));
    int M = octaves * WAVES_PER_OCTAVE;
    f->k = malloc((size_t)M * 3 * sizeof *f->k);
    f->amp = malloc((size_t)M * n * sizeof *f->amp);
    f->nugget_sd = malloc((size_t)n * sizeof *f->nugget_sd);
    if (!f->k || !f->amp || !f->nugget_sd) {
        fbm_field_free(f);
        return false;
    }
    f->nwaves = M;
    for (int i = 0; i < M; i++) {
        uint32_t s = seed ^ k_hash(0xadd17105u + (uint32_t)i);
        double u0 = k_hash3(s, STREAM_ADD, 0) * 0x1p-32, u1 = k_hash3(s, STREAM_ADD, 1) * 0x1p-32;
        double u2 = k_hash3(s, STREAM_ADD, 2) * 0x1p-32;
        double lk = log(kmin) + (i + u0) * L / M, kk = exp(lk);
        double th = M_PI * ((i % WAVES_PER_OCTAVE) + u1) / WAVES_PER_OCTAVE;
        f->k[3 * i] = kk * cos(th), f->k[3 * i + 1] = kk * sin(th), f->k[3 * i + 2] = 2 * M_PI * u2;
        for (int c = 0; c < n; c++) {
            double H = hs[2 * c], w = hs[2 * c + 1] / fbm_integral(H);
            f->amp[(size_t)c * M + i] = sqrt(w * exp(-2 * H * lk) * L / M);
        }
    }
    for (int c = 0; c < n; c++) {
        double H = hs[2 * c], w = hs[2 * c + 1] / fbm_integral(H);
        f->nugget_sd[c] = sqrt(w * pow(kmax, -2 * H) / (4 * H));
    }
    return true;
}

/* cos x in plain arithmetic, the same bits on every machine and twice as fast as libm here for the
 * fine waves' large arguments: x reduced to r in [-pi, pi] (an error of about |x| 1e-16, the size of
 * x's own rounding; 7e-12 at |x| = 1e5), then cos r = 2 cos^2(r / 2) - 1 with the Taylor series of
 * cos to degree 22 on [-pi/2, pi/2] (truncation 2e-17). */
static inline double cos_poly(double x)
{
    const double inv2pi = 0.15915494309189535, pi2_hi = 6.283185307179586, pi2_lo = 2.4492935982947064e-16;
    const double magic = 0x1.8p52; /* adding and subtracting it rounds to an integer (|x| < 2^50) */
    double n = (x * inv2pi + magic) - magic, r = (x - n * pi2_hi) - n * pi2_lo, h = 0.25 * r * r; /* (r / 2)^2 */
    double c = -1.0 / 1124000727777607680000.0;                                                   /* -1 / 22! */
    static const double inv_fact[10] = {-1.0 / 2,
                                        1.0 / 24,
                                        -1.0 / 720,
                                        1.0 / 40320,
                                        -1.0 / 3628800,
                                        1.0 / 479001600,
                                        -1.0 / 87178291200,
                                        1.0 / 20922789888000,
                                        -1.0 / 6402373705728000,
                                        1.0 / 2432902008176640000.0};
    for (int k = 9; k >= 0; k--) c = c * h + inv_fact[k];
    c = c * h + 1;
    return 2 * c * c - 1;
}

static double fbm_at(const fbm_field *f, int c, const double *p)
{
    const double *a = f->amp + (size_t)c * f->nwaves;
    double x = p[0] - f->origin[0], y = p[1] - f->origin[1];
    double acc[4] = {0, 0, 0, 0}; /* four partial sums (nwaves is a multiple of 4): independent chains */
    for (int i = 0; i < f->nwaves; i += 4)
        for (int j = 0; j < 4; j++)
            acc[j] += a[i + j] * cos_poly(f->k[3 * (i + j)] * x + f->k[3 * (i + j) + 1] * y + f->k[3 * (i + j) + 2]);
    return (acc[0] + acc[1]) + (acc[2] + acc[3]);
}

static const fb_terrain_center *nearest_center(const fb_terrain_opts *o, const double *p)
{
    const fb_terrain_center *best = NULL;
    double bd = INFINITY;
    for (int i = 0; i < o->ncenters; i++) {
        double dx = p[0] - o->centers[i].x, dy = p[1] - o->centers[i].y, dd = dx * dx + dy * dy;
        if (dd < bd) bd = dd, best = &o->centers[i];
    }
    return best;
}

/* The field F for the asked H and sigma (or each centre's) over t's hull, refined to nv_final vertices. */
static bool field_make(const fb_terrain *t, const fb_terrain_opts *o, double sigma2, const double *csig2,
                       uint64_t nv_final, fbm_field *f)
{
    double hfinal = sqrt(mesh_area(t) / (double)nv_final);
    int n = o->ncenters ? o->ncenters : 1;
    double *hs = malloc((size_t)n * 2 * sizeof *hs);
    if (!hs) return false;
    for (int c = 0; c < n; c++) {
        hs[2 * c] = o->ncenters ? o->centers[c].hurst : o->hurst;
        hs[2 * c + 1] = o->ncenters ? csig2[c] : sigma2;
    }
    bool ok = fbm_field_init(f, o->seed, t->bbox, hfinal, hs, n);
    free(hs);
    return ok;
}

fb_result fb_terrain_field(const fb_terrain *t, const fb_terrain_opts *o, double sigma2, uint64_t nv_final,
                           const double *xy, size_t n, double *z)
{
    fb_terrain_opts global = *o; /* the one H and sigma: centres ignored */
    global.ncenters = 0;
    fbm_field f;
    if (!field_make(t, &global, sigma2, NULL, nv_final, &f))
        return fb_fail(FB_ERR_NOMEM, "terrain field: out of memory");
    for (size_t i = 0; i < n; i++) z[i] = fbm_at(&f, 0, xy + 2 * i);
    fbm_field_free(&f);
    return FB_OK;
}

/* The field, and the input vertices' residuals: their heights minus F. */
static fb_result additions_init(const fb_terrain *t, const fb_terrain_opts *o, double sigma2, const double *csig2,
                                fbm_field *f, double **resid, const char *who)
{
    const fb_dt *d = &t->dt;
    *resid = malloc(((size_t)d->nv + o->insert) * sizeof **resid);
    if (!*resid || !field_make(t, o, sigma2, csig2, (uint64_t)d->nv + o->insert, f)) {
        free(*resid), *resid = NULL;
        return fb_fail(FB_ERR_NOMEM, "%s: out of memory", who);
    }
    for (uint32_t v = 0; v < d->nv; v++) {
        const double *p = d->xy + 2 * (size_t)v;
        int c = o->ncenters ? (int)(nearest_center(o, p) - o->centers) : 0;
        (*resid)[v] = t->z[v] - fbm_at(f, c, p);
    }
    return FB_OK;
}

/* sigma^2 of each centre (given, the global one, or estimated from its Hurst exponent) in *out
 * (NULL without centres); refuses variances that overflowed (heights or distances too large for
 * their squares), given or estimated, which would turn the mesh into NaN or infinities. */
static fb_result center_variances(const fb_terrain *t, const fb_terrain_opts *o, double sigma2, const char *who,
                                  double **out)
{
    double *csig2 = NULL;
    if (o->ncenters) {
        csig2 = malloc((size_t)o->ncenters * sizeof *csig2);
        if (!csig2) return fb_fail(FB_ERR_NOMEM, "%s: out of memory", who);
        for (int i = 0; i < o->ncenters; i++) {
            const fb_terrain_center *c = &o->centers[i];
            csig2[i] = c->sigma >= 0   ? c->sigma * c->sigma
                       : o->sigma >= 0 ? sigma2
                                       : fb_terrain_sigma2_estimate(t, c->hurst);
        }
    }
    bool finite = isfinite(sigma2);
    for (int i = 0; i < o->ncenters && csig2; i++) finite = finite && isfinite(csig2[i]);
    if (!finite) {
        free(csig2);
        return fb_fail(FB_ERR_INPUT,
                       "%s: the variance of the height increments is not a finite number (sigma^2 = %g): the "
                       "points' heights or distances are too large",
                       who, sigma2);
    }
    *out = csig2;
    return FB_OK;
}

fb_result fb_terrain_refine(fb_terrain *t, const fb_terrain_opts *o, const char *who, fb_terrain_stats *st)
{
    double t0 = fb_now();
    fb_dt *d = &t->dt;
    fb_terrain_stats local_st = {0};
    if (!st) st = &local_st;
    /* sigma^2 per centre (or the one global value), estimated where not given */
    double sigma2 = o->sigma >= 0 ? o->sigma * o->sigma : fb_terrain_sigma2_estimate(t, o->hurst);
    st->sigma = sqrt(sigma2);
    double *csig2 = NULL;
    fb_result rc = center_variances(t, o, sigma2, who, &csig2);
    if (rc) return rc;
    hint_grid g = {0};
    if (!o->sweep && !grid_rebuild(&g, t)) {
        free(csig2);
        return fb_fail(FB_ERR_NOMEM, "%s: out of memory", who);
    }
    double V = o->additions ? 0 : stage_variance(t);
    uint32_t stage_nv = d->nv;
    st->stages = o->additions ? 0 : 1;
    /* additions: the field F and each vertex's residual */
    fbm_field field = {0};
    double *resid = NULL;
    if (o->additions && (rc = additions_init(t, o, sigma2, csig2, &field, &resid, who))) {
        free(g.cell);
        free(csig2);
        return rc;
    }
    uint64_t draws = 0, cursor = 0, attempts = 0;
    const uint64_t max_attempts = o->insert * 64 + 4096;
    for (uint64_t i = 0; i < o->insert;) {
        if (++attempts > max_attempts) {
            rc = fb_fail(FB_ERR_INPUT, "%s: could not place new points (the hull has no room left at double precision)",
                         who);
            break;
        }
        uint32_t tr;
        if (o->sweep) {
            for (;; cursor++) {
                tr = (uint32_t)(cursor % d->nt);
                if (!fb_dt_is_ghost(d, tr)) break;
            }
            cursor++;
        } else {
            uint64_t k = draws++;
            uint32_t s = o->seed ^ k_hash((uint32_t)(k >> 32));
            double q[2] = {t->bbox[0] + (t->bbox[1] - t->bbox[0]) * (k_hash3(s, STREAM_SITE_X, (uint32_t)k) * 0x1p-32),
                           t->bbox[2] + (t->bbox[3] - t->bbox[2]) * (k_hash3(s, STREAM_SITE_Y, (uint32_t)k) * 0x1p-32)};
            uint32_t hv = g.cell[grid_index(&g, q[0], q[1])]; /* never empty: see grid_rebuild */
            tr = fb_dt_locate(d, q, d->vt[hv]);
            if (fb_dt_is_ghost(d, tr)) {
                st->rejected++;
                continue;
            }
        }
        const uint32_t *v = d->tv + 3 * (size_t)tr;
        const double *a = d->xy + 2 * (size_t)v[0], *b = d->xy + 2 * (size_t)v[1], *c = d->xy + 2 * (size_t)v[2];
        double p[2] = {(a[0] + b[0] + c[0]) / 3, (a[1] + b[1] + c[1]) / 3}, mid[2];
        uint32_t owner;
        int he = fb_terrain_encroached(d, tr, p, &owner);
        const uint32_t *ov = d->tv + 3 * (size_t)owner;
        bool split = he >= 0 && fb_terrain_hull_midpoint(d, owner, d->xy + 2 * (size_t)ov[(he + 1) % 3],
                                                         d->xy + 2 * (size_t)ov[(he + 2) % 3], mid);
        if (split) { /* the hull edge's midpoint instead, from its triangle's corners */
            tr = owner, v = ov, p[0] = mid[0], p[1] = mid[1];
            a = d->xy + 2 * (size_t)v[0], b = d->xy + 2 * (size_t)v[1], c = d->xy + 2 * (size_t)v[2];
        }
        if (d->nv >= 2 * (uint64_t)stage_nv && !o->local_variance && !o->additions) {
            V = stage_variance(t);
            stage_nv = d->nv;
            st->stages++;
        }
        double H = o->hurst, s2 = sigma2;
        uint32_t ci = 0;
        if (o->ncenters) {
            const fb_terrain_center *cc = nearest_center(o, p);
            ci = (uint32_t)(cc - o->centers);
            H = cc->hurst, s2 = csig2[ci];
        }
        fb_hull_weights hw; /* on a hull edge: the neighbourhood's weights in the new height */
        if (split && !fb_terrain_hull_krige(d, tr, p, H, &hw)) split = false; /* then the plain mean */
        double z = (t->z[v[0]] + t->z[v[1]] + t->z[v[2]]) / 3,
               res = resid ? (resid[v[0]] + resid[v[1]] + resid[v[2]]) / 3 : 0;
        if (split) {
            z = res = 0;
            for (int k = 0; k < hw.n; k++) z += hw.w[k] * t->z[hw.v[k]], res += resid ? hw.w[k] * resid[hw.v[k]] : 0;
        }
        if (o->additions) {
            int c = o->ncenters ? (int)ci : 0;
            z = res + fbm_at(&field, c, p) + field.nugget_sd[c] * fb_terrain_gauss(o->seed, i);
        } else { /* equations IV to VI; on a hull edge, a third of the kriging variance (terrain_hull.h) */
            double var_abc = o->local_variance ? local_variance(t, tr) : V, var = 0;
            for (int k = 0; k < 3; k++) {
                const double *x = d->xy + 2 * (size_t)v[k];
                double dx = p[0] - x[0], dy = p[1] - x[1];
                var += pow(dx * dx + dy * dy, H) * s2 - var_abc; /* |p - x|^(2H) sigma^2 */
            }
            var = split ? s2 * hw.kvar / 6 : var / 9; /* split: a third of (sigma^2 / 2) kvar */
            if (var < 0) {
                st->clamped++;
                var = 0;
            }
            z += sqrt(var) * fb_terrain_gauss(o->seed, i);
        }
        if (!reserve_z(t, (size_t)d->nv + 1)) {
            rc = fb_fail(FB_ERR_NOMEM, "%s: out of memory after %llu inserted points", who, (unsigned long long)i);
            break;
        }
        uint32_t nvx;
        int r = fb_dt_insert(d, p[0], p[1], tr, &nvx);
        if (r < 0) {
            rc = fb_fail(FB_ERR_NOMEM, "%s: out of memory after %llu inserted points", who, (unsigned long long)i);
            break;
        }
        if (r > 0) { /* the barycentre rounded onto a vertex: a triangle too small for doubles */
            st->rejected++;
            continue;
        }
        t->z[nvx] = z;
        if (resid) resid[nvx] = res;
        st->hull_splits += split;
        i++;
        st->inserted = i;
        if (!o->sweep) {
            if (d->nv > 4ull * g.side * g.side && g.side < 4096 && !grid_rebuild(&g, t)) {
                rc = fb_fail(FB_ERR_NOMEM, "%s: out of memory", who);
                break;
            }
            g.cell[grid_index(&g, p[0], p[1])] = nvx;
        }
        if (o->progress && (i & 0xffff) == 0) o->progress(o->user, i, o->insert);
    }
    free(g.cell);
    free(csig2);
    free(resid);
    fbm_field_free(&field);
    st->refine_seconds = fb_now() - t0;
    return rc;
}
