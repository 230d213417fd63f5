/*
 * The Julia benchmark: c = -0.8+0.156i, 256 iterations, on every backend, in iterations executed per
 * second, against the hand-vectorised AVX2 escape loop (which also counts the iterations one image
 * executes); and the layer storing only `iter`, like for like with that loop.
 */
#include "benchkit.h"
#include "gen_julia.h"
#include "julia_avx2.h"
/* after the headers of core: the SPIR-V arrays are uint32_t[] */
#include "julia_iter_peer_comp.h"
#include "julia_peer_comp.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct ref_job {
    const fb_gen *g;
    uint32_t *out;
    uint64_t totals[4096]; /* iterations per task */
} ref_job;

static void ref_rows(void *ctx, int y0, int n, int task)
{
    ref_job *j = ctx;
    uint64_t total = 0;
    fb_julia_avx2_rows(j->g->params, y0, n, j->out + (size_t)y0 * j->g->scene->width, &total);
    j->totals[task] = total;
}

/* Median seconds of the AVX2 loop over the whole image and the iterations it executes; -1 without AVX2. */
static double time_reference(const fb_scene *s, int threads, uint64_t *iters)
{
    fb_gen g;
    ref_job *j = calloc(1, sizeof *j);
    double t = -1;
    if (!j || fb_gen_init(&g, s, &s->layers[0])) {
        free(j);
        return -1;
    }
    j->g = &g;
    j->out = fb_julia_avx2_supported(g.params) ? malloc((size_t)s->width * s->height * 4) : NULL;
    int tasks = 0;
    if (j->out) t = fb_bench_rows(threads, s->height, ref_rows, j, &tasks);
    *iters = 0;
    for (int k = 0; k < tasks; k++) *iters += j->totals[k];
    free(j->out);
    free(j);
    fb_gen_fini(&g);
    return t;
}

fb_result fb_julia_bench(fb_bench *b)
{
    char json[512];
    snprintf(json, sizeof json,
             "{\"size\": [%d, %d], \"seed\": 1, \"layers\": [{\"type\": \"julia\", \"c\": [-0.8, 0.156], "
             "\"max-iter\": 256}]}",
             b->width, b->height);
    fb_bench_case bc = {"julia", "Giter/s", 0, 1e9, "mpix_per_s", 0};
    fb_scene s;
    fb_result rc = fb_scene_parse(json, NULL, &s);
    if (!rc) {
        fb_bench_heading(b, "Julia %d x %d, c = -0.8+0.156i, max-iter 256 (rate: iterations executed); median of 3",
                         b->width, b->height);
        /* the reference runs first: it counts the iterations one image executes */
        uint64_t iters = 0;
        double tref = time_reference(&s, b->threads > 0 ? b->threads : fb_cpu_count(), &iters);
        if (tref < 0 || iters == 0) rc = fb_fail(FB_ERR_INTERNAL, "bench: the julia benchmark needs AVX2");
        bc.work = (double)iters;
        bc.extra_per_work = 1e3 * (double)b->width * b->height / (double)iters; /* Giter/s -> Mpix/s */
        if (!rc) rc = fb_bench_layer(b, &bc, &s, tref);
        fb_bench_peer full = {
            .name = "minimal GLSL (bench/peers/julia_peer.comp)", FB_SPV(julia_peer_comp), .planes = 7, .input = true};
        if (!rc) rc = fb_bench_peer_layer(b, &bc, &s, &full);
    }
    fb_scene_fini(&s);
    /* the same layer storing `iter` only: the escape loop alone, as the AVX2 reference runs it */
    snprintf(json, sizeof json,
             "{\"size\": [%d, %d], \"seed\": 1, \"layers\": [{\"type\": \"julia\", \"c\": [-0.8, 0.156], "
             "\"max-iter\": 256, \"channels\": [\"iter\"]}]}",
             b->width, b->height);
    if (!rc) rc = fb_scene_parse(json, NULL, &s);
    if (!rc) rc = fb_bench_variant(b, &bc, &s, "generate-iter-only");
    fb_bench_peer loop = {
        .name = "minimal GLSL (bench/peers/julia_iter_peer.comp)", .mode = "-iter-only", FB_SPV(julia_iter_peer_comp)};
    if (!rc) rc = fb_bench_peer_layer(b, &bc, &s, &loop);
    fb_scene_fini(&s);
    return rc;
}
