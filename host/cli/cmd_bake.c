/* The baking commands' shared options and the bake itself (cmd_bake.h). */
#include "cmd_bake.h"

#include "bake.h"
#include "cliout.h"
#include "exrio.h"
#include "faces.h"
#include "heightmap.h"
#include "output.h"
#include "plan.h"
#include "sequence.h"
#include "textin.h"

#include <stdlib.h>
#include <string.h>

fb_result fb_arg_seconds(const char *flag, const char *value, void *field)
{
    char *end;
    double v = strtod(value, &end);
    if (!*value || *end || !(v >= 0 && v <= 3600))
        return fb_fail(FB_ERR_USAGE, "%s: expected seconds in 0..3600, found \"%s\"", flag, value);
    *(double *)field = v;
    return FB_OK;
}

fb_result fb_arg_memory(const char *flag, const char *value, void *field)
{
    if (!fb_parse_memory(value, field))
        return fb_fail(FB_ERR_USAGE, "%s: expected a size such as 8G, 512M or 50%%, found \"%s\"", flag, value);
    return FB_OK;
}

bool fb_parse_region(const char *s, int r[4])
{
    long v[4];
    int used = 0;
    if (sscanf(s, "%ld,%ld,%ld,%ld%n", &v[0], &v[1], &v[2], &v[3], &used) != 4 || s[used]) return false;
    for (int i = 0; i < 4; i++)
        if (v[i] < (i < 2 ? 0 : 1) || v[i] > FB_MAX_DIM) return false;
    for (int i = 0; i < 4; i++) r[i] = (int)v[i];
    return true;
}

bool fb_parse_points_part(const char *s, int pp[2])
{
    const char *end;
    long long k, n;
    if (!fb_text_int(s, 1, 4096, &end, &k) || *end != '/' || !fb_text_int(end + 1, 1, 4096, NULL, &n) || k > n)
        return false;
    pp[0] = (int)k, pp[1] = (int)n;
    return true;
}

static fb_result arg_backend(const char *flag, const char *v, void *field)
{
    static const char *const names[] = {"auto", "vulkan", "native"};
    static const fb_backend backends[] = {FB_BACKEND_AUTO, FB_BACKEND_VULKAN, FB_BACKEND_NATIVE};
    for (int k = 0; k < 3; k++)
        if (!strcmp(v, names[k])) return *(fb_backend *)field = backends[k], FB_OK;
    return fb_fail(FB_ERR_USAGE, "%s: expected auto, vulkan or native, found \"%s\"", flag, v);
}

static fb_result arg_region(const char *flag, const char *v, void *field)
{
    if (!fb_parse_region(v, field))
        return fb_fail(FB_ERR_USAGE, "%s: expected X,Y,W,H (integers, W and H >= 1), found \"%s\"", flag, v);
    return FB_OK;
}

static fb_result arg_points_part(const char *flag, const char *v, void *field)
{
    if (!fb_parse_points_part(v, field))
        return fb_fail(FB_ERR_USAGE, "%s: expected K/N with 1 <= K <= N <= 4096, found \"%s\"", flag, v);
    return FB_OK;
}

static fb_result arg_task(const char *flag, const char *v, void *field)
{
    char *end;
    long k = strtol(v, &end, 10), n = *end == '/' ? strtol(end + 1, &end, 10) : 0;
    if (!*v || *end || k < 0 || n < 1 || k >= n || n > FB_PLAN_MAX_TASKS)
        return fb_fail(
            FB_ERR_USAGE,
            "%s: expected K/N with 0 <= K < N <= %d (K counts from 0, like SLURM_ARRAY_TASK_ID), found \"%s\"", flag,
            FB_PLAN_MAX_TASKS, v);
    int *t = field;
    t[0] = (int)k, t[1] = (int)n;
    return FB_OK;
}

