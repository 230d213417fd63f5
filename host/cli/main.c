/*
 * fractalbake: the command line. The only place that decides what the user sees and how the
 * process exits (0 ok, 1 comparison beyond threshold, 2 bad usage or input, 3 runtime failure).
 */
#include "bake.h"
#include "bench.h"
#include "cliout.h"
#include "tonemap.h"
#include "compare.h"
#include "env.h"
#include "info.h"
#include "exrio.h"
#include "generators.h"
#include "heightmap.h"
#include "merge.h"
#include "output.h"
#include "plan.h"
#include "progress.h"
#include "flags.h"
#include "scene.h"
#include "textin.h"
#include "vkc.h"
#include "jsonout.h"

#include <jansson.h>

#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* The first error is the one line the user sees; warnings are shown as they come. */
static char g_first_error[2048];
static bool g_quiet_warnings;

/* --json: the command's summary, printed on standard output by main() once its outputs are in
 * place, with what was written ("outputs": path, what, bytes) added. */
static json_t *g_summary;
/* The environment, read once when the program starts (env.h), for every engine a command opens. */
static fb_env g_env;

static json_t *summary_start(const char *command)
{
    json_decref(g_summary);
    g_summary = json_object();
    json_object_set_new(g_summary, "command", json_string(command));
    return g_summary;
}

static void sink(int level, const char *msg, void *user)
{
    (void)user;
    if (level == FB_LOG_ERROR) {
        if (!g_first_error[0]) snprintf(g_first_error, sizeof g_first_error, "%s", msg);
    } else if (level == FB_LOG_WARN && !g_quiet_warnings) {
        fprintf(stderr, "fractalbake: warning: %s\n", msg);
    }
}

/* Progress lines and bars (progress.h) go to stderr. */
static void progress_sink(const char *text, void *user)
{
    (void)user;
    fputs(text, stderr);
    fflush(stderr);
}

static int finish(fb_result rc)
{
    if (rc) fprintf(stderr, "fractalbake: %s\n", g_first_error[0] ? g_first_error : fb_result_string(rc));
    return fb_result_exit_code(rc);
}

_Static_assert(EXRIO_ZIP_LEVEL_MAX == 12, "merge's --zip-level message says 1..12");

static int usage_error(const char *fmt, const char *arg)
{
    fprintf(stderr, "fractalbake: ");
    fprintf(stderr, fmt, arg);
    fprintf(stderr, "\n");
    return 2;
}

static void print_line(const char *line, void *user)
{
    fprintf(user ? (FILE *)user : stdout, "%s\n", line);
}

/* compare --quiet: the verdict line alone */
static void print_result_only(const char *line, void *user)
{
    if (!strncmp(line, "result: ", 8)) print_line(line, user);
}

static const char *const k_usage =
    "usage: fractalbake COMMAND [options]\n"
    "\n"
    "commands:\n"
    "  render [SCENE.json] [-o OUT.exr]   bake every layer of a scene (no scene: the embedded default);\n"
    "         [--from OLD.exr] [--set K=V]  or the scene stored in a file; override keys\n"
    "%s" /* one line per generator */
    "  tonemap IN.exr -o OUT.exr [tone]   re-run a chaos game's tone mapping (no new game)\n"
    "  compare A.exr B.exr [thresholds]   exit 0 within thresholds, 1 beyond, 2 on error\n"
    "  plan [SCENE.json] --tasks N        split a bake into N tasks of about equal cost (render --task)\n"
    "  merge PARTS... -o OUT.exr          join task files (--task), region files (--region) or points\n"
    "                                     parts (--points-part) into the whole bake\n"
    "  info FILE.exr                      layers, channels, types, attributes and the stored scene\n"
    "  generators [--json]                the generators, their keys and how a plan shares them\n"
    "  scene default|SCENE.json           a scene with every default filled in (scene default > s.json)\n"
    "  devices                            the Vulkan devices found, and which one is chosen\n"
    "  bench [--json] [--size WxH]        throughput of every generator on each backend\n"
    "\n"
    "common options:\n"
    "  -o, --output FILE     output EXR (written to a temporary file, renamed when complete)\n"
    "  --preview FILE.png    also write a PNG preview (grey, colour or hillshade, as the layer suits)\n"
    "  --preview-layer L     the layer it shows; `all`: a contact sheet, a labelled tile per layer; or\n"
    "                        `over`: every layer composited back to front by its coverage A (the\n"
    "                        default for scenes of several layers)\n"
    "  --backend B           auto | vulkan | native (default auto: a GPU when there is one; on lavapipe,\n"
    "                        each layer where it is faster (see `fractalbake devices`); else native)\n"
    "  --device D            Vulkan device index or name substring (see `fractalbake devices`)\n"
    "  --threads N           native threads, EXR compression threads and lavapipe's own compute\n"
    "                        threads (LP_NUM_THREADS) (default: all cores)\n"
    "  --strip-rows N        rows computed per strip (the result does not depend on it)\n"
    "  --region X,Y,W,H      bake only these pixels (the same as in the full bake) into a region file;\n"
    "                        `fractalbake merge` joins region files into the whole image\n"
    "  --points-part K/N     bake the K-th of N shares of every chaos game's points (the other\n"
    "                        layers whole); `fractalbake merge` adds the N parts' hits exactly\n"
    "  --task K/N            bake task K (from 0, like SLURM_ARRAY_TASK_ID) of the N of `fractalbake plan`:\n"
    "                        only its share (a band, points parts or whole layers); merge joins the N\n"
    "  --task-startup S      the start-up of a task the plan assumes (default 0.07 s; 0: use every task\n"
    "                        that shortens the longest); give the same to plan, every task and merge\n"
    "  --zip-level N         deflate level of ZIP compression, 1 (fastest) to 12 (smallest) (default 1)\n"
    "  --dry-run             print the predicted peak memory per layer, bake nothing, write nothing\n"
    "  --max-memory SIZE     stop before allocating when the predicted peak is larger (8G, 512M, 50%;\n"
    "                        default 80% of this machine's memory)\n"
    "  --validation          enable VK_LAYER_KHRONOS_validation (also FB_VK_VALIDATION=1)\n"
    "  -q, --quiet           no progress bar, no warnings, no summary line\n"
    "  --json                one JSON object on stdout when done: what was written (paths, sizes),\n"
    "                        the time, each layer's backend and summary (terrain: points, stages)\n"
    "  --help, --version\n"
    "\n"
    "exit codes: 0 success, 1 comparison beyond threshold, 2 bad usage or input, 3 runtime failure\n";

/* The top-level help, with a line for each generator that is a command. */
static void print_usage(FILE *f)
{
    char gens[2048] = "";
    for (int i = 0; fb_gen_list[i]; i++)
        if (fb_gen_list[i]->synopsis)
            snprintf(gens + strlen(gens), sizeof gens - strlen(gens), "  %-34s %s\n", fb_gen_list[i]->synopsis,
                     fb_gen_list[i]->summary);
    const char *at = strstr(k_usage, "%s");
    fwrite(k_usage, 1, (size_t)(at - k_usage), f);
    fputs(gens, f);
    fputs(at + 2, f);
}

/* Options every baking command shares. */
typedef struct common_opts {
    const char *out, *preview, *preview_layer, *device;
    fb_backend backend;
    int threads, strip_rows, zip_level;
    int region[4];       /* x, y, w, h; w == 0: none */
    int points_part[2];  /* K, N; N == 0: none */
    int task[2];         /* render --task K/N (K from 0); N == 0: none */
    double task_startup; /* --task-startup S, when task_startup_set */
    bool task_startup_set;
    bool quiet, validation, help, json, dry_run;
    uint64_t max_memory; /* 0: the default (80% of physical memory) */
} common_opts;

/* An integer flag's value: decimal, or exponent notation with a whole value (--tasks 1e1 is 10), as
 * the generators' integer flags take it. */
static bool parse_int_arg(const char *s, long lo, long hi, int *out)
{
    long long v;
    if (fb_text_int(s, lo, hi, NULL, &v)) {
        *out = (int)v;
        return true;
    }
    char *end;
    double d = strtod(s, &end);
    if (!*s || *end || !(d >= (double)lo && d <= (double)hi) || d != floor(d) || !strpbrk(s, "eE")) return false;
    *out = (int)d;
    return true;
}

/* --task-startup: seconds, finite, 0 to an hour. */
static bool parse_seconds(const char *s, double *out)
{
    char *end;
    double v = strtod(s, &end);
    if (!*s || *end || !(v >= 0 && v <= 3600)) return false;
    *out = v;
    return true;
}

static bool parse_region(const char *s, int r[4])
{
    long v[4];
    int used = 0;
    if (sscanf(s, "%ld,%ld,%ld,%ld%n", &v[0], &v[1], &v[2], &v[3], &used) != 4 || s[used]) return false;
    for (int i = 0; i < 4; i++)
        if (v[i] < (i < 2 ? 0 : 1) || v[i] > FB_MAX_DIM) return false;
    for (int i = 0; i < 4; i++) r[i] = (int)v[i];
    return true;
}

