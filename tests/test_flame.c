/*
 * The flame's chaos game (host/gen/flame/game.c) against a plain reference: every chain stepped
 * with the same kernel (kernels/flame.h) on one thread, each plotted point added straight into
 * 64-bit sums by the rule of fb_flame_cell (colour times opacity, in 2^-4 units). The game's total
 * histogram must equal it cell for cell on 1, 3 and 5 threads: the scattered 16-byte cells of opaque
 * genomes, the 24-byte cells of others, and the spills of cells that pass 2^31 (a genome that sends
 * every point to one cell). The plotted points and those outside the frame add up to the chains'
 * points, and the filter's count channel sums exactly to the points plotted inside the image.
 */
#include "game.h"

#include "flame_xml.h"
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
/* a translucent xform with random draws and one with a post transform: the lanes' 24-byte cells */
static const char *const k_lanes_translucent =
    "<flame size=\"64 48\" scale=\"20\" estimator_radius=\"3\">"
    "<xform weight=\"0.5\" color=\"0.2\" opacity=\"0.7\" horseshoe=\"0.6\" blade=\"0.4\" coefs=\"0.5 0.2 -0.3 "
    "0.6 0.2 0.1\"/>"
    "<xform weight=\"0.5\" color=\"0.9\" polar=\"0.3\" disc=\"0.5\" coefs=\"0.8 0 0 0.8 0 0\" post=\"1 0.1 0 1 "
    "0.1 0.2\"/>" PAL "</flame>";
/* the camera rotated: the lanes rotate their planes of points */
static const char *const k_lanes_rotated =
    "<flame size=\"64 48\" scale=\"20\" rotate=\"33\" center=\"0.1 -0.2\" estimator_radius=\"3\">"
    "<symmetry kind=\"2\"/>"
    "<xform weight=\"0.5\" color=\"0.2\" julia=\"0.6\" curl=\"0.4\" curl_c1=\"0.3\" coefs=\"0.5 0.2 -0.3 0.6 "
    "0.2 0.1\"/>"
    "<xform weight=\"0.5\" color=\"0.9\" rectangles=\"0.5\" coefs=\"0.8 0 0 0.8 0 0\"/>" PAL "</flame>";
/* final xforms on the lanes: one translucent (the opacity's draw) with random draws and bad values,
 * and one whose variation has no lane form (a chain at a time) */
static const char *const k_lanes_final =
    "<flame size=\"64 48\" scale=\"20\" estimator_radius=\"3\"><symmetry kind=\"3\"/>"
    "<xform weight=\"0.5\" color=\"0.2\" ex=\"0.6\" blob=\"0.4\" coefs=\"0.5 0.2 -0.3 0.6 0.2 0.1\"/>"
    "<xform weight=\"0.05\" color=\"0.5\" linear=\"1\" coefs=\"1e12 0 0 1e12 0 0\"/>"
    "<finalxform color=\"0.7\" color_speed=\"0.5\" opacity=\"0.6\" spherical=\"0.5\" blade=\"0.5\" "
    "coefs=\"0.9 0.1 0 0.9 0 0.1\"/>" PAL "</flame>";
/* a final xform whose points beyond the unit square are bad values (random points, their draws) */
static const char *const k_lanes_final_bad =
    "<flame size=\"64 48\" scale=\"20\" estimator_radius=\"3\"><symmetry kind=\"2\"/>"
    "<xform weight=\"0.5\" color=\"0.2\" swirl=\"0.7\" blur=\"0.3\" coefs=\"0.9 0.2 -0.3 0.8 0.4 0.1\"/>"
    "<finalxform color=\"0.7\" opacity=\"0.8\" linear=\"1\" coefs=\"1e10 0 0 1e10 0 0\"/>" PAL "</flame>";
/* xaos (each chain's choice from the row of its last xform, gathered), a final xform, a plain
 * linear xform */
static const char *const k_lanes_xaos =
    "<flame size=\"64 48\" scale=\"20\" estimator_radius=\"3\">"
    "<xform weight=\"0.5\" color=\"0.2\" ex=\"0.6\" julia=\"0.4\" coefs=\"0.5 0.2 -0.3 0.6 0.2 0.1\" "
    "chaos=\"0 1 3\"/>"
    "<xform weight=\"0.3\" color=\"0.5\" linear=\"1\" coefs=\"-1 0 0 -1 0 0\" chaos=\"1 1 0\"/>"
    "<xform weight=\"0.4\" color=\"0.9\" rectangles=\"0.5\" coefs=\"0.8 0 0 0.8 0.1 0\" chaos=\"2 0.5 1\"/>"
    "<finalxform color=\"0.7\" opacity=\"0.5\" spherical=\"0.3\" linear=\"0.7\" coefs=\"1 0 0 1 0 0\"/>" PAL "</flame>";
