/*
 * Benchmarks: the shared timing. See benchkit.h.
 */
#include "benchkit.h"
#include "gen.h"

#include "bake.h"
#include "output.h"
#include "pool.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void fb_bench_heading(const fb_bench *b, const char *fmt, ...)
{
    char text[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    if (b->heading) b->heading(b, text);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double fb_bench_median3(double t[3])
{
    qsort(t, 3, sizeof t[0], cmp_double);
    return t[1];
}

fb_result fb_bench_timed(fb_engine *e, const fb_scene *s, const char *out, double *wall, double *gpu)
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
    *wall = fb_bench_median3(w);
    *gpu = fb_bench_median3(g);
    return FB_OK;
}

fb_result fb_bench_prepared(fb_engine *e, const fb_scene *s, void (*read)(const fb_gen *g, double *sec, double *gpu),
                            double *sec, double *gpu)
{
    double w[3], g[3];
    fb_result rc = FB_OK;
    for (int i = -1; i < 3 && !rc; i++) {
        fb_gen gen;
        rc = fb_gen_init(&gen, s, &s->layers[0]);
        if (!rc) rc = gen.prepare(&gen, e, false);
        if (!rc && i >= 0) read(&gen, &w[i], &g[i]);
        fb_gen_fini(&gen);
    }
    if (rc) return rc;
    *sec = fb_bench_median3(w);
    *gpu = fb_bench_median3(g);
    return FB_OK;
}

fb_result fb_bench_open_vulkan(const fb_bench *b, fb_engine *e, bool *have)
{
    fb_result rc = fb_engine_open(
        &(fb_engine_desc){
            .backend = FB_BACKEND_VULKAN, .device = b->device, .threads = b->threads, .vk_options = b->vk_options},
        e);
    *have = rc == FB_OK;
    if (rc == FB_ERR_NODEVICE && b->native) {
        fb_log(FB_LOG_WARN, "no Vulkan device: benchmarking the native backend only");
        rc = FB_OK;
    }
    return rc;
}

void fb_bench_report(const fb_bench *b, const fb_bench_case *bc, const char *device, const char *backend,
                     const char *mode, int threads, double seconds, double gpu_seconds)
{
    fb_bench_row r = {.generator = bc->generator,
                      .backend = backend,
                      .device = device,
                      .mode = mode,
                      .unit = bc->unit,
                      .rate = bc->work / seconds / bc->unit_scale,
                      .gpu_rate = gpu_seconds > 0 ? bc->work / gpu_seconds / bc->unit_scale : 0,
                      .threads = threads,
                      .size = true};
    if (bc->extra) r.extra[r.nextra++] = (typeof(r.extra[0])){bc->extra, r.rate * bc->extra_per_work, 1};
    b->row(b, &r);
}

/* ---- encode-only: the EXR writer from memory ------------------------------------------------ */

#define ENCODE_HELD ((uint64_t)1 << 30) /* the most of a file held in memory; more rows repeat these */

typedef struct held_file {
    exrio_writer_desc desc;
    exrio_channel ch[FB_GEN_MAX_CHANNELS];
    char names[FB_GEN_MAX_CHANNELS][80], part_names[EXRIO_MAX_PARTS][80];
    const char *part_ptrs[EXRIO_MAX_PARTS];
    exrio_compression part_comp[EXRIO_MAX_PARTS];
    float *planes; /* nchannels planes of `rows` rows (uint channels as their bits) */
    int rows;
} held_file;

/* The file at path read into memory (its first rows, up to ENCODE_HELD bytes), with the writer's
 * description of the same channels, types, parts and compression. */
static fb_result hold_file(const char *path, held_file *h)
{
    exrio_reader *r = NULL;
    fb_result rc = exrio_open(path, &r);
    if (rc) return rc;
    int w = exrio_width(r), ht = exrio_height(r), nch = exrio_nchannels(r), np = exrio_nparts(r);
    if (nch > FB_GEN_MAX_CHANNELS || np > EXRIO_MAX_PARTS) {
        exrio_close(&r);
        return fb_fail(FB_ERR_INTERNAL, "bench: %s has more channels or parts than the encoder bench holds", path);
    }
    uint64_t row_bytes = (uint64_t)w * (uint64_t)nch * 4;
    h->rows = (int)(ENCODE_HELD / row_bytes < (uint64_t)ht ? ENCODE_HELD / row_bytes : (uint64_t)ht);
    if (h->rows < 1) h->rows = 1;
    h->planes = malloc((size_t)row_bytes * (size_t)h->rows);
    if (!h->planes) rc = fb_fail(FB_ERR_NOMEM, "out of memory for the encoder bench");
    void *planes[FB_GEN_MAX_CHANNELS];
    for (int c = 0; c < nch && !rc; c++) {
        snprintf(h->names[c], sizeof h->names[c], "%s", exrio_channel_name(r, c));
        h->ch[c] = (exrio_channel){h->names[c], exrio_channel_type(r, c), exrio_channel_part(r, c)};
        planes[c] = h->planes + (size_t)c * (size_t)w * (size_t)h->rows;
    }
    for (int p = 0; p < np && !rc; p++) {
        snprintf(h->part_names[p], sizeof h->part_names[p], "%s", exrio_part_name(r, p));
        h->part_ptrs[p] = h->part_names[p];
        int comp = exrio_compression_parse(exrio_part_compression(r, p));
        h->part_comp[p] = comp < 0 ? EXRIO_NONE : (exrio_compression)comp;
    }
    if (!rc) rc = exrio_read_rows(r, 0, h->rows, planes);
    if (!rc)
        h->desc = (exrio_writer_desc){.path = path,
                                      .what = "benchmark output",
                                      .width = w,
                                      .height = ht,
                                      .nparts = np,
                                      .part_names = np > 1 ? h->part_ptrs : NULL,
                                      .part_compression = np > 1 ? h->part_comp : NULL,
                                      .compression = h->part_comp[0],
                                      .channels = h->ch,
                                      .nchannels = nch,
                                      .envmap = exrio_envmap_of(r)};
    exrio_close(&r);
    return rc;
}

/* One write of the held file through the writer, strips of about a MiB a channel as a bake gives
 * them; the held rows repeat where the file had more. */
static fb_result write_held(const held_file *h, int threads)
{
    exrio_writer_desc d = h->desc;
    d.threads = threads;
    int w = d.width, strip = (1 << 20) / w > 1 ? (1 << 20) / w : 1;
    if (strip > h->rows) strip = h->rows;
    fb_outputs_begin();
    exrio_writer *wr = NULL;
    fb_result rc = exrio_writer_create(&d, &wr);
    for (int y0 = 0; y0 < d.height && !rc; y0 += strip) {
        int n = d.height - y0 < strip ? d.height - y0 : strip, at = y0 % h->rows;
        if (at + n > h->rows) at = 0;
        const void *planes[FB_GEN_MAX_CHANNELS];
        for (int c = 0; c < d.nchannels; c++)
            planes[c] = h->planes + ((size_t)c * (size_t)h->rows + (size_t)at) * (size_t)w;
        rc = exrio_writer_rows(wr, y0, n, planes);
    }
    if (!rc) rc = exrio_writer_finish(&wr);
    exrio_writer_abort(&wr);
    return fb_outputs_end(rc);
}

fb_result fb_bench_encode(const fb_bench *b, const fb_bench_case *bc, const char *compression, double bake_seconds)
{
    held_file *h = calloc(1, sizeof *h);
    if (!h) return fb_fail(FB_ERR_NOMEM, "out of memory");
    fb_result rc = hold_file(b->out, h);
    int threads = b->threads > 0 ? b->threads : fb_cpu_count();
    double t[3];
    for (int k = 0; k < 3 && !rc; k++) {
        double t0 = fb_now();
        rc = write_held(h, threads);
        t[k] = fb_now() - t0;
    }
    if (!rc) {
        double sec = fb_bench_median3(t);
        char mode[64];
        snprintf(mode, sizeof mode, "encode-only-%s", compression);
        fb_bench_row r = {.generator = bc->generator,
                          .backend = "native",
                          .device = "EXR writer from memory",
                          .mode = mode,
                          .unit = bc->unit,
                          .rate = bc->work / sec / bc->unit_scale,
                          .threads = threads,
                          .size = true,
                          .nextra = 1,
                          .extra = {{"bake_vs_encode", bake_seconds / sec, 3}}};
        snprintf(r.note, sizeof r.note, "(%d channels, %.3f s; the whole bake %.2fx that)", h->desc.nchannels, sec,
                 bake_seconds / sec);
        b->row(b, &r);
    }
    free(h->planes);
    free(h);
    return rc;
}

/* Whole bakes with the EXR written, for each compression: what a user's bake costs. */
static fb_result end_to_end(const fb_bench *b, const fb_bench_case *bc, fb_engine *e, fb_scene *s)
{
    static const exrio_compression comps[] = {EXRIO_NONE, EXRIO_ZIP, EXRIO_PIZ};
    static const char *names[] = {"end-to-end-none", "end-to-end-zip", "end-to-end-piz"};
    exrio_compression keep = s->compression;
    fb_result rc = FB_OK;
    for (int c = 0; c < 3 && !rc; c++) {
        double wall, gpu;
        s->compression = comps[c];
        rc = fb_bench_timed(e, s, b->out, &wall, &gpu);
        if (!rc) fb_bench_report(b, bc, e->device, fb_backend_name(e->kind), names[c], e->threads, wall, gpu);
        if (!rc) rc = fb_bench_encode(b, bc, exrio_compression_name(comps[c]), wall);
    }
    s->compression = keep;
    return rc;
}

fb_result fb_bench_auto_zip(const fb_bench *b, const fb_bench_case *bc, fb_scene *s)
{
    if (!b->vulkan || !b->native) return FB_OK; /* auto is the choice between the two */
    fb_engine e;
    fb_result rc = fb_engine_open(
        &(fb_engine_desc){
            .backend = FB_BACKEND_AUTO, .device = b->device, .threads = b->threads, .vk_options = b->vk_options},
        &e);
    if (rc) return rc;
    exrio_compression keep = s->compression;
    s->compression = EXRIO_ZIP;
    double wall, gpu;
    rc = fb_bench_timed(&e, s, b->out, &wall, &gpu);
    s->compression = keep;
    char device[300];
    snprintf(device, sizeof device, "%s%s", e.per_layer ? "per layer: native C or " : "", e.device);
    if (!rc) fb_bench_report(b, bc, device, "auto", "end-to-end-zip", e.threads, wall, -1);
    fb_engine_close(&e);
    return rc;
}

fb_result fb_bench_layer(const fb_bench *b, const fb_bench_case *bc, fb_scene *s, double tref)
{
    fb_result rc0 = fb_bench_auto_zip(b, bc, s); /* what a user's default bake gets */
    if (rc0) return rc0;
    fb_result rc = FB_OK;
    double wall, gpu;
    int threads = b->threads > 0 ? b->threads : fb_cpu_count();
    fb_engine e;
    bool have_vulkan = false;
    if (b->vulkan && !(rc = fb_bench_open_vulkan(b, &e, &have_vulkan)) && have_vulkan) {
        rc = fb_bench_timed(&e, s, NULL, &wall, &gpu);
        if (!rc) fb_bench_report(b, bc, e.device, "vulkan", "generate", 0, wall, gpu);
        if (!rc) rc = end_to_end(b, bc, &e, s);
        fb_engine_close(&e);
    }
    if (!rc && b->native) {
        rc = fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = b->threads}, &e);
        if (!rc) {
            rc = fb_bench_timed(&e, s, NULL, &wall, &gpu);
            if (!rc) fb_bench_report(b, bc, e.device, "native", "generate", e.threads, wall, -1);
            if (!have_vulkan && !rc) rc = end_to_end(b, bc, &e, s);
            fb_engine_close(&e);
        }
        /* The references: the same algorithm hand-vectorised with AVX2 (bit-exact with the kernel,
         * tests/test_avx2.c) on every core, and the kernel in a plain scalar loop on one core. */
        if (!rc && tref > 0)
            fb_bench_report(b, bc, "hand-vectorised AVX2 C", "native", "avx2-reference", threads, tref, -1);
        if (!rc) rc = fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = 1, .scalar = true}, &e);
        if (!rc) {
            rc = fb_bench_timed(&e, s, NULL, &wall, &gpu);
            if (!rc) fb_bench_report(b, bc, e.device, "native", "scalar-1-thread", 1, wall, -1);
            fb_engine_close(&e);
        }
    }
    return rc;
}