static bool parse_points_part(const char *s, int pp[2])
{
    const char *end;
    long long k, n;
    if (!fb_text_int(s, 1, 4096, &end, &k) || *end != '/' || !fb_text_int(end + 1, 1, 4096, NULL, &n) || k > n)
        return false;
    pp[0] = (int)k, pp[1] = (int)n;
    return true;
}

/* The common options (without dashes), for "did you mean" hints. */
static const char *const k_common_flags[] = {"output",       "preview",    "preview-layer", "backend",     "device",
                                             "threads",      "strip-rows", "region",        "points-part", "task",
                                             "task-startup", "dry-run",    "max-memory",    "zip-level",   "validation",
                                             "quiet",        "json",       "help",          "version"};

/* "; did you mean --octaves?" for an unknown flag of `cmd` (kind: a generator's flags too), or "". */
static void flag_hint(const char *flag, const char *kind, const char *const *extra, int nextra, char *out, size_t size)
{
    const char *cands[256];
    int n = 0;
    for (size_t i = 0; i < sizeof k_common_flags / sizeof k_common_flags[0]; i++) cands[n++] = k_common_flags[i];
    for (int i = 0; i < nextra && n < 256; i++) cands[n++] = extra[i];
    if (kind) n += fb_scene_flags(kind, cands + n, 256 - n);
    const char *near = !strncmp(flag, "--", 2) ? fb_closest(flag + 2, cands, n) : NULL;
    snprintf(out, size, near ? "; did you mean --%s?" : "", near);
}

/* Consumes a common option at argv[*i]; returns 1 if consumed, 0 if not common, -1 on error (logged). */
static int common_option(int argc, char **argv, int *i, common_opts *o)
{
    const char *a = argv[*i];
    const char *val = *i + 1 < argc ? argv[*i + 1] : NULL;
#define NEED_VALUE()                                                                                                   \
    do {                                                                                                               \
        if (!val) {                                                                                                    \
            fb_fail(FB_ERR_USAGE, "%s: missing value", a);                                                             \
            return -1;                                                                                                 \
        }                                                                                                              \
        (*i)++;                                                                                                        \
    } while (0)
    if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
        NEED_VALUE();
        o->out = val;
        if (fb_output_format(a, val, ".exr")) return -1;
    } else if (!strcmp(a, "--preview")) {
        NEED_VALUE();
        o->preview = val;
        if (fb_output_format(a, val, ".png")) return -1;
    } else if (!strcmp(a, "--preview-layer")) {
        NEED_VALUE();
        o->preview_layer = val;
    } else if (!strcmp(a, "--device")) {
        NEED_VALUE();
        o->device = val;
    } else if (!strcmp(a, "--backend")) {
        NEED_VALUE();
        if (!strcmp(val, "vulkan"))
            o->backend = FB_BACKEND_VULKAN;
        else if (!strcmp(val, "native"))
            o->backend = FB_BACKEND_NATIVE;
        else if (!strcmp(val, "auto"))
            o->backend = FB_BACKEND_AUTO;
        else {
            fb_fail(FB_ERR_USAGE, "--backend: expected auto, vulkan or native, found \"%s\"", val);
            return -1;
        }
    } else if (!strcmp(a, "--threads")) {
        NEED_VALUE();
        if (!parse_int_arg(val, 1, 1024, &o->threads)) {
            fb_fail(FB_ERR_USAGE, "--threads: expected an integer in 1..1024, found \"%s\"", val);
            return -1;
        }
    } else if (!strcmp(a, "--strip-rows")) {
        NEED_VALUE();
        if (!parse_int_arg(val, 1, FB_MAX_DIM, &o->strip_rows)) {
            fb_fail(FB_ERR_USAGE, "--strip-rows: expected an integer in 1..%d, found \"%s\"", FB_MAX_DIM, val);
            return -1;
        }
    } else if (!strcmp(a, "--region")) {
        NEED_VALUE();
        if (!parse_region(val, o->region)) {
            fb_fail(FB_ERR_USAGE, "--region: expected X,Y,W,H (integers, W and H >= 1), found \"%s\"", val);
            return -1;
        }
    } else if (!strcmp(a, "--points-part")) {
        NEED_VALUE();
        if (!parse_points_part(val, o->points_part)) {
            fb_fail(FB_ERR_USAGE, "--points-part: expected K/N with 1 <= K <= N <= 4096, found \"%s\"", val);
            return -1;
        }
    } else if (!strcmp(a, "--task")) {
        NEED_VALUE();
        char *end;
        long k = strtol(val, &end, 10), n = *end == '/' ? strtol(end + 1, &end, 10) : 0;
        if (!*val || *end || k < 0 || n < 1 || k >= n || n > FB_PLAN_MAX_TASKS) {
            fb_fail(
                FB_ERR_USAGE,
                "--task: expected K/N with 0 <= K < N <= %d (K counts from 0, like SLURM_ARRAY_TASK_ID), found \"%s\"",
                FB_PLAN_MAX_TASKS, val);
            return -1;
        }
        o->task[0] = (int)k, o->task[1] = (int)n;
    } else if (!strcmp(a, "--task-startup")) {
        NEED_VALUE();
        o->task_startup_set = true;
        if (!parse_seconds(val, &o->task_startup)) {
            fb_fail(FB_ERR_USAGE, "--task-startup: expected seconds in 0..3600, found \"%s\"", val);
            return -1;
        }
    } else if (!strcmp(a, "--max-memory")) {
        NEED_VALUE();
        if (!fb_parse_memory(val, &o->max_memory)) {
            fb_fail(FB_ERR_USAGE, "--max-memory: expected a size such as 8G, 512M or 50%%, found \"%s\"", val);
            return -1;
        }
    } else if (!strcmp(a, "--zip-level")) {
        NEED_VALUE();
        int level;
        if (!parse_int_arg(val, 1, EXRIO_ZIP_LEVEL_MAX, &level)) {
            fb_fail(FB_ERR_USAGE, "--zip-level: expected an integer in 1..%d, found \"%s\"", EXRIO_ZIP_LEVEL_MAX, val);
            return -1;
        }
        o->zip_level = level;
    } else if (!strcmp(a, "--dry-run")) {
        o->dry_run = true;
    } else if (!strcmp(a, "--quiet")) {
        o->quiet = true;
    } else if (!strcmp(a, "--json")) {
        o->json = true;
    } else if (!strcmp(a, "--validation")) {
        o->validation = true;
    } else if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
        o->help = true;
    } else {
        return 0;
    }
    return 1;
#undef NEED_VALUE
}

static void report(const char *layer, const char *summary, const char *json, void *user)
{
    const common_opts *o = user;
    if (o->json) { /* into the layer's entry of the summary */
        json_t *layers = json_object_get(g_summary, "layers"), *l;
        size_t i;
        json_array_foreach(layers, i, l) if (!strcmp(json_string_value(json_object_get(l, "name")), layer))
            json_object_set_new(l, "summary", json_loads(json, 0, NULL));
    } else if (!o->quiet) {
        cli_after("fractalbake: %s", summary);
    }
}

/* --dry-run: the predicted peak memory, per layer and in all, on stdout. */
static void print_plan(const fb_bake_plan *p, bool json)
{
    char a[32], b[32];
    if (json) {
        printf("{\"peak_bytes\": %llu, \"limit_bytes\": %llu, \"base_bytes\": %llu, \"writer_bytes\": %llu, "
               "\"preview_bytes\": %llu, \"layers\": [",
               (unsigned long long)p->peak, (unsigned long long)p->limit, (unsigned long long)p->base,
               (unsigned long long)p->writer, (unsigned long long)p->preview);
        for (int i = 0; i < p->nlayers; i++)
            printf("%s{\"name\": \"%s\", \"bytes\": %llu}", i ? ", " : "", p->layers[i].name,
                   (unsigned long long)p->layers[i].bytes);
        printf("]}\n");
        return;
    }
    for (int i = 0; i < p->nlayers; i++) {
        fb_format_bytes(p->layers[i].bytes, a, sizeof a);
        printf("layer %-20s %12s\n", p->layers[i].name, a);
    }
    fb_format_bytes(p->base, a, sizeof a);
    printf("%-26s %12s\n", "process and backend", a);
    fb_format_bytes(p->writer, a, sizeof a);
    printf("%-26s %12s\n", "EXR writer queue", a);
    if (p->preview) {
        fb_format_bytes(p->preview, a, sizeof a);
        printf("%-26s %12s\n", "preview", a);
    }
    fb_format_bytes(p->peak, a, sizeof a);
    fb_format_bytes(p->limit, b, sizeof b);
    printf("%-26s %12s  (--max-memory %s)\n", "predicted peak", a, b);
}

static const char *heightmap_format_name(int f)
{
    return f == FB_HEIGHTMAP_PNG16   ? "16-bit grey PNG"
           : f == FB_HEIGHTMAP_RAW16 ? "16-bit little-endian raw"
                                     : "float GeoTIFF";
}

