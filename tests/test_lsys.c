/*
 * L-systems: derived strings against hand derivations and a closed-form length, stochastic choice
 * frequencies against their binomial spread, the turtle's segments (brackets restore the state,
 * f leaves a gap, | turns back), segment counts equal to the number of F symbols, the checks, and
 * the coverage rasteriser: exact coverage of axis-aligned lines, area conservation for a slanted
 * one, tiling equal to a brute-force sum over all segments, width tapering, auto-framing, and the
 * same bits on 1, 2 and 3 threads, any strip height, and lavapipe.
 */
#include "bake.h"
#include "exrio.h"
#include "gen.h"
#include "lsys.h"
#include "../kernels/lsys.h"

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

static char *derive(const fb_lsys *ls, uint32_t seed, size_t *len)
{
    char *s = NULL;
    size_t n = 0;
    fb_result rc = fb_lsys_derive(ls, seed, 1u << 28, 0, NULL, "test", &s, &n);
    CHECKF(rc == FB_OK, "%s", g_last_error);
    if (len) *len = n;
    return s;
}

static size_t count_char(const char *s, char c)
{
    size_t n = 0;
    for (; *s; s++) n += *s == c;
    return n;
}

/* ---- rewriting ------------------------------------------------------------------------------ */

static void test_derive(void)
{
    fb_lsys ls;
    CHECK(fb_lsys_preset("bush", &ls) == FB_OK);
    ls.iterations = 1;
    char *s = derive(&ls, 1, NULL);
    CHECK(s && !strcmp(s, "F[+F]F[-F]F"));
    free(s);
    ls.iterations = 2;
    s = derive(&ls, 1, NULL);
    CHECK(s && !strcmp(s, "F[+F]F[-F]F[+F[+F]F[-F]F]F[+F]F[-F]F[-F[+F]F[-F]F]F[+F]F[-F]F"));
    free(s);
    /* closed form: 5^n F symbols and 6 (5^n - 1) / 4 others */
    ls.iterations = 5;
    size_t n;
    s = derive(&ls, 1, &n);
    CHECK(n == 3125 + 4686 && s && count_char(s, 'F') == 3125);
    free(s);

    CHECK(fb_lsys_preset("tree", &ls) == FB_OK);
    ls.iterations = 1;
    s = derive(&ls, 1, NULL);
    CHECK(s && !strcmp(s, "YFX[+Y][-Y]"));
    free(s);
    ls.iterations = 2;
    s = derive(&ls, 1, NULL);
    CHECK(s && !strcmp(s, "YFX[+Y][-Y]FX[-FFF]F[+FFF]FX[+YFX[+Y][-Y]][-YFX[+Y][-Y]]"));
    free(s);
    ls.iterations = 0;
    s = derive(&ls, 1, NULL);
    CHECK(s && !strcmp(s, "Y"));
    free(s);

    /* symbols without a rule are kept; the arrow form parses the same */
    fb_lsys k = {.axiom = "AB", .nrules = 1, .iterations = 3};
    char msg[256];
    CHECK(fb_lsys_parse_rule("A -> AB", &k.rules[0], msg, sizeof msg));
    s = derive(&k, 1, NULL);
    CHECK(s && !strcmp(s, "ABBBB"));
    free(s);
}

static void test_explosion(void)
{
    fb_lsys ls = {.axiom = "F", .nrules = 1, .iterations = 40};
    char msg[256], *s = NULL;
    size_t n = 0;
    CHECK(fb_lsys_parse_rule("F=FF", &ls.rules[0], msg, sizeof msg));
    g_last_error[0] = 0;
    fb_result rc = fb_lsys_derive(&ls, 1, 1000, 0, NULL, "test", &s, &n);
    /* 2^9 = 512 <= 1000 < 1024 = 2^10: refused at iteration 10, before any string of 1024 exists */
    CHECKF(rc == FB_ERR_INPUT && s == NULL && strstr(g_last_error, "iteration 10 of 40"), "%s", g_last_error);
    ls.iterations = 9;
    rc = fb_lsys_derive(&ls, 1, 512, 0, NULL, "test", &s, &n);
    CHECK(rc == FB_OK && n == 512);
    free(s);
}

