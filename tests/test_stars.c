/*
 * The stars generator: star counts per magnitude against the asked slope (the maximum-likelihood
 * slope of a large sample) and the asked count brighter than magnitude 6; the Milky Way's density
 * contrast; blackbody colours (luminance 1, hot stars blue, cool ones red); the total flux of the
 * image (the sum of value times the pixel's exact solid angle, computed here in double) equal to
 * the stars' total within 1e-5 at three sizes of every mapping; the same stars at two sizes (the
 * brightest stars' centroids as directions), also as a cube; and the same bits on 1, 2 and 3
 * threads, any strip height, and lavapipe (a GPU within 1e-6 relative: the cube's square roots).
 */
#include "bake.h"
#include "catalog.h"
#include "exrio.h"
#include "gen.h"
#include "../kernels/envmap.h"

#include "testengines.h"
#include "testhelp.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char g_last_error[1024];

static void sink(int level, const char *msg, void *user)
{
    (void)user;
    if (level == FB_LOG_ERROR) snprintf(g_last_error, sizeof g_last_error, "%s", msg);
}

static fb_stars_params defaults(void)
{
    fb_stars_params P = {.mapping = 1,
                         .limit = 8,
                         .slope = 0.49,
                         .count6 = 4970,
                         .brightness = 1,
                         .psf = 1,
                         .milky_way = 0,
                         .mw_width = 8,
                         .pole = {192.86, 27.13}};
    return P;
}

/* ---- the catalogue ----------------------------------------------------------------------------- */

/* The maximum-likelihood slope of magnitudes drawn with density ~ 10^(a m) below `limit`:
 * 1 / (ln 10 mean(limit - m)); its standard error is a / sqrt(n). */
static double ml_slope(const fb_star *s, size_t n, double limit)
{
    double sum = 0;
    for (size_t i = 0; i < n; i++) sum += limit - s[i].mag;
    return n / (log(10.0) * sum);
}

static void check_counts(double slope, double limit, double count6, uint32_t seed)
{
    fb_stars_params P = defaults();
    P.slope = slope, P.limit = limit, P.count6 = count6;
    fb_star *s = NULL;
    size_t n = 0;
    fb_result rc = fb_stars_catalog(&P, seed, &s, &n);
    CHECKF(rc == FB_OK, "%s", g_last_error);
    if (rc) return;
    double expect = fb_stars_expected(&P);
    size_t n6 = 0;
    for (size_t i = 0; i < n; i++) n6 += s[i].mag < 6;
    double a = ml_slope(s, n, limit), se = slope / sqrt((double)n);
    /* the bound 0.03, and 5 standard errors of the estimate */
    CHECKF(fabs(a - slope) < 0.03 && fabs(a - slope) < 5 * se, "slope %.4f asked %.4f (n %zu, se %.4f)", a, slope, n,
           se);
    /* Poisson counts: within 5 sigma of the expected */
    CHECKF(fabs(n - expect) < 5 * sqrt(expect), "%zu stars, expected %.0f", n, expect);
    CHECKF(fabs(n6 - count6) < 5 * sqrt(count6), "%zu brighter than 6, asked %.0f", n6, count6);
    /* directions: unit, and uniform over the sphere (each axis' mean within 5 sigma of 0: var 1/3) */
    double m[3] = {0, 0, 0}, worst = 0;
    for (size_t i = 0; i < n; i++) {
        double l = sqrt(s[i].dir[0] * s[i].dir[0] + s[i].dir[1] * s[i].dir[1] + s[i].dir[2] * s[i].dir[2]);
        worst = fmax(worst, fabs(l - 1));
        for (int c = 0; c < 3; c++) m[c] += s[i].dir[c];
    }
    CHECK(worst < 1e-12);
    for (int c = 0; c < 3; c++)
        CHECKF(fabs(m[c] / n) < 5 * sqrt(1.0 / 3 / n), "axis %d mean %.4f over %zu stars", c, m[c] / n, n);
    free(s);
}

