/*
 * Op layers (compositing): each op's pixels equal its formula evaluated independently here on the
 * inputs read back from the file (float channels, so exactly); layers may refer to later layers;
 * the strip height does not change anything; a missing layer, a missing channel and a cycle are
 * errors naming both layers; an op whose value overflows a float fails the bake, naming the first
 * such pixel (found here from the threshold it multiplies).
 */
#include "bake.h"
#include "exrio.h"
#include "scene.h"

#include "testhelp.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char g_msg[2048];
static void sink(int level, const char *msg, void *user)
{
    (void)user;
    if (level == FB_LOG_ERROR && !g_msg[0]) snprintf(g_msg, sizeof g_msg, "%s", msg);
}

/* The op layers come first in the file, before the layers they use. */
static const char *k_scene =
    "{\"size\": [96, 40], \"seed\": 3, \"layers\": ["
    "{\"type\": \"op\", \"name\": \"ground\", \"op\": \"add\", \"inputs\": [\"terrain.Y\", \"detail\", 2.5],"
    " \"weights\": [1, 5, -1]},"
    "{\"type\": \"op\", \"name\": \"high\", \"op\": \"threshold\", \"inputs\": [\"ground\"], \"level\": 30, \"width\": "
    "10},"
    "{\"type\": \"op\", \"name\": \"step\", \"op\": \"threshold\", \"inputs\": [\"ground\"], \"level\": 30},"
    "{\"type\": \"op\", \"name\": \"lowplants\", \"op\": \"mix\", \"inputs\": [\"plants.A\", 0], \"mask\": \"high\"},"
    "{\"type\": \"op\", \"name\": \"h01\", \"op\": \"remap\", \"inputs\": [\"terrain.Y\"], \"from\": [0, 80], \"to\": "
    "[-1, 1]},"
    "{\"type\": \"op\", \"name\": \"free\", \"op\": \"remap\", \"inputs\": [\"terrain\"], \"from\": [0, 80], "
    "\"clamp\": false},"
    "{\"type\": \"op\", \"name\": \"prod\", \"op\": \"multiply\", \"inputs\": [\"detail.Y\", \"plants.count\", 0.5]},"
    "{\"type\": \"terrain\", \"name\": \"terrain\", \"points\": [[0,0,0],[100,0,10],[0,50,20],[100,50,40],[50,25,45]],"
    " \"insert\": 2000, \"bounds\": [0, 100, 0, 50]},"
    "{\"type\": \"fbm\", \"name\": \"detail\", \"octaves\": 5, \"frequency\": 8},"
    "{\"type\": \"ifs\", \"name\": \"plants\", \"preset\": \"fern\", \"points\": 300000, \"half\": false}]}";

static const char *const k_names[] = {"ground.Y", "high.Y",    "step.Y",   "lowplants.Y", "h01.Y",       "free.Y",
                                      "prod.Y",   "terrain.Y", "detail.Y", "plants.A",    "plants.count"};
enum { GROUND, HIGH, STEP, LOW, H01, FREE, PROD, TER, DET, PA, PC, NCH };

static bool bake_read(fb_engine *e, const fb_scene *s, int strip, const char *path, float *out[NCH])
{
    fb_bake_stats st;
    if (fb_bake(e, &(fb_bake_desc){.scene = s, .out = path, .strip_rows = strip}, &st) != FB_OK) return false;
    exrio_reader *r = NULL;
    if (exrio_open(path, &r) != FB_OK) return false;
    void *planes[64] = {0};
    size_t n = (size_t)s->width * s->height;
    for (int c = 0; c < NCH; c++) {
        int k = exrio_find_channel(r, k_names[c]);
        CHECKF(k >= 0, "%s", k_names[c]);
        out[c] = malloc(n * 4);
        if (k >= 0) planes[k] = out[c];
    }
    bool ok = exrio_read_rows(r, 0, s->height, planes) == FB_OK;
    exrio_close(&r);
    unlink(path);
    return ok;
}

