/*
 * The fBm peer: the simplest fast 8-octave gradient fBm one would write by hand, to measure
 * fractalbake's native fBm against (bench/run.sh builds and runs it beside `fractalbake bench`).
 * The same lattice as fractalbake's gradient noise (the lowbias32 hash of the cell, Perlin's 8
 * gradients of length sqrt(5), the quintic fade, a power-of-two period as a mask) and none of its
 * extras: no tileable, warp or huge-coordinate paths, gain 1/2, lacunarity 2, 4 cycles across the
 * image. AVX2, 8 pixels a vector, rows split over the cores with pthreads. Two forms, each timed:
 *
 * - "rotated": the formula of Musgrave's fBm that fractalbake computes, fbm(x) = sum G^i
 *   noise(R^i L^i x + o_i), with the layer's default rotation R of 36.87 degrees and an offset per
 *   octave: the like-for-like peer.
 * - "plain": no rotation and no offset, octave i at 2^i x: one addition per octave where the
 *   rotation and offset take ten operations (four of them on the chain from one octave's
 *   coordinates to the next). The fastest form of the algorithm, without its rotation.
 *
 * Build: gcc -O3 -mavx2 -o fbm_peer bench/fbm_peer.c -lpthread -lm
 * Usage: fbm_peer [--json] [--size WxH] [--threads N]     (median of 3 after a warm-up, each form)
 */
#include <immintrin.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static int W = 4096, H = 4096, NT = 0, rotated;
static float *out;

static inline __m256i hash8(__m256i x) /* lowbias32 */
{
    x = _mm256_xor_si256(x, _mm256_srli_epi32(x, 16));
    x = _mm256_mullo_epi32(x, _mm256_set1_epi32(0x7feb352d));
    x = _mm256_xor_si256(x, _mm256_srli_epi32(x, 15));
    x = _mm256_mullo_epi32(x, _mm256_set1_epi32((int)0x846ca68bu));
    return _mm256_xor_si256(x, _mm256_srli_epi32(x, 16));
}

static inline __m256 grad(__m256i h, __m256 x, __m256 y)
{
    __m256i b = _mm256_and_si256(h, _mm256_set1_epi32(7));
    __m256 lo = _mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_set1_epi32(4), b)); /* b < 4 */
    __m256 u = _mm256_blendv_ps(y, x, lo), v = _mm256_blendv_ps(x, y, lo);
    __m256 s1 = _mm256_castsi256_ps(_mm256_slli_epi32(b, 31));                       /* b & 1: sign of u */
    __m256 s2 = _mm256_castsi256_ps(_mm256_slli_epi32(_mm256_srli_epi32(b, 1), 31)); /* b & 2: sign of v */
    return _mm256_add_ps(_mm256_xor_ps(u, s1), _mm256_xor_ps(_mm256_add_ps(v, v), s2));
}

static inline __m256 fade(__m256 t) /* t^3 (t (6t - 15) + 10) */
{
    __m256 p = _mm256_add_ps(_mm256_mul_ps(t, _mm256_sub_ps(_mm256_mul_ps(t, _mm256_set1_ps(6)), _mm256_set1_ps(15))),
                             _mm256_set1_ps(10));
    return _mm256_mul_ps(_mm256_mul_ps(_mm256_mul_ps(t, t), t), p);
}

static inline __m256 noise(uint32_t seed, __m256 x, __m256 y)
{
    __m256 fx = _mm256_floor_ps(x), fy = _mm256_floor_ps(y), tx = _mm256_sub_ps(x, fx), ty = _mm256_sub_ps(y, fy);
    const __m256i mask = _mm256_set1_epi32(4095), one = _mm256_set1_epi32(1);
    __m256i ix0 = _mm256_and_si256(_mm256_cvttps_epi32(fx), mask),
            iy0 = _mm256_and_si256(_mm256_cvttps_epi32(fy), mask);
    __m256i ix1 = _mm256_and_si256(_mm256_add_epi32(ix0, one), mask),
            iy1 = _mm256_and_si256(_mm256_add_epi32(iy0, one), mask);
    __m256i s = _mm256_set1_epi32((int)(seed ^ 0x632be5abu)), k = _mm256_set1_epi32((int)0x9e3779b1u);
    __m256i r0 = hash8(_mm256_xor_si256(iy0, s)), r1 = hash8(_mm256_xor_si256(iy1, s));
    __m256i x0k = _mm256_mullo_epi32(ix0, k), x1k = _mm256_mullo_epi32(ix1, k);
    __m256 one_f = _mm256_set1_ps(1), tx1 = _mm256_sub_ps(tx, one_f), ty1 = _mm256_sub_ps(ty, one_f);
    __m256 n00 = grad(hash8(_mm256_xor_si256(x0k, r0)), tx, ty), n10 = grad(hash8(_mm256_xor_si256(x1k, r0)), tx1, ty);
    __m256 n01 = grad(hash8(_mm256_xor_si256(x0k, r1)), tx, ty1),
           n11 = grad(hash8(_mm256_xor_si256(x1k, r1)), tx1, ty1);
    __m256 u = fade(tx), v = fade(ty);
    __m256 a = _mm256_add_ps(n00, _mm256_mul_ps(u, _mm256_sub_ps(n10, n00)));
    __m256 b = _mm256_add_ps(n01, _mm256_mul_ps(u, _mm256_sub_ps(n11, n01)));
    return _mm256_mul_ps(_mm256_set1_ps(0.6324555f), _mm256_add_ps(a, _mm256_mul_ps(v, _mm256_sub_ps(b, a))));
}

