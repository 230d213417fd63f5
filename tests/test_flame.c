/*
 * The flame's chaos game (host/gen/flame/game.c) against a plain reference: every chain stepped
 * with the same kernel (kernels/flame.h) on one thread, each plotted point added straight into
 * 64-bit sums by the rule of fb_flame_cell (colour times opacity, in 2^-4 units). The game's total
 * histogram must equal it cell for cell on 1, 3 and 5 threads: the scattered 16-byte cells of opaque
 * genomes, the 24-byte cells of others, and the spills of cells that pass 2^31 (a genome that sends
 * every point to one cell). The plotted points and those outside the frame add up to the chains'
 * points, and the filter's count channel sums exactly to the points plotted inside the image.
 *
 * And kernels/kmath.h, the float-only exp, log, pow, atan2, tan, sinh, cosh (and fmod) that the
 * flame's kernel uses in C and in the shader alike: within a few ulp of libm in double over the
 * ranges a chain visits, and IEEE's answers at the edges (0, infinities, NaN).
 */
#include "game.h"

#include "testhelp.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PAL "<color index=\"0\" rgb=\"255 40 0\"/><color index=\"128\" rgb=\"0 200 90\"/>"

/* opaque: the 16-byte cells */
static const char *const k_opaque =
    "<flame size=\"64 48\" scale=\"20\" estimator_radius=\"3\">"
    "<xform weight=\"0.5\" color=\"0\" linear=\"0.6\" spherical=\"0.4\" coefs=\"0.5 0.2 -0.3 0.6 0.2 0.1\"/>"
    "<xform weight=\"0.3\" color=\"1\" julia=\"1\" coefs=\"0.8 0 0 0.8 0 0\"/>"
    "<xform weight=\"0.2\" color=\"0.5\" ex=\"0.7\" blur=\"0.05\" coefs=\"0 1 -1 0 0.3 0\"/>" PAL "</flame>";
/* an xform half transparent: the 24-byte cells */
static const char *const k_translucent =
    "<flame size=\"64 48\" scale=\"20\" estimator_radius=\"3\">"
    "<xform weight=\"0.5\" color=\"0\" opacity=\"0.5\" linear=\"0.6\" spherical=\"0.4\" coefs=\"0.5 0.2 -0.3 0.6 0.2 "
    "0.1\"/>"
    "<xform weight=\"0.5\" color=\"1\" swirl=\"0.3\" linear=\"0.5\" coefs=\"0.8 0 0 0.8 0 0\"/>" PAL "</flame>";
/* symmetry (plain linear xforms, game.c's fast path) among others: a linear one with a post
 * transform, one whose points fly off (bad values, retried), a final xform */
static const char *const k_mixed =
    "<flame size=\"64 48\" scale=\"20\" estimator_radius=\"3\"><symmetry kind=\"3\"/>"
    "<xform weight=\"0.5\" color=\"0\" ex=\"0.7\" cosine=\"0.3\" coefs=\"0.5 0.2 -0.3 0.6 0.2 0.1\"/>"
    "<xform weight=\"0.3\" color=\"1\" linear=\"0.9\" coefs=\"0.8 0 0 0.8 0.1 0\" post=\"1 0 0 1 0.1 0.2\"/>"
    "<xform weight=\"0.05\" color=\"0.5\" linear=\"1\" coefs=\"1e12 0 0 1e12 0 0\"/>"
    "<finalxform color=\"0.3\" color_speed=\"0.5\" linear=\"1\" coefs=\"0.9 0 0 0.9 0 0\"/>" PAL "</flame>";
/* the same without the final xform: game.c's AVX2 lanes take it (plain linear steps on the lanes,
 * the others and the bad values a lane at a time through the scalar step) */
static const char *const k_lanes =
    "<flame size=\"64 48\" scale=\"20\" estimator_radius=\"3\"><symmetry kind=\"3\"/>"
    "<xform weight=\"0.5\" color=\"0\" ex=\"0.7\" cosine=\"0.3\" coefs=\"0.5 0.2 -0.3 0.6 0.2 0.1\"/>"
    "<xform weight=\"0.3\" color=\"1\" color_speed=\"0.3\" linear=\"0.9\" coefs=\"0.8 0 0 0.8 0.1 0\"/>"
    "<xform weight=\"0.05\" color=\"0.5\" linear=\"1\" coefs=\"1e12 0 0 1e12 0 0\"/>" PAL "</flame>";
