/*
 * Terrain: exact predicates against integer arithmetic, the Delaunay oracle on hard inputs, qhull
 * agreement (when built with libqhull), degenerate input, and the refinement's properties (exact
 * interpolation, counts, determinism, variogram slopes, regions).
 */
#include "delaunay.h"
#include "predicates.h"
#include "terrain.h"
#include "terrain_io.h"
#include "testhelp.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

#ifdef FB_HAVE_QHULL
#include <libqhull_r/qhull_ra.h>
#endif

/* ---- predicates against exact integer determinants ------------------------------------------------ */

static int sgn128(__int128 v)
{
    return v > 0 ? 1 : v < 0 ? -1 : 0;
}
static int sgnd(double v)
{
    return v > 0 ? 1 : v < 0 ? -1 : 0;
}

static void test_predicates(void)
{
    int bad_o = 0, bad_i = 0, zero_o = 0, zero_i = 0;
    for (int k = 0; k < 200000; k++) {
        /* small integers on a big offset: many exact collinear / cocircular cases, and the float
         * evaluation loses the low bits (offset 2^40 makes the products exceed 2^53) */
        const int64_t off = (int64_t)1 << 40;
        int64_t ix[4], iy[4];
        for (int i = 0; i < 4; i++) ix[i] = off + (int64_t)(th_next() % 5), iy[i] = off + (int64_t)(th_next() % 5);
        double p[4][2];
        for (int i = 0; i < 4; i++) p[i][0] = (double)ix[i], p[i][1] = (double)iy[i];
        __int128 ax = ix[0] - ix[3], ay = iy[0] - iy[3], bx = ix[1] - ix[3], by = iy[1] - iy[3], cx = ix[2] - ix[3],
                 cy = iy[2] - iy[3];
        __int128 o = (__int128)(ix[1] - ix[0]) * (iy[2] - iy[0]) - (__int128)(iy[1] - iy[0]) * (ix[2] - ix[0]);
        __int128 ic = (ax * ax + ay * ay) * (bx * cy - cx * by) + (bx * bx + by * by) * (cx * ay - ax * cy) +
                      (cx * cx + cy * cy) * (ax * by - bx * ay);
        bad_o += sgnd(fb_orient2d(p[0], p[1], p[2])) != sgn128(o);
        bad_o += sgnd(fb_orient2d_exact(p[0], p[1], p[2])) != sgn128(o);
        bad_i += sgnd(fb_incircle(p[0], p[1], p[2], p[3])) != sgn128(ic);
        bad_i += sgnd(fb_incircle_exact(p[0], p[1], p[2], p[3])) != sgn128(ic);
        zero_o += o == 0;
        zero_i += ic == 0;
    }
    CHECKF(bad_o == 0, "%d orient2d signs differ from the integer determinant", bad_o);
    CHECKF(bad_i == 0, "%d incircle signs differ from the integer determinant", bad_i);
    CHECK(zero_o > 1000 && zero_i > 1000); /* the degenerate cases were exercised */
    /* Non-representable translations: points near (0.5, 0.5) perturbed by ulps (Shewchuk's test) */
    double a[2] = {0.5, 0.5}, b[2] = {12, 12}, c[2] = {24, 24};
    CHECK(fb_orient2d(a, b, c) == 0);
    double a2[2] = {nextafter(0.5, 1), 0.5};
    CHECK(fb_orient2d(a2, b, c) < 0); /* moved right of the line y = x going up: clockwise */
}

/* ---- triangulations ------------------------------------------------------------------------------------ */

static void check_build(const char *what, const double *xy, size_t n, size_t expect_dups)
{
    fb_dt d;
    fb_result rc = fb_dt_build(&d, xy, n, NULL, what);
    CHECKF(rc == FB_OK, "%s: build failed", what);
    if (rc) return;
    fb_dt_check_report r;
    uint64_t bad = fb_dt_check(&d, &r);
    CHECKF(bad == 0, "%s: %llu violations (orientation %llu, empty circle %llu, hull %llu, adjacency %llu)", what,
           (unsigned long long)bad, (unsigned long long)r.orientation, (unsigned long long)r.empty_circle,
           (unsigned long long)r.hull_convexity, (unsigned long long)r.adjacency);
    CHECKF(d.nv + d.duplicates == n && d.duplicates == expect_dups, "%s: %u vertices + %llu duplicates of %zu", what,
           d.nv, (unsigned long long)d.duplicates, n);
    CHECKF(r.triangles == 2 * d.nv - 2 - r.hull, "%s: %u triangles, 2n - 2 - h = %u", what, r.triangles,
           2 * d.nv - 2 - r.hull);
    fb_dt_free(&d);
}

