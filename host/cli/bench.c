/*
 * fractalbake bench: runs the benchmarks of every generator that has some (struct
 * fb_gen_class.bench, in the generators' folders) and prints their rows, for people or as JSON lines
 * (bench/run.sh appends those to bench/results.jsonl).
 */
#include "textin.h"
#include "command.h"

#include "benchkit.h"
#include "ceilings.h"
#include "gen.h"
#include "progress.h"

#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static fb_progress g_prog; /* which generator of how many, on stderr */

/* What every row is read against: the machine's ceilings, lavapipe's settings, and an earlier run. */
typedef struct bench_ctx {
    fb_ceilings ceil;
    const fb_env *env;
    json_t *before;          /* --compare: the earlier run's rows, or NULL */
    double before_gflops[2]; /* its FMA ceilings: vulkan, native (0: none) */
    const char *before_path;
} bench_ctx;

/* The FMA ceiling a row's rate is read against: the Vulkan device's for vulkan rows, else the
 * native loop's. */
static double ceiling_of(const bench_ctx *c, const char *backend)
{
    return !strcmp(backend, "vulkan") ? c->ceil.vk_gflops : c->ceil.native_gflops;
}

/* The earlier run's row of the same generator, backend, mode and unit, or NULL. */
static const json_t *before_row(const bench_ctx *c, const fb_bench_row *r)
{
    size_t i;
    const json_t *o;
    json_array_foreach(c->before, i, o)
    {
        const char *g = json_string_value(json_object_get(o, "generator")),
                   *be = json_string_value(json_object_get(o, "backend")),
                   *m = json_string_value(json_object_get(o, "mode")),
                   *u = json_string_value(json_object_get(o, "unit"));
        if (g && be && m && u && !strcmp(g, r->generator) && !strcmp(be, r->backend) && !strcmp(m, r->mode) &&
            !strcmp(u, r->unit))
            return o;
    }
    return NULL;
}

/* A result line on a terminal where the progress bar is drawn: the bar's line cleared first (the
 * progress thread draws it again). */
static void clear_bar(void)
{
    if (g_prog.drawn && g_prog.tty && isatty(STDOUT_FILENO)) {
        fprintf(stderr, "\r%*s\r", 110, "");
        fflush(stderr);
    }
}

static void print_heading(const fb_bench *b, const char *text)
{
    clear_bar();
    if (!b->json) printf("%s\n", text);
}

static void print_row(const fb_bench *b, const fb_bench_row *r)
{
    const bench_ctx *c = b->user;
    bool ceiling = !strcmp(r->generator, "ceiling");
    double peak = ceiling_of(c, r->backend), per_peak = peak > 0 && !ceiling ? r->rate / peak : 0;
    const json_t *old = c->before ? before_row(c, r) : NULL;
    double old_rate = old ? json_number_value(json_object_get(old, "rate")) : 0;
    double old_peak = old ? c->before_gflops[strcmp(r->backend, "vulkan") ? 1 : 0] : 0;
    double vs = old_rate > 0 ? r->rate / old_rate : 0;
    double vs_peak = vs > 0 && old_peak > 0 && peak > 0 ? vs * old_peak / peak : 0;
    clear_bar();
    if (b->json) {
        printf("{\"generator\": \"%s\", \"backend\": \"%s\", \"device\": \"%s\", \"mode\": \"%s\", \"unit\": \"%s\", "
               "\"rate\": %.3f",
               r->generator, r->backend, r->device, r->mode, r->unit, r->rate);
        if (r->size) printf(", \"size\": [%d, %d]", b->width, b->height);
        for (int i = 0; i < r->nextra; i++)
            printf(", \"%s\": %.*f", r->extra[i].name, r->extra[i].decimals, r->extra[i].value);
        printf(", \"threads\": %d", r->threads);
        if (r->gpu_rate > 0) printf(", \"gpu_rate\": %.3f", r->gpu_rate);
        if (per_peak > 0) printf(", \"per_peak_gflops\": %.6g", per_peak);
        if (vs > 0) printf(", \"vs_before\": %.4f", vs);
        if (vs_peak > 0) printf(", \"vs_before_per_peak\": %.4f", vs_peak);
        printf(", \"LP_NUM_THREADS\": \"%s\", \"LP_NATIVE_VECTOR_WIDTH\": \"%s\"}\n", c->env->lp_num_threads,
               c->env->lp_vector_width);
    } else {
        printf("%-9s %-7s %-22s %9.3f %s", r->generator, r->backend, r->mode, r->rate, r->unit);
        if (r->note[0]) printf("  %s", r->note);
        if (r->gpu_rate > 0) printf("  (timestamps: %.3f %s)", r->gpu_rate, r->unit);
        if (per_peak > 0) printf("  {%.3g per peak GFLOP/s}", per_peak);
        if (vs > 0) printf("  <x%.3f of before%s>", vs, vs_peak > 0 ? "" : ", no ceiling then");
        if (vs_peak > 0) printf("  <x%.3f per peak>", vs_peak);
        if (r->threads > 0 && strcmp(r->backend, "vulkan")) /* a GPU's rows: its EXR threads are not the point */
            printf("  [%s, %d thread%s]\n", r->device, r->threads, r->threads > 1 ? "s" : "");
        else
            printf("  [%s]\n", r->device);
    }
    fflush(stdout);
}