/* Stochastic productions: each of 1000 A's decides once per iteration for 64 iterations (64000
 * draws); the count of each successor is binomial, and must be within 5 standard deviations. */
static void test_stochastic(void)
{
    fb_lsys ls = {.nrules = 3, .iterations = 64};
    memset(ls.axiom, 'A', 1000);
    char msg[256];
    CHECK(fb_lsys_parse_rule("A(0.2)=AB", &ls.rules[0], msg, sizeof msg));
    CHECK(fb_lsys_parse_rule("A(0.3)=AC", &ls.rules[1], msg, sizeof msg));
    CHECK(fb_lsys_parse_rule("A(0.5)=AD", &ls.rules[2], msg, sizeof msg));
    int bad;
    CHECK(fb_lsys_valid(&ls, &bad, msg, sizeof msg));
    size_t n;
    char *s = derive(&ls, 7, &n);
    const double N = 1000.0 * 64, p[3] = {0.2, 0.3, 0.5};
    CHECK(n == 1000 * 65);
    for (int k = 0; k < 3 && s; k++) {
        double got = (double)count_char(s, "BCD"[k]), sd = sqrt(N * p[k] * (1 - p[k]));
        CHECKF(fabs(got - N * p[k]) < 5 * sd, "%c: %g, expected %g +- %g", "BCD"[k], got, N * p[k], 5 * sd);
    }
    /* a pure function of the seed */
    char *again = derive(&ls, 7, NULL), *other = derive(&ls, 8, NULL);
    CHECK(s && again && !strcmp(s, again));
    CHECK(s && other && strcmp(s, other) != 0);
    free(s);
    free(again);
    free(other);

    /* the stochastic preset's productions share symbol F */
    CHECK(fb_lsys_preset("stochastic", &ls) == FB_OK && ls.nrules == 3 && fb_lsys_valid(&ls, &bad, msg, sizeof msg));
}

static void test_checks(void)
{
    char msg[256];
    fb_lsys_rule r;
    CHECK(fb_lsys_parse_rule("F=F[+F]F", &r, msg, sizeof msg) && r.pred == 'F' && r.p == -1 &&
          !strcmp(r.succ, "F[+F]F"));
    CHECK(fb_lsys_parse_rule("F(0.25)= F [+F] ", &r, msg, sizeof msg) && r.p == 0.25 && !strcmp(r.succ, "F[+F]"));
    CHECK(fb_lsys_parse_rule("X=", &r, msg, sizeof msg) && r.succ[0] == 0); /* erasing */
    CHECK(!fb_lsys_parse_rule("=F", &r, msg, sizeof msg));
    CHECK(!fb_lsys_parse_rule("FF", &r, msg, sizeof msg));
    CHECK(!fb_lsys_parse_rule("F(x)=F", &r, msg, sizeof msg));
    CHECK(!fb_lsys_parse_rule("F(0.5=F", &r, msg, sizeof msg));

    int bad;
    fb_lsys ls = {.axiom = "F", .nrules = 1, .iterations = 1};
    fb_lsys_parse_rule("F=F[+F", &ls.rules[0], msg, sizeof msg);
    CHECK(!fb_lsys_valid(&ls, &bad, msg, sizeof msg) && bad == 0 && strstr(msg, "never closed"));
    fb_lsys_parse_rule("F=F]+F[", &ls.rules[0], msg, sizeof msg);
    CHECK(!fb_lsys_valid(&ls, &bad, msg, sizeof msg) && bad == 0 && strstr(msg, "closes nothing"));
    fb_lsys_parse_rule("F=F[+F]", &ls.rules[0], msg, sizeof msg);
    CHECK(fb_lsys_valid(&ls, &bad, msg, sizeof msg));
    snprintf(ls.axiom, sizeof ls.axiom, "F]");
    CHECK(!fb_lsys_valid(&ls, &bad, msg, sizeof msg) && bad == -1 && strstr(msg, "axiom"));
    snprintf(ls.axiom, sizeof ls.axiom, "F");
    fb_lsys_parse_rule("[=F", &ls.rules[0], msg, sizeof msg);
    CHECK(!fb_lsys_valid(&ls, &bad, msg, sizeof msg) && bad == 0);
    ls.nrules = 2;
    fb_lsys_parse_rule("F(0.5)=F+F", &ls.rules[0], msg, sizeof msg);
    fb_lsys_parse_rule("F(0.4)=F-F", &ls.rules[1], msg, sizeof msg);
    CHECK(!fb_lsys_valid(&ls, &bad, msg, sizeof msg) && strstr(msg, "sum to"));
    fb_lsys_parse_rule("F=F-F", &ls.rules[1], msg, sizeof msg);
    CHECK(!fb_lsys_valid(&ls, &bad, msg, sizeof msg) && strstr(msg, "every one"));
    fb_lsys_parse_rule("F(0)=F-F", &ls.rules[1], msg, sizeof msg);
    CHECK(!fb_lsys_valid(&ls, &bad, msg, sizeof msg) && bad == 1);
    /* several productions without probabilities share equally */
    fb_lsys_parse_rule("F=F+F", &ls.rules[0], msg, sizeof msg);
    fb_lsys_parse_rule("F=F-F", &ls.rules[1], msg, sizeof msg);
    CHECK(fb_lsys_valid(&ls, &bad, msg, sizeof msg));
    fb_lsys tmp;
    CHECK(fb_lsys_preset("nonesuch", &tmp) == FB_ERR_INPUT);
}

