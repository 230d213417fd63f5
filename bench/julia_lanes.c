/*
 * The Julia layer's native rows against the AVX2 escape loop in thread CPU time, one thread: rates
 * that other processes on a shared machine do not move (the bench's wall-clock rates do). The
 * scene is `fractalbake bench --generator julia`'s (c = -0.8+0.156i, max-iter 256) at 1024 x 1024;
 * each line is the best of 7 passes, the variants alternating within each pass.
 *
 *     cmake --build build --target julia_lanes && build/julia_lanes
 */
#include "gen.h"
#include "julia_avx2.h"
#include "scene.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double cpu_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* A layer storing `channels` (a JSON list), its rows timed. */
static double layer_seconds(const char *channels, bool scalar)
{
    char json[512];
    snprintf(json, sizeof json,
             "{\"size\": [1024, 1024], \"seed\": 1, \"layers\": [{\"type\": \"julia\", \"c\": [-0.8, 0.156], "
             "\"max-iter\": 256, \"channels\": %s}]}",
             channels);
    fb_scene s;
    fb_gen g;
    if (fb_scene_parse(json, NULL, &s) || fb_gen_init(&g, &s, &s.layers[0])) exit(1);
    void *planes[FB_GEN_MAX_CHANNELS] = {0};
    /* touched before the clock starts: a bake reuses its strip buffers, so page faults are not the layer's */
    for (int c = 0; c < g.store.nchannels; c++) planes[fb_gen_plane_of(&g, c)] = calloc((size_t)s.width * s.height, 4);
    for (int c = 0; c < FB_GEN_MAX_CHANNELS; c++)
        if (planes[c]) memset(planes[c], 1, (size_t)s.width * s.height * 4);
    g.run.scalar = scalar;
    double t0 = cpu_seconds();
    g.compute.native_rows(&g, 0, s.height, planes);
    double t = cpu_seconds() - t0;
    for (int c = 0; c < FB_GEN_MAX_CHANNELS; c++) free(planes[c]);
    fb_gen_fini(&g);
    fb_scene_fini(&s);
    return t;
}

int main(void)
{
    const char *json = "{\"size\": [1024, 1024], \"seed\": 1, \"layers\": [{\"type\": \"julia\", \"c\": [-0.8, 0.156], "
                       "\"max-iter\": 256}]}";
    fb_scene s;
    fb_gen g;
    if (fb_scene_parse(json, NULL, &s) || fb_gen_init(&g, &s, &s.layers[0])) return 1;
    if (!fb_julia_avx2_supported(g.params)) {
        fprintf(stderr, "julia_lanes: this CPU has no AVX2\n");
        return 77;
    }
    uint32_t *iter = malloc((size_t)s.width * s.height * 4);
    static const char *const what[] = {"the AVX2 escape loop (avx2-reference)",
                                       "the layer, iter",
                                       "the layer, n",
                                       "the layer, de",
                                       "the layer, iter n inside de",
                                       "the layer, all seven channels",
                                       "the scalar loop, all seven channels"};
    static const char *const channels[] = {NULL,
                                           "[\"iter\"]",
                                           "[\"n\"]",
                                           "[\"de\"]",
                                           "[\"iter\", \"n\", \"inside\", \"de\"]",
                                           "[\"iter\", \"n\", \"inside\", \"de\", \"R\", \"G\", \"B\"]",
                                           "[\"iter\", \"n\", \"inside\", \"de\", \"R\", \"G\", \"B\"]"};
    double best[7] = {0};
    uint64_t iters = 0;
    for (int pass = 0; pass < 7; pass++)
        for (int k = 0; k < 7; k++) {
            if (k == 6 && pass > 0) continue; /* the scalar loop once: it is slow */
            double t;
            if (k == 0) {
                iters = 0;
                double t0 = cpu_seconds();
                fb_julia_avx2_rows(g.params, 0, s.height, iter, &iters);
                t = cpu_seconds() - t0;
            } else {
                t = layer_seconds(channels[k], k == 6);
            }
            double rate = (double)iters / t / 1e9;
            if (rate > best[k]) best[k] = rate;
        }
    printf("Julia 1024 x 1024, c = -0.8+0.156i, max-iter 256: %.1f iterations a pixel; one thread, CPU time\n",
           (double)iters / ((double)s.width * s.height));
    for (int k = 0; k < 7; k++)
        printf("%-40s %6.3f Giter/s  %5.2fx the escape loop\n", what[k], best[k], best[k] / best[0]);
    free(iter);
    fb_gen_fini(&g);
    fb_scene_fini(&s);
    return 0;
}
