/*
 * fractalbake bench: runs the benchmarks of every generator that has some (struct
 * fb_gen_class.bench, in the generators' folders) and prints their rows, for people or as JSON lines
 * (bench/run.sh appends those to bench/results.jsonl).
 */
#include "bench.h"
#include "env.h"

#include "benchkit.h"
#include "gen.h"
#include "progress.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static fb_progress g_prog; /* which generator of how many, on stderr */

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
        printf("}\n");
    } else {
        printf("%-9s %-7s %-22s %9.3f %s", r->generator, r->backend, r->mode, r->rate, r->unit);
        if (r->note[0]) printf("  %s", r->note);
        if (r->gpu_rate > 0) printf("  (timestamps: %.3f %s)", r->gpu_rate, r->unit);
        if (r->threads > 0 && strcmp(r->backend, "vulkan")) /* a GPU's rows: its EXR threads are not the point */
            printf("  [%s, %d thread%s]\n", r->device, r->threads, r->threads > 1 ? "s" : "");
        else
            printf("  [%s]\n", r->device);
    }
    fflush(stdout);
}

fb_result fb_bench_main(int argc, char **argv, const fb_env *env)
{
    fb_bench b = {.vk_options = env->vk,
                  .width = 4096,
                  .height = 4096,
                  .vulkan = true,
                  .native = true,
                  .points = 268435456,
                  .heading = print_heading,
                  .row = print_row};
    const fb_gen_class *only = NULL;
    bool quiet = false;
    char names[256] = "", words[256] = ""; /* "fbm|julia|ifs", "fbm, julia or ifs" */
    int nb = 0, k = 0;
    for (int i = 0; fb_gen_list[i]; i++) nb += fb_gen_list[i]->bench != NULL;
    for (int i = 0; fb_gen_list[i]; i++) {
        if (!fb_gen_list[i]->bench) continue;
        snprintf(names + strlen(names), sizeof names - strlen(names), "%s%s", k ? "|" : "", fb_gen_list[i]->name);
        snprintf(words + strlen(words), sizeof words - strlen(words), "%s%s",
                 !k            ? ""
                 : k == nb - 1 ? " or "
                               : ", ",
                 fb_gen_list[i]->name);
        k++;
    }
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--json")) {
            b.json = true;
        } else if (!strcmp(a, "--quiet")) {
            quiet = true;
        } else if (!strcmp(a, "--size") && v) {
            if (sscanf(v, "%dx%d", &b.width, &b.height) != 2 || b.width < 64 || b.height < 64 || b.width > 16384 ||
                b.height > 16384)
                return fb_fail(FB_ERR_USAGE, "--size: expected WxH with sides in 64..16384, found \"%s\"", v);
            i++;
        } else if (!strcmp(a, "--backend") && v) {
            b.vulkan = !strcmp(v, "vulkan");
            b.native = !strcmp(v, "native");
            if (!b.vulkan && !b.native)
                return fb_fail(FB_ERR_USAGE, "--backend: expected vulkan or native, found \"%s\"", v);
            i++;
        } else if (!strcmp(a, "--generator") && v) {
            only = fb_gen_find(v);
            if (!only || !only->bench) return fb_fail(FB_ERR_USAGE, "--generator: expected %s, found \"%s\"", words, v);
            i++;
        } else if (!strcmp(a, "--points") && v) {
            char *end;
            b.points = strtod(v, &end);
            if (*end || !(b.points >= 1e6 && b.points <= 1e12))
                return fb_fail(FB_ERR_USAGE, "--points: expected a number in 1e6..1e12, found \"%s\"", v);
            b.points = (double)(uint64_t)b.points;
            i++;
        } else if (!strcmp(a, "--device") && v) {
            b.device = v;
            i++;
        } else if (!strcmp(a, "--threads") && v) {
            b.threads = atoi(v);
            if (b.threads < 1) return fb_fail(FB_ERR_USAGE, "--threads: expected a positive integer, found \"%s\"", v);
            i++;
        } else if (!strcmp(a, "--help")) {
            printf("usage: fractalbake bench [--json] [--quiet] [--size WxH] [--generator %s] [--points N] "
                   "[--backend vulkan|native] [--device D] [--threads N]\n"
                   "Throughput of every generator on each backend, a line per measurement (--json: a JSON object\n"
                   "per line); progress on stderr unless --quiet.\n",
                   names);
            return FB_OK;
        } else {
            return fb_fail(FB_ERR_USAGE, "%s: unknown or incomplete flag for `fractalbake bench`", a);
        }
    }
    char dir[] = "/tmp/fractalbake-bench-XXXXXX";
    if (!mkdtemp(dir)) return fb_fail(FB_ERR_IO, "cannot create a temporary folder for the benchmark");
    char out[64];
    snprintf(out, sizeof out, "%s/bench.exr", dir);
    b.out = out;
    fb_result rc = FB_OK;
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
    return rc;
}
