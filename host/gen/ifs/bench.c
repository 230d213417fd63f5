/*
 * The chaos-game benchmark: Barnsley's fern on every backend (the game alone, and the whole bake),
 * against the hand-vectorised AVX2 game on every core and the textbook loop on one.
 */
#include "benchkit.h"
#include "gen_ifs.h"
#include "ifs_avx2.h"

#include "kernels/ifs.h"
/* after the headers of core: the SPIR-V array is a uint32_t[] */
#include "ifs_peer_comp.h"

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

/* The chaos game's seconds of a prepared generator (the game alone: no reduction to pixels, no tone
 * mapping, no file). */
static void game_seconds(const fb_gen *g, double *sec, double *gpu)
{
    const fb_ifs_stats *st = fb_gen_ifs_stats(g);
    *sec = st->game_seconds, *gpu = st->gpu_seconds;
}

/* The bench's scene: Barnsley's fern at the bench's size, `points` points. */
static fb_result fern_scene(const fb_bench *b, double points, fb_scene *s)
{
    char json[512];
    snprintf(json, sizeof json,
             "{\"size\": [%d, %d], \"seed\": 1, \"layers\": [{\"type\": \"ifs\", \"preset\": \"fern\", "
             "\"points\": %.0f}]}",
             b->width, b->height, points);
    return fb_scene_parse(json, NULL, s);
}

/* ---- the chaos game beside its minimal shader (bench/peers/ifs_peer.comp) ---------------------- */

typedef struct peer_game {
    vkc_pipeline *pipe;
    vkc_job *job;
    vkc_buffer *buf[3]; /* maps, chains (16 bytes each), histogram (8 bytes a cell) */
    void *zero;
    size_t cells;
} peer_game;

static void peer_fini(vkc_context *vk, peer_game *pg)
{
    for (int k = 0; k < 3; k++) vkc_buffer_destroy(vk, &pg->buf[k]);
    vkc_job_destroy(vk, &pg->job);
    vkc_pipeline_destroy(vk, &pg->pipe);
    free(pg->zero);
}

static fb_result peer_init(vkc_context *vk, const fb_gen *g, peer_game *pg)
{
    const K_IfsParams *p = (const K_IfsParams *)(const void *)g->params;
    pg->cells = (size_t)p->hist_w * p->hist_h;
    fb_result rc = vkc_pipeline_create(
        vk,
        &(vkc_pipeline_desc){FB_SPV(ifs_peer_comp), .push_size = sizeof(K_IfsParams), .buffers = 3, .name = "ifs_peer"},
        &pg->pipe);
    if (!rc) rc = vkc_job_create(vk, pg->pipe, &pg->job);
    if (!rc) rc = vkc_buffer_create(vk, g->compute.shader.input_size, &pg->buf[0]);
    if (!rc) rc = vkc_buffer_create(vk, 16ull * p->chains, &pg->buf[1]);
    if (!rc) rc = vkc_buffer_create(vk, 8ull * pg->cells, &pg->buf[2]);
    if (!rc) rc = vkc_buffer_upload(vk, pg->buf[0], g->compute.shader.input, g->compute.shader.input_size);
    if (!rc && !(pg->zero = calloc(pg->cells, 8))) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    return rc;
}

/* One whole game of the peer in dispatches of `nsteps` steps a chain, the histogram cleared first
 * (by a job of no steps, outside the timing, as the layer's); host-clock and timestamp seconds. */
static fb_result peer_run(vkc_context *vk, const fb_gen *g, peer_game *pg, uint32_t nsteps, double *wall, double *gpu)
{
    K_IfsParams p = *(const K_IfsParams *)(const void *)g->params;
    uint32_t groups[3] = {(p.chains + 63) / 64, 1, 1}, last = p.base + (p.extra ? 1u : 0u);
    fb_result rc = vkc_buffer_upload(vk, pg->buf[2], pg->zero, 8ull * pg->cells);
    p.step0 = 0, p.nsteps = 0;
    if (!rc) rc = vkc_job_submit(vk, pg->job, pg->buf, 3, &p, groups);
    if (!rc) rc = vkc_job_wait(vk, pg->job, NULL);
    *gpu = 0;
    double t0 = fb_now();
    for (uint32_t step0 = 0; step0 < last && !rc; step0 += nsteps) {
        p.step0 = step0, p.nsteps = nsteps;
        double t = -1;
        rc = vkc_job_submit(vk, pg->job, pg->buf, 3, &p, groups);
        if (!rc) rc = vkc_job_wait(vk, pg->job, &t);
        *gpu += t > 0 ? t : 0;
    }
    *wall = fb_now() - t0;
    return rc;
}

/* The layer's game (by prepare, as a bake plays it) and the peer's, alternating, a warm-up and three
 * each, on the fern of `points` points; the layer's count and colour against the peer's histogram
 * on the last. */
