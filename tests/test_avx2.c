/* The hand-vectorised loops (the native fast paths and the benchmarks' references) compute exactly
 * what the shared kernels compute: every pixel of several fBm and Julia images, and every cell of
 * chaos-game histograms, is bit-identical to the scalar kernel's (the layer with `scalar` set). */
#include "../kernels/fbm.h"
#include "../kernels/ifs.h"
#include "flame_avx2.h"
#include "fbm3_avx2.h"
#include "fbm_avx2.h"
#include "ifs_avx2.h"
#include "julia_avx2.h"
#include "layer_avx2.h"
#include "bake.h"
#include "gen_ifs.h"
#include "gen.h"

#include "testhelp.h"

#include <string.h>

#if defined(__x86_64__) || defined(__i386__)
/* A float from a test's stream: mostly moderate values, and the edge cases (zeros of both signs,
 * tiny, huge, infinities, NaN, the reduction's limits). */
static float flame_value(uint32_t i)
{
    static const float edge[] = {0.0f,       -0.0f,     1e-30f, -1e-38f, 1e-45f,     1.0f,       -1.0f, 0.5f,
                                 2.4142137f, 0.414213f, 88.7f,  -87.4f,  89.0f,      -90.0f,     1e10f, -1e10f,
                                 3e38f,      -3e38f,    1e5f,   -2e6f,   1.5707964f, 3.1415927f, 0.8f,  -0.8f};
    uint32_t h = k_hash(i * 0x9e3779b9u + 17u);
    if (h % 11u == 0u) {
        uint32_t k = (h >> 8) % (sizeof edge / sizeof edge[0] + 3u);
        if (k == sizeof edge / sizeof edge[0]) return K_INF;
        if (k == sizeof edge / sizeof edge[0] + 1u) return -K_INF;
        if (k == sizeof edge / sizeof edge[0] + 2u) return K_NAN;
        return edge[k];
    }
    float u = k_u01(k_hash(h)) * 2.0f - 1.0f;
    switch (h % 5u) {
    case 0:
        return u;
    case 1:
        return u * 4.0f;
    case 2:
        return u * 100.0f;
    case 3:
        return u * 1e4f;
    default:
        return u * 0.01f;
    }
}

/* the same bits, or both NaN */
static bool flame_same(float a, float b)
{
    return (a != a && b != b) || !memcmp(&a, &b, 4);
}

/* The flame's lanes (host/gen/flame/flame_avx2.h): sin, cos, tan, exp, log, pow, sinh, cosh and atan2 are
 * kernels/kmath.h's to the bit on random and edge arguments, and fl_apply8 is k_flame_apply for xforms
 * of every variation it has, alone and in random mixes, with and without a post transform, on the
 * same inputs: the point, colour, counter and bad values. */
