/*
 * The IFS chaos game against an independent scalar chaos game written here (its own RNG, double
 * precision, one long chain), the Sierpinski triangle's box-counting dimension, exact point
 * accounting, bit-identical histograms across thread counts and backends, the condensation row's
 * 0.75 scaling, the .ifs reader and the map-list checks, and the tone curve.
 */
#include "bake.h"
#include "gen.h"
#include "gen_ifs.h"
#include "../kernels/ifs.h"

#include "testengines.h"
#include "testhelp.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static char g_last_error[1024];

static void sink(int level, const char *msg, void *user)
{
    (void)user;
    if (level == FB_LOG_ERROR) snprintf(g_last_error, sizeof g_last_error, "%s", msg);
}

typedef struct run_out {
    uint32_t *count; /* width x height */
    float *colour;
    fb_ifs_stats stats;
    int width, height;
} run_out;

/* Bakes the single ifs layer of `json` on engine e into memory. */
static fb_result run_scene(fb_engine *e, const char *json, run_out *out)
{
    fb_scene s;
    memset(out, 0, sizeof *out);
    fb_result rc = fb_scene_parse(json, NULL, &s);
    if (rc) return rc;
    fb_gen g;
    rc = fb_gen_init(&g, &s, &s.layers[0]);
    if (!rc) rc = g.prepare(&g, e, false);
    if (!rc) {
        size_t n = (size_t)s.width * s.height;
        float *planes[7];
        for (int c = 0; c < 7; c++) planes[c] = malloc(n * 4);
        g.compute.native_rows(&g, 0, s.height, (void *const *)planes);
        out->count = (uint32_t *)(void *)planes[0];
        out->colour = planes[2];
        for (int c = 0; c < 7; c++)
            if (c != 0 && c != 2) free(planes[c]);
        out->stats = *fb_gen_ifs_stats(&g);
        out->width = s.width;
        out->height = s.height;
    }
    fb_gen_fini(&g);
    fb_scene_fini(&s);
    return rc;
}

static void run_free(run_out *r)
{
    free(r->count);
    free(r->colour);
}

/* ---- an independent chaos game: xorshift64*, doubles, one chain ------------------------------- */

static uint64_t g_rng = 0x9e3779b97f4a7c15ull;

static double rnd(void)
{
    g_rng ^= g_rng >> 12;
    g_rng ^= g_rng << 25;
    g_rng ^= g_rng >> 27;
    return (double)((g_rng * 0x2545f4914f6cdd1dull) >> 11) * 0x1.0p-53;
}

/* Histogram of n points over [x0, x1] x [y0, y1] (y up) at w x h, maps as in fb_ifs. */
static double *reference_game(const fb_ifs *ifs, uint64_t n, int w, int h, const double b[4])
{
    double *hist = calloc((size_t)w * h, sizeof *hist), p[FB_IFS_MAX_MAPS], cum[FB_IFS_MAX_MAPS];
    double sum = 0, x = 0, y = 0;
    for (int k = 0; k < ifs->n; k++) sum += ifs->m[k].p;
    for (int k = 0; k < ifs->n; k++) p[k] = ifs->m[k].p / sum, cum[k] = (k ? cum[k - 1] : 0) + p[k];
    for (uint64_t i = 0; i < n + 1000; i++) {
        double r = rnd();
        int k = 0;
        while (k + 1 < ifs->n && r >= cum[k]) k++;
        const fb_ifs_map *m = &ifs->m[k];
        double nx = m->a * x + m->b * y + m->e, ny = m->c * x + m->d * y + m->f;
        x = nx, y = ny;
        if (i < 1000) continue;
        double px = (x - b[0]) / (b[1] - b[0]) * w, py = (b[3] - y) / (b[3] - b[2]) * h;
        if (px >= 0 && py >= 0 && px < w && py < h) hist[(size_t)py * w + (size_t)px] += 1;
    }
    return hist;
}

static double correlation(const uint32_t *a, const double *b, size_t n)
{
    double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
    for (size_t i = 0; i < n; i++) {
        sa += a[i], sb += b[i], saa += (double)a[i] * a[i], sbb += b[i] * b[i], sab += a[i] * b[i];
    }
    double ma = sa / n, mb = sb / n;
    return (sab / n - ma * mb) / sqrt((saa / n - ma * ma) * (sbb / n - mb * mb));
}

