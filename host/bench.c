/*
 * Benchmarks. Each measurement is a warm-up run (shader compilation, page faults) followed by
 * three timed runs, of which the median is reported. Generation-only runs compute every strip
 * and discard it; end-to-end runs write the EXR file as a user's bake would.
 */
#include "bench.h"

#include "bake.h"
#include "fbm_avx2.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

typedef struct bench_opts {
    bool json;
    int width, height;
    const char *device;
    int threads;
    bool vulkan, native;
} bench_opts;

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Median wall seconds (and GPU seconds) of three bakes after one warm-up. */
static fb_result timed(fb_engine *e, const fb_scene *s, const char *out, double *wall, double *gpu)
{
    double w[3], g[3];
    fb_bake_stats st;
    fb_result rc = fb_bake(e, &(fb_bake_desc){.scene = s, .out = out}, &st);
    for (int i = 0; i < 3 && !rc; i++) {
        rc = fb_bake(e, &(fb_bake_desc){.scene = s, .out = out}, &st);
        w[i] = st.seconds;
        g[i] = st.gpu_seconds;
    }
    if (rc) return rc;
    qsort(w, 3, sizeof w[0], cmp_double);
    qsort(g, 3, sizeof g[0], cmp_double);
    *wall = w[1];
    *gpu = g[1];
    return FB_OK;
}

static void report(const bench_opts *o, const fb_engine *e, const char *backend, const char *mode, int octaves,
                   int threads, double seconds, double gpu_seconds)
{
    double px = (double)o->width * o->height;
    double rate = px / seconds * 1e-6;
    if (o->json) {
        printf(
            "{\"generator\": \"fbm\", \"backend\": \"%s\", \"device\": \"%s\", \"mode\": \"%s\", \"unit\": \"Mpix/s\", "
            "\"rate\": %.2f, \"moctaves_per_s\": %.1f, \"size\": [%d, %d], \"octaves\": %d, \"threads\": %d",
            backend, e->device, mode, rate, rate * octaves, o->width, o->height, octaves, threads);
        if (gpu_seconds > 0) printf(", \"gpu_rate\": %.2f", px / gpu_seconds * 1e-6);
        printf("}\n");
    } else {
        printf("fbm  %-7s %-18s %8.1f Mpix/s %9.1f Moctave/s", backend, mode, rate, rate * octaves);
        if (gpu_seconds > 0) printf("  (timestamps: %.1f Mpix/s)", px / gpu_seconds * 1e-6);
        printf("  [%s]\n", e->device);
    }
    fflush(stdout);
}

/* Whole bakes with the EXR written, for each compression: what a user's bake costs. */
static fb_result end_to_end(const bench_opts *o, fb_engine *e, fb_scene *s, const char *out, int octaves)
{
    static const exrio_compression comps[] = {EXRIO_NONE, EXRIO_ZIP, EXRIO_PIZ};
    static const char *names[] = {"end-to-end-none", "end-to-end-zip", "end-to-end-piz"};
    exrio_compression keep = s->compression;
    fb_result rc = FB_OK;
    for (int c = 0; c < 3 && !rc; c++) {
        double wall, gpu;
        s->compression = comps[c];
        rc = timed(e, s, out, &wall, &gpu);
        if (!rc) report(o, e, fb_backend_name(e->kind), names[c], octaves, e->threads, wall, gpu);
    }
    s->compression = keep;
    return rc;
}

/* The AVX2 reference loop on every thread of the pool, strip by strip like the native backend. */
typedef struct avx2_job {
    const fb_gen *g;
    float *out;
    int rows_per_task, height;
} avx2_job;

static void avx2_task(void *ctx, int t)
{
    const avx2_job *j = ctx;
    int y0 = t * j->rows_per_task, n = y0 + j->rows_per_task <= j->height ? j->rows_per_task : j->height - y0;
    fb_fbm_avx2_rows(j->g->params, y0, n, j->out + (size_t)y0 * j->g->scene->width);
}

/* Median seconds of three full-image runs after a warm-up; -1 when AVX2 or memory is missing. */
static double time_avx2(const fb_scene *s, int threads)
{
    fb_gen g;
    fb_pool *pool = NULL;
    if (fb_gen_init(&g, s, &s->layers[0]) || !fb_fbm_avx2_supported(g.params)) return -1;
    float *out = malloc((size_t)s->width * s->height * 4);
    if (!out || fb_pool_create(threads, &pool)) {
        free(out);
        return -1;
    }
    avx2_job j = {.g = &g, .out = out, .rows_per_task = 16, .height = s->height};
    double t[4];
    for (int k = 0; k < 4; k++) {
        double t0 = fb_now();
        fb_pool_run(pool, (s->height + 15) / 16, avx2_task, &j);
        t[k] = fb_now() - t0;
    }
    fb_pool_destroy(&pool);
    free(out);
    qsort(t + 1, 3, sizeof t[0], cmp_double);
    return t[2];
}