static void test_counts(void)
{
    check_counts(0.49, 10, 4970, 1);
    check_counts(0.35, 9, 2000, 7);
    check_counts(0.6, 8.5, 10000, 3);

    /* the same scene twice: the same catalogue */
    fb_stars_params P = defaults();
    fb_star *a = NULL, *b = NULL;
    size_t na = 0, nb = 0;
    CHECK(fb_stars_catalog(&P, 5, &a, &na) == FB_OK && fb_stars_catalog(&P, 5, &b, &nb) == FB_OK);
    CHECK(na == nb && na > 0 && !memcmp(a, b, na * sizeof *a));
    free(a), free(b);
}

/* The Milky Way: stars within 5 degrees of the band's plane are denser than those beyond 30 by
 * about the contrast (clouds vary it), and the slope does not change. */
static void test_milky_way(void)
{
    fb_stars_params P = defaults();
    P.milky_way = 4, P.mw_width = 10, P.limit = 9;
    double pole[3] = {sin(P.pole[0] * M_PI / 180) * cos(P.pole[1] * M_PI / 180), sin(P.pole[1] * M_PI / 180),
                      cos(P.pole[0] * M_PI / 180) * cos(P.pole[1] * M_PI / 180)};
    fb_star *s = NULL;
    size_t n = 0;
    CHECKF(fb_stars_catalog(&P, 2, &s, &n) == FB_OK, "%s", g_last_error);
    size_t in = 0, out = 0;
    for (size_t i = 0; i < n; i++) {
        double z = s[i].dir[0] * pole[0] + s[i].dir[1] * pole[1] + s[i].dir[2] * pole[2];
        in += fabs(z) < sin(5 * M_PI / 180);
        out += fabs(z) > sin(30 * M_PI / 180);
    }
    /* per steradian: the band |b| < 5 covers 4 pi sin 5deg, |b| > 30 covers 4 pi (1 - sin 30deg) */
    double ratio = (in / sin(5 * M_PI / 180)) / (out / (1 - sin(30 * M_PI / 180)));
    CHECKF(ratio > 2.5 && ratio < 8, "band density %.2f times the sky far from it (contrast 4)", ratio);
    double expect = fb_stars_expected(&P);
    CHECKF(fabs(n - expect) < 0.03 * expect, "%zu stars with the band, expected %.0f", n, expect);
    double a = ml_slope(s, n, P.limit);
    CHECKF(fabs(a - 0.49) < 5 * 0.49 / sqrt((double)n), "slope %.4f with the band", a);
    free(s);
}

static void test_colours(void)
{
    double hot[3], sun[3], cool[3];
    fb_stars_blackbody(20000, hot);
    fb_stars_blackbody(5800, sun);
    fb_stars_blackbody(3000, cool);
    const double *c[3] = {hot, sun, cool};
    for (int i = 0; i < 3; i++) {
        double lum = 0.2126729 * c[i][0] + 0.7151522 * c[i][1] + 0.0721750 * c[i][2];
        CHECKF(fabs(lum - 1) < 1e-12 && c[i][0] >= 0 && c[i][1] >= 0 && c[i][2] >= 0, "luminance %g", lum);
    }
    CHECK(hot[2] > hot[0] && cool[0] > cool[2] && cool[0] > 1.5 * cool[2]);
    /* the sun is near white: each channel within 25% of the others */
    CHECKF(fabs(sun[0] / sun[2] - 1) < 0.25 && fabs(sun[1] / sun[2] - 1) < 0.25, "sun %g %g %g", sun[0], sun[1],
           sun[2]);
}

/* ---- images ------------------------------------------------------------------------------------ */

typedef struct image {
    float *p[4]; /* R, G, B, mag */
    int w, h;
    unsigned mapping;
} image;

