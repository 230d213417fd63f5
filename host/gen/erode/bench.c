/*
 * Erosion at the benchmark size (at most 1024 x 1024) over fBm-like ridges, 50 iterations, on each backend: the model
 * alone (no input layer, no file), in cell-iterations per second; on the device, beside a minimal shader of the same
 * passes (bench/peers/erode_peer.comp) in the same run, its results checked bit for bit.
 */
#include "benchkit.h"
#include "erode.h"
#include "gen_erode.h"

#include "kernels/erode.h"
/* after the headers of core: the SPIR-V array is a uint32_t[] */
#include "erode_peer_comp.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { ITERS = 50 };

static void terrain(int W, int H, float *h)
{
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            double u = (double)x / W, v = (double)y / H;
            h[(size_t)y * W + x] = (float)(40 * sin(6.1 * u) * cos(4.3 * v) + 12 * sin(23 * u + 17 * v) +
                                           4 * cos(71 * u - 53 * v) + 30 * v);
        }
}

static void row(const fb_bench *b, const char *backend, const char *device, int threads, double rate, double gpu,
                double sec)
{
    fb_bench_row r = {.generator = "erode",
                      .backend = backend,
                      .device = device,
                      .mode = "generate",
                      .unit = "Mcell-iter/s",
                      .rate = rate,
                      .gpu_rate = gpu,
                      .threads = threads,
                      .size = true};
    snprintf(r.note, sizeof r.note, "(%d iterations in %.3f s)", ITERS, sec);
    b->row(b, &r);
}

/* The minimal shader's side: a pipeline and a job a pass, the four grids. */
typedef struct peer_side {
    vkc_pipeline *pipe[3];
    vkc_job *job[3];
    vkc_buffer *buf[4]; /* S, T, F, M as the layer's (host/gen/erode/erode.c) */
} peer_side;

static void peer_fini(vkc_context *vk, peer_side *ps)
{
    for (int k = 0; k < 3; k++) vkc_job_destroy(vk, &ps->job[k]), vkc_pipeline_destroy(vk, &ps->pipe[k]);
    for (int k = 0; k < 4; k++) vkc_buffer_destroy(vk, &ps->buf[k]);
}

static fb_result peer_init(vkc_context *vk, size_t n, peer_side *ps)
{
    fb_result rc = FB_OK;
    for (uint32_t k = 0; k < 3 && !rc; k++) {
        rc = vkc_pipeline_create(vk,
                                 &(vkc_pipeline_desc){FB_SPV(erode_peer_comp), .push_size = sizeof(K_ErodeParams),
                                                      .buffers = 4, .spec = &k, .nspec = 1, .name = "erode_peer"},
                                 &ps->pipe[k]);
        if (!rc) rc = vkc_job_create(vk, ps->pipe[k], &ps->job[k]);
    }
    for (int k = 0; k < 4 && !rc; k++) rc = vkc_buffer_create(vk, (uint64_t)n * 16, &ps->buf[k]);
    return rc;
}

/* The whole model by the peer: the grids as the layer starts them, then its passes; host-clock and
 * timestamp seconds of the passes. */
static fb_result peer_run(vkc_context *vk, const fb_erode_desc *d, peer_side *ps, double *wall, double *gpu)
{
    size_t n = (size_t)d->width * d->height;
    k_vec4 *init = calloc(n, sizeof *init);
    if (!init) return fb_fail(FB_ERR_NOMEM, "out of memory");
    fb_result rc = FB_OK;
    for (int k = 3; k >= 0 && !rc; k--) {
        if (k == 0)
            for (size_t i = 0; i < n; i++) init[i].x = d->bed[i];
        rc = vkc_buffer_upload(vk, ps->buf[k], init, (uint64_t)n * 16);
    }
    free(init);
    K_ErodeParams p = fb_erode_params(d);
    uint32_t groups[3] = {((uint32_t)d->width + 15) / 16, ((uint32_t)d->height + 15) / 16, 1};
    *gpu = 0;
    double t0 = fb_now();
    for (int it = 0; it < d->iterations && !rc; it++)
        for (int k = 0; k < 3 && !rc; k++) {
            double t = -1;
            rc = vkc_job_submit(vk, ps->job[k], ps->buf, 4, &p, groups);
            if (!rc) rc = vkc_job_wait(vk, ps->job[k], &t);
            *gpu += t > 0 ? t : 0;
        }
    *wall = fb_now() - t0;
    return rc;
}

/* The values of the layer's result that differ from the peer's grids (bed, water, sediment; flow,
 * wear, deposit). */
