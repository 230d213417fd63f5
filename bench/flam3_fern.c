/*
 * The peer for `fractalbake bench --generator ifs`: libflam3 (Debian libflam3-dev) rendering
 * Barnsley's fern as a flame of four linear xforms (the same maps and weights as fractalbake's
 * `fern` preset, one colour per map), 4096 x 4096, oversample 1, no density estimation, on every
 * core. flam3 iterates in double and plots into a histogram of double RGBA + count buckets.
 *
 * flam3_render also filters, tone-maps and writes 8-bit pixels, which the chaos-game rate must
 * not include, so each size of game is rendered 3 times at two qualities and the rate reported is
 * the marginal one: (iterations at Q2 - iterations at Q1) / (median time at Q2 - at Q1). The
 * whole-render rate at Q2 is reported beside it. Prints JSON lines like fractalbake's.
 * Built and run by bench/run.sh when libflam3-dev is installed; never part of fractalbake itself.
 *
 * Usage: flam3_fern [--json] [--size WxH] [--points N] [--ppm OUT.ppm]
 *   N: chaos-game points at Q2 (default 2^28); OUT.ppm: the last image, to check the framing
 */
#include <flam3.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* One flame: the fern framed like fractalbake's auto bounds (x -2.2..2.7, y 0..10), quality q. */
static char *fern_xml(int w, int h, double q)
{
    /* fractalbake's maps (a b c d e f p): x' = a x + b y + e, y' = c x + d y + f; flam3's coefs are
     * "c00 c01 c10 c11 c20 c21" with x' = c00 x + c10 y + c20, y' = c01 x + c11 y + c21. flam3's image y
     * points down, so the maps are conjugated by y -> -y (b, c, f negated) for an upright fern. */
    static const double maps[4][7] = {{0, 0, 0, 0.16, 0, 0, 0.01},
                                      {0.85, 0.04, -0.04, 0.85, 0, 1.6, 0.85},
                                      {0.2, -0.26, 0.23, 0.22, 0, 1.6, 0.07},
                                      {-0.15, 0.28, 0.26, 0.24, 0, 0.44, 0.07}};
    size_t cap = 64 * 1024, n = 0;
    char *s = malloc(cap);
    if (!s) return NULL;
    double scale = (w / 4.9 < h / 10.0 ? w / 4.9 : h / 10.0);
    n += (size_t)snprintf(s + n, cap - n,
                          "<flame size=\"%d %d\" center=\"0.25 -5\" scale=\"%.6f\" quality=\"%.6f\" oversample=\"1\" "
                          "filter=\"0.5\" estimator_radius=\"0\" estimator_minimum=\"0\" estimator_curve=\"0.4\" "
                          "brightness=\"4\" gamma=\"4\" vibrancy=\"1\" background=\"0 0 0\" passes=\"1\" "
                          "temporal_samples=\"1\">\n",
                          w, h, scale, q);
    for (int i = 0; i < 4; i++) {
        const double *m = maps[i];
        n += (size_t)snprintf(s + n, cap - n,
                              "<xform weight=\"%g\" color=\"%g\" linear=\"1\" coefs=\"%g %g %g %g %g %g\"/>\n", m[6],
                              i / 3.0, m[0], -m[2], -m[1], m[3], m[4], -m[5]);
    }
    for (int i = 0; i < 256; i++) /* a green-to-gold ramp */
        n += (size_t)snprintf(s + n, cap - n, "<color index=\"%d\" rgb=\"%d %d %d\"/>\n", i, 40 + i * 200 / 255,
                              200 - i * 40 / 255, 40);
    snprintf(s + n, cap - n, "</flame>\n");
    return s;
}

