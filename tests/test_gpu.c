/*
 * lavapipe (or any Vulkan device) against the native backend: the same bits from both for every fBm
 * noise kind, style and mapping, and every Julia mapping and precision (every shader's arithmetic is
 * exact: kernels/exact.h); determinism across strip heights; zero validation messages. With
 * FB_VK_STAGING=1 (the CTest twin NAME-staging) the device takes a discrete GPU's path: the portable
 * division and square root, device-local memory and staging copies. Returns 77
 * (not run) only when there is no Vulkan device.
 */
#include "bake.h"
#include "env.h"
#include "exrio.h"

#include "testhelp.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static char g_dir[] = "/tmp/fb-test-gpu-XXXXXX";

/* Bakes `json` with engine e and returns channel `channel` of the file as 4-byte values. */
static void *bake_read_channel(fb_engine *e, const char *json, int strip, const char *name, const char *channel)
{
    fb_scene s;
    if (fb_scene_parse(json, NULL, &s)) return NULL;
    char path[128];
    snprintf(path, sizeof path, "%s/%s.exr", g_dir, name);
    fb_result rc = fb_bake(e, &(fb_bake_desc){.scene = &s, .out = path, .strip_rows = strip}, NULL);
    void *px = NULL;
    exrio_reader *r = NULL;
    if (!rc && !exrio_open(path, &r)) {
        int c = channel ? exrio_find_channel(r, channel) : 0;
        void *planes[16] = {0};
        px = c >= 0 ? malloc((size_t)s.width * s.height * 4) : NULL;
        if (px) planes[c] = px;
        if (px && exrio_read_rows(r, 0, s.height, planes)) {
            free(px);
            px = NULL;
        }
        exrio_close(&r);
    }
    fb_scene_fini(&s);
    return px;
}

static float *bake_read(fb_engine *e, const char *json, int strip, const char *name)
{
    return bake_read_channel(e, json, strip, name, NULL);
}

/* Julia: every mapping's start (sincos.h), orbit (contraction-free), smooth count and distance
 * (explog.h, kernels/exact.h) are the same operations rounded the same on both sides: every channel
 * the same bits, boundary pixels included. */
static void test_julia(fb_engine *gpu, fb_engine *cpu)
{
    static const char *variants[] = {"",
                                     ", \"alpha\": [0.5, 0.25]",
                                     ", \"mapping\": \"polar\", \"alpha\": [-0.3, 0]",
                                     ", \"mapping\": \"polar\", \"alpha\": [-0.3, 0], \"turbulence\": 0.2",
                                     ", \"mapping\": \"latlong\", \"alpha\": [-0.3, 0], \"turbulence\": 0.2",
                                     ", \"mapping\": \"cube\", \"alpha\": [0.3, 0.1], \"radius\": 1.2"};
    static const int sizes[][2] = {{181, 97}, {181, 97}, {181, 97}, {181, 97}, {192, 96}, {56, 336}};
    for (int k = 0; k < 6; k++) {
        char json[512];
        const int W = sizes[k][0], H = sizes[k][1];
        snprintf(json, sizeof json, "{\"size\": [%d, %d], \"layers\": [{\"type\": \"julia\", \"max-iter\": 300%s}]}", W,
                 H, variants[k]);
        /* every channel the same bits (sincos.h and kernels/exact.h on both sides) */
        static const char *chans[] = {"sky.iter", "sky.n", "sky.de", "sky.R"};
        for (int c = 0; c < 4; c++) {
            void *a = bake_read_channel(gpu, json, 13, "jg", chans[c]),
                 *b = bake_read_channel(cpu, json, 0, "jc", chans[c]);
            CHECK(a && b);
            int diff = 0;
            for (int i = 0; a && b && i < W * H; i++) diff += memcmp((char *)a + 4 * i, (char *)b + 4 * i, 4) != 0;
            CHECKF(diff == 0, "julia %d: %d of %d %s values differ", k, diff, W * H, chans[c]);
            free(a), free(b);
        }
    }
}