/* every point to (0.01, 0.01): one cell takes them all, so its 32-bit sums spill */
static const char *const k_point =
    "<flame size=\"8 8\" scale=\"2\" estimator_radius=\"0\">"
    "<xform weight=\"1\" color=\"0.2\" linear=\"1\" coefs=\"0 0 0 0 0.01 0.01\"/>" PAL "</flame>";
static const char *const k_point_translucent =
    "<flame size=\"8 8\" scale=\"2\" estimator_radius=\"0\">"
    "<xform weight=\"1\" color=\"0.2\" opacity=\"0.9\" linear=\"1\" coefs=\"0 0 0 0 0.01 0.01\"/>" PAL "</flame>";

/* The reference: chains [0, chains) on this thread into 64-bit cells; returns the points plotted,
 * *outside the others. */
static uint64_t reference(const fb_flame_setup *S, fb_flame_cell *ref, uint64_t *outside)
{
    const K_FlameParams P = S->p;
    const K_FlameXform *k_flame_xf = S->xf;
    const K_FlameVar *k_flame_var = S->var;
    const uint *k_flame_dist = S->dist;
    uint64_t plotted = 0;
    *outside = 0;
    for (uint32_t i = 0; i < P.chains; i++) {
        uint32_t key = k_flame_key(P.seed, i), len = i + 1 == P.chains ? P.last_len : P.len;
        K_FlameChain s = k_flame_init(key);
        for (uint32_t t = 0; t < P.fuse; t++) s = k_flame_step(P, s, key K_FLAME_TABLES);
        for (uint32_t t = 0; t < len; t++) {
            s = k_flame_step(P, s, key K_FLAME_TABLES);
            uint32_t cell = k_flame_cell(P, s), visq = S->xf[s.vis].visq;
            if (cell == K_FLAME_NONE) {
                ++*outside;
                continue;
            }
            const uint32_t *q = S->palq[k_flame_index(s.pc)];
            for (int k = 0; k < 4; k++) ref[cell].c[k] += (q[k] * visq + 16384) >> 15;
            ref[cell].c[4] += (4080u * visq + 16384) >> 15;
            ref[cell].hits++;
            plotted++;
        }
    }
    return plotted;
}

static void test_genome(const char *what, const char *xml, int w, int h, double quality, size_t want_bytes)
{
    fb_flame_genome g;
    fb_flame_setup S;
    REQUIRE(fb_flame_read(xml, strlen(xml), what, NULL, NULL, &g, NULL) == FB_OK);
    REQUIRE(fb_flame_setup_init(&g, w, h, quality, 7, &S) == FB_OK);
    CHECKF(fb_flame_cell_bytes(&S) == want_bytes, "%s: %zu-byte cells", what, fb_flame_cell_bytes(&S));
    size_t cells = (size_t)S.p.hist_w * S.p.hist_h;
    fb_flame_cell *ref = calloc(cells, sizeof *ref), *total = calloc(cells, sizeof *total);
    REQUIRE(ref && total);
    uint64_t outside, plotted = reference(&S, ref, &outside), points = 0;
    for (uint32_t i = 0; i < S.p.chains; i++) points += i + 1 == S.p.chains ? S.p.last_len : S.p.len;
    CHECKF(plotted + outside == points && points == (uint64_t)S.samples, "%s: %llu + %llu of %.0f", what,
           (unsigned long long)plotted, (unsigned long long)outside, S.samples);
    CHECKF(plotted > points / 2, "%s: only %llu of %llu points plotted", what, (unsigned long long)plotted,
           (unsigned long long)points);
    uint64_t most = 0;
    for (size_t c = 0; c < cells; c++) most = ref[c].hits > most ? ref[c].hits : most;
    /* 1, 3 and 5 threads with the AVX2 lanes where they apply, then 3 with the portable step only */
    for (int run = 0; run < 4; run++) {
        int threads = run < 3 ? 1 + 2 * run : 3;
        bool scalar = run == 3;
        fb_pool *pool = NULL;
        REQUIRE(fb_pool_create(threads, &pool) == FB_OK);
        memset(total, 0, cells * sizeof *total);
        uint64_t bad = 0;
        CHECK(fb_flame_play(&S, pool, threads, scalar, 0, S.p.chains, total, &bad, NULL) == FB_OK);
        size_t diff = 0;
        for (size_t c = 0; c < cells; c++) diff += memcmp(&total[c], &ref[c], sizeof ref[c]) != 0;
        CHECKF(diff == 0, "%s, %d threads%s: %zu of %zu cells differ from the reference", what, threads,
               scalar ? " (scalar)" : "", diff, cells);
        fb_pool_destroy(&pool);
    }
    /* the count channel: the hits of each pixel's own cells, inside the filters' margin */
    size_t npix = (size_t)w * h;
    float *acc[4];
    uint32_t *count = malloc(npix * 4);
    for (int k = 0; k < 4; k++) acc[k] = malloc(npix * 4);
    REQUIRE(count && acc[0] && acc[1] && acc[2] && acc[3]);
    CHECK(fb_flame_filter(&S, total, acc, count, NULL) == FB_OK);
    /* the filter on the pool, in bands: the same bits for any thread count */
    for (int threads = 2; threads <= 7; threads += 5) {
        fb_pool *pool = NULL;
        float *acc2[4];
        uint32_t *count2 = malloc(npix * 4);
        for (int k = 0; k < 4; k++) acc2[k] = malloc(npix * 4);
        REQUIRE(fb_pool_create(threads, &pool) == FB_OK && count2 && acc2[0] && acc2[1] && acc2[2] && acc2[3]);
        CHECK(fb_flame_filter(&S, total, acc2, count2, pool) == FB_OK);
        size_t diff = memcmp(count2, count, npix * 4) != 0;
        for (int k = 0; k < 4; k++) diff += memcmp(acc2[k], acc[k], npix * 4) != 0;
        CHECKF(diff == 0, "%s, the filter on %d threads: %zu planes differ from one thread's", what, threads, diff);
        for (int k = 0; k < 4; k++) free(acc2[k]);
        free(count2);
        fb_pool_destroy(&pool);
    }
    uint64_t counted = 0, inside = 0;
    for (size_t p = 0; p < npix; p++) counted += count[p];
    for (uint32_t y = (uint32_t)S.gutter; y < (uint32_t)(S.gutter + S.ss * h); y++)
        for (uint32_t x = (uint32_t)S.gutter; x < (uint32_t)(S.gutter + S.ss * w); x++)
            inside += ref[(size_t)y * S.p.hist_w + x].hits;
    CHECKF(counted == inside && inside > 0, "%s: the count channel sums to %llu, the points inside the image %llu",
           what, (unsigned long long)counted, (unsigned long long)inside);
    printf("%s: %llu points, %llu plotted (%llu inside the image), the fullest cell %llu hits\n", what,
           (unsigned long long)points, (unsigned long long)plotted, (unsigned long long)inside,
           (unsigned long long)most);
    for (int k = 0; k < 4; k++) free(acc[k]);
    free(count), free(ref), free(total);
    fb_flame_setup_fini(&S);
}

