/*
 * The erosion peer: the virtual-pipe model (Mei, Decaudin and Hu 2007) with talus slides (Musgrave,
 * Kolb and Mace 1989) written the plain way one would by hand, to measure fractalbake's erode layer
 * against (bench/run.sh builds and runs it beside `fractalbake bench`). The same three passes per
 * iteration and the same formulas as kernels/erode.h (flux with the outflow scaled to the water a
 * cell has; depth, velocity, capacity, dissolution or deposition, evaporation; sediment carried in
 * proportion to the water, slides above the talus step), on separate float arrays (structure of
 * arrays) instead of fractalbake's four-float cells, rows split over the cores with pthreads and a
 * barrier between passes. The same terrain and parameters as `fractalbake bench`'s erode rows.
 *
 * Build: gcc -O3 -march=native -o erode_peer bench/erode_peer.c -lpthread -lm
 * Usage: erode_peer [--json] [--size WxH] [--threads N] [--iterations N]   (median of 3)
 */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static int W = 1024, H = 1024, NT = 0, ITERS = 50;
static float *b, *d, *s, *fl, *fr, *ft, *fb, *b1, *d1a, *s1, *dn, *flow, *wear, *dep;
static float rain, pipe_, vol, dt_area, inv_l, half_inv_l, kc, ks, kd, keep, dmin, talus, kt, flow_w, inv_depth;
static pthread_barrier_t bar;

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

static float carry(float sv, float f, float dv)
{
    return dv > 0 ? sv * ((f * dt_area) / dv) : 0;
}

static float slide(float a, float z)
{
    return kt * fmaxf(0, (a - z) - talus) * 0.5f;
}

static void flux(int y0, int y1)
{
    for (int y = y0; y < y1; y++)
        for (int x = 0; x < W; x++) {
            int i = y * W + x;
            float hc = b[i] + (d[i] + rain), dd = d[i] + rain;
            float l = x > 0 ? fmaxf(0, fl[i] + pipe_ * (hc - (b[i - 1] + (d[i - 1] + rain)))) : 0;
            float r = x + 1 < W ? fmaxf(0, fr[i] + pipe_ * (hc - (b[i + 1] + (d[i + 1] + rain)))) : 0;
            float t = y > 0 ? fmaxf(0, ft[i] + pipe_ * (hc - (b[i - W] + (d[i - W] + rain)))) : 0;
            float u = y + 1 < H ? fmaxf(0, fb[i] + pipe_ * (hc - (b[i + W] + (d[i + W] + rain)))) : 0;
            float sum = l + r + t + u, k = sum > 0 ? fminf(1, dd * vol / sum) : 1;
            fl[i] = l * k, fr[i] = r * k, ft[i] = t * k, fb[i] = u * k;
        }
}

static void water(int y0, int y1)
{
    for (int y = y0; y < y1; y++)
        for (int x = 0; x < W; x++) {
            int i = y * W + x;
            float il = x > 0 ? fr[i - 1] : 0, ir = x + 1 < W ? fl[i + 1] : 0;
            float it = y > 0 ? fb[i - W] : 0, ib = y + 1 < H ? ft[i + W] : 0;
            float dd = d[i] + rain, out = fl[i] + fr[i] + ft[i] + fb[i];
            float d2 = dd + (il + ir + it + ib - out) * dt_area, dm = (dd + d2) * 0.5f;
            float wx = (il - fl[i] + fr[i] - ir) * 0.5f, wy = (it - ft[i] + fb[i] - ib) * 0.5f;
            float q = sqrtf(wx * wx + wy * wy) * inv_l, speed = q / fmaxf(dm, dmin);
            float gx = ((x + 1 < W ? b[i + 1] : b[i]) - (x > 0 ? b[i - 1] : b[i])) * half_inv_l;
            float gy = ((y + 1 < H ? b[i + W] : b[i]) - (y > 0 ? b[i - W] : b[i])) * half_inv_l;
            float g2 = gx * gx + gy * gy, sina = sqrtf(g2 / (1 + g2));
            float cap = kc * sina * speed * fminf(1, dm * inv_depth), nb, ns;
            if (cap > s[i]) {
                float a = ks * (cap - s[i]);
                nb = b[i] - a, ns = s[i] + a;
            } else {
                float a = kd * (s[i] - cap);
                nb = b[i] + a, ns = s[i] - a;
            }
            b1[i] = nb, s1[i] = ns, d1a[i] = dd, dn[i] = fmaxf(0, d2) * keep;
            flow[i] += q * flow_w, wear[i] += fmaxf(0, b[i] - nb), dep[i] += fmaxf(0, nb - b[i]);
        }
}

