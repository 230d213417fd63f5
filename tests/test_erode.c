/*
 * Erosion (kernels/erode.h, host/gen/erode/erode.c): bed plus sediment is conserved over 1000
 * iterations on the closed grid; rain on a tilted plane gathers at its low edge; flow concentrates
 * on a V-valley's floor; thermal erosion leaves no step above the talus step once converged; the
 * native result has the same bits for 1, 2 and 3 threads. With the argument `gpu`: the Vulkan
 * device (lavapipe) gives the same bits as the native path, under a silent validation layer;
 * 77 (not run) without a device. The masks' PNGs are their channels scaled to full scale at each one's
 * maximum, within half a step, at 8 and 16 bits.
 */
#include "bake.h"
#include "engine.h"
#include "env.h"
#include "erode.h"
#include "exrio.h"
#include "output.h"
#include "pngio.h"
#include "scene.h"

#include "testhelp.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static fb_erode_desc base(int w, int h, const float *bed)
{
    return (fb_erode_desc){.width = w,
                           .height = h,
                           .cell = 1,
                           .iterations = 200,
                           .duration = 60,
                           .rain = 0.005,
                           .gravity = 9.81,
                           .capacity = 0.05,
                           .dissolve = 0.5,
                           .deposit = 1,
                           .evaporate = 0.2,
                           .depth = 0.05,
                           .talus = 35,
                           .thermal = 0.5,
                           .bed = bed};
}

/* Ridges and valleys of a few sines, heights 0..~60, with slopes above the talus in places. */
static float *hills(int w, int h)
{
    float *b = malloc((size_t)w * h * sizeof *b);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            b[(size_t)y * w + x] = (float)(30 + 12 * sin(0.21 * x) * cos(0.17 * y) + 6 * sin(0.9 * x + 0.7 * y) +
                                           3 * cos(1.9 * x - 1.3 * y) + 0.1 * x);
    return b;
}

static bool same_out(const fb_erode_out *a, const fb_erode_out *b, size_t n)
{
    return !memcmp(a->bed, b->bed, n * 4) && !memcmp(a->water, b->water, n * 4) &&
           !memcmp(a->sediment, b->sediment, n * 4) && !memcmp(a->flow, b->flow, n * 4) &&
           !memcmp(a->wear, b->wear, n * 4) && !memcmp(a->deposit, b->deposit, n * 4);
}

/* Every transfer is computed alike by both cells, so only the additions' rounding changes the total:
 * each of ~5 additions per cell and iteration errs by at most half an ULP of a height below 64
 * (2^-19), independently, so over N cells and I iterations the total drifts by about
 * sqrt(5 N I) 2^-19 ~ 4e-3 here, 1e-8 of the total (3e6): 1e-5 relative leaves room for bias. */
static void test_mass(void)
{
    const int W = 96, H = 80;
    float *b = hills(W, H);
    fb_erode_desc d = base(W, H, b);
    d.iterations = 1000;
    d.duration = 300;
    fb_erode_out o;
    REQUIRE(fb_erode_run_native(&d, NULL, NULL, &o) == FB_OK);
    double m0 = 0, m1 = 0, moved = 0, water = 0;
    for (int i = 0; i < W * H; i++) {
        m0 += b[i];
        m1 += (double)o.bed[i] + o.sediment[i];
        moved += o.wear[i];
        water += o.water[i];
    }
    CHECKF(fabs(m1 - m0) <= 1e-5 * fabs(m0), "mass %.9g -> %.9g (relative %.3g)", m0, m1, (m1 - m0) / m0);
    /* and the run did something: material moved (well above the rounding), water is left */
    CHECKF(moved > 1e-3 * W * H && water > 0, "moved %g, water %g", moved, water);
    fb_erode_out_free(&o);
    free(b);
}

/* A plane falling towards x = 0, slope 0.2, no erosion: the rain runs down and stands at the low
 * edge. With no evaporation, the mean depth over the grid is the rain (total volume, to rounding);
 * the low edge's column holds over three times the mean and the upper half under a fifth of it. */
static void test_plane(void)
{
    const int W = 64, H = 24;
    float *b = malloc(W * H * sizeof *b);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) b[y * W + x] = (float)(0.2 * x);
    fb_erode_desc d = base(W, H, b);
    d.capacity = 0, d.thermal = 0, d.evaporate = 0, d.rain = 0.01, d.duration = 100, d.iterations = 400;
    fb_erode_out o;
    REQUIRE(fb_erode_run_native(&d, NULL, NULL, &o) == FB_OK);
    double low = 0, high = 0, all = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            double v = o.water[y * W + x];
            all += v / (W * H);
            if (x == 0) low += v / H;
            if (x >= W / 2) high += v / (H * W / 2);
        }
    CHECKF(fabs(all - 1.0) < 1e-3, "mean depth %g, rained 1", all);
    CHECKF(low > 3 * all && high < 0.2 * all, "low edge %g, upper half %g, mean %g", low, high, all);
    /* nothing eroded: the bed is the plane */
    CHECK(!memcmp(o.bed, b, W * H * 4));
    fb_erode_out_free(&o);
    free(b);
}