typedef struct bench_opts {
    fb_arg_list files;
    bool json, quiet, help;
    int size[2];
    int backend; /* 0: both, 1: vulkan, 2: native */
    const fb_gen_class *only;
    double points;
    const char *compare, *device;
    int threads;
} bench_opts;

static void init(void *opts)
{
    bench_opts *o = opts;
    o->size[0] = o->size[1] = 4096;
    o->points = 268435456;
}

/* "fbm|julia|ifs" (sep "|") or "fbm, julia or ifs" (sep NULL): the generators that have benchmarks. */
static void bench_names(const char *sep, char *out, size_t size)
{
    int nb = 0, k = 0;
    out[0] = 0;
    for (int i = 0; fb_gen_list[i]; i++) nb += fb_gen_list[i]->bench != NULL;
    for (int i = 0; fb_gen_list[i]; i++) {
        if (!fb_gen_list[i]->bench) continue;
        snprintf(out + strlen(out), size - strlen(out), "%s%s",
                 !k            ? ""
                 : sep         ? sep
                 : k == nb - 1 ? " or "
                               : ", ",
                 fb_gen_list[i]->name);
        k++;
    }
}

static fb_result arg_size(const char *flag, const char *v, void *field)
{
    int *wh = field, used = 0;
    if (sscanf(v, "%dx%d%n", &wh[0], &wh[1], &used) != 2 || v[used] || wh[0] < 64 || wh[1] < 64 || wh[0] > 16384 ||
        wh[1] > 16384)
        return fb_fail(FB_ERR_USAGE, "%s: expected WxH with sides in 64..16384, found \"%s\"", flag, v);
    return FB_OK;
}

static fb_result arg_backend(const char *flag, const char *v, void *field)
{
    if (strcmp(v, "vulkan") && strcmp(v, "native"))
        return fb_fail(FB_ERR_USAGE, "%s: expected vulkan or native, found \"%s\"", flag, v);
    *(int *)field = !strcmp(v, "vulkan") ? 1 : 2;
    return FB_OK;
}

static fb_result arg_generator(const char *flag, const char *v, void *field)
{
    const fb_gen_class *c = fb_gen_find(v);
    if (!c || !c->bench) {
        char words[256];
        bench_names(NULL, words, sizeof words);
        return fb_fail(FB_ERR_USAGE, "%s: expected %s, found \"%s\"", flag, words, v);
    }
    *(const fb_gen_class **)field = c;
    return FB_OK;
}

static fb_result arg_points(const char *flag, const char *v, void *field)
{
    char *end;
    double p = strtod(v, &end);
    if (*end || !(p >= 1e6 && p <= 1e12))
        return fb_fail(FB_ERR_USAGE, "%s: expected a number in 1e6..1e12, found \"%s\"", flag, v);
    *(double *)field = (double)(uint64_t)p;
    return FB_OK;
}