static void test_inputs(void)
{
    const size_t n = 100000;
    double *xy = malloc(2 * n * sizeof *xy);
    for (size_t i = 0; i < n; i++) xy[2 * i] = th_unif(), xy[2 * i + 1] = th_unif();
    check_build("random", xy, n, 0);
    /* grid: every cell's four corners are cocircular */
    for (size_t i = 0; i < n; i++) xy[2 * i] = (double)(i % 316), xy[2 * i + 1] = (double)(i / 316);
    check_build("grid", xy, n, 0);
    /* clustered: 20 tight clusters, some points repeated exactly */
    for (size_t i = 0; i < n; i++) {
        int c = (int)(th_next() % 20);
        xy[2 * i] = c * 17.0 + 1e-6 * th_unif(), xy[2 * i + 1] = (c % 7) * 3.0 + 1e-6 * th_unif();
    }
    for (size_t i = 0; i < 100; i++) xy[2 * (n - 1 - i)] = xy[2 * i], xy[2 * (n - 1 - i) + 1] = xy[2 * i + 1];
    check_build("clustered", xy, n, 100);
    /* points on a circle (all cocircular, many repeated), and a line with one point off it */
    for (size_t i = 0; i < 1000; i++) {
        /* exactly representable cocircular points: Pythagorean triples scaled onto radius 5^k */
        static const int t[][2] = {{3, 4}, {4, 3}, {0, 5}, {5, 0}};
        int k = (int)(i % 4), q = (int)(i / 4) % 4;
        double sx = q & 1 ? -1 : 1, sy = q & 2 ? -1 : 1;
        xy[2 * i] = sx * t[k][0], xy[2 * i + 1] = sy * t[k][1];
    }
    check_build("circle (duplicates)", xy, 1000, 1000 - 12);
    for (size_t i = 0; i < 1000; i++) xy[2 * i] = (double)i, xy[2 * i + 1] = 2.0 * i;
    xy[2 * 999 + 1] = 0;
    check_build("line plus one", xy, 1000, 0);
    /* degenerate: collinear, fewer than three distinct */
    fb_dt d;
    for (size_t i = 0; i < 50; i++) xy[2 * i] = (double)i, xy[2 * i + 1] = 3.0 * i + 1;
    CHECK(fb_dt_build(&d, xy, 50, NULL, "collinear") == FB_ERR_INPUT);
    for (size_t i = 0; i < 50; i++) xy[2 * i] = (double)(i % 2), xy[2 * i + 1] = 0;
    CHECK(fb_dt_build(&d, xy, 50, NULL, "two points") == FB_ERR_INPUT);
    CHECK(fb_dt_build(&d, xy, 0, NULL, "none") == FB_ERR_INPUT);
    free(xy);
}

/* Every triangle's circumcircle is empty of every point (a global check, not the oracle's local
 * one), on a small set. */
static void test_global_empty_circle(void)
{
    const size_t n = 400;
    double xy[2 * 400];
    for (size_t i = 0; i < n; i++) xy[2 * i] = th_unif(), xy[2 * i + 1] = th_unif();
    fb_dt d;
    CHECK(fb_dt_build(&d, xy, n, NULL, "small") == FB_OK);
    uint64_t inside = 0, tris = 0;
    for (uint32_t t = 0; t < d.nt; t++) {
        if (fb_dt_is_ghost(&d, t)) continue;
        tris++;
        const uint32_t *v = d.tv + 3 * (size_t)t;
        for (uint32_t k = 0; k < d.nv; k++)
            inside += fb_incircle(d.xy + 2 * v[0], d.xy + 2 * v[1], d.xy + 2 * v[2], d.xy + 2 * k) > 0;
    }
    CHECK(tris > 700);
    CHECKF(inside == 0, "%llu points strictly inside circumcircles", (unsigned long long)inside);
    fb_dt_free(&d);
}

#ifdef FB_HAVE_QHULL
static int cmp3(const void *a, const void *b)
{
    const uint32_t *x = a, *y = b;
    for (int i = 0; i < 3; i++)
        if (x[i] != y[i]) return x[i] < y[i] ? -1 : 1;
    return 0;
}
static void sort3(uint32_t *t)
{
    for (int i = 0; i < 2; i++)
        for (int j = 0; j < 2 - i; j++)
            if (t[j] > t[j + 1]) {
                uint32_t s = t[j];
                t[j] = t[j + 1], t[j + 1] = s;
            }
}