FL_AVX2 static void flame_lanes_check(void)
{
    int diff = 0;
    for (uint32_t i = 0; i < 400000u; i += 8) {
        float a[8], b[8], r[9][8];
        for (int l = 0; l < 8; l++) a[l] = flame_value(i + (uint32_t)l), b[l] = flame_value(i + 7777777u + (uint32_t)l);
        __m256 va = _mm256_loadu_ps(a), vb = _mm256_loadu_ps(b), s, c, hs, hc;
        fl_sincos(va, &s, &c);
        fl_sinhcosh(va, &hs, &hc);
        _mm256_storeu_ps(r[0], s), _mm256_storeu_ps(r[1], c), _mm256_storeu_ps(r[2], fl_exp(va));
        _mm256_storeu_ps(r[3], hs), _mm256_storeu_ps(r[4], hc), _mm256_storeu_ps(r[5], fl_atan2(va, vb));
        _mm256_storeu_ps(r[6], fl_log(va)), _mm256_storeu_ps(r[7], fl_pow(fl_abs(va), vb));
        _mm256_storeu_ps(r[8], fl_tan(va));
        for (int l = 0; l < 8; l++) {
            k_vec2 sc = k_sincos(a[l]), sh = k_xsinhcosh(a[l]);
            float want[9] = {sc.x,         sc.y,
                             k_xexp(a[l]), sh.x,
                             sh.y,         k_xatan2(a[l], b[l]),
                             k_xlog(a[l]), k_xpow(fabsf(a[l]), b[l]),
                             k_xtan(a[l])};
            for (int f = 0; f < 9; f++)
                if (!flame_same(r[f][l], want[f]) && diff++ < 10)
                    fprintf(stderr, "function %d of %a (%a): %a, not %a\n", f, a[l], b[l], r[f][l], want[f]);
        }
    }
    CHECKF(diff == 0, "%d results of the flame's lane functions differ from kmath.h's", diff);
    /* xforms */
    uint32_t ids[K_V_COUNT], nid = 0;
    for (uint32_t v = 0; v < K_V_COUNT; v++)
        if (fl_var_avx2(v)) ids[nid++] = v;
    CHECKF(nid >= 40, "only %u variations on the lanes", nid);
    K_FlameVar var[8];
    K_FlameXform X;
    uint dist[1] = {0};
    int xdiff = 0, nbad = 0;
    uint32_t seed = 1;
    for (uint32_t trial = 0; trial < 6000u; trial++) {
#define R01() k_u01(k_hash(seed++ * 0x9e3779b9u))
#define RS()  (R01() * 2.0f - 1.0f)
        memset(&X, 0, sizeof X);
        X.ax = RS() * 1.5f, X.bx = RS(), X.cx = RS(), X.ay = RS(), X.by = RS() * 1.5f, X.cy = RS();
        X.pax = RS(), X.pbx = RS(), X.pcx = RS(), X.pay = RS(), X.pby = RS(), X.pcy = RS();
        X.color = R01(), X.speed = R01();
        X.nvar = trial < 4u * nid ? 1u : 1u + (uint32_t)(R01() * 4.0f);
        /* the precalcs all xforms' variations might read (those not read change nothing) */
        X.flags = K_FLAME_SQRT | K_FLAME_ANGLES | K_FLAME_ATAN_XY | K_FLAME_ATAN_YX;
        if (R01() < 0.3f) X.flags |= K_FLAME_HAS_POST;
        uint32_t last = 0;
        for (uint32_t k = 0; k < X.nvar; k++) {
            K_FlameVar *V = &var[k];
            memset(V, 0, sizeof *V);
            V->id = trial < 4u * nid ? ids[trial % nid] : ids[(uint32_t)(R01() * (float)nid) % nid];
            if (V->id < last) V->id = last; /* ascending, as the genome's */
            last = V->id;
            V->w = RS() * 1.2f, V->p0 = RS() * 3.0f, V->p1 = RS() * 2.0f, V->p2 = RS() * 6.0f, V->p3 = RS() * 4.0f;
        }
        float x[8], y[8], c[8];
        uint32_t n[8], key[8];
        for (int l = 0; l < 8; l++) {
            uint32_t j = trial * 8u + (uint32_t)l;
            x[l] = trial % 4u == 3u ? flame_value(j) : RS() * 2.0f;
            y[l] = trial % 4u == 3u ? flame_value(j + 555555u) : RS() * 2.0f;
            c[l] = R01(), n[l] = k_hash(j) >> 4, key[l] = k_hash(j ^ 0xabcdefu);
        }
        fl_lanes p = {_mm256_loadu_ps(x), _mm256_loadu_ps(y), _mm256_loadu_ps(c),
                      _mm256_loadu_si256((const __m256i *)n)};
        unsigned bad = (unsigned)_mm256_movemask_ps(fl_apply8(&X, var, _mm256_loadu_si256((const __m256i *)key), &p));
        float ox[8], oy[8], oc[8];
        uint32_t on[8];
        _mm256_storeu_ps(ox, p.x), _mm256_storeu_ps(oy, p.y), _mm256_storeu_ps(oc, p.c);
        _mm256_storeu_si256((__m256i *)on, p.n);
        const K_FlameXform *k_flame_xf = &X;
        const K_FlameVar *k_flame_var = var;
        const uint *k_flame_dist = dist;
        for (int l = 0; l < 8; l++) {
            K_FlameOut o = k_flame_apply(0u, x[l], y[l], c[l], key[l], n[l] K_FLAME_TABLES);
            bool lb = bad >> l & 1u;
            nbad += o.bad;
            bool same =
                lb == o.bad &&
                (o.bad || (flame_same(ox[l], o.x) && flame_same(oy[l], o.y) && flame_same(oc[l], o.c) && on[l] == o.n));
            if (!same && xdiff++ < 10)
                fprintf(stderr,
                        "xform of %u variations (first %u): lane %d: %a %a %a %u bad %d, not %a %a %a %u bad %d\n",
                        X.nvar, var[0].id, l, ox[l], oy[l], oc[l], on[l], lb, o.x, o.y, o.c, o.n, o.bad);
        }
#undef R01
#undef RS
    }
    CHECKF(xdiff == 0, "%d lanes of the flame's xforms differ from k_flame_apply", xdiff);
    CHECKF(nbad > 0, "no bad value among the xforms' results");
}
#endif

