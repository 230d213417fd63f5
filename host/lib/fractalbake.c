/*
 * libfractalbake (include/fractalbake.h): a context is an engine, an output transaction, a logger and a
 * progress sink of its own. Each call sets them as the calling thread's scope (fb.h) for its length
 * and puts the caller's scope back, so that nothing one context does is seen by another, nor by the
 * program around it.
 */
#include "fractalbake.h"

#include "bake.h"
#include "compare.h"
#include "engine.h"
#include "exrio.h"
#include "fb.h"
#include "output.h"
#include "progress.h"
#include "scene.h"

#include <errno.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

_Static_assert((int)FRACTALBAKE_ERR_CANCELLED == (int)FB_ERR_CANCELLED &&
                   (int)FRACTALBAKE_ERR_INPUT == (int)FB_ERR_INPUT &&
                   (int)FRACTALBAKE_ERR_INTERNAL == (int)FB_ERR_INTERNAL,
               "the API's codes are fb_result's");
_Static_assert((int)FRACTALBAKE_UINT == (int)EXRIO_UINT && (int)FRACTALBAKE_HALF == (int)EXRIO_HALF &&
                   (int)FRACTALBAKE_FLOAT == (int)EXRIO_FLOAT,
               "the API's types are exrio_type's");

struct fractalbake_context {
    atomic_int busy; /* a call is under way (check_call): another is refused, never waited for */
    fb_engine engine;
    bool open;
    fb_outputs *outputs;
    fb_logger log;
    fb_progress_sink progress;
    fractalbake_progress_fn fn;
    void *user;
    uint64_t max_memory;
    char tmpdir[PATH_MAX];
    char first[2048];      /* the first error of the call under way */
    char error[2048 + 16]; /* the last call's line */
    char device[256 + 32]; /* fractalbake_device */
};

/* The files a scene was read from (its own, and any its loading read): a bake notes them as its
 * inputs, so that no output of it replaces one (output.h). */
#define SCENE_INPUTS 16

struct fractalbake_scene {
    fb_scene scene;
    int ninputs;
    char *inputs[SCENE_INPUTS], *whats[SCENE_INPUTS];
};

struct fractalbake_image {
    exrio_reader *r;
};

int fractalbake_api(void)
{
    return FRACTALBAKE_API;
}

const char *fractalbake_version(void)
{
    return FB_VERSION;
}

/* The context's log: its first error is the call's line; warnings and the rest go nowhere. */
static void log_to(int level, const char *msg, void *user)
{
    fractalbake_context *ctx = user;
    if (level == FB_LOG_ERROR && !ctx->first[0]) snprintf(ctx->first, sizeof ctx->first, "%s", msg);
}

static int poll_to(double fraction, void *user)
{
    const fractalbake_context *ctx = user;
    return ctx->fn ? ctx->fn(fraction, ctx->user) : 0;
}

/* The context as the calling thread's scope, for one call; returns the scope it replaces. */
static fb_scope enter(fractalbake_context *ctx)
{
    ctx->first[0] = 0;
    return fb_scope_set((fb_scope){.log = &ctx->log, .outputs = ctx->outputs, .progress = &ctx->progress});
}

/* Puts the caller's scope back and keeps the call's line (main.c's, for the same failure). */
static int leave(fractalbake_context *ctx, fb_scope old, fb_result rc)
{
    fb_scope_set(old);
    atomic_store(&ctx->busy, 0);
    if (rc)
        snprintf(ctx->error, sizeof ctx->error, "fractalbake: %s", ctx->first[0] ? ctx->first : fb_result_string(rc));
    else
        ctx->error[0] = 0;
    return (int)rc;
}

/* ---- The boundary: every pointer, count and size an entry point takes, checked before anything is
 * done, with the command line's limits and words; and one call at a time on a context. ---- */