static void test_against_reference(fb_engine *e, const char *preset, const double b[4])
{
    char json[512];
    snprintf(json, sizeof json,
             "{\"size\": [256, 256], \"seed\": 5, \"layers\": [{\"type\": \"ifs\", \"preset\": \"%s\", "
             "\"points\": 10000000, \"bounds\": [%.17g, %.17g, %.17g, %.17g]}]}",
             preset, b[0], b[1], b[2], b[3]);
    run_out r;
    fb_result rc = run_scene(e, json, &r);
    CHECKF(rc == FB_OK, "%s: %s", preset, g_last_error);
    if (rc) return;
    fb_ifs ifs;
    fb_ifs_preset(preset, &ifs, NULL, NULL);
    double *ref = reference_game(&ifs, 10000000, 256, 256, b);
    double rho = correlation(r.count, ref, 256 * 256);
    CHECKF(rho > 0.99, "%s on %s: correlation %.5f with the reference chaos game", preset, fb_backend_name(e->kind),
           rho);
    free(ref);
    run_free(&r);
}

/* Box counting on the support: N(s) boxes of s x s pixels holding a hit; the slope of log N against
 * log(1/s) over s = 2..64. */
static void test_box_dimension(fb_engine *e)
{
    const char *json = "{\"size\": [1024, 1024], \"seed\": 9, \"layers\": [{\"type\": \"ifs\", \"preset\": "
                       "\"sierpinski\", \"points\": 20000000, \"bounds\": [0, 1, 0, 1]}]}";
    run_out r;
    fb_result rc = run_scene(e, json, &r);
    CHECKF(rc == FB_OK, "%s", g_last_error);
    if (rc) return;
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    int m = 0;
    for (int s = 2; s <= 64; s *= 2, m++) {
        int n = 0;
        for (int by = 0; by < 1024; by += s)
            for (int bx = 0; bx < 1024; bx += s) {
                bool hit = false;
                for (int y = by; y < by + s && !hit; y++)
                    for (int x = bx; x < bx + s && !hit; x++) hit = r.count[y * 1024 + x] > 0;
                n += hit;
            }
        double lx = log(1.0 / s), ly = log((double)n);
        sx += lx, sy += ly, sxx += lx * lx, sxy += lx * ly;
    }
    double slope = (m * sxy - sx * sy) / (m * sxx - sx * sx), want = log(3) / log(2);
    CHECKF(fabs(slope - want) < 0.05, "box-counting dimension %.4f, log 3 / log 2 = %.4f", slope, want);
    run_free(&r);
}

/* points = hits + outside + discarded, exactly; discarded = chains x skip when nothing restarts. */
static void test_accounting(fb_engine *e)
{
    const char *json = "{\"size\": [200, 150], \"seed\": 3, \"layers\": [{\"type\": \"ifs\", \"preset\": \"fern\", "
                       "\"points\": 1000003, \"chains\": 640, \"skip\": 37, \"bounds\": [-1, 2, 2, 8]}]}";
    run_out r;
    fb_result rc = run_scene(e, json, &r);
    CHECKF(rc == FB_OK, "%s", g_last_error);
    if (rc) return;
    uint64_t sum = 0;
    for (int i = 0; i < 200 * 150; i++) sum += r.count[i];
    const fb_ifs_stats *s = &r.stats;
    CHECKF(sum == s->hits, "count channel sums to %llu, stats say %llu hits", (unsigned long long)sum,
           (unsigned long long)s->hits);
    CHECKF(sum + s->outside + s->discarded == 1000003, "%llu + %llu + %llu != 1000003", (unsigned long long)sum,
           (unsigned long long)s->outside, (unsigned long long)s->discarded);
    CHECK(s->restarts == 0 && s->discarded == 640ull * 37);
    CHECK(s->outside > 100000 && sum > 100000); /* the frame cuts the fern: both are large */
    run_free(&r);
}

