/*
 * The stream-power peer: the same model as fractalbake's rivers layer written the plain way, one
 * thread, to measure the layer against (bench/rivers.sh runs both on the same grid). Each step:
 * steepest-descent receivers (D8); each pit's depression filled by priority-flood with epsilon
 * (Barnes, Lehman and Mulla 2014), from the pit up to where the water leaves its basin and back from
 * there, as the layer does (rounds while a fill uncovers a pit); Braun and Willett's stack by donor
 * lists and a walk from the outlets; drainage area in reverse stack order; uplift and the implicit
 * stream power law (n = 1) in stack order; hillslope diffusion implicit along rows, then columns
 * (Thomas's algorithm). Flat start at 0 plus uniform noise in [0, 1), open edges, filled depressions:
 * the rivers layer's defaults, and the same start (the noise is the same hash of the seed and cell).
 *
 * Build: gcc -O3 -march=native -o rivers_peer bench/peers/rivers_peer.c -lm
 * Usage: rivers_peer [--json] [--size WxH] [--steps N] [--extent E]   (one run; prints the rate,
 *        the relief and the largest basin's share, to compare with the layer's summary)
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static int W = 2048, H = 2048, STEPS = 500;
static double EXTENT = 100000, U = 1e-3, K = 5e-6, M = 0.5, KD = 0.03, DT = 5e4;
static double *h, *A, *cp;
static int *rcv, *stack, *ndon, *don, *heap, nheap;
static uint8_t *done;

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

/* kernels/hash.h's k_hash3 and k_u01: the layer's starting noise */
static uint32_t hash(uint32_t x)
{
    x ^= x >> 16, x *= 0x7feb352du, x ^= x >> 15, x *= 0x846ca68bu, x ^= x >> 16;
    return x;
}

static float noise(uint32_t seed, uint32_t i)
{
    return (float)(hash(i ^ hash(0x72697672u ^ hash(seed ^ 0x9e3779b9u))) >> 8) * (1.0f / 16777216.0f);
}

static int edge(int i)
{
    int x = i % W, y = i / W;
    return x == 0 || y == 0 || x == W - 1 || y == H - 1;
}

static const int DX[8] = {0, -1, 1, 0, -1, 1, -1, 1}, DY[8] = {-1, 0, 0, 1, -1, -1, 1, 1};

/* steepest descent; returns the cells (not on the edge) with no lower neighbour */
static int receivers(void)
{
    int pits = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            int i = y * W + x, r = i;
            double best = 0;
            if (!edge(i))
                for (int k = 0; k < 8; k++) {
                    int j = (y + DY[k]) * W + x + DX[k];
                    double s = (h[i] - h[j]) * (k < 4 ? 1 : M_SQRT1_2);
                    if (s > best) best = s, r = j;
                }
            rcv[i] = r;
            pits += r == i && !edge(i);
        }
    return pits;
}

static int less(int a, int b)
{
    return h[a] < h[b] || (h[a] == h[b] && a < b);
}

static void push(int v)
{
    int k = nheap++;
    while (k > 0 && less(v, heap[(k - 1) / 2])) heap[k] = heap[(k - 1) / 2], k = (k - 1) / 2;
    heap[k] = v;
}

static int pop(void)
{
    int top = heap[0], v = heap[--nheap], k = 0;
    for (;;) {
        int c = 2 * k + 1;
        if (c >= nheap) break;
        if (c + 1 < nheap && less(heap[c + 1], heap[c])) c++;
        if (!less(heap[c], v)) break;
        heap[k] = heap[c], k = c;
    }
    if (nheap) heap[k] = v;
    return top;
}

/* the pit a cell drains to, or -1 for an edge (walking down the receivers) */
static int root(int i)
{
    while (rcv[i] != i) i = rcv[i];
    return edge(i) ? -1 : i;
}