static fb_result render(const char *mapping, int w, int h, const char *extra, image *out)
{
    char json[512];
    snprintf(json, sizeof json,
             "{\"size\": [%d, %d], \"seed\": 3, \"layers\": [{\"type\": \"stars\", \"mapping\": \"%s\"%s}]}", w, h,
             mapping, extra ? extra : "");
    fb_scene s;
    memset(out, 0, sizeof *out);
    fb_result rc = fb_scene_parse(json, NULL, &s);
    if (rc) return rc;
    fb_gen g;
    rc = fb_gen_init(&g, &s, &s.layers[0]);
    if (!rc) {
        size_t n = (size_t)w * h;
        for (int c = 0; c < 4; c++) out->p[c] = calloc(n, 4);
        g.compute.native_rows(&g, 0, h, (void *const *)out->p);
        out->w = w, out->h = h;
        out->mapping = ((const fb_stars_params *)fb_layer_params(&s.layers[0]))->mapping;
        fb_gen_fini(&g);
    }
    fb_scene_fini(&s);
    return rc;
}

static void image_free(image *im)
{
    for (int c = 0; c < 4; c++) free(im->p[c]);
}

static double face_F(double s, double t)
{
    return atan(s * t / sqrt(1 + s * s + t * t));
}

/* The exact solid angle of pixel (x, y): its box clipped to the image (lat-long: its half pixels on
 * the poles and the seam) or to its face (cube), in OpenEXR's layout. */
static double pixel_omega(const image *im, int x, int y)
{
    double W = im->w, H = im->h;
    if (im->mapping == 1) { /* lat-long */
        double dl = 2 * M_PI / (W - 1) * ((x == 0 || x == im->w - 1) ? 0.5 : 1.0);
        double c = M_PI / 2 - y * M_PI / (H - 1), h = 0.5 * M_PI / (H - 1);
        return dl * (sin(fmin(c + h, M_PI / 2)) - sin(fmax(c - h, -M_PI / 2)));
    }
    if (im->mapping == 2) { /* cube */
        int n = im->w, b = y % n;
        double k = 2.0 / (n - 1);
        double s0 = fmax(x - 0.5, 0) * k - 1, s1 = fmin(x + 0.5, n - 1) * k - 1;
        double t0 = fmax(b - 0.5, 0) * k - 1, t1 = fmin(b + 0.5, n - 1) * k - 1;
        return face_F(s1, t1) - face_F(s0, t1) - face_F(s1, t0) + face_F(s0, t0);
    }
    /* polar: azimuth 2 pi / W, zenith angle 2 atan(v) over the row's radii */
    double v0 = 1 - (y + 1.0) / H, v1 = 1 - y / H;
    return 2 * M_PI / W * ((1 - v0 * v0) / (1 + v0 * v0) - (1 - v1 * v1) / (1 + v1 * v1));
}

/* The stars' total luminance flux (polar: the upper hemisphere's), from the catalogue. */
static double catalogue_flux(unsigned mapping)
{
    fb_stars_params P = defaults();
    fb_star *s = NULL;
    size_t n = 0;
    if (fb_stars_catalog(&P, 3, &s, &n)) return -1;
    double f = 0;
    for (size_t i = 0; i < n; i++)
        if (mapping != 3 || s[i].dir[1] > 0) f += pow(10.0, -0.4 * s[i].mag);
    free(s);
    return f;
}

static void test_flux(void)
{
    static const struct {
        const char *mapping;
        unsigned id;
        int size[3][2];
    } cases[] = {
        {"latlong", 1, {{48, 24}, {250, 125}, {1024, 512}}},
        {"cube", 2, {{24, 144}, {97, 582}, {256, 1536}}},
        {"polar", 3, {{64, 32}, {301, 200}, {1024, 512}}},
    };
    double worst = 0;
    for (int m = 0; m < 3; m++) {
        double want = catalogue_flux(cases[m].id), omega_sum = 0;
        for (int k = 0; k < 3; k++) {
            image im;
            int w = cases[m].size[k][0], h = cases[m].size[k][1];
            fb_result rc = render(cases[m].mapping, w, h, NULL, &im);
            CHECKF(rc == FB_OK, "%s", g_last_error);
            if (rc) continue;
            double lum = 0, rgb[3] = {0, 0, 0};
            omega_sum = 0;
            for (int y = 0; y < h; y++)
                for (int x = 0; x < w; x++) {
                    size_t i = (size_t)y * w + x;
                    double o = pixel_omega(&im, x, y);
                    omega_sum += o;
                    for (int c = 0; c < 3; c++) rgb[c] += im.p[c][i] * o;
                }
            lum = 0.2126729 * rgb[0] + 0.7151522 * rgb[1] + 0.0721750 * rgb[2];
            CHECKF(fabs(lum / want - 1) < 1e-5, "%s %d x %d: flux %.9g, the stars' %.9g (relative %.2g)",
                   cases[m].mapping, w, h, lum, want, lum / want - 1);
            worst = fmax(worst, fabs(lum / want - 1));
            double sky = cases[m].id == 3 ? 2 * M_PI : 4 * M_PI;
            CHECKF(fabs(omega_sum / sky - 1) < 1e-12, "%s: the pixels cover %.15g sr", cases[m].mapping, omega_sum);
            image_free(&im);
        }
    }
    printf("flux: the largest relative difference from the stars' total over 9 images is %.2g\n", worst);
}