static bool same_run(const run_out *a, const run_out *b)
{
    size_t n = (size_t)a->width * a->height;
    return a->count && b->count && !memcmp(a->count, b->count, n * 4) && !memcmp(a->colour, b->colour, n * 4) &&
           a->stats.hits == b->stats.hits && a->stats.outside == b->stats.outside &&
           a->stats.discarded == b->stats.discarded;
}

/* The same histogram on 1, 2 and 3 threads, on lavapipe, and with condensation. */
static void test_determinism(fb_engine *engines, int nengines)
{
    const char *scenes[3] = {
        "{\"size\": [300, 200], \"seed\": 11, \"layers\": [{\"type\": \"ifs\", \"preset\": \"maple\", "
        "\"points\": 3000000, \"oversample\": 2}]}",
        "{\"size\": [300, 200], \"seed\": 12, \"layers\": [{\"type\": \"ifs\", \"preset\": \"population\", "
        "\"points\": 3000000}]}",
        "{\"size\": [300, 200], \"seed\": 13, \"layers\": [{\"type\": \"ifs\", \"maps\": [[0.6, 0, 0, 0.6, 0.4, 0]], "
        "\"condensation\": {\"preset\": \"stochastic\", \"iterations\": 4}, \"points\": 3000000}]}",
    };
    for (int sc = 0; sc < 3; sc++) {
        run_out first;
        fb_result rc = run_scene(&engines[0], scenes[sc], &first);
        CHECKF(rc == FB_OK, "%s", g_last_error);
        for (int i = 1; i < nengines && !rc; i++) {
            run_out r;
            rc = run_scene(&engines[i], scenes[sc], &r);
            CHECKF(rc == FB_OK && same_run(&first, &r), "scene %d: engine %d (%s, %d threads) differs", sc, i,
                   fb_backend_name(engines[i].kind), engines[i].threads);
            run_free(&r);
        }
        run_free(&first);
    }
}

/* More points than a fold interval of the device's 64-bit cells (kernels/ifs.h, 2^28 - 1), all into
 * one cell: a map onto the point (0.5, 0.5), the pixel (8, 8) of a 16 x 16 frame [0, 1]^2. The cell
 * holds every point plotted, on every engine, with the same colour: the fold (shaders/ifs_fold.comp)
 * carried the hits past 2^28 and the colour sum past 2^32 exactly. */
static void test_fold(fb_engine *engines, int nengines)
{
    const char *json = "{\"size\": [16, 16], \"seed\": 5, \"layers\": [{\"type\": \"ifs\", \"maps\": "
                       "[[0, 0, 0, 0, 0.5, 0.5]], \"bounds\": [0, 1, 0, 1], \"points\": 280000000}]}";
    run_out first;
    fb_result rc = run_scene(&engines[0], json, &first);
    CHECKF(rc == FB_OK, "%s", g_last_error);
    if (rc) return;
    uint64_t plotted = 280000000ull - first.stats.discarded;
    CHECKF(first.count[8 * 16 + 8] == plotted && first.stats.hits == plotted && plotted > (1u << 28),
           "one cell: %u hits of %llu plotted", first.count[8 * 16 + 8], (unsigned long long)plotted);
    for (int i = 1; i < nengines; i++) {
        if (engines[i].kind != FB_BACKEND_VULKAN) continue;
        run_out r;
        rc = run_scene(&engines[i], json, &r);
        CHECKF(rc == FB_OK && same_run(&first, &r), "the fold: %s differs from native (%u hits)", engines[i].device,
               rc ? 0u : r.count[8 * 16 + 8]);
        if (!rc) run_free(&r);
    }
    run_free(&first);
}

/* The population: trees at x_k = 1 - 0.75^k whose tops are at 0.75^k times the first one's; C the
 * tree IFS (the preset) or an L-system tree 0.25 high. */