static uint64_t differing(const fb_erode_out *o, const peer_side *ps, size_t n)
{
    const k_vec4 *S = vkc_buffer_data(ps->buf[0]), *M = vkc_buffer_data(ps->buf[3]);
    uint64_t diff = 0;
    for (size_t i = 0; i < n; i++) {
        const float a[6] = {o->bed[i], o->water[i], o->sediment[i], o->flow[i], o->wear[i], o->deposit[i]};
        const float c[6] = {S[i].x, S[i].y, S[i].z, M[i].x, M[i].y, M[i].z};
        for (int k = 0; k < 6; k++) diff += memcmp(&a[k], &c[k], 4) != 0;
    }
    return diff;
}

/* The layer's model and the peer's, alternating: a warm-up (which compiles the pipelines) and three
 * each; the "generate" row, then the "kernel" and "peer" rows. */
static fb_result time_vulkan(const fb_bench *b, fb_engine *e, const fb_erode_desc *d, double work)
{
    size_t n = (size_t)d->width * d->height;
    peer_side ps = {0};
    fb_result rc = peer_init(e->vk, n, &ps);
    double wall[2][3], gpu[2][3];
    uint64_t diff = 0;
    for (int k = -1; k < 3 && !rc; k++) {
        fb_erode_out o;
        double t0 = fb_now(), w, g = 0;
        rc = fb_erode_run_vulkan(d, e->vk, NULL, &o);
        if (rc) break;
        w = fb_now() - t0;
        if (k >= 0) wall[0][k] = w, gpu[0][k] = o.gpu_seconds;
        rc = peer_run(e->vk, d, &ps, &w, &g);
        if (!rc && k >= 0) wall[1][k] = w, gpu[1][k] = g;
        if (!rc && k == 2) diff = differing(&o, &ps, n);
        fb_erode_out_free(&o);
    }
    if (!rc) {
        double sec = fb_bench_median3(wall[0]), g = fb_bench_median3(gpu[0]);
        row(b, "vulkan", e->device, 0, work / sec, g > 0 ? work / g : 0, sec);
        char note[64];
        snprintf(note, sizeof note, "(%d iterations of 3 dispatches)", d->iterations);
        fb_bench_peer_rows(b, "erode", e->device, "minimal GLSL (bench/peers/erode_peer.comp)", NULL, "Mcell-iter/s",
                           work, 1, wall, gpu, diff, note);
    }
    peer_fini(e->vk, &ps);
    return rc;
}

fb_result fb_erode_bench(fb_bench *b)
{
    /* at most 1024 x 1024: 16 bytes a cell must fit a storage buffer of lavapipe's 128 MiB */
    int W = b->width < 1024 ? b->width : 1024, H = b->height < 1024 ? b->height : 1024;
    float *h = malloc((size_t)W * H * sizeof *h);
    if (!h) return fb_fail(FB_ERR_NOMEM, "out of memory");
    terrain(W, H, h);
    fb_erode_desc d = {.width = W,
                       .height = H,
                       .cell = 1024.0 / W,
                       .iterations = ITERS,
                       .duration = 15,
                       .rain = 0.005,
                       .gravity = 9.81,
                       .capacity = 0.05,
                       .dissolve = 0.5,
                       .deposit = 1,
                       .evaporate = 0.2,
                       .depth = 0.05,
                       .talus = 35,
                       .thermal = 0.5,
                       .bed = h};
    double work = (double)W * H * ITERS * 1e-6;
    fb_bench_heading(b, "erosion %d x %d, %d iterations of the pipe model and thermal slides; median of 3", W, H,
                     ITERS);
    fb_result rc = FB_OK;
    fb_engine e;
    bool have = false;
    if (b->vulkan && !(rc = fb_bench_open_vulkan(b, &e, &have)) && have) {
        rc = time_vulkan(b, &e, &d, work);
        fb_engine_close(&e);
    }
    if (!rc && b->native) {
        rc = fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = b->threads}, &e);
        if (!rc) {
            double t[3];
            for (int k = 0; k < 3 && !rc; k++) {
                fb_erode_out o;
                double t0 = fb_now();
                rc = fb_erode_run_native(&d, e.pool, NULL, &o);
                t[k] = fb_now() - t0;
                if (!rc) fb_erode_out_free(&o);
            }
            if (!rc) {
                double sec = fb_bench_median3(t);
                row(b, "native", e.device, e.threads, work / sec, 0, sec);
            }
            fb_engine_close(&e);
        }
    }
    free(h);
    return rc;
}