static fb_result bake_scene(const char *command, fb_scene *scene, const common_opts *o)
{
    if (o->json && !o->dry_run && o->out && !strcmp(o->out, "-"))
        return fb_fail(FB_ERR_USAGE, "--json: standard output holds the EXR (-o -): one or the other");
    if (o->preview_layer && !o->preview)
        return fb_fail(FB_ERR_USAGE,
                       "--preview-layer %s: only with --preview FILE.png (there is no preview to show it)",
                       o->preview_layer);
    if (o->json && !o->dry_run) {
        json_t *sum = summary_start(command), *layers = json_array();
        for (int i = 0; i < scene->nlayers; i++)
            json_array_append_new(
                layers, json_pack("{ssss}", "name", scene->layers[i].name, "type", scene->layers[i].cls->name));
        json_object_set_new(sum, "layers", layers);
    }
    if (o->points_part[1] > 0) {
        bool chaos = false;
        for (int i = 0; i < scene->nlayers; i++) chaos = chaos || scene->layers[i].cls->share == FB_SHARE_POINTS;
        if (!chaos) return fb_fail(FB_ERR_USAGE, "--points-part: the scene has no chaos-game layer to split by points");
        if (o->region[2] > 0)
            return fb_fail(FB_ERR_USAGE, "--points-part: not with --region (split a bake by pixels or by points)");
    }
    /* render --task K/N: the plan's share K, as a scene of its layers only */
    fb_scene *sub = NULL;
    fb_plan *plan_n = NULL;
    char *plan_json = NULL, task_attr[32], share[2048] = "";
    exrio_attr task_attrs[2];
    common_opts ot = *o;
    if (o->task_startup_set && !o->task[1])
        return fb_fail(FB_ERR_USAGE, "--task-startup: only with --task K/N (and fractalbake plan)");
    if (o->task[1] > 0) {
        const char *clash = o->region[2]        ? "--region"
                            : o->points_part[1] ? "--points-part"
                            : o->preview        ? "--preview"
                            : o->dry_run        ? "--dry-run"
                                                : NULL;
        if (clash)
            return fb_fail(FB_ERR_USAGE, "--task: not with %s (a task bakes the share its plan gives it)", clash);
        if (!strcmp(o->out, "-")) return fb_fail(FB_ERR_USAGE, "--task: -o - is refused: merge reads task files");
        fb_result rc = (plan_n = malloc(sizeof *plan_n)) && (sub = calloc(1, sizeof *sub))
                           ? fb_plan_make(scene, o->task[1], o->task_startup_set ? o->task_startup : -1, plan_n)
                           : fb_fail(FB_ERR_NOMEM, "out of memory");
        if (!rc && o->task[0] >= plan_n->nactive) {
            if (o->json)
                json_object_set_new(g_summary, "task",
                                    json_pack("{sisisb}", "index", o->task[0], "of", o->task[1], "idle", 1));
            else if (!o->quiet)
                fprintf(stderr,
                        "fractalbake: task %d/%d has nothing to do: the plan gives this bake to tasks 0-%d "
                        "(`fractalbake plan --tasks %d`); no file written\n",
                        o->task[0], o->task[1], plan_n->nactive - 1, o->task[1]);
            free(plan_n);
            free(sub);
            return FB_OK;
        }
        const fb_task *t = rc ? NULL : &plan_n->tasks[o->task[0]];
        if (!rc) rc = fb_scene_subset(scene, t->layers, sub);
        if (!rc && !(plan_json = fb_plan_json(scene, plan_n, false))) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
        if (rc) {
            if (sub) fb_scene_fini(sub);
            free(sub);
            free(plan_n);
            return rc;
        }
        fb_plan_describe(scene, t, share, sizeof share);
        if (t->band) ot.region[0] = 0, ot.region[1] = t->y0, ot.region[2] = scene->width, ot.region[3] = t->y1 - t->y0;
        if (t->points) ot.points_part[0] = t->part, ot.points_part[1] = t->nparts;
        snprintf(task_attr, sizeof task_attr, "%d/%d", o->task[0], o->task[1]);
        task_attrs[0] = (exrio_attr){"fractalbake/task", task_attr};
        task_attrs[1] = (exrio_attr){"fractalbake/plan", plan_json};
        scene = sub;
        o = &ot;
        if (o->json)
            json_object_set_new(g_summary, "task",
                                json_pack("{sisiss}", "index", o->task[0], "of", o->task[1], "share", share));
    }
    fb_engine e;
    fb_result rc = fb_engine_open(&(fb_engine_desc){.backend = o->backend,
                                                    .device = o->device,
                                                    .threads = o->threads,
                                                    .validation = o->validation,
                                                    .vk_options = g_env.vk},
                                  &e);
    if (rc) goto done;
    fb_bake_stats st;
    fb_bake_plan plan;
    fb_memory_set_limit(o->max_memory);
    rc = fb_bake(&e,
                 &(fb_bake_desc){.scene = scene,
                                 .out = o->out,
                                 .preview = o->preview,
                                 .preview_layer = o->preview_layer,
                                 .strip_rows = o->strip_rows,
                                 .zip_level = o->zip_level,
                                 .points_part = {o->points_part[0], o->points_part[1]},
                                 .region = {o->region[0], o->region[1], o->region[2], o->region[3]},
                                 .progress = !o->quiet,
                                 .plan = &plan,
                                 .dry_run = o->dry_run,
                                 .report = report,
                                 .user = (void *)o,
                                 .attrs = task_attrs,
                                 .nattrs = o->task[1] > 0 ? 2 : 0,
                                 .layer_backends = o->task[1] > 0},
                 &st);
    if (!rc && o->dry_run) {
        print_plan(&plan, o->json);
    } else if (!rc && o->json) {
        json_object_set_new(g_summary, "size", json_pack("[ii]", scene->width, scene->height));
        if (o->region[2])
            json_object_set_new(g_summary, "region",
                                json_pack("[iiii]", o->region[0], o->region[1], o->region[2], o->region[3]));
        json_object_set_new(g_summary, "seconds", json_real(st.seconds));
        bool any_vk = false; /* "device": the Vulkan device where a layer ran on it, else native C */
        for (int i = 0; i < scene->nlayers; i++) any_vk = any_vk || st.layer_backend[i] == FB_BACKEND_VULKAN;
        json_object_set_new(g_summary, "device", json_string(any_vk ? e.device : "native C"));
        if (st.preview[0]) json_object_set_new(g_summary, "preview", json_string(st.preview));
        json_t *hms = json_array();
        for (int i = 0; i < st.nheightmaps; i++) {
            const fb_bake_heightmap *h = &st.heightmaps[i];
            json_t *j =
                json_pack("{ssssss}", "layer", h->layer, "path", h->path, "format", heightmap_format_name(h->format));
            if (h->format != FB_HEIGHTMAP_GEOTIFF) {
                json_object_set_new(j, "height_at_0", json_real(h->lo));
                json_object_set_new(j, "height_at_65535", json_real(h->hi));
            }
            json_array_append_new(hms, j);
        }
        if (st.nheightmaps)
            json_object_set_new(g_summary, "heightmaps", hms);
        else
            json_decref(hms);
        json_t *layers = json_object_get(g_summary, "layers");
        for (int i = 0; i < scene->nlayers; i++) {
            json_t *l = json_array_get(layers, (size_t)i);
            json_object_set_new(l, "backend", json_string(fb_backend_name(st.layer_backend[i])));
            json_object_set_new(l, "device",
                                json_string(st.layer_backend[i] == FB_BACKEND_VULKAN ? e.device : "native C"));
        }
    } else if (!rc && !o->quiet) {
        if (o->task[1] > 0) cli_after("fractalbake: task %d/%d: %s", o->task[0], o->task[1], share);
        cli_after("fractalbake: wrote %s (%d x %d%s, %d layer%s) in %.2f s %s",
                  strcmp(o->out, "-") ? o->out : "standard output", o->region[2] ? o->region[2] : scene->width,
                  o->region[2] ? o->region[3] : scene->height, o->region[2] ? " region" : "", scene->nlayers,
                  scene->nlayers == 1 ? "" : "s", st.seconds, st.ran_on);
        if (st.preview[0]) cli_after("fractalbake: preview %s: %s", o->preview, st.preview);
        for (int i = 0; i < st.nheightmaps; i++) {
            const fb_bake_heightmap *h = &st.heightmaps[i];
            char lo[40], hi[40];
            fb_format_shortest(h->lo, lo, sizeof lo);
            fb_format_shortest(h->hi, hi, sizeof hi);
            if (h->format == FB_HEIGHTMAP_GEOTIFF)
                cli_after("fractalbake: heightmap %s: layer %s's heights as float, with its geotransform", h->path,
                          h->layer);
            else
                cli_after("fractalbake: heightmap %s: layer %s's heights %s (0) to %s (65535), %s", h->path, h->layer,
                          lo, hi, heightmap_format_name(h->format));
        }
    }
    fb_engine_close(&e);
done:
    if (sub) fb_scene_fini(sub);
    free(sub);
    free(plan_n);
    free(plan_json);
    return rc;
}