/* ---- the same stars at two sizes ------------------------------------------------------------------ */

static void normalise(double d[3])
{
    double l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int i = 0; i < 3; i++) d[i] /= l;
}

/* The direction of lat-long position (x, y) (OpenEXR's convention, written out here). */
static void latlong_dir(const image *im, double x, double y, double d[3])
{
    double lat = -M_PI * (y / (im->h - 1) - 0.5), lon = -2 * M_PI * (x / (im->w - 1) - 0.5);
    d[0] = sin(lon) * cos(lat), d[1] = sin(lat), d[2] = cos(lon) * cos(lat);
}

/* The flux-weighted centroid, as a direction, of the pixels within 3 of the brightest pixel within 4
 * of lat-long position (x, y); false if nothing is lit there. */
static bool centroid(const image *im, double x, double y, double d[3])
{
    int bx = -1, by = -1;
    float best = 0;
    for (int j = (int)y - 4; j <= (int)y + 4; j++)
        for (int i = (int)x - 4; i <= (int)x + 4; i++) {
            if (i < 0 || j < 0 || i >= im->w || j >= im->h) continue;
            float v = im->p[1][(size_t)j * im->w + i];
            if (v > best) best = v, bx = i, by = j;
        }
    if (bx < 0) return false;
    double sum[3] = {0, 0, 0};
    for (int j = by - 3; j <= by + 3; j++)
        for (int i = bx - 3; i <= bx + 3; i++) {
            if (i < 0 || j < 0 || i >= im->w || j >= im->h) continue;
            double e[3], f = im->p[1][(size_t)j * im->w + i] * pixel_omega(im, i, j);
            latlong_dir(im, i, j, e);
            for (int c = 0; c < 3; c++) sum[c] += f * e[c];
        }
    normalise(sum);
    memcpy(d, sum, sizeof sum);
    return true;
}

/* The same for cube position (x, y): the flux-weighted centroid of the pixels of its face within 3
 * of the brightest within 4, their directions from kernels/envmap.h (checked against OpenEXR's). */
static bool cube_centroid(const image *im, double x, double y, double d[3])
{
    int n = im->w, f0 = (int)floor((y + 0.5) / n) * n, bx = -1, by = -1;
    float best = 0;
    for (int j = (int)y - 4; j <= (int)y + 4; j++)
        for (int i = (int)x - 4; i <= (int)x + 4; i++) {
            if (i < 0 || j < f0 || i >= n || j >= f0 + n) continue;
            float v = im->p[1][(size_t)j * n + i];
            if (v > best) best = v, bx = i, by = j;
        }
    if (bx < 0) return false;
    double sum[3] = {0, 0, 0};
    for (int j = by - 3; j <= by + 3; j++)
        for (int i = bx - 3; i <= bx + 3; i++) {
            if (i < 0 || j < f0 || i >= n || j >= f0 + n) continue;
            k_vec3 e = k_env_cube_dir((float)i, (float)j, (uint32_t)n);
            double v[3] = {e.x, e.y, e.z}, f = im->p[1][(size_t)j * n + i] * pixel_omega(im, i, j);
            normalise(v);
            for (int c = 0; c < 3; c++) sum[c] += f * v[c];
        }
    normalise(sum);
    memcpy(d, sum, sizeof sum);
    return true;
}

