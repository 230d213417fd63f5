/*
 * Heightmaps: the heights a bake writes as a 16-bit PNG or RAW read back within one 16-bit step of the
 * EXR's Y channel (the range's ends exactly: the lowest height is 0, the highest 65535); an explicit
 * range clamps beyond it; a region's heightmap is the full one's crop; a terrain's float GeoTIFF holds
 * the EXR's heights bit for bit, with the geotransform of its frame and the CRS it was given, and
 * NoData (GDAL's tag, the lowest float) exactly where the pixel is outside the hull. Engine
 * presets accept exactly the sizes of the engines' tables (written out here), and their heightmap
 * read back as the engine reads it, through the sidecar's import settings, is within half a 16-bit
 * step of the EXR's heights; a region of another size is refused before anything is written.
 * Tiles: each preset accepts exactly the whole sizes whose tiles are in its table; the tiles, named by
 * the engine's convention, hold one range (the whole bake's), neighbours hold their shared row or
 * column byte for byte, the tiles put together are the single-file heightmap of the same bake
 * exactly, and the sidecar's offsets put every tile where its samples lie; a region is refused.
 */
#include "bake.h"
#include "exrio.h"
#include "heightmap.h"
#include "pngio.h"
#include "scene.h"

#include "testhelp.h"

#include <geotiff/geotiff.h>
#include <geotiff/geovalues.h>
#include <geotiff/xtiffio.h>

#include <jansson.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The Y channel of layer `layer` in the EXR at path (w x h floats). */
static float *read_y(const char *path, const char *channel, int *w, int *h)
{
    exrio_reader *r = NULL;
    if (exrio_open(path, &r) != FB_OK) return NULL;
    *w = exrio_width(r), *h = exrio_height(r);
    void *planes[64] = {0};
    int c = exrio_find_channel(r, channel);
    float *y = c >= 0 ? malloc((size_t)*w * *h * 4) : NULL;
    if (y) planes[c] = y;
    if (!y || exrio_read_rows(r, 0, *h, planes) != FB_OK) free(y), y = NULL;
    exrio_close(&r);
    return y;
}

static uint16_t *read_r16(const char *path, size_t n)
{
    FILE *f = fopen(path, "rb");
    uint8_t *b = malloc(n * 2);
    uint16_t *q = malloc(n * 2);
    if (!f || !b || !q || fread(b, 2, n, f) != n || fgetc(f) != EOF) {
        if (f) fclose(f);
        free(b), free(q);
        return NULL;
    }
    fclose(f);
    for (size_t i = 0; i < n; i++) q[i] = (uint16_t)(b[2 * i] | b[2 * i + 1] << 8); /* little-endian */
    free(b);
    return q;
}

static bool bake(fb_engine *e, const char *json, const char *out, const int region[4], fb_bake_stats *st)
{
    fb_scene s;
    if (fb_scene_parse(json, NULL, &s) != FB_OK) return false;
    fb_bake_desc d = {.scene = &s, .out = out};
    if (region) memcpy(d.region, region, sizeof d.region);
    fb_result rc = fb_bake(e, &d, st);
    fb_scene_fini(&s);
    return rc == FB_OK;
}

/* The engines' tables, written out here: Unreal's recommended landscape sizes, Unity's 2^n + 1. */
static bool in_list(const int *t, int n, int v)
{
    for (int i = 0; i < n; i++)
        if (t[i] == v) return true;
    return false;
}

