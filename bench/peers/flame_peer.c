/*
 * The ceiling for issue 31's native flame speed (bench/RESULTS.md): the simplest fast chaos game
 * for the genome `gold` of docs/examples/flames.flame at 1024 x 1024, hard-coded, without any of the
 * generator's constraints (no determinism across thread counts or devices, libm's float sinf/cosf/
 * atan2f/expf, one endless chain a thread with its own xorshift generator, no fuse restarts, no
 * density estimation, no spatial filter, no file): its 2 xforms with their variations (ex, cosine,
 * flower; blob, blade) and the 6 linear rotations of its symmetry (3 distinct ones, weight 2 each),
 * the xform chosen by weight from a 16384-entry table as flam3 does, a histogram of hit counts and
 * palette colour sums (16-byte cells, one a thread, points scattered a batch at a time with the
 * cells prefetched ahead), the histograms summed and a plain log-density tone map into 8-bit RGBA
 * in memory, all on the threads.
 *
 *   flame_peer [--json] [THREADS] [QUALITY]     defaults 2, 20: prints points, seconds, Mpts/s (wall
 *                                               and CPU); --json: `fractalbake bench`'s rows instead
 *                                               (generator flame, modes peer and peer-game: the whole
 *                                               and the game alone; bench/run.sh)
 */
#define _GNU_SOURCE
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "kmath.h"

/* kernels/kmath.h's float polynomials (faster than glibc's atan2f; -DPEER_LIBM: libm's) */
#ifndef PEER_LIBM
#define atan2f(y, x) k_xatan2(y, x)
#define expf(x)      k_xexp(x)
#define sinf(x)      k_xsin(x)
#define cosf(x)      k_xcos(x)
#define sincosf(a_, s_, c_)                                                                                            \
    do {                                                                                                               \
        k_vec2 sc_ = k_sincos(a_);                                                                                     \
        *(s_) = sc_.x, *(c_) = sc_.y;                                                                                  \
    } while (0)
#endif

#define W     1024
#define H     1024
#define BATCH 1024
#ifndef CHAINS
#define CHAINS 2
#endif
#ifndef AHEAD
#define AHEAD 32
#endif

static const uint8_t pal[256][3] = {
#include "flame_peer_palette.inc"
};

typedef struct cell {
    uint32_t r, g, b, hits;
} cell;

static uint8_t choose[16384];
/* the rotations by 90, 180 and 270 degrees: x -> (a x + b y, c x + d y), and their colour */
static const float rot[3][5] = {{0, -1, 1, 0, 0.0f}, {-1, 0, 0, -1, 0.5f}, {0, 1, -1, 0, 1.0f}};
static float ppu, xmin, ymin;