/* ---- the turtle ----------------------------------------------------------------------------- */

static bool seg_is(const fb_lsys_seg *s, double x0, double y0, double x1, double y1, int depth)
{
    const double e = 1e-12;
    return fabs(s->x0 - x0) < e && fabs(s->y0 - y0) < e && fabs(s->x1 - x1) < e && fabs(s->y1 - y1) < e &&
           s->depth == depth;
}

static void test_turtle(void)
{
    fb_lsys_seg *s = NULL;
    size_t n = 0;
    int depth = 0;
    /* heading up, 90 degree turns: the bracket returns to (0, 1) heading up */
    const char *t1 = "F[+F]F";
    CHECK(fb_lsys_turtle(t1, strlen(t1), 90, 90, 1, "t", &s, &n, &depth) == FB_OK && n == 3 && depth == 1);
    CHECK(n == 3 && seg_is(&s[0], 0, 0, 0, 1, 0) && seg_is(&s[1], 0, 1, -1, 1, 1) && seg_is(&s[2], 0, 1, 0, 2, 0));
    free(s);
    /* nested brackets, each restoring its own state */
    const char *t2 = "F[+F[-F]F]F";
    CHECK(fb_lsys_turtle(t2, strlen(t2), 90, 90, 2, "t", &s, &n, &depth) == FB_OK && n == 5 && depth == 2);
    CHECK(n == 5 && seg_is(&s[1], 0, 2, -2, 2, 1) && seg_is(&s[2], -2, 2, -2, 4, 2) && seg_is(&s[3], -2, 2, -4, 2, 1) &&
          seg_is(&s[4], 0, 2, 0, 4, 0));
    free(s);
    /* f moves without drawing; | turns back; other symbols are ignored */
    const char *t3 = "FfXF|F";
    CHECK(fb_lsys_turtle(t3, strlen(t3), 30, 0, 1, "t", &s, &n, &depth) == FB_OK && n == 3 && depth == 0);
    CHECK(n == 3 && seg_is(&s[0], 0, 0, 1, 0, 0) && seg_is(&s[1], 2, 0, 3, 0, 0) && seg_is(&s[2], 3, 0, 2, 0, 0));
    free(s);
    /* a full turn of + is the identity */
    const char *t4 = "++++++++++++F";
    CHECK(fb_lsys_turtle(t4, strlen(t4), 30, 90, 1, "t", &s, &n, &depth) == FB_OK && n == 1 &&
          seg_is(&s[0], 0, 0, 0, 1, 0));
    free(s);
    const char *t5 = "F]F";
    CHECK(fb_lsys_turtle(t5, strlen(t5), 30, 90, 1, "t", &s, &n, &depth) == FB_ERR_INPUT);

    /* every preset: one segment per F */
    const char *presets[5] = {"bush", "tree", "sticks", "weed", "stochastic"};
    for (int i = 0; i < 5; i++) {
        fb_lsys ls;
        fb_lsys_preset(presets[i], &ls);
        size_t len;
        char *str = derive(&ls, 3, &len);
        CHECK(str && fb_lsys_turtle(str, len, ls.angle, 90, 1, "t", &s, &n, &depth) == FB_OK);
        CHECKF(str && n == count_char(str, 'F'), "%s: %zu segments", presets[i], n);
        free(s);
        free(str);
    }
}