static void test_engine_sizes(void)
{
    static const int unreal[] = {8129, 4033, 2017, 1009, 505, 253, 127};
    static const int unity[] = {33, 65, 129, 257, 513, 1025, 2049, 4097};
    char msg[256];
    int nu = 0, ny = 0, wrong = 0;
    for (int n = 1; n <= 9000; n++) {
        bool u = fb_heightmap_engine_check(FB_ENGINE_UNREAL, n, n, FB_HEIGHTMAP_PNG16, msg, sizeof msg);
        bool y = fb_heightmap_engine_check(FB_ENGINE_UNITY, n, n, FB_HEIGHTMAP_RAW16, msg, sizeof msg);
        nu += u, ny += y;
        wrong += u != in_list(unreal, 7, n) || y != in_list(unity, 8, n);
    }
    CHECKF(nu == 7 && ny == 8 && wrong == 0, "accepted %d unreal and %d unity sizes, %d wrong", nu, ny, wrong);
    CHECK(fb_heightmap_engine_check(FB_ENGINE_UNREAL, 2017, 1009, FB_HEIGHTMAP_PNG16, msg, sizeof msg));
    CHECK(!fb_heightmap_engine_check(FB_ENGINE_UNITY, 129, 257, FB_HEIGHTMAP_RAW16, msg, sizeof msg));
    CHECK(!fb_heightmap_engine_check(FB_ENGINE_UNREAL, 127, 127, FB_HEIGHTMAP_RAW16, msg, sizeof msg));
    CHECK(!fb_heightmap_engine_check(FB_ENGINE_UNITY, 129, 129, FB_HEIGHTMAP_PNG16, msg, sizeof msg));
    CHECK(!fb_heightmap_engine_check(FB_ENGINE_UNREAL, 1000, 1000, FB_HEIGHTMAP_PNG16, msg, sizeof msg) &&
          strstr(msg, "the nearest are 505 and 1009"));
    CHECK(!fb_heightmap_engine_check(FB_ENGINE_UNITY, 5000, 5000, FB_HEIGHTMAP_RAW16, msg, sizeof msg) &&
          strstr(msg, "the nearest is 4097"));
}

static double num_at(const json_t *o, const char *key, int i)
{
    const json_t *v = json_object_get(o, key);
    return json_number_value(i >= 0 ? json_array_get(v, (size_t)i) : v);
}

/* An engine preset's heightmap read back through its sidecar's import settings, as the engine reads
 * it: every height within half a 16-bit step of the EXR's. */
static void test_engine_sidecar(fb_engine *e, const char *engine, int n, const char *ext)
{
    char json[1024], hm[600], side[600], exr[600];
    snprintf(hm, sizeof hm, "%s", th_path(strcmp(ext, "png") ? "eng.r16" : "eng.png"));
    snprintf(side, sizeof side, "%s", th_path("eng.import.json"));
    snprintf(exr, sizeof exr, "%s", th_path("eng.exr"));
    snprintf(json, sizeof json,
             "{\"size\": [%d, %d], \"seed\": 2, \"layers\": [{\"type\": \"terrain\", \"name\": \"t\", "
             "\"insert\": 3000, \"points\": [[0, 0, 3], [500, 0, 40], [0, 400, 25], [500, 400, 9], [250, 200, 120]], "
             "\"heightmap\": \"%s\", \"heightmap-engine\": \"%s\"}]}",
             n, n, hm, engine);
    fb_bake_stats st;
    REQUIRE(bake(e, json, exr, NULL, &st));
    CHECK(st.nheightmaps == 1); /* (its strings were the scene's, freed by bake) */
    int w, h;
    float *y = read_y(exr, "t.Y", &w, &h);
    json_t *sc = json_load_file(side, 0, NULL);
    REQUIRE(y && sc && w == n && h == n);
    CHECK(!strcmp(json_string_value(json_object_get(sc, "engine")), engine));
    double lo = num_at(sc, "height_range", 0), hi = num_at(sc, "height_range", 1), half = (hi - lo) / 131070;
    double *v = malloc((size_t)n * n * sizeof *v), worst = 0;
    REQUIRE(v);
    if (!strcmp(ext, "png")) {
        fb_png png;
        REQUIRE(fb_png_read(hm, &png) == FB_OK);
        CHECK(png.depth == 16 && png.channels == 1 && png.width == n && png.height == n);
        for (int i = 0; i < n * n; i++) v[i] = round(png.plane[0][i] * 65535.0);
        fb_png_fini(&png);
    } else {
        uint16_t *q = read_r16(hm, (size_t)n * n);
        REQUIRE(q);
        for (int i = 0; i < n * n; i++) v[i] = q[i];
        free(q);
    }
    const json_t *u = json_object_get(sc, "unreal"), *un = json_object_get(sc, "unity");
    for (int i = 0; i < n * n; i++) {
        double z = u ? (num_at(u, "location", 2) + (v[i] - 32768) * num_at(u, "scale", 2) / 128) / 100 /* cm */
                     : num_at(un, "position", 1) + v[i] / 65535 * num_at(un, "terrain_height", -1);
        worst = fmax(worst, fabs(z - y[i]));
    }
    CHECKF(worst <= half * (1 + 1e-6) + 1e-12 * fabs(hi),
           "%s: heights from the file and sidecar %g off; half a step %g", engine, worst, half);
    if (u) { /* the sample spacing, in centimetres: the frame over n pixels */
        CHECK(fabs(num_at(u, "scale", 0) - 100 * 500.0 / n) < 1e-9 &&
              fabs(num_at(u, "scale", 1) - 100 * 400.0 / n) < 1e-9);
    } else {
        CHECK(fabs(num_at(un, "terrain_width", -1) - 500.0 * (n - 1) / n) < 1e-9 &&
              fabs(num_at(un, "terrain_length", -1) - 400.0 * (n - 1) / n) < 1e-9 && num_at(un, "resolution", -1) == n);
    }
    /* a region of another size is refused before anything is written */
    remove(hm), remove(side), remove(exr);
    int region[4] = {0, 0, n - 1, n};
    CHECK(!bake(e, json, exr, region, &st));
    CHECK(access(hm, F_OK) != 0 && access(side, F_OK) != 0 && access(exr, F_OK) != 0);
    free(v), free(y);
    json_decref(sc);
}