static void test_values(void)
{
    fb_scene s;
    CHECKF(fb_scene_parse(k_scene, "scene", &s) == FB_OK, "%s", g_msg);
    /* the order puts every op after its inputs */
    int pos[FB_MAX_LAYERS];
    for (int i = 0; i < s.nlayers; i++) pos[s.order[i]] = i;
    CHECK(pos[0] > pos[7] && pos[0] > pos[8] && pos[1] > pos[0] && pos[3] > pos[1] && pos[3] > pos[9]);
    fb_engine e;
    CHECK(fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = 2}, &e) == FB_OK);
    float *a[NCH], *b[NCH];
    CHECK(bake_read(&e, &s, 0, th_path("compose-a.exr"), a));
    CHECK(bake_read(&e, &s, 7, th_path("compose-b.exr"), b));
    size_t n = (size_t)s.width * s.height, bad = 0, same = 0, highs = 0, lows = 0;
    for (size_t i = 0; i < n; i++) {
        double g = (double)a[TER][i] + 5.0 * a[DET][i] - 2.5;
        double t = (a[GROUND][i] - 25.0) / 10.0;
        t = t < 0 ? 0 : t > 1 ? 1 : t;
        double hi = t * t * (3 - 2 * t);
        double m = a[HIGH][i];
        double low = a[PA][i] + (0.0 - a[PA][i]) * m;
        double u = a[TER][i] / 80.0;
        double cu = u < 0 ? 0 : u > 1 ? 1 : u;
        uint32_t count;
        memcpy(&count, &a[PC][i], 4); /* uint channels come back as uint32 */
        double prod = (double)a[DET][i] * (double)count * 0.5;
        bad += a[GROUND][i] != (float)g;
        bad += a[HIGH][i] != (float)hi;
        bad += a[STEP][i] != (a[GROUND][i] >= 30.0f ? 1.0f : 0.0f);
        bad += a[LOW][i] != (float)low;
        bad += a[H01][i] != (float)(-1.0 + 2.0 * cu);
        bad += a[FREE][i] != (float)u;
        bad += a[PROD][i] != (float)prod;
        highs += a[STEP][i] == 1.0f;
        lows += a[STEP][i] == 0.0f && a[PA][i] > 0;
        for (int c = 0; c < NCH; c++) same += memcmp(&a[c][i], &b[c][i], 4) == 0;
    }
    CHECKF(bad == 0, "%zu op values differ from their formulas", bad);
    CHECK(same == n * NCH);                      /* strip height 7 == automatic */
    CHECK(highs > n / 20 && highs < n - n / 20); /* the threshold splits the image: the test sees both sides */
    CHECK(lows > 0);
    for (int c = 0; c < NCH; c++) free(a[c]), free(b[c]);
    fb_engine_close(&e);
    fb_scene_fini(&s);
}

static void expect_error(const char *json, const char *want)
{
    fb_scene s;
    g_msg[0] = 0;
    fb_result rc = fb_scene_parse(json, "t.json", &s);
    if (rc == FB_OK) { /* channel errors surface when the bake resolves the inputs */
        fb_engine e;
        CHECK(fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = 1}, &e) == FB_OK);
        rc = fb_bake(&e, &(fb_bake_desc){.scene = &s}, NULL);
        fb_engine_close(&e);
    }
    CHECKF(rc != FB_OK && strstr(g_msg, want), "wanted \"%s\", got \"%s\"", want, g_msg);
    fb_scene_fini(&s);
}

