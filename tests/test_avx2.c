/* The hand-vectorised loops (the native fast paths and the benchmarks' references) compute exactly
 * what the shared kernels compute: every pixel of several fBm and Julia images, and every cell of
 * chaos-game histograms, is bit-identical to the scalar kernel's (the layer with `scalar` set). */
#include "../kernels/fbm.h"
#include "../kernels/ifs.h"
#include "fbm_avx2.h"
#include "ifs_avx2.h"
#include "julia_avx2.h"
#include "bake.h"
#include "gen_ifs.h"
#include "gen.h"

#include "testhelp.h"

#include <string.h>

int main(void)
{
    const char *scenes[] = {
        "{\"size\": [203, 61], \"seed\": 1, \"layers\": [{\"type\": \"fbm\"}]}",
        "{\"size\": [128, 128], \"seed\": 77, \"layers\": [{\"type\": \"fbm\", \"octaves\": 24, \"hurst\": 0.3, "
        "\"lacunarity\": 2.3, \"rotation\": -20, \"frequency\": 11, \"offset\": [-5000, 3.5]}]}",
        "{\"size\": [64, 300], \"seed\": 4000000000, \"layers\": [{\"type\": \"fbm\", \"octaves\": 32, \"lacunarity\": "
        "3.1}]}",
    };
    for (int k = 0; k < 3; k++) {
        fb_scene s;
        CHECK(fb_scene_parse(scenes[k], NULL, &s) == FB_OK);
        fb_gen g;
        CHECK(fb_gen_init(&g, &s, &s.layers[0]) == FB_OK);
        if (!fb_fbm_avx2_supported(g.params)) TEST_SKIP("this CPU has no AVX2");
        size_t n = (size_t)s.width * s.height;
        float *a = malloc(n * 4), *b = malloc(n * 4);
        void *planes[1] = {a};
        g.scalar = true; /* the portable kernel, k_fbm_pixel per pixel: not the AVX2 loop again */
        g.native_rows(&g, 0, s.height, planes);
        fb_fbm_avx2_rows(g.params, 0, s.height, b);
        int diff = 0;
        for (size_t i = 0; i < n; i++) diff += memcmp(&a[i], &b[i], 4) != 0;
        CHECKF(diff == 0, "scene %d: %d of %zu pixels differ", k, diff, n);
        free(a);
        free(b);
        fb_scene_fini(&s);
    }
    /* Julia: the escape counts of the AVX2 loop are the kernel's, pole and warp included. */
    const char *julias[] = {
        "{\"size\": [203, 61], \"layers\": [{\"type\": \"julia\"}]}",
        "{\"size\": [160, 120], \"layers\": [{\"type\": \"julia\", \"alpha\": [0.5, 0.25], \"c\": [-0.4, 0.6], "
        "\"rotation\": 30, \"center\": [0.2, -0.1], \"max-iter\": 500, \"bailout\": 3}]}",
        "{\"size\": [64, 64], \"layers\": [{\"type\": \"julia\", \"alpha\": [0.5, 0], \"scale\": [6, 6]}]}",
    };
    for (int k = 0; k < 3; k++) {
        fb_scene s;
        CHECK(fb_scene_parse(julias[k], NULL, &s) == FB_OK);
        fb_gen g;
        CHECK(fb_gen_init(&g, &s, &s.layers[0]) == FB_OK);
        if (!fb_julia_avx2_supported(g.params)) TEST_SKIP("this CPU has no AVX2");
        size_t n = (size_t)s.width * s.height;
        uint32_t *a = malloc(n * 4), *b = malloc(n * 4);
        float *rest[6];
        for (int c = 0; c < 6; c++) rest[c] = malloc(n * 4);
        void *planes[7] = {a, rest[0], rest[1], rest[2], rest[3], rest[4], rest[5]};
        g.scalar = true;
        g.native_rows(&g, 0, s.height, planes);
        uint64_t total = 0, want = 0;
        fb_julia_avx2_rows(g.params, 0, s.height, b, &total);
        int diff = 0;
        for (size_t i = 0; i < n; i++) diff += a[i] != b[i], want += a[i];
        CHECKF(diff == 0, "julia %d: %d of %zu escape counts differ", k, diff, n);
        CHECK(total == want);
        free(a), free(b);
        for (int c = 0; c < 6; c++) free(rest[c]);
        fb_gen_fini(&g);
        fb_scene_fini(&s);
    }
    /* IFS: the AVX2 chaos game's histogram and counters are the portable kernel's (scalar engine),
     * with a chain count that leaves a scalar tail and points that leave an uneven last step. */
    const char *ifss[] = {
        "{\"size\": [200, 120], \"seed\": 3, \"layers\": [{\"type\": \"ifs\", \"points\": 2000003, \"chains\": 1000, "
        "\"bounds\": [-2, 2, 1, 9]}]}",
        "{\"size\": [90, 90], \"seed\": 8, \"layers\": [{\"type\": \"ifs\", \"preset\": \"spiral\", \"oversample\": 2, "
        "\"points\": 1000000}]}",
        /* condensation: the chain also walks C's IFS and w0 jumps onto it */
        "{\"size\": [160, 80], \"seed\": 5, \"layers\": [{\"type\": \"ifs\", \"preset\": \"population\", "
        "\"points\": 1500007, \"chains\": 1003, \"bounds\": [-0.05, 0.9, -0.03, 0.5]}]}",
        "{\"size\": [64, 64], \"seed\": 11, \"layers\": [{\"type\": \"ifs\", \"preset\": \"fern\", \"condensation\": "
        "\"sierpinski\", \"condensation-probability\": 0.3, \"points\": 700001, \"skip\": 7}]}",
    };
    for (int k = 0; k < 4; k++) {
        fb_scene s;
        CHECK(fb_scene_parse(ifss[k], NULL, &s) == FB_OK);
        fb_gen g;
        CHECK(fb_gen_init(&g, &s, &s.layers[0]) == FB_OK);
        if (!fb_ifs_avx2_supported(g.params)) TEST_SKIP("this CPU has no AVX2");
        fb_engine e;
        CHECK(fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = 1, .scalar = true}, &e) ==
              FB_OK);
        g.scalar = true;
        CHECK(g.prepare(&g, &e, false) == FB_OK);
        const fb_ifs_stats *st = fb_gen_ifs_stats(&g);
        const K_IfsParams *p = (const K_IfsParams *)(const void *)g.params;
        size_t cells = (size_t)p->hist_w * p->hist_h, n = (size_t)s.width * s.height;
        uint32_t *hits = calloc(cells, 4), *count = malloc(n * 4);
        uint64_t *sum = calloc(cells, 8), counts[3] = {0, 0, 0};
        fb_ifs_avx2_chains(g.params, g.input, 0, p->chains, 0, UINT32_MAX, NULL, hits, sum, counts);
        /* the same chains in step windows one after another (uneven, some past a chain's end): the
         * same sums, bit for bit, and the same counters */
        {
            uint32_t *h2 = calloc(cells, 4);
            uint64_t *s2 = calloc(cells, 8), n2[3] = {0, 0, 0};
            K_IfsChain *state = calloc(p->chains, sizeof *state);
            const uint32_t win[] = {0, 1, 8, 1000, 1777, 1000000, UINT32_MAX};
            for (int w = 0; w + 1 < 7; w++)
                fb_ifs_avx2_chains(g.params, g.input, 0, p->chains, win[w], win[w + 1], state, h2, s2, n2);
            CHECKF(!memcmp(h2, hits, cells * 4) && !memcmp(s2, sum, cells * 8),
                   "ifs %d: step windows give other sums than one window", k);
            CHECKF(!memcmp(n2, counts, sizeof n2), "ifs %d: step windows give other counters", k);
            free(h2), free(s2), free(state);
        }
        float *rest[6];
        for (int c = 0; c < 6; c++) rest[c] = malloc(n * 4);
        void *planes[7] = {count, rest[0], rest[1], rest[2], rest[3], rest[4], rest[5]};
        g.native_rows(&g, 0, s.height, planes);
        int diff = 0;
        uint32_t K = p->hist_w / (uint32_t)s.width;
        for (int y = 0; y < s.height; y++)
            for (int x = 0; x < s.width; x++) {
                uint64_t c = 0, sm = 0;
                for (uint32_t j = 0; j < K; j++)
                    for (uint32_t i = 0; i < K; i++) {
                        size_t cell = ((size_t)y * K + j) * p->hist_w + (size_t)x * K + i;
                        c += hits[cell], sm += sum[cell];
                    }
                size_t at = (size_t)y * s.width + x;
                float colour = c ? (float)((double)sm / (255.0 * (double)c)) : 0.0f;
                diff += count[at] != c || memcmp(&rest[1][at], &colour, 4) != 0;
            }
        CHECKF(diff == 0, "ifs %d: %d of %zu pixels differ", k, diff, n);
        CHECKF(counts[0] == st->outside && counts[1] == st->discarded && counts[2] == st->restarts,
               "ifs %d: counters %llu %llu %llu vs %llu %llu %llu", k, (unsigned long long)counts[0],
               (unsigned long long)counts[1], (unsigned long long)counts[2], (unsigned long long)st->outside,
               (unsigned long long)st->discarded, (unsigned long long)st->restarts);
        CHECKF(st->outside > 0 || k == 1 || k == 3, "ifs %d: no point fell outside the frame", k); /* counted */
        free(hits), free(sum), free(count);
        for (int c = 0; c < 6; c++) free(rest[c]);
        fb_engine_close(&e);
        fb_gen_fini(&g);
        fb_scene_fini(&s);
    }
    TEST_REPORT();
}
