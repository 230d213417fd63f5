/*
 * Benchmarks. Each measurement is a warm-up run (shader compilation, page faults) followed by
 * three timed runs, of which the median is reported. Generation-only runs compute every strip
 * and discard it; end-to-end runs write the EXR file as a user's bake would. Every figure of one
 * generator comes from the same run, so that ratios between backends are meaningful on a noisy
 * machine.
 */
#include "bench.h"
#include "constrain.h"
#include "delaunay.h"
#include "terrain.h"

#include "bake.h"
#include "fbm_avx2.h"
#include "ifs.h"
#include "ifs_avx2.h"
#include "julia_avx2.h"

#include <math.h>
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
    bool fbm, julia, ifs, terrain, constrain;
    double points; /* ifs: chaos-game steps per run */
} bench_opts;

/* One benchmark: a one-layer scene, its work unit, and the work one image represents. */
typedef struct bench_case {
    const char *generator; /* "fbm", "julia" */
    const char *unit;      /* "Mpix/s", "Giter/s" */
    double work;           /* units of work in one image (pixels, iterations) */
    double unit_scale;     /* work per unit: 1e6 for Mpix, 1e9 for Giter */
    const char *extra;     /* a second figure's JSON name, or NULL */
    double extra_per_work; /* its work per unit of `work`, in millions */
} bench_case;

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

static void report(const bench_opts *o, const bench_case *bc, const char *device, const char *backend, const char *mode,
                   int threads, double seconds, double gpu_seconds)
{
    double rate = bc->work / seconds / bc->unit_scale;
    if (o->json) {
        printf("{\"generator\": \"%s\", \"backend\": \"%s\", \"device\": \"%s\", \"mode\": \"%s\", \"unit\": \"%s\", "
               "\"rate\": %.3f, \"size\": [%d, %d], \"threads\": %d",
               bc->generator, backend, device, mode, bc->unit, rate, o->width, o->height, threads);
        if (bc->extra) printf(", \"%s\": %.1f", bc->extra, rate * bc->extra_per_work);
        if (gpu_seconds > 0) printf(", \"gpu_rate\": %.3f", bc->work / gpu_seconds / bc->unit_scale);
        printf("}\n");
    } else {
        printf("%-6s %-7s %-18s %8.2f %s", bc->generator, backend, mode, rate, bc->unit);
        if (gpu_seconds > 0) printf("  (timestamps: %.2f %s)", bc->work / gpu_seconds / bc->unit_scale, bc->unit);
        printf("  [%s]\n", device);
    }
    fflush(stdout);
}

/* Whole bakes with the EXR written, for each compression: what a user's bake costs. */
static fb_result end_to_end(const bench_opts *o, const bench_case *bc, fb_engine *e, fb_scene *s, const char *out)
{
    static const exrio_compression comps[] = {EXRIO_NONE, EXRIO_ZIP, EXRIO_PIZ};
    static const char *names[] = {"end-to-end-none", "end-to-end-zip", "end-to-end-piz"};
    exrio_compression keep = s->compression;
    fb_result rc = FB_OK;
    for (int c = 0; c < 3 && !rc; c++) {
        double wall, gpu;
        s->compression = comps[c];
        rc = timed(e, s, out, &wall, &gpu);
        if (!rc) report(o, bc, e->device, fb_backend_name(e->kind), names[c], e->threads, wall, gpu);
    }
    s->compression = keep;
    return rc;
}

/* ---- the hand-vectorised references, on every thread of a pool --------------------------------- */

typedef struct ref_job {
    const fb_gen *g;
    void *out;
    int rows_per_task, height;
    bool julia;
    uint64_t totals[4096];
} ref_job;

static void ref_task(void *ctx, int t)
{
    ref_job *j = ctx;
    int y0 = t * j->rows_per_task, n = y0 + j->rows_per_task <= j->height ? j->rows_per_task : j->height - y0;
    size_t at = (size_t)y0 * j->g->scene->width;
    if (j->julia)
        fb_julia_avx2_rows(j->g->params, y0, n, (uint32_t *)j->out + at, &j->totals[t]);
    else
        fb_fbm_avx2_rows(j->g->params, y0, n, (float *)j->out + at);
}