static void test_condensation_row(fb_engine *e, const char *set)
{
    const double b[4] = {-0.2, 1.1, -0.02, 0.3};
    char json[512];
    snprintf(json, sizeof json,
             "{\"size\": [2048, 504], \"seed\": 4, \"layers\": [{\"type\": \"ifs\", %s, "
             "\"points\": 40000000, \"bounds\": [%g, %g, %g, %g]}]}",
             set, b[0], b[1], b[2], b[3]);
    run_out r;
    fb_result rc = run_scene(e, json, &r);
    CHECKF(rc == FB_OK, "%s", g_last_error);
    if (rc) return;
    double top[5];
    for (int k = 0; k < 5; k++) {
        double xk = 1 - pow(0.75, k), half = 0.1 * pow(0.75, k);
        int c0 = (int)((xk - half - b[0]) / (b[1] - b[0]) * r.width);
        int c1 = (int)((xk + half - b[0]) / (b[1] - b[0]) * r.width);
        int row = r.height;
        for (int y = 0; y < r.height && row == r.height; y++)
            for (int x = c0; x <= c1; x++)
                if (r.count[y * r.width + x]) {
                    row = y;
                    break;
                }
        top[k] = b[3] - (row + 0.5) / r.height * (b[3] - b[2]); /* the tree stands on y = 0 */
    }
    for (int k = 0; k + 1 < 5; k++)
        CHECKF(fabs(top[k + 1] / top[k] - 0.75) < 0.025, "%s: tree %d to %d: height ratio %.4f (tops %.4f, %.4f)", set,
               k, k + 1, top[k + 1] / top[k], top[k], top[k + 1]);
    run_free(&r);
}

static double seg_dist(double px, double py, double ax, double ay, double bx, double by)
{
    double dx = bx - ax, dy = by - ay, t = ((px - ax) * dx + (py - ay) * dy) / (dx * dx + dy * dy);
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return hypot(px - ax - t * dx, py - ay - t * dy);
}

/* An L-system condensation set with w0 taken at every step: every plotted point lies on the drawing
 * (the turtle's segments, base at the origin, scaled to `height`), so every hit cell's centre is
 * within half a cell diagonal of a segment; and the drawing is covered end to end. */
static void test_condensation_lsystem(fb_engine *e)
{
    const char *json = "{\"size\": [200, 200], \"seed\": 3, \"layers\": [{\"type\": \"ifs\", \"maps\": [[0.5, 0, 0, "
                       "0.5, 0, 0]], \"condensation\": {\"axiom\": \"F[+F]F[-F]F\", \"angle\": 30, \"height\": 1.5}, "
                       "\"condensation-probability\": 1, \"points\": 400000, \"bounds\": [-1, 1, -0.25, 1.75]}]}";
    run_out r;
    CHECKF(run_scene(e, json, &r) == FB_OK, "%s", g_last_error);
    if (!r.count) return;
    /* the drawing by hand: a stem of three steps with a branch at 30 degrees either side after the first */
    const double c30 = cos(M_PI / 6), s30 = sin(M_PI / 6), k = 1.5 / 3.0; /* extent 3 steps -> 1.5 */
    const double seg[5][4] = {{0, 0, 0, 1}, {0, 1, -s30, 1 + c30}, {0, 1, 0, 2}, {0, 2, s30, 2 + c30}, {0, 2, 0, 3}};
    int far = 0, hit = 0;
    double top = 0;
    for (int y = 0; y < 200; y++)
        for (int x = 0; x < 200; x++) {
            if (!r.count[y * 200 + x]) continue;
            hit++;
            double px = -1 + (x + 0.5) * 0.01, py = 1.75 - (y + 0.5) * 0.01, d = 1e9;
            for (int i = 0; i < 5; i++)
                d = fmin(d, seg_dist(px, py, seg[i][0] * k, seg[i][1] * k, seg[i][2] * k, seg[i][3] * k));
            far += d > 0.01 * M_SQRT1_2 + 1e-6;
            top = fmax(top, py);
        }
    CHECKF(far == 0 && hit > 240, "%d of %d hit cells off the drawing", far, hit);
    CHECKF(fabs(top - 1.5) < 0.011, "the drawing's top at %g, expected 1.5", top);
    run_free(&r);
}

/* `colors`: all maps at 0 or all at 1 pin every hit pixel's colour there (the start colour 0.5 has
 * halved away by the end of the transient); `condensation` as a map list equals the preset that uses
 * the same set; `condensation-probability` is the share of points on C itself (the first tree). */
