/*
 * The fBm benchmark: 8 octaves of gradient noise on every backend, against the hand-vectorised AVX2
 * loop (the same kernel, bit-exact) on every core.
 */
#include "benchkit.h"
#include "fbm_avx2.h"
#include "gen_fbm.h"

#include <stdio.h>
#include <stdlib.h>

typedef struct ref_job {
    const fb_gen *g;
    float *out;
} ref_job;

static void ref_rows(void *ctx, int y0, int n, int task)
{
    ref_job *j = ctx;
    fb_fbm_avx2_rows(j->g->params, y0, n, j->out + (size_t)y0 * j->g->scene->width);
}

/* Median seconds of the AVX2 loop over the whole image; -1 without AVX2. */
static double time_reference(const fb_scene *s, int threads)
{
    fb_gen g;
    if (fb_gen_init(&g, s, &s->layers[0])) return -1;
    double t = -1;
    ref_job j = {&g, fb_fbm_avx2_supported(g.params) ? malloc((size_t)s->width * s->height * 4) : NULL};
    if (j.out) t = fb_bench_rows(threads, s->height, ref_rows, &j, NULL);
    free(j.out);
    fb_gen_fini(&g);
    return t;
}

fb_result fb_fbm_bench(fb_bench *b)
{
    const int octaves = 8;
    char json[512];
    snprintf(json, sizeof json,
             "{\"size\": [%d, %d], \"seed\": 1, \"layers\": [{\"type\": \"fbm\", \"noise\": \"gradient\", "
             "\"octaves\": %d}]}",
             b->width, b->height, octaves);
    fb_bench_heading(b, "fBm %d x %d, %d octaves of gradient noise; median of 3 runs after a warm-up", b->width,
                     b->height, octaves);
    fb_bench_case bc = {"fbm", "Mpix/s", (double)b->width * b->height, 1e6, "moctaves_per_s", octaves};
    fb_scene s;
    fb_result rc = fb_scene_parse(json, NULL, &s);
    if (!rc) rc = fb_bench_layer(b, &bc, &s, time_reference(&s, b->threads > 0 ? b->threads : fb_cpu_count()));
    fb_scene_fini(&s);
    return rc;
}