/* The line of a refusal made before the call's scope exists. */
static int refuse(fractalbake_context *ctx, int code, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static int refuse(fractalbake_context *ctx, int code, const char *fmt, ...)
{
    if (ctx) {
        va_list ap;
        va_start(ap, fmt);
        int k = snprintf(ctx->error, sizeof ctx->error, "fractalbake: ");
        vsnprintf(ctx->error + k, sizeof ctx->error - (size_t)k, fmt, ap);
        va_end(ap);
    }
    return code;
}

/* Takes the context for a call (fn: the entry point, for the message): a context runs one call at a
 * time, so a call made while another runs (from its progress callback, or on another thread) is
 * refused at once, never waited for (a callback would wait for itself). Released by leave(). */
static int check_call(fractalbake_context *ctx, const char *fn)
{
    if (!ctx) return FRACTALBAKE_ERR_USAGE;
    if (atomic_exchange(&ctx->busy, 1))
        return refuse(ctx, FRACTALBAKE_ERR_USAGE,
                      "%s: the context is running another call (this one came from its progress callback or "
                      "another thread): a context runs one call at a time",
                      fn);
    return FRACTALBAKE_OK;
}

/* A context's description: the command line's limits for --threads and --max-memory. */
static fb_result check_desc(const fractalbake_context_desc *d)
{
    if (!d) return fb_fail(FB_ERR_USAGE, "fractalbake_context_create: no description");
    if (d->api != FRACTALBAKE_API)
        return fb_fail(FB_ERR_USAGE, "fractalbake_context_create: API %d asked for, this library (%s) offers API %d",
                       d->api, FB_VERSION, FRACTALBAKE_API);
    if (d->threads < 0 || d->threads > 1024)
        return fb_fail(FB_ERR_USAGE, "threads %d: expected 0 (one per core) or 1..1024, as --threads", d->threads);
    if (d->max_memory != 0 && (d->max_memory < (1u << 20) || d->max_memory > (uint64_t)9e18))
        return fb_fail(FB_ERR_USAGE,
                       "max_memory %llu: expected 0 (80%% of the memory) or 1 MiB to 9e18 bytes, as --max-memory",
                       (unsigned long long)d->max_memory);
    if (d->tmpdir && strlen(d->tmpdir) >= PATH_MAX - 64)
        return fb_fail(FB_ERR_USAGE, "tmpdir %.60s...: path too long", d->tmpdir);
    return FB_OK;
}

/* A scene's overrides: nsets of them, none NULL. */
static fb_result check_sets(const char *const *sets, int nsets)
{
    if (nsets < 0 || nsets > 65536 || (nsets > 0 && !sets))
        return fb_fail(FB_ERR_USAGE, "fractalbake_scene_load: %d overrides and %s", nsets,
                       sets ? "at most 65536 are taken" : "no list of them");
    for (int i = 0; i < nsets; i++)
        if (!sets[i])
            return fb_fail(FB_ERR_USAGE, "fractalbake_scene_load: sets[%d] is NULL: expected KEY.PATH=VALUE, as --set",
                           i);
    return FB_OK;
}

/* A bake's scene, output path (NULL: into planes) and region: the output named for what the call
 * writes (OpenEXR, a file: the library writes no standard output), the region inside the image. */
static fb_result check_bake(const fractalbake_context *ctx, const fractalbake_scene *s, const char *fn,
                            const char *path, bool to_file, const int *region)
{
    if (!ctx->open) return fb_fail(FB_ERR_USAGE, "the context has no backend (its creation failed)");
    if (!s) return fb_fail(FB_ERR_USAGE, "%s: no scene", fn);
    if (to_file && (!path || !*path)) return fb_fail(FB_ERR_USAGE, "%s: no output path", fn);
    if (to_file && !strcmp(path, "-"))
        return fb_fail(FB_ERR_USAGE, "%s -: the library writes no standard output: name a file .exr", fn);
    fb_result rc = to_file ? fb_output_format(fn, path, ".exr") : FB_OK;
    if (rc || !region) return rc;
    if (region[0] < 0 || region[1] < 0 || region[2] < 1 || region[3] < 1 || region[2] > FB_MAX_DIM ||
        region[3] > FB_MAX_DIM)
        return fb_fail(FB_ERR_USAGE, "region %d,%d,%d,%d: expected X,Y >= 0 and W,H in 1..%d", region[0], region[1],
                       region[2], region[3], FB_MAX_DIM);
    if ((long)region[0] + region[2] > s->scene.width || (long)region[1] + region[3] > s->scene.height)
        return fb_fail(FB_ERR_USAGE, "region %d,%d,%d,%d: not inside the %d x %d image", region[0], region[1],
                       region[2], region[3], s->scene.width, s->scene.height);
    return FB_OK;
}

int fractalbake_context_create(const fractalbake_context_desc *d, fractalbake_context **out)
{
    if (!out) return FRACTALBAKE_ERR_USAGE;
    fractalbake_context *ctx = calloc(1, sizeof *ctx);
    *out = ctx;
    if (!ctx) return FRACTALBAKE_ERR_NOMEM;
    atomic_store(&ctx->busy, 1); /* leave() releases it */
    ctx->log = (fb_logger){log_to, ctx};
    ctx->progress = (fb_progress_sink){.poll = poll_to, .user = ctx};
    fb_scope old = enter(ctx);
    fb_result rc = check_desc(d);
    fb_backend backend = FB_BACKEND_AUTO;
    if (rc)
        ;
    else if (!d->backend || !strcmp(d->backend, "auto"))
        backend = FB_BACKEND_AUTO;
    else if (!strcmp(d->backend, "vulkan"))
        backend = FB_BACKEND_VULKAN;
    else if (!strcmp(d->backend, "native"))
        backend = FB_BACKEND_NATIVE;
    else
        rc = fb_fail(FB_ERR_USAGE, "backend \"%s\": expected auto, vulkan or native", d->backend);
    if (!rc) {
        ctx->max_memory = d->max_memory;
        snprintf(ctx->tmpdir, sizeof ctx->tmpdir, "%s", d->tmpdir && *d->tmpdir ? d->tmpdir : "/tmp");
        /* the transaction before the engine: it is what a scope names while the engine opens */
        rc = fb_outputs_create(&ctx->outputs);
    }
    if (!rc) {
        fb_scope_set((fb_scope){.log = &ctx->log, .outputs = ctx->outputs, .progress = &ctx->progress});
        rc = fb_engine_open(&(fb_engine_desc){.backend = backend, .device = d->device, .threads = d->threads},
                            &ctx->engine);
        ctx->open = rc == FB_OK;
    }
    if (ctx->open)
        snprintf(ctx->device, sizeof ctx->device, "%s",
                 ctx->engine.kind == FB_BACKEND_VULKAN ? ctx->engine.device : "native C");
    return leave(ctx, old, rc);
}

void fractalbake_context_destroy(fractalbake_context *ctx)
{
    if (!ctx || check_call(ctx, "fractalbake_context_destroy")) return; /* from its own callback: not now */
    fb_scope old = enter(ctx);
    if (ctx->open) fb_engine_close(&ctx->engine);
    fb_outputs_destroy(&ctx->outputs);
    fb_scope_set(old);
    free(ctx);
}

const char *fractalbake_error(const fractalbake_context *ctx)
{
    return ctx ? ctx->error : "fractalbake: out of memory";
}

const char *fractalbake_backend(const fractalbake_context *ctx)
{
    return ctx && ctx->open ? fb_backend_name(ctx->engine.kind) : "";
}

const char *fractalbake_device(const fractalbake_context *ctx)
{
    return ctx ? ctx->device : "";
}

void fractalbake_set_progress(fractalbake_context *ctx, fractalbake_progress_fn fn, void *user)
{
    if (!ctx) return;
    ctx->fn = fn;
    ctx->user = user;
}

/* Keeps the inputs noted while the scene loaded (its file and those its loading read). */
static fb_result scene_inputs(fractalbake_scene *s)
{
    const char *paths[SCENE_INPUTS], *whats[SCENE_INPUTS];
    int n = fb_inputs_noted(paths, whats, SCENE_INPUTS);
    for (int i = 0; i < n; i++) {
        s->inputs[i] = strdup(paths[i]);
        s->whats[i] = strdup(whats[i]);
        s->ninputs = i + 1;
        if (!s->inputs[i] || !s->whats[i]) return fb_fail(FB_ERR_NOMEM, "out of memory");
    }
    return FB_OK;
}

int fractalbake_scene_load(fractalbake_context *ctx, const char *text, const char *path, const char *const *sets,
                           int nsets, fractalbake_scene **out)
{
    int busy = check_call(ctx, "fractalbake_scene_load");
    if (busy) return busy;
    fb_scope old = enter(ctx);
    fb_result rc =
        out ? check_sets(sets, nsets) : fb_fail(FB_ERR_USAGE, "fractalbake_scene_load: no place for the scene");
    fractalbake_scene *s = rc ? NULL : calloc(1, sizeof *s);
    if (out) *out = NULL;
    if (!rc && !s) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    if (rc) return leave(ctx, old, rc);
    fb_outputs_begin(); /* the files read are noted, for the bakes to come (scene_inputs) */
    if (text)
        rc = fb_scene_parse_sets(text, "(scene text)", sets, nsets, &s->scene);
    else if (path)
        rc = fb_scene_load_sets(path, sets, nsets, &s->scene);
    else
        rc = fb_scene_parse_sets(fb_scene_default_json(), "(default scene)", sets, nsets, &s->scene);
    if (!rc) rc = scene_inputs(s);
    rc = fb_outputs_end(rc);
    if (rc)
        fractalbake_scene_destroy(s);
    else
        *out = s;
    return leave(ctx, old, rc);
}

void fractalbake_scene_destroy(fractalbake_scene *s)
{
    if (!s) return;
    fb_scene_fini(&s->scene);
    for (int i = 0; i < s->ninputs; i++) free(s->inputs[i]), free(s->whats[i]);
    free(s);
}

void fractalbake_scene_size(const fractalbake_scene *s, int *width, int *height)
{
    if (width) *width = s ? s->scene.width : 0;
    if (height) *height = s ? s->scene.height : 0;
}

const char *fractalbake_scene_json(const fractalbake_scene *s)
{
    return s ? s->scene.json : NULL;
}

/* One bake into path, in the context's transaction: every file in place together at the end, or none. */
static fb_result bake(fractalbake_context *ctx, const fractalbake_scene *s, const char *path, const int *region)
{
    fb_bake_desc d = {.scene = &s->scene, .out = path, .progress = ctx->fn != NULL, .max_memory = ctx->max_memory};
    if (region) memcpy(d.region, region, sizeof d.region);
    fb_bake_stats st;
    fb_result rc = FB_OK;
    fb_outputs_begin();
    for (int i = 0; i < s->ninputs && !rc; i++) rc = fb_input_note(s->inputs[i], s->whats[i], -1);
    if (!rc) rc = fb_bake(&ctx->engine, &d, &st);
    return fb_outputs_end(rc);
}

int fractalbake_bake(fractalbake_context *ctx, const fractalbake_scene *s, const char *path, const int *region)
{
    int busy = check_call(ctx, "fractalbake_bake");
    if (busy) return busy;
    fb_scope old = enter(ctx);
    fb_result rc = check_bake(ctx, s, "fractalbake_bake", path, true, region);
    return leave(ctx, old, rc ? rc : bake(ctx, s, path, region));
}

/* The file opened as an image. */
static fb_result open_image(const char *path, fractalbake_image **out)
{
    fractalbake_image *img = calloc(1, sizeof *img);
    if (!img) return fb_fail(FB_ERR_NOMEM, "out of memory");
    fb_result rc = exrio_open(path, &img->r);
    if (rc)
        free(img);
    else
        *out = img;
    return rc;
}

int fractalbake_render(fractalbake_context *ctx, const fractalbake_scene *s, const int *region, fractalbake_image **out)
{
    int busy = check_call(ctx, "fractalbake_render");
    if (busy) return busy;
    fb_scope old = enter(ctx);
    if (!out) return leave(ctx, old, fb_fail(FB_ERR_USAGE, "fractalbake_render: no place for the image"));
    *out = NULL;
    fb_result checked = check_bake(ctx, s, "fractalbake_render", NULL, false, region);
    if (checked) return leave(ctx, old, checked);
    /* The bake's file, in a folder of its own, open while the image lives and already unlinked: a
     * call that fails or a process that dies leaves at most the empty folder. */
    char dir[PATH_MAX], path[PATH_MAX + 16];
    fb_result rc = FB_OK;
    /* planes, not files: the scene without the files its layers would write besides the EXR */
    char *kept = NULL, dropped[1024];
    fractalbake_scene planes = {0};
    if (s) rc = fb_scene_drop_outputs(s->scene.json, &kept, dropped, sizeof dropped);
    if (!rc && s) rc = fb_scene_parse(kept, "(scene)", &planes.scene);
    free(kept);
    if (!rc && (snprintf(dir, sizeof dir, "%s/fractalbake-XXXXXX", ctx->tmpdir) >= (int)sizeof dir || !mkdtemp(dir)))
        rc = fb_fail(FB_ERR_IO, "%s: cannot make a folder for the bake's file: %s", ctx->tmpdir, strerror(errno));
    if (!rc) {
        snprintf(path, sizeof path, "%s/bake.exr", dir);
        rc = bake(ctx, s ? &planes : NULL, path, region);
        if (!rc) rc = open_image(path, out);
        unlink(path);
        rmdir(dir);
    }
    fb_scene_fini(&planes.scene);
    return leave(ctx, old, rc);
}

int fractalbake_open(fractalbake_context *ctx, const char *path, fractalbake_image **out)
{
    int busy = check_call(ctx, "fractalbake_open");
    if (busy) return busy;
    fb_scope old = enter(ctx);
    if (out) *out = NULL;
    fb_result rc = path && out ? open_image(path, out)
                               : fb_fail(FB_ERR_USAGE, "fractalbake_open: no path or no place for the image");
    return leave(ctx, old, rc);
}

void fractalbake_image_window(const fractalbake_image *img, int *x, int *y, int *width, int *height, int *full_width,
                              int *full_height)
{
    int x0 = 0, y0 = 0, fw = 0, fh = 0;
    if (img) exrio_window(img->r, &x0, &y0, &fw, &fh);
    if (x) *x = x0;
    if (y) *y = y0;
    if (width) *width = img ? exrio_width(img->r) : 0;
    if (height) *height = img ? exrio_height(img->r) : 0;
    if (full_width) *full_width = fw;
    if (full_height) *full_height = fh;
}

int fractalbake_image_channels(const fractalbake_image *img)
{
    return img ? exrio_nchannels(img->r) : 0;
}

const char *fractalbake_image_channel(const fractalbake_image *img, int c)
{
    return img && c >= 0 && c < exrio_nchannels(img->r) ? exrio_channel_name(img->r, c) : NULL;
}

int fractalbake_image_type(const fractalbake_image *img, int c)
{
    return img && c >= 0 && c < exrio_nchannels(img->r) ? (int)exrio_channel_type(img->r, c) : -1;
}

const char *fractalbake_image_attribute(const fractalbake_image *img, const char *name)
{
    return img && name ? exrio_attr_string(img->r, name) : NULL;
}

int fractalbake_image_read(fractalbake_context *ctx, fractalbake_image *img, void *const *planes)
{
    int busy = check_call(ctx, "fractalbake_image_read");
    if (busy) return busy;
    fb_scope old = enter(ctx);
    fb_result rc = img && planes ? exrio_read_rows(img->r, 0, exrio_height(img->r), planes)
                                 : fb_fail(FB_ERR_USAGE, "fractalbake_image_read: no image or no planes");
    return leave(ctx, old, rc);
}

void fractalbake_image_destroy(fractalbake_image *img)
{
    if (!img) return;
    exrio_close(&img->r);
    free(img);
}

/* The compare's text, line after line. */
typedef struct text {
    char *s;
    size_t n;
    bool nomem;
} text;

static void collect(const char *line, void *user)
{
    text *t = user;
    size_t k = strlen(line);
    char *grown = t->nomem ? NULL : realloc(t->s, t->n + k + 2);
    if (!grown) {
        t->nomem = true;
        return;
    }
    t->s = grown;
    memcpy(t->s + t->n, line, k);
    t->n += k;
    t->s[t->n++] = '\n';
    t->s[t->n] = 0;
}

int fractalbake_compare(fractalbake_context *ctx, const char *a, const char *b, const fractalbake_compare_desc *desc,
                        char **json, int *passed)
{
    int busy = check_call(ctx, "fractalbake_compare");
    if (busy) return busy;
    fb_scope old = enter(ctx);
    const fractalbake_compare_desc none = {0}, *c = desc ? desc : &none;
    text t = {0};
    fb_compare_desc d = {.a = a,
                         .b = b,
                         .layer = c->layer,
                         .json = true,
                         .flip = c->flip != 0,
                         .ignore_missing = c->ignore_missing != 0,
                         .print = collect,
                         .user = &t};
    struct {
        const char *flag, *value;
        fb_limit *limit;
    } lim[] = {{"--max-abs", c->max_abs, &d.fail}, {"--fail-percent", c->fail_percent, &d.failpercent},
               {"--warn", c->warn, &d.warn},       {"--warn-percent", c->warn_percent, &d.warnpercent},
               {"--rmse", c->rmse, &d.rmse},       {"--psnr", c->psnr, &d.psnr},
               {"--ssim", c->ssim, &d.ssim}};
    fb_result rc =
        !a || !b || !json ? fb_fail(FB_ERR_USAGE, "fractalbake_compare: two paths and a place for the result") : FB_OK;
    for (size_t i = 0; i < sizeof lim / sizeof lim[0] && !rc; i++)
        if (lim[i].value) rc = fb_limit_parse(lim[i].flag, lim[i].value, lim[i].limit);
    fb_verdict v = FB_VERDICT_FAIL;
    if (!rc) rc = fb_compare(&d, &v);
    if (!rc && t.nomem) rc = fb_fail(FB_ERR_NOMEM, "out of memory for the comparison's report");
    if (json) *json = rc ? NULL : t.s;
    if (rc) free(t.s);
    if (passed) *passed = !rc && v != FB_VERDICT_FAIL;
    return leave(ctx, old, rc);
}

void fractalbake_free(void *p)
{
    free(p);
}