/* --compare EARLIER.json: the rows of an earlier `bench --json` run, and its FMA ceilings. */
static fb_result read_before(const char *v, bench_ctx *ctx)
{
    ctx->before = json_array();
    ctx->before_path = v;
    char *text = NULL;
    size_t len = 0;
    fb_result rc = fb_input_slurp(v, "bench --json", (size_t)64 << 20, &text, &len);
    if (rc) return rc;
    int lineno = 0;
    for (char *line = text, *next; line < text + len; line = next) {
        next = line + strcspn(line, "\n");
        if (*next) *next++ = 0;
        lineno++;
        if (!line[strspn(line, " \t\r")]) continue;
        json_t *o = json_loads(line, 0, NULL);
        if (!json_is_object(o) || !json_is_number(json_object_get(o, "rate"))) {
            json_decref(o);
            free(text);
            return fb_fail(FB_ERR_INPUT, "%s:%d: not a line of `fractalbake bench --json`", v, lineno);
        }
        const char *g = json_string_value(json_object_get(o, "generator")),
                   *m = json_string_value(json_object_get(o, "mode")),
                   *be = json_string_value(json_object_get(o, "backend"));
        if (g && m && be && !strcmp(g, "ceiling") && !strcmp(m, "fma"))
            ctx->before_gflops[strcmp(be, "vulkan") ? 1 : 0] = json_number_value(json_object_get(o, "rate"));
        json_array_append_new(ctx->before, o);
    }
    free(text);
    if (!json_array_size(ctx->before)) return fb_fail(FB_ERR_INPUT, "--compare: %s holds no bench rows", v);
    return FB_OK;
}

static void help(const fb_cli *cli)
{
    (void)cli;
    char names[256];
    bench_names("|", names, sizeof names);
    printf("usage: fractalbake bench [--json] [--quiet] [--size WxH] [--generator %s] [--points N] "
           "[--backend vulkan|native] [--device D] [--threads N] [--compare EARLIER.json]\n"
           "Throughput of every generator on each backend, a line per measurement (--json: a JSON object\n"
           "per line); progress on stderr unless --quiet. First the machine's ceilings on each backend:\n"
           "an FMA-bound kernel (GFLOP/s) and a buffer copy (GB/s, bytes read plus written), with the CPU,\n"
           "device and driver named; on the device, by its timestamps: the copy shader (shader-copy; by the\n"
           "host clock with vkc's staging readback: shader-copy-readback), its own memory (device-copy) and\n"
           "the host transfer each way (upload, download: bytes copied). After each whole bake, an\n"
           "encode-only row: the same channels and compression from memory, on all cores. On the device,\n"
           "each layer's shader (kernel rows) beside a minimal shader of its formula (peer rows,\n"
           "bench/peers/) in the same run: vs_peer, and same_bits where their outputs agree to the bit.\n"
           "Every rate is then also given per peak GFLOP/s of its backend, and every line records\n"
           "LP_NUM_THREADS and LP_NATIVE_VECTOR_WIDTH (lavapipe's speed and subgroup size).\n"
           "--compare EARLIER.json: each row's rate against the same row of an earlier --json run, as is\n"
           "and per peak (each run's rate divided by its own ceiling: a change of machine cancels out).\n",
           names);
}

static fb_result bench(const fb_env *env, const bench_opts *o);

static fb_result run(const fb_cli *cli, void *opts)
{
    return bench(cli->env, opts);
}

#define B(f) offsetof(bench_opts, f)
static const fb_arg flags[] = {
    {FB_ARG_DOCUMENT, "--json", NULL, B(json)},
    {FB_ARG_BOOL, "--quiet", NULL, B(quiet)},
    {FB_ARG_VALUE, "--size", NULL, B(size), .parse = arg_size},
    {FB_ARG_VALUE, "--backend", NULL, B(backend), .parse = arg_backend},
    {FB_ARG_VALUE, "--generator", NULL, B(only), .parse = arg_generator},
    {FB_ARG_VALUE, "--points", NULL, B(points), .parse = arg_points},
    {FB_ARG_STRING, "--compare", NULL, B(compare)},
    {FB_ARG_STRING, "--device", NULL, B(device)},
    {FB_ARG_INT, "--threads", NULL, B(threads), 1, 1024},
    {FB_ARG_BOOL, "--help", "-h", B(help)},
    {FB_ARG_END},
};
static const fb_arg *const tables[] = {flags, NULL};
static const fb_argspec spec = {.flags = tables, .files_off = B(files)};

/* bench bakes to a scratch file again and again: each of its bakes is a transaction of its own */
const fb_command fb_cmd_bench = {
    .name = "bench",
    .usage = "  bench [--json] [--size WxH]        throughput of every generator on each backend\n",
    .opts_size = sizeof(bench_opts),
    .init = init,
    .args = &spec,
    .help = help,
    .help_off = B(help),
    .run = run,
    .own_outputs = true};
#undef B