static void receiver(int i)
{
    int x = i % W, y = i / W, r = i;
    double best = 0;
    if (!edge(i))
        for (int k = 0; k < 8; k++) {
            int j = (y + DY[k]) * W + x + DX[k];
            double s = (h[i] - h[j]) * (k < 4 ? 1 : M_SQRT1_2);
            if (s > best) best = s, r = j;
        }
    rcv[i] = r;
}

/* Fills pit p's depression: priority-flood from the pit up to the first cell outside its basin (the
 * exit), then priority-flood + epsilon from the exit back over the cells taken; they and their
 * neighbours drain anew. region[] and done[] (clear outside a call) are scratch. */
static int *region;
static void fill_pit(int p)
{
    int nr = 0, exit = -1;
    nheap = 0;
    push(p), done[p] = 1;
    while (nheap) {
        int c = pop();
        if (c != p && (h[c] <= h[p] || root(c) != p)) {
            exit = c;
            break;
        }
        region[nr++] = c, done[c] = 2;
        for (int k = 0; k < 8; k++) {
            int nx = c % W + DX[k], ny = c / W + DY[k];
            if (nx < 0 || ny < 0 || nx >= W || ny >= H || done[ny * W + nx]) continue;
            done[ny * W + nx] = 1, push(ny * W + nx);
        }
    }
    while (nheap) done[heap[--nheap]] = 0;
    done[exit] = 0;
    push(exit);
    while (nheap) {
        int c = pop();
        double up = nextafter(h[c], INFINITY);
        for (int k = 0; k < 8; k++) {
            int nx = c % W + DX[k], ny = c / W + DY[k];
            if (nx < 0 || ny < 0 || nx >= W || ny >= H || done[ny * W + nx] != 2) continue;
            int j = ny * W + nx;
            done[j] = 0;
            if (h[j] < up) h[j] = up;
            push(j);
        }
    }
    for (int k = 0; k < nr; k++) {
        int c = region[k];
        receiver(c);
        for (int d = 0; d < 8; d++) {
            int nx = c % W + DX[d], ny = c / W + DY[d];
            if (nx >= 0 && ny >= 0 && nx < W && ny < H) receiver(ny * W + nx);
        }
    }
}

/* every pit's depression filled, round after round while filling uncovers new pits */
static void fill(void)
{
    for (int pits = 1; pits;) {
        pits = 0;
        for (int i = 0; i < W * H; i++)
            if (rcv[i] == i && !edge(i)) fill_pit(i), pits++;
        if (pits) {
            pits = 0;
            for (int i = 0; i < W * H; i++) pits += rcv[i] == i && !edge(i);
        }
    }
}

static void build_stack(void)
{
    memset(ndon, 0, (size_t)(W * H + 1) * sizeof *ndon);
    for (int i = 0; i < W * H; i++)
        if (rcv[i] != i) ndon[rcv[i] + 1]++;
    for (int i = 0; i < W * H; i++) ndon[i + 1] += ndon[i];
    int *cur = heap; /* free here */
    memcpy(cur, ndon, (size_t)W * H * sizeof *cur);
    for (int i = 0; i < W * H; i++)
        if (rcv[i] != i) don[cur[rcv[i]]++] = i;
    int n = 0;
    for (int i = 0; i < W * H; i++)
        if (rcv[i] == i) stack[n++] = i;
    for (int k = 0; k < n; k++)
        for (int d = ndon[stack[k]]; d < ndon[stack[k] + 1]; d++) stack[n++] = don[d];
}

/* (1 + 2r) x_j - r (x_{j-1} + x_{j+1}) = v_j along a line of L cells s apart; edge cells held */
static void line(double *v, int s, int L, int held_ends, double r)
{
    double pc = 0, pd = 0;
    for (int j = 0; j < L; j++) {
        int fixed = held_ends && (j == 0 || j == L - 1);
        double a = fixed ? 0 : -r, c = fixed ? 0 : -r, b = 1 - a - c;
        double inv = 1 / (b - a * pc);
        cp[j] = c * inv, pd = (v[j * s] - a * pd) * inv, pc = cp[j];
        v[j * s] = pd;
    }
    for (int j = L - 2; j >= 0; j--) v[j * s] -= cp[j] * v[(j + 1) * s];
}