static double now(clockid_t c)
{
    struct timespec t;
    clock_gettime(c, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

static inline uint64_t next(uint64_t *s)
{
    uint64_t x = *s;
    x ^= x >> 12, x ^= x << 25, x ^= x >> 27;
    *s = x;
    return x * 0x2545F4914F6CDD1Dull;
}

static inline float u01(uint64_t r)
{
    return (float)(r >> 40) * (1.0f / 16777216.0f);
}

/* One iteration: the xform chosen by weight and applied to (x, y, c) as flam3 does. */
static inline __attribute__((always_inline)) void step(float *px, float *py, float *pc, uint64_t *rng)
{
    uint64_t r = next(rng);
    float x = *px, y = *py, nx, ny;
    unsigned fn = choose[r & 16383];
    if (__builtin_expect(fn >= 2, 1)) { /* the symmetry's rotations: linear, colour speed 0, no branch between them */
        const float *R = rot[fn - 2];
        nx = R[0] * x + R[1] * y, ny = R[2] * x + R[3] * y, *pc = R[4];
    } else
        switch (fn) {
        case 0: { /* ex 0.41934, cosine 0.574757, flower 0.00590257 (petals 3.5477, holes 0.539886) */
            float tx = -0.0848142f * x + -0.202407f * y + 0.546221f, ty = -0.900293f * x + 0.370426f * y + -0.321092f;
            float sq = sqrtf(tx * tx + ty * ty), atxy = atan2f(tx, ty), atyx = atan2f(ty, tx);
            float n0 = sinf(atxy + sq), n1 = cosf(atxy - sq), m0 = n0 * n0 * n0 * sq, m1 = n1 * n1 * n1 * sq;
            nx = 0.41934f * (m0 + m1), ny = 0.41934f * (m0 - m1);
            float s, co, e = expf(ty), ei = 1.0f / e;
            sincosf(tx * (float)M_PI, &s, &co);
            nx += 0.574757f * co * 0.5f * (e + ei), ny -= 0.574757f * s * 0.5f * (e - ei);
            float fr = 0.00590257f * (u01(next(rng)) - 0.539886f) * cosf(3.5477f * atyx) / sq;
            nx += fr * tx, ny += fr * ty;
            *pc = 0.5f * 0.0f + 0.5f * *pc;
            break;
        }
        default: { /* blob 0.516139 (low 0.401652, high 0.943134, waves 5), blade 0.483861 */
            float tx = 0.741856f * x + -0.309256f * y + -0.954755f, ty = -0.865792f * x + -0.0467611f * y + -0.587651f;
            float sq = sqrtf(tx * tx + ty * ty), atxy = atan2f(tx, ty);
            float br = sq * (0.401652f + (0.943134f - 0.401652f) * (0.5f + 0.5f * sinf(5.0f * atxy)));
            nx = 0.516139f * (tx / sq) * br, ny = 0.516139f * (ty / sq) * br;
            float s, co;
            sincosf(u01(r) * 0.483861f * sq, &s, &co);
            nx += 0.483861f * tx * (co + s), ny += 0.483861f * tx * (co - s);
            *pc = 0.5f * 1.0f + 0.5f * *pc;
            break;
        }
        }
    if (!(fabsf(nx) < 1e10f && fabsf(ny) < 1e10f)) /* NaN or too far: a random point (flam3's rule) */
        nx = u01(next(rng)) * 2 - 1, ny = u01(next(rng)) * 2 - 1;
    *px = nx, *py = ny;
}

typedef struct job {
    int id, threads;
    uint64_t points;
    cell *hist[64];
    uint8_t *img;
} job;

static void *play(void *arg)
{
    job *J = ((job **)arg)[0];
    int id = (int)(intptr_t)((void **)arg)[1];
    cell *h = J->hist[id];
    uint64_t rng = 0x9E3779B97F4A7C15ull * (id + 1), n = J->points / J->threads + (id < (int)(J->points % J->threads));
    /* CHAINS independent chains a thread, stepped in turn (their arithmetic overlaps) */
    float x[CHAINS], y[CHAINS], c[CHAINS];
    for (int j = 0; j < CHAINS; j++) {
        x[j] = u01(next(&rng)) * 2 - 1, y[j] = u01(next(&rng)) * 2 - 1, c[j] = u01(next(&rng));
        for (int t = 0; t < 15; t++) step(&x[j], &y[j], &c[j], &rng);
    }
    uint32_t cells[BATCH];
    uint8_t cols[BATCH];
    while (n > 0) {
        uint32_t m = n < BATCH ? (uint32_t)n : BATCH, k = 0;
        for (uint32_t t = 0; t < m; t++) {
            int j = t % CHAINS;
            step(&x[j], &y[j], &c[j], &rng);
            int ix = (int)((x[j] - xmin) * ppu), iy = (int)((y[j] - ymin) * ppu), ci = (int)(c[j] * 256.0f);
            cells[k] = (uint32_t)iy * W + (uint32_t)ix;
            cols[k] = (uint8_t)(ci < 0 ? 0 : ci > 255 ? 255 : ci);
            k += x[j] >= xmin && y[j] >= ymin && (unsigned)ix < W && (unsigned)iy < H;
        }
        for (uint32_t t = 0; t < k; t++) {
            if (t + AHEAD < k) __builtin_prefetch(&h[cells[t + AHEAD]], 1);
            cell *e = &h[cells[t]];
            const uint8_t *p = pal[cols[t]];
            e->r += p[0], e->g += p[1], e->b += p[2], e->hits++;
        }
        n -= m;
    }
    return NULL;
}

/* The histograms summed and toned, rows [H id / threads, H (id + 1) / threads). */
static void *tone(void *arg)
{
    job *J = ((job **)arg)[0];
    int id = (int)(intptr_t)((void **)arg)[1];
    size_t a = (size_t)W * (H * id / J->threads), b = (size_t)W * (H * (id + 1) / J->threads);
    const float k2 = 1.0f / (float)(J->points / ((double)W * H)), bright = 4.0f, ig = 1.0f / 4.0f;
    for (size_t i = a; i < b; i++) {
        cell s = J->hist[0][i];
        for (int t = 1; t < J->threads; t++)
            s.r += J->hist[t][i].r, s.g += J->hist[t][i].g, s.b += J->hist[t][i].b, s.hits += J->hist[t][i].hits;
        uint8_t *o = J->img + 4 * i;
        if (!s.hits) {
            memset(o, 0, 4);
            continue;
        }
        float ls = bright * logf(1.0f + s.hits * k2) / s.hits, alpha = powf(s.hits * ls, ig);
        float f = alpha / (s.hits * ls) * ls / 255.0f * 255.0f;
        float rgb[3] = {s.r * f, s.g * f, s.b * f};
        for (int k = 0; k < 3; k++) o[k] = (uint8_t)(rgb[k] > 255 ? 255 : rgb[k]);
        o[3] = (uint8_t)(alpha > 1 ? 255 : alpha * 255);
    }
    return NULL;
}

static void run(job *J, void *(*fn)(void *))
{
    pthread_t th[64];
    void *args[64][2];
    for (int t = 0; t < J->threads; t++) {
        args[t][0] = J, args[t][1] = (void *)(intptr_t)t;
        pthread_create(&th[t], NULL, fn, args[t]);
    }
    for (int t = 0; t < J->threads; t++) pthread_join(th[t], NULL);
}

int main(int argc, char **argv)
{
    int json = argc > 1 && !strcmp(argv[1], "--json");
    argc -= json, argv += json;
    int threads = argc > 1 ? atoi(argv[1]) : 2;
    double q = argc > 2 ? atof(argv[2]) : 20;
    if (threads < 1 || threads > 64 || !(q > 0)) return fprintf(stderr, "flame_peer [--json] [THREADS] [QUALITY]\n"), 2;
    /* the weights: xform 0 and 1 0.5 each, the 3 rotations 2 each (twice 1: the genome's and the symmetry's) */
    const double w[5] = {0.5, 0.5, 2, 2, 2};
    double sum = 0, acc = 0;
    for (int i = 0; i < 5; i++) sum += w[i];
    for (int i = 0, j = 0; i < 16384; i++) {
        while (j < 4 && i * sum / 16384 >= acc + w[j]) acc += w[j++];
        choose[i] = (uint8_t)j;
    }
    ppu = 311.821312f, xmin = -0.510105f - W / 2 / ppu, ymin = 0.367588f - H / 2 / ppu;
    job J = {.threads = threads, .points = (uint64_t)(q * W * H)};
    double t0 = now(CLOCK_MONOTONIC), c0 = now(CLOCK_PROCESS_CPUTIME_ID);
    for (int t = 0; t < threads; t++)
        if (!(J.hist[t] = calloc((size_t)W * H, sizeof(cell)))) return 1;
    if (!(J.img = malloc((size_t)W * H * 4))) return 1;
    run(&J, play);
    double t1 = now(CLOCK_MONOTONIC);
    run(&J, tone);
    double t2 = now(CLOCK_MONOTONIC), c2 = now(CLOCK_PROCESS_CPUTIME_ID);
    uint64_t lit = 0, sum8 = 0;
    for (size_t i = 0; i < (size_t)W * H; i++) lit += J.img[4 * i + 3] != 0, sum8 += J.img[4 * i + 1];
    if (json) {
        const char *modes[2] = {"peer", "peer-game"};
        double sec[2] = {t2 - t0, t1 - t0};
        for (int k = 0; k < 2; k++)
            printf("{\"generator\": \"flame\", \"backend\": \"native\", \"device\": \"minimal C peer "
                   "(bench/peers/flame_peer.c)\", \"mode\": \"%s\", \"unit\": \"Mpts/s\", \"rate\": %.3f, "
                   "\"threads\": %d, \"points\": %llu}\n",
                   modes[k], J.points / sec[k] * 1e-6, threads, (unsigned long long)J.points);
    } else
        printf("flame_peer: %llu points, %d threads: %.3f s wall (game %.3f, tone %.3f), %.3f CPU s: %.1f Mpts/s, "
               "%.1f Mpts/CPU-s (%llu pixels lit, green sum %llu)\n",
               (unsigned long long)J.points, threads, t2 - t0, t1 - t0, t2 - t1, c2 - c0, J.points / (t2 - t0) * 1e-6,
               J.points / (c2 - c0) * 1e-6, (unsigned long long)lit, (unsigned long long)sum8);
    for (int t = 0; t < threads; t++) free(J.hist[t]);
    free(J.img);
    return 0;
}