static void test_keys(fb_engine *e)
{
    for (int v = 0; v <= 1; v++) {
        char json[256];
        snprintf(json, sizeof json,
                 "{\"size\": [96, 96], \"layers\": [{\"type\": \"ifs\", \"points\": 300000, \"colors\": [%d, %d, %d, "
                 "%d]}]}",
                 v, v, v, v);
        run_out r;
        CHECKF(run_scene(e, json, &r) == FB_OK, "%s", g_last_error);
        int bad = 0, hit = 0;
        for (int i = 0; i < 96 * 96; i++)
            if (r.count[i]) hit++, bad += r.colour[i] != (float)v;
        CHECKF(hit > 500 && bad == 0, "colors all %d: %d of %d hit pixels have another colour", v, bad, hit);
        run_free(&r);
    }
    fb_ifs tree;
    fb_ifs_preset("tree", &tree, NULL, NULL);
    char maps[512] = "";
    for (int k = 0; k < tree.n; k++)
        snprintf(maps + strlen(maps), sizeof maps - strlen(maps), "%s[%.17g, %.17g, %.17g, %.17g, %.17g, %.17g, %.17g]",
                 k ? ", " : "", tree.m[k].a, tree.m[k].b, tree.m[k].c, tree.m[k].d, tree.m[k].e * 0.25,
                 tree.m[k].f * 0.25, tree.m[k].p);
    char a[1024], b[256];
    snprintf(a, sizeof a,
             "{\"size\": [160, 60], \"seed\": 2, \"layers\": [{\"type\": \"ifs\", \"points\": 500000, \"maps\": "
             "[[0.75, 0, 0, 0.75, 0.25, 0]], \"condensation\": [%s]}]}",
             maps);
    snprintf(b, sizeof b,
             "{\"size\": [160, 60], \"seed\": 2, \"layers\": [{\"type\": \"ifs\", \"points\": 500000, \"preset\": "
             "\"population\"}]}");
    run_out ra, rb;
    CHECKF(run_scene(e, a, &ra) == FB_OK && run_scene(e, b, &rb) == FB_OK, "%s", g_last_error);
    CHECK(same_run(&ra, &rb));
    run_free(&ra), run_free(&rb);
    const double p0[2] = {0.2, 0.6};
    for (int k = 0; k < 2; k++) {
        snprintf(a, sizeof a,
                 "{\"size\": [1300, 100], \"layers\": [{\"type\": \"ifs\", \"preset\": \"population\", \"points\": "
                 "2000000, \"condensation-probability\": %g, \"bounds\": [-0.2, 1.1, -0.02, 0.3]}]}",
                 p0[k]);
        run_out r;
        CHECKF(run_scene(e, a, &r) == FB_OK, "%s", g_last_error);
        uint64_t first = 0, all = 0; /* the first tree: x < 0.14, i.e. columns < 340 */
        for (int y = 0; y < r.height; y++)
            for (int x = 0; x < r.width; x++) {
                all += r.count[y * r.width + x];
                if (x < 340) first += r.count[y * r.width + x];
            }
        double share = (double)first / (double)all;
        CHECKF(fabs(share - p0[k]) < 0.01, "condensation-probability %g: %.4f of the hits on the first tree", p0[k],
               share);
        run_free(&r);
    }
}

/* ---- kernel details ------------------------------------------------------------------------- */

