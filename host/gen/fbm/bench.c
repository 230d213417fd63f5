/*
 * The fBm benchmark: 8 octaves of gradient noise on every backend, against the hand-vectorised AVX2
 * loop (the same kernel, bit-exact) on every core.
 */
#include "benchkit.h"
#include "fbm_avx2.h"
#include "gen_fbm.h"
/* after gen_fbm.h (core's headers): the SPIR-V array is a uint32_t[] */
#include "fbm_peer_comp.h"

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

/* The layer's shader against its minimal peer (bench/peers/fbm_peer.comp) on the device, for every
 * noise kind on the plane and gradient noise on the sphere (lat-long 2N x N, cube N x 6N at a
 * quarter of the bench's width), 8 octaves each. */
static fb_result peers(const fb_bench *b)
{
    static const char *const kinds[] = {"gradient", "value", "simplex", "cellular", "cellular-f2", "sine"};
    fb_result rc = FB_OK;
    for (uint32_t k = 0; k < 8 && !rc; k++) {
        uint32_t noise = k < 6 ? k : 0, mapping = k < 6 ? 0 : k - 5;
        int w = b->width, h = mapping == 0 ? b->height : mapping == 1 ? b->width / 2 : 6 * (b->width / 4);
        if (mapping == 2) w = b->width / 4;
        char json[512], mode[64];
        snprintf(json, sizeof json,
                 "{\"size\": [%d, %d], \"seed\": 1, \"layers\": [{\"type\": \"fbm\", \"noise\": \"%s\", "
                 "\"octaves\": 8, \"mapping\": \"%s\"}]}",
                 w, h, kinds[noise],
                 mapping == 0   ? "rect"
                 : mapping == 1 ? "latlong"
                                : "cube");
        snprintf(mode, sizeof mode, "-%s%s", kinds[noise], mapping == 0 ? "" : mapping == 1 ? "-latlong" : "-cube");
        fb_bench_case bc = {"fbm", "Mpix/s", (double)w * h, 1e6, NULL, 0};
        const uint32_t spec[2] = {noise, mapping};
        fb_bench_peer peer = {.name = "minimal GLSL (bench/peers/fbm_peer.comp)",
                              .mode = mode,
                              FB_SPV(fbm_peer_comp),
                              .spec = spec,
                              .nspec = 2};
        fb_scene s;
        rc = fb_scene_parse(json, NULL, &s);
        if (!rc) rc = fb_bench_peer_layer(b, &bc, &s, &peer);
        fb_scene_fini(&s);
    }
    return rc;
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
    if (!rc && b->vulkan) {
        fb_bench_heading(b, "fBm against its minimal shader on the device, 8 octaves, every noise kind on the plane "
                            "and gradient noise on the sphere; one dispatch a pass, median of 3 (timestamps)");
        rc = peers(b);
    }
    return rc;
}