/* A julia layer storing a subset of its channels: exactly those channels in the file, each equal to
 * the full layer's to the bit on the same backend (the orbits skip only what nothing stored needs).
 * Odd width: the shader's last pair has one pixel. Baking another configuration in between on the
 * same engine (reused pipelines) changes nothing. */
static void test_julia_channels(fb_engine *gpu, fb_engine *cpu)
{
    static const char *subsets[] = {"[\"iter\"]", "[\"de\"]", "[\"R\", \"G\", \"B\"]", "[\"n\", \"inside\"]",
                                    "[\"B\", \"iter\", \"G\", \"R\"]"};
    static const char *all[] = {"sky.iter", "sky.n", "sky.inside", "sky.de", "sky.R", "sky.G", "sky.B"};
    static const int counts[] = {1, 1, 3, 2, 4};
    const char *fmt = "{\"size\": [95, 40], \"layers\": [{\"type\": \"julia\", \"alpha\": [0.5, 0.25]%s%s}]}";
    const int N = 95 * 40;
    for (int b = 0; b < 2; b++) {
        fb_engine *e = b ? cpu : gpu;
        char json[512];
        snprintf(json, sizeof json, fmt, ", \"samples\": 2", "");
        for (int k = 0; k < 5; k++) {
            /* anti-aliasing samples shape R, G and B only (a layer without them refuses the key), so
             * the other channels must come out the same without it */
            char sub[512], extra[128];
            snprintf(extra, sizeof extra, "%s, \"channels\": %s", strstr(subsets[k], "\"R\"") ? ", \"samples\": 2" : "",
                     subsets[k]);
            snprintf(sub, sizeof sub, fmt, extra, "");
            int found = 0, bad = 0;
            for (int c = 0; c < 7; c++) {
                const char *name = all[c] + 4;
                char quoted[16];
                snprintf(quoted, sizeof quoted, "\"%s\"", name);
                bool listed = strstr(subsets[k], quoted) != NULL;
                void *full = bake_read_channel(e, json, 11, "chf", all[c]);
                void *part = bake_read_channel(e, sub, 11, "chp", all[c]);
                found += part != NULL;
                if (listed)
                    bad += !full || !part || memcmp(full, part, (size_t)N * 4);
                else
                    bad += part != NULL;
                free(full), free(part);
            }
            CHECKF(found == counts[k] && bad == 0, "%s channels %s: %d channels stored, %d wrong",
                   b ? "native" : "vulkan", subsets[k], found, bad);
        }
    }
    /* the same configuration before and after another one on the same engine */
    const char *a = "{\"size\": [64, 32], \"layers\": [{\"type\": \"julia\", \"channels\": [\"iter\"]}]}";
    const char *other = "{\"size\": [64, 32], \"layers\": [{\"type\": \"julia\", \"mapping\": \"polar\"}]}";
    uint32_t *a1 = bake_read_channel(gpu, a, 0, "re1", "sky.iter"),
             *o = bake_read_channel(gpu, other, 0, "re2", "sky.iter"),
             *a2 = bake_read_channel(gpu, a, 0, "re3", "sky.iter");
    CHECK(a1 && o && a2 && !memcmp(a1, a2, 64 * 32 * 4) && memcmp(a1, o, 64 * 32 * 4));
    free(a1), free(o), free(a2);
}

/* Double precision: the device's escape counts and smooth counts equal C's to the bit in both
 * mappings (sin and cos are the kernel's own in double, division kx_ddiv's), turbulence included. */