static void test_restart(void)
{
    K_IfsMap maps[2] = {{2, 0, 0, 2, 1, 0, 0.0f, 0u}, {0.5f, 0, 0, 0.5f, 0, 0, 1.0f, 0x80000000u}};
    K_IfsParams p;
    memset(&p, 0, sizeof p);
    p.seed = 1, p.chains = 1, p.nmaps = 2, p.skip = 3, p.limit = 100.0f;
    K_IfsChain s = k_ifs_init(p, 0);
    CHECK(s.left == 3 && s.x >= -1 && s.x < 1 && s.y >= -1 && s.y < 1);
    int restarts = 0;
    for (uint32_t t = 0; t < 10000; t++) {
        s = k_ifs_step(p, s, 0, t, maps);
        if (s.status == K_IFS_RESTART) {
            restarts++;
            CHECK(s.left == 3 && fabsf(s.x) <= 1 && fabsf(s.y) <= 1);
        }
        CHECK(fabsf(s.x) <= 100 && !isnan(s.x));
    }
    CHECK(restarts > 10); /* the expanding map wins runs of 7 often enough */
    s.x = NAN;
    s = k_ifs_step(p, s, 0, 1, maps);
    CHECK(s.status == K_IFS_RESTART && !isnan(s.x));
    /* cells: the frame's edges */
    p.x0 = 0, p.y0 = 1, p.sx = 10, p.sy = 10, p.hist_w = 10, p.hist_h = 10;
    CHECK(k_ifs_cell(p, 0.0f, 1.0f) == 0);
    CHECK(k_ifs_cell(p, 0.999f, 0.001f) == 99);
    CHECK(k_ifs_cell(p, 1.0f, 0.5f) == K_IFS_NONE && k_ifs_cell(p, -0.01f, 0.5f) == K_IFS_NONE);
    CHECK(k_ifs_cell(p, 0.5f, 1.01f) == K_IFS_NONE && k_ifs_cell(p, 0.5f, 0.0f) == K_IFS_NONE);
    CHECK(k_ifs_quant(0.0f) == 0 && k_ifs_quant(1.0f) == 255 && k_ifs_quant(0.5f) == 128);
}

static void test_reader(void)
{
    const char *text = "; a comment\n"
                       "binary { ; halves\n"
                       "  .5 0 0 .5 -2.5 0 .333333\n"
                       "  .5 0 0 .5 2.5 0 .333333 ; trailing\n"
                       "  .5 0 0 .5 0 2.5 .333334\n"
                       "}\n"
                       "3dfern (3D) {\n"
                       "  0 0 0 0 .18 0 0 0 0 0 0 0 .01\n"
                       "}\n"
                       "fern{0 0 0 .16 0 0 .01 .85 .04 -.04 .85 0 1.6 .85\n"
                       " .2 -.26 .23 .22 0 1.6 .07 -.15 .28 .26 .24 0 .44 .07}\n";
    fb_ifs ifs;
    CHECK(fb_ifs_parse_text(text, "t.ifs", NULL, &ifs) == FB_OK && ifs.n == 3 && ifs.m[1].e == 2.5);
    CHECK(fb_ifs_parse_text(text, "t.ifs", "fern", &ifs) == FB_OK && ifs.n == 4 && ifs.m[1].f == 1.6 &&
          ifs.m[3].p == 0.07);
    CHECK(fb_ifs_parse_text(text, "t.ifs", "nope", &ifs) == FB_ERR_INPUT && strstr(g_last_error, "binary, 3dfern"));
    CHECK(fb_ifs_parse_text(text, "t.ifs", "3dfern", &ifs) == FB_ERR_INPUT && strstr(g_last_error, "3D"));
    CHECKF(fb_ifs_parse_text("a {\n 1 2 3 4 5 6 x7\n}\n", "b.ifs", NULL, &ifs) == FB_ERR_INPUT &&
               strstr(g_last_error, "b.ifs:2:14: expected a number, found \"x7\""),
           "%s", g_last_error);
    CHECKF(fb_ifs_parse_text("a {\n 1 2 3 4 5 6\n}\n", "b.ifs", NULL, &ifs) == FB_ERR_INPUT &&
               strstr(g_last_error, "b.ifs:3:1:") && strstr(g_last_error, "6 numbers"),
           "%s", g_last_error);
    CHECKF(fb_ifs_parse_text("a {\n 1 2 3 4 5 6 7\n", "b.ifs", NULL, &ifs) == FB_ERR_INPUT &&
               strstr(g_last_error, "not closed"),
           "%s", g_last_error);
    CHECK(fb_ifs_parse_text("a 1 2 }", "b.ifs", NULL, &ifs) == FB_ERR_INPUT && strstr(g_last_error, "b.ifs:1:3:"));
    CHECK(fb_ifs_parse_text("", "e.ifs", NULL, &ifs) == FB_ERR_INPUT && strstr(g_last_error, "no 2D"));
    CHECK(fb_ifs_read_file("/nonexistent/x.ifs", NULL, &ifs) == FB_ERR_INPUT &&
          strstr(g_last_error, "/nonexistent/x.ifs: cannot open"));
}

