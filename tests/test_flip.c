/*
 * FLIP against NVIDIA's published tool (version 1.6): tests/data/flip/expected.csv holds its mean,
 * weighted median and quartiles, min and max (and for HDR the exposures it chose) for eight pairs,
 * and maps/ four of its error maps as grey PNGs (round(255 * error)). Every number must agree
 * within 1e-4 and the maps within 1/255 at all but a thousandth of the pixels. Then the zero-median
 * rule (flip.h) on a reference three quarters black, against an independent solution of the ACES
 * exposure, and the weighted percentiles on a hand-made map.
 */
#include "exrio.h"
#include "flip.h"
#include "pngio.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int failures;
#define CHECK(cond, ...)                                                                                               \
    do {                                                                                                               \
        if (!(cond)) {                                                                                                 \
            failures++;                                                                                                \
            fprintf(stderr, "FAIL %s:%d: ", __FILE__, __LINE__);                                                       \
            fprintf(stderr, __VA_ARGS__);                                                                              \
            fputc('\n', stderr);                                                                                       \
        }                                                                                                              \
    } while (0)

typedef struct rgb {
    int w, h;
    float *p[3];
} rgb;

static bool load(const char *dir, const char *name, rgb *o)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    memset(o, 0, sizeof *o);
    if (strstr(name, ".png")) {
        fb_png png;
        if (fb_png_read(path, &png)) return false;
        o->w = png.width, o->h = png.height;
        for (int q = 0; q < 3; q++) {
            o->p[q] = malloc((size_t)o->w * o->h * sizeof(float));
            memcpy(o->p[q], png.plane[png.channels >= 3 ? q : 0], (size_t)o->w * o->h * sizeof(float));
        }
        fb_png_fini(&png);
        return true;
    }
    exrio_reader *r;
    if (exrio_open(path, &r)) return false;
    o->w = exrio_width(r), o->h = exrio_height(r);
    void *planes[64] = {0};
    const char *names[3] = {"R", "G", "B"};
    for (int q = 0; q < 3; q++) {
        int c = exrio_find_channel(r, names[q]);
        if (c < 0) return false;
        planes[c] = o->p[q] = malloc((size_t)o->w * o->h * sizeof(float));
    }
    bool ok = !exrio_read_rows(r, 0, o->h, planes);
    exrio_close(&r);
    return ok;
}

static void unload(rgb *o)
{
    for (int q = 0; q < 3; q++) free(o->p[q]);
}

static void check_map(const char *dir, const char *mapname, const float *map, int w, int h)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/maps/%s", dir, mapname);
    fb_png png;
    if (fb_png_read(path, &png)) {
        CHECK(0, "cannot read %s", path);
        return;
    }
    CHECK(png.width == w && png.height == h, "%s: %d x %d", mapname, png.width, png.height);
    size_t off = 0, n = (size_t)w * h;
    double worst = 0;
    for (size_t i = 0; i < n && png.width == w; i++) {
        double mine = floor(255.0 * map[i] + 0.5), theirs = floor(png.plane[0][i] * 255.0 + 0.5);
        double d = fabs(mine - theirs);
        if (d > 1) off++;
        if (d > worst) worst = d;
    }
    CHECK(off * 1000 <= n, "%s: %zu of %zu pixels more than 1/255 apart (worst %g/255)", mapname, off, n, worst);
    printf("  map %s: %zu pixels beyond 1/255, worst %g/255\n", mapname, off, worst);
    fb_png_fini(&png);
}