#define OPT(f) offsetof(fb_bake_opts, f)
const fb_arg fb_bake_flags[] = {
    {FB_ARG_OUTPUT, "--output", "-o", OPT(out), .ext = ".exr"},
    {FB_ARG_OUTPUT, "--preview", NULL, OPT(preview), .ext = ".png"},
    {FB_ARG_STRING, "--preview-layer", NULL, OPT(preview_layer)},
    {FB_ARG_STRING, "--cube-faces", NULL, OPT(cube_faces)},
    {FB_ARG_STRING, "--device", NULL, OPT(device)},
    {FB_ARG_VALUE, "--backend", NULL, OPT(backend), .parse = arg_backend},
    {FB_ARG_INT, "--threads", NULL, OPT(threads), 1, 1024},
    {FB_ARG_INT, "--strip-rows", NULL, OPT(strip_rows), 1, FB_MAX_DIM},
    {FB_ARG_VALUE, "--region", NULL, OPT(region), .parse = arg_region},
    {FB_ARG_VALUE, "--points-part", NULL, OPT(points_part), .parse = arg_points_part},
    {FB_ARG_VALUE, "--task", NULL, OPT(task), .parse = arg_task},
    {FB_ARG_VALUE, "--task-startup", NULL, OPT(task_startup), .parse = fb_arg_seconds},
    {FB_ARG_VALUE, "--max-memory", NULL, OPT(max_memory), .parse = fb_arg_memory},
    {FB_ARG_INT, "--zip-level", NULL, OPT(zip_level), 1, EXRIO_ZIP_LEVEL_MAX},
    {FB_ARG_BOOL, "--dry-run", NULL, OPT(dry_run)},
    {FB_ARG_BOOL, "--quiet", NULL, OPT(quiet)},
    {FB_ARG_DOCUMENT, "--json", NULL, OPT(json)},
    {FB_ARG_BOOL, "--validation", NULL, OPT(validation)},
    {FB_ARG_BOOL, "--help", "-h", OPT(help)},
    {FB_ARG_END},
};
#undef OPT

void fb_bake_opts_init(fb_bake_opts *o)
{
    o->task_startup = -1;
}

typedef struct bake_ctx {
    const fb_cli *cli;
    const fb_bake_opts *o;
} bake_ctx;

static void report(const char *layer, const char *summary, const char *json, void *user)
{
    const bake_ctx *c = user;
    if (c->o->json) { /* into the layer's entry of the summary */
        json_t *layers = json_object_get(*c->cli->summary, "layers"), *l;
        size_t i;
        json_array_foreach(layers, i, l) if (!strcmp(json_string_value(json_object_get(l, "name")), layer))
            json_object_set_new(l, "summary", json_loads(json, 0, NULL));
    } else if (!c->o->quiet) {
        cli_after("fractalbake: %s", summary);
    }
}