/* Each preset's tiles: exactly the whole sizes cols (t - 1) + 1 with t in the engine's table (without
 * an engine, any t >= 2), and Unity's only square. */
static void test_tile_sizes(void)
{
    static const int unreal[] = {8129, 4033, 2017, 1009, 505, 253, 127};
    static const int unity[] = {33, 65, 129, 257, 513, 1025, 2049, 4097};
    char msg[512];
    for (int cols = 1; cols <= 4; cols++) {
        int nu = 0, ny = 0, nn = 0, wrong = 0;
        for (int n = 1; n <= 4 * 8128 + 2; n++) {
            bool u = fb_heightmap_tiles_check(FB_ENGINE_UNREAL, n, 127, cols, 1, FB_HEIGHTMAP_PNG16, msg, sizeof msg);
            bool y = fb_heightmap_tiles_check(FB_ENGINE_UNITY, n, n, cols, cols, FB_HEIGHTMAP_RAW16, msg, sizeof msg);
            bool none = fb_heightmap_tiles_check(FB_ENGINE_NONE, n, 9, cols, 2, FB_HEIGHTMAP_RAW16, msg, sizeof msg);
            bool whole = (n - 1) % cols == 0;
            int t = (n - 1) / cols + 1;
            nu += u, ny += y, nn += none;
            wrong += u != (whole && in_list(unreal, 7, t)) || y != (whole && in_list(unity, 8, t)) ||
                     none != (whole && t >= 2);
        }
        CHECKF(nu == 7 && ny == 8 && nn == (4 * 8128 + 1) / cols && wrong == 0,
               "%d columns: accepted %d unreal, %d unity, %d engine-free widths, %d wrong", cols, nu, ny, nn, wrong);
    }
    CHECK(!fb_heightmap_tiles_check(FB_ENGINE_UNREAL, 1201, 253, 4, 1, FB_HEIGHTMAP_PNG16, msg, sizeof msg) &&
          strstr(msg, "would be 301 samples: the nearest are 1009 (tiles of 253) and 2017 (tiles of 505)"));
    CHECK(!fb_heightmap_tiles_check(FB_ENGINE_NONE, 64, 9, 2, 2, FB_HEIGHTMAP_PNG16, msg, sizeof msg) &&
          strstr(msg, "the nearest are 63 (tiles of 32) and 65 (tiles of 33)"));
    CHECK(!fb_heightmap_tiles_check(FB_ENGINE_UNITY, 129, 65, 1, 1, FB_HEIGHTMAP_RAW16, msg, sizeof msg) &&
          strstr(msg, "square tiles"));
    CHECK(fb_heightmap_tiles_check(FB_ENGINE_UNITY, 257, 129, 2, 1, FB_HEIGHTMAP_RAW16, msg, sizeof msg));
    CHECK(!fb_heightmap_tiles_check(FB_ENGINE_NONE, 65, 65, 2, 2, FB_HEIGHTMAP_GEOTIFF, msg, sizeof msg));
    CHECK(!fb_heightmap_tiles_check(FB_ENGINE_UNREAL, 253, 253, 2, 2, FB_HEIGHTMAP_RAW16, msg, sizeof msg));
    /* the names: Unreal's x east, y south from the north-west; Unity's X index, then Z (north) index */
    char name[64];
    fb_heightmap_tile_path("out/land.png", FB_ENGINE_UNREAL, 1, 0, 2, name, sizeof name);
    CHECKF(!strcmp(name, "out/land_x1_y0.png"), "%s", name);
    fb_heightmap_tile_path("land.r16", FB_ENGINE_UNITY, 1, 0, 2, name, sizeof name);
    CHECKF(!strcmp(name, "land_1_1.r16"), "%s", name);
    fb_heightmap_tile_path("a.b/land", FB_ENGINE_NONE, 3, 2, 4, name, sizeof name);
    CHECKF(!strcmp(name, "a.b/land_x3_y2"), "%s", name);
}