static int cmd_generator(const char *kind, int argc, char **argv)
{
    common_opts o = {0};
    char **gen_args = calloc((size_t)argc + 1, sizeof *gen_args);
    int ngen = 0;
    fb_result rc = FB_OK;
    if (!gen_args) return finish(fb_fail(FB_ERR_NOMEM, "out of memory"));
    for (int i = 0; i < argc; i++) {
        int c = common_option(argc, argv, &i, &o);
        if (c < 0) {
            free(gen_args);
            return finish(FB_ERR_USAGE);
        }
        if (c > 0) continue;
        if (!strncmp(argv[i], "--", 2) && fb_scene_flag_arity(kind, argv[i] + 2) < 0 && strcmp(argv[i], "--half")) {
            char hint[96];
            flag_hint(argv[i], kind, NULL, 0, hint, sizeof hint);
            fb_fail(FB_ERR_USAGE, "%s: unknown flag for `fractalbake %s`%s (see fractalbake %s --help)", argv[i], kind,
                    hint, kind);
            free(gen_args);
            return finish(FB_ERR_USAGE);
        }
        gen_args[ngen++] = argv[i];
        if (strncmp(argv[i], "--", 2) == 0 && fb_scene_flag_arity(kind, argv[i] + 2) == 1 && i + 1 < argc)
            gen_args[ngen++] = argv[++i];
    }
    if (o.help) {
        printf("usage: fractalbake %s [options] -o OUT.exr [--preview OUT.png]\n\noptions (each is also a scene key of "
               "the same name):\n",
               kind);
        fb_scene_print_keys(kind, print_line, stdout);
        printf("\nand the common options of `fractalbake --help`.\n");
        free(gen_args);
        return 0;
    }
    g_quiet_warnings = o.quiet;
    char *json = NULL;
    fb_scene scene = {0};
    rc = fb_scene_from_flags(kind, ngen, gen_args, &json);
    if (!rc) rc = fb_scene_parse(json, NULL, &scene);
    if (!rc && !o.out && !o.dry_run)
        rc = fb_fail(FB_ERR_USAGE, "-o: missing output file (fractalbake %s ... -o OUT.exr)", kind);
    if (!rc) rc = bake_scene(kind, &scene, &o);
    fb_scene_fini(&scene);
    free(json);
    free(gen_args);
    return finish(rc);
}

/* The scene stored in a file baked by fractalbake, and the backend that baked it. */
/* The scene stored in a file fractalbake wrote, its backend, and what part of a bake the file is: a
 * region, a points part, or task[0]/task[1] of a plan with *startup (render --task). */
static fb_result stored_scene(const char *path, char **json, fb_backend *backend, int region[4], int points_part[2],
                              int task[2], double *startup)
{
    exrio_reader *r = NULL;
    fb_result rc = exrio_open(path, &r);
    if (rc) return rc;
    const char *tk = exrio_attr_string(r, "fractalbake/task"), *plan = exrio_attr_string(r, "fractalbake/plan");
    if (tk) {
        json_t *pj = plan ? json_loads(plan, 0, NULL) : NULL;
        char *end;
        long k = strtol(tk, &end, 10), n = *end == '/' ? strtol(end + 1, &end, 10) : 0;
        if (*end || k < 0 || n < 1 || k >= n || n > FB_PLAN_MAX_TASKS ||
            !json_is_number(json_object_get(pj, "startup")))
            rc =
                fb_fail(FB_ERR_INPUT, "%s: malformed attributes fractalbake/task \"%s\" or fractalbake/plan", path, tk);
        else
            task[0] = (int)k, task[1] = (int)n, *startup = json_number_value(json_object_get(pj, "startup"));
        json_decref(pj);
        exrio_close(&r);
        if (rc) return rc;
        if ((rc = exrio_open(path, &r))) return rc;
    }
    const char *text = exrio_attr_string(r, "fractalbake/scene");
    const char *be = exrio_attr_string(r, "fractalbake/backend");
    const char *reg = tk ? NULL : exrio_attr_string(r, "fractalbake/region"); /* a task's come from its plan */
    const char *pp = tk ? NULL : exrio_attr_string(r, "fractalbake/points-part");
    if (pp && !parse_points_part(pp, points_part))
        rc = fb_fail(FB_ERR_INPUT, "%s: malformed attribute fractalbake/points-part \"%s\"", path, pp);
    if (reg && !parse_region(reg, region))
        rc = fb_fail(FB_ERR_INPUT, "%s: malformed attribute fractalbake/region \"%s\"", path, reg);
    if (rc)
        ;
    else if (!text)
        rc = fb_fail(FB_ERR_INPUT, "%s: no stored scene (attribute fractalbake/scene): not baked by fractalbake", path);
    else if (!(*json = strdup(text)))
        rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    *backend = be && !strcmp(be, "native")   ? FB_BACKEND_NATIVE
               : be && !strcmp(be, "vulkan") ? FB_BACKEND_VULKAN
                                             : FB_BACKEND_AUTO;
    exrio_close(&r);
    return rc;
}

static int cmd_render(int argc, char **argv)
{
    common_opts o = {0};
    const char *scene_path = NULL, *from = NULL;
    const char **sets = calloc((size_t)argc + 1, sizeof *sets);
    int nsets = 0;
    if (!sets) return finish(fb_fail(FB_ERR_NOMEM, "out of memory"));
    for (int i = 0; i < argc; i++) {
        int c = common_option(argc, argv, &i, &o);
        const char *a = argv[i], *val = i + 1 < argc ? argv[i + 1] : NULL;
        int bad = 0;
        if (c < 0) {
            free(sets);
            return finish(FB_ERR_USAGE);
        }
        if (c > 0) continue;
        if (!strcmp(a, "--set") || !strcmp(a, "--from")) {
            if (!val) {
                free(sets);
                return usage_error("%s: missing value", a);
            }
            if (!strcmp(a, "--set"))
                sets[nsets++] = val;
            else if (from)
                bad = usage_error("%s: only one --from may be given", a);
            else
                from = val;
            i++;
        } else if (a[0] == '-' && a[1]) { /* "-": the scene from standard input */
            static const char *const render_flags[] = {"set", "from"};
            char hint[96];
            flag_hint(a, NULL, render_flags, 2, hint, sizeof hint);
            fb_fail(FB_ERR_USAGE, "%s: unknown flag for `fractalbake render`%s", a, hint);
            bad = finish(FB_ERR_USAGE);
        } else if (scene_path) {
            bad = usage_error("%s: only one scene file may be given", a);
        } else {
            scene_path = a;
        }
        if (bad) {
            free(sets);
            return bad;
        }
    }
    if (o.help) {
        printf("usage: fractalbake render [SCENE.json | --from OLD.exr] [--set KEY.PATH=VALUE ...] [-o OUT.exr]\n"
               "                          [--preview OUT.png [--preview-layer NAME|over]]\n"
               "Bakes every layer of the scene into one EXR. Without SCENE.json, bakes the embedded default scene\n"
               "(a night sky, a refined terrain and a plant population). --from bakes the scene stored in a file\n"
               "fractalbake wrote, on the backend that wrote it unless --backend is given: the same pixels.\n"
               "--set overrides one key before validation: size=2048x1024, seed=9, layers.sky.c=-0.8,0.156,\n"
               "layers.1.insert=5000 (a list element by index or by layer name; lists comma-separated).\n"
               "Default output: fractalbake.exr in the current folder.\n");
        free(sets);
        return 0;
    }
    g_quiet_warnings = o.quiet;
    if (!o.out) o.out = "fractalbake.exr";
    fb_scene scene = {0};
    fb_result rc = FB_OK;
    if (from && scene_path) {
        rc = fb_fail(FB_ERR_USAGE, "--from %s: give either a scene file or --from, not both", from);
    } else if (from) {
        char *json = NULL, origin[1100];
        fb_backend stored = FB_BACKEND_AUTO;
        int region[4] = {0}, part[2] = {0}, task[2] = {0};
        double startup = 0;
        rc = stored_scene(from, &json, &stored, region, part, task, &startup);
        if (!rc && o.region[2] == 0 && o.points_part[1] == 0 && o.task[1] == 0) {
            memcpy(o.region, region, sizeof region);
            memcpy(o.points_part, part, sizeof part);
            memcpy(o.task, task, sizeof task);
            if (task[1]) o.task_startup = startup, o.task_startup_set = true;
        }
        snprintf(origin, sizeof origin, "%s (stored scene)", from);
        /* A file from elsewhere must not choose what this run writes: its layers' output paths go,
         * and --set puts back the ones the user names. */
        char *kept = NULL, dropped[2048];
        if (!rc) rc = fb_scene_drop_outputs(json, &kept, dropped, sizeof dropped);
        if (!rc && dropped[0])
            fb_log(FB_LOG_WARN, "--from %s: not writing the stored scene's outputs (%s); name them with --set", from,
                   dropped);
        if (!rc) rc = fb_scene_parse_sets(kept, origin, sets, nsets, &scene);
        free(kept);
        if (o.backend == FB_BACKEND_AUTO) o.backend = stored;
        free(json);
    } else if (scene_path) {
        rc = fb_scene_load_sets(scene_path, sets, nsets, &scene);
    } else {
        rc = fb_scene_parse_sets(fb_scene_default_json(), "(default scene)", sets, nsets, &scene);
    }
    if (!rc) rc = bake_scene("render", &scene, &o);
    fb_scene_fini(&scene);
    free(sets);
    return finish(rc);
}

/* idiff's single-dash spelling of a flag compare shares, as ours (in buf); its other flags answered
 * with ours (NULL, the error logged); any other argument as it is. */