/* ---- coverage ------------------------------------------------------------------------------- */

static K_LsysSeg seg_px(double ax, double ay, double bx, double by, double hw)
{
    double len = hypot(bx - ax, by - ay);
    return (K_LsysSeg){
        (float)ax, (float)ay, (float)((bx - ax) / len), (float)((by - ay) / len), (float)len, (float)hw, 1.0f,
        0.5f,      0.25f};
}

static float coverage(K_LsysSeg s, int x, int y)
{
    K_LsysAcc a = {0, 0, 0, 0};
    return k_lsys_finish(k_lsys_add(a, s, (float)x + 0.5f, (float)y + 0.5f)).a;
}

static void test_coverage(void)
{
    /* a horizontal line through row 20's centres, half a pixel wide: 0.5 on each of its 40 pixels */
    K_LsysSeg h = seg_px(10, 20.5, 50, 20.5, 0.25);
    double sum = 0;
    int lit = 0;
    for (int y = 0; y < 64; y++)
        for (int x = 0; x < 64; x++) {
            float c = coverage(h, x, y);
            sum += c;
            lit += c > 0;
            if (y == 20 && x >= 10 && x < 50) CHECK(c == 0.5f);
        }
    CHECK(sum == 20.0 && lit == 40);
    /* a 3-pixel-wide vertical bar on pixel boundaries covers its pixels fully */
    K_LsysSeg v = seg_px(11.5, 5, 11.5, 25, 1.5);
    CHECK(coverage(v, 10, 10) == 1.0f && coverage(v, 11, 10) == 1.0f && coverage(v, 12, 10) == 1.0f);
    CHECK(coverage(v, 9, 10) == 0.0f && coverage(v, 13, 10) == 0.0f && coverage(v, 11, 4) == 0.0f);
    /* slanted: the coverage sums to the area (length x width) within the sampling error */
    K_LsysSeg d = seg_px(20.3, 30.7, 20.3 + 200 * cos(0.5236), 30.7 + 200 * sin(0.5236), 1.5);
    sum = 0;
    for (int y = 0; y < 256; y++)
        for (int x = 0; x < 256; x++) sum += coverage(d, x, y);
    CHECKF(fabs(sum - 600) < 6, "slanted line: coverage %g for an area of 600", sum);
    /* overlapping lines saturate at 1; colour stays the segments' (premultiplied by 1) */
    K_LsysAcc acc = {0, 0, 0, 0};
    acc = k_lsys_add(acc, v, 11.5f, 10.5f);
    acc = k_lsys_add(acc, v, 11.5f, 10.5f);
    acc = k_lsys_finish(acc);
    CHECK(acc.a == 1.0f && acc.r == 1.0f && acc.g == 0.5f && acc.b == 0.25f);
}

/* ---- the generator -------------------------------------------------------------------------- */

typedef struct planes4 {
    float *p[4]; /* A, R, G, B */
    int w, h;
} planes4;

static fb_result gen_rows(const char *json, planes4 *out, fb_gen *keep)
{
    fb_scene s;
    memset(out, 0, sizeof *out);
    fb_result rc = fb_scene_parse(json, NULL, &s);
    if (rc) return rc;
    fb_gen g;
    rc = fb_gen_init(&g, &s, &s.layers[0]);
    if (!rc) {
        size_t n = (size_t)s.width * s.height;
        for (int c = 0; c < 4; c++) out->p[c] = calloc(n, 4);
        g.compute.native_rows(&g, 0, s.height, (void *const *)out->p);
        out->w = s.width, out->h = s.height;
    }
    if (keep && !rc) {
        *keep = g;
        keep->scene = NULL; /* the scene is gone; the caller reads only params and input */
        keep->layer = NULL;
    } else {
        fb_gen_fini(&g);
    }
    fb_scene_fini(&s);
    return rc;
}

