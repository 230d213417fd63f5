/*
 * The chaos-game benchmark: Barnsley's fern on every backend (the game alone, and the whole bake),
 * against the hand-vectorised AVX2 game on every core and the textbook loop on one.
 */
#include "benchkit.h"
#include "gen_ifs.h"
#include "ifs_avx2.h"

#include "kernels/ifs.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The peer: the textbook chaos game on one core, as one would write it first. One chain of `points`
 * steps, xorshift32, the first `skip` points discarded. Adds to hits[] and sum[]; returns the points
 * plotted inside the frame. */
static uint64_t scalar_game(const void *params, const void *maps_, uint64_t points, uint32_t *hits, uint64_t *sum)
{
    const K_IfsParams *p = params;
    const K_IfsMap *maps = maps_;
    float cum[K_IFS_MAX_MAPS];
    for (uint32_t k = 0; k < p->nmaps; k++)
        cum[k] = k + 1 < p->nmaps ? (float)((double)maps[k + 1].thr / 4294967296.0) : 2.0f;
    uint32_t s = 2463534242u;
    float x = 0, y = 0, c = 0.5f;
    uint64_t plotted = 0;
    for (uint64_t i = 0; i < points; i++) {
        s ^= s << 13, s ^= s >> 17, s ^= s << 5; /* xorshift32 */
        float r = (float)(s >> 8) * (1.0f / 16777216.0f);
        uint32_t k = 0;
        while (r >= cum[k]) k++;
        const K_IfsMap *m = &maps[k];
        float nx = m->a * x + m->b * y + m->e, ny = m->c * x + m->d * y + m->f;
        x = nx, y = ny, c = (c + m->colour) * 0.5f;
        if (i < p->skip) continue;
        float px = (x - p->x0) * p->sx, py = (p->y0 - y) * p->sy;
        if (px >= 0 && py >= 0 && px < (float)p->hist_w && py < (float)p->hist_h) {
            size_t cell = (size_t)py * p->hist_w + (size_t)px;
            hits[cell]++;
            sum[cell] += (uint32_t)(c * 255.0f + 0.5f);
            plotted++;
        }
    }
    return plotted;
}

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
                rc = fb_ifs_avx2_game(g.params, g.compute.shader.input, threads, hits, sum);
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
            scalar_game(g.params, g.compute.shader.input, n, hits, sum);
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
        fb_bench_case bc = {"ifs", "Mpts/s", b->points, 1e6, NULL, 0};
        rc = fb_bench_auto_zip(b, &bc, &s);
        if (!rc) rc = run(b, &s);
    }
    fb_scene_fini(&s);
    return rc;
}