/* The 16-bit samples of a heightmap file (PNG or RAW) of w x h, or NULL. */
static uint16_t *read_16(const char *path, int w, int h)
{
    if (strcmp(path + strlen(path) - 4, ".png")) return read_r16(path, (size_t)w * h);
    fb_png png;
    if (fb_png_read(path, &png) != FB_OK) return NULL;
    uint16_t *q = png.width == w && png.height == h && png.depth == 16 ? malloc((size_t)w * h * 2) : NULL;
    for (int i = 0; q && i < w * h; i++) q[i] = (uint16_t)lround(png.plane[0][i] * 65535.0);
    fb_png_fini(&png);
    return q;
}

/* Whether the PNG at path has the tEXt chunk key=value (the bytes as written). */
static bool png_text(const char *path, const char *key, const char *value)
{
    FILE *f = fopen(path, "rb");
    static char buf[1 << 20];
    size_t n = f ? fread(buf, 1, sizeof buf, f) : 0;
    if (f) fclose(f);
    char want[160];
    int len = snprintf(want, sizeof want, "tEXt%s%c%s", key, 0, value);
    for (size_t i = 0; i + len <= n; i++)
        if (!memcmp(buf + i, want, (size_t)len)) return true;
    return false;
}

/* A heightmap in cols x rows tiles of an engine: the same bake's single heightmap cut up exactly, the
 * shared rows and columns byte for byte, one range, the sidecar's offsets and settings. */