static void test_checks(void)
{
    fb_ifs ifs = {2, {{0.5, 0, 0, 0.5, 0, 0, 0.5}, {0.5, 0, 0, 0.5, 1, 0, 0.5}}};
    int bad;
    char msg[256];
    CHECK(fb_ifs_valid(&ifs, &bad, msg, sizeof msg));
    ifs.m[1].p = -0.1;
    CHECK(!fb_ifs_valid(&ifs, &bad, msg, sizeof msg) && bad == 1 && strstr(msg, "negative"));
    ifs.m[0].p = ifs.m[1].p = 0;
    CHECK(!fb_ifs_valid(&ifs, &bad, msg, sizeof msg) && bad == -1 && strstr(msg, "sum to 0"));
    ifs.m[0].p = -1; /* not given, while map 1 gives one */
    CHECK(!fb_ifs_valid(&ifs, &bad, msg, sizeof msg) && strstr(msg, "every map or for none"));
    ifs.m[1].p = -1;
    ifs.m[1].a = 1.0;
    CHECK(!fb_ifs_valid(&ifs, &bad, msg, sizeof msg) && bad == 1 && strstr(msg, "not contractive"));
    ifs.m[1].a = 0.5, ifs.m[1].b = 0.9; /* rows of norm < 1, but the largest singular value is 1.02 */
    CHECK(!fb_ifs_valid(&ifs, &bad, msg, sizeof msg) && bad == 1);
    ifs.m[1].b = 0;
    ifs.n = 0;
    CHECK(!fb_ifs_valid(&ifs, &bad, msg, sizeof msg) && strstr(msg, "empty"));
    /* |det| weighting with a 1% floor: dets 0.25, 0.0625, 0 */
    fb_ifs d = {3, {{0.5, 0, 0, 0.5, 0, 0, -1}, {0.25, 0, 0, 0.25, 0, 0, -1}, {0, 0, 0, 0.3, 0, 0, -1}}};
    double p[3], sum = 0.25 + 0.0625 + 0.0025;
    fb_ifs_probabilities(&d, p);
    CHECK(fabs(p[0] - 0.25 / sum) < 1e-12 && fabs(p[1] - 0.0625 / sum) < 1e-12 && fabs(p[2] - 0.0025 / sum) < 1e-12);
    CHECK(fabs(fb_ifs_contraction(&(fb_ifs_map){0, -2, 0.5, 0, 0, 0, 0}) - 2) < 1e-12);
    /* presets: contractive, probabilities summing to 1 */
    const char *names[] = {"fern", "sierpinski", "maple", "tree", "spiral", "population"};
    for (int i = 0; i < 6; i++) {
        fb_ifs a, c;
        bool has;
        CHECK(fb_ifs_preset(names[i], &a, &c, &has) == FB_OK && fb_ifs_valid(&a, &bad, msg, sizeof msg));
        CHECK(has == (i == 5) && (!has || fb_ifs_valid(&c, &bad, msg, sizeof msg)));
    }
}

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

