/*
 * libfractalbake through its installed header alone (linked to the shared library): a bake into
 * planes and into a file equal `fractalbake render` bit for bit; a region is the full bake's pixels;
 * errors are the command line's line; a progress callback sees the fraction grow and can cancel,
 * leaving no file; two contexts on two backends at once on two threads give their own results and
 * errors.
 *   test_library FRACTALBAKE_PROGRAM
 * Exit 77 where the Vulkan part cannot run (no device): the native parts have run by then.
 */
#include "fractalbake.h"

#include <dirent.h>
#include <pthread.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

static int g_fail;
#define CHECK(cond, ...)                                                                                               \
    do {                                                                                                               \
        if (!(cond)) {                                                                                                 \
            fprintf(stderr, "FAIL %s:%d: ", __FILE__, __LINE__);                                                       \
            fprintf(stderr, __VA_ARGS__);                                                                              \
            fputc('\n', stderr);                                                                                       \
            g_fail++;                                                                                                  \
        }                                                                                                              \
    } while (0)

static const char *g_cli;
static char g_dir[64];
static const char *const k_small[] = {"size=96x48"};

/* Every channel of an image: names, types and samples. */
typedef struct planes {
    int n, x, y, w, h;
    char names[64][64];
    int types[64];
    uint32_t *data[64];
} planes;

static void planes_free(planes *p)
{
    for (int c = 0; c < p->n; c++) free(p->data[c]);
    memset(p, 0, sizeof *p);
}

static int read_image(fractalbake_context *ctx, fractalbake_image *img, planes *p)
{
    memset(p, 0, sizeof *p);
    p->n = fractalbake_image_channels(img);
    if (p->n > 64) return -1;
    fractalbake_image_window(img, &p->x, &p->y, &p->w, &p->h, NULL, NULL);
    for (int c = 0; c < p->n; c++) {
        snprintf(p->names[c], sizeof p->names[c], "%s", fractalbake_image_channel(img, c));
        p->types[c] = fractalbake_image_type(img, c);
        p->data[c] = malloc((size_t)p->w * p->h * 4);
    }
    return fractalbake_image_read(ctx, img, (void *const *)p->data);
}

static int open_planes(fractalbake_context *ctx, const char *path, planes *p)
{
    fractalbake_image *img = NULL;
    int rc = fractalbake_open(ctx, path, &img);
    if (!rc) rc = read_image(ctx, img, p);
    fractalbake_image_destroy(img);
    return rc;
}

/* Whether b is a's pixels at (dx, dy) of a, every channel with the same name, type and bits. */
static bool same(const planes *a, const planes *b, int dx, int dy, const char *what)
{
    if (a->n != b->n || a->n == 0) {
        fprintf(stderr, "%s: %d channels against %d\n", what, a->n, b->n);
        return false;
    }
    for (int c = 0; c < a->n; c++) {
        if (strcmp(a->names[c], b->names[c]) || a->types[c] != b->types[c]) {
            fprintf(stderr, "%s: channel %d: %s (%d) against %s (%d)\n", what, c, a->names[c], a->types[c], b->names[c],
                    b->types[c]);
            return false;
        }
        for (int y = 0; y < b->h; y++)
            if (memcmp(a->data[c] + (size_t)(y + dy) * a->w + dx, b->data[c] + (size_t)y * b->w, (size_t)b->w * 4)) {
                fprintf(stderr, "%s: channel %s differs in row %d\n", what, a->names[c], y);
                return false;
            }
    }
    return true;
}

