/*
 * The flame benchmark: the genome `gold` of docs/examples/flames.flame (two xforms of ex, cosine,
 * flower, blob and blade, and the rotations of its 4-fold symmetry) at 1024 x 1024, the view of
 * bench/peers/flame_peer.c, its peer and ceiling (bench/run.sh runs it beside this and adds its rows:
 * mode "peer"). On each backend, in points per second: the chaos game alone (no density estimation,
 * filter or file; a device's rate from its timestamps too), the game with density estimation and the
 * spatial filter (no tone map or file), and the whole render (the file written, ZIP). The palette is a generated ramp,
 * not gold's: the work is the same, colour for colour.
 */
#include "benchkit.h"
#include "gen_flame.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* gold at 1024 x 1024 (its scale times 1024 / 768), its palette left to write_genome */
static const char k_gold[] =
    "<flame size=\"1024 1024\" center=\"-0.510105 0.367588\" scale=\"311.821312\" rotate=\"0\" supersample=\"1\" "
    "filter=\"0.5\" filter_shape=\"gaussian\" quality=\"50\" background=\"0 0 0\" brightness=\"4\" gamma=\"4\" "
    "highlight_power=\"-1\" vibrancy=\"1\" estimator_radius=\"9\" estimator_minimum=\"0\" estimator_curve=\"0.4\" "
    "gamma_threshold=\"0.01\" palette_mode=\"step\" name=\"gold\">\n"
    "<symmetry kind=\"4\"/>\n"
    "<xform weight=\"0.5\" color=\"0\" color_speed=\"0.5\" ex=\"0.41934\" cosine=\"0.574757\" flower=\"0.00590257\" "
    "flower_petals=\"3.5477\" flower_holes=\"0.539886\" coefs=\"-0.0848142 -0.900293 -0.202407 0.370426 0.546221 "
    "-0.321092\"/>\n"
    "<xform weight=\"0.5\" color=\"1\" color_speed=\"0.5\" blob=\"0.516139\" blade=\"0.483861\" "
    "blob_low=\"0.401652\" blob_high=\"0.943134\" blob_waves=\"5\" coefs=\"0.741856 -0.865792 -0.309256 "
    "-0.0467611 -0.954755 -0.587651\"/>\n"
    "<xform weight=\"1\" color=\"0\" color_speed=\"0\" linear=\"1\" coefs=\"0 1 -1 0 0 0\"/>\n"
    "<xform weight=\"1\" color=\"0.5\" color_speed=\"0\" linear=\"1\" coefs=\"-1 0 0 -1 0 0\"/>\n"
    "<xform weight=\"1\" color=\"1\" color_speed=\"0\" linear=\"1\" coefs=\"0 -1 1 0 0 0\"/>\n";

/* The genome file beside the bench's scratch EXR: gold and a ramp of 256 colours. */
static fb_result write_genome(const char *path)
{
    FILE *f = fopen(path, "w");
    if (!f) return fb_fail(FB_ERR_IO, "cannot write the flame benchmark's genome %s", path);
    fputs(k_gold, f);
    for (int i = 0; i < 256; i++) fprintf(f, "<color index=\"%d\" rgb=\"%d %d %d\"/>\n", i, 255 - i / 2, i, 64 + i / 4);
    fputs("</flame>\n", f);
    return fclose(f) ? fb_fail(FB_ERR_IO, "cannot write the flame benchmark's genome %s", path) : FB_OK;
}

static void report(const fb_bench *b, const char *backend, const char *mode, const char *device, int threads,
                   double points, double sec, double gpu_sec)
{
    fb_bench_row r = {.generator = "flame",
                      .backend = backend,
                      .device = device,
                      .mode = mode,
                      .unit = "Mpts/s",
                      .rate = points / sec * 1e-6,
                      .gpu_rate = gpu_sec > 0 ? points / gpu_sec * 1e-6 : 0,
                      .threads = threads,
                      .nextra = 1,
                      .extra = {{"points", points, 0}}};
    snprintf(r.note, sizeof r.note, "(%.0f points in %.3f s)", points, sec);
    b->row(b, &r);
}

/* The points of the last game timed (the chains' exact count: the rows' work), and the prepares'
 * seconds (game, density estimation and filter) of the timed runs */
static double g_points, g_prepare[3];
static int g_nprepare;

/* The chaos game's seconds of a prepared generator (the game alone); its whole prepare's kept. */
static void game_seconds(const fb_gen *g, double *sec, double *gpu)
{
    const fb_flame_stats *st = fb_gen_flame_stats(g);
    *sec = st->game_seconds, *gpu = st->gpu_seconds, g_points = st->points;
    g_prepare[g_nprepare++ % 3] = st->prepare_seconds;
}

/* One backend's two rows. */
static fb_result run(const fb_bench *b, fb_engine *e, const char *backend, int threads, const fb_scene *s)
{
    double sec = 0, gpu = 0, wall = 0, gwall = 0;
    g_nprepare = 0;
    fb_result rc = fb_bench_prepared(e, s, game_seconds, &sec, &gpu);
    double points = g_points;
    if (!rc) report(b, backend, "chaos-game", e->device, threads, points, sec, gpu);
    /* the measure: the game, density estimation and filter (no tone map, no file) */
    if (!rc) report(b, backend, "game-de-filter", e->device, threads, points, fb_bench_median3(g_prepare), 0);
    if (!rc) rc = fb_bench_timed(e, s, b->out, &wall, &gwall);
    if (!rc) report(b, backend, "end-to-end-zip", e->device, threads, points, wall, 0);
    return rc;
}

fb_result fb_flame_bench(fb_bench *b)
{
    /* at most the peer's 20 samples a pixel: lavapipe renders a few Mpts/s */
    double quality = b->points / (1024.0 * 1024.0);
    if (quality > 20) quality = 20;
    char path[512], json[1024];
    snprintf(path, sizeof path, "%s.flame", b->out);
    fb_result rc = write_genome(path);
    if (rc) return rc;
    snprintf(json, sizeof json,
             "{\"size\": [1024, 1024], \"seed\": 1, \"layers\": [{\"type\": \"flame\", "
             "\"file\": \"%s\", \"quality\": %.6g}]}",
             path, quality);
    fb_scene s;
    rc = fb_scene_parse(json, NULL, &s);
    remove(path);
    if (rc) return rc;
    fb_bench_heading(b,
                     "flame: the genome gold at 1024 x 1024, quality %.6g (%.0f points; rate: points per second); "
                     "median of 3",
                     quality, quality * 1024 * 1024);
    fb_engine e;
    bool have = false;
    if (b->vulkan && !(rc = fb_bench_open_vulkan(b, &e, &have)) && have) {
        rc = run(b, &e, "vulkan", 0, &s);
        fb_engine_close(&e);
    }
    if (!rc && b->native &&
        !(rc = fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = b->threads}, &e))) {
        rc = run(b, &e, "native", e.threads, &s);
        fb_engine_close(&e);
    }
    fb_scene_fini(&s);
    return rc;
}