static void test_tiles(fb_engine *e, const char *engine, int cols, int rows, int t)
{
    int w = cols * (t - 1) + 1, h = rows * (t - 1) + 1;
    bool unreal = !strcmp(engine, "unreal");
    char json[1024], whole[600], pattern[600], exr[600], side[600];
    snprintf(whole, sizeof whole, "%s", th_path(unreal ? "whole.png" : "whole.r16"));
    snprintf(pattern, sizeof pattern, "%s", th_path(unreal ? "land.png" : "land.r16"));
    snprintf(side, sizeof side, "%s", th_path("land.import.json"));
    snprintf(exr, sizeof exr, "%s", th_path("tiles.exr"));
    const char *fmt = "{\"size\": [%d, %d], \"seed\": 5, \"layers\": [{\"type\": \"terrain\", \"name\": \"t\", "
                      "\"insert\": 4000, \"points\": [[0, 0, 3], [600, 0, 40], [0, 500, 25], [600, 500, 9], "
                      "[300, 250, 120]], \"heightmap\": \"%s\"%s}]}";
    fb_bake_stats st;
    snprintf(json, sizeof json, fmt, w, h, whole, "");
    REQUIRE(bake(e, json, th_path("whole.exr"), NULL, &st));
    char extra[128];
    snprintf(extra, sizeof extra, ", \"heightmap-engine\": \"%s\", \"tiles\": [%d, %d]", engine, cols, rows);
    snprintf(json, sizeof json, fmt, w, h, pattern, extra);
    REQUIRE(bake(e, json, exr, NULL, &st));
    CHECK(st.nheightmaps == 1);
    uint16_t *all = read_16(whole, w, h);
    float *y = read_y(exr, "t.Y", &w, &h);
    json_t *sc = json_load_file(side, 0, NULL);
    REQUIRE(all && y && sc);
    const json_t *tl = json_object_get(sc, "tiles"), *files = json_object_get(tl, "files");
    CHECK(num_at(tl, "columns", -1) == cols && num_at(tl, "rows", -1) == rows && num_at(tl, "samples", 0) == t &&
          num_at(tl, "samples", 1) == t && (int)json_array_size(files) == cols * rows);
    double lo = num_at(sc, "height_range", 0), hi = num_at(sc, "height_range", 1), half = (hi - lo) / 131070;
    char slo[40], shi[40];
    fb_format_shortest(lo, slo, sizeof slo);
    fb_format_shortest(hi, shi, sizeof shi);
    const json_t *set = json_object_get(sc, unreal ? "unreal" : "unity");
    const char *key = unreal ? "location" : "position";
    double sx = unreal ? num_at(set, "scale", 0) : num_at(sc, "sample_spacing", 0);
    double sy = unreal ? num_at(set, "scale", 1) : num_at(sc, "sample_spacing", 1);
    uint16_t *back = calloc((size_t)w * h, 2), **tile = calloc((size_t)cols * rows, sizeof *tile);
    int named = 0, placed = 0, ranged = 0, worst_tile = 0;
    double worst = 0;
    for (int r = 0; r < rows; r++)
        for (int c = 0; c < cols; c++) {
            const json_t *f = json_array_get(files, (size_t)(r * cols + c));
            char want[64], path[600];
            if (unreal)
                snprintf(want, sizeof want, "land_x%d_y%d.png", c, r); /* x east, y south */
            else
                snprintf(want, sizeof want, "land_%d_%d.r16", c, rows - 1 - r); /* X, then Z (north) */
            named += f && !strcmp(json_string_value(json_object_get(f, "file")), want);
            snprintf(path, sizeof path, "%s", th_path(want));
            uint16_t *q = tile[r * cols + c] = read_16(path, t, t);
            REQUIRE(q);
            int px = (int)num_at(f, "pixels", 0), py = (int)num_at(f, "pixels", 1);
            /* the sidecar's place of the tile: its first sample where the whole's sample (px, py) is */
            double ex = num_at(set, key, 0) + px * sx;
            double ez = unreal ? num_at(set, key, 1) + py * sy                      /* Y: south */
                               : num_at(set, key, 2) + (h - 1 - (py + t - 1)) * sy; /* z of its south row */
            placed += px == c * (t - 1) && py == r * (t - 1) && fabs(num_at(f, key, 0) - ex) < 1e-6 &&
                      fabs(num_at(f, key, unreal ? 1 : 2) - ez) < 1e-6 &&
                      num_at(f, key, unreal ? 2 : 1) == num_at(set, key, unreal ? 2 : 1);
            if (unreal)
                ranged +=
                    png_text(path, "fractalbake/height-min", slo) && png_text(path, "fractalbake/height-max", shi);
            for (int j = 0; j < t; j++)
                for (int i = 0; i < t; i++) {
                    uint16_t v = q[j * t + i];
                    back[(size_t)(py + j) * w + px + i] = v;
                    double z = unreal ? (num_at(f, key, 2) + (v - 32768.0) * num_at(set, "scale", 2) / 128) / 100
                                      : num_at(f, key, 1) + v / 65535.0 * num_at(set, "terrain_height", -1);
                    double off = fabs(z - y[(size_t)(py + j) * w + px + i]);
                    if (off > worst) worst = off, worst_tile = r * cols + c;
                }
        }
    if (!unreal) /* the whole grid, for Unity's Terrain Toolbox */
        CHECK(num_at(set, "tiles_x", -1) == cols && num_at(set, "tiles_z", -1) == rows &&
              fabs(num_at(set, "total_width", -1) - cols * num_at(set, "terrain_width", -1)) < 1e-9 &&
              fabs(num_at(set, "total_length", -1) - rows * num_at(set, "terrain_length", -1)) < 1e-9);
    CHECKF(named == cols * rows, "%s: %d of %d tiles named by the convention", engine, named, cols * rows);
    CHECKF(placed == cols * rows, "%s: %d of %d tiles placed by the sidecar where their samples lie", engine, placed,
           cols * rows);
    if (unreal)
        CHECKF(ranged == cols * rows, "%d of %d tiles store the whole's range %s..%s", ranged, cols * rows, slo, shi);
    CHECKF(worst <= half * (1 + 1e-6) + 1e-12 * fabs(hi),
           "%s: tile %d's heights through the sidecar %g off; half a step %g", engine, worst_tile, worst, half);
    /* neighbours' shared columns and rows, byte for byte */
    int shared = 0, expect = 0;
    for (int r = 0; r < rows; r++)
        for (int c = 0; c < cols; c++) {
            const uint16_t *q = tile[r * cols + c];
            if (c + 1 < cols) {
                const uint16_t *east = tile[r * cols + c + 1];
                for (int j = 0; j < t; j++) shared += q[j * t + t - 1] == east[j * t], expect++;
            }
            if (r + 1 < rows) {
                const uint16_t *south = tile[(r + 1) * cols + c];
                shared += !memcmp(q + (size_t)(t - 1) * t, south, (size_t)t * 2), expect++;
            }
        }
    CHECKF(shared == expect && expect > 0, "%s: %d of %d shared edge samples (columns) and rows equal", engine, shared,
           expect);
    CHECKF(!memcmp(back, all, (size_t)w * h * 2), "%s: the tiles put together differ from the single heightmap",
           engine);
    /* a region of the image is refused before anything is written */
    for (int k = 0; k < cols * rows; k++) {
        const json_t *f = json_array_get(files, (size_t)k);
        remove(th_path(json_string_value(json_object_get(f, "file"))));
        free(tile[k]);
    }
    remove(side), remove(exr);
    int region[4] = {0, 0, w, t};
    CHECK(!bake(e, json, exr, region, &st));
    char first[600];
    snprintf(first, sizeof first, "%s", th_path(unreal ? "land_x0_y0.png" : "land_0_0.r16"));
    CHECK(access(first, F_OK) != 0 && access(side, F_OK) != 0 && access(exr, F_OK) != 0);
    free(tile), free(back), free(all), free(y);
    json_decref(sc);
}