static void test_qhull(void)
{
    const size_t n = 5000;
    double *xy = malloc(2 * n * sizeof *xy);
    uint32_t *perm = malloc(n * sizeof *perm);
    for (size_t i = 0; i < n; i++) xy[2 * i] = th_unif() * 100, xy[2 * i + 1] = th_unif() * 100;
    fb_dt d;
    CHECK(fb_dt_build(&d, xy, n, perm, "qhull") == FB_OK);
    uint32_t *ours = malloc(3 * (size_t)d.nfinite * sizeof *ours), no = 0;
    for (uint32_t t = 0; t < d.nt; t++) {
        if (fb_dt_is_ghost(&d, t)) continue;
        for (int k = 0; k < 3; k++) ours[3 * no + k] = perm[d.tv[3 * (size_t)t + k]];
        sort3(ours + 3 * no++);
    }
    qhT qh_qh, *qh = &qh_qh;
    QHULL_LIB_CHECK
    qh_zero(qh, stderr);
    int exit = qh_new_qhull(qh, 2, (int)n, xy, False, (char *)"qhull d Qbb Qt", NULL, stderr);
    CHECK(exit == 0);
    uint32_t *theirs = malloc(3 * 4 * n * sizeof *theirs), nq = 0;
    facetT *facet;
    vertexT *vertex, **vertexp;
    FORALLfacets
    {
        if (facet->upperdelaunay) continue;
        int k = 0;
        FOREACHvertex_(facet->vertices)
        {
            if (k < 3) theirs[3 * nq + k] = (uint32_t)qh_pointid(qh, vertex->point);
            k++;
        }
        if (k == 3) sort3(theirs + 3 * nq++);
    }
    qh_freeqhull(qh, !qh_ALL);
    int curlong, totlong;
    qh_memfreeshort(qh, &curlong, &totlong);
    qsort(ours, no, 3 * sizeof *ours, cmp3);
    qsort(theirs, nq, 3 * sizeof *theirs, cmp3);
    CHECKF(no == nq && !memcmp(ours, theirs, 3 * (size_t)no * sizeof *ours), "ours %u triangles, qhull %u", no, nq);
    free(ours), free(theirs), free(xy), free(perm);
    fb_dt_free(&d);
}
#endif

/* ---- refinement ----------------------------------------------------------------------------------- */

/* Least-squares slope of log variogram against log distance over random vertex pairs in [lo, hi]
 * (only vertices with x in [x0, x1) when x1 > x0). */