static const char *idiff_flag(const char *a, char *buf, size_t size)
{
    /* idiff's own single-dash spellings of the flags that mean the same here; its others answered */
    static const char *const idiff_same[] = {"fail", "failrelative", "failpercent", "hardfail", "allowfailures",
                                             "warn", "warnrelative", "warnpercent", "hardwarn"};
    static const char *const idiff_other[][2] = {
        {"-o", "the difference image: --diff OUT.exr (|A - B|; idiff -o writes A - B)"},
        {"-od", "--diff writes its file whatever the difference"},
        {"-abs", "--diff writes |A - B| already"},
        {"-scale", "--diff writes |A - B| unscaled"},
        {"-p", "a perceptual comparison: --flip (idiff -p is Yee's metric)"},
        {"-a", "every part is compared: channels are matched by name"},
        {"-v", "compare prints its statistics already (--idiff-stats: idiff's)"},
        {"-q", "--quiet"}};
    for (size_t k = 0; a[0] == '-' && a[1] != '-' && k < sizeof idiff_same / sizeof idiff_same[0]; k++)
        if (!strcmp(a + 1, idiff_same[k])) return snprintf(buf, size, "-%s", a), buf;
    for (size_t k = 0; k < sizeof idiff_other / sizeof idiff_other[0]; k++)
        if (!strcmp(a, idiff_other[k][0])) {
            fb_fail(FB_ERR_USAGE, "%s: idiff's flag; fractalbake compare: %s", a, idiff_other[k][1]);
            return NULL;
        }
    return a;
}

static void compare_help(void)
{
    printf("usage: fractalbake compare A B [thresholds] [--layer L] [--ignore-missing] [--diff OUT.exr]\n"
           "                          [--diff-png OUT.png [--heat]] [--json] [--quiet]\n"
           "A and B are EXR or PNG files (a PNG's channels are Y, Y A, R G B or R G B A, 0..1).\n"
           "Per channel: the largest |A - B| and where, RMSE, PSNR (peak: A's range), the share of pixels\n"
           "beyond the fail threshold, and with --ssim the mean SSIM (Wang et al. 2004, L: A's range).\n"
           "\n"
           "thresholds (idiff's names; each takes a value for every channel, CHANNEL=VALUE or\n"
           "LAYER=VALUE rules, or both: --max-abs 1e-4,sky.R=1e-3,terrain=1e-6):\n"
           "  --max-abs E, --fail E      a pixel fails when |A - B| > E (default 0: every pixel equal)\n"
           "  --fail-percent P           the channel fails when more than P%% of its pixels fail (default 0)\n"
           "  --hardfail E               ... or when any pixel's |A - B| > E, whatever P\n"
           "  --warn E, --warn-percent P, --hardwarn E   the same for a warning\n"
           "  --rmse E, --psnr DB, --ssim S              fail beyond an RMSE, below a PSNR or an SSIM\n"
           "  (--failpercent and --warnpercent are accepted too)\n"
           "  --allowfailures N          a channel fails (on --fail-percent or --hardfail) only when more than\n"
           "                             N of its pixels are beyond --fail (idiff's rule)\n"
           "  --failrelative R, --warnrelative R   a pixel is beyond --fail (--warn) only when |A - B| is\n"
           "                             also beyond R * (|A| + |B|) / 2\n"
           "  idiff's single-dash spellings (-fail, -failpercent, -hardfail, -allowfailures, -warn, ...)\n"
           "  are taken too.\n"
           "--report OUT.html: one page that works offline: every layer's reference, test, difference\n"
           "and FLIP pictures (full size on click), statistics and verdict, failing layers first, and the\n"
           "stored scenes' keys that differ. --junit OUT.xml: a test case per channel and threshold.\n"
           "--idiff-stats adds idiff's statistics: over all compared channels together, RMS error and\n"
           "PSNR with peak max(1, the largest value), the pixels over --warn and --fail (any channel).\n"
           "\n"
           "FLIP (Andersson et al. 2020; HDR-FLIP 2021), per layer of R, G, B (or Y as grey):\n"
           "  --flip                     compute it: LDR-FLIP for PNGs, HDR-FLIP for EXRs (ACES, automatic\n"
           "                             exposures); the mean, weighted median and quartiles, max\n"
           "  --flip-fail E, --flip-warn E   fail (warn) when a layer's statistic is beyond E (LAYER=E rules)\n"
           "  --flip-stat mean|median|q1|q3|max   the statistic they test (default mean)\n"
           "  --flip-mode auto|ldr|hdr   LDR-FLIP takes sRGB values in [0, 1], HDR-FLIP linear ones\n"
           "  --flip-png OUT.png         the error of the layer with the largest mean, grey (255: error 1)\n"
           "  (each implies --flip; --diff then holds LAYER.FLIP too)\n"
           "\n"
           "--diff writes |A - B| per channel; --diff-png a picture: red where a channel fails, over A's\n"
           "first channel in dim grey; with --heat a heat map of the largest |A - B| over the channels,\n"
           "log scale (black 1e-8, blue 1e-6, red 1e-4, yellow 0.01, white 1). --json: the report as one\n"
           "JSON object. --quiet: only the result line.\n"
           "\n"
           "exit: 0 pass or warn (the result line says WARN; --json: \"result\": \"warn\"), 1 fail (also\n"
           "different sizes or channel sets, with the reason), 2 bad usage or input, 3 runtime failure.\n"
           "idiff returns 1 for a warning and 2 for a failure: fractalbake keeps 2 for bad input, as\n"
           "every fractalbake command does, and lets a warning pass.\n");
}