static fb_result bench(const fb_env *env, const bench_opts *o)
{
    fb_bench b = {.vk_options = env->vk,
                  .width = o->size[0],
                  .height = o->size[1],
                  .vulkan = o->backend != 2,
                  .native = o->backend != 1,
                  .points = o->points,
                  .device = o->device,
                  .threads = o->threads,
                  .json = o->json,
                  .heading = print_heading,
                  .row = print_row};
    bench_ctx ctx = {.env = env};
    b.user = &ctx;
    if (b.vulkan) fb_env_lavapipe_threads(o->threads);
    const fb_gen_class *only = o->only;
    bool quiet = o->quiet;
    int nb = 0;
    for (int i = 0; fb_gen_list[i]; i++) nb += fb_gen_list[i]->bench != NULL;
    if (o->device && o->backend == 2)
        return fb_fail(FB_ERR_USAGE, "--device %s: only with a Vulkan backend (--backend native opens no device)",
                       o->device);
    if (o->compare) {
        fb_result rc = read_before(o->compare, &ctx);
        if (rc) {
            json_decref(ctx.before);
            return rc;
        }
    }
    char dir[] = "/tmp/fractalbake-bench-XXXXXX";
    if (!mkdtemp(dir)) return fb_fail(FB_ERR_IO, "cannot create a temporary folder for the benchmark");
    char out[64];
    snprintf(out, sizeof out, "%s/bench.exr", dir);
    b.out = out;
    fb_result rc = FB_OK;
    /* the ceilings, once, before anything else */
    {
        fb_engine ne, ve;
        bool have_vk = false;
        rc = fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = b.threads}, &ne);
        if (!rc && b.vulkan) rc = fb_bench_open_vulkan(&b, &ve, &have_vk);
        if (!rc) rc = fb_ceilings_measure(have_vk ? &ve : NULL, b.native ? &ne : NULL, &ctx.ceil);
        if (have_vk) fb_engine_close(&ve);
        fb_engine_close(&ne);
        if (!rc) {
            fb_bench_heading(
                &b, "machine: %s; Vulkan: %s, %s; LP_NUM_THREADS=%s, LP_NATIVE_VECTOR_WIDTH=%s",
                ctx.ceil.cpu[0] ? ctx.ceil.cpu : "(CPU not named)", ctx.ceil.device[0] ? ctx.ceil.device : "no device",
                ctx.ceil.driver[0] ? ctx.ceil.driver : "-", env->lp_num_threads[0] ? env->lp_num_threads : "(unset)",
                env->lp_vector_width[0] ? env->lp_vector_width : "(unset)");
            struct {
                const char *backend, *mode, *unit;
                double rate;
                const char *device;
                int threads;
            } rows[] = {
                {"vulkan", "fma", "GFLOP/s", ctx.ceil.vk_gflops, ctx.ceil.device, 0},
                {"vulkan", "shader-copy", "GB/s", ctx.ceil.vk_gbps, ctx.ceil.device, 0},
                {"vulkan", "shader-copy-readback", "GB/s", ctx.ceil.vk_gbps_wall, ctx.ceil.device, 0},
                {"vulkan", "device-copy", "GB/s", ctx.ceil.vk_copy_gbps, ctx.ceil.device, 0},
                {"vulkan", "upload", "GB/s", ctx.ceil.vk_upload_gbps, ctx.ceil.device, 0},
                {"vulkan", "download", "GB/s", ctx.ceil.vk_download_gbps, ctx.ceil.device, 0},
                {"native", "fma", "GFLOP/s", ctx.ceil.native_gflops, "native C", ctx.ceil.threads},
                {"native", "copy", "GB/s", ctx.ceil.native_gbps, "native C", ctx.ceil.threads},
            };
            for (size_t k = 0; k < sizeof rows / sizeof rows[0]; k++)
                if (rows[k].rate > 0)
                    print_row(&b, &(fb_bench_row){.generator = "ceiling",
                                                  .backend = rows[k].backend,
                                                  .device = rows[k].device,
                                                  .mode = rows[k].mode,
                                                  .unit = rows[k].unit,
                                                  .rate = rows[k].rate,
                                                  .threads = rows[k].threads});
        }
    }
    int total = only ? 1 : nb, done = 0;
    fb_progress_init_steps(&g_prog, !quiet, "bench");
    for (int i = 0; fb_gen_list[i] && !rc; i++)
        if (fb_gen_list[i]->bench && (!only || only == fb_gen_list[i])) {
            fb_progress_update(&g_prog, (uint64_t)done, (uint64_t)total);
            fb_progress_detail(&g_prog, fb_gen_list[i]->name);
            rc = fb_gen_list[i]->bench(&b);
            done++;
        }
    fb_progress_finish(&g_prog);
    unlink(out);
    rmdir(dir);
    json_decref(ctx.before);
    return rc;
}