static void test_julia_double(fb_engine *gpu, fb_engine *cpu)
{
    static const char *variants[] = {"", ", \"mapping\": \"polar\", \"alpha\": [-0.3, 0], \"turbulence\": 0.2"};
    for (int k = 0; k < 2; k++) {
        char json[512];
        snprintf(json, sizeof json,
                 "{\"size\": [181, 97], \"layers\": [{\"type\": \"julia\", \"max-iter\": 300, \"precision\": "
                 "\"double\", \"samples\": 2%s}]}",
                 variants[k]);
        uint32_t *ia = bake_read_channel(gpu, json, 13, "dg", "sky.iter"),
                 *ib = bake_read_channel(cpu, json, 0, "dc", "sky.iter");
        float *na = bake_read_channel(gpu, json, 13, "dg2", "sky.n"),
              *nb = bake_read_channel(cpu, json, 0, "dc2", "sky.n");
        CHECK(ia && ib && na && nb);
        if (ia && ib && na && nb) {
            int N = 181 * 97, n_bad = 0;
            for (int i = 0; i < N; i++) n_bad += memcmp(&na[i], &nb[i], 4) != 0;
            CHECKF(!memcmp(ia, ib, (size_t)N * 4), "julia double %d: escape counts differ", k);
            CHECKF(n_bad == 0, "julia double %d: %d smooth counts differ", k, n_bad);
        }
        free(ia), free(ib), free(na), free(nb);
    }
}