static int cmd_compare(int argc, char **argv)
{
    fb_compare_desc d = {.print = print_line};
    const char *files[2];
    int nfiles = 0;
    bool quiet = false;
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i], *val = i + 1 < argc ? argv[i + 1] : NULL;
        char dashed[64];
        if (!(a = idiff_flag(a, dashed, sizeof dashed))) return finish(FB_ERR_USAGE);
        /* idiff's names beside ours: --fail is --max-abs, --failpercent --fail-percent */
        static const struct {
            const char *flag;
            size_t off;
        } limits[] = {
            {"--max-abs", offsetof(fb_compare_desc, fail)},
            {"--fail", offsetof(fb_compare_desc, fail)},
            {"--fail-percent", offsetof(fb_compare_desc, failpercent)},
            {"--failpercent", offsetof(fb_compare_desc, failpercent)},
            {"--hardfail", offsetof(fb_compare_desc, hardfail)},
            {"--warn", offsetof(fb_compare_desc, warn)},
            {"--warn-percent", offsetof(fb_compare_desc, warnpercent)},
            {"--warnpercent", offsetof(fb_compare_desc, warnpercent)},
            {"--hardwarn", offsetof(fb_compare_desc, hardwarn)},
            {"--rmse", offsetof(fb_compare_desc, rmse)},
            {"--psnr", offsetof(fb_compare_desc, psnr)},
            {"--ssim", offsetof(fb_compare_desc, ssim)},
            {"--flip-fail", offsetof(fb_compare_desc, flip_fail)},
            {"--flip-warn", offsetof(fb_compare_desc, flip_warn)},
        };
        fb_limit *lim = NULL;
        for (size_t k = 0; k < sizeof limits / sizeof limits[0] && !lim; k++)
            if (!strcmp(a, limits[k].flag)) lim = (fb_limit *)((char *)&d + limits[k].off);
        if (lim) {
            if (!val) return usage_error("%s: missing value", a);
            if (fb_limit_parse(a, val, lim)) return finish(FB_ERR_USAGE);
            i++;
        } else if (!strcmp(a, "--layer") || !strcmp(a, "--diff") || !strcmp(a, "--diff-png")) {
            if (!val) return usage_error("%s: missing value", a);
            *(!strcmp(a, "--layer") ? &d.layer : !strcmp(a, "--diff") ? &d.diff : &d.diff_png) = val;
            if (strcmp(a, "--layer") && fb_output_format(a, val, !strcmp(a, "--diff") ? ".exr" : ".png"))
                return finish(FB_ERR_USAGE);
            i++;
        } else if (!strcmp(a, "--report") || !strcmp(a, "--junit")) {
            if (!val) return usage_error("%s: missing value", a);
            if (fb_output_format(a, val, !strcmp(a, "--report") ? ".html" : ".xml")) return finish(FB_ERR_USAGE);
            *(!strcmp(a, "--report") ? &d.report : &d.junit) = val;
            i++;
        } else if (!strcmp(a, "--flip-png")) {
            if (!val) return usage_error("%s: missing value", a);
            if (fb_output_format(a, val, ".png")) return finish(FB_ERR_USAGE);
            d.flip_png = val;
            i++;
        } else if (!strcmp(a, "--flip-mode") || !strcmp(a, "--flip-stat")) {
            static const char *const modes[] = {"auto", "ldr", "hdr"}, *const stats[] = {"mean", "median", "q1", "q3",
                                                                                         "max"};
            bool mode = !strcmp(a, "--flip-mode");
            int n = mode ? 3 : 5, k = 0;
            if (!val) return usage_error("%s: missing value", a);
            while (k < n && strcmp(val, (mode ? modes : stats)[k])) k++;
            if (k == n) {
                fb_fail(FB_ERR_USAGE, "%s: expected %s, found \"%s\"", a,
                        mode ? "auto|ldr|hdr" : "mean|median|q1|q3|max", val);
                return finish(FB_ERR_USAGE);
            }
            if (mode)
                d.flip_mode = (fb_flip_mode)k;
            else
                d.flip_stat = k;
            d.flip = true;
            i++;
        } else if (!strcmp(a, "--flip")) {
            d.flip = true;
        } else if (!strcmp(a, "--idiff-stats")) {
            d.idiff_stats = true;
        } else if (!strcmp(a, "--allowfailures") || !strcmp(a, "--failrelative") || !strcmp(a, "--warnrelative")) {
            char *end;
            if (!val) return usage_error("%s: missing value", a);
            errno = 0;
            double v = strtod(val, &end);
            bool count = !strcmp(a, "--allowfailures");
            if (end == val || *end || errno || !isfinite(v) || v < 0 || (count && (v != floor(v) || v > 9e18))) {
                fb_fail(FB_ERR_USAGE, "%s: expected %s, found \"%s\"", a,
                        count ? "a whole number of pixels >= 0" : "a finite number >= 0", val);
                return finish(FB_ERR_USAGE);
            }
            if (count)
                d.allowfailures = (long long)v;
            else
                *(!strcmp(a, "--failrelative") ? &d.failrelative : &d.warnrelative) = v;
            i++;
        } else if (!strcmp(a, "--ignore-missing")) {
            d.ignore_missing = true;
        } else if (!strcmp(a, "--heat")) {
            d.heat = true;
        } else if (!strcmp(a, "--json")) {
            d.json = true;
        } else if (!strcmp(a, "--quiet")) {
            quiet = true;
        } else if (!strcmp(a, "--help")) {
            compare_help();
            return 0;
        } else if (a[0] == '-' && a[1]) {
            static const char *const flags[] = {
                "max-abs",      "fail",        "fail-percent", "failpercent",   "hardfail",       "warn",
                "warn-percent", "warnpercent", "hardwarn",     "rmse",          "psnr",           "ssim",
                "layer",        "diff",        "diff-png",     "heat",          "ignore-missing", "json",
                "quiet",        "help",        "flip",         "flip-fail",     "flip-warn",      "flip-stat",
                "flip-mode",    "flip-png",    "idiff-stats",  "allowfailures", "failrelative",   "warnrelative",
                "report",       "junit"};
            const char *near = !strncmp(a, "--", 2) ? fb_closest(a + 2, flags, sizeof flags / sizeof flags[0]) : NULL;
            char hint[96] = "";
            if (near) snprintf(hint, sizeof hint, "; did you mean --%s?", near);
            fb_fail(FB_ERR_USAGE, "%s: unknown flag for `fractalbake compare`%s", a, hint);
            return finish(FB_ERR_USAGE);
        } else if (nfiles < 2) {
            files[nfiles++] = a;
        } else {
            return usage_error("%s: compare takes exactly two files", a);
        }
    }
    if (nfiles != 2) return usage_error("%s", "compare: expected two images: fractalbake compare A.exr B.exr");
    if (d.flip_fail.set || d.flip_warn.set || d.flip_png) d.flip = true;
    d.a = files[0];
    d.b = files[1];
    if (quiet && !d.json) d.print = print_result_only;
    fb_verdict v = FB_VERDICT_PASS;
    if (d.heat && !d.diff_png)
        return usage_error("%s", "--heat: only with --diff-png OUT.png (it chooses that picture's colours)");
    fb_result rc = fb_compare(&d, &v);
    if (rc) return finish(rc);
    return v == FB_VERDICT_FAIL ? 1 : 0;
}

static int cmd_merge(int argc, char **argv)
{
    const char *out = NULL;
    const char **parts = calloc((size_t)argc + 1, sizeof *parts);
    int n = 0, threads = 0, zip_level = 0, bad = 0;
    bool quiet = false, json = false;
    if (!parts) return finish(fb_fail(FB_ERR_NOMEM, "out of memory"));
    for (int i = 0; i < argc && !bad; i++) {
        const char *a = argv[i], *val = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "-o") || !strcmp(a, "--output") || !strcmp(a, "--threads")) {
            if (!val)
                bad = usage_error("%s: missing value", a);
            else if (strcmp(a, "--threads"))
                bad = fb_output_format(a, out = val, ".exr") ? finish(FB_ERR_USAGE) : 0;
            else if (!parse_int_arg(val, 1, 1024, &threads))
                bad = usage_error("--threads: expected an integer in 1..1024, found \"%s\"", val);
            i++;
        } else if (!strcmp(a, "--zip-level")) {
            int level = 0;
            if (!val || !parse_int_arg(val, 1, EXRIO_ZIP_LEVEL_MAX, &level))
                bad = usage_error("--zip-level: expected an integer in 1..12, found \"%s\"", val ? val : "");
            zip_level = level;
            i++;
        } else if (!strcmp(a, "--max-memory")) {
            uint64_t m = 0;
            if (!val || !fb_parse_memory(val, &m))
                bad =
                    usage_error("--max-memory: expected a size such as 8G, 512M or 50%%, found \"%s\"", val ? val : "");
            fb_memory_set_limit(m);
            i++;
        } else if (!strcmp(a, "--quiet")) {
            quiet = true;
        } else if (!strcmp(a, "--json")) {
            json = true;
        } else if (!strcmp(a, "--help")) {
            printf("usage: fractalbake merge PART.exr... -o OUT.exr [--threads N] [--zip-level N] [--max-memory SIZE] "
                   "[--quiet] [--json]\n"
                   "Joins the region files of `fractalbake render --region X,Y,W,H` into the whole image: regions\n"
                   "of one bake (same size, channels and scene) that cover it with no overlap. Or adds the N points\n"
                   "parts of `render --points-part K/N` (chaos games split by points) into the whole game.\n");
            free(parts);
            return 0;
        } else if (a[0] == '-' && a[1]) {
            bad = usage_error("%s: unknown flag for `fractalbake merge`", a);
        } else {
            parts[n++] = a;
        }
    }
    if (!bad && !out) bad = usage_error("%s", "merge: -o OUT.exr is required (fractalbake merge PARTS... -o OUT.exr)");
    if (!bad && n == 0) bad = usage_error("%s", "merge: no region files given (fractalbake merge PARTS... -o OUT.exr)");
    if (bad) {
        free(parts);
        return bad;
    }
    if (json && !strcmp(out, "-"))
        bad = usage_error("%s", "--json: standard output holds the EXR (-o -): one or the other");
    if (bad) {
        free(parts);
        return bad;
    }
    double t0 = fb_now();
    fb_result rc = fb_merge(parts, n, out, threads, zip_level);
    if (!rc && json) {
        json_t *sum = summary_start("merge"), *in = json_array();
        for (int i = 0; i < n; i++) json_array_append_new(in, json_string(parts[i]));
        json_object_set_new(sum, "parts", in);
        json_object_set_new(sum, "seconds", json_real(fb_now() - t0));
    } else if (!rc && !quiet) {
        cli_after("fractalbake: merged %d part%s into %s in %.2f s", n, n == 1 ? "" : "s", out, fb_now() - t0);
    }
    free(parts);
    return finish(rc);
}

static int cmd_info(int argc, char **argv)
{
    const char *path = NULL;
    bool json = false;
    for (int i = 0; i < argc; i++) {
        if (!strcmp(argv[i], "--help")) {
            printf("usage: fractalbake info FILE.exr [--json]\n"
                   "Size, compression, layers and channels with their types, every attribute with its value,\n"
                   "and the stored scene (what `render --from FILE.exr` bakes). --json: all of it as one JSON\n"
                   "object.\n");
            return 0;
        } else if (!strcmp(argv[i], "--json")) {
            json = true;
        } else if (!strcmp(argv[i], "--quiet")) {
            /* nothing to leave out: the description is the output */
        } else if (argv[i][0] == '-' && argv[i][1]) {
            return usage_error("%s: unknown flag for `fractalbake info` (only --json)", argv[i]);
        } else if (path) {
            return usage_error("%s: info takes one EXR file", argv[i]);
        } else {
            path = argv[i];
        }
    }
    if (!path) return usage_error("%s", "info: expected one EXR file: fractalbake info FILE.exr");
    return finish(fb_info(path, json, print_line, stdout));
}

/* `fractalbake scene default|FILE.json|-` [--set K=V ...] [--pretty]: the scene with every default
 * filled in, as a bake stores it; what `render --from` and the docs' examples start from. */