static void check_cases(const char *dir)
{
    char path[1024], line[512];
    snprintf(path, sizeof path, "%s/expected.csv", dir);
    FILE *f = fopen(path, "r");
    CHECK(f, "cannot open %s", path);
    if (!f) return;
    int rows = 0;
    if (!fgets(line, sizeof line, f)) return; /* the header */
    while (fgets(line, sizeof line, f)) {
        char ref[64], test[64], mode[8];
        double e[6];
        float se = 0, ste = 0;
        int ne = 0;
        int k = sscanf(line, "%63[^,],%63[^,],%7[^,],%lf,%lf,%lf,%lf,%lf,%lf,%f,%f,%d", ref, test, mode, &e[0], &e[1],
                       &e[2], &e[3], &e[4], &e[5], &se, &ste, &ne);
        if (k < 9) continue;
        bool hdr = !strcmp(mode, "HDR");
        rgb a, b;
        CHECK(load(dir, ref, &a) && load(dir, test, &b), "cannot load %s or %s", ref, test);
        float *map = malloc((size_t)a.w * a.h * sizeof(float));
        fb_flip_result r;
        CHECK(!fb_flip((const float *const *)a.p, (const float *const *)b.p, a.w, a.h, hdr, fb_flip_default_ppd(), map,
                       &r),
              "fb_flip failed");
        double got[6] = {r.mean, r.median, r.q1, r.q3, r.min, r.max};
        const char *what[6] = {"mean", "weighted median", "1st weighted quartile", "3rd weighted quartile", "min",
                               "max"};
        for (int q = 0; q < 6; q++)
            CHECK(fabs(got[q] - e[q]) <= 1e-4, "%s vs %s (%s): %s %.6f, the tool's %.6f", ref, test, mode, what[q],
                  got[q], e[q]);
        if (hdr) {
            CHECK(fabsf(r.start_exposure - se) <= 1e-4f && fabsf(r.stop_exposure - ste) <= 1e-4f && r.nexp == ne,
                  "%s: exposures %.4f..%.4f in %d, the tool's %.4f..%.4f in %d", ref, r.start_exposure, r.stop_exposure,
                  r.nexp, se, ste, ne);
            CHECK(!r.zero_median, "%s: zero median flagged", ref);
        }
        printf("%s %s %s: mean %.6f median %.6f q1 %.6f q3 %.6f min %.6f max %.6f\n", ref, test, mode, r.mean, r.median,
               r.q1, r.q3, r.min, r.max);
        if (ref[0] == 'b') { /* the fBm pairs are grey: once more on the grey path (one plane three times) */
            const float *ga[3] = {a.p[0], a.p[0], a.p[0]}, *gb[3] = {b.p[0], b.p[0], b.p[0]};
            fb_flip_result g;
            CHECK(!fb_flip(ga, gb, a.w, a.h, hdr, fb_flip_default_ppd(), NULL, &g), "fb_flip (grey) failed");
            double gg[6] = {g.mean, g.median, g.q1, g.q3, g.min, g.max};
            for (int q = 0; q < 6; q++)
                CHECK(fabs(gg[q] - e[q]) <= 1e-4, "%s vs %s (%s, grey): %s %.6f, the tool's %.6f", ref, test, mode,
                      what[q], gg[q], e[q]);
            printf("  grey path: mean %.6f median %.6f q1 %.6f q3 %.6f\n", g.mean, g.median, g.q1, g.q3);
        }
        char mapname[128];
        snprintf(mapname, sizeof mapname, "flip.%.*s.%.*s.%s.png", (int)(strchr(ref, '_') - ref), ref,
                 (int)(strchr(test, '_') - test), test, hdr ? "exr" : "png");
        snprintf(path, sizeof path, "%s/maps/%s", dir, mapname);
        FILE *m = fopen(path, "rb");
        if (m) {
            fclose(m);
            check_map(dir, mapname, map, a.w, a.h);
        }
        free(map);
        unload(&a);
        unload(&b);
        rows++;
    }
    fclose(f);
    CHECK(rows == 8, "expected.csv: %d rows read, 8 expected", rows);
}

/* Three quarters of the reference black, the rest white (luminance 1): the published tool's median
 * is 0 and its stop exposure infinite; ours takes the median of the positive luminances, 1, so
 * start = stop = log2(x) where ACES(x) = 0.85 and two exposures. x solved here in double. */