static void settle(int y0, int y1)
{
    for (int y = y0; y < y1; y++)
        for (int x = 0; x < W; x++) {
            int i = y * W + x;
            float sv = s1[i], dd = d1a[i];
            float out = carry(sv, fl[i], dd) + carry(sv, fr[i], dd) + carry(sv, ft[i], dd) + carry(sv, fb[i], dd);
            float in = (x > 0 ? carry(s1[i - 1], fr[i - 1], d1a[i - 1]) : 0) +
                       (x + 1 < W ? carry(s1[i + 1], fl[i + 1], d1a[i + 1]) : 0) +
                       (y > 0 ? carry(s1[i - W], fb[i - W], d1a[i - W]) : 0) +
                       (y + 1 < H ? carry(s1[i + W], ft[i + W], d1a[i + W]) : 0);
            float bc = b1[i], bl = x > 0 ? b1[i - 1] : bc, br = x + 1 < W ? b1[i + 1] : bc;
            float bt = y > 0 ? b1[i - W] : bc, bb = y + 1 < H ? b1[i + W] : bc;
            float nb = bc - (slide(bc, bl) + slide(bc, br) + slide(bc, bt) + slide(bc, bb)) +
                       (slide(bl, bc) + slide(br, bc) + slide(bt, bc) + slide(bb, bc));
            s[i] = sv - out + in, d[i] = dn[i];
            wear[i] += fmaxf(0, bc - nb), dep[i] += fmaxf(0, nb - bc);
            b[i] = nb;
        }
}

static void *worker(void *arg)
{
    int k = (int)(long)arg, rows = (H + NT - 1) / NT, y0 = k * rows, y1 = y0 + rows < H ? y0 + rows : H;
    for (int it = 0; it < ITERS; it++) {
        flux(y0, y1);
        pthread_barrier_wait(&bar);
        water(y0, y1);
        pthread_barrier_wait(&bar);
        settle(y0, y1);
        pthread_barrier_wait(&bar);
    }
    return NULL;
}

static void setup(void)
{
    size_t n = (size_t)W * H;
    float **all[] = {&b, &d, &s, &fl, &fr, &ft, &fb, &b1, &d1a, &s1, &dn, &flow, &wear, &dep};
    for (size_t k = 0; k < sizeof all / sizeof all[0]; k++) {
        free(*all[k]);
        *all[k] = calloc(n, sizeof(float));
        if (!*all[k]) {
            fprintf(stderr, "erode_peer: out of memory\n");
            exit(3);
        }
    }
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            double u = (double)x / W, v = (double)y / H;
            b[(size_t)y * W + x] = (float)(40 * sin(6.1 * u) * cos(4.3 * v) + 12 * sin(23 * u + 17 * v) +
                                           4 * cos(71 * u - 53 * v) + 30 * v);
        }
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
        else if (!strcmp(argv[i], "--iterations") && i + 1 < argc)
            ITERS = atoi(argv[++i]);
        else {
            fprintf(stderr, "usage: erode_peer [--json] [--size WxH] [--threads N] [--iterations N]\n");
            return 2;
        }
    }
    if (W > 1024) W = 1024; /* the size of fractalbake's erode benchmark */
    if (H > 1024) H = 1024;
    if (NT <= 0) NT = (int)sysconf(_SC_NPROCESSORS_ONLN);
    /* the parameters of fractalbake bench's erode rows: cell 1024 / W, 15 time units */
    double l = 1024.0 / W, dt = 15.0 / ITERS;
    rain = (float)(0.005 * dt), pipe_ = (float)(dt * 9.81 * l), vol = (float)(l * l / dt),
    dt_area = (float)(dt / (l * l));
    inv_l = (float)(1 / l), half_inv_l = (float)(0.5 / l), kc = 0.05f, ks = (float)fmin(1, 0.5 * dt);
    kd = (float)fmin(1, dt), keep = (float)(1 - 0.2 * dt), dmin = 1e-4f, talus = (float)(tan(35 * M_PI / 180) * l);
    kt = (float)fmin(0.5, 0.5 * dt), flow_w = (float)(dt / 15), inv_depth = 20;
    double t[3];
    for (int r = 0; r < 3; r++) {
        setup();
        pthread_barrier_init(&bar, NULL, (unsigned)NT);
        pthread_t th[256];
        double t0 = now();
        for (int k = 1; k < NT; k++) pthread_create(&th[k], NULL, worker, (void *)(long)k);
        worker((void *)0);
        for (int k = 1; k < NT; k++) pthread_join(th[k], NULL);
        t[r] = now() - t0;
        pthread_barrier_destroy(&bar);
    }
    for (int i = 0; i < 3; i++)
        for (int j = i + 1; j < 3; j++)
            if (t[j] < t[i]) {
                double x = t[i];
                t[i] = t[j], t[j] = x;
            }
    double rate = (double)W * H * ITERS / t[1] * 1e-6;
    if (json)
        printf(
            "{\"generator\": \"erode\", \"backend\": \"native\", \"device\": \"minimal C peer (bench/erode_peer.c)\", "
            "\"mode\": \"peer\", \"unit\": \"Mcell-iter/s\", \"rate\": %.3f, \"size\": [%d, %d], \"threads\": %d}\n",
            rate, W, H, NT);
    else
        printf("erode peer %d x %d, %d iterations, %d threads: %.3f Mcell-iter/s (%.3f s)\n", W, H, ITERS, NT, rate,
               t[1]);
    return 0;
}