int main(void)
{
#if defined(__x86_64__) || defined(__i386__)
    if (__builtin_cpu_supports("avx2")) flame_lanes_check();
#endif
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
        g.run.scalar = true; /* the portable kernel, k_fbm_pixel per pixel: not the AVX2 loop again */
        g.compute.native_rows(&g, 0, s.height, planes);
        fb_fbm_avx2_rows(g.params, 0, s.height, b);
        int diff = 0;
        for (size_t i = 0; i < n; i++) diff += memcmp(&a[i], &b[i], 4) != 0;
        CHECKF(diff == 0, "scene %d: %d of %zu pixels differ", k, diff, n);
        free(a);
        free(b);
        fb_scene_fini(&s);
    }
    /* fBm on the sphere: the lat-long and cube rows on AVX2 lanes are the scalar kernel's to the bit
     * (memcmp) for every noise kind the lanes implement, plain, ridged and billow, with and without
     * the warp, whole and in strips of 1, 2, 3, ... rows; widths that are not multiples of 8 leave a
     * partial last block. */
    static const char *const kinds[] = {"gradient", "value", "simplex", "sine", "cellular", "cellular-f2"};
    static const char *const shapes[] = {"", ", \"ridged\": true", ", \"billow\": true"};
    int env_scenes = 0;
    for (int kind = 0; kind < 6; kind++)
        for (int cube = 0; cube < 2; cube++)
            for (int warp = 0; warp < 2; warp++)
                for (int shape = 0; shape < 3; shape++) {
                    int v = ((kind * 2 + cube) * 2 + warp) * 3 + shape;
                    char json[512];
                    snprintf(json, sizeof json,
                             "{\"size\": [%s], \"seed\": %d, \"layers\": [{\"type\": \"fbm\", \"mapping\": "
                             "\"%s\", \"noise\": \"%s\", \"octaves\": %d, \"hurst\": %.2f, \"lacunarity\": %.2f, "
                             "\"rotation\": %d, \"frequency\": %.1f, \"offset\": [%d, %.2f], \"warp\": %.2f%s}]}",
                             cube ? "13, 78" : "58, 29", 1000 + 7 * v, cube ? "cube" : "latlong", kinds[kind],
                             3 + v % 5, 0.3 + 0.1 * (v % 7), 1.7 + 0.3 * (v % 4), -170 + (37 * v) % 340,
                             2.0 + 1.3 * (v % 9), -100 + 13 * v, 0.25 * (v % 5), warp ? 0.2 + 0.3 * (v % 3) : 0.0,
                             shapes[shape]);
                    fb_scene s;
                    CHECKF(fb_scene_parse(json, NULL, &s) == FB_OK, "%s", json);
                    fb_gen g;
                    CHECK(fb_gen_init(&g, &s, &s.layers[0]) == FB_OK);
                    const K_FbmParams *p = (const K_FbmParams *)(const void *)g.params;
                    if (!__builtin_cpu_supports("avx2")) TEST_SKIP("this CPU has no AVX2");
                    CHECKF(fb_fbm3_avx2_supported(p), "%s: the lanes are not used", kinds[kind]);
                    size_t n = (size_t)s.width * s.height;
                    float *a = malloc(n * 4), *b = malloc(n * 4), *c = malloc(n * 4);
                    g.run.scalar = true;
                    g.compute.native_rows(&g, 0, s.height, (void *[]){a});
                    g.run.scalar = false;
                    g.compute.native_rows(&g, 0, s.height, (void *[]){b});
                    for (int y0 = 0, h = 1; y0 < s.height; y0 += h, h++) {
                        int rows = y0 + h <= s.height ? h : s.height - y0;
                        g.compute.native_rows(&g, y0, rows, (void *[]){c + (size_t)y0 * s.width});
                    }
                    int diff = 0, split = 0, moved = 0;
                    for (size_t i = 0; i < n; i++) {
                        diff += memcmp(&a[i], &b[i], 4) != 0;
                        split += memcmp(&b[i], &c[i], 4) != 0;
                        moved += i > 0 && a[i] != a[i - 1];
                    }
                    CHECKF(diff == 0, "fbm %s %s warp %d shape %d: %d of %zu pixels differ from the scalar kernel",
                           kinds[kind], cube ? "cube" : "latlong", warp, shape, diff, n);
                    CHECKF(split == 0, "fbm %s %s warp %d shape %d: %d pixels differ between strip splits", kinds[kind],
                           cube ? "cube" : "latlong", warp, shape, split);
                    /* a field, not a constant (the comparison would then say little) */
                    CHECKF(moved > (int)n / 2, "fbm %s %s: only %d of %zu neighbours differ", kinds[kind],
                           cube ? "cube" : "latlong", moved, n);
                    env_scenes++;
                    free(a), free(b), free(c);
                    fb_gen_fini(&g);
                    fb_scene_fini(&s);
                }
    CHECK(env_scenes == 72);
    /* The lanes function alone (what the Julia turbulence calls): directions of any length and far
     * from the unit sphere, every stream, against k_fbm3 lane by lane; with offset 1e5 and lacunarity
     * 2.9 the lattice coordinates pass 2^24 from the seventh octave on (the wrap's float path). */
    for (int kind = 0; kind < 6; kind++) {
        static const uint32_t kk[] = {K_NOISE_GRADIENT, K_NOISE_VALUE,    K_NOISE_SIMPLEX,
                                      K_NOISE_SINE,     K_NOISE_CELLULAR, K_NOISE_CELLULAR_F2};
        K_FbmParams p = {.seed = 99u + (uint32_t)kind,
                         .noise = kk[kind],
                         .octaves = 32,
                         .gain = 0.6f,
                         .lacunarity = 2.9f,
                         .rot_c = 0.8f,
                         .rot_s = 0.6f,
                         .freq_x = 7.0f,
                         .offset_x = -3.5f,
                         .offset_y = 1e5f,
                         .flags = kind == 1 ? K_FBM_RIDGED : 0u};
        int diff = 0, moved = 0;
        float last = 0.0f;
        for (int t = 0; t < 64; t++) {
            float d[3][8], out[8];
            for (int k = 0; k < 8; k++)
                for (int j = 0; j < 3; j++)
                    d[j][k] = (float)((k_hash((uint32_t)(t * 24 + k * 3 + j)) >> 8) * (1.0 / 16777216.0) - 0.5) *
                              (t < 32 ? 2.0f : 3000.0f);
            for (uint32_t stream = 0; stream < 4; stream++) {
                fb_fbm3_avx2_lanes(&p, stream, d, out);
                for (int k = 0; k < 8; k++) {
                    float want = k_fbm3(p, stream, k_vec3(d[0][k], d[1][k], d[2][k]));
                    diff += memcmp(&want, &out[k], 4) != 0;
                    moved += want != last;
                    last = want;
                }
            }
        }
        CHECKF(diff == 0, "fb_fbm3_avx2_lanes, noise %u: %d of %d lanes differ from k_fbm3", kk[kind], diff,
               64 * 8 * 4);
        CHECKF(moved > 64 * 8 * 4 / 2, "noise %u: only %d values differ from the one before", kk[kind], moved);
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
        g.run.scalar = true;
        g.compute.native_rows(&g, 0, s.height, planes);
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
    /* The Julia layer's whole native path on AVX2 lanes: every stored channel of every pixel is the
     * scalar kernel's to the bit (memcmp, so NaN and -0 count), on rect, polar, lat-long and cube grids, with the
     * pole, turbulence (tileable with power-of-two and other periods), jittered samples, gamma,
     * density, every palette kind and channel subsets (what is not stored is not computed). Widths
     * that are not multiples of 8 leave a partial last block. */
    const char *layers[] = {
        "{\"size\": [203, 61], \"seed\": 9, \"layers\": [{\"type\": \"julia\"}]}",
        "{\"size\": [160, 120], \"layers\": [{\"type\": \"julia\", \"alpha\": [0.5, 0.25], \"c\": [-0.4, 0.6], "
        "\"rotation\": 30, \"center\": [0.2, -0.1], \"max-iter\": 500, \"bailout\": 3, \"palette\": \"ember\"}]}",
        /* the pole 1/a = 2 lies in the grid (pixel centre x = 2 exactly: 6 * (u - 0.5) at u = 5/6) */
        "{\"size\": [96, 64], \"layers\": [{\"type\": \"julia\", \"alpha\": [0.5, 0], \"scale\": [6, 4], "
        "\"max-iter\": 12}]}",
        "{\"size\": [131, 77], \"seed\": 5, \"layers\": [{\"type\": \"julia\", \"mapping\": \"polar\", \"radius\": "
        "1.7, "
        "\"alpha\": [0.3, -0.2], \"turbulence\": 0.4, \"samples\": 3, \"palette\": \"aurora\", \"gamma\": 0.8}]}",
        "{\"size\": [100, 50], \"seed\": 6, \"layers\": [{\"type\": \"julia\", \"mapping\": \"polar\", "
        "\"turbulence\": 0.7, \"turbulence-frequency\": 3, \"turbulence-octaves\": 5, \"density\": 0, "
        "\"inside-color\": [0.1, 0.2, 0.3], \"c\": [-0.7, 0.27]}]}",
        "{\"size\": [117, 90], \"seed\": 7, \"layers\": [{\"type\": \"julia\", \"turbulence\": 0.3, "
        "\"turbulence-frequency\": 5.5, \"turbulence-hurst\": 0.5, \"samples\": 4, \"max-iter\": 300, "
        "\"cosine\": [0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 1, 1, 1, 0, 0.33, 0.67], \"period\": 7, \"palette-offset\": 0.3, "
        "\"brightness\": 2.5, \"density\": 2.5, \"density-count\": 20}]}",
        "{\"size\": [77, 45], \"seed\": 8, \"layers\": [{\"type\": \"julia\", \"stops\": [[0, 0, 0, 0.1], [0.4, 1, "
        "0.5, "
        "0], [1, 1, 1, 1]], \"samples\": 2, \"gamma\": 2.2, \"bailout\": 1000, \"c\": [0.285, 0.01]}]}",
        "{\"size\": [90, 70], \"layers\": [{\"type\": \"julia\", \"channels\": [\"iter\", \"de\"], \"alpha\": [0.2, "
        "0.1], "
        "\"max-iter\": 9}]}",
        "{\"size\": [90, 70], \"layers\": [{\"type\": \"julia\", \"channels\": [\"n\", \"inside\"], \"mapping\": "
        "\"polar\"}]}",
        "{\"size\": [90, 70], \"seed\": 3, \"layers\": [{\"type\": \"julia\", \"channels\": [\"R\", \"G\", \"B\"], "
        "\"samples\": 5, \"palette\": \"nebula\"}]}",
        /* environment maps: the nadir (-1/a) and the pole of the warp on the sphere, turbulence, samples */
        "{\"size\": [130, 65], \"seed\": 4, \"layers\": [{\"type\": \"julia\", \"mapping\": \"latlong\", "
        "\"alpha\": [-0.3, 0.1], \"turbulence\": 0.2, \"samples\": 3, \"rotation\": 15}]}",
        "{\"size\": [21, 126], \"seed\": 2, \"layers\": [{\"type\": \"julia\", \"mapping\": \"cube\", "
        "\"alpha\": [0.5, 0], \"radius\": 1.1, \"max-iter\": 40}]}",
        /* the turbulence's 3D fBm on the lanes (fbm3_avx2.c): lat-long and cube, other octaves, Hurst
         * exponents and frequencies, jittered samples */
        "{\"size\": [98, 49], \"seed\": 12, \"layers\": [{\"type\": \"julia\", \"mapping\": \"latlong\", "
        "\"alpha\": [-0.3, 0], \"c\": [-0.76, 0.2], \"radius\": 1.2, \"turbulence\": 0.6, \"turbulence-octaves\": "
        "9, \"turbulence-hurst\": 0.3, \"turbulence-frequency\": 7.5, \"samples\": 2}]}",
        "{\"size\": [19, 114], \"seed\": 13, \"layers\": [{\"type\": \"julia\", \"mapping\": \"cube\", "
        "\"alpha\": [0.2, 0.3], \"turbulence\": 1.5, \"turbulence-octaves\": 3, \"turbulence-frequency\": 2, "
        "\"samples\": 3, \"max-iter\": 60}]}",
    };
    const int nlayers = (int)(sizeof layers / sizeof layers[0]);
    int seen_inside = 0, seen_pole = 0, seen_de = 0;
    for (int k = 0; k < nlayers; k++) {
        fb_scene s;
        CHECK(fb_scene_parse(layers[k], NULL, &s) == FB_OK);
        fb_gen g;
        CHECK(fb_gen_init(&g, &s, &s.layers[0]) == FB_OK);
        if (!fb_julia_avx2_layer_supported((const K_JuliaParams *)(const void *)g.params))
            TEST_SKIP("this CPU has no AVX2");
        size_t n = (size_t)s.width * s.height;
        uint32_t stored = g.compute.shader.spec[4];
        void *a[7] = {0}, *b[7] = {0}, *c[7] = {0};
        for (int p = 0; p < 7; p++)
            if (stored & (1u << p)) a[p] = malloc(n * 4), b[p] = malloc(n * 4), c[p] = malloc(n * 4);
        g.run.scalar = true;
        g.compute.native_rows(&g, 0, s.height, a);
        g.run.scalar = false;
        g.compute.native_rows(&g, 0, s.height, b);
        /* strips of 1, 2, 3, ... rows: the same bits whatever the split */
        for (int y0 = 0, h = 1; y0 < s.height; y0 += h, h++) {
            int rows = y0 + h <= s.height ? h : s.height - y0;
            void *sub[7];
            for (int p = 0; p < 7; p++) sub[p] = c[p] ? (char *)c[p] + (size_t)y0 * s.width * 4 : NULL;
            g.compute.native_rows(&g, y0, rows, sub);
        }
        static const char *const plane[7] = {"iter", "n", "inside", "de", "R", "G", "B"};
        for (int p = 0; p < 7; p++) {
            if (!a[p]) continue;
            int diff = 0, split = 0;
            for (size_t i = 0; i < n; i++) {
                diff += memcmp((char *)a[p] + 4 * i, (char *)b[p] + 4 * i, 4) != 0;
                split += memcmp((char *)b[p] + 4 * i, (char *)c[p] + 4 * i, 4) != 0;
            }
            CHECKF(diff == 0, "julia layer %d: %s differs from the scalar kernel at %d of %zu pixels", k, plane[p],
                   diff, n);
            CHECKF(split == 0, "julia layer %d: %s differs between strip splits at %d pixels", k, plane[p], split);
        }
        /* what the scenes exercise: inside points, pixels at the pole (iter 0, not inside), distances */
        for (size_t i = 0; i < n; i++) {
            if (a[2] && ((float *)a[2])[i] == 1.0f) seen_inside++;
            if (a[0] && a[2] && ((uint32_t *)a[0])[i] == 0 && ((float *)a[2])[i] == 0.0f) seen_pole++;
            if (a[3] && ((float *)a[3])[i] > 0.0f) seen_de++;
        }
        for (int p = 0; p < 7; p++) free(a[p]), free(b[p]), free(c[p]);
        fb_gen_fini(&g);
        fb_scene_fini(&s);
    }
    CHECKF(seen_inside > 100 && seen_pole >= 1 && seen_de > 1000, "the scenes saw %d inside, %d pole, %d de pixels",
           seen_inside, seen_pole, seen_de);
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
        g.run.scalar = true;
        CHECK(g.prepare(&g, &e, false) == FB_OK);
        const fb_ifs_stats *st = fb_gen_ifs_stats(&g);
        const K_IfsParams *p = (const K_IfsParams *)(const void *)g.params;
        size_t cells = (size_t)p->hist_w * p->hist_h, n = (size_t)s.width * s.height;
        uint32_t *hits = calloc(cells, 4), *count = malloc(n * 4);
        uint64_t *sum = calloc(cells, 8), counts[3] = {0, 0, 0};
        fb_ifs_avx2_chains(g.params, g.compute.shader.input, 0, p->chains, 0, UINT32_MAX, NULL, hits, sum, counts);
        /* the same chains in step windows one after another (uneven, some past a chain's end): the
         * same sums, bit for bit, and the same counters */
        {
            uint32_t *h2 = calloc(cells, 4);
            uint64_t *s2 = calloc(cells, 8), n2[3] = {0, 0, 0};
            K_IfsChain *state = calloc(p->chains, sizeof *state);
            const uint32_t win[] = {0, 1, 8, 1000, 1777, 1000000, UINT32_MAX};
            for (int w = 0; w + 1 < 7; w++)
                fb_ifs_avx2_chains(g.params, g.compute.shader.input, 0, p->chains, win[w], win[w + 1], state, h2, s2,
                                   n2);
            CHECKF(!memcmp(h2, hits, cells * 4) && !memcmp(s2, sum, cells * 8),
                   "ifs %d: step windows give other sums than one window", k);
            CHECKF(!memcmp(n2, counts, sizeof n2), "ifs %d: step windows give other counters", k);
            free(h2), free(s2), free(state);
        }
        float *rest[6];
        for (int c = 0; c < 6; c++) rest[c] = malloc(n * 4);
        void *planes[7] = {count, rest[0], rest[1], rest[2], rest[3], rest[4], rest[5]};
        g.compute.native_rows(&g, 0, s.height, planes);
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