static void check_zero_median(void)
{
    int w = 64, h = 64;
    size_t n = (size_t)w * h;
    float *a = calloc(n, sizeof *a), *b = calloc(n, sizeof *b), *map = malloc(n * sizeof *map);
    for (size_t i = 0; i < n; i++) {
        bool lit = (i % w) >= 48;
        a[i] = lit ? 1.0f : 0.0f;
        b[i] = lit ? 0.8f : 0.0f; /* the test darker where lit */
    }
    const float *ra[3] = {a, a, a}, *rb[3] = {b, b, b};
    fb_flip_result r;
    CHECK(!fb_flip(ra, rb, w, h, true, fb_flip_default_ppd(), map, &r), "fb_flip failed");
    double c0 = 0.36 * 2.51, c1 = 0.6 * 0.03, c3 = 0.36 * 2.43, c4 = 0.6 * 0.59, c5 = 0.14, t = 0.85;
    double qa = c0 - t * c3, qb = c1 - t * c4, qc = -t * c5;
    double x = (-qb + sqrt(qb * qb - 4 * qa * qc)) / (2 * qa);
    CHECK(r.zero_median, "the zero median is not flagged");
    CHECK(fabs(r.start_exposure - log2(x)) < 1e-5 && fabs(r.stop_exposure - log2(x)) < 1e-5 && r.nexp == 2,
          "zero median: exposures %.6f..%.6f in %d, expected %.6f twice", r.start_exposure, r.stop_exposure, r.nexp,
          log2(x));
    CHECK(isfinite(r.mean) && r.mean > 0.01 && r.max <= 1, "zero median: mean %g max %g", r.mean, r.max);
    /* a black reference: start = stop = 0 */
    memset(a, 0, n * sizeof *a);
    CHECK(!fb_flip(ra, rb, w, h, true, fb_flip_default_ppd(), map, &r), "fb_flip failed");
    CHECK(r.zero_median && r.start_exposure == 0 && r.stop_exposure == 0 && r.nexp == 2 && isfinite(r.mean),
          "black reference: %g..%g in %d, mean %g", r.start_exposure, r.stop_exposure, r.nexp, r.mean);
    free(a);
    free(b);
    free(map);
}

/* Weighted percentiles of {0.1 x 6, 0.4, 0.5} (sum 1.5): the running sums 0.1 .. 0.6, 1.0, 1.5 pass
 * 0.375 at the 4th value (0.1), 0.75 at the 7th (0.4), 1.125 at the 8th (0.5). */
static void check_pool(void)
{
    float m[8] = {0.5f, 0.1f, 0.1f, 0.4f, 0.1f, 0.1f, 0.1f, 0.1f};
    fb_flip_result r;
    CHECK(!fb_flip_pool(m, 8, &r), "pool failed");
    CHECK(fabs(r.q1 - 0.1) < 1e-7 && fabs(r.median - 0.4) < 1e-7 && fabs(r.q3 - 0.5) < 1e-7,
          "weighted quartiles %g %g %g, expected 0.1 0.4 0.5", r.q1, r.median, r.q3);
    CHECK(fabs(r.mean - 1.5 / 8) < 1e-7 && fabs(r.min - 0.1) < 1e-7 && fabs(r.max - 0.5) < 1e-7, "mean %g", r.mean);
}

/* The same bits on 1, 2 and 3 threads (bands of 128 rows; 300 rows leave a partial band). */
static void check_threads(const char *dir)
{
    rgb a, b;
    CHECK(load(dir, "b8_rgb.exr", &a) && load(dir, "b6_rgb.exr", &b), "cannot load b8/b6");
    int h = a.h < 300 ? a.h : 300;
    size_t n = (size_t)a.w * h;
    float *m[3];
    for (int t = 0; t < 3; t++) {
        fb_flip_result r;
        m[t] = malloc(n * sizeof(float));
        fb_flip_set_threads(t + 1);
        CHECK(!fb_flip((const float *const *)a.p, (const float *const *)b.p, a.w, h, true, fb_flip_default_ppd(), m[t],
                       &r),
              "fb_flip failed");
    }
    fb_flip_set_threads(0);
    CHECK(!memcmp(m[0], m[1], n * sizeof(float)) && !memcmp(m[0], m[2], n * sizeof(float)),
          "FLIP differs between 1, 2 and 3 threads");
    for (int t = 0; t < 3; t++) { /* and the grey path, LDR (the first 300 rows of b8's R as sRGB) */
        const float *ga[3] = {a.p[0], a.p[0], a.p[0]}, *gb[3] = {b.p[0], b.p[0], b.p[0]};
        fb_flip_result r;
        fb_flip_set_threads(t + 1);
        CHECK(!fb_flip(ga, gb, a.w, h, false, fb_flip_default_ppd(), m[t], &r), "fb_flip failed");
    }
    fb_flip_set_threads(0);
    CHECK(!memcmp(m[0], m[1], n * sizeof(float)) && !memcmp(m[0], m[2], n * sizeof(float)),
          "grey FLIP differs between 1, 2 and 3 threads");
    for (int t = 0; t < 3; t++) free(m[t]);
    unload(&a);
    unload(&b);
}

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : "tests/data/flip";
    check_pool();
    check_zero_median();
    check_cases(dir);
    check_threads(dir);
    if (failures) fprintf(stderr, "%d failures\n", failures);
    return failures ? 1 : 0;
}