/* Error of got against the double want, in ulps of want's float (relative to the smallest normal
 * below it). */
static double ulps(float got, double want)
{
    float w = (float)want;
    double u = nextafterf(fabsf(w), INFINITY) - fabsf(w);
    if (u < 1.1754944e-38 * 1.1920929e-7) u = 1.1754944e-38 * 1.1920929e-7;
    return fabs(got - want) / u;
}

static void test_kmath(void)
{
    double worst[8] = {0};
    uint32_t h = 12345;
    for (int i = 0; i < 1000000; i++) {
        float a = k_u01(h = k_hash(h)) * 2 - 1, b = k_u01(h = k_hash(h)) * 2 - 1, c = k_u01(h = k_hash(h));
        float x = a * 80, y = b * 80, p = c * 200 + 1e-30f, s = a * 3;
        double e[8] = {ulps(k_xexp(x), exp(x)),
                       ulps(k_xlog(p), log(p)),
                       ulps(k_xatan2(y, x), atan2(y, x)),
                       ulps(k_xtan(s * 0.5f), tan(s * 0.5f)),
                       ulps(k_xsinh(s), sinh(s)),
                       ulps(k_xcosh(s), cosh(s)),
                       ulps(k_xpow(c * 4, b * 6), pow(c * 4, b * 6)),
                       ulps(k_xsin(x), sin(x))};
        for (int k = 0; k < 8; k++)
            if (e[k] > worst[k]) worst[k] = e[k];
    }
    const char *name[8] = {"exp", "log", "atan2", "tan", "sinh", "cosh", "pow", "sin"};
    /* pow: e^(y ln x) carries the rounding of y ln x, up to 90 here: about 0.6 ulp a unit of it */
    const double bound[8] = {2, 2, 4, 5, 3, 3, 64, 4};
    for (int k = 0; k < 8; k++) CHECKF(worst[k] <= bound[k], "k_x%s: %.2f ulp from libm", name[k], worst[k]);
    /* the edges */
    CHECK(k_xexp(-100.0f) == 0.0f && isinf(k_xexp(100.0f)) && k_xexp(0.0f) == 1.0f && isnan(k_xexp(NAN)));
    CHECK(isinf(k_xlog(0.0f)) && k_xlog(0.0f) < 0 && isnan(k_xlog(-1.0f)) && k_xlog(1.0f) == 0.0f);
    CHECK(isinf(k_xlog(INFINITY)) && isnan(k_xlog(NAN)) && isinf(k_xlog(1e-40f))); /* a subnormal reads as 0 */
    CHECK(k_xpow(0.0f, 2.0f) == 0.0f && k_xpow(0.0f, 0.0f) == 1.0f && isinf(k_xpow(0.0f, -1.0f)));
    CHECK(k_xpow(2.0f, 0.0f) == 1.0f && isnan(k_xpow(-2.0f, 0.5f)));
    CHECK(k_xatan2(0.0f, 0.0f) == 0.0f && k_xatan2(0.0f, -1.0f) == K_PI && k_xatan2(1.0f, 0.0f) == K_HALF_PI);
    CHECK(k_xatan2(-1.0f, 0.0f) == -K_HALF_PI && isnan(k_xatan2(NAN, 1.0f)));
    CHECK(fabsf(k_xatan2(INFINITY, INFINITY) - K_QUART_PI) < 1e-7f && k_xatan2(1.0f, INFINITY) == 0.0f);
    CHECK(k_xfmod(7.5f, 2.0f) == 1.5f && k_xfmod(-7.5f, 2.0f) == -1.5f);
    /* sincos beyond the int range (its quadrant was undefined as K_I(q) & 3, its reduction loses
     * everything): in [-1, 1] */
    for (float x = 3e9f; x < 1e12f; x *= 3.7f) {
        k_vec2 sc = k_sincos(x);
        CHECKF(fabsf(sc.x) <= 1 && fabsf(sc.y) <= 1, "k_sincos(%g) = (%g, %g)", x, sc.x, sc.y);
    }
}

