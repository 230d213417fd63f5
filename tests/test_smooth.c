/*
 * The smooth terrain surface ("interpolation": "smooth", the Clough-Tocher element of smooth.h):
 * - the element alone: planes reproduced exactly; value and gradient continuous across a shared
 *   edge and across the split edges inside a triangle; the vertices' heights interpolated;
 * - the layer: every input point that falls on a pixel centre is that pixel's height exactly, with
 *   both interpolations;
 * - no facets: on a TIN of a smooth function, the largest second difference of the image
 *   (z[x-1] - 2 z[x] + z[x+1], pixels h apart) behaves like h^2 when the resolution doubles (a C1
 *   surface: its second differences are h^2 times a second derivative, which is bounded on every
 *   patch), where the planes' kinks at triangle edges make it behave like h (a jump of the gradient
 *   g gives |g| h). The bound stated: at twice the resolution the largest second difference of the
 *   smooth surface falls by at least 3x (4x ideally), the linear one's by at most 2.5x.
 */
#include "bake.h"
#include "exrio.h"
#include "scene.h"
#include "smooth.h"

#include "testhelp.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static float *bake_y(fb_engine *e, const char *json, const char *out, int *w, int *h)
{
    fb_scene s;
    if (fb_scene_parse(json, NULL, &s) != FB_OK) return NULL;
    fb_result rc = fb_bake(e, &(fb_bake_desc){.scene = &s, .out = out}, NULL);
    fb_scene_fini(&s);
    if (rc) return NULL;
    exrio_reader *r = NULL;
    if (exrio_open(out, &r) != FB_OK) return NULL;
    *w = exrio_width(r), *h = exrio_height(r);
    void *planes[8] = {0};
    float *y = malloc((size_t)*w * *h * 4);
    planes[exrio_find_channel(r, "terrain.Y")] = y;
    if (exrio_read_rows(r, 0, *h, planes) != FB_OK) free(y), y = NULL;
    exrio_close(&r);
    return y;
}

static double f(double x, double y)
{
    return 50 * sin(x / 150) * cos(y / 120) + 0.02 * x;
}

/* the largest horizontal second difference away from the hull's border (a frame of 10%) */
static double max_d2(const float *y, int w, int h)
{
    double m = 0;
    for (int r = h / 10; r < h - h / 10; r++)
        for (int x = w / 10; x < w - w / 10; x++) {
            const float *p = y + (size_t)r * w + x;
            m = fmax(m, fabs((double)p[-1] - 2.0 * p[0] + p[1]));
        }
    return m;
}