/* 21 xforms (a symmetry of 18): the lanes' tables in three registers */
static const char *const k_lanes_wide =
    "<flame size=\"64 48\" scale=\"20\" estimator_radius=\"3\"><symmetry kind=\"18\"/>"
    "<xform weight=\"2\" color=\"0.2\" ex=\"0.6\" julia=\"0.4\" coefs=\"0.5 0.2 -0.3 0.6 0.2 0.1\"/>"
    "<xform weight=\"2\" color=\"0.6\" disc=\"0.8\" coefs=\"0.7 0.1 0 0.7 0.1 0\"/>"
    "<xform weight=\"1\" color=\"0.9\" rectangles=\"0.5\" coefs=\"0.8 0 0 0.8 0.1 0\"/>" PAL "</flame>";
/* a final xform whose variation has no lane form: applied a chain at a time */
static const char *const k_lanes_final_scalar =
    "<flame size=\"64 48\" scale=\"20\" estimator_radius=\"3\"><symmetry kind=\"2\"/>"
    "<xform weight=\"0.5\" color=\"0.2\" julia=\"1\" coefs=\"0.5 0.2 -0.3 0.6 0.2 0.1\"/>"
    "<finalxform color=\"0.7\" rectangles=\"0.5\" coefs=\"0.9 0 0 0.9 0 0\"/>" PAL "</flame>";
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

static void test_genome(const char *what, const char *xml, int w, int h, double quality, size_t want_bytes,
                        double min_plotted)
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
    CHECKF(plotted > points * min_plotted, "%s: only %llu of %llu points plotted", what, (unsigned long long)plotted,
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

/* Every variation: genomes of five variations each (flam3's numbers 5k .. 5k + 4), in three xforms
 * with random coefficients and parameters (tests/flame_xml.h), on the threads against the one-thread
 * reference. Many of them send points out of the frame or to bad values: a tenth plotted is enough. */
static void test_variations(void)
{
    static char xml[16384];
    for (int v0 = 0; v0 < (int)K_V_COUNT; v0 += 5) {
        int v[5], n = 0;
        for (int k = 0; k < 5 && v0 + k < (int)K_V_COUNT; k++) v[n++] = v0 + k;
        snprintf(xml, sizeof xml, "<flame size=\"64 48\" scale=\"10\" estimator_radius=\"3\">");
        xform_xml(xml, sizeof xml, v, 2, false);
        xform_xml(xml, sizeof xml, v + 2, n > 3 ? 2 : 1, true);
        if (n > 4) xform_xml(xml, sizeof xml, v + 4, 1, false);
        strcat(xml, PAL "</flame>");
        char what[64];
        snprintf(what, sizeof what, "variations %d-%d", v0, v0 + n - 1);
        test_genome(what, xml, 64, 48, 20, 16, 0.1);
    }
}

int main(void)
{
    test_hostile_text();
    test_genome("opaque", k_opaque, 64, 48, 100, 16, 0.5);
    test_genome("translucent", k_translucent, 64, 48, 100, 24, 0.5);
    test_genome("symmetry, post, bad values, final", k_mixed, 64, 48, 100, 16, 0.5);
    test_genome("symmetry, bad values (AVX2 lanes)", k_lanes, 64, 48, 100, 16, 0.5);
    test_genome("translucent, post (AVX2 lanes)", k_lanes_translucent, 64, 48, 100, 24, 0.3);
    test_genome("camera rotation (AVX2 lanes)", k_lanes_rotated, 64, 48, 100, 16, 0.3);
    test_genome("final xform, translucent (AVX2 lanes)", k_lanes_final, 64, 48, 100, 16, 0.1);
    test_genome("final xform, a chain at a time (AVX2 lanes)", k_lanes_final_scalar, 64, 48, 100, 16, 0.1);
    test_genome("final xform, bad values (AVX2 lanes)", k_lanes_final_bad, 64, 48, 100, 16, 0.1);
    test_genome("xaos, final xform (AVX2 lanes)", k_lanes_xaos, 64, 48, 100, 16, 0.1);
    test_genome("21 xforms (AVX2 lanes)", k_lanes_wide, 64, 48, 100, 16, 0.1);
    /* 2^21 points into one cell: past 2^19 hits a 16-byte cell spills, past 2^31 / 4080 a 24-byte one */
    test_genome("one cell, opaque", k_point, 8, 8, 32768, 16, 0.5);
    test_genome("one cell, translucent", k_point_translucent, 8, 8, 32768, 24, 0.5);
    test_variations();
    TEST_REPORT();
}