static double variogram_slope(const fb_terrain *t, double lo, double hi, double x0, double x1)
{
    double sum[64] = {0}, cnt[64] = {0};
    uint32_t nv = t->dt.nv;
    for (long k = 0; k < 2000000; k++) {
        uint32_t a = (uint32_t)(th_next() % nv), b = (uint32_t)(th_next() % nv);
        const double *p = t->dt.xy + 2 * (size_t)a, *q = t->dt.xy + 2 * (size_t)b;
        if (x1 > x0 && (p[0] < x0 || p[0] >= x1 || q[0] < x0 || q[0] >= x1)) continue;
        double dd = hypot(p[0] - q[0], p[1] - q[1]);
        if (dd < lo || dd >= hi) continue;
        int bin = (int)(log2(dd / lo) * 4);
        double dz = t->z[a] - t->z[b];
        sum[bin] += dz * dz, cnt[bin]++;
    }
    double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (int b = 0; b < 64; b++)
        if (cnt[b] > 20) {
            double x = log(lo) + (b + 0.5) / 4 * log(2.0), y = log(sum[b] / cnt[b]);
            n++, sx += x, sy += y, sxx += x * x, sxy += x * y;
        }
    return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

static const double square[] = {0, 0, 0, 1000, 0, 0, 0, 1000, 0, 1000, 1000, 0, 500, 500, 0};

static void refine_square(fb_terrain *t, double H, uint32_t seed, uint64_t insert, bool local)
{
    fb_terrain_stats st = {0};
    CHECK(fb_terrain_build(t, square, 5, "square", &st) == FB_OK);
    fb_terrain_opts o = {.insert = insert, .hurst = H, .sigma = 1, .seed = seed, .local_variance = local};
    CHECK(fb_terrain_refine(t, &o, "square", &st) == FB_OK);
}

static void test_refine_properties(void)
{
    /* survey points with relief */
    const size_t n = 1000;
    double *xyz = malloc(3 * n * sizeof *xyz);
    for (size_t i = 0; i < n; i++) {
        double x = th_unif() * 1000, y = th_unif() * 1000;
        xyz[3 * i] = x, xyz[3 * i + 1] = y, xyz[3 * i + 2] = 100 * sin(x / 90) * cos(y / 70) + 0.01 * i;
    }
    fb_terrain t1, t2;
    fb_terrain_stats s1 = {0}, s2 = {0};
    CHECK(fb_terrain_build(&t1, xyz, n, "survey", &s1) == FB_OK);
    CHECK(fb_terrain_build(&t2, xyz, n, "survey", &s2) == FB_OK);
    fb_terrain_opts o = {.insert = 100000, .hurst = 0.8, .sigma = -1, .seed = 9};
    CHECK(fb_terrain_refine(&t1, &o, "survey", &s1) == FB_OK);
    CHECK(fb_terrain_refine(&t2, &o, "survey", &s2) == FB_OK);
    CHECK(s1.inserted == 100000 && t1.dt.nv == n + 100000);
    CHECK(s1.sigma > 0);
    CHECK(fb_dt_check(&t1.dt, NULL) == 0);
    /* input points exactly interpolated: the same coordinates and heights, bit for bit */
    size_t same = 0;
    for (uint32_t v = 0; v < t1.ninput; v++)
        for (size_t i = 0; i < n; i++)
            if (xyz[3 * i] == t1.dt.xy[2 * v] && xyz[3 * i + 1] == t1.dt.xy[2 * v + 1]) {
                same += xyz[3 * i + 2] == t1.z[v];
                break;
            }
    CHECK(same == n && t1.ninput == n);
    /* determinism */
    CHECK(t1.dt.nv == t2.dt.nv && !memcmp(t1.z, t2.z, t1.dt.nv * sizeof *t1.z) &&
          !memcmp(t1.dt.xy, t2.dt.xy, 2 * t1.dt.nv * sizeof *t1.dt.xy) && t1.dt.nt == t2.dt.nt &&
          !memcmp(t1.dt.tv, t2.dt.tv, 3 * (size_t)t1.dt.nt * sizeof *t1.dt.tv));
    CHECK(s1.clamped == s2.clamped && s1.clamped < s1.inserted);
    fb_terrain_free(&t2);
    o.seed = 10;
    CHECK(fb_terrain_build(&t2, xyz, n, "survey", &s2) == FB_OK);
    CHECK(fb_terrain_refine(&t2, &o, "survey", &s2) == FB_OK);
    CHECK(memcmp(t1.z + n, t2.z + n, 1000 * sizeof *t1.z) != 0); /* another seed, another terrain */
    fb_terrain_free(&t1);
    fb_terrain_free(&t2);
    /* sweep order and local variance also keep the Delaunay property and the counts */
    CHECK(fb_terrain_build(&t1, xyz, n, "survey", &s1) == FB_OK);
    o.sweep = true, o.local_variance = true, o.insert = 20000;
    CHECK(fb_terrain_refine(&t1, &o, "survey", &s1) == FB_OK);
    CHECK(t1.dt.nv == n + 20000 && fb_dt_check(&t1.dt, NULL) == 0);
    fb_terrain_free(&t1);
    free(xyz);

    /* Gaussian draws: mean 0 and variance 1 within 5 standard errors */
    double m = 0, v = 0;
    const int N = 200000;
    for (int i = 0; i < N; i++) {
        double g = fb_terrain_gauss(3, (uint64_t)i);
        m += g, v += g * g;
    }
    m /= N, v = v / N - m * m;
    CHECKF(fabs(m) < 5 / sqrt(N) && fabs(v - 1) < 5 * sqrt(2.0 / N), "mean %g variance %g", m, v);
}

/* The variogram of a refined flat square follows dist^(2H): the slope rises with H, and stays
 * within the method's bias of 2H (midpoint displacement is known to flatten the variogram of
 * persistent surfaces; measured here: about 2H - 0.1 at H = 0.5 and 2H - 0.4 at H = 0.85, see
 * docs/terrain.md). Tolerances: 4 standard deviations of the mean over 6 seeds, plus that bias. */
static void test_variogram(void)
{
    double mean[2], sd[2];
    const double Hs[2] = {0.5, 0.85}, bias[2] = {0.15, 0.45};
    for (int h = 0; h < 2; h++) {
        double s = 0, s2 = 0;
        const int seeds = 6;
        for (int k = 1; k <= seeds; k++) {
            fb_terrain t;
            refine_square(&t, Hs[h], (uint32_t)k, 50000, false);
            CHECK(fb_dt_check(&t.dt, NULL) == 0);
            double sl = variogram_slope(&t, 5, 100, 0, 0);
            s += sl, s2 += sl * sl;
            fb_terrain_free(&t);
        }
        mean[h] = s / seeds;
        sd[h] = sqrt(fmax(s2 / seeds - mean[h] * mean[h], 0) / (seeds - 1));
        CHECKF(mean[h] > 2 * Hs[h] - bias[h] - 4 * sd[h] && mean[h] < 2 * Hs[h] + 4 * sd[h] + 0.05,
               "H %g: slope %g +- %g, 2H = %g", Hs[h], mean[h], sd[h], 2 * Hs[h]);
    }
    CHECKF(mean[1] > mean[0] + 4 * (sd[0] + sd[1]), "slope at H 0.85 (%g) not above H 0.5 (%g)", mean[1], mean[0]);

    /* regions: D = 2.1 on the left half, D = 2.6 on the right: the left is smoother */
    fb_terrain_center c[2] = {{250, 500, 0.9, 1}, {750, 500, 0.4, 22.4}}; /* equal variance at 500 */
    double left = 0, right = 0;
    for (int k = 1; k <= 3; k++) {
        fb_terrain t;
        fb_terrain_stats st = {0};
        CHECK(fb_terrain_build(&t, square, 5, "square", &st) == FB_OK);
        fb_terrain_opts o = {.insert = 50000,
                             .hurst = 0.5,
                             .sigma = 1,
                             .seed = (uint32_t)k,
                             .centers = c,
                             .ncenters = 2,
                             .local_variance = false};
        CHECK(fb_terrain_refine(&t, &o, "square", &st) == FB_OK);
        left += variogram_slope(&t, 3, 60, 0, 450) / 3;
        right += variogram_slope(&t, 3, 60, 550, 1000) / 3;
        fb_terrain_free(&t);
    }
    CHECKF(left > right + 0.3, "region slopes: left (D 2.1) %g, right (D 2.6) %g", left, right);
}

static void test_io(void)
{
    const char *path = "test_terrain_points.csv";
    FILE *f = fopen(path, "w");
    fprintf(f, "# survey\nx,y,z\n0,0,1\n1 0 2\n\n0, 1, 3 # comment\n1,1,4\n");
    fclose(f);
    double *xyz = NULL;
    size_t n = 0;
    CHECK(fb_terrain_read_points(path, &xyz, &n) == FB_OK && n == 4 && xyz[5] == 2 && xyz[6] == 0 && xyz[7] == 1 &&
          xyz[11] == 4);
    free(xyz);
    f = fopen(path, "w");
    fprintf(f, "0 0 1\n1 0 nan\n");
    fclose(f);
    CHECK(fb_terrain_read_points(path, &xyz, &n) == FB_ERR_INPUT);
    f = fopen(path, "w");
    fprintf(f, "0 0 1\n1 0\n");
    fclose(f);
    CHECK(fb_terrain_read_points(path, &xyz, &n) == FB_ERR_INPUT);
    f = fopen(path, "w");
    fprintf(f, "# nothing\n");
    fclose(f);
    CHECK(fb_terrain_read_points(path, &xyz, &n) == FB_ERR_INPUT);
    CHECK(fb_terrain_read_points("/nonexistent/points.xyz", &xyz, &n) == FB_ERR_INPUT);
    f = fopen(path, "w");
    fprintf(f, "x,y,D,sigma\n0,0,2.2,\n5,5,2.7,0.5\n");
    fclose(f);
    fb_terrain_center *c = NULL;
    int nc = 0;
    CHECK(fb_terrain_read_centers(path, &c, &nc) == FB_OK && nc == 2 && c[0].sigma < 0 &&
          fabs(c[0].hurst - 0.8) < 1e-12 && c[1].sigma == 0.5);
    free(c);
    f = fopen(path, "w");
    fprintf(f, "0,0,3.2,1\n");
    fclose(f);
    CHECK(fb_terrain_read_centers(path, &c, &nc) == FB_ERR_INPUT);
    remove(path);
}

int main(void)
{
    test_predicates();
    test_inputs();
    test_global_empty_circle();
#ifdef FB_HAVE_QHULL
    test_qhull();
#else
    printf("qhull comparison not built (libqhull-dev missing)\n");
#endif
    test_refine_properties();
    test_variogram();
    test_io();
    TEST_REPORT();
}