/* --dry-run: the predicted peak memory, per layer and in all, on stdout. */
static void print_plan(const fb_bake_plan *p, bool json)
{
    char a[32], b[32];
    if (json) {
        printf("{\"peak_bytes\": %llu, \"planned_bytes\": %llu, \"limit_bytes\": %llu, \"base_bytes\": %llu, "
               "\"pieces_bytes\": %llu, "
               "\"writer_bytes\": %llu, \"preview_bytes\": %llu, \"device_bytes\": %llu, \"compile_bytes\": %llu, "
               "\"piece_rows\": %d, \"pieces_in_flight\": %d, \"layers\": [",
               (unsigned long long)p->peak, (unsigned long long)p->planned, (unsigned long long)p->limit,
               (unsigned long long)p->base, (unsigned long long)p->pieces, (unsigned long long)p->writer,
               (unsigned long long)p->preview, (unsigned long long)p->device, (unsigned long long)p->compile,
               p->piece_rows, p->slots);
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
    if (p->compile) {
        fb_format_bytes(p->compile, a, sizeof a);
        printf("%-26s %12s  (before the pieces: at most one of the two at once)\n", "shader compile (CPU)", a);
    }
    fb_format_bytes(p->pieces, a, sizeof a);
    printf("%-26s %12s  (%d pieces of %d rows in flight)\n", "pieces", a, p->slots, p->piece_rows);
    fb_format_bytes(p->writer, a, sizeof a);
    printf("%-26s %12s\n", "EXR writer queue", a);
    if (p->preview) {
        fb_format_bytes(p->preview, a, sizeof a);
        printf("%-26s %12s\n", "preview", a);
    }
    fb_format_bytes(p->peak, a, sizeof a);
    fb_format_bytes(p->limit, b, sizeof b);
    printf("%-26s %12s  (--max-memory %s%s)\n", "predicted peak", a, b,
           p->peak > p->limit ? ": more than it, so the bake would be refused" : "");
    if (p->peak != p->planned) {
        fb_format_bytes(p->planned, a, sizeof a);
        printf("%-26s %12s  (the ring shrunk to %d pieces to fit --max-memory)\n", "with every piece in flight", a,
               p->slots);
    }
    if (p->device) {
        fb_format_bytes(p->device, a, sizeof a);
        printf("%-26s %12s  (the GPU's own memory, besides the peak)\n", "device memory", a);
    }
}

static const char *heightmap_format_name(int f)
{
    return f == FB_HEIGHTMAP_PNG16   ? "16-bit grey PNG"
           : f == FB_HEIGHTMAP_RAW16 ? "16-bit little-endian raw"
                                     : "float GeoTIFF";
}

/* Whether a part of the scene's file is ZIP-compressed (what --zip-level tunes). */
static bool scene_has_zip(const fb_scene *scene)
{
    if (!scene->multipart) return scene->compression == EXRIO_ZIP;
    for (int i = 0; i < scene->nlayers; i++)
        if (scene->layers[i].compression == EXRIO_ZIP) return true;
    return false;
}

/* Flags that would change nothing in this bake: refused rather than ignored. */
static fb_result check_no_effect(const fb_scene *scene, const fb_bake_opts *o)
{
    if (o->backend == FB_BACKEND_NATIVE && (o->device || o->validation))
        return fb_fail(FB_ERR_USAGE,
                       "%s: only with --backend vulkan or auto (this bake runs natively%s, which opens no Vulkan "
                       "device)",
                       o->device ? "--device" : "--validation", o->backend_from ? ", as the --from file was" : "");
    if (o->zip_level && !scene_has_zip(scene))
        return fb_fail(FB_ERR_USAGE,
                       "--zip-level %d: no part of this file is ZIP-compressed (compression %s), so the level "
                       "would change nothing",
                       o->zip_level,
                       scene->multipart ? "per layer, none zip" : exrio_compression_name(scene->compression));
    return FB_OK;
}

/* Options that cannot go together, before anything is baked. */
static fb_result check_options(const fb_scene *scene, const fb_bake_opts *o)
{
    fb_result rc = check_no_effect(scene, o);
    if (rc) return rc;
    if (o->preview_layer && !o->preview)
        return fb_fail(FB_ERR_USAGE,
                       "--preview-layer %s: only with --preview FILE.png (there is no preview to show it)",
                       o->preview_layer);
    if (o->points_part[1] > 0) {
        bool chaos = false;
        for (int i = 0; i < scene->nlayers; i++) chaos = chaos || scene->layers[i].cls->share == FB_SHARE_POINTS;
        if (!chaos) return fb_fail(FB_ERR_USAGE, "--points-part: the scene has no chaos-game layer to split by points");
        if (o->region[2] > 0)
            return fb_fail(FB_ERR_USAGE, "--points-part: not with --region (split a bake by pixels or by points)");
    }
    if (o->cube_faces) {
        char names[6][FB_FACES_PATH];
        fb_result rc = fb_faces_paths(o->cube_faces, names);
        if (rc) return rc;
        if (scene->envmap != EXRIO_ENVMAP_CUBE)
            return fb_fail(FB_ERR_USAGE,
                           "--cube-faces: the scene is %s, not a cube environment map (\"mapping\": \"cube\")",
                           scene->envmap == EXRIO_ENVMAP_LATLONG ? "a lat-long environment map" : "a plane");
        const char *clash = o->region[2]        ? "--region"
                            : o->task[1]        ? "--task"
                            : o->points_part[1] ? "--points-part"
                            : o->dry_run        ? "--dry-run"
                                                : NULL;
        if (clash) return fb_fail(FB_ERR_USAGE, "--cube-faces: not with %s (a face set is the whole cube)", clash);
    }
    if (o->task_startup >= 0 && !o->task[1])
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
    }
    return FB_OK;
}