static void planes_free(planes4 *p)
{
    for (int c = 0; c < 4; c++) free(p->p[c]);
}

static void test_generator(void)
{
    /* axiom F from the origin along +x, 40 units, framed so that it runs along row 43's centres from
     * x = 10 to 50, half a pixel wide: exactly the kernel test's line */
    planes4 a;
    fb_result rc = gen_rows("{\"size\": [64, 64], \"layers\": [{\"type\": \"lsystem\", \"axiom\": \"F\", "
                            "\"heading\": 0, \"step\": 40, \"width\": 0.0125, \"bounds\": [-10, 54, -20.5, 43.5], "
                            "\"stops\": [[0, 0.5, 0.25, 1], [1, 0.5, 0.25, 1]]}]}",
                            &a, NULL);
    CHECKF(rc == FB_OK, "%s", g_last_error);
    if (!rc) {
        double sum = 0;
        for (int i = 0; i < 64 * 64; i++) sum += a.p[0][i];
        CHECK(sum == 20.0);
        CHECK(a.p[0][43 * 64 + 10] == 0.5f && a.p[0][43 * 64 + 49] == 0.5f && a.p[0][43 * 64 + 50] == 0.0f);
        CHECK(a.p[1][43 * 64 + 30] == 0.25f && a.p[3][43 * 64 + 30] == 0.5f); /* premultiplied colour */
        planes_free(&a);
    }

    /* tiling: the same bits as summing every segment over every pixel, in drawing order */
    fb_gen g;
    rc = gen_rows("{\"size\": [203, 157], \"seed\": 5, \"layers\": [{\"type\": \"lsystem\", \"preset\": "
                  "\"stochastic\", \"iterations\": 4, \"width\": 1.5}]}",
                  &a, &g);
    CHECKF(rc == FB_OK, "%s", g_last_error);
    if (!rc) {
        const K_LsysParams *p = (const K_LsysParams *)(const void *)g.params;
        const uint32_t *w = g.compute.shader.input;
        size_t nseg = (g.compute.shader.input_size / 4 - p->seg_off) / K_LSYS_SEG_WORDS, diff = 0, lit = 0;
        for (uint32_t y = 0; y < 157; y++)
            for (uint32_t x = 0; x < 203; x++) {
                K_LsysAcc acc = {0, 0, 0, 0};
                for (size_t k = 0; k < nseg; k++) {
                    K_LsysSeg sg;
                    memcpy(&sg, w + p->seg_off + k * K_LSYS_SEG_WORDS, sizeof sg);
                    acc = k_lsys_add(acc, sg, (float)x + 0.5f, (float)y + 0.5f);
                }
                acc = k_lsys_finish(acc);
                size_t i = (size_t)y * 203 + x;
                diff += acc.a != a.p[0][i] || acc.r != a.p[1][i] || acc.g != a.p[2][i] || acc.b != a.p[3][i];
                lit += acc.a > 0;
            }
        CHECKF(diff == 0 && lit > 1000, "%zu of %zu lit pixels differ from the brute-force sum", diff, lit);
        fb_gen_fini(&g);
        planes_free(&a);
    }

    /* tapering: depth d has half width hw0 taper^d; the depth-0 width is `width` steps */
    rc = gen_rows("{\"size\": [100, 100], \"layers\": [{\"type\": \"lsystem\", \"axiom\": \"F[+F[+F]]\", "
                  "\"angle\": 20, \"taper\": 0.5, \"width\": 0.1, \"bounds\": [-5, 5, -2, 8]}]}",
                  &a, &g);
    CHECKF(rc == FB_OK, "%s", g_last_error);
    if (!rc) {
        const K_LsysParams *p = (const K_LsysParams *)(const void *)g.params;
        K_LsysSeg s[3];
        memcpy(s, (const uint32_t *)g.compute.shader.input + p->seg_off, sizeof s);
        CHECKF(fabsf(s[0].hw - 0.5f) < 1e-5f && fabsf(s[1].hw - 0.25f) < 1e-5f && fabsf(s[2].hw - 0.125f) < 1e-5f,
               "half widths %g %g %g", s[0].hw, s[1].hw, s[2].hw);
        CHECK(fabsf(s[0].len - 10.0f) < 1e-4f && fabsf(s[0].ay - 80.0f) < 1e-4f); /* 10 px per unit, y up */
        fb_gen_fini(&g);
        planes_free(&a);
    }

    /* auto framing: the drawing fills the limiting dimension to within the 4% padding, inside */
    rc = gen_rows("{\"size\": [300, 200], \"layers\": [{\"type\": \"lsystem\", \"preset\": \"tree\"}]}", &a, NULL);
    CHECKF(rc == FB_OK, "%s", g_last_error);
    if (!rc) {
        int y0 = 200, y1 = -1, x0 = 300, x1 = -1;
        for (int y = 0; y < 200; y++)
            for (int x = 0; x < 300; x++)
                if (a.p[0][y * 300 + x] > 0) {
                    y0 = y < y0 ? y : y0, y1 = y > y1 ? y : y1;
                    x0 = x < x0 ? x : x0, x1 = x > x1 ? x : x1;
                }
        /* the tree is taller than wide here: its rows span 200 / 1.08 = 185 pixels, centred */
        CHECKF(y1 - y0 + 1 >= 183 && y1 - y0 + 1 <= 187 && y0 >= 5 && y0 <= 10 && 199 - y1 >= 5 && 199 - y1 <= 10,
               "rows %d..%d", y0, y1);
        CHECKF(x0 > 0 && x1 < 299 && abs((x0 + x1) - 299) < 10, "columns %d..%d", x0, x1);
        planes_free(&a);
    }
}