/* Runs the command line; its exit code, its stderr's first line in err. */
static int cli(const char *args, char *err, size_t size)
{
    char cmd[2048], errpath[128];
    snprintf(errpath, sizeof errpath, "%s/cli.err", g_dir);
    snprintf(cmd, sizeof cmd, "'%s' %s 2>'%s'", g_cli, args, errpath);
    int st = system(cmd);
    if (err) {
        err[0] = 0;
        FILE *f = fopen(errpath, "r");
        if (f && fgets(err, (int)size, f)) err[strcspn(err, "\n")] = 0;
        if (f) fclose(f);
    }
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

static fractalbake_context *context(const char *backend)
{
    fractalbake_context *ctx = NULL;
    int rc = fractalbake_context_create(
        &(fractalbake_context_desc){.api = FRACTALBAKE_API, .backend = backend, .threads = 2, .tmpdir = g_dir}, &ctx);
    if (rc) {
        fprintf(stderr, "context %s: %s\n", backend, fractalbake_error(ctx));
        fractalbake_context_destroy(ctx);
        return NULL;
    }
    return ctx;
}

/* The progress callback's record. */
typedef struct seen {
    int calls, stop_at;
    double last;
    bool monotone;
} seen;

static int on_progress(double f, void *user)
{
    seen *s = user;
    s->monotone = s->monotone && f >= s->last && f >= 0 && f <= 1;
    s->last = f;
    return ++s->calls >= s->stop_at && s->stop_at > 0;
}

/* The default scene, small, native: in planes, in a file, a region; against the command line's file. */
static void test_native(void)
{
    fractalbake_context *ctx = context("native");
    if (!ctx) {
        g_fail++;
        return;
    }
    CHECK(!strcmp(fractalbake_backend(ctx), "native"), "backend %s", fractalbake_backend(ctx));
    CHECK(fractalbake_api() == FRACTALBAKE_API, "api %d", fractalbake_api());
    char path[256], args[512];
    snprintf(path, sizeof path, "%s/cli.exr", g_dir);
    snprintf(args, sizeof args, "render -q --backend native --threads 2 --set %s -o '%s'", k_small[0], path);
    CHECK(cli(args, NULL, 0) == 0, "%s failed", args);
    planes want = {0}, got = {0}, file = {0}, part = {0};
    CHECK(open_planes(ctx, path, &want) == 0, "open %s: %s", path, fractalbake_error(ctx));
    CHECK(want.w == 96 && want.h == 48 && want.n >= 20, "the CLI's file: %d x %d, %d channels", want.w, want.h, want.n);

    fractalbake_scene *scene = NULL;
    CHECK(fractalbake_scene_load(ctx, NULL, NULL, k_small, 1, &scene) == 0, "%s", fractalbake_error(ctx));
    int w = 0, h = 0;
    if (scene) fractalbake_scene_size(scene, &w, &h);
    CHECK(w == 96 && h == 48, "scene size %d x %d", w, h);
    seen s = {.monotone = true};
    fractalbake_set_progress(ctx, on_progress, &s);
    fractalbake_image *img = NULL;
    CHECK(fractalbake_render(ctx, scene, NULL, &img) == 0, "render: %s", fractalbake_error(ctx));
    CHECK(!strcmp(fractalbake_error(ctx), ""), "error after success: %s", fractalbake_error(ctx));
    CHECK(s.calls >= 1 && s.monotone && s.last == 1.0, "progress: %d calls, last %g, monotone %d", s.calls, s.last,
          s.monotone);
    if (img) CHECK(read_image(ctx, img, &got) == 0, "read: %s", fractalbake_error(ctx));
    CHECK(img && !strcmp(fractalbake_image_attribute(img, "fractalbake/backend"), "native"), "backend attribute");
    fractalbake_image_destroy(img);
    CHECK(same(&want, &got, 0, 0, "planes against the CLI"), "the planes differ from fractalbake render's file");

    snprintf(path, sizeof path, "%s/lib.exr", g_dir);
    CHECK(fractalbake_bake(ctx, scene, path, NULL) == 0, "bake: %s", fractalbake_error(ctx));
    CHECK(open_planes(ctx, path, &file) == 0, "open %s", path);
    CHECK(same(&want, &file, 0, 0, "file against the CLI"), "the library's file differs from fractalbake render's");

    int region[4] = {10, 7, 40, 21};
    img = NULL;
    CHECK(fractalbake_render(ctx, scene, region, &img) == 0, "region: %s", fractalbake_error(ctx));
    if (img) CHECK(read_image(ctx, img, &part) == 0, "read region");
    fractalbake_image_destroy(img);
    CHECK(part.x == 10 && part.y == 7 && part.w == 40 && part.h == 21, "region window %d,%d %dx%d", part.x, part.y,
          part.w, part.h);
    CHECK(same(&want, &part, 10, 7, "region"), "the region's pixels differ from the full bake's");

    /* cancelled at the first call: an error, no file, the message says so */
    seen stop = {.monotone = true, .stop_at = 1};
    fractalbake_set_progress(ctx, on_progress, &stop);
    snprintf(path, sizeof path, "%s/cancelled.exr", g_dir);
    int rc = fractalbake_bake(ctx, scene, path, NULL);
    CHECK(rc == FRACTALBAKE_ERR_CANCELLED, "cancel: %d (%s)", rc, fractalbake_error(ctx));
    CHECK(strstr(fractalbake_error(ctx), "cancelled") != NULL, "cancel line: %s", fractalbake_error(ctx));
    CHECK(access(path, F_OK) != 0, "a cancelled bake left %s", path);
    CHECK(stop.calls == 1, "the callback was called %d times after it asked to stop", stop.calls);
    fractalbake_set_progress(ctx, NULL, NULL);

    /* the bakes into planes left nothing in the context's tmpdir: their folders went with their files */
    DIR *d = opendir(g_dir);
    int left = 0;
    for (struct dirent *e; d && (e = readdir(d));) left += !strncmp(e->d_name, "fractalbake-", 12);
    if (d) closedir(d);
    CHECK(left == 0, "%d temporary folders left in %s", left, g_dir);

    planes_free(&want), planes_free(&got), planes_free(&file), planes_free(&part);
    fractalbake_scene_destroy(scene);
    fractalbake_context_destroy(ctx);
}

/* A bad scene: the library's line is the command line's, and the code its exit's class. */
static void test_errors(void)
{
    fractalbake_context *ctx = context("native");
    if (!ctx) {
        g_fail++;
        return;
    }
    const char *bad = "{\"size\": [64, 32], \"layers\": [{\"type\": \"fbm\", \"octaves\": 99}]}";
    char path[256], args[512], err[1024];
    snprintf(path, sizeof path, "%s/bad.json", g_dir);
    FILE *f = fopen(path, "w");
    if (f) fputs(bad, f), fclose(f);
    snprintf(args, sizeof args, "render -q --backend native '%s' -o '%s/bad.exr'", path, g_dir);
    int code = cli(args, err, sizeof err);
    fractalbake_scene *scene = NULL;
    int rc = fractalbake_scene_load(ctx, NULL, path, NULL, 0, &scene);
    CHECK(code == 2 && rc == FRACTALBAKE_ERR_INPUT && !scene, "exit %d, code %d", code, rc);
    CHECK(!strcmp(fractalbake_error(ctx), err) && strstr(err, "octaves"), "library: %s\ncli:     %s",
          fractalbake_error(ctx), err);
    const char *const set[] = {"layers.nosuch.octaves=3"};
    rc = fractalbake_scene_load(ctx, NULL, NULL, set, 1, &scene);
    snprintf(args, sizeof args, "render -q --backend native --set %s -o '%s/bad.exr'", set[0], g_dir);
    code = cli(args, err, sizeof err);
    CHECK(code == 2 && rc == FRACTALBAKE_ERR_USAGE, "--set: exit %d, code %d", code, rc);
    CHECK(!strcmp(fractalbake_error(ctx), err), "library: %s\ncli:     %s", fractalbake_error(ctx), err);
    fractalbake_context *none = NULL;
    rc = fractalbake_context_create(&(fractalbake_context_desc){.api = FRACTALBAKE_API + 1}, &none);
    CHECK(rc == FRACTALBAKE_ERR_USAGE && strstr(fractalbake_error(none), "API"), "api check: %d %s", rc,
          fractalbake_error(none));
    fractalbake_context_destroy(none);
    rc = fractalbake_context_create(&(fractalbake_context_desc){.api = FRACTALBAKE_API, .backend = "cuda"}, &none);
    CHECK(rc == FRACTALBAKE_ERR_USAGE &&
              !strcmp(fractalbake_error(none), "fractalbake: backend \"cuda\": expected auto, vulkan or native"),
          "backend check: %s", fractalbake_error(none));
    fractalbake_context_destroy(none);
    fractalbake_context_destroy(ctx);
}

/* Whether the context's line is "fractalbake: " and then want, exactly. */
static bool said(const fractalbake_context *ctx, const char *want)
{
    char line[2048];
    snprintf(line, sizeof line, "fractalbake: %s", want);
    if (!strcmp(fractalbake_error(ctx), line)) return true;
    fprintf(stderr, "  said: %s\n  want: %s\n", fractalbake_error(ctx), line);
    return false;
}

/* A file's bytes, for "untouched" checks (at most size; -1 when it cannot be read). */
static long slurp(const char *path, char *buf, size_t size)
{
    FILE *f = fopen(path, "rb");
    if (!f) return -1;
    long n = (long)fread(buf, 1, size, f);
    fclose(f);
    return n;
}

/* Entries of g_dir whose name holds part. */
static int entries(const char *part)
{
    DIR *d = opendir(g_dir);
    int n = 0;
    for (struct dirent *e; d && (e = readdir(d));) n += strstr(e->d_name, part) != NULL;
    if (d) closedir(d);
    return n;
}

/* A progress callback that calls back into its own context: every call refused at once. */
typedef struct reentry {
    fractalbake_context *ctx;
    const fractalbake_scene *scene;
    int calls, render_rc, bake_rc, load_rc;
    char line[2048];
} reentry;

static int reenter(double fraction, void *user)
{
    (void)fraction;
    reentry *r = user;
    if (r->calls++) return 0;
    fractalbake_image *img = NULL;
    fractalbake_scene *sc = NULL;
    char path[256];
    snprintf(path, sizeof path, "%s/inner.exr", g_dir);
    r->render_rc = fractalbake_render(r->ctx, r->scene, NULL, &img);
    snprintf(r->line, sizeof r->line, "%s", fractalbake_error(r->ctx));
    r->bake_rc = fractalbake_bake(r->ctx, r->scene, path, NULL);
    r->load_rc = fractalbake_scene_load(r->ctx, NULL, NULL, NULL, 0, &sc);
    fractalbake_context_destroy(r->ctx); /* not now: the context is working */
    fractalbake_image_destroy(img);
    fractalbake_scene_destroy(sc);
    return 0;
}

/* The boundary: every pointer, count, size and region an entry point takes is checked before any work,
 * with the command line's limits; a call from the context's own progress callback is refused, not
 * deadlocked; no bake replaces its scene's file or writes an EXR under another name. */
static void test_boundary(void)
{
    fractalbake_context *none = NULL;
    int rc = fractalbake_context_create(
        &(fractalbake_context_desc){.api = FRACTALBAKE_API, .backend = "native", .threads = 1000000}, &none);
    CHECK(rc == FRACTALBAKE_ERR_USAGE &&
              said(none, "threads 1000000: expected 0 (one per core) or 1..1024, as --threads"),
          "threads 10^6: %d", rc);
    fractalbake_context_destroy(none);
    rc = fractalbake_context_create(
        &(fractalbake_context_desc){.api = FRACTALBAKE_API, .backend = "native", .max_memory = UINT64_MAX}, &none);
    CHECK(rc == FRACTALBAKE_ERR_USAGE &&
              said(none, "max_memory 18446744073709551615: expected 0 (80% of the memory) or 1 MiB to 9e18 bytes, as "
                         "--max-memory"),
          "max_memory 2^64-1 (-1 through a cast): %d", rc);
    fractalbake_context_destroy(none);
    rc = fractalbake_context_create(
        &(fractalbake_context_desc){.api = FRACTALBAKE_API, .backend = "native", .max_memory = 1000}, &none);
    CHECK(rc == FRACTALBAKE_ERR_USAGE && strstr(fractalbake_error(none), "max_memory 1000:"), "max_memory 1000: %d",
          rc);
    fractalbake_context_destroy(none);
    CHECK(fractalbake_context_create(NULL, NULL) == FRACTALBAKE_ERR_USAGE, "no place for the context");
    CHECK(fractalbake_bake(NULL, NULL, "x.exr", NULL) == FRACTALBAKE_ERR_USAGE, "no context");
    CHECK(!strcmp(fractalbake_backend(NULL), "") && !strcmp(fractalbake_device(NULL), ""), "NULL context's names");
    fractalbake_set_progress(NULL, NULL, NULL);

    fractalbake_context *ctx = context("native");
    if (!ctx) {
        g_fail++;
        return;
    }
    fractalbake_scene *scene = (fractalbake_scene *)1;
    const char *const holes[] = {"size=96x48", NULL};
    rc = fractalbake_scene_load(ctx, NULL, NULL, holes, 2, &scene);
    CHECK(rc == FRACTALBAKE_ERR_USAGE && !scene &&
              said(ctx, "fractalbake_scene_load: sets[1] is NULL: expected KEY.PATH=VALUE, as --set"),
          "sets[1] NULL: %d", rc);
    rc = fractalbake_scene_load(ctx, NULL, NULL, holes, -1, &scene);
    CHECK(rc == FRACTALBAKE_ERR_USAGE && strstr(fractalbake_error(ctx), "-1 overrides"), "nsets -1: %d", rc);
    CHECK(fractalbake_scene_load(ctx, NULL, NULL, NULL, 0, NULL) == FRACTALBAKE_ERR_USAGE, "no place for the scene");

    /* the scene from a file, then baked into that file, any spelling: refused, the file as it was */
    char spath[256], alias[300], text[4096], after[4096], out[300];
    snprintf(spath, sizeof spath, "%s/scene.exr", g_dir); /* a JSON scene under an EXR name */
    FILE *f = fopen(spath, "w");
    if (f) fputs("{\"size\": [96, 48], \"layers\": [{\"name\": \"n\", \"type\": \"fbm\"}]}\n", f), fclose(f);
    long n = slurp(spath, text, sizeof text);
    rc = fractalbake_scene_load(ctx, NULL, spath, NULL, 0, &scene);
    CHECK(rc == 0 && scene, "scene file: %s", fractalbake_error(ctx));
    if (!scene) {
        fractalbake_context_destroy(ctx);
        g_fail++;
        return;
    }
    snprintf(alias, sizeof alias, "%s/./scene.exr", g_dir);
    char want[1024];
    snprintf(want, sizeof want,
             "%s: is an input of this run (read as the scene) and cannot also be the output: write the output under "
             "another name, then mv it over the input",
             spath);
    rc = fractalbake_bake(ctx, scene, spath, NULL);
    CHECK(rc == FRACTALBAKE_ERR_USAGE && said(ctx, want), "bake into its scene's file: %d", rc);
    rc = fractalbake_bake(ctx, scene, alias, NULL);
    CHECK(rc == FRACTALBAKE_ERR_USAGE && strstr(fractalbake_error(ctx), "is the same file as"),
          "another spelling: %d %s", rc, fractalbake_error(ctx));
    CHECK(slurp(spath, after, sizeof after) == n && !memcmp(text, after, (size_t)n), "the scene's file changed");
    /* an EXR only under an EXR's name, and never on standard output */
    snprintf(out, sizeof out, "%s/o.png", g_dir);
    rc = fractalbake_bake(ctx, scene, out, NULL);
    snprintf(want, sizeof want, "fractalbake_bake %s: this writes OpenEXR (.exr), not .png: name the file .exr", out);
    CHECK(rc == FRACTALBAKE_ERR_USAGE && said(ctx, want), "o.png: %d", rc);
    rc = fractalbake_bake(ctx, scene, "-", NULL);
    CHECK(rc == FRACTALBAKE_ERR_USAGE && said(ctx, "fractalbake_bake -: the library writes no standard output: name a "
                                                   "file .exr"),
          "-: %d", rc);
    CHECK(fractalbake_bake(ctx, scene, NULL, NULL) == FRACTALBAKE_ERR_USAGE &&
              said(ctx, "fractalbake_bake: no output path"),
          "NULL path");
    CHECK(fractalbake_bake(ctx, NULL, out, NULL) == FRACTALBAKE_ERR_USAGE && said(ctx, "fractalbake_bake: no scene"),
          "NULL scene");
    /* regions: the command line's limits, inside the image */
    snprintf(out, sizeof out, "%s/r.exr", g_dir);
    const struct {
        int r[4];
        const char *line;
    } regions[] = {{{90, 0, 10, 10}, "region 90,0,10,10: not inside the 96 x 48 image"},
                   {{0, 0, 4, 0}, "region 0,0,4,0: expected X,Y >= 0 and W,H in 1..65536"},
                   {{-1, 0, 4, 4}, "region -1,0,4,4: expected X,Y >= 0 and W,H in 1..65536"},
                   {{0, 0, 2147483647, 4}, "region 0,0,2147483647,4: expected X,Y >= 0 and W,H in 1..65536"},
                   {{2147483647, 0, 65536, 4}, "region 2147483647,0,65536,4: not inside the 96 x 48 image"}};
    for (size_t i = 0; i < sizeof regions / sizeof regions[0]; i++) {
        fractalbake_image *img = (fractalbake_image *)1;
        CHECK(fractalbake_bake(ctx, scene, out, regions[i].r) == FRACTALBAKE_ERR_USAGE && said(ctx, regions[i].line),
              "bake region %zu", i);
        CHECK(fractalbake_render(ctx, scene, regions[i].r, &img) == FRACTALBAKE_ERR_USAGE && !img &&
                  said(ctx, regions[i].line),
              "render region %zu", i);
    }
    CHECK(fractalbake_render(ctx, scene, NULL, NULL) == FRACTALBAKE_ERR_USAGE, "render: no place for the image");
    CHECK(fractalbake_open(ctx, NULL, NULL) == FRACTALBAKE_ERR_USAGE, "open: NULL");
    CHECK(fractalbake_image_channels(NULL) == 0 && !fractalbake_image_channel(NULL, 0) &&
              fractalbake_image_type(NULL, 0) == -1 && !fractalbake_image_attribute(NULL, "x"),
          "NULL image");
    int w = -1, h = -1;
    fractalbake_scene_size(NULL, &w, &h);
    CHECK(w == 0 && h == 0 && !fractalbake_scene_json(NULL), "NULL scene's size");

    /* re-entry from the progress callback: each inner call refused at once with one line; the outer
     * bake goes on and succeeds; destroying the context from it is put off (the context still works) */
    reentry r = {.ctx = ctx, .scene = scene};
    fractalbake_set_progress(ctx, reenter, &r);
    snprintf(out, sizeof out, "%s/outer.exr", g_dir);
    rc = fractalbake_bake(ctx, scene, out, NULL);
    CHECK(rc == 0 && access(out, F_OK) == 0, "the outer bake: %d %s", rc, fractalbake_error(ctx));
    CHECK(r.calls >= 1 && r.render_rc == FRACTALBAKE_ERR_USAGE && r.bake_rc == FRACTALBAKE_ERR_USAGE &&
              r.load_rc == FRACTALBAKE_ERR_USAGE,
          "inner calls: %d %d %d (%d calls)", r.render_rc, r.bake_rc, r.load_rc, r.calls);
    CHECK(!strcmp(r.line, "fractalbake: fractalbake_render: the context is running another call (this one came from "
                          "its progress callback or another thread): a context runs one call at a time"),
          "inner line: %s", r.line);
    snprintf(out, sizeof out, "%s/inner.exr", g_dir);
    CHECK(access(out, F_OK) != 0, "the refused inner bake wrote %s", out);
    fractalbake_set_progress(ctx, NULL, NULL);
    snprintf(out, sizeof out, "%s/after.exr", g_dir);
    CHECK(fractalbake_bake(ctx, scene, out, NULL) == 0, "after the callback: %s", fractalbake_error(ctx));
    CHECK(entries(".tmp") == 0 && entries("o.png") == 0 && access("-", F_OK) != 0, "files left behind");
    snprintf(out, sizeof out, "%s/r.exr", g_dir);
    CHECK(access(out, F_OK) != 0, "a refused region wrote %s", out);
    fractalbake_scene_destroy(scene);
    fractalbake_context_destroy(ctx);
}

/* One context's work on a thread: the default scene (small) in planes, then a scene that fails. */
typedef struct job {
    fractalbake_context *ctx;
    planes out;
    int rc, bad_rc;
    char bad_error[1024], backend[32];
} job;

static void *work(void *arg)
{
    job *j = arg;
    fractalbake_scene *scene = NULL;
    fractalbake_image *img = NULL;
    for (int round = 0; round < 3 && !j->rc; round++) {
        planes_free(&j->out);
        j->rc = fractalbake_scene_load(j->ctx, NULL, NULL, k_small, 1, &scene);
        if (!j->rc) j->rc = fractalbake_render(j->ctx, scene, NULL, &img);
        if (!j->rc) j->rc = read_image(j->ctx, img, &j->out);
        if (img) snprintf(j->backend, sizeof j->backend, "%s", fractalbake_image_attribute(img, "fractalbake/backend"));
        fractalbake_image_destroy(img), img = NULL;
        fractalbake_scene_destroy(scene), scene = NULL;
    }
    const char *const set[] = {"seed=-1"};
    j->bad_rc = fractalbake_scene_load(j->ctx, NULL, NULL, set, 1, &scene);
    snprintf(j->bad_error, sizeof j->bad_error, "%s", fractalbake_error(j->ctx));
    return NULL;
}

/* Native and Vulkan contexts at once: each its own backend, the same pixels (the kernels are exact
 * on both), each its own error. */
static int test_two_contexts(void)
{
    job a = {.ctx = context("native")}, b = {.ctx = context("vulkan")};
    if (!a.ctx) g_fail++;
    if (!b.ctx) {
        fractalbake_context_destroy(a.ctx);
        return 77;
    }
    CHECK(!strcmp(fractalbake_backend(b.ctx), "vulkan"), "backend %s", fractalbake_backend(b.ctx));
    pthread_t ta, tb;
    pthread_create(&ta, NULL, work, &a);
    pthread_create(&tb, NULL, work, &b);
    pthread_join(ta, NULL);
    pthread_join(tb, NULL);
    CHECK(a.rc == 0 && b.rc == 0, "native: %s; vulkan: %s", fractalbake_error(a.ctx), fractalbake_error(b.ctx));
    CHECK(!strcmp(a.backend, "native") && !strcmp(b.backend, "vulkan"), "backends %s, %s", a.backend, b.backend);
    CHECK(same(&a.out, &b.out, 0, 0, "native against vulkan"), "two contexts' bakes differ");
    CHECK(a.bad_rc == FRACTALBAKE_ERR_USAGE && b.bad_rc == FRACTALBAKE_ERR_USAGE && strstr(a.bad_error, "seed") &&
              !strcmp(a.bad_error, b.bad_error),
          "errors: %s | %s", a.bad_error, b.bad_error);
    planes_free(&a.out), planes_free(&b.out);
    fractalbake_context_destroy(a.ctx);
    fractalbake_context_destroy(b.ctx);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: test_library FRACTALBAKE_PROGRAM\n");
        return 2;
    }
    g_cli = argv[1];
    snprintf(g_dir, sizeof g_dir, "/tmp/fb-library-XXXXXX");
    if (!mkdtemp(g_dir)) return 2;
    test_native();
    test_errors();
    test_boundary();
    int skip = test_two_contexts();
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", g_dir);
    if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", g_dir);
    if (g_fail) fprintf(stderr, "%d check(s) failed\n", g_fail);
    return g_fail ? 1 : skip;
}
