/*
 * Every one of flam3 3.1.1's 99 variations against flam3 itself: libflam3's own apply_xform (the
 * library Debian's flam3-utils render with) and the kernel's k_flame_apply (kernels/flame.h) apply
 * the same xform, read from the same XML by each side's own parser, to the same points, and for the
 * random variations with the same random numbers: the test supplies libflam3's
 * flam3_random_isaac_01, _11 and _bit (the library calls them through its PLT, so the test's
 * definitions take their place) and feeds them the kernel's own draws, k_flame_u01(key, n), in the
 * order flam3 draws them. So a variation's formula, its parameters' names, defaults and precalcs,
 * the precalcs of the point (sqrt, sina, cosa, the angles), pre_blur, the order of the sums and
 * the count and order of the draws (the kernel's counter must end where flam3's does) are all
 * checked against flam3's, not against a copy of them.
 *
 * flam3 computes in double, the kernel in float (with its own transcendentals): per variation, at
 * least 98% of 3000 random points must agree (both bad values, or both good and within 1e-3 of
 * flam3's result relative to its size; the rest are points near a singularity, where float's
 * rounding moves a result far). Then xforms of several variations with pre_blur and a post
 * transform, where the variations' draws must line up one after another. Built where libflam3-dev
 * is installed (tests/CMakeLists.txt), as it is for CI.
 */
#include "render.h"

#include "flame_xml.h"
#include "testhelp.h"

#include <flam3.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* libflam3's, not in its header */
int prepare_precalc_flags(flam3_genome *cp);
void xform_precalc(flam3_genome *cp, int xi);
int apply_xform(flam3_genome *cp, int fn, double *p, double *q, randctx *rc);

/* libflam3's random numbers, replaced: the kernel's draws from (g_key, g_n) on */
static uint32_t g_key, g_n;
double flam3_random_isaac_01(randctx *ct)
{
    (void)ct;
    return k_flame_u01(g_key, g_n++);
}
double flam3_random_isaac_11(randctx *ct)
{
    (void)ct;
    return k_flame_u01(g_key, g_n++) * 2.0f - 1.0f;
}
int flam3_random_isaac_bit(randctx *ct)
{
    (void)ct;
    return (int)(k_hash(g_n++ ^ g_key) & 1u);
}

/* An xform of variations vars[0 .. n) applied by both sides to 3000 points; returns the share of
 * points that agree, and the share of flam3's results that are good in *good. */
static double compare(const int *vars, int n, bool post, double *good, char *xml, size_t cap)
{
    snprintf(xml, cap, "<flame size=\"64 64\" scale=\"20\">");
    xform_xml(xml, cap, vars, n, post);
    strcat(xml, "<color index=\"0\" rgb=\"255 0 0\"/><color index=\"255\" rgb=\"0 0 255\"/></flame>");
    fb_flame_genome g;
    fb_flame_setup S;
    if (fb_flame_read(xml, strlen(xml), "test", NULL, NULL, &g, NULL) != FB_OK) return -1;
    if (fb_flame_setup_init(&g, 64, 64, 1, 1, &S) != FB_OK) return -1;
    int ncps = 0;
    char *copy = strdup(xml);
    flam3_genome *cp = flam3_parse_xml2(copy, "test", flam3_defaults_on, &ncps);
    free(copy);
    if (!cp || ncps != 1) return -1;
    prepare_precalc_flags(cp);
    xform_precalc(cp, 0);
    const K_FlameXform *k_flame_xf = S.xf;
    const K_FlameVar *k_flame_var = S.var;
    const uint *k_flame_dist = S.dist;
    int agree = 0, ngood = 0, N = 3000;
    for (int i = 0; i < N; i++) {
        float x = (float)uni(-2, 2), y = (float)uni(-2, 2), c = (float)uni(0, 1);
        uint32_t key = k_hash((uint32_t)i * 7919u + 1u), n0 = 3u + (uint32_t)i;
        K_FlameOut o = k_flame_apply(0, x, y, c, key, n0 K_FLAME_TABLES);
        double p[4] = {x, y, c, 0}, q[4];
        g_key = key, g_n = n0;
        bool bad = apply_xform(cp, 0, p, q, NULL) != 0;
        if (!bad) ngood++;
        /* the same draws: as many (flam3's bad value takes two more, as the kernel's) */
        if (bad != o.bad || g_n != o.n) continue;
        if (bad) {
            agree++;
            continue;
        }
        double scale = 1 + fmax(fabs(q[0]), fabs(q[1]));
        if (fabs(o.x - q[0]) <= 1e-3 * scale && fabs(o.y - q[1]) <= 1e-3 * scale && fabs(o.c - q[2]) < 1e-5) agree++;
    }
    clear_cp(cp, flam3_defaults_on); /* its xforms and xaos rows */
    flam3_free(cp);
    fb_flame_setup_fini(&S);
    *good = (double)ngood / N;
    return (double)agree / N;
}

int main(void)
{
    static char xml[16384];
    double worst = 1;
    for (int v = 0; v < (int)K_V_COUNT; v++) {
        int vars[2] = {v, (int)K_V_LINEAR};
        /* pre_blur moves the point; alone it would leave nothing to move it to: with linear */
        int n = v == (int)K_V_PRE_BLUR ? 2 : 1;
        double good = 0, share = compare(vars, n, false, &good, xml, sizeof xml);
        CHECKF(share >= 0.98 && good >= 0.5, "%s: %.1f%% of points agree with libflam3 (%.1f%% good values)",
               fb_flame_variation_name(v), 100 * share, 100 * good);
        if (share < worst) worst = share;
    }
    printf("all 99 variations: at least %.1f%% of points agree with libflam3's apply_xform\n", 100 * worst);
    /* several variations an xform, pre_blur, a post transform: the draws line up */
    for (int t = 0; t < 40; t++) {
        int vars[5], n = 0;
        vars[n++] = (int)K_V_PRE_BLUR;
        while (n < 5) {
            int v = (int)uni(0, K_V_COUNT), dup = v == (int)K_V_PRE_BLUR;
            for (int k = 0; k < n; k++) dup |= vars[k] == v;
            if (!dup) vars[n++] = v;
        }
        double good = 0, share = compare(vars, n, t & 1, &good, xml, sizeof xml);
        CHECKF(share >= 0.98 && good >= 0.3, "pre_blur, %s, %s, %s, %s: %.1f%% agree (%.1f%% good)",
               fb_flame_variation_name(vars[1]), fb_flame_variation_name(vars[2]), fb_flame_variation_name(vars[3]),
               fb_flame_variation_name(vars[4]), 100 * share, 100 * good);
    }
    TEST_REPORT();
}