/* ---- bakes on every engine ------------------------------------------------------------------ */

static bool bake_read(fb_engine *e, const char *json, int strip, const char *path, planes4 *out)
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
        rc = exrio_read_rows(r, 0, s.height, planes); /* channels sorted by name: A, B, G, R */
        out->w = s.width, out->h = s.height;
    }
    exrio_close(&r);
    unlink(path);
    fb_scene_fini(&s);
    return rc == FB_OK;
}

static void test_engines(fb_engine *engines, int n)
{
    const char *json = "{\"size\": [301, 211], \"seed\": 9, \"layers\": [{\"type\": \"lsystem\", \"preset\": "
                       "\"stochastic\", \"width\": 2, \"half\": false}]}";
    const int strips[4] = {0, 7, 64, 211};
    char path[64];
    snprintf(path, sizeof path, "%s", th_path("lsys.exr"));
    planes4 first;
    CHECKF(bake_read(&engines[0], json, 0, path, &first), "%s", g_last_error);
    for (int i = 1; i < n; i++) {
        planes4 o;
        bool ok = bake_read(&engines[i], json, strips[i % 4], path, &o);
        bool same = ok && first.p[0];
        for (int c = 0; c < 4 && same; c++) same = !memcmp(first.p[c], o.p[c], (size_t)301 * 211 * 4);
        CHECKF(same, "engine %d (%s, %d threads, strips of %d) differs", i, fb_backend_name(engines[i].kind),
               engines[i].threads, strips[i % 4]);
        planes_free(&o);
    }
    planes_free(&first);
}

int main(int argc, char **argv)
{
    fb_log_set_sink(sink, NULL);
    test_derive();
    test_explosion();
    test_stochastic();
    test_checks();
    test_turtle();
    test_coverage();
    test_generator();

    fb_engine engines[4];
    bool have_gpu;
    int n = th_open_engines(argc, argv, engines, &have_gpu);
    test_engines(engines, n);
    if (have_gpu) CHECKF(vkc_validation_messages(engines[n - 1].vk) == 0, "validation layer messages");
    for (int i = 0; i < n; i++) fb_engine_close(&engines[i]);
    TEST_REPORT();
}