/* The same stars in another mapping: the brightest stars away from the cube's edges, centred in a
 * 256-pixel cube where the 1024-wide lat-long map has them. */
static void test_mappings(void)
{
    fb_stars_params P = defaults();
    fb_star *s = NULL;
    size_t n = 0;
    CHECK(fb_stars_catalog(&P, 3, &s, &n) == FB_OK);
    image a, c;
    CHECKF(render("latlong", 1024, 512, NULL, &a) == FB_OK, "%s", g_last_error);
    CHECKF(render("cube", 256, 1536, NULL, &c) == FB_OK, "%s", g_last_error);
    if (!a.p[0] || !c.p[0] || !s) return;
    int checked = 0, close = 0;
    double pix = 2.0 / 255; /* a cube pixel's angle at the face's centre, its largest */
    for (int k = 0; k < 40; k++) {
        size_t best = n;
        for (size_t i = 0; i < n; i++)
            if (fabs(s[i].dir[1]) < 0.9 && (best == n || s[i].mag < s[best].mag)) best = i;
        if (best == n) break;
        double *d = s[best].dir, lat = asin(d[1]), lon = atan2(d[0], d[2]);
        s[best].mag = 1e9;
        k_vec2 cp = k_env_cube_pos(k_vec3((float)d[0], (float)d[1], (float)d[2]), 256);
        double b = fmod(cp.y, 256);
        if (cp.x < 5 || cp.x > 250 || b < 5 || b > 250) continue; /* split between faces */
        double ax = (lon / (-2 * M_PI) + 0.5) * (a.w - 1), ay = (lat / (-M_PI) + 0.5) * (a.h - 1);
        double da[3], dc[3];
        if (!centroid(&a, ax, ay, da) || !cube_centroid(&c, cp.x, cp.y, dc)) continue;
        double ang = acos(fmin(1, da[0] * dc[0] + da[1] * dc[1] + da[2] * dc[2]));
        checked++;
        close += ang < pix;
    }
    CHECKF(checked >= 25 && close >= checked - 2, "%d of %d stars within a cube pixel in both mappings", close,
           checked);
    image_free(&a);
    image_free(&c);
    free(s);
}

static void test_positions(void)
{
    fb_stars_params P = defaults();
    fb_star *s = NULL;
    size_t n = 0;
    CHECK(fb_stars_catalog(&P, 3, &s, &n) == FB_OK);
    image a, b;
    CHECKF(render("latlong", 256, 128, NULL, &a) == FB_OK, "%s", g_last_error);
    CHECKF(render("latlong", 1024, 512, NULL, &b) == FB_OK, "%s", g_last_error);
    if (!a.p[0] || !b.p[0]) return;
    /* the 40 brightest stars away from the poles */
    int checked = 0, close = 0;
    double pix = M_PI / (a.h - 1), worst = 0;
    for (int k = 0; k < 40; k++) {
        size_t best = n;
        for (size_t i = 0; i < n; i++)
            if (fabs(s[i].dir[1]) < 0.9 && (best == n || s[i].mag < s[best].mag)) best = i;
        if (best == n) break;
        double *d = s[best].dir, lat = asin(d[1]), lon = atan2(d[0], d[2]);
        s[best].mag = 1e9; /* taken */
        double ax = (lon / (-2 * M_PI) + 0.5) * (a.w - 1), ay = (lat / (-M_PI) + 0.5) * (a.h - 1);
        double bx = (lon / (-2 * M_PI) + 0.5) * (b.w - 1), by = (lat / (-M_PI) + 0.5) * (b.h - 1);
        double da[3], db[3];
        if (!centroid(&a, ax, ay, da) || !centroid(&b, bx, by, db)) continue;
        double ang = acos(fmin(1, da[0] * db[0] + da[1] * db[1] + da[2] * db[2]));
        double to_star = acos(fmin(1, da[0] * d[0] + da[1] * d[1] + da[2] * d[2]));
        checked++;
        close += ang < pix && to_star < pix;
        worst = fmax(worst, ang);
    }
    /* a fainter neighbour may pull a centroid; nearly all must agree within a coarse pixel */
    CHECKF(checked == 40 && close >= 38, "%d of %d stars within a pixel (%.3g rad) at both sizes, worst %.3g", close,
           checked, pix, worst);
    image_free(&a);
    image_free(&b);
    free(s);
}