fb_result fb_bench_main(int argc, char **argv)
{
    bench_opts o = {.width = 4096, .height = 4096, .vulkan = true, .native = true};
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--json")) {
            o.json = true;
        } else if (!strcmp(a, "--size") && v) {
            if (sscanf(v, "%dx%d", &o.width, &o.height) != 2 || o.width < 64 || o.height < 64 || o.width > 16384 ||
                o.height > 16384)
                return fb_fail(FB_ERR_USAGE, "--size: expected WxH with sides in 64..16384, found \"%s\"", v);
            i++;
        } else if (!strcmp(a, "--backend") && v) {
            o.vulkan = !strcmp(v, "vulkan");
            o.native = !strcmp(v, "native");
            if (!o.vulkan && !o.native)
                return fb_fail(FB_ERR_USAGE, "--backend: expected vulkan or native, found \"%s\"", v);
            i++;
        } else if (!strcmp(a, "--device") && v) {
            o.device = v;
            i++;
        } else if (!strcmp(a, "--threads") && v) {
            o.threads = atoi(v);
            if (o.threads < 1) return fb_fail(FB_ERR_USAGE, "--threads: expected a positive integer, found \"%s\"", v);
            i++;
        } else if (!strcmp(a, "--help")) {
            printf("usage: fractalbake bench [--json] [--size WxH] [--backend vulkan|native] [--device D] "
                   "[--threads N]\n");
            return FB_OK;
        } else {
            return fb_fail(FB_ERR_USAGE, "%s: unknown or incomplete flag for `fractalbake bench`", a);
        }
    }
    const int octaves = 8;
    char json[512];
    snprintf(json, sizeof json,
             "{\"size\": [%d, %d], \"seed\": 1, \"compression\": \"zip\", \"layers\": [{\"type\": \"fbm\", "
             "\"noise\": \"gradient\", \"octaves\": %d}]}",
             o.width, o.height, octaves);
    fb_scene s;
    fb_result rc = fb_scene_parse(json, NULL, &s);
    if (rc) return rc;
    char dir[] = "/tmp/fractalbake-bench-XXXXXX";
    if (!mkdtemp(dir)) {
        fb_scene_fini(&s);
        return fb_fail(FB_ERR_IO, "cannot create a temporary folder for the benchmark");
    }
    char out[64];
    snprintf(out, sizeof out, "%s/bench.exr", dir);
    if (!o.json)
        printf("fBm %d x %d, %d octaves of gradient noise; median of 3 runs after a warm-up\n", o.width, o.height,
               octaves);

    double wall, gpu;
    fb_engine e;
    bool have_vulkan = false;
    if (o.vulkan) {
        rc = fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_VULKAN, .device = o.device, .threads = o.threads},
                            &e);
        if (rc == FB_ERR_NODEVICE && o.native) {
            fb_log(FB_LOG_WARN, "no Vulkan device: benchmarking the native backend only");
            rc = FB_OK;
        } else if (!rc) {
            have_vulkan = true;
            rc = timed(&e, &s, NULL, &wall, &gpu);
            if (!rc) report(&o, &e, "vulkan", "generate", octaves, 0, wall, gpu);
            if (!rc) rc = end_to_end(&o, &e, &s, out, octaves);
            fb_engine_close(&e);
        }
    }
    if (!rc && o.native) {
        rc = fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = o.threads}, &e);
        if (!rc) {
            rc = timed(&e, &s, NULL, &wall, &gpu);
            if (!rc) report(&o, &e, "native", "generate", octaves, e.threads, wall, -1);
            if (!have_vulkan && !rc) rc = end_to_end(&o, &e, &s, out, octaves);
            fb_engine_close(&e);
        }
        /* The references: the same algorithm hand-vectorised with AVX2 (bit-exact with the kernel,
         * tests/test_avx2.c) on every core, and the kernel in a plain scalar loop on one core. */
        if (!rc) {
            int threads = o.threads > 0 ? o.threads : fb_cpu_count();
            double t = time_avx2(&s, threads);
            if (t > 0) {
                fb_engine ref = {.kind = FB_BACKEND_NATIVE, .threads = threads};
                snprintf(ref.device, sizeof ref.device, "hand-vectorised AVX2 C");
                report(&o, &ref, "native", "avx2-reference", octaves, threads, t, -1);
            }
        }
        if (!rc) rc = fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = 1, .scalar = true}, &e);
        if (!rc) {
            rc = timed(&e, &s, NULL, &wall, &gpu);
            if (!rc) report(&o, &e, "native", "scalar-1-thread", octaves, 1, wall, -1);
            fb_engine_close(&e);
        }
    }
    unlink(out);
    rmdir(dir);
    fb_scene_fini(&s);
    return rc;
}
