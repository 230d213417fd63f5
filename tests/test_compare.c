/*
 * compare's verdicts on constructed pairs (compare/compare.c): images written here with known
 * differences, each threshold checked on both sides of its boundary: max-abs with fail-percent,
 * hardfail, warnings, per-channel and per-layer rules, RMSE, a size mismatch, a missing channel and
 * --ignore-missing.
 */
#include "compare.h"
#include "exrio.h"
#include "output.h"

#include "testhelp.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

enum { W = 40, H = 25 };
static char g_dir[] = "/tmp/fb-test-compare-XXXXXX";

/* Writes a W x H (or w x h) float EXR of channels names[0..n) where channel c, pixel i is
 * base(c, i) + delta when i is in [d0, d1) of channel dc. */
static void write_exr(const char *name, int w, int h, const char *const *names, int n, int dc, int d0, int d1,
                      float delta, char *path, size_t size)
{
    snprintf(path, size, "%s/%s", g_dir, name);
    exrio_channel ch[4];
    for (int c = 0; c < n; c++) ch[c] = (exrio_channel){names[c], EXRIO_FLOAT};
    float *planes[4];
    for (int c = 0; c < n; c++) {
        planes[c] = malloc((size_t)w * h * 4);
        for (int i = 0; i < w * h; i++)
            planes[c][i] = (float)((i * 7 + c * 3) % 17) / 16.0f + (c == dc && i >= d0 && i < d1 ? delta : 0.0f);
    }
    fb_outputs_begin();
    exrio_writer *wr = NULL;
    fb_result rc = exrio_writer_create(
        &(exrio_writer_desc){
            .path = path, .width = w, .height = h, .compression = EXRIO_NONE, .channels = ch, .nchannels = n},
        &wr);
    if (!rc) rc = exrio_writer_rows(wr, 0, h, (const void *const *)planes);
    if (!rc) rc = exrio_writer_finish(&wr);
    exrio_writer_abort(&wr);
    rc = fb_outputs_end(rc);
    REQUIRE(rc == FB_OK);
    for (int c = 0; c < n; c++) free(planes[c]);
}

static void quiet(const char *line, void *user)
{
    (void)line, (void)user;
}

/* The verdict of comparing a and b with thresholds given as flag/value pairs ("--max-abs", "0.1"). */
static fb_verdict verdict_of(const char *a, const char *b, const char *const *args, int nargs, bool ignore_missing)
{
    fb_compare_desc d = {.a = a, .b = b, .ignore_missing = ignore_missing, .print = quiet};
    for (int i = 0; i + 1 < nargs; i += 2) {
        fb_limit *l = !strcmp(args[i], "--max-abs")        ? &d.fail
                      : !strcmp(args[i], "--fail-percent") ? &d.failpercent
                      : !strcmp(args[i], "--hardfail")     ? &d.hardfail
                      : !strcmp(args[i], "--warn")         ? &d.warn
                      : !strcmp(args[i], "--rmse")         ? &d.rmse
                                                           : NULL;
        REQUIRE(l && fb_limit_parse(args[i], args[i + 1], l) == FB_OK);
    }
    fb_verdict v = FB_VERDICT_FAIL;
    fb_result rc = fb_compare(&d, &v);
    CHECKF(rc == FB_OK, "compare %s %s ran", a, b);
    return rc ? (fb_verdict)-1 : v;
}

#define V(a, b, ...)                                                                                                   \
    verdict_of(a, b, (const char *const[]){__VA_ARGS__}, sizeof((const char *const[]){__VA_ARGS__}) / sizeof(char *),  \
               false)