typedef struct {
    int y0, y1;
} band;

static void *rows(void *arg)
{
    const band *b = arg;
    const float fx = 4.0f / (float)W, fy = 4.0f * (float)H / (float)W / (float)H;
    const __m256 lane = _mm256_setr_ps(0.5f, 1.5f, 2.5f, 3.5f, 4.5f, 5.5f, 6.5f, 7.5f);
    const double a = 36.87 * 3.14159265358979323846 / 180.0;
    const __m256 c = _mm256_set1_ps((float)cos(a)), s = _mm256_set1_ps((float)sin(a)), L = _mm256_set1_ps(2.0f);
    float ox[8], oy[8];
    for (int o = 0; o < 8; o++) ox[o] = 0.37f * (float)(o + 1), oy[o] = 0.61f * (float)(o + 1);
    for (int y = b->y0; y < b->y1; y++)
        for (int x = 0; x < W; x += 8) {
            __m256 px = _mm256_mul_ps(_mm256_add_ps(_mm256_set1_ps((float)x), lane), _mm256_set1_ps(fx));
            __m256 py = _mm256_set1_ps(((float)y + 0.5f) * fy), sum = _mm256_setzero_ps(), amp = _mm256_set1_ps(1);
            for (int o = 0; o < 8; o++) {
                sum = _mm256_add_ps(sum, _mm256_mul_ps(amp, noise(0x1234567u + (uint32_t)o * 0x9e3779b9u, px, py)));
                amp = _mm256_mul_ps(amp, _mm256_set1_ps(0.5f));
                if (rotated) { /* R L x + o */
                    __m256 nx = _mm256_mul_ps(L, _mm256_sub_ps(_mm256_mul_ps(c, px), _mm256_mul_ps(s, py)));
                    __m256 ny = _mm256_mul_ps(L, _mm256_add_ps(_mm256_mul_ps(s, px), _mm256_mul_ps(c, py)));
                    px = _mm256_add_ps(nx, _mm256_set1_ps(ox[o])), py = _mm256_add_ps(ny, _mm256_set1_ps(oy[o]));
                } else {
                    px = _mm256_add_ps(px, px), py = _mm256_add_ps(py, py);
                }
            }
            _mm256_storeu_ps(out + (size_t)y * W + x, sum);
        }
    return NULL;
}

/* The median of 3 timed runs after a warm-up, in Mpix/s. */
static double run(void);

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv)
{
    int json = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--json"))
            json = 1;
        else if (!strcmp(argv[i], "--size") && i + 1 < argc && sscanf(argv[i + 1], "%dx%d", &W, &H) == 2)
            i++;
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc)
            NT = atoi(argv[++i]);
        else {
            fprintf(stderr, "usage: fbm_peer [--json] [--size WxH] [--threads N]\n");
            return 2;
        }
    }
    if (W < 8 || W % 8 || H < 1 || W > 16384 || H > 16384) {
        fprintf(stderr, "fbm_peer: --size: the width must be a multiple of 8 in 8..16384, the height in 1..16384\n");
        return 2;
    }
    if (NT <= 0) NT = (int)sysconf(_SC_NPROCESSORS_ONLN);
    if (!(out = malloc((size_t)W * H * 4))) return 3;
    if (NT > 256) NT = 256;
    static const char *what[2] = {"plain: no rotation or offset", "rotated: R and an offset per octave, as the layer"};
    for (rotated = 1; rotated >= 0; rotated--) {
        double rate = run();
        if (json)
            printf(
                "{\"generator\": \"fbm\", \"backend\": \"native\", \"device\": \"peer: minimal AVX2 gradient fBm, "
                "%s (bench/fbm_peer.c)\", \"mode\": \"generate\", \"unit\": \"Mpix/s\", \"rate\": %.3f, \"size\": [%d, "
                "%d], \"threads\": %d}\n",
                what[rotated], rate, W, H, NT);
        else
            printf("fbm peer (minimal AVX2 gradient fBm, 8 octaves, %s) %d x %d: %.2f Mpix/s [%d threads]\n",
                   what[rotated], W, H, rate, NT);
    }
    free(out);
    return 0;
}

static double run(void)
{
    pthread_t th[256];
    band b[256];
    double t[4];
    for (int k = 0; k < 4; k++) { /* a warm-up, then three */
        double t0 = now();
        for (int i = 0; i < NT; i++) {
            b[i] = (band){H * i / NT, H * (i + 1) / NT};
            pthread_create(&th[i], NULL, rows, &b[i]);
        }
        for (int i = 0; i < NT; i++) pthread_join(th[i], NULL);
        t[k] = now() - t0;
    }
    qsort(t + 1, 3, sizeof t[0], cmp);
    return (double)W * H / t[2] * 1e-6;
}