static void test_tone(void)
{
    /* the reference density: the 99.5th percentile of the positive values, against a sort */
    enum { N = 5000 };
    static float d[N], pos[N];
    int m = 0;
    for (int i = 0; i < N; i++) {
        d[i] = i % 3 == 0 ? 0.0f : (float)(rnd() * 100);
        if (d[i] > 0) pos[m++] = d[i];
    }
    qsort(pos, (size_t)m, sizeof *pos, cmp_float);
    CHECK(fb_ifs_density_ref(d, N) == pos[(int)(0.995 * (m - 1))]);
    fb_ifs_tone t = {.brightness = 1, .gamma = 2, .threshold = 0.01, .vibrancy = 1, .highlight = 1, .dref = 50};
    for (int i = 0; i < 256; i++) t.palette[i][0] = t.palette[i][1] = t.palette[i][2] = 1.0f;
    float dens[4] = {0, 50, 5, 5000}, col[4] = {0.5f, 0.5f, 0.5f, 0.5f}, R[4], G[4], B[4], A[4];
    fb_ifs_tonemap_row(&t, dens, col, 4, R, G, B, A);
    CHECK(R[0] == 0 && A[0] == 0);
    CHECK(fabsf(A[1] - 1.0f) < 1e-6f && fabsf(R[1] - 1.0f) < 1e-6f); /* dref: full */
    float a5 = (float)sqrt(log1p(5.0) / log1p(50.0));
    CHECK(fabsf(A[2] - a5) < 1e-6f && fabsf(G[2] - a5) < 1e-6f);
    CHECK(A[3] == 1.0f && R[3] <= 1.0f && B[3] <= 1.0f); /* over-bright: highlight handling keeps <= 1 */
    /* vibrancy 0: the gamma per channel, on a grey palette */
    for (int i = 0; i < 256; i++) t.palette[i][0] = t.palette[i][1] = t.palette[i][2] = 0.5f;
    t.vibrancy = 0;
    fb_ifs_tonemap_row(&t, dens, col, 4, R, G, B, A);
    float g5 = (float)sqrt(0.5 * log1p(5.0) / log1p(50.0));
    CHECK(fabsf(R[2] - g5) < 1e-6f && fabsf(A[2] - a5) < 1e-6f);
    t.vibrancy = 1;
    fb_ifs_tonemap_row(&t, dens, col, 4, R, G, B, A);
    CHECK(fabsf(R[2] - 0.5f * a5) < 1e-6f);
    /* the linear part below the threshold meets the curve there */
    t.dref = exp(1.0) - 1; /* alin = log1p(d) */
    float tiny[1] = {(float)expm1(0.01)}, tiny2[1] = {(float)expm1(0.005)}, c1[1] = {0.5f}, r1, g1, b1, a1, a2;
    fb_ifs_tonemap_row(&t, tiny, c1, 1, &r1, &g1, &b1, &a1);
    fb_ifs_tonemap_row(&t, tiny2, c1, 1, &r1, &g1, &b1, &a2);
    CHECK(fabsf(a1 - 0.1f) < 1e-5f && fabsf(a2 - 0.05f) < 1e-5f);
}

int main(int argc, char **argv)
{
    fb_log_set_sink(sink, NULL);
    test_restart();
    test_reader();
    test_checks();
    test_tone();

    fb_engine engines[4];
    bool have_gpu;
    int n = th_open_engines(argc, argv, engines, &have_gpu);
    /* --int32 (with FB_VK_NO_INT64=1): the device's 32-bit atomics, the histogram's words folded as a
     * device without 64-bit atomics has them; everything below holds the same there */
    bool int32 = false;
    for (int i = 1; i < argc; i++) int32 = int32 || !strcmp(argv[i], "--int32");
    if (have_gpu && int32) CHECKF(!vkc_info(engines[n - 1].vk)->int64_atomics, "--int32: 64-bit atomics still on");

    const double fern_b[4] = {-2.75, 2.75, -0.25, 10.25}, tri_b[4] = {-0.05, 1.05, -0.05, 0.9};
    for (int i = 0; i < n; i += (have_gpu ? 3 : 4)) {
        test_against_reference(&engines[i], "fern", fern_b);
        test_against_reference(&engines[i], "sierpinski", tri_b);
    }
    test_box_dimension(&engines[0]);
    test_accounting(&engines[0]);
    if (have_gpu) test_accounting(&engines[n - 1]);
    test_determinism(engines, n);
    if (have_gpu) test_fold(engines, n);
    test_condensation_row(&engines[0], "\"preset\": \"population\"");
    test_condensation_row(&engines[0],
                          "\"maps\": [[0.75, 0, 0, 0.75, 0.25, 0]], \"condensation\": {\"preset\": \"tree\"}");
    test_condensation_lsystem(&engines[0]);
    test_keys(&engines[0]);
    if (have_gpu) CHECKF(vkc_validation_messages(engines[n - 1].vk) == 0, "validation layer messages");
    for (int i = 0; i < n; i++) fb_engine_close(&engines[i]);
    TEST_REPORT();
}