/* render --task K/N: the plan's share K, as a scene of its layers only (*sub), the options that bake
 * that share (*ot), the attributes the task file records and its description. *idle: the plan gives
 * this task nothing. */
typedef struct task_share {
    fb_scene *sub;
    fb_plan *plan;
    char *plan_json, attr[32], share[2048];
    exrio_attr attrs[2];
    fb_bake_opts ot;
    bool idle;
} task_share;

static fb_result task_make(const fb_scene *scene, const fb_bake_opts *o, task_share *ts)
{
    ts->ot = *o;
    if (!(ts->plan = malloc(sizeof *ts->plan)) || !(ts->sub = calloc(1, sizeof *ts->sub)))
        return fb_fail(FB_ERR_NOMEM, "out of memory");
    fb_result rc = fb_plan_make(scene, o->task[1], o->task_startup, ts->plan);
    if (rc) return rc;
    if (o->task[0] >= ts->plan->nactive) return ts->idle = true, FB_OK;
    const fb_task *t = &ts->plan->tasks[o->task[0]];
    if ((rc = fb_scene_subset(scene, t->layers, ts->sub))) return rc;
    if (!(ts->plan_json = fb_plan_json(scene, ts->plan, false))) return fb_fail(FB_ERR_NOMEM, "out of memory");
    fb_plan_describe(scene, t, ts->share, sizeof ts->share);
    if (t->band)
        ts->ot.region[0] = 0, ts->ot.region[1] = t->y0, ts->ot.region[2] = scene->width,
        ts->ot.region[3] = t->y1 - t->y0;
    if (t->points) ts->ot.points_part[0] = t->part, ts->ot.points_part[1] = t->nparts;
    snprintf(ts->attr, sizeof ts->attr, "%d/%d", o->task[0], o->task[1]);
    ts->attrs[0] = (exrio_attr){"fractalbake/task", ts->attr};
    ts->attrs[1] = (exrio_attr){"fractalbake/plan", ts->plan_json};
    return FB_OK;
}

static void task_free(task_share *ts)
{
    if (ts->sub) fb_scene_fini(ts->sub);
    free(ts->sub);
    free(ts->plan);
    free(ts->plan_json);
}