int main(void)
{
    fb_engine gpu, cpu;
    fb_env env0; /* the pipeline cache's folder, as the command line has it */
    fb_env_read(&env0);
    fb_result rc = fb_engine_open(
        &(fb_engine_desc){.backend = FB_BACKEND_VULKAN, .validation = true, .vk_options = env0.vk}, &gpu);
    if (rc == FB_ERR_NODEVICE) TEST_SKIP("no Vulkan device");
    CHECK(rc == FB_OK);
    if (rc) TEST_REPORT();
    CHECK(vkc_validation_enabled(gpu.vk)); /* the layer is installed in CI: a silent test must mean clean */
    CHECK(fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = 3}, &cpu) == FB_OK);
    if (!mkdtemp(g_dir)) TEST_SKIP("no temporary folder");

    static const char *noises[] = {"gradient", "value", "simplex", "cellular", "cellular-f2", "sine"};
    static const char *styles[] = {"",
                                   ", \"ridged\": true",
                                   ", \"billow\": true, \"warp\": 0.8",
                                   ", \"tileable\": true, \"warp\": 0.5",
                                   ", \"mapping\": \"latlong\"",
                                   ", \"mapping\": \"cube\", \"warp\": 0.5"};
    static const int sizes[][2] = {{193, 77}, {193, 77}, {193, 77}, {193, 77}, {192, 96}, {32, 192}};
    for (int n = 0; n < 6; n++)
        for (int st = 0; st < 6; st++) {
            const int W = sizes[st][0], H = sizes[st][1];
            if (st == 3 && n == 2) continue; /* simplex is not tileable */
            char json[512];
            snprintf(json, sizeof json,
                     "{\"size\": [%d, %d], \"seed\": %d, \"layers\": [{\"type\": \"fbm\", \"noise\": \"%s\", "
                     "\"octaves\": 9, \"hurst\": 0.6%s}]}",
                     W, H, 3 + n, noises[n], styles[st]);
            float *a = bake_read(&gpu, json, 16, "gpu");
            float *b = bake_read(&cpu, json, 0, "cpu");
            CHECKF(a && b, "%s", json);
            if (!a || !b) {
                free(a);
                free(b);
                continue;
            }
            double worst = 0;
            int exact = 0;
            for (int i = 0; i < W * H; i++) {
                double d = fabs((double)a[i] - b[i]);
                worst = d > worst ? d : worst;
                exact += a[i] == b[i];
            }
            /* Every pixel the same bits: no contraction (the SPIR-V pass), sine noise through sincos.h,
             * division and square root through kernels/exact.h. */
            CHECKF(exact == W * H, "%s %s: %d of %d pixels bit-exact (max abs %g)", noises[n],
                   styles[st][0] ? styles[st] : "plain", exact, W * H, worst);
            free(a);
            free(b);
        }

    test_julia(&gpu, &cpu);
    test_julia_channels(&gpu, &cpu);
    if (vkc_info(gpu.vk)->float64)
        test_julia_double(&gpu, &cpu);
    else
        fprintf(stderr,
                "note: no shaderFloat64 on this device; double precision compared on the native backend only\n");

    /* Anti-aliasing: jittered samples average the colour, which lowers the image's total variation
     * (aliased speckle) substantially; with one sample it is the centre-only colour exactly. The
     * jitter is keyed by absolute pixel, so strip heights do not change a bit. */
    {
        const char *one = "{\"size\": [240, 160], \"layers\": [{\"type\": \"julia\", \"alpha\": [0.5, 0.25]}]}";
        const char *many = "{\"size\": [240, 160], \"layers\": [{\"type\": \"julia\", \"alpha\": [0.5, 0.25], "
                           "\"samples\": 8}]}";
        const char *explicit1 = "{\"size\": [240, 160], \"layers\": [{\"type\": \"julia\", \"alpha\": [0.5, 0.25], "
                                "\"samples\": 1}]}";
        float *a = bake_read_channel(&cpu, one, 0, "aa1", "sky.G"),
              *b = bake_read_channel(&cpu, many, 0, "aa8", "sky.G");
        float *c = bake_read_channel(&cpu, explicit1, 0, "aa1e", "sky.G");
        float *d = bake_read_channel(&gpu, many, 7, "aa8g", "sky.G"),
              *e = bake_read_channel(&gpu, many, 160, "aa8h", "sky.G");
        CHECK(a && b && c && d && e);
        if (a && b && c && d && e) {
            double tv1 = 0, tv8 = 0;
            for (int y = 0; y < 160; y++)
                for (int x = 1; x < 240; x++) {
                    tv1 += fabsf(a[y * 240 + x] - a[y * 240 + x - 1]);
                    tv8 += fabsf(b[y * 240 + x] - b[y * 240 + x - 1]);
                }
            CHECKF(tv8 < 0.75 * tv1, "total variation %g with 8 samples vs %g with 1", tv8, tv1);
            CHECK(!memcmp(a, c, 240 * 160 * 4));
            CHECK(!memcmp(d, e, 240 * 160 * 4));
        }
        free(a), free(b), free(c), free(d), free(e);
    }

    /* Strip height does not change a bit, on either backend. */
    const char *json = "{\"size\": [301, 150], \"seed\": 11, \"layers\": [{\"type\": \"fbm\", \"octaves\": 12, "
                       "\"warp\": 1.0, \"noise\": \"simplex\"}]}";
    float *s1 = bake_read(&gpu, json, 1, "s1"), *s2 = bake_read(&gpu, json, 150, "s2"),
          *s3 = bake_read(&gpu, json, 37, "s3");
    CHECK(s1 && s2 && s3 && !memcmp(s1, s2, 301 * 150 * 4) && !memcmp(s1, s3, 301 * 150 * 4));
    free(s1);
    free(s2);
    free(s3);

    /* The staging path (device-local memory copied to a host-cached buffer, as on discrete GPUs)
     * gives the same bits as direct mapping, with the validation layer watching. */
    fb_env env = env0;
    env.vk.staging = true;
    fb_engine staged;
    CHECK(fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_VULKAN, .validation = true, .vk_options = env.vk},
                         &staged) == FB_OK);
    float *d1 = bake_read(&gpu, json, 40, "direct"), *d2 = bake_read(&staged, json, 40, "staged");
    CHECK(d1 && d2 && !memcmp(d1, d2, 301 * 150 * 4));
    CHECKF(vkc_validation_messages(staged.vk) == 0, "%u validation messages (staging)",
           vkc_validation_messages(staged.vk));
    free(d1);
    free(d2);
    fb_engine_close(&staged);

    /* Timestamps work: a dispatch takes a positive, finite time. */
    fb_scene sc;
    CHECK(fb_scene_parse(json, NULL, &sc) == FB_OK);
    fb_bake_stats stats;
    CHECK(fb_bake(&gpu, &(fb_bake_desc){.scene = &sc}, &stats) == FB_OK);
    CHECKF(stats.gpu_seconds > 0 && stats.gpu_seconds < 60, "gpu seconds %g", stats.gpu_seconds);
    fb_scene_fini(&sc);

    CHECKF(vkc_validation_messages(gpu.vk) == 0, "%u validation messages", vkc_validation_messages(gpu.vk));
    fb_engine_close(&gpu);
    fb_engine_close(&cpu);
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf %s", g_dir);
    if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", g_dir);
    TEST_REPORT();
}