static int cmd_scene(int argc, char **argv)
{
    const char *which = NULL;
    const char **sets = calloc((size_t)argc + 1, sizeof *sets);
    int nsets = 0, bad = 0;
    bool pretty = false;
    if (!sets) return finish(fb_fail(FB_ERR_NOMEM, "out of memory"));
    for (int i = 0; i < argc && !bad; i++) {
        const char *a = argv[i], *val = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help")) {
            printf("usage: fractalbake scene default|SCENE.json|- [--set KEY.PATH=VALUE ...] [--pretty]\n"
                   "Prints the scene with every default filled in, keys sorted, numbers in their shortest form:\n"
                   "what a bake stores in its file and `render --from` bakes again. `default` is the embedded\n"
                   "default scene, `-` a scene on standard input. One line of JSON, or indented with --pretty:\n"
                   "  fractalbake scene default > scene.json\n");
            free(sets);
            return 0;
        } else if (!strcmp(a, "--set")) {
            if (!val)
                bad = usage_error("%s: missing value", a);
            else
                sets[nsets++] = val, i++;
        } else if (!strcmp(a, "--pretty")) {
            pretty = true;
        } else if (!strcmp(a, "--json") || !strcmp(a, "--quiet")) {
            /* the output is JSON already, and nothing else */
        } else if (a[0] == '-' && a[1]) {
            bad = usage_error("%s: unknown flag for `fractalbake scene` (--set, --pretty)", a);
        } else if (which) {
            bad = usage_error("%s: scene takes one scene (default, a file or -)", a);
        } else {
            which = a;
        }
    }
    if (!bad && !which)
        bad = usage_error("%s", "scene: expected default, a scene file or - (fractalbake scene default > scene.json)");
    if (bad) {
        free(sets);
        return bad;
    }
    fb_scene sc = {0};
    fb_result rc = !strcmp(which, "default")
                       ? fb_scene_parse_sets(fb_scene_default_json(), "(default scene)", sets, nsets, &sc)
                       : fb_scene_load_sets(which, sets, nsets, &sc);
    if (!rc) {
        json_t *j = json_loads(sc.json, 0, NULL);
        char *text = j ? fb_json_dumps(j, pretty ? 2 : 0) : NULL;
        if (text)
            printf("%s\n", text);
        else
            rc = fb_fail(FB_ERR_NOMEM, "out of memory");
        free(text);
        json_decref(j);
    }
    fb_scene_fini(&sc);
    free(sets);
    return finish(rc);
}

/* fractalbake plan: how render --task K/N splits a bake (plan.h). */
static int cmd_plan(int argc, char **argv)
{
    const char *scene_path = NULL;
    const char **sets = calloc((size_t)argc + 1, sizeof *sets);
    int nsets = 0, bad = 0, ntasks = 0;
    double startup = -1;
    bool json = false;
    if (!sets) return finish(fb_fail(FB_ERR_NOMEM, "out of memory"));
    for (int i = 0; i < argc && !bad; i++) {
        const char *a = argv[i], *val = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            char by_share[3][256];
            for (int k = 0; k < 3; k++) by_share[k][0] = 0;
            for (const fb_gen_class *const *c = fb_gen_list; *c; c++) {
                char *o = by_share[(*c)->share];
                snprintf(o + strlen(o), 256 - strlen(o), "%s%s", *o ? ", " : "", (*c)->name);
            }
            printf("usage: fractalbake plan [SCENE.json|-] --tasks N [--set KEY.PATH=VALUE ...] [--task-startup S]\n"
                   "                        [--json]\n"
                   "Splits a bake into N tasks of about equal cost: per-pixel layers (%s) into bands of rows,\n"
                   "chaos games (%s) into points parts, and layers whose cost does not shrink with a band\n"
                   "(%s, a layer writing a heightmap, and the layers using them) whole, each in one task.\n"
                   "Costs come from a model of each generator (seconds of one core).\n"
                   "Tasks count from 0, like SLURM_ARRAY_TASK_ID; the plan uses the fewest that keep the tasks'\n"
                   "total within 10%% of one bake, so with small bakes the last tasks may have nothing to do.\n"
                   "--task-startup S: each task's start-up the plan assumes (default 0.07 s, measured with\n"
                   "lavapipe; 0: every task that shortens the longest); give the same to each render --task.\n"
                   "Each task: fractalbake render SCENE.json --task K/N -o part-K.exr; then\n"
                   "fractalbake merge part-*.exr -o OUT.exr checks the set is complete and joins it.\n"
                   "Without SCENE.json, the embedded default scene.\n",
                   by_share[FB_SHARE_BAND], by_share[FB_SHARE_POINTS], by_share[FB_SHARE_WHOLE]);
            free(sets);
            return 0;
        } else if (!strcmp(a, "--set") || !strcmp(a, "--tasks") || !strcmp(a, "--task-startup")) {
            if (!val)
                bad = usage_error("%s: missing value", a);
            else if (!strcmp(a, "--task-startup")) {
                if (!parse_seconds(val, &startup))
                    bad = usage_error("--task-startup: expected seconds in 0..3600, found \"%s\"", val);
            } else if (!strcmp(a, "--set"))
                sets[nsets++] = val;
            else if (!parse_int_arg(val, 1, FB_PLAN_MAX_TASKS, &ntasks))
                bad = usage_error("--tasks: expected an integer in 1..1024, found \"%s\"", val);
            i++;
        } else if (!strcmp(a, "--json")) {
            json = true;
        } else if (!strcmp(a, "--quiet") || !strcmp(a, "-q")) {
            /* it prints the plan and nothing else */
        } else if (a[0] == '-' && a[1]) {
            bad = usage_error("%s: unknown flag for `fractalbake plan` (--tasks, --set, --task-startup, --json)", a);
        } else if (scene_path) {
            bad = usage_error("%s: only one scene file may be given", a);
        } else {
            scene_path = a;
        }
    }
    if (!bad && ntasks == 0)
        bad = usage_error("%s", "plan: --tasks N is required (fractalbake plan SCENE.json --tasks 8)");
    if (bad) {
        free(sets);
        return bad;
    }
    fb_scene *sc = calloc(1, sizeof *sc);
    fb_plan *p = malloc(sizeof *p);
    fb_result rc = !sc || !p    ? fb_fail(FB_ERR_NOMEM, "out of memory")
                   : scene_path ? fb_scene_load_sets(scene_path, sets, nsets, sc)
                                : fb_scene_parse_sets(fb_scene_default_json(), "(default scene)", sets, nsets, sc);
    if (!rc) rc = fb_plan_make(sc, ntasks, startup, p);
    if (!rc && json) {
        char *text = fb_plan_json(sc, p, true);
        if (text)
            printf("%s\n", text);
        else
            rc = fb_fail(FB_ERR_NOMEM, "out of memory");
        free(text);
    } else if (!rc) {
        printf("plan: %d x %d, %d layer%s over %d task%s (numbered from 0, like SLURM_ARRAY_TASK_ID)\n", sc->width,
               sc->height, sc->nlayers, sc->nlayers == 1 ? "" : "s", ntasks, ntasks == 1 ? "" : "s");
        printf("\n%-20s %-10s %-13s %10s\n", "layer", "type", "split", "model s");
        for (int i = 0; i < sc->nlayers; i++)
            printf("%-20s %-10s %-13s %10.3f\n", sc->layers[i].name, sc->layers[i].cls->name,
                   fb_plan_share_name(p->share[i]), p->layer_seconds[i]);
        printf("\n%-6s %-56s %10s\n", "task", "share", "model s");
        for (int k = 0; k < p->nactive; k++) {
            char d[2048];
            fb_plan_describe(sc, &p->tasks[k], d, sizeof d);
            printf("%-6d %-56s %10.3f\n", k, d, p->tasks[k].seconds);
        }
        if (p->nactive < ntasks)
            printf("%d-%-4d nothing: more tasks would not shorten the longest within 10%% of one bake's cost\n",
                   p->nactive, ntasks - 1);
        printf("\none bake %.2f s; the %d task%s %.2f s in all (%.2fx), the longest %.2f s (%.1fx sooner)\n", p->one,
               p->nactive, p->nactive == 1 ? "" : "s", p->total, p->total / p->one, p->longest, p->one / p->longest);
        printf("(model seconds of one core of the reference machine; docs/scenes.md)\n");
    }
    if (sc) fb_scene_fini(sc);
    free(sc);
    free(p);
    free(sets);
    return finish(rc);
}