int main(void)
{
    REQUIRE(mkdtemp(g_dir) != NULL);
    const char *rgb[3] = {"sky.R", "sky.G", "ground.Y"};
    char a[256], b[256], c[256], big[256], two[256], diff10[256];
    write_exr("a.exr", W, H, rgb, 3, -1, 0, 0, 0, a, sizeof a);
    /* b: 10 pixels of sky.G off by 0.5 (1% of the 1000) */
    write_exr("b.exr", W, H, rgb, 3, 1, 100, 110, 0.5f, b, sizeof b);
    /* c: one pixel of ground.Y off by 0.01 */
    write_exr("c.exr", W, H, rgb, 3, 2, 7, 8, 0.01f, c, sizeof c);
    write_exr("big.exr", W + 1, H, rgb, 3, -1, 0, 0, 0, big, sizeof big);
    write_exr("two.exr", W, H, rgb, 2, -1, 0, 0, 0, two, sizeof two);
    write_exr("d10.exr", W, H, rgb, 3, 1, 0, 1000, 0.25f, diff10, sizeof diff10);

    CHECK(V(a, a, "--max-abs", "0") == FB_VERDICT_PASS);
    CHECK(V(a, b, "--max-abs", "0") == FB_VERDICT_FAIL);
    CHECK(V(a, b, "--max-abs", "0.49") == FB_VERDICT_FAIL);
    CHECK(V(a, b, "--max-abs", "0.51") == FB_VERDICT_PASS);
    /* 1% of sky.G's pixels fail: within 1.5%, not within 0.5% */
    CHECK(V(a, b, "--max-abs", "0.1", "--fail-percent", "1.5") == FB_VERDICT_PASS);
    CHECK(V(a, b, "--max-abs", "0.1", "--fail-percent", "0.5") == FB_VERDICT_FAIL);
    /* ... but never beyond a hard limit */
    CHECK(V(a, b, "--max-abs", "0.1", "--fail-percent", "1.5", "--hardfail", "0.4") == FB_VERDICT_FAIL);
    CHECK(V(a, b, "--max-abs", "0.1", "--fail-percent", "1.5", "--hardfail", "0.6") == FB_VERDICT_PASS);
    /* a rule for one channel or one layer wins over the value for all */
    CHECK(V(a, b, "--max-abs", "0,sky.G=0.6") == FB_VERDICT_PASS);
    CHECK(V(a, b, "--max-abs", "0,sky=0.6") == FB_VERDICT_PASS);
    CHECK(V(a, b, "--max-abs", "0,ground=0.6") == FB_VERDICT_FAIL);
    /* a warning passes, a failure does not */
    CHECK(V(a, c, "--max-abs", "0.1", "--warn", "0.005") == FB_VERDICT_WARN);
    CHECK(V(a, c, "--max-abs", "0.1", "--warn", "0.02") == FB_VERDICT_PASS);
    /* RMSE: every sky.G pixel off by 0.25 gives 0.25 exactly */
    CHECK(V(a, diff10, "--max-abs", "1", "--rmse", "0.26") == FB_VERDICT_PASS);
    CHECK(V(a, diff10, "--max-abs", "1", "--rmse", "0.24") == FB_VERDICT_FAIL);
    /* what cannot be compared fails */
    CHECK(V(a, big, "--max-abs", "1") == FB_VERDICT_FAIL);
    CHECK(V(a, two, "--max-abs", "1") == FB_VERDICT_FAIL);
    CHECK(verdict_of(a, two, (const char *const[]){"--max-abs", "1"}, 2, true) == FB_VERDICT_PASS);
    /* an unreadable file is an error, not a verdict */
    fb_verdict v;
    char missing[300];
    snprintf(missing, sizeof missing, "%s/none.exr", g_dir);
    CHECK(fb_compare(&(fb_compare_desc){.a = a, .b = missing, .print = quiet}, &v) != FB_OK);

    const char *files[] = {"a.exr", "b.exr", "c.exr", "big.exr", "two.exr", "d10.exr"};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        char p[300];
        snprintf(p, sizeof p, "%s/%s", g_dir, files[i]);
        unlink(p);
    }
    rmdir(g_dir);
    TEST_REPORT();
}
