/*
 * The terrain benchmarks (CPU, one thread): Delaunay triangulation of 10^6 uniform random points
 * (the same points as bench/cgal_delaunay.cpp), and 10^3 survey points refined by 10^6 insertions.
 */
#include "benchkit.h"
#include "delaunay.h"
#include "gen_terrain.h"
#include "terrain.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void report(const fb_bench *b, const char *generator, const char *mode, double inserts, double seconds)
{
    fb_bench_row r = {.generator = generator,
                      .backend = "native",
                      .device = "native C",
                      .mode = mode,
                      .unit = "Minserts/s",
                      .rate = inserts / seconds * 1e-6,
                      .threads = 1,
                      .nextra = 2,
                      .extra = {{"inserts", inserts, 0}, {"seconds", seconds, 3}}};
    snprintf(r.note, sizeof r.note, "(%.0f inserts in %.3f s)", inserts, seconds);
    b->row(b, &r);
}

fb_result fb_terrain_bench(fb_bench *b)
{
    if (!b->native) return FB_OK;
    const size_t n = 1000000;
    double *xy = malloc(n * 2 * sizeof *xy), *xyz = malloc(1000 * 3 * sizeof *xyz);
    double w[3];
    fb_result rc = xy && xyz ? FB_OK : fb_fail(FB_ERR_NOMEM, "out of memory");
    uint64_t seed = 1;
    for (size_t i = 0; i < 2 * n && !rc; i++) xy[i] = fb_bench_unit(&seed);
    fb_bench_heading(b,
                     "Delaunay: 10^6 uniform random points; terrain: 10^3 survey points refined by 10^6; median of 3");
    for (int i = -1; i < 3 && !rc; i++) { /* a warm-up, then three */
        fb_dt d;
        memset(&d, 0, sizeof d);
        double t0 = fb_now();
        rc = fb_dt_build(&d, xy, n, NULL, "bench");
        if (i >= 0) w[i] = fb_now() - t0;
        fb_dt_free(&d);
    }
    if (!rc) report(b, "delaunay", "build-1e6-uniform", (double)n, fb_bench_median3(w));
    /* survey points: a smooth hill with noise over a 1000 x 1000 area */
    for (size_t i = 0; i < 1000 && !rc; i++) {
        double x = 1000 * fb_bench_unit(&seed), y = 1000 * fb_bench_unit(&seed);
        xyz[3 * i] = x, xyz[3 * i + 1] = y;
        xyz[3 * i + 2] =
            300 * exp(-((x - 500) * (x - 500) + (y - 450) * (y - 450)) / 1.2e5) + 20 * fb_bench_unit(&seed);
    }
    for (int i = -1; i < 3 && !rc; i++) {
        fb_terrain t;
        fb_terrain_stats st;
        memset(&t, 0, sizeof t);
        rc = fb_terrain_build(&t, xyz, 1000, "bench", &st);
        if (!rc)
            rc = fb_terrain_refine(&t, &(fb_terrain_opts){.insert = 1000000, .hurst = 0.85, .sigma = -1, .seed = 1},
                                   "bench", &st);
        if (!rc && i >= 0) w[i] = st.refine_seconds;
        fb_terrain_free(&t);
    }
    if (!rc) report(b, "refine", "refine-1e3-by-1e6", 1e6, fb_bench_median3(w));
    free(xy);
    free(xyz);
    return rc;
}