/* A V-valley along y (flanks of slope 0.5, floor falling 0.05 per cell towards y = H - 1): the
 * flow (time-averaged discharge) on the floor is greater than on either flank, 8 cells out, in every
 * row away from the ends, and more than twice it in the upper half (the closed lower end fills into
 * a lake, where the water spreads across). */
static void test_valley(void)
{
    const int W = 49, H = 64, c = W / 2;
    float *b = malloc(W * H * sizeof *b);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) b[y * W + x] = (float)(0.5 * abs(x - c) + 0.05 * (H - 1 - y));
    fb_erode_desc d = base(W, H, b);
    d.thermal = 0, d.duration = 100, d.iterations = 400;
    fb_erode_out o;
    REQUIRE(fb_erode_run_native(&d, NULL, NULL, &o) == FB_OK);
    int bad = 0;
    double worst = 1e30, worst_upper = 1e30;
    for (int y = 8; y < H - 8; y++) {
        double floor_ = o.flow[y * W + c], flank = fmax(o.flow[y * W + c - 8], o.flow[y * W + c + 8]);
        worst = fmin(worst, floor_ / flank);
        if (y < H / 2) worst_upper = fmin(worst_upper, floor_ / flank);
        bad += !(floor_ > flank);
    }
    CHECKF(bad == 0 && worst_upper > 2,
           "%d rows where the floor's flow is not above the flanks' (worst ratio %g, %g "
           "in the upper half)",
           bad, worst, worst_upper);
    fb_erode_out_free(&o);
    free(b);
}

/* Thermal erosion alone (no rain) on rough random heights: after convergence no step between
 * 4-neighbours exceeds the talus step tan(30 deg) l by more than 1e-3 of it; mass is conserved. */
static void test_thermal(void)
{
    const int W = 48, H = 40;
    float *b = malloc(W * H * sizeof *b);
    th_rng = 12345;
    for (int i = 0; i < W * H; i++) b[i] = (float)(10 * th_unif());
    fb_erode_desc d = base(W, H, b);
    d.rain = 0, d.capacity = 0, d.talus = 30, d.cell = 0.5;
    d.iterations = 3000, d.duration = 3000, d.thermal = 1; /* kt = 0.5 per iteration: the fastest stable */
    fb_erode_out o;
    REQUIRE(fb_erode_run_native(&d, NULL, NULL, &o) == FB_OK);
    double step = tan(30 * M_PI / 180) * d.cell, worst = 0, m0 = 0, m1 = 0, before = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            int i = y * W + x;
            m0 += b[i], m1 += o.bed[i];
            if (x + 1 < W) {
                worst = fmax(worst, fabs((double)o.bed[i] - o.bed[i + 1]));
                before = fmax(before, fabs((double)b[i] - b[i + 1]));
            }
            if (y + 1 < H) worst = fmax(worst, fabs((double)o.bed[i] - o.bed[i + W]));
        }
    CHECKF(before > 10 * step, "the input is not rough enough (%g)", before);
    CHECKF(worst <= step * (1 + 1e-3), "largest step %.9g, talus step %.9g", worst, step);
    CHECKF(fabs(m1 - m0) <= 1e-6 * m0, "mass %.9g -> %.9g", m0, m1);
    fb_erode_out_free(&o);
    free(b);
}

/* Jacobi passes: 1, 2 and 3 threads (bands of different heights) give the same bits. */
static void test_threads(void)
{
    const int W = 83, H = 71;
    float *b = hills(W, H);
    fb_erode_desc d = base(W, H, b);
    d.iterations = 60;
    fb_erode_out ref, o;
    REQUIRE(fb_erode_run_native(&d, NULL, NULL, &ref) == FB_OK);
    for (int t = 1; t <= 3; t++) {
        fb_pool *pool = NULL;
        REQUIRE(fb_pool_create(t, &pool) == FB_OK);
        REQUIRE(fb_erode_run_native(&d, pool, NULL, &o) == FB_OK);
        CHECKF(same_out(&ref, &o, (size_t)W * H), "%d threads differ", t);
        fb_erode_out_free(&o);
        fb_pool_destroy(&pool);
    }
    fb_erode_out_free(&ref);
    free(b);
}

/* The device against the native path: the same bits (every kernel operation is `precise`, and the
 * operations are +, -, *, /, sqrt, min and max, which both round correctly), on a grid whose width
 * is not a multiple of the workgroup, with rain, dissolution, deposition and slides all active. */
