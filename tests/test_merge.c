/*
 * merge's checks of what it is given (core/merge.c), on files baked here: region files that tile
 * the image merge to the whole-image bake byte for byte, in any order; overlapping regions, a
 * missing region, a region of another scene, of another size or with other channels, and a mix of
 * region files and points parts are each refused (FB_ERR_INPUT) naming what is wrong, and write
 * nothing.
 */
#include "bake.h"
#include "merge.h"
#include "output.h"
#include "scene.h"

#include "testhelp.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char g_msg[2048];
static void sink(int level, const char *msg, void *user)
{
    (void)user;
    if (level == FB_LOG_ERROR && !g_msg[0]) snprintf(g_msg, sizeof g_msg, "%s", msg);
}

static const char *const k_fbm = "{\"size\": [64, 48], \"seed\": %d, \"layers\": [{\"type\": \"fbm\", "
                                 "\"name\": \"n\", \"octaves\": %d}]}";

/* Bakes the fbm scene (seed, octaves, size w x h) natively into `name`, pixels region r (r[2] == 0:
 * the whole image). Returns the file's path (kept: th_path's buffers are reused). */
static const char *bake(const char *name, int seed, int octaves, int w, int h, const int r[4])
{
    char json[512];
    snprintf(json, sizeof json, k_fbm, seed, octaves);
    if (w != 64 || h != 48) { /* another size */
        char *at = strstr(json, "[64, 48]");
        char sz[16];
        snprintf(sz, sizeof sz, "[%d, %d]", w, h);
        memmove(at + strlen(sz), at + 8, strlen(at + 8) + 1);
        memcpy(at, sz, strlen(sz));
    }
    fb_scene s;
    REQUIRE(fb_scene_parse(json, name, &s) == FB_OK);
    fb_engine e;
    REQUIRE(fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = 2}, &e) == FB_OK);
    static char kept[16][600];
    static int nkept;
    REQUIRE(nkept < 16);
    char *path = kept[nkept++];
    snprintf(path, 600, "%s", th_path(name));
    fb_outputs_begin();
    fb_result rc = fb_bake(&e, &(fb_bake_desc){.scene = &s, .out = path, .region = {r[0], r[1], r[2], r[3]}}, NULL);
    rc = fb_outputs_end(rc);
    CHECKF(rc == FB_OK, "%s: %s", name, g_msg);
    fb_engine_close(&e);
    fb_scene_fini(&s);
    return path;
}

/* fb_merge of the n files into `out` inside an output transaction; the error message in g_msg. */
static fb_result merge(const char *const *paths, int n, const char *out)
{
    g_msg[0] = 0;
    fb_outputs_begin();
    fb_result rc = fb_merge(&(fb_merge_desc){.paths = paths, .n = n, .out = out, .threads = 2});
    return fb_outputs_end(rc);
}

static bool same_bytes(const char *a, const char *b)
{
    FILE *fa = fopen(a, "rb"), *fb = fopen(b, "rb");
    bool same = fa && fb;
    while (same) {
        int x = fgetc(fa), y = fgetc(fb);
        same = x == y;
        if (x == EOF) break;
    }
    if (fa) fclose(fa);
    if (fb) fclose(fb);
    return same;
}

/* A merge that must fail with FB_ERR_INPUT, saying `want`, and leave no output file. */
static void refused(const char *const *paths, int n, const char *want)
{
    const char *out = th_path("refused.exr");
    fb_result rc = merge(paths, n, out);
    CHECKF(rc == FB_ERR_INPUT && strstr(g_msg, want), "wanted \"%s\", got %d \"%s\"", want, rc, g_msg);
    CHECKF(access(out, F_OK) != 0, "a refused merge left %s", out);
}

int main(void)
{
    fb_log_set_sink(sink, NULL);
    const char *whole = bake("whole.exr", 1, 5, 64, 48, (const int[4]){0});
    const char *top = bake("top.exr", 1, 5, 64, 48, (const int[4]){0, 0, 64, 20});
    const char *bottom = bake("bottom.exr", 1, 5, 64, 48, (const int[4]){0, 20, 64, 28});
    const char *left = bake("left.exr", 1, 5, 64, 48, (const int[4]){0, 20, 30, 28});
    const char *right = bake("right.exr", 1, 5, 64, 48, (const int[4]){30, 20, 34, 28});

    /* tiles in any order: the whole bake's bytes */
    const char *out = th_path("merged.exr");
    CHECKF(merge((const char *[]){top, bottom}, 2, out) == FB_OK, "%s", g_msg);
    CHECK(same_bytes(out, whole));
    CHECKF(merge((const char *[]){right, top, left}, 3, out) == FB_OK, "%s", g_msg);
    CHECK(same_bytes(out, whole));

    /* the set's own faults */
    const char *low = bake("low.exr", 1, 5, 64, 48, (const int[4]){0, 16, 64, 32});
    refused((const char *[]){top, low}, 2, "overlap");
    refused((const char *[]){top, left}, 2, "a region is missing");
    refused((const char *[]){top, bottom, left}, 3, "overlap");
    /* files of other bakes */
    const char *seed2 = bake("seed2.exr", 2, 5, 64, 48, (const int[4]){0, 20, 64, 28});
    refused((const char *[]){top, seed2}, 2, "baked from another scene");
    const char *taller = bake("taller.exr", 1, 5, 64, 50, (const int[4]){0, 20, 64, 30});
    refused((const char *[]){top, taller}, 2, "taller.exr: a region of a 64 x 50 image, but");
    const char *octaves = bake("octaves.exr", 1, 6, 64, 48, (const int[4]){0, 20, 64, 28});
    refused((const char *[]){top, octaves}, 2, "baked from another scene");
    /* a whole bake is a region covering everything: with another it overlaps */
    refused((const char *[]){whole, top}, 2, "overlap");
    /* not a fractalbake file at all */
    FILE *f = fopen(th_path("junk.exr"), "wb");
    REQUIRE(f);
    fputs("not an EXR", f);
    fclose(f);
    g_msg[0] = 0;
    CHECK(merge((const char *[]){top, th_path("junk.exr")}, 2, th_path("refused.exr")) != FB_OK);
    CHECK(access(th_path("refused.exr"), F_OK) != 0);
    TEST_REPORT();
}