static fb_result peer_compare(const fb_bench *b, fb_engine *e, double points)
{
    fb_scene scene;
    fb_result rc = fern_scene(b, points, &scene);
    if (rc) return rc;
    const fb_scene *s = &scene;
    fb_gen g;
    peer_game pg = {0};
    rc = fb_gen_init(&g, s, &s->layers[0]);
    if (rc) {
        fb_scene_fini(&scene);
        return rc;
    }
    rc = peer_init(e->vk, &g, &pg);
    uint32_t nsteps = fb_ifs_steps_per_dispatch(&g, e->vk);
    double wall[2][3], gpu[2][3];
    size_t n = (size_t)s->width * s->height;
    uint32_t *count = malloc(n * 4);
    float *planes[7] = {0};
    for (int c = 0; c < 7 && !rc; c++)
        if (!(planes[c] = malloc(n * 4))) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    for (int run = -1; run < 3 && !rc; run++) {
        fb_gen layer;
        rc = fb_gen_init(&layer, s, &s->layers[0]);
        if (!rc) rc = layer.prepare(&layer, e, false);
        if (!rc && run >= 0) {
            wall[0][run] = fb_gen_ifs_stats(&layer)->game_seconds;
            gpu[0][run] = fb_gen_ifs_stats(&layer)->gpu_seconds;
        }
        if (!rc && run == 2) layer.compute.native_rows(&layer, 0, s->height, (void *const *)planes);
        fb_gen_fini(&layer);
        double w = 0, t = 0;
        if (!rc) rc = peer_run(e->vk, &g, &pg, nsteps, &w, &t);
        if (!rc && run >= 0) wall[1][run] = w, gpu[1][run] = t;
    }
    uint64_t diff = 0;
    if (!rc) {
        /* the bench's layer has one histogram cell a pixel (no oversampling) */
        const uint64_t *cell = vkc_buffer_data(pg.buf[2]);
        memcpy(count, planes[0], n * 4);
        for (size_t i = 0; i < n; i++) {
            uint64_t hits = cell[i] & K_IFS_HIT_MASK, sum = cell[i] >> K_IFS_HIT_BITS;
            float colour = hits ? (float)((double)sum / (255.0 * (double)hits)) : 0.0f;
            diff += count[i] != hits || memcmp(&planes[2][i], &colour, 4) != 0;
        }
        char note[64];
        snprintf(note, sizeof note, "(%.0f points, %u steps a chain a dispatch)", points, nsteps);
        fb_bench_peer_rows(b, "ifs", e->device, "minimal GLSL (bench/peers/ifs_peer.comp)", NULL, "Mpts/s", points, 1e6,
                           wall, gpu, diff, note);
    }
    for (int c = 0; c < 7; c++) free(planes[c]);
    free(count);
    peer_fini(e->vk, &pg);
    fb_gen_fini(&g);
    fb_scene_fini(&scene);
    return rc;
}

static fb_result run(const fb_bench *b, const fb_bench_case *bc, const fb_scene *s)
{
    int threads = b->threads > 0 ? b->threads : fb_cpu_count();
    double pts = b->points, sec, gpu;
    fb_engine e;
    fb_result rc = FB_OK;
    bool have_vulkan = false;
    if (b->vulkan && !(rc = fb_bench_open_vulkan(b, &e, &have_vulkan)) && have_vulkan) {
        rc = fb_bench_prepared(&e, s, game_seconds, &sec, &gpu);
        if (!rc) report(b, "vulkan", "chaos-game", e.device, 0, pts / sec * 1e-6, gpu > 0 ? pts / gpu * 1e-6 : 0);
        double wall;
        if (!rc) rc = fb_bench_timed(&e, s, b->out, &wall, &gpu);
        if (!rc) report(b, "vulkan", "end-to-end-zip", e.device, 0, pts / wall * 1e-6, 0);
        if (!rc) rc = fb_bench_encode(b, bc, "zip", wall);
        /* on a CPU device (lavapipe) the pair plays at most 2^25 points a game: eight games of the
         * bench's 2^28 would take minutes there */
        double cap = !strcmp(vkc_info(e.vk)->type, "cpu") && pts > 33554432.0 ? 33554432.0 : pts;
        if (!rc && vkc_info(e.vk)->int64_atomics) rc = peer_compare(b, &e, cap);
        fb_engine_close(&e);
    }
    if (!rc && b->native) {
        rc = fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = b->threads}, &e);
        if (!rc) {
            rc = fb_bench_prepared(&e, s, game_seconds, &sec, &gpu);
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
    fb_scene s;
    fb_result rc = fern_scene(b, b->points, &s);
    if (!rc) {
        fb_bench_heading(b,
                         "IFS chaos game: Barnsley's fern, %d x %d, %.0f points (rate: points per second); median of 3",
                         b->width, b->height, b->points);
        fb_bench_case bc = {"ifs", "Mpts/s", b->points, 1e6, NULL, 0};
        rc = fb_bench_auto_zip(b, &bc, &s);
        if (!rc) rc = run(b, &bc, &s);
    }
    fb_scene_fini(&s);
    return rc;
}