int main(int argc, char **argv)
{
    int json = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--json"))
            json = 1;
        else if (!strcmp(argv[i], "--size") && i + 1 < argc && sscanf(argv[i + 1], "%dx%d", &W, &H) == 2)
            i++;
        else if (!strcmp(argv[i], "--steps") && i + 1 < argc)
            STEPS = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--extent") && i + 1 < argc)
            EXTENT = atof(argv[++i]);
        else {
            fprintf(stderr, "usage: rivers_peer [--json] [--size WxH] [--steps N] [--extent E]\n");
            return 2;
        }
    }
    size_t N = (size_t)W * H;
    h = malloc(N * sizeof *h), A = malloc(N * sizeof *A), cp = malloc((size_t)(W > H ? W : H) * sizeof *cp);
    rcv = malloc(N * sizeof *rcv), stack = malloc(N * sizeof *stack), ndon = malloc((N + 1) * sizeof *ndon);
    don = malloc(N * sizeof *don), heap = malloc(N * sizeof *heap), done = calloc(N, 1);
    region = malloc(N * sizeof *region);
    if (!h || !A || !cp || !rcv || !stack || !ndon || !don || !heap || !done || !region) {
        fprintf(stderr, "rivers_peer: out of memory\n");
        return 1;
    }
    double dx = EXTENT / W, F[2], r = KD * DT / (dx * dx);
    F[0] = K * DT * pow(dx * dx, M) / dx, F[1] = F[0] / M_SQRT2;
    for (size_t i = 0; i < N; i++) h[i] = noise(1, (uint32_t)i);
    double t0 = now();
    for (int t = 0; t < STEPS; t++) {
        if (receivers()) fill();
        build_stack();
        for (size_t i = 0; i < N; i++) A[i] = 1;
        for (size_t k = N; k-- > 0;)
            if (rcv[stack[k]] != stack[k]) A[rcv[stack[k]]] += A[stack[k]];
        for (size_t k = 0; k < N; k++) {
            int i = stack[k], j = rcv[i];
            if (j == i) continue;
            double h0 = h[i] + U * DT;
            if (!(h0 > h[j])) {
                h[i] = h0;
                continue;
            }
            int diag = (i % W != j % W) && (i / W != j / W);
            double f = F[diag] * (M == 0.5 ? sqrt(A[i]) : pow(A[i], M));
            h[i] = (h0 + f * h[j]) / (1 + f);
        }
        if (r > 0) {
            for (int y = 1; y < H - 1; y++) line(h + (size_t)y * W, 1, W, 1, r);
            for (int x = 1; x < W - 1; x++) line(h + x, W, H, 1, r);
        }
    }
    double sec = now() - t0, lo = INFINITY, hi = -INFINITY, top = 0;
    for (size_t i = 0; i < N; i++) {
        lo = fmin(lo, h[i]), hi = fmax(hi, h[i]);
        if (rcv[i] == (int)i) top = fmax(top, A[i]);
    }
    double rate = (double)N * STEPS / sec * 1e-6;
    if (json)
        printf("{\"generator\": \"rivers\", \"backend\": \"native\", \"device\": \"minimal C peer "
               "(bench/peers/rivers_peer.c)\", \"mode\": \"peer\", \"unit\": \"Mcell-steps/s\", \"rate\": %.3f, "
               "\"size\": [%d, %d], \"steps\": %d, \"seconds\": %.3f, \"threads\": 1, \"relief\": %.6g, "
               "\"largest_basin\": %.6g}\n",
               rate, W, H, STEPS, sec, hi - lo, top / N);
    else
        printf("rivers peer %d x %d, %d steps, 1 thread: %.3f Mcell-steps/s (%.3f s); relief %.6g, largest basin "
               "%.3g%%\n",
               W, H, STEPS, rate, sec, hi - lo, 100 * top / N);
    return 0;
}
