/*
 * Stream-power erosion at the benchmark size (at most 1024 x 1024), 50 time steps from a flat start
 * under uniform uplift with open edges, hillslope diffusion and filled depressions: the model alone
 * (no file), in cell-steps per second. The first steps fill many depressions (the start is noise);
 * bench/rivers.sh runs 2048 x 2048 and 500 steps beside the plain C peer, bench/peers/rivers_peer.c.
 * Then the same model an eighth as wide, amplified to the benchmark size (amplify.h), in pixels per
 * second (no file).
 */
#include "amplify.h"
#include "benchkit.h"
#include "gen_rivers.h"
#include "rivers.h"

#include <stdio.h>
#include <stdlib.h>

enum { STEPS = 50 };

typedef struct amp_job {
    const fb_rivers_amp *a;
    float *Y; /* the whole image's heights */
} amp_job;

static void amp_rows(void *ctx, int y0, int n, int task)
{
    (void)task;
    const amp_job *j = ctx;
    fb_rivers_amp_rows(j->a, y0, n, j->Y + (size_t)y0 * j->a->W, NULL, NULL, NULL);
}

/* The model on a grid an eighth of W x H, amplified to W x H: the heights alone. */
static fb_result amplify_row(fb_bench *b, const fb_engine *e, fb_rivers_desc d, int W, int H)
{
    d.width = W / 8 > 16 ? W / 8 : 16, d.height = H / 8 > 16 ? H / 8 : 16, d.cell *= (double)W / d.width;
    d.receivers = true;
    if (2 * d.width > W || 2 * d.height > H) return FB_OK; /* too small to amplify */
    fb_rivers_out o;
    fb_rivers_amp a;
    fb_result rc = fb_rivers_run(&d, e->pool, NULL, &o);
    if (rc) return rc;
    rc = fb_rivers_amp_init(&a, &d, &o, W, H, 0.6);
    fb_rivers_out_free(&o);
    if (rc) return rc;
    amp_job j = {&a, malloc((size_t)W * H * sizeof(float))};
    double sec = j.Y ? fb_bench_rows(e->threads, H, amp_rows, &j, NULL) : -1;
    if (sec < 0) rc = fb_fail(FB_ERR_NOMEM, "rivers: out of memory for the amplification's benchmark");
    if (!rc) {
        fb_bench_row r = {.generator = "rivers",
                          .backend = "native",
                          .device = e->device,
                          .mode = "amplify",
                          .unit = "Mpix/s",
                          .rate = (double)W * H / sec * 1e-6,
                          .threads = e->threads,
                          .size = true};
        snprintf(r.note, sizeof r.note, "(from %d x %d cells, %.3f s)", d.width, d.height, sec);
        b->row(b, &r);
    }
    free(j.Y);
    fb_rivers_amp_fini(&a);
    return rc;
}

fb_result fb_rivers_bench(fb_bench *b)
{
    if (!b->native) return FB_OK; /* the host computes it on every backend: nothing of Vulkan's to measure */
    int W = b->width < 1024 ? b->width : 1024, H = b->height < 1024 ? b->height : 1024;
    fb_rivers_desc d = {.width = W,
                        .height = H,
                        .cell = 100000.0 / W,
                        .noise = 1,
                        .seed = 1,
                        .uplift = 1e-3,
                        .K = 5e-6,
                        .m = 0.5,
                        .n = 1,
                        .kd = 0.03,
                        .dt = 5e4,
                        .steps = STEPS,
                        .outlets = FB_RIVERS_NORTH | FB_RIVERS_SOUTH | FB_RIVERS_EAST | FB_RIVERS_WEST,
                        .river_area = 1e7};
    fb_bench_heading(b, "stream-power erosion %d x %d, %d steps (uplift, K A^m S^n, diffusion, fills); median of 3", W,
                     H, STEPS);
    fb_engine e;
    fb_result rc = fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = b->threads}, &e);
    if (rc) return rc;
    double t[3];
    for (int k = 0; k < 3 && !rc; k++) {
        fb_rivers_out o;
        double t0 = fb_now();
        rc = fb_rivers_run(&d, e.pool, NULL, &o);
        t[k] = fb_now() - t0;
        if (!rc) fb_rivers_out_free(&o);
    }
    if (!rc) {
        double sec = fb_bench_median3(t);
        fb_bench_row r = {.generator = "rivers",
                          .backend = "native",
                          .device = e.device,
                          .mode = "generate",
                          .unit = "Mcell-steps/s",
                          .rate = (double)W * H * STEPS / sec * 1e-6,
                          .threads = e.threads,
                          .size = true};
        snprintf(r.note, sizeof r.note, "(%d steps in %.3f s)", STEPS, sec);
        b->row(b, &r);
    }
    if (!rc) rc = amplify_row(b, &e, d, b->width, b->height);
    fb_engine_close(&e);
    return rc;
}