/* Median seconds of three full-image runs after a warm-up; -1 when AVX2 or memory is missing.
 * *total (optional) receives the Julia iterations executed in one image. */
static double time_reference(const fb_scene *s, int threads, uint64_t *total)
{
    fb_gen g;
    fb_pool *pool = NULL;
    ref_job *j = calloc(1, sizeof *j);
    double result = -1;
    if (!j || fb_gen_init(&g, s, &s->layers[0])) {
        free(j);
        return -1;
    }
    j->julia = s->layers[0].kind == FB_LAYER_JULIA;
    bool ok = j->julia ? fb_julia_avx2_supported(g.params) : fb_fbm_avx2_supported(g.params);
    j->out = ok ? malloc((size_t)s->width * s->height * 4) : NULL;
    if (j->out && !fb_pool_create(threads, &pool)) {
        j->g = &g;
        j->rows_per_task = (s->height + 4095) / 4096 > 16 ? (s->height + 4095) / 4096 : 16;
        j->height = s->height;
        int tasks = (s->height + j->rows_per_task - 1) / j->rows_per_task;
        double t[4];
        for (int k = 0; k < 4; k++) {
            memset(j->totals, 0, sizeof j->totals);
            double t0 = fb_now();
            fb_pool_run(pool, tasks, ref_task, j);
            t[k] = fb_now() - t0;
        }
        if (total) {
            *total = 0;
            for (int k = 0; k < tasks; k++) *total += j->totals[k];
        }
        qsort(t + 1, 3, sizeof t[0], cmp_double);
        result = t[2];
    }
    fb_pool_destroy(&pool);
    free(j->out);
    free(j);
    fb_gen_fini(&g);
    return result;
}

/* Opens the Vulkan engine; *have is false (and the result FB_OK) when there is no device and the
 * native backend is benchmarked anyway. */
static fb_result open_vulkan(const bench_opts *o, fb_engine *e, bool *have)
{
    fb_result rc =
        fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_VULKAN, .device = o->device, .threads = o->threads}, e);
    *have = rc == FB_OK;
    if (rc == FB_ERR_NODEVICE && o->native) {
        fb_log(FB_LOG_WARN, "no Vulkan device: benchmarking the native backend only");
        rc = FB_OK;
    }
    return rc;
}

/* ---- the chaos game -------------------------------------------------------------------------- */

static void report_rate(const bench_opts *o, const char *backend, const char *mode, const char *device, int threads,
                        double mpts, double gpu_mpts)
{
    if (o->json) {
        printf("{\"generator\": \"ifs\", \"backend\": \"%s\", \"device\": \"%s\", \"mode\": \"%s\", \"unit\": "
               "\"Mpts/s\", \"rate\": %.3f, \"size\": [%d, %d], \"points\": %.0f, \"threads\": %d",
               backend, device, mode, mpts, o->width, o->height, o->points, threads);
        if (gpu_mpts > 0) printf(", \"gpu_rate\": %.3f", gpu_mpts);
        printf("}\n");
    } else {
        printf("%-6s %-7s %-18s %8.1f Mpts/s", "ifs", backend, mode, mpts);
        if (gpu_mpts > 0) printf("  (timestamps: %.1f Mpts/s)", gpu_mpts);
        printf("  [%s]\n", device);
    }
    fflush(stdout);
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
    qsort(w, 3, sizeof w[0], cmp_double);
    qsort(g, 3, sizeof g[0], cmp_double);
    *sec = w[1];
    *gpu = g[1];
    return FB_OK;
}