fb_result fb_bench_variant(const fb_bench *b, const fb_bench_case *bc, fb_scene *s, const char *mode)
{
    fb_result rc = FB_OK;
    double wall, gpu;
    fb_engine e;
    bool have_vulkan = false;
    if (b->vulkan && !(rc = fb_bench_open_vulkan(b, &e, &have_vulkan)) && have_vulkan) {
        rc = fb_bench_timed(&e, s, NULL, &wall, &gpu);
        if (!rc) fb_bench_report(b, bc, e.device, "vulkan", mode, 0, wall, gpu);
        fb_engine_close(&e);
    }
    if (!rc && b->native) {
        rc = fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = b->threads}, &e);
        if (!rc) {
            rc = fb_bench_timed(&e, s, NULL, &wall, &gpu);
            if (!rc) fb_bench_report(b, bc, e.device, "native", mode, e.threads, wall, -1);
            fb_engine_close(&e);
        }
    }
    return rc;
}

typedef struct rows_job {
    void (*rows)(void *ctx, int y0, int n, int task);
    void *ctx;
    int rows_per_task, height;
} rows_job;

static void rows_task(void *ctx, int t)
{
    rows_job *j = ctx;
    int y0 = t * j->rows_per_task, n = y0 + j->rows_per_task <= j->height ? j->rows_per_task : j->height - y0;
    j->rows(j->ctx, y0, n, t);
}

double fb_bench_rows(int threads, int height, void (*rows)(void *ctx, int y0, int n, int task), void *ctx, int *ntasks)
{
    fb_pool *pool = NULL;
    if (fb_pool_create(threads, &pool)) return -1;
    rows_job j = {rows, ctx, (height + 4095) / 4096 > 16 ? (height + 4095) / 4096 : 16, height};
    int tasks = (height + j.rows_per_task - 1) / j.rows_per_task;
    double t[4];
    for (int k = 0; k < 4; k++) {
        double t0 = fb_now();
        fb_pool_run(pool, tasks, rows_task, &j);
        t[k] = fb_now() - t0;
    }
    fb_pool_destroy(&pool);
    if (ntasks) *ntasks = tasks;
    return fb_bench_median3(t + 1);
}

uint64_t fb_bench_splitmix64(uint64_t *s)
{
    uint64_t z = (*s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

double fb_bench_unit(uint64_t *s)
{
    return (double)(fb_bench_splitmix64(s) >> 11) * 0x1.0p-53;
}
