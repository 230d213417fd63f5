/*
 * Erosion at the benchmark size (at most 1024 x 1024) over fBm-like ridges, 50 iterations, on each backend: the model
 * alone (no input layer, no file), in cell-iterations per second.
 */
#include "benchkit.h"
#include "erode.h"
#include "gen_erode.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

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
        double t[4], gpu[4];
        for (int k = 0; k < 4 && !rc; k++) { /* the first compiles the pipeline */
            fb_erode_out o;
            double t0 = fb_now();
            rc = fb_erode_run_vulkan(&d, e.vk, NULL, &o);
            t[k] = fb_now() - t0;
            gpu[k] = rc ? -1 : o.gpu_seconds;
            if (!rc) fb_erode_out_free(&o);
        }
        if (!rc) {
            double sec = fb_bench_median3(t + 1), g = fb_bench_median3(gpu + 1);
            row(b, "vulkan", e.device, 0, work / sec, g > 0 ? work / g : 0, sec);
        }
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