static fb_result run_ifs(const bench_opts *o, const fb_scene *s, const char *out)
{
    int threads = o->threads > 0 ? o->threads : fb_cpu_count();
    double pts = o->points, sec, gpu;
    fb_engine e;
    fb_result rc = FB_OK;
    bool have_vulkan = false;
    if (o->vulkan && !(rc = open_vulkan(o, &e, &have_vulkan)) && have_vulkan) {
        rc = time_game(&e, s, &sec, &gpu);
        if (!rc) report_rate(o, "vulkan", "chaos-game", e.device, 0, pts / sec * 1e-6, gpu > 0 ? pts / gpu * 1e-6 : 0);
        double wall;
        if (!rc) rc = timed(&e, s, out, &wall, &gpu);
        if (!rc) report_rate(o, "vulkan", "end-to-end-zip", e.device, 0, pts / wall * 1e-6, 0);
        fb_engine_close(&e);
    }
    if (!rc && o->native) {
        rc = fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = o->threads}, &e);
        if (!rc) {
            rc = time_game(&e, s, &sec, &gpu);
            if (!rc) report_rate(o, "native", "chaos-game", e.device, e.threads, pts / sec * 1e-6, 0);
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
            qsort(t + 1, 3, sizeof t[0], cmp_double);
            if (!rc)
                report_rate(o, "native", "avx2-reference", "hand-vectorised AVX2 C", threads, pts / t[2] * 1e-6, 0);
        }
        if (!rc) {
            uint64_t n = (uint64_t)(pts / 8);
            memset(hits, 0, cells * 4);
            memset(sum, 0, cells * 8);
            double t0 = fb_now();
            fb_ifs_scalar_game(g.params, g.input, n, hits, sum);
            report_rate(o, "native", "scalar-1-thread", "textbook C loop", 1, (double)n / (fb_now() - t0) * 1e-6, 0);
        }
        free(hits);
        free(sum);
        fb_gen_fini(&g);
    }
    return rc;
}

/* ---- one generator on every backend ----------------------------------------------------------- */

static fb_result run_case(const bench_opts *o, bench_case *bc, fb_scene *s, const char *out)
{
    fb_result rc = FB_OK;
    double wall, gpu;
    int threads = o->threads > 0 ? o->threads : fb_cpu_count();
    /* The reference runs first: for Julia it also counts the iterations one image executes. */
    uint64_t iters = 0;
    double tref = time_reference(s, threads, bc->work == 0 ? &iters : NULL);
    if (bc->work == 0) {
        if (tref < 0) return fb_fail(FB_ERR_INTERNAL, "bench: the %s benchmark needs AVX2", bc->generator);
        bc->work = (double)iters;
        bc->extra_per_work = 1e3 * (double)o->width * o->height / (double)iters; /* Giter/s -> Mpix/s */
    }
    fb_engine e;
    bool have_vulkan = false;
    if (o->vulkan && !(rc = open_vulkan(o, &e, &have_vulkan)) && have_vulkan) {
        rc = timed(&e, s, NULL, &wall, &gpu);
        if (!rc) report(o, bc, e.device, "vulkan", "generate", 0, wall, gpu);
        if (!rc) rc = end_to_end(o, bc, &e, s, out);
        fb_engine_close(&e);
    }
    if (!rc && o->native) {
        rc = fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = o->threads}, &e);
        if (!rc) {
            rc = timed(&e, s, NULL, &wall, &gpu);
            if (!rc) report(o, bc, e.device, "native", "generate", e.threads, wall, -1);
            if (!have_vulkan && !rc) rc = end_to_end(o, bc, &e, s, out);
            fb_engine_close(&e);
        }
        /* The references: the same algorithm hand-vectorised with AVX2 (bit-exact with the kernel,
         * tests/test_avx2.c) on every core, and the kernel in a plain scalar loop on one core. */
        if (!rc && tref > 0) report(o, bc, "hand-vectorised AVX2 C", "native", "avx2-reference", threads, tref, -1);
        if (!rc) rc = fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = 1, .scalar = true}, &e);
        if (!rc) {
            rc = timed(&e, s, NULL, &wall, &gpu);
            if (!rc) report(o, bc, e.device, "native", "scalar-1-thread", 1, wall, -1);
            fb_engine_close(&e);
        }
    }
    return rc;
}

/* The layer alone (no file) on each backend, under another mode name: a variant of a case whose work
 * run_case has measured (a julia layer storing only `iter`: like for like with the AVX2 loop). */