/* ---- bakes on every engine ------------------------------------------------------------------ */

static bool bake_read(fb_engine *e, const char *json, int strip, const char *path, image *out)
{
    fb_scene s;
    memset(out, 0, sizeof *out);
    if (fb_scene_parse(json, NULL, &s)) return false;
    fb_bake_stats st;
    fb_result rc = fb_bake(e, &(fb_bake_desc){.scene = &s, .out = path, .strip_rows = strip}, &st);
    exrio_reader *r = NULL;
    if (!rc) rc = exrio_open(path, &r);
    if (!rc) {
        size_t n = (size_t)s.width * s.height;
        void *planes[4];
        for (int c = 0; c < 4; c++) planes[c] = out->p[c] = calloc(n, 4);
        rc = exrio_read_rows(r, 0, s.height, planes); /* channels sorted by name: B, G, R, mag */
        out->w = s.width, out->h = s.height;
    }
    exrio_close(&r);
    unlink(path);
    fb_scene_fini(&s);
    return rc == FB_OK;
}

static void test_engines(fb_engine *engines, int n)
{
    static const char *const scenes[3] = {
        "{\"size\": [24, 144], \"seed\": 4, \"layers\": [{\"type\": \"stars\", \"mapping\": \"cube\", \"limit\": 9, "
        "\"milky-way\": 3}]}",
        "{\"size\": [300, 150], \"seed\": 9, \"layers\": [{\"type\": \"stars\", \"psf\": 1.7}]}",
        "{\"size\": [203, 97], \"seed\": 2, \"layers\": [{\"type\": \"stars\", \"mapping\": \"polar\"}]}",
    };
    const int strips[4] = {0, 7, 64, 211};
    char path[64];
    snprintf(path, sizeof path, "%s", th_path("stars.exr"));
    for (int k = 0; k < 3; k++) {
        image first;
        CHECKF(bake_read(&engines[0], scenes[k], 0, path, &first), "%s", g_last_error);
        size_t np = (size_t)first.w * first.h;
        for (int i = 1; i < n; i++) {
            image o;
            bool ok = bake_read(&engines[i], scenes[k], strips[i % 4], path, &o);
            bool same = ok && first.p[0];
            /* lavapipe and the native path round every operation alike; a GPU may round the cube's
             * square roots and divisions by an ulp or two (kernels/stars.h): 1e-6 relative there */
            double tol = engines[i].kind == FB_BACKEND_VULKAN && !strstr(engines[i].device, "llvmpipe") ? 1e-6 : 0;
            for (int c = 0; c < 4 && same; c++)
                for (size_t q = 0; q < np && same; q++)
                    same = first.p[c][q] == o.p[c][q] ||
                           (c < 3 && fabs(first.p[c][q] - o.p[c][q]) <= tol * fabs(first.p[c][q]));
            CHECKF(same, "scene %d: engine %d (%s, %d threads, strips of %d) differs", k, i,
                   fb_backend_name(engines[i].kind), engines[i].threads, strips[i % 4]);
            image_free(&o);
        }
        image_free(&first);
    }
}

int main(int argc, char **argv)
{
    fb_log_set_sink(sink, NULL);
    test_counts();
    test_milky_way();
    test_colours();
    test_flux();
    test_positions();
    test_mappings();

    fb_engine engines[4];
    bool have_gpu;
    int n = th_open_engines(argc, argv, engines, &have_gpu);
    test_engines(engines, n);
    if (have_gpu) CHECKF(vkc_validation_messages(engines[n - 1].vk) == 0, "validation layer messages");
    for (int i = 0; i < n; i++) fb_engine_close(&engines[i]);
    TEST_REPORT();
}