static int test_gpu(void)
{
    fb_engine e;
    fb_env env; /* FB_VK_STAGING: the discrete-GPU path */
    fb_env_read(&env);
    if (fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_VULKAN, .validation = true, .vk_options = env.vk}, &e))
        TEST_SKIP("no Vulkan device");
    const int W = 157, H = 93;
    float *b = hills(W, H);
    fb_erode_desc d = base(W, H, b);
    d.iterations = 150;
    fb_erode_out g, n;
    REQUIRE(fb_erode_run_vulkan(&d, e.vk, NULL, &g) == FB_OK);
    REQUIRE(fb_erode_run_native(&d, NULL, NULL, &n) == FB_OK);
    size_t diff = 0;
    for (size_t i = 0; i < (size_t)W * H; i++) diff += memcmp(&g.bed[i], &n.bed[i], 4) != 0;
    CHECKF(same_out(&g, &n, (size_t)W * H), "%zu of %d beds differ between %s and native", diff, W * H, e.device);
    double moved = 0;
    for (int i = 0; i < W * H; i++) moved += n.wear[i];
    CHECKF(moved > 1e-3 * W * H, "nothing eroded (%g)", moved);
    CHECK(g.gpu_seconds != 0);
    CHECKF(vkc_validation_messages(e.vk) == 0, "%u validation messages", vkc_validation_messages(e.vk));
    fb_erode_out_free(&g);
    fb_erode_out_free(&n);
    free(b);
    fb_engine_close(&e);
    TEST_REPORT();
}

/* The masks as PNGs ("masks", "mask-bits"): each is the EXR's channel scaled from 0 at 0 to full
 * scale at the channel's maximum, within half a step (8 and 16 bits), and written with the EXR. */
static void test_masks(int bits)
{
    const int W = 48, H = 40;
    char json[512], prefix[600], exr[600];
    snprintf(prefix, sizeof prefix, "%s", th_path(bits == 8 ? "m8" : "m16"));
    snprintf(exr, sizeof exr, "%s", th_path(bits == 8 ? "m8.exr" : "m16.exr"));
    snprintf(json, sizeof json,
             "{\"size\": [%d, %d], \"layers\": [{\"type\": \"fbm\", \"name\": \"h\", \"octaves\": 5}, "
             "{\"type\": \"erode\", \"name\": \"e\", \"input\": \"h\", \"extent\": 8, \"iterations\": 30, "
             "\"duration\": 10, \"masks\": \"%s\", \"mask-bits\": %d}]}",
             W, H, prefix, bits);
    fb_scene sc;
    REQUIRE(fb_scene_parse(json, "masks", &sc) == FB_OK);
    fb_engine e;
    REQUIRE(fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = 2}, &e) == FB_OK);
    fb_outputs_begin();
    REQUIRE(fb_outputs_end(fb_bake(&e, &(fb_bake_desc){.scene = &sc, .out = exr}, NULL)) == FB_OK);
    fb_engine_close(&e);
    fb_scene_fini(&sc);
    exrio_reader *r;
    REQUIRE(exrio_open(exr, &r) == FB_OK);
    static const char *const names[4] = {"flow", "wear", "deposition", "sediment"};
    for (int k = 0; k < 4; k++) {
        char ch[32], png_path[700];
        snprintf(ch, sizeof ch, "e.%s", names[k]);
        snprintf(png_path, sizeof png_path, "%s.%s.png", prefix, names[k]);
        float *v = malloc((size_t)W * H * sizeof *v);
        void *planes[16] = {0};
        int c = exrio_find_channel(r, ch);
        REQUIRE(v && c >= 0 && c < 16);
        planes[c] = v;
        REQUIRE(exrio_read_rows(r, 0, H, planes) == FB_OK);
        fb_png png;
        REQUIRE(fb_png_read(png_path, &png) == FB_OK);
        CHECK(png.width == W && png.height == H && png.channels == 1 && png.depth == bits);
        double top = 0, worst = 0, full = bits == 16 ? 65535 : 255;
        for (int i = 0; i < W * H; i++) top = fmax(top, v[i]);
        int at_full = 0;
        for (int i = 0; i < W * H; i++) {
            double q = round(png.plane[0][i] * full);
            worst = fmax(worst, fabs(q / full * top - fmax(v[i], 0)));
            at_full += q == full;
        }
        CHECKF(top > 0 && worst <= 0.5 * top / full * (1 + 1e-6) && at_full >= 1,
               "%s, %d bits: %g off (half a step %g)", names[k], bits, worst, 0.5 * top / full);
        fb_png_fini(&png);
        free(v);
    }
    exrio_close(&r);
}

int main(int argc, char **argv)
{
    if (argc > 1 && !strcmp(argv[1], "gpu")) return test_gpu();
    test_mass();
    test_plane();
    test_valley();
    test_thermal();
    test_threads();
    test_masks(8);
    test_masks(16);
    TEST_REPORT();
}