/* --json: what the bake did, into the summary main prints after the commit. */
static void summary_json(json_t *sum, const fb_scene *scene, const fb_bake_opts *o, const fb_bake_stats *st,
                         const char *device)
{
    json_object_set_new(sum, "size", json_pack("[ii]", scene->width, scene->height));
    if (o->region[2])
        json_object_set_new(sum, "region", json_pack("[iiii]", o->region[0], o->region[1], o->region[2], o->region[3]));
    json_object_set_new(sum, "seconds", json_real(st->seconds));
    /* the device's own time: its dispatches' timestamps, summed (none where nothing ran on it) */
    if (st->gpu_seconds > 0) json_object_set_new(sum, "gpu_seconds", json_real(st->gpu_seconds));
    json_object_set_new(sum, "backend", json_string(fb_backend_name(o->backend))); /* as fractalbake/backend */
    bool any_vk = false; /* "device": the Vulkan device where a layer ran on it, else native C */
    for (int i = 0; i < scene->nlayers; i++) any_vk = any_vk || st->layer_backend[i] == FB_BACKEND_VULKAN;
    json_object_set_new(sum, "device", json_string(any_vk ? device : "native C"));
    if (st->preview[0]) json_object_set_new(sum, "preview", json_string(st->preview));
    json_t *hms = json_array();
    for (int i = 0; i < st->nheightmaps; i++) {
        const fb_bake_heightmap *h = &st->heightmaps[i];
        json_t *j =
            json_pack("{ssssss}", "layer", h->layer, "path", h->path, "format", heightmap_format_name(h->format));
        if (h->format != FB_HEIGHTMAP_GEOTIFF) {
            json_object_set_new(j, "height_at_0", json_real(h->lo));
            json_object_set_new(j, "height_at_65535", json_real(h->hi));
        }
        if (h->sidecar) json_object_set_new(j, "sidecar", json_string(h->sidecar));
        if (h->tiles[0]) {
            json_t *files = json_array();
            for (int t = 0; t < h->tiles[0] * h->tiles[1]; t++)
                json_array_append_new(files, json_string(h->tile_paths + (size_t)t * FB_TILE_PATH));
            json_object_set_new(j, "tiles", json_pack("[ii]", h->tiles[0], h->tiles[1]));
            json_object_set_new(j, "tile_files", files);
        }
        json_array_append_new(hms, j);
    }
    if (st->nheightmaps)
        json_object_set_new(sum, "heightmaps", hms);
    else
        json_decref(hms);
    json_t *layers = json_object_get(sum, "layers");
    for (int i = 0; i < scene->nlayers; i++) {
        json_t *l = json_array_get(layers, (size_t)i);
        json_object_set_new(l, "backend", json_string(fb_backend_name(st->layer_backend[i])));
        json_object_set_new(l, "device", json_string(st->layer_backend[i] == FB_BACKEND_VULKAN ? device : "native C"));
    }
}

/* The lines printed once the outputs are in place. */
static void summary_text(const fb_scene *scene, const fb_bake_opts *o, const fb_bake_stats *st, const char *share)
{
    if (o->task[1] > 0) cli_after("fractalbake: task %d/%d: %s", o->task[0], o->task[1], share);
    cli_after("fractalbake: wrote %s (%d x %d%s, %d layer%s) in %.2f s %s",
              strcmp(o->out, "-") ? o->out : "standard output", o->region[2] ? o->region[2] : scene->width,
              o->region[2] ? o->region[3] : scene->height, o->region[2] ? " region" : "", scene->nlayers,
              scene->nlayers == 1 ? "" : "s", st->seconds, st->ran_on);
    if (st->preview[0]) cli_after("fractalbake: preview %s: %s", o->preview, st->preview);
    for (int i = 0; i < st->nheightmaps; i++) {
        const fb_bake_heightmap *h = &st->heightmaps[i];
        char lo[40], hi[40];
        fb_format_shortest(h->lo, lo, sizeof lo);
        fb_format_shortest(h->hi, hi, sizeof hi);
        if (h->format == FB_HEIGHTMAP_GEOTIFF)
            cli_after("fractalbake: heightmap %s: layer %s's heights as float, with its geotransform", h->path,
                      h->layer);
        else if (h->tiles[0]) { /* the tiles named 0, 0 and last by the engine's convention */
            char first[FB_TILE_PATH], last[FB_TILE_PATH];
            int cols = h->tiles[0], rows = h->tiles[1], unity = h->engine == FB_ENGINE_UNITY;
            fb_heightmap_tile_path(h->path, h->engine, 0, unity ? rows - 1 : 0, rows, first, sizeof first);
            fb_heightmap_tile_path(h->path, h->engine, cols - 1, unity ? 0 : rows - 1, rows, last, sizeof last);
            cli_after("fractalbake: heightmap %s to %s: %d x %d tiles of %d x %d sharing their edges, layer %s's "
                      "heights %s (0) to %s (65535) in every one, %s",
                      first, last, cols, rows, (scene->width - 1) / cols + 1, (scene->height - 1) / rows + 1, h->layer,
                      lo, hi, heightmap_format_name(h->format));
        } else
            cli_after("fractalbake: heightmap %s: layer %s's heights %s (0) to %s (65535), %s", h->path, h->layer, lo,
                      hi, heightmap_format_name(h->format));
        if (h->sidecar) cli_after("fractalbake: heightmap %s: the engine's import settings", h->sidecar);
    }
}

