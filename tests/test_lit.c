/*
 * The lit, coloured terrain (a terrain layer's "palette", "stops" or "cosine", with "light",
 * "ambient" and "colour-range"), checked against the closed form on surveys that are planes:
 * - a tilted plane under a light: every covered pixel's R, G, B is the palette's colour times
 *   ambient + (1 - ambient) max(0, n.l), n the plane's unit normal and l the light's direction
 *   (azimuth clockwise from north, y up; altitude above the horizon), with both interpolations;
 *   a plane facing away from the light gets the ambient alone;
 * - colour by height: a black-to-white ramp under an overhead light with no shading is the height
 *   mapped linearly from the mesh's lowest to its highest point, or from colour-range, clamped;
 * - outside the survey's hull (A = 0) the colour is 0, and without a palette there is no R, G, B.
 */
#include "bake.h"
#include "exrio.h"
#include "scene.h"

#include "testhelp.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { W = 96, H = 64 };

/* The terrain layer's channels of a bake of `json`: R, G, B, A, Y (W x H each) into ch[0..4]; false
 * when the bake fails or a channel is missing (want_rgb: whether R, G, B should exist). */
static bool bake(fb_engine *e, const char *json, float *ch[5], bool want_rgb)
{
    fb_scene s;
    if (fb_scene_parse(json, NULL, &s) != FB_OK) return false;
    const char *out = "test_lit.exr";
    fb_result rc = fb_bake(e, &(fb_bake_desc){.scene = &s, .out = out}, NULL);
    fb_scene_fini(&s);
    if (rc) return false;
    exrio_reader *r = NULL;
    if (exrio_open(out, &r) != FB_OK) return false;
    static const char *const names[5] = {"terrain.R", "terrain.G", "terrain.B", "terrain.A", "terrain.Y"};
    void *planes[16] = {0};
    bool ok = exrio_nchannels(r) <= 16;
    for (int c = 0; c < 5 && ok; c++) {
        int k = exrio_find_channel(r, names[c]);
        if (c < 3 && !want_rgb) {
            ok = k < 0;
            continue;
        }
        ok = k >= 0;
        if (ok) planes[k] = ch[c];
    }
    if (ok) ok = exrio_read_rows(r, 0, H, planes) == FB_OK;
    exrio_close(&r);
    remove(out);
    return ok;
}

/* A survey of the plane z = a x + b y + z0 over [0, 100] x [0, 60] (corners and a centre point),
 * nothing inserted, the frame larger than the hull so that some pixels are outside it. */
static void plane_scene(char *out, size_t size, double a, double b, double z0, const char *extra)
{
    double p[5][2] = {{0, 0}, {100, 0}, {0, 60}, {100, 60}, {37, 23}};
    char pts[512] = "";
    for (int i = 0; i < 5; i++)
        snprintf(pts + strlen(pts), sizeof pts - strlen(pts), "%s[%g, %g, %.17g]", i ? ", " : "", p[i][0], p[i][1],
                 a * p[i][0] + b * p[i][1] + z0);
    snprintf(out, size,
             "{\"size\": [%d, %d], \"layers\": [{\"type\": \"terrain\", \"insert\": 0, \"sigma\": 0, \"bounds\": [-10, "
             "110, -10, 70], \"points\": [%s], %s}]}",
             W, H, pts, extra);
}

/* The largest difference between R, G, B and want * (cr, cg, cb) over the covered pixels, and
 * the largest R, G, B outside. */
static void compare(float *const ch[5], double want, const double col[3], double *inside, double *outside, int *covered)
{
    *inside = *outside = 0;
    *covered = 0;
    for (int i = 0; i < W * H; i++)
        for (int c = 0; c < 3; c++) {
            if (ch[3][i] > 0.5f)
                *inside = fmax(*inside, fabs(ch[c][i] - want * col[c]));
            else
                *outside = fmax(*outside, fabs(ch[c][i]));
            *covered += ch[3][i] > 0.5f && c == 0;
        }
}