int main(void)
{
    TIFFSetWarningHandler(NULL); /* libtiff's note on GDAL's tag, which it reads as an anonymous field */
    fb_engine e;
    CHECK(fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = 2}, &e) == FB_OK);
    fb_bake_stats st;
    char json[1024];

    /* fBm, PNG, the image's own range */
    snprintf(json, sizeof json,
             "{\"size\": [97, 61], \"seed\": 4, \"layers\": [{\"type\": \"fbm\", \"name\": \"h\", \"heightmap\": "
             "\"%s\"}]}",
             th_path("h.png"));
    REQUIRE(bake(&e, json, th_path("h.exr"), NULL, &st));
    REQUIRE(st.nheightmaps == 1 && st.heightmaps[0].format == FB_HEIGHTMAP_PNG16);
    int w, h;
    float *y = read_y(th_path("h.exr"), "h.Y", &w, &h);
    REQUIRE(y && w == 97 && h == 61);
    double lo = INFINITY, hi = -INFINITY;
    for (int i = 0; i < w * h; i++) lo = fmin(lo, y[i]), hi = fmax(hi, y[i]);
    CHECKF(st.heightmaps[0].lo == lo && st.heightmaps[0].hi == hi, "range %g..%g, the image's %g..%g",
           st.heightmaps[0].lo, st.heightmaps[0].hi, lo, hi);
    fb_png png;
    REQUIRE(fb_png_read(th_path("h.png"), &png) == FB_OK);
    CHECK(png.width == 97 && png.height == 61 && png.channels == 1 && png.depth == 16);
    double step = (hi - lo) / 65535, worst = 0;
    int at0 = 0, at1 = 0;
    for (int i = 0; i < w * h; i++) {
        double q = round(png.plane[0][i] * 65535.0); /* the stored sample */
        worst = fmax(worst, fabs(lo + q * step - y[i]));
        at0 += q == 0 && y[i] == lo, at1 += q == 65535 && y[i] == hi;
    }
    CHECKF(worst <= 0.5 * step * (1 + 1e-6), "PNG: a height read back %g from the EXR's; half a step is %g", worst,
           0.5 * step);
    CHECK(at0 >= 1 && at1 >= 1); /* the lowest pixel stored as 0, the highest as 65535 */
    fb_png_fini(&png);

    /* RAW, an explicit range narrower than the image's: clamped at its ends, within a step inside */
    snprintf(json, sizeof json,
             "{\"size\": [97, 61], \"seed\": 4, \"layers\": [{\"type\": \"fbm\", \"name\": \"h\", \"heightmap\": "
             "\"%s\", \"heightmap-range\": [-0.5, 0.25]}]}",
             th_path("h.r16"));
    REQUIRE(bake(&e, json, th_path("h2.exr"), NULL, &st));
    CHECK(st.heightmaps[0].lo == -0.5 && st.heightmaps[0].hi == 0.25 && st.heightmaps[0].format == FB_HEIGHTMAP_RAW16);
    uint16_t *q = read_r16(th_path("h.r16"), (size_t)w * h);
    REQUIRE(q);
    step = 0.75 / 65535, worst = 0;
    int clamped = 0;
    for (int i = 0; i < w * h; i++) {
        if (y[i] < -0.5 || y[i] > 0.25) {
            clamped += q[i] == (y[i] < -0.5 ? 0 : 65535);
            continue;
        }
        worst = fmax(worst, fabs(-0.5 + q[i] * step - y[i]));
        clamped += 1;
    }
    CHECKF(clamped == w * h, "%d of %d pixels stored right", clamped, w * h);
    CHECKF(worst <= 0.5 * step * (1 + 1e-6), "RAW: %g off, half a step is %g", worst, 0.5 * step);

    /* a region's heightmap (with the same explicit range) is the crop of the whole one */
    snprintf(json, sizeof json,
             "{\"size\": [97, 61], \"seed\": 4, \"layers\": [{\"type\": \"fbm\", \"name\": \"h\", \"heightmap\": "
             "\"%s\", \"heightmap-range\": [-0.5, 0.25]}]}",
             th_path("part.r16"));
    int region[4] = {13, 7, 40, 30};
    REQUIRE(bake(&e, json, th_path("part.exr"), region, &st));
    uint16_t *part = read_r16(th_path("part.r16"), 40 * 30);
    REQUIRE(part);
    int same = 0;
    for (int r = 0; r < 30; r++)
        for (int x = 0; x < 40; x++) same += part[r * 40 + x] == q[(size_t)(r + 7) * w + x + 13];
    CHECKF(same == 40 * 30, "%d of %d region pixels equal the full heightmap's", same, 40 * 30);
    free(part), free(q), free(y);

    /* a terrain's GeoTIFF: the EXR's heights exactly, its frame's geotransform, its CRS */
    snprintf(json, sizeof json,
             "{\"size\": [120, 80], \"layers\": [{\"type\": \"terrain\", \"points\": [[500000, 4600000, 100], "
             "[500600, 4600000, 130], [500000, 4600400, 90], [500600, 4600400, 150], [500300, 4600200, 240]], "
             "\"insert\": 3000, \"crs\": \"EPSG:32633\", \"heightmap\": \"%s\"}]}",
             th_path("t.tif"));
    REQUIRE(bake(&e, json, th_path("t.exr"), NULL, &st));
    y = read_y(th_path("t.exr"), "terrain.Y", &w, &h);
    REQUIRE(y);
    TIFF *tif = XTIFFOpen(th_path("t.tif"), "r");
    REQUIRE(tif);
    uint32_t tw = 0, th = 0;
    uint16_t bits = 0, fmt = 0;
    TIFFGetField(tif, TIFFTAG_IMAGEWIDTH, &tw);
    TIFFGetField(tif, TIFFTAG_IMAGELENGTH, &th);
    TIFFGetField(tif, TIFFTAG_BITSPERSAMPLE, &bits);
    TIFFGetField(tif, TIFFTAG_SAMPLEFORMAT, &fmt);
    CHECK(tw == 120 && th == 80 && bits == 32 && fmt == SAMPLEFORMAT_IEEEFP);
    float *row = malloc(120 * 4);
    int exact = 0;
    for (uint32_t r = 0; r < th && row; r++)
        if (TIFFReadScanline(tif, row, r, 0) == 1) exact += memcmp(row, y + (size_t)r * 120, 120 * 4) == 0;
    CHECKF(exact == 80, "%d of 80 GeoTIFF rows equal the EXR's, bit for bit", exact);
    uint16_t count = 0;
    double *scale = NULL, *tie = NULL;
    CHECK(TIFFGetField(tif, TIFFTAG_GEOPIXELSCALE, &count, &scale) && count == 3);
    if (scale)
        CHECKF(scale[0] == 5.0 && scale[1] == 5.0, "pixel scale %g, %g (600 m / 120, 400 m / 80)", scale[0], scale[1]);
    CHECK(TIFFGetField(tif, TIFFTAG_GEOTIEPOINTS, &count, &tie) && count == 6);
    if (tie) CHECK(tie[0] == 0 && tie[1] == 0 && tie[3] == 500000 && tie[4] == 4600400); /* the top-left corner */
    GTIF *gt = GTIFNew(tif);
    uint16_t model = 0, raster = 0, pcs = 0;
    CHECK(gt && GTIFKeyGet(gt, GTModelTypeGeoKey, &model, 0, 1) == 1 && model == ModelTypeProjected);
    CHECK(gt && GTIFKeyGet(gt, GTRasterTypeGeoKey, &raster, 0, 1) == 1 && raster == RasterPixelIsArea);
    CHECK(gt && GTIFKeyGet(gt, ProjectedCSTypeGeoKey, &pcs, 0, 1) == 1 && pcs == 32633);
    if (gt) GTIFFree(gt);
    XTIFFClose(tif);
    free(row), free(y);
    /* a triangle's hull: the GeoTIFF's pixels outside it are NoData, with GDAL's tag; inside, the EXR's */
    snprintf(json, sizeof json,
             "{\"size\": [90, 60], \"layers\": [{\"type\": \"terrain\", \"points\": [[0, 0, 10], [900, 0, 30], "
             "[450, 600, 70]], \"insert\": 2000, \"heightmap\": \"%s\"}]}",
             th_path("tri.tif"));
    REQUIRE(bake(&e, json, th_path("tri.exr"), NULL, &st));
    float *ty = read_y(th_path("tri.exr"), "terrain.Y", &w, &h), *ta = read_y(th_path("tri.exr"), "terrain.A", &w, &h);
    tif = XTIFFOpen(th_path("tri.tif"), "r");
    REQUIRE(ty && ta && tif);
    char *nodata = NULL; /* an unknown tag to libtiff: read as an anonymous field, count and text */
    uint32_t ncount = 0;
    CHECK(TIFFGetField(tif, TIFFTAG_GDAL_NODATA, &ncount, &nodata) == 1 && nodata && strtod(nodata, NULL) == -FLT_MAX);
    int right = 0, outside = 0;
    row = malloc((size_t)w * 4);
    for (int r = 0; r < h && row; r++) {
        if (TIFFReadScanline(tif, row, (uint32_t)r, 0) != 1) continue;
        for (int x = 0; x < w; x++) {
            size_t i = (size_t)r * w + x;
            outside += ta[i] == 0;
            right += ta[i] == 0 ? row[x] == -FLT_MAX : memcmp(&row[x], &ty[i], 4) == 0;
        }
    }
    CHECKF(right == w * h && outside > w * h / 4, "%d of %d pixels right, %d outside the hull", right, w * h, outside);
    XTIFFClose(tif);
    free(ty), free(ta), free(row);

    test_engine_sizes();
    test_engine_sidecar(&e, "unreal", 127, "png");
    test_engine_sidecar(&e, "unity", 129, "r16");
    test_tile_sizes();
    test_tiles(&e, "unreal", 3, 2, 127);
    test_tiles(&e, "unity", 2, 2, 65);
    fb_engine_close(&e);
    TEST_REPORT();
}
