/*
 * The chaos-game benchmark: Barnsley's fern on every backend (the game alone, and the whole bake),
 * against the hand-vectorised AVX2 game on every core and the textbook loop on one.
 */
#include "benchkit.h"
#include "gen_ifs.h"
#include "ifs_avx2.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void report(const fb_bench *b, const char *backend, const char *mode, const char *device, int threads,
                   double mpts, double gpu_mpts)
{
    fb_bench_row r = {.generator = "ifs",
                      .backend = backend,
                      .device = device,
                      .mode = mode,
                      .unit = "Mpts/s",
                      .rate = mpts,
                      .gpu_rate = gpu_mpts,
                      .threads = threads,
                      .size = true,
                      .nextra = 1,
                      .extra = {{"points", b->points, 0}}};
    b->row(b, &r);
}

/* Median chaos-game seconds of three prepares after a warm-up (the game alone: no reduction to
 * pixels, no tone mapping, no file). */
static fb_result time_game(fb_engine *e, const fb_scene *s, double *sec, double *gpu)
{
    double w[3], g[3];
    fb_result rc = FB_OK;
    for (int i = -1; i < 3 && !rc; i++) {
        fb_gen gen;
        rc = fb_gen_init(&gen, s, &s->layers[0]);
        if (!rc) rc = gen.prepare(&gen, e, false);
        if (!rc && i >= 0) {
            const fb_ifs_stats *st = fb_gen_ifs_stats(&gen);
            w[i] = st->game_seconds;
            g[i] = st->gpu_seconds;
        }
        fb_gen_fini(&gen);
    }
    if (rc) return rc;
    *sec = fb_bench_median3(w);
    *gpu = fb_bench_median3(g);
    return FB_OK;
}

static fb_result run(const fb_bench *b, const fb_scene *s)
{
    int threads = b->threads > 0 ? b->threads : fb_cpu_count();
    double pts = b->points, sec, gpu;
    fb_engine e;
    fb_result rc = FB_OK;
    bool have_vulkan = false;
    if (b->vulkan && !(rc = fb_bench_open_vulkan(b, &e, &have_vulkan)) && have_vulkan) {
        rc = time_game(&e, s, &sec, &gpu);
        if (!rc) report(b, "vulkan", "chaos-game", e.device, 0, pts / sec * 1e-6, gpu > 0 ? pts / gpu * 1e-6 : 0);
        double wall;
        if (!rc) rc = fb_bench_timed(&e, s, b->out, &wall, &gpu);
        if (!rc) report(b, "vulkan", "end-to-end-zip", e.device, 0, pts / wall * 1e-6, 0);
        fb_engine_close(&e);
    }
    if (!rc && b->native) {
        rc = fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = b->threads}, &e);
        if (!rc) {
            rc = time_game(&e, s, &sec, &gpu);
            if (!rc) report(b, "native", "chaos-game", e.device, e.threads, pts / sec * 1e-6, 0);
            fb_engine_close(&e);
        }
        /* the references: hand-vectorised AVX2 on every core, and the textbook loop on one */
        fb_gen g;
        if (!rc) rc = fb_gen_init(&g, s, &s->layers[0]);
        if (rc) return rc;
        size_t cells = (size_t)s->width * s->height;
        uint32_t *hits = malloc(cells * 4);
        uint64_t *sum = malloc(cells * 8);
        if (!hits || !sum) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
        if (!rc && fb_ifs_avx2_supported(g.params)) {
            double t[4];
            for (int k = 0; k < 4 && !rc; k++) {
                double t0 = fb_now();
                rc = fb_ifs_avx2_game(g.params, g.input, threads, hits, sum);
                t[k] = fb_now() - t0;
            }
            if (!rc)
                report(b, "native", "avx2-reference", "hand-vectorised AVX2 C", threads,
                       pts / fb_bench_median3(t + 1) * 1e-6, 0);
        }
        if (!rc) {
            uint64_t n = (uint64_t)(pts / 8);
            memset(hits, 0, cells * 4);
            memset(sum, 0, cells * 8);
            double t0 = fb_now();
            fb_ifs_scalar_game(g.params, g.input, n, hits, sum);
            report(b, "native", "scalar-1-thread", "textbook C loop", 1, (double)n / (fb_now() - t0) * 1e-6, 0);
        }
        free(hits);
        free(sum);
        fb_gen_fini(&g);
    }
    return rc;
}

fb_result fb_ifs_bench(fb_bench *b)
{
    char json[512];
    snprintf(json, sizeof json,
             "{\"size\": [%d, %d], \"seed\": 1, \"layers\": [{\"type\": \"ifs\", \"preset\": \"fern\", "
             "\"points\": %.0f}]}",
             b->width, b->height, b->points);
    fb_scene s;
    fb_result rc = fb_scene_parse(json, NULL, &s);
    if (!rc) {
        fb_bench_heading(b,
                         "IFS chaos game: Barnsley's fern, %d x %d, %.0f points (rate: points per second); median of 3",
                         b->width, b->height, b->points);
        rc = run(b, &s);
    }
    fb_scene_fini(&s);
    return rc;
}