static fb_result run_variant(const bench_opts *o, const bench_case *bc, fb_scene *s, const char *mode)
{
    fb_result rc = FB_OK;
    double wall, gpu;
    fb_engine e;
    bool have_vulkan = false;
    if (o->vulkan && !(rc = open_vulkan(o, &e, &have_vulkan)) && have_vulkan) {
        rc = timed(&e, s, NULL, &wall, &gpu);
        if (!rc) report(o, bc, e.device, "vulkan", mode, 0, wall, gpu);
        fb_engine_close(&e);
    }
    if (!rc && o->native) {
        rc = fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = o->threads}, &e);
        if (!rc) {
            rc = timed(&e, s, NULL, &wall, &gpu);
            if (!rc) report(o, bc, e.device, "native", mode, e.threads, wall, -1);
            fb_engine_close(&e);
        }
    }
    return rc;
}

/* ---- Delaunay triangulation and terrain refinement (CPU, one thread) ----------------------------- */

/* The benchmark's points: splitmix64, so that bench/cgal_delaunay.cpp generates the same ones. */
static uint64_t splitmix64(uint64_t *s)
{
    uint64_t z = (*s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static double unit_of(uint64_t *s)
{
    return (double)(splitmix64(s) >> 11) * 0x1.0p-53;
}

static void report_inserts(const bench_opts *o, const char *generator, const char *mode, double inserts, double seconds)
{
    double rate = inserts / seconds * 1e-6;
    if (o->json)
        printf("{\"generator\": \"%s\", \"backend\": \"native\", \"device\": \"native C\", \"mode\": \"%s\", "
               "\"unit\": \"Minserts/s\", \"rate\": %.3f, \"inserts\": %.0f, \"seconds\": %.3f, \"threads\": 1}\n",
               generator, mode, rate, inserts, seconds);
    else
        printf("%-8s native  %-22s %8.3f Minserts/s  (%.0f inserts in %.3f s)  [native C, 1 thread]\n", generator, mode,
               rate, inserts, seconds);
    fflush(stdout);
}

static fb_result run_terrain(const bench_opts *o)
{
    const size_t n = 1000000;
    double *xy = malloc(n * 2 * sizeof *xy), *xyz = malloc(1000 * 3 * sizeof *xyz);
    double w[3];
    fb_result rc = xy && xyz ? FB_OK : fb_fail(FB_ERR_NOMEM, "out of memory");
    uint64_t seed = 1;
    for (size_t i = 0; i < 2 * n && !rc; i++) xy[i] = unit_of(&seed);
    if (!o->json)
        printf("Delaunay: 10^6 uniform random points; terrain: 10^3 survey points refined by 10^6; median of 3\n");
    for (int i = -1; i < 3 && !rc; i++) { /* a warm-up, then three */
        fb_dt d;
        memset(&d, 0, sizeof d);
        double t0 = fb_now();
        rc = fb_dt_build(&d, xy, n, NULL, "bench");
        if (i >= 0) w[i] = fb_now() - t0;
        fb_dt_free(&d);
    }
    if (!rc) {
        qsort(w, 3, sizeof w[0], cmp_double);
        report_inserts(o, "delaunay", "build-1e6-uniform", (double)n, w[1]);
    }
    /* survey points: a smooth hill with noise over a 1000 x 1000 area */
    for (size_t i = 0; i < 1000 && !rc; i++) {
        double x = 1000 * unit_of(&seed), y = 1000 * unit_of(&seed);
        xyz[3 * i] = x, xyz[3 * i + 1] = y;
        xyz[3 * i + 2] = 300 * exp(-((x - 500) * (x - 500) + (y - 450) * (y - 450)) / 1.2e5) + 20 * unit_of(&seed);
    }
    for (int i = -1; i < 3 && !rc; i++) {
        fb_terrain t;
        fb_terrain_stats st;
        memset(&t, 0, sizeof t);
        rc = fb_terrain_build(&t, xyz, 1000, "bench", &st);
        if (!rc)
            rc = fb_terrain_refine(&t, &(fb_terrain_opts){.insert = 1000000, .hurst = 0.85, .sigma = -1, .seed = 1},
                                   "bench", &st);
        if (!rc && i >= 0) w[i] = st.refine_seconds;
        fb_terrain_free(&t);
    }
    if (!rc) {
        qsort(w, 3, sizeof w[0], cmp_double);
        report_inserts(o, "refine", "refine-1e3-by-1e6", 1e6, w[1]);
    }
    free(xy);
    free(xyz);
    return rc;
}

/* The FBM constraint model at the benchmark size with 100 discrete and 20 continuous constraints. */
static fb_result run_constrain(const bench_opts *o)
{
    int W = o->width, H = o->height;
    float *m = malloc((size_t)W * H * sizeof *m);
    fb_cpoint pts[100];
    fb_cregion regs[20];
    uint64_t seed = 7;
    for (int i = 0; i < 100; i++) pts[i] = (fb_cpoint){(int)(unit_of(&seed) * W), (int)(unit_of(&seed) * H)};
    for (int i = 0; i < 20; i++)
        regs[i] = (fb_cregion){(int)(unit_of(&seed) * W), (int)(unit_of(&seed) * H), i % 2 == 0, i % 2 ? 0.1 : 0.9};
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
                           .threads = o->threads};
    double w[3];
    fb_result rc = FB_OK;
    int threads = o->threads > 0 ? o->threads : fb_cpu_count();
    if (!o->json)
        printf("FBM constraint model %d x %d, 100 discrete and 20 continuous constraints; median of 3\n", W, H);
    for (int i = 0; i < 3 && !rc; i++) {
        fb_constrain_out out;
        double t0 = fb_now();
        rc = fb_constrain_run(&d, false, &out);
        w[i] = fb_now() - t0;
        free(out.D), free(out.T), free(out.H);
    }
    free(m);
    if (rc) return rc;
    qsort(w, 3, sizeof w[0], cmp_double);
    double rate = (double)W * H / w[1] * 1e-6;
    if (o->json)
        printf("{\"generator\": \"constrain\", \"backend\": \"native\", \"device\": \"native C\", \"mode\": "
               "\"generate\", \"unit\": \"Mpix/s\", \"rate\": %.3f, \"size\": [%d, %d], \"threads\": %d}\n",
               rate, W, H, threads);
    else
        printf("%-8s native  %-22s %8.2f Mpix/s  (%.3f s)  [native C, %d threads]\n", "constrain", "generate", rate,
               w[1], threads);
    fflush(stdout);
    return FB_OK;
}

fb_result fb_bench_main(int argc, char **argv)
{
    bench_opts o = {.width = 4096,
                    .height = 4096,
                    .vulkan = true,
                    .native = true,
                    .fbm = true,
                    .julia = true,
                    .ifs = true,
                    .terrain = true,
                    .constrain = true,
                    .points = 268435456};
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
        } else if (!strcmp(a, "--generator") && v) {
            o.fbm = !strcmp(v, "fbm");
            o.julia = !strcmp(v, "julia");
            o.ifs = !strcmp(v, "ifs");
            o.terrain = !strcmp(v, "terrain");
            o.constrain = !strcmp(v, "constrain");
            if (!o.fbm && !o.julia && !o.ifs && !o.terrain && !o.constrain)
                return fb_fail(FB_ERR_USAGE,
                               "--generator: expected fbm, julia, ifs, terrain or constrain, found \"%s\"", v);
            i++;
        } else if (!strcmp(a, "--points") && v) {
            char *end;
            o.points = strtod(v, &end);
            if (*end || !(o.points >= 1e6 && o.points <= 1e12))
                return fb_fail(FB_ERR_USAGE, "--points: expected a number in 1e6..1e12, found \"%s\"", v);
            o.points = (double)(uint64_t)o.points;
            i++;
        } else if (!strcmp(a, "--device") && v) {
            o.device = v;
            i++;
        } else if (!strcmp(a, "--threads") && v) {
            o.threads = atoi(v);
            if (o.threads < 1) return fb_fail(FB_ERR_USAGE, "--threads: expected a positive integer, found \"%s\"", v);
            i++;
        } else if (!strcmp(a, "--help")) {
            printf("usage: fractalbake bench [--json] [--size WxH] [--generator fbm|julia|ifs|terrain|constrain] "
                   "[--points N] "
                   "[--backend "
                   "vulkan|native] "
                   "[--device D] [--threads N]\n");
            return FB_OK;
        } else {
            return fb_fail(FB_ERR_USAGE, "%s: unknown or incomplete flag for `fractalbake bench`", a);
        }
    }
    char dir[] = "/tmp/fractalbake-bench-XXXXXX";
    if (!mkdtemp(dir)) return fb_fail(FB_ERR_IO, "cannot create a temporary folder for the benchmark");
    char out[64];
    snprintf(out, sizeof out, "%s/bench.exr", dir);
    fb_result rc = FB_OK;
    char json[512];
    fb_scene s;
    if (o.fbm) {
        const int octaves = 8;
        snprintf(json, sizeof json,
                 "{\"size\": [%d, %d], \"seed\": 1, \"layers\": [{\"type\": \"fbm\", \"noise\": \"gradient\", "
                 "\"octaves\": %d}]}",
                 o.width, o.height, octaves);
        if (!o.json)
            printf("fBm %d x %d, %d octaves of gradient noise; median of 3 runs after a warm-up\n", o.width, o.height,
                   octaves);
        bench_case bc = {"fbm", "Mpix/s", (double)o.width * o.height, 1e6, "moctaves_per_s", octaves};
        rc = fb_scene_parse(json, NULL, &s);
        if (!rc) rc = run_case(&o, &bc, &s, out);
        fb_scene_fini(&s);
    }
    if (!rc && o.julia) {
        snprintf(json, sizeof json,
                 "{\"size\": [%d, %d], \"seed\": 1, \"layers\": [{\"type\": \"julia\", \"c\": [-0.8, 0.156], "
                 "\"max-iter\": 256}]}",
                 o.width, o.height);
        bench_case bc = {"julia", "Giter/s", 0, 1e9, "mpix_per_s", 0};
        rc = fb_scene_parse(json, NULL, &s);
        if (!rc) {
            if (!o.json)
                printf("Julia %d x %d, c = -0.8+0.156i, max-iter 256 (rate: iterations executed); median of 3\n",
                       o.width, o.height);
            rc = run_case(&o, &bc, &s, out);
        }
        fb_scene_fini(&s);
        /* the same layer storing `iter` only: the escape loop alone, as the AVX2 reference runs it */
        snprintf(json, sizeof json,
                 "{\"size\": [%d, %d], \"seed\": 1, \"layers\": [{\"type\": \"julia\", \"c\": [-0.8, 0.156], "
                 "\"max-iter\": 256, \"channels\": [\"iter\"]}]}",
                 o.width, o.height);
        if (!rc) rc = fb_scene_parse(json, NULL, &s);
        if (!rc) rc = run_variant(&o, &bc, &s, "generate-iter-only");
        fb_scene_fini(&s);
    }
    if (!rc && o.ifs) {
        snprintf(json, sizeof json,
                 "{\"size\": [%d, %d], \"seed\": 1, \"layers\": [{\"type\": \"ifs\", \"preset\": \"fern\", "
                 "\"points\": %.0f}]}",
                 o.width, o.height, o.points);
        rc = fb_scene_parse(json, NULL, &s);
        if (!rc) {
            if (!o.json)
                printf("IFS chaos game: Barnsley's fern, %d x %d, %.0f points (rate: points per second); median of 3\n",
                       o.width, o.height, o.points);
            rc = run_ifs(&o, &s, out);
        }
        fb_scene_fini(&s);
    }
    if (!rc && o.terrain && o.native) rc = run_terrain(&o);
    if (!rc && o.constrain && o.native) rc = run_constrain(&o);
    unlink(out);
    rmdir(dir);
    return rc;
}