static fb_result bake_once(const fb_cli *cli, const char *command, fb_scene *scene, const fb_bake_opts *o)
{
    fb_result rc = check_options(scene, o);
    if (rc) return rc;
    json_t *sum = NULL;
    if (o->json && !o->dry_run) {
        json_t *layers = json_array();
        sum = fb_cli_summary(cli, command);
        for (int i = 0; i < scene->nlayers; i++)
            json_array_append_new(
                layers, json_pack("{ssss}", "name", scene->layers[i].name, "type", scene->layers[i].cls->name));
        json_object_set_new(sum, "layers", layers);
    }
    task_share ts = {0};
    if (o->task[1] > 0) {
        if ((rc = task_make(scene, o, &ts))) goto done;
        if (ts.idle) {
            if (o->json)
                json_object_set_new(sum, "task",
                                    json_pack("{sisisb}", "index", o->task[0], "of", o->task[1], "idle", 1));
            else if (!o->quiet)
                fprintf(stderr,
                        "fractalbake: task %d/%d has nothing to do: the plan gives this bake to tasks 0-%d "
                        "(`fractalbake plan --tasks %d`); no file written\n",
                        o->task[0], o->task[1], ts.plan->nactive - 1, o->task[1]);
            goto done;
        }
        scene = ts.sub;
        o = &ts.ot;
        if (o->json)
            json_object_set_new(sum, "task",
                                json_pack("{sisiss}", "index", o->task[0], "of", o->task[1], "share", ts.share));
    }
    fb_engine e;
    if (o->backend != FB_BACKEND_NATIVE) fb_env_lavapipe_threads(o->threads);
    rc = fb_engine_open(&(fb_engine_desc){.backend = o->backend,
                                          .device = o->device,
                                          .threads = o->threads,
                                          .validation = o->validation,
                                          .vk_options = cli->env->vk},
                        &e);
    if (rc) goto done;
    fb_bake_stats st;
    fb_bake_plan plan;
    bake_ctx ctx = {cli, o};
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
                                 .max_memory = o->max_memory,
                                 .report = report,
                                 .user = &ctx,
                                 .attrs = ts.attrs,
                                 .nattrs = o->task[1] > 0 ? 2 : 0,
                                 .layer_backends = o->task[1] > 0,
                                 .cube_faces = o->cube_faces,
                                 .layer_kinds = o->layer_kinds},
                 &st);
    if (!rc && o->dry_run)
        print_plan(&plan, o->json);
    else if (!rc && o->json)
        summary_json(sum, scene, o, &st, e.device);
    else if (!rc && !o->quiet)
        summary_text(scene, o, &st, ts.share);
    fb_engine_close(&e);
done:
    task_free(&ts);
    return rc;
}

/* Frame f of a sequence as a bake of its own, committed when done: its own transaction, so that the
 * frames finished stay when a later one fails or the run is stopped. */
static fb_result bake_frame(const fb_cli *cli, const char *command, const char *json, const fb_bake_opts *fo)
{
    fb_outputs *tx = NULL;
    fb_result rc = fb_outputs_create(&tx);
    if (rc) return rc;
    fb_scope old = fb_scope_get(), frame = old;
    frame.outputs = tx;
    fb_scope_set(frame);
    fb_outputs_begin();
    fb_scene fs = {0};
    rc = fb_scene_parse(json, NULL, &fs);
    if (!rc) rc = bake_once(cli, command, &fs, fo);
    fb_scene_fini(&fs);
    rc = fb_outputs_end(rc);
    fb_scope_set(old);
    fb_outputs_destroy(&tx);
    return rc;
}