/* Renders at quality q three times; returns the median seconds and the iterations of a render. */
static int render(int w, int h, double q, int threads, const char *ppm, double *sec, double *iters)
{
    char *xml = fern_xml(w, h, q);
    int ncps = 0;
    flam3_genome *cp = xml ? flam3_parse_xml2(xml, "fern", flam3_defaults_on, &ncps) : NULL;
    free(xml);
    if (!cp || ncps != 1) return fprintf(stderr, "flam3_fern: the flame did not parse\n"), 1;
    unsigned char *img = malloc((size_t)w * h * 3);
    if (!img) return fprintf(stderr, "flam3_fern: out of memory\n"), 1;
    double t[3];
    for (int r = 0; r < 3; r++) {
        flam3_frame f;
        stat_struct st;
        memset(&f, 0, sizeof f);
        flam3_init_frame(&f);
        f.genomes = cp;
        f.ngenomes = 1;
        f.pixel_aspect_ratio = 1.0;
        f.bits = 64;
        f.bytes_per_channel = 1;
        f.nthreads = threads;
        f.sub_batch_size = 10000;
        double t0 = now();
        if (flam3_render(&f, img, flam3_field_both, 3, 0, &st))
            return fprintf(stderr, "flam3_fern: render failed\n"), 1;
        t[r] = now() - t0;
        *iters = (double)st.num_iters;
    }
    qsort(t, 3, sizeof t[0], cmp_double);
    *sec = t[1];
    FILE *out = ppm ? fopen(ppm, "wb") : NULL;
    if (ppm && (!out || fprintf(out, "P6\n%d %d\n255\n", w, h) < 0 ||
                fwrite(img, 3, (size_t)w * h, out) != (size_t)w * h || fclose(out)))
        return fprintf(stderr, "flam3_fern: cannot write %s\n", ppm), 1;
    free(img);
    for (int i = 0; i < ncps; i++) free(cp[i].xform); /* flam3 3.1 has no genome destructor */
    free(cp);
    return 0;
}

int main(int argc, char **argv)
{
    int json = 0, w = 4096, h = 4096;
    const char *ppm = NULL;
    double points = 268435456.0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--json"))
            json = 1;
        else if (!strcmp(argv[i], "--size") && i + 1 < argc && sscanf(argv[i + 1], "%dx%d", &w, &h) == 2 && w > 0 &&
                 h > 0 && w <= 16384 && h <= 16384)
            i++;
        else if (!strcmp(argv[i], "--points") && i + 1 < argc && (points = atof(argv[i + 1])) >= 1e6 && points <= 1e11)
            i++;
        else if (!strcmp(argv[i], "--ppm") && i + 1 < argc)
            ppm = argv[++i];
        else {
            fprintf(stderr, "usage: flam3_fern [--json] [--size WxH] [--points N] [--ppm OUT.ppm]\n");
            return 2;
        }
    }
    int threads = flam3_count_nthreads();
    double q2 = points / ((double)w * h), q1 = q2 / 4, s1, s2, i1, i2;
    if (render(w, h, q1, threads, NULL, &s1, &i1) || render(w, h, q2, threads, ppm, &s2, &i2)) return 1;
    double marginal = (i2 - i1) / (s2 - s1) * 1e-6, whole = i2 / s2 * 1e-6;
    if (json) {
        printf("{\"generator\": \"ifs\", \"backend\": \"native\", \"device\": \"libflam3 %s\", \"mode\": "
               "\"chaos-game-marginal\", \"unit\": \"Mpts/s\", \"rate\": %.3f, \"size\": [%d, %d], \"points\": %.0f, "
               "\"threads\": %d}\n",
               flam3_version(), marginal, w, h, i2, threads);
        printf("{\"generator\": \"ifs\", \"backend\": \"native\", \"device\": \"libflam3 %s\", \"mode\": "
               "\"render-whole\", \"unit\": \"Mpts/s\", \"rate\": %.3f, \"size\": [%d, %d], \"points\": %.0f, "
               "\"threads\": %d, \"seconds\": %.3f}\n",
               flam3_version(), whole, w, h, i2, threads, s2);
    } else {
        printf("libflam3 %s, Barnsley's fern as 4 linear xforms, %d x %d, %d threads; median of 3\n", flam3_version(),
               w, h, threads);
        printf("  %.0f iterations: %.3f s; %.0f iterations: %.3f s\n", i1, s1, i2, s2);
        printf("  chaos game (marginal)  %8.1f Mpts/s\n  whole render           %8.1f Mpts/s\n", marginal, whole);
    }
    return 0;
}