static void test_errors(void)
{
    const char *fbm = "{\"type\": \"fbm\", \"name\": \"n\"}";
    char j[1024];
    snprintf(j, sizeof j,
             "{\"layers\": [%s, {\"type\": \"op\", \"name\": \"a\", \"op\": \"add\", \"inputs\": [\"b\", \"n\"]},"
             "{\"type\": \"op\", \"name\": \"b\", \"op\": \"multiply\", \"inputs\": [\"n\", \"a.Y\"]}]}",
             fbm);
    expect_error(j, "layers[2]: layer \"b\" uses layer \"a\", which depends on \"b\": a cycle");
    snprintf(j, sizeof j,
             "{\"layers\": [{\"type\": \"op\", \"name\": \"a\", \"op\": \"remap\", \"inputs\": [\"a\"], \"from\": [0, "
             "1]}]}");
    expect_error(j, "layer \"a\" uses layer \"a\", which depends on \"a\": a cycle");
    snprintf(
        j, sizeof j,
        "{\"layers\": [%s,\n {\"type\": \"op\", \"name\": \"a\", \"op\": \"add\", \"inputs\": [\"n\", \"terain.Y\"]}]}",
        fbm);
    expect_error(j,
                 "t.json:2: layers[1].inputs[1]: layer \"a\" refers to \"terain.Y\", but no layer is named \"terain\"");
    snprintf(j, sizeof j,
             "{\"layers\": [%s, {\"type\": \"op\", \"name\": \"a\", \"op\": \"add\", \"inputs\": [\"n.Q\", 1]}]}", fbm);
    expect_error(j, "layer \"a\": input \"n.Q\": layer \"n\" has no channel Q (channels: Y)");
    snprintf(j, sizeof j,
             "{\"layers\": [{\"type\": \"julia\"}, {\"type\": \"op\", \"op\": \"threshold\", \"inputs\": [\"sky\"], "
             "\"level\": 1}]}");
    expect_error(j, "layer \"sky\" has no channel Y (name one) (channels: iter, n, inside, de, R, G, B)");
    snprintf(j, sizeof j, "{\"layers\": [%s, {\"type\": \"op\", \"op\": \"mix\", \"inputs\": [\"n\", 1]}]}", fbm);
    expect_error(j, "layers[1].mask: required for op mix");
    snprintf(j, sizeof j, "{\"layers\": [%s, {\"type\": \"op\", \"op\": \"add\", \"inputs\": [\"n\"]}]}", fbm);
    expect_error(j, "add takes 2 to 8 inputs, found 1");
    snprintf(j, sizeof j,
             "{\"layers\": [%s, {\"type\": \"op\", \"op\": \"add\", \"inputs\": [\"n\", 2], \"level\": 3}]}", fbm);
    expect_error(j, "layers[1].level: only for op threshold, not add");
    snprintf(j, sizeof j,
             "{\"layers\": [%s, {\"type\": \"op\", \"op\": \"add\", \"inputs\": [\"n\", 2], \"weights\": [1]}]}", fbm);
    expect_error(j, "expected one weight per input (2), found 1");
    snprintf(j, sizeof j,
             "{\"layers\": [%s, {\"type\": \"op\", \"op\": \"remap\", \"inputs\": [\"n\"], \"from\": [2, 2]}]}", fbm);
    expect_error(j, "the source range must not be empty");
    snprintf(j, sizeof j, "{\"layers\": [%s, {\"type\": \"op\", \"op\": \"add\", \"inputs\": [\"n\", \".Y\"]}]}", fbm);
    expect_error(j, "expected \"layer.channel\", \"layer\" or a number");
}

/* terrain.slope: on a plane z = 0.5 x + 0.25 y every pixel in the hull has the plane's slope,
 * atan(|grad z|); an op masks by it. */
static void test_slope(void)
{
    const char *json = "{\"size\": [40, 30], \"layers\": [{\"type\": \"terrain\", \"insert\": 0, \"points\": "
                       "[[0, 0, 0], [40, 0, 20], [0, 30, 7.5], [40, 30, 27.5], [13, 11, 9.25]]},"
                       "{\"type\": \"op\", \"name\": \"steep\", \"op\": \"threshold\", \"inputs\": [\"terrain.slope\"],"
                       " \"level\": 29}]}";
    fb_scene s;
    CHECKF(fb_scene_parse(json, "slope", &s) == FB_OK, "%s", g_msg);
    fb_engine e;
    CHECK(fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = 2}, &e) == FB_OK);
    CHECK(fb_bake(&e, &(fb_bake_desc){.scene = &s, .out = th_path("slope.exr")}, NULL) == FB_OK);
    exrio_reader *r = NULL;
    CHECK(exrio_open(th_path("slope.exr"), &r) == FB_OK);
    size_t n = 40 * 30;
    float *A = malloc(n * 4), *S = malloc(n * 4), *M = malloc(n * 4);
    void *planes[16] = {0};
    planes[exrio_find_channel(r, "terrain.A")] = A;
    planes[exrio_find_channel(r, "terrain.slope")] = S;
    planes[exrio_find_channel(r, "steep.Y")] = M;
    CHECK(exrio_read_rows(r, 0, 30, planes) == FB_OK);
    double want = atan(sqrt(0.5 * 0.5 + 0.25 * 0.25)) * 180.0 / M_PI; /* 29.206 degrees */
    size_t inside = 0, bad = 0;
    for (size_t i = 0; i < n; i++) {
        if (A[i] == 1.0f) {
            inside++;
            bad += fabs(S[i] - want) > 1e-4 || M[i] != 1.0f;
        } else {
            bad += S[i] != 0.0f || M[i] != 0.0f;
        }
    }
    CHECKF(inside == n && bad == 0, "%zu of %zu inside, %zu wrong (want %.6f)", inside, n, bad, want);
    exrio_close(&r);
    unlink(th_path("slope.exr"));
    free(A), free(S), free(M);
    fb_engine_close(&e);
    fb_scene_fini(&s);
}