static int cmd_devices(int argc, char **argv)
{
    const char *sel = NULL;
    bool json = false;
    for (int i = 0; i < argc; i++) {
        if (!strcmp(argv[i], "--device") && i + 1 < argc) {
            sel = argv[++i];
        } else if (!strcmp(argv[i], "--json")) {
            json = true;
        } else if (!strcmp(argv[i], "--help")) {
            printf("usage: fractalbake devices [--device D] [--json]\n"
                   "Lists the Vulkan devices (index, name, type, memory, subgroup size, driver), marks the one\n"
                   "fractalbake chooses (with --device D: the one D names), and says what --backend auto does.\n"
                   "--json: the same as one JSON object.\n");
            return 0;
        } else if (!strcmp(argv[i], "--quiet")) {
            /* nothing to leave out: the list is the output */
        } else
            return usage_error("%s: unknown argument for `fractalbake devices` (only --device D, --json)", argv[i]);
    }
    vkc_device_info *infos = NULL;
    int n = 0;
    fb_result rc = vkc_enumerate(sel, &infos, &n);
    if (rc == FB_ERR_NODEVICE) {
        if (json) {
            json_t *o = json_pack("{s[]sssisssi}", "devices", "reason", g_first_error, "native_threads", fb_cpu_count(),
                                  "auto", "native", "chosen", -1);
            char *t = fb_json_dumps(o, 0);
            printf("%s\n", t ? t : "{}");
            free(t);
            json_decref(o);
        } else {
            printf("no Vulkan device: %s\nfractalbake will use the native backend (%d threads).\n", g_first_error,
                   fb_cpu_count());
        }
        g_first_error[0] = 0;
        return 0;
    }
    if (rc) return finish(rc);
    if (json) {
        json_t *o = json_object(), *list = json_array();
        int chosen = -1;
        for (int i = 0; i < n; i++) {
            json_array_append_new(list,
                                  json_pack("{sisssssIsiss}", "index", i, "name", infos[i].name, "type", infos[i].type,
                                            "memory_bytes", (json_int_t)infos[i].memory, "subgroup_size",
                                            (int)infos[i].subgroup_size, "driver", infos[i].driver));
            if (infos[i].chosen) chosen = i;
        }
        json_object_set_new(o, "devices", list);
        json_object_set_new(o, "chosen", json_integer(chosen));
        json_object_set_new(o, "native_threads", json_integer(fb_cpu_count()));
        /* what --backend auto does with the chosen device */
        json_object_set_new(o, "auto",
                            json_string(chosen < 0                           ? "native"
                                        : !strcmp(infos[chosen].type, "cpu") ? "per layer"
                                                                             : "device"));
        char *t = fb_json_dumps(o, 0);
        printf("%s\n", t ? t : "{}");
        free(t);
        json_decref(o);
        free(infos);
        return 0;
    }
    printf("%-3s %-3s %-34s %-10s %-10s %-8s %s\n", "#", "use", "name", "type", "memory", "subgroup", "driver");
    for (int i = 0; i < n; i++)
        printf("%-3d %-3s %-34s %-10s %-10.0f %-8u %s\n", i, infos[i].chosen ? "*" : "", infos[i].name, infos[i].type,
               (double)infos[i].memory / (1024.0 * 1024.0), infos[i].subgroup_size, infos[i].driver);
    printf("(memory in MiB; * marks the device fractalbake chooses%s)\n", sel ? " for --device" : "");
    for (int i = 0; i < n; i++) {
        if (!infos[i].chosen) continue;
        if (!strcmp(infos[i].type, "cpu"))
            printf("--backend auto (the default): %s is a CPU implementation of Vulkan, so each layer runs where it\n"
                   "is faster on this machine: the native C path (fBm with its AVX2 loop, float Julia sets with\n"
                   "AVX2, other Julia sets below about 8 million samples or with turbulence, the chaos game,\n"
                   "L-systems, terrain, constraints), the device for the rest. --backend vulkan runs every layer\n"
                   "on it.\n",
                   infos[i].name);
        else
            printf("--backend auto (the default): every layer runs on %s.\n", infos[i].name);
    }
    free(infos);
    return 0;
}

static int run_command(int argc, char **argv);

/* The habits of other command lines, spelled the one way the commands read: --flag=value becomes
 * --flag value (the value may hold '='s: --set=layers.sky.c=0,1), -q is --quiet, `help CMD` is
 * CMD --help. A new argv; the strings are argv's own or the split copies (kept for the process). */
static char **g_args;  /* the normalised argv, freed when main returns */
static char **g_split; /* the "--flag" halves it allocated */
static int g_nsplit;

static void free_args(void)
{
    for (int i = 0; i < g_nsplit; i++) free(g_split[i]);
    free(g_split);
    free(g_args);
}

static char **normalise_args(int *argc, char **argv)
{
    char **out = g_args = calloc((size_t)*argc * 2 + 2, sizeof *out);
    g_split = calloc((size_t)*argc + 1, sizeof *g_split);
    if (!out || !g_split) {
        free(out), free(g_split);
        g_args = g_split = NULL;
        return argv;
    }
    int n = 0;
    for (int i = 0; i < *argc; i++) {
        const char *a = argv[i], *eq = strchr(a, '=');
        if (i == 1 && !strcmp(a, "help") && *argc > 2) { /* help CMD */
            out[n++] = argv[2];
            out[n++] = "--help";
            i = 2;
            continue;
        }
        if (i > 0 && !strcmp(a, "-q")) {
            out[n++] = "--quiet";
        } else if (i > 0 && !strncmp(a, "--", 2) && eq && eq > a + 2 && (out[n] = strndup(a, (size_t)(eq - a)))) {
            g_split[g_nsplit++] = out[n++];
            out[n++] = (char *)eq + 1;
        } else {
            out[n++] = argv[i];
        }
    }
    *argc = n;
    return out;
}

int main(int argc, char **argv)
{
    cli_start();
    fb_log_set_sink(sink, NULL);
    fb_progress_set_sink(&(fb_progress_sink){.terminal = isatty(STDERR_FILENO), .write = progress_sink});
    fb_env_read(&g_env);
    argv = normalise_args(&argc, argv);
    /* bench bakes to a scratch file again and again: each of its bakes is a transaction of its own */
    if (argc >= 2 && !strcmp(argv[1], "bench")) {
        int code = run_command(argc, argv);
        fb_result out = cli_stdout_finish();
        if (out && code == 0) code = finish(out);
        free_args();
        return code;
    }
    /* Every file the command writes is renamed into place here, together, or none is (output.h).
     * A comparison beyond threshold (1) still writes its diff pictures. */
    fb_outputs_begin();
    int code = run_command(argc, argv);
    g_first_error[0] = 0;
    fb_result rc = fb_outputs_end(code == 0 || code == 1 ? FB_OK : FB_ERR_INTERNAL);
    if (rc && (code == 0 || code == 1)) code = finish(rc);
    cli_after_flush(code == 0 || code == 1); /* "wrote ...": now that it is true */
    if (g_summary && code == 0) {            /* --json: the summary, now that the outputs are in place */
        const char *paths[FB_MAX_OUTPUTS], *whats[FB_MAX_OUTPUTS];
        uint64_t bytes[FB_MAX_OUTPUTS];
        int n = fb_outputs_written(paths, whats, bytes, FB_MAX_OUTPUTS);
        json_t *outs = json_array();
        for (int i = 0; i < n; i++)
            json_array_append_new(
                outs, json_pack("{sssssI}", "path", paths[i], "what", whats[i], "bytes", (json_int_t)bytes[i]));
        json_object_set_new(g_summary, "outputs", outs);
        char *text = fb_json_dumps(g_summary, 0);
        if (text) printf("%s\n", text);
        free(text);
    }
    json_decref(g_summary);
    g_first_error[0] = 0;
    fb_result out = cli_stdout_finish();
    if (out && (code == 0 || code == 1)) code = finish(out);
    free_args();
    return code;
}

/* tonemap's output path, for its summary line: the value of its -o (it refused a command without). */
static const char *tonemap_out(int argc, char **argv)
{
    for (int i = 0; i + 1 < argc; i++)
        if (!strcmp(argv[i], "-o") || !strcmp(argv[i], "--output")) return argv[i + 1];
    return "the output";
}

static int run_command(int argc, char **argv)
{
    if (argc < 2) {
        print_usage(stderr);
        return 2;
    }
    const char *cmd = argv[1];
    if (!strcmp(cmd, "--help") || !strcmp(cmd, "-h") || !strcmp(cmd, "help")) {
        print_usage(stdout);
        return 0;
    }
    if (!strcmp(cmd, "--version")) {
        printf("fractalbake %s\n", FB_VERSION);
        return 0;
    }
    if (!strcmp(cmd, "render")) return cmd_render(argc - 2, argv + 2);
    const fb_gen_class *gen = fb_gen_find(cmd);
    if (gen && gen->synopsis) return cmd_generator(gen->name, argc - 2, argv + 2);
    if (!strcmp(cmd, "tonemap")) {
        bool quiet = false, json = false, help = false;
        for (int i = 2; i < argc; i++) help = help || !strcmp(argv[i], "--help");
        double t0 = fb_now();
        fb_result rc = fb_tonemap_main(argc - 2, argv + 2, &quiet, &json);
        if (!rc && json && !help)
            json_object_set_new(summary_start("tonemap"), "seconds", json_real(fb_now() - t0));
        else if (!rc && !quiet && !help)
            cli_after("fractalbake: wrote %s (tone-mapped) in %.2f s", tonemap_out(argc - 2, argv + 2), fb_now() - t0);
        return finish(rc);
    }
    if (!strcmp(cmd, "compare")) return cmd_compare(argc - 2, argv + 2);
    if (!strcmp(cmd, "info")) return cmd_info(argc - 2, argv + 2);
    if (!strcmp(cmd, "merge")) return cmd_merge(argc - 2, argv + 2);
    if (!strcmp(cmd, "devices")) return cmd_devices(argc - 2, argv + 2);
    if (!strcmp(cmd, "scene")) return cmd_scene(argc - 2, argv + 2);
    if (!strcmp(cmd, "plan")) return cmd_plan(argc - 2, argv + 2);
    if (!strcmp(cmd, "generators")) return finish(fb_generators_main(argc - 2, argv + 2));
    if (!strcmp(cmd, "bench")) return finish(fb_bench_main(argc - 2, argv + 2, &g_env));
    return usage_error("%s: unknown command (see fractalbake --help)", cmd);
}