int main(void)
{
    /* the element alone */
    double p[3][2] = {{0, 0}, {4, 0}, {1, 3}}, q[3][2] = {{4, 0}, {5, 4}, {1, 3}}, z[3], g[3][2], zq[3], gq[3][2];
    for (int i = 0; i < 3; i++) z[i] = 2 * p[i][0] - 3 * p[i][1] + 5, g[i][0] = 2, g[i][1] = -3;
    fb_smooth_tri A, B;
    fb_smooth_setup(&A, p, z, g);
    double worst = 0;
    for (double x = 0.1; x < 3; x += 0.37)
        for (double y = 0.1; y < 2; y += 0.29) {
            double gr[2], v = fb_smooth_eval(&A, x, y, gr);
            worst = fmax(worst, fabs(v - (2 * x - 3 * y + 5)) + fabs(gr[0] - 2) + fabs(gr[1] + 3));
        }
    CHECKF(worst < 1e-12, "a plane off by %g", worst);
    for (int i = 0; i < 3; i++) { /* x^2 + xy - y^2 on two triangles sharing the edge (4,0)-(1,3) */
        double x = p[i][0], y = p[i][1];
        z[i] = x * x + x * y - y * y, g[i][0] = 2 * x + y, g[i][1] = x - 2 * y;
        x = q[i][0], y = q[i][1];
        zq[i] = x * x + x * y - y * y, gq[i][0] = 2 * x + y, gq[i][1] = x - 2 * y;
    }
    fb_smooth_setup(&A, p, z, g);
    fb_smooth_setup(&B, q, zq, gq);
    double dv = 0, dg = 0;
    for (double t = 0.05; t < 1; t += 0.05) {
        double x = 4 - 3 * t, y = 3 * t, ga[2], gb[2];
        dv = fmax(dv, fabs(fb_smooth_eval(&A, x, y, ga) - fb_smooth_eval(&B, x, y, gb)));
        dg = fmax(dg, fabs(ga[0] - gb[0]) + fabs(ga[1] - gb[1]));
    }
    CHECKF(dv < 1e-12 && dg < 1e-12, "across a shared edge: value %g, gradient %g apart", dv, dg);
    double c[2] = {5.0 / 3, 1}, jump = 0; /* the split edge from (0, 0) to the centroid */
    for (double t = 0.1; t < 0.95; t += 0.1) {
        double x = t * c[0], y = t * c[1], n[2] = {-c[1] / hypot(c[0], c[1]), c[0] / hypot(c[0], c[1])}, g1[2], g2[2];
        fb_smooth_eval(&A, x + 1e-9 * n[0], y + 1e-9 * n[1], g1);
        fb_smooth_eval(&A, x - 1e-9 * n[0], y - 1e-9 * n[1], g2);
        jump = fmax(jump, fabs(g1[0] - g2[0]) + fabs(g1[1] - g2[1]));
    }
    CHECKF(jump < 1e-6, "the gradient jumps by %g across a split edge", jump);
    for (int i = 0; i < 3; i++) CHECK(fb_smooth_eval(&A, p[i][0], p[i][1], NULL) == z[i]);

    /* the layer: points of f on a jittered grid, 25 units apart over a 1000 x 500 frame (triangles of
     * 12 to 25 pixels a side), with both interpolations at 500 x 250 and 1000 x 500 pixels */
    char *json = malloc(400000), *pts = malloc(380000);
    size_t at = 0;
    unsigned seed = 7;
    for (int j = 0; j <= 20; j++)
        for (int i = 0; i <= 40; i++) {
            seed = seed * 1103515245u + 12345u;
            double jx = (i > 0 && i < 40) ? ((seed >> 8) % 1000) / 1000.0 * 10 - 5 : 0;
            seed = seed * 1103515245u + 12345u;
            double jy = (j > 0 && j < 20) ? ((seed >> 8) % 1000) / 1000.0 * 10 - 5 : 0;
            double x = i * 25 + jx, y = j * 25 + jy;
            at += (size_t)snprintf(pts + at, 380000 - at, "%s[%.6f, %.6f, %.9f]", at ? ", " : "", x, y, f(x, y));
        }
    fb_engine e;
    REQUIRE(fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = 2}, &e) == FB_OK);
    double d2[2][2];
    for (int smooth = 0; smooth < 2; smooth++)
        for (int k = 0; k < 2; k++) {
            int W = 500 << k, H = 250 << k, w, h;
            snprintf(
                json, 400000,
                "{\"size\": [%d, %d], \"layers\": [{\"type\": \"terrain\", \"insert\": 0, \"bounds\": [0, 1000, 0, "
                "500], \"interpolation\": \"%s\", \"points\": [%s]}]}",
                W, H, smooth ? "smooth" : "linear", pts);
            float *y = bake_y(&e, json, th_path("s.exr"), &w, &h);
            REQUIRE(y && w == W && h == H);
            d2[smooth][k] = max_d2(y, w, h);
            free(y);
        }
    printf("largest second difference: linear %.4g -> %.4g (ratio %.2f), smooth %.4g -> %.4g (ratio %.2f)\n", d2[0][0],
           d2[0][1], d2[0][0] / d2[0][1], d2[1][0], d2[1][1], d2[1][0] / d2[1][1]);
    CHECKF(d2[1][0] / d2[1][1] >= 3.0, "smooth: the largest second difference fell by %.2fx, not >= 3x",
           d2[1][0] / d2[1][1]);
    CHECKF(d2[0][0] / d2[0][1] <= 2.5, "linear: the largest second difference fell by %.2fx (kinks give about 2x)",
           d2[0][0] / d2[0][1]);
    CHECK(d2[1][1] < d2[0][1] / 3); /* and far below the planes' kinks */

    /* input points exactly on pixel centres: heights kept exactly by both surfaces */
    snprintf(json, 400000,
             "{\"size\": [40, 20], \"layers\": [{\"type\": \"terrain\", \"insert\": 300, \"bounds\": [0, 40, 0, 20], "
             "\"interpolation\": \"%%s\", \"points\": [[0.5, 0.5, 3.25], [39.5, 0.5, -2.5], [0.5, 19.5, 7.75], "
             "[39.5, 19.5, 1.5], [20.5, 10.5, 12.125], [10.5, 5.5, 4.5], [30.5, 14.5, -6.25]]}]}");
    const int px[7][2] = {{0, 19}, {39, 19}, {0, 0}, {39, 0}, {20, 9}, {10, 14}, {30, 5}};
    const float pz[7] = {3.25f, -2.5f, 7.75f, 1.5f, 12.125f, 4.5f, -6.25f};
    for (int smooth = 0; smooth < 2; smooth++) {
        char j2[2048];
        snprintf(j2, sizeof j2, json, smooth ? "smooth" : "linear");
        int w, h;
        float *y = bake_y(&e, j2, th_path("p.exr"), &w, &h);
        REQUIRE(y);
        int kept = 0;
        for (int i = 0; i < 7; i++) kept += y[px[i][1] * w + px[i][0]] == pz[i];
        CHECKF(kept == 7, "%s: %d of 7 input points kept exactly", smooth ? "smooth" : "linear", kept);
        free(y);
    }
    fb_engine_close(&e);
    free(json), free(pts);
    TEST_REPORT();
}