int main(void)
{
    fb_engine e;
    REQUIRE(fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE}, &e) == FB_OK);
    float *ch[5];
    for (int c = 0; c < 5; c++) REQUIRE((ch[c] = malloc(sizeof(float) * W * H)) != NULL);
    char json[2048];
    const double grey[3] = {0.5, 0.25, 0.75};

    /* a tilted plane under a light from azimuth 200, altitude 30, ambient 0.1 */
    const double a = -0.8, b = 1.3, az = 200 * M_PI / 180, alt = 30 * M_PI / 180, amb = 0.1;
    double lx = sin(az) * cos(alt), ly = cos(az) * cos(alt), lz = sin(alt);
    double d = (-a * lx - b * ly + lz) / sqrt(a * a + b * b + 1);
    double want = amb + (1 - amb) * fmax(d, 0);
    CHECKF(d > 0.3, "the plane should face the light (n.l = %g)", d);
    static const char *const interp[2] = {"linear", "smooth"};
    for (int k = 0; k < 2; k++) {
        char extra[512];
        snprintf(extra, sizeof extra,
                 "\"interpolation\": \"%s\", \"stops\": [[0, 0.5, 0.25, 0.75], [1, 0.5, 0.25, 0.75]], \"light\": "
                 "[200, 30], \"ambient\": 0.1",
                 interp[k]);
        plane_scene(json, sizeof json, a, b, 40, extra);
        REQUIRE(bake(&e, json, ch, true));
        double in, out;
        int covered;
        compare(ch, want, grey, &in, &out, &covered);
        CHECKF(covered > W * H / 2 && covered < W * H, "%s: %d of %d pixels covered", interp[k], covered, W * H);
        CHECKF(in < 2e-6, "%s: lit colour off by %g (want %g x the colour)", interp[k], in, want);
        CHECKF(out == 0, "%s: colour %g outside the hull", interp[k], out);
    }
    /* facing away from the light: the ambient alone */
    plane_scene(json, sizeof json, -a, -b, 40,
                "\"stops\": [[0, 0.5, 0.25, 0.75], [1, 0.5, 0.25, 0.75]], \"light\": [200, 30], \"ambient\": 0.1");
    CHECKF((-(-a) * lx - (-b) * ly + lz) < 0, "the mirrored plane should face away");
    REQUIRE(bake(&e, json, ch, true));
    {
        double in, out;
        int covered;
        compare(ch, amb, grey, &in, &out, &covered);
        CHECKF(in < 2e-6, "a plane facing away: off the ambient by %g", in);
    }

    /* colour by height: z = x (0 .. 100 over the hull), black to white, lit from overhead with no
     * ambient, so R = G = B = (z - lo) / (hi - lo), clamped */
    static const char *const ranges[2] = {"", ", \"colour-range\": [25, 75]"};
    for (int k = 0; k < 2; k++) {
        char extra[512];
        snprintf(extra, sizeof extra, "\"stops\": [[0, 0, 0, 0], [1, 1, 1, 1]], \"light\": [0, 90], \"ambient\": 0%s",
                 ranges[k]);
        plane_scene(json, sizeof json, 1, 0, 0, extra);
        REQUIRE(bake(&e, json, ch, true));
        double lo = k ? 25 : 0, hi = k ? 75 : 100, worst = 0;
        for (int i = 0; i < W * H; i++) {
            if (ch[3][i] < 0.5f) continue;
            double t = (ch[4][i] - lo) / (hi - lo);
            t = t < 0 ? 0 : t > 1 ? 1 : t;
            /* an overhead light on a slope of 45 degrees: n.l = cos 45 */
            double v = t * sqrt(0.5);
            for (int c = 0; c < 3; c++) worst = fmax(worst, fabs(ch[c][i] - v));
        }
        CHECKF(worst < 2e-6, "colour by height%s off by %g", k ? " (colour-range)" : "", worst);
    }

    /* no palette: no colour channels */
    plane_scene(json, sizeof json, a, b, 40, "\"hurst\": 0.8");
    CHECK(bake(&e, json, ch, false));

    for (int c = 0; c < 5; c++) free(ch[c]);
    fb_engine_close(&e);
    TEST_REPORT();
}