/* The text reader checks what it is given before it builds a tree (scan.h): an entity declaration
 * is refused (nothing is expanded: here 10^6 "lol"s in an attribute otherwise), as are 300
 * attributes on one xform, and nothing of libxml2's own reaches stderr. */
static void test_hostile_text(void)
{
    static const char laughs[] = "<!DOCTYPE flame [<!ENTITY a \"lolololololololololol\"><!ENTITY b "
                                 "\"&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;\"><!ENTITY c \"&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;\">"
                                 "<!ENTITY d \"&c;&c;&c;&c;&c;&c;&c;&c;&c;&c;\"><!ENTITY e \"&d;&d;&d;&d;&d;&d;&d;"
                                 "&d;&d;&d;\">]><flame name=\"&e;\"><xform weight=\"1\" linear=\"1\"/>"
                                 "<color index=\"0\" rgb=\"1 2 3\"/></flame>";
    fb_flame_genome g;
    CHECK(fb_flame_read(laughs, strlen(laughs), "laughs", NULL, NULL, &g, NULL) == FB_ERR_INPUT);
    char many[8192] = "<flame><xform weight=\"1\" linear=\"1\"";
    for (int i = 0; i < 300; i++) snprintf(many + strlen(many), sizeof many - strlen(many), " p%d=\"0\"", i);
    snprintf(many + strlen(many), sizeof many - strlen(many), "/><color index=\"0\" rgb=\"1 2 3\"/></flame>");
    CHECK(fb_flame_read(many, strlen(many), "many", NULL, NULL, &g, NULL) == FB_ERR_INPUT);
    static const char ok[] = "<flame><xform weight=\"1\" linear=\"1\"/><color index=\"0\" rgb=\"1 2 3\"/></flame>";
    CHECK(fb_flame_read(ok, strlen(ok), "ok", NULL, NULL, &g, NULL) == FB_OK);
}

int main(void)
{
    test_kmath();
    test_hostile_text();
    test_genome("opaque", k_opaque, 64, 48, 100, 16);
    test_genome("translucent", k_translucent, 64, 48, 100, 24);
    test_genome("symmetry, post, bad values, final", k_mixed, 64, 48, 100, 16);
    test_genome("symmetry, bad values (AVX2 lanes)", k_lanes, 64, 48, 100, 16);
    /* 2^21 points into one cell: past 2^19 hits a 16-byte cell spills, past 2^31 / 4080 a 24-byte one */
    test_genome("one cell, opaque", k_point, 8, 8, 32768, 16);
    test_genome("one cell, translucent", k_point_translucent, 8, 8, 32768, 24);
    TEST_REPORT();
}
