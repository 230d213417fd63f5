/*
 * The FBM constraint model at the benchmark size with 100 discrete and 20 continuous constraints
 * (native C, every thread).
 */
#include "benchkit.h"
#include "constrain.h"
#include "gen_constrain.h"

#include <stdio.h>
#include <stdlib.h>

fb_result fb_constrain_bench(fb_bench *b)
{
    if (!b->native) return FB_OK;
    int W = b->width, H = b->height;
    float *m = malloc((size_t)W * H * sizeof *m);
    fb_cpoint pts[100];
    fb_cregion regs[20];
    uint64_t seed = 7;
    for (int i = 0; i < 100; i++)
        pts[i] = (fb_cpoint){(int)(fb_bench_unit(&seed) * W), (int)(fb_bench_unit(&seed) * H)};
    for (int i = 0; i < 20; i++)
        regs[i] = (fb_cregion){(int)(fb_bench_unit(&seed) * W), (int)(fb_bench_unit(&seed) * H), i % 2 == 0,
                               i % 2 ? 0.1 : 0.9};
    if (!m) return fb_fail(FB_ERR_NOMEM, "out of memory");
    fb_constrain_macro("boss", W, H, 10, m);
    fb_constrain_desc d = {.width = W,
                           .height = H,
                           .seed = 1,
                           .hurst = 0.8,
                           .T = 0.3,
                           .sigma = 1,
                           .delta = 0.01,
                           .macro = m,
                           .points = pts,
                           .npoints = 100,
                           .regions = regs,
                           .nregions = 20,
                           .domain = 8,
                           .falloff = 0.0005,
                           .threads = b->threads};
    fb_result rc = FB_OK;
    int threads = b->threads > 0 ? b->threads : fb_cpu_count();
    fb_bench_heading(b, "FBM constraint model %d x %d, 100 discrete and 20 continuous constraints; median of 3", W, H);
    for (int linear = 0; linear < 2 && !rc; linear++) { /* the default smooth stencils, then the paper's averages */
        d.linear = linear;
        double w[3];
        for (int i = 0; i < 3 && !rc; i++) {
            fb_constrain_out out;
            double t0 = fb_now();
            rc = fb_constrain_run(&d, false, &out);
            w[i] = fb_now() - t0;
            free(out.D), free(out.T), free(out.H);
        }
        if (rc) break;
        double sec = fb_bench_median3(w);
        fb_bench_row r = {.generator = "constrain",
                          .backend = "native",
                          .device = "native C",
                          .mode = linear ? "generate, linear" : "generate",
                          .unit = "Mpix/s",
                          .rate = (double)W * H / sec * 1e-6,
                          .threads = threads,
                          .size = true};
        snprintf(r.note, sizeof r.note, "(%.3f s)", sec);
        b->row(b, &r);
    }
    free(m);
    return rc;
}