/* The finite check: "big" is infinite exactly where the threshold "t" is 1 (1e45 overflows a float),
 * so the first such pixel (row by row) of t, read back from a bake without "big", is the one the
 * failing bake must name. A width of 77: rows of 72 values on eight lanes and a tail of five. */
static void test_nonfinite(void)
{
    static const float levels[] = {0.3f, 0.45f, 0.6f};
    for (size_t l = 0; l < sizeof levels / sizeof levels[0]; l++) {
        char base[512], json[768];
        snprintf(base, sizeof base,
                 "{\"size\": [77, 40], \"seed\": %zu, \"layers\": [{\"type\": \"fbm\", \"name\": \"n\", "
                 "\"octaves\": 4, \"frequency\": 6}, {\"type\": \"op\", \"name\": \"t\", \"op\": \"threshold\", "
                 "\"inputs\": [\"n\"], \"level\": %g}",
                 l + 1, levels[l]);
        snprintf(json, sizeof json, "%s]}", base);
        fb_scene s;
        fb_engine e;
        REQUIRE(fb_scene_parse(json, "t.json", &s) == FB_OK);
        REQUIRE(fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = 2}, &e) == FB_OK);
        const char *path = th_path("finite.exr");
        REQUIRE(fb_bake(&e, &(fb_bake_desc){.scene = &s, .out = path}, NULL) == FB_OK);
        exrio_reader *r = NULL;
        REQUIRE(exrio_open(path, &r) == FB_OK);
        float *t = malloc(77 * 40 * 4);
        void *planes[8] = {0};
        int k = exrio_find_channel(r, "t.Y");
        REQUIRE(k >= 0 && k < 8 && t);
        planes[k] = t;
        REQUIRE(exrio_read_rows(r, 0, 40, planes) == FB_OK);
        exrio_close(&r);
        unlink(path);
        fb_scene_fini(&s);
        int first = -1;
        for (int i = 0; i < 77 * 40 && first < 0; i++)
            if (t[i] == 1.0f) first = i;
        free(t);
        CHECKF(first >= 0, "level %g: no pixel of t is 1", levels[l]);
        snprintf(json, sizeof json,
                 "%s, {\"type\": \"op\", \"name\": \"big\", \"op\": \"multiply\", \"inputs\": [\"t\", 1e15, "
                 "1e15, 1e15]}]}",
                 base);
        REQUIRE(fb_scene_parse(json, "t.json", &s) == FB_OK);
        g_msg[0] = 0;
        fb_result rc = fb_bake(&e, &(fb_bake_desc){.scene = &s, .out = path}, NULL);
        char want[64];
        snprintf(want, sizeof want, "an infinity at pixel (%d, %d) of big.Y", first % 77, first / 77);
        CHECKF(rc != FB_OK && strstr(g_msg, want), "level %g: wanted \"%s\", got \"%s\"", levels[l], want, g_msg);
        CHECK(access(path, F_OK) != 0); /* no partial output */
        fb_engine_close(&e);
        fb_scene_fini(&s);
    }
}

int main(void)
{
    fb_log_set_sink(sink, NULL);
    test_slope();
    test_values();
    test_errors();
    test_nonfinite();
    TEST_REPORT();
}