/* The frames' paths and stored scenes (what each would be), this task's share of them. Each frame
 * already there with the same scene is skipped; one there with another is refused before any is
 * baked. */
static fb_result bake_sequence(const fb_cli *cli, const char *command, fb_scene *scene, const fb_bake_opts *o,
                               const fb_frames *fr)
{
    if (o->json || o->dry_run || o->region[2] || o->points_part[1])
        return fb_fail(FB_ERR_USAGE,
                       "-o %s: a sequence of frames is baked whole: no --json, --dry-run, --region or "
                       "--points-part",
                       o->out);
    long i0 = 0, i1 = fb_frames_count(fr);
    if (o->task[1] > 0) fb_frames_share(fr, o->task[0], o->task[1], &i0, &i1); /* a task of a cluster's array */
    fb_result rc = FB_OK;
    long todo = 0, skip = 0;
    char **json = calloc((size_t)(i1 - i0 + 1), sizeof *json);
    if (!json) return fb_fail(FB_ERR_NOMEM, "out of memory");
    for (long i = i0; i < i1 && !rc; i++) {
        long f = fr->first + i * fr->step;
        char path[4096], *text = NULL;
        fb_scene fs = {0};
        bool done = false;
        fb_frame_path(o->out, f, path, sizeof path);
        rc = fb_frame_scene_json(scene, f, &text);
        if (!rc) rc = fb_scene_parse(text, NULL, &fs);
        free(text);
        if (!rc) rc = fb_frame_done(path, fs.json, &done);
        if (!rc && !done && !(json[i - i0] = strdup(fs.json))) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
        fb_scene_fini(&fs);
        done ? skip++ : todo++;
    }
    if (!rc && !o->quiet && skip)
        fprintf(stderr, "fractalbake: %ld of %ld frames are there from the same scene: kept\n", skip, i1 - i0);
    long at = 0;
    for (long i = i0; i < i1 && !rc; i++) {
        if (!json[i - i0]) continue;
        long f = fr->first + i * fr->step;
        char path[4096], preview[4096];
        fb_bake_opts fo = *o;
        fb_frame_path(o->out, f, path, sizeof path);
        fo.out = path, fo.task[0] = fo.task[1] = 0;
        if (o->preview) fb_frame_path(o->preview, f, preview, sizeof preview), fo.preview = preview;
        if (!o->quiet) fprintf(stderr, "fractalbake: frame %ld (%ld of %ld): %s\n", f, ++at, todo, path);
        rc = bake_frame(cli, command, json[i - i0], &fo);
    }
    for (long i = 0; i < i1 - i0; i++) free(json[i]);
    free(json);
    return rc;
}

fb_result fb_cli_bake(const fb_cli *cli, const char *command, fb_scene *scene, const fb_bake_opts *o)
{
    bool seq = false, pseq = false;
    fb_result rc = o->out ? fb_frame_pattern("-o", o->out, &seq) : FB_OK;
    if (!rc && o->preview) rc = fb_frame_pattern("--preview", o->preview, &pseq);
    if (rc) return rc;
    bool ft = false;
    fb_frames fr;
    if ((rc = fb_scene_frames(scene, &ft, &fr))) return rc;
    if (seq && !ft)
        return fb_fail(FB_ERR_USAGE,
                       "-o %s: a sequence needs its frames (--frames A-B[:STEP], or the scene key frames)", o->out);
    if (!seq && ft)
        return fb_fail(FB_ERR_USAGE, "frames: a sequence writes a file a frame: -o NAME.%%04d.exr (a frame number in "
                                     "the name)");
    if (seq != pseq && o->preview)
        return fb_fail(FB_ERR_USAGE, "--preview %s: %s", o->preview,
                       seq ? "a sequence's previews need a frame number too (NAME.%04d.png)"
                           : "a frame number in the preview's name needs one in -o's");
    return seq ? bake_sequence(cli, command, scene, o, &fr) : bake_once(cli, command, scene, o);
}
