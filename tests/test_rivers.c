/*
 * Stream-power erosion (host/gen/rivers/): the model against closed forms (steady channel profiles,
 * diffusion), its fills against an independent one (Planchon and Darboux), the same bits on any thread
 * count, and its parameter checks. Its scenes are measured as river basins are by tests/drainage.py.
 */
#include "amplify.h"
#include "pool.h"
#include "rivers.h"

#include "testhelp.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- the model ---------------------------------------------------------------------------------- */

static fb_rivers_desc base(int W, int H)
{
    return (fb_rivers_desc){.width = W,
                            .height = H,
                            .cell = 100,
                            .seed = 3,
                            .uplift = 1e-3,
                            .K = 2e-5,
                            .m = 0.5,
                            .n = 1,
                            .dt = 1e5,
                            .steps = 400,
                            .outlets = FB_RIVERS_NORTH | FB_RIVERS_SOUTH | FB_RIVERS_EAST | FB_RIVERS_WEST,
                            .river_area = 1e5};
}

/* A channel one cell wide draining west, under uniform uplift and no diffusion, reaches the steady
 * state of the stream power law, U = K A^m S^n: each cell stands dx (U / (K A^m))^(1/n) above its
 * receiver, A being the cells from it to the channel's head (times dx^2). Braun and Willett's scheme
 * holds this state exactly (n = 1) or to Newton's tolerance; the stored heights are single precision. */
static void test_profile(double n)
{
    const int W = 64;
    fb_rivers_desc d = base(W, 1);
    d.outlets = FB_RIVERS_WEST, d.n = n, d.steps = n == 1 ? 400 : 1500;
    fb_rivers_out o;
    REQUIRE(fb_rivers_run(&d, NULL, NULL, &o) == FB_OK);
    double h = 0, worst = 0;
    for (int i = 1; i < W; i++) {
        double A = (double)(W - i) * d.cell * d.cell;
        h += d.cell * pow(d.uplift / (d.K * pow(A, d.m)), 1 / n);
        worst = fmax(worst, fabs(o.height[i] - h) / h);
    }
    CHECKF(o.height[0] == 0 && worst < 1e-6, "n = %g: heights off the steady state by %.3g (relative)", n, worst);
    /* the drainage area: the cells upstream, itself included */
    bool area = true;
    for (int i = 1; i < W; i++) area = area && o.area[i] == (float)((W - i) * d.cell * d.cell);
    CHECKF(area, "n = %g: the drainage area of a channel", n);
    fb_rivers_out_free(&o);
}

/* Diffusion alone (K = 0) between two held ends under uniform uplift reaches the parabola
 * kd h'' = -U: h(x) = U x (L - x) / (2 kd), which the implicit scheme's steady state holds exactly
 * (a parabola's second difference is its second derivative). */
static void test_diffusion(void)
{
    const int W = 41;
    fb_rivers_desc d = base(W, 1);
    d.outlets = FB_RIVERS_WEST | FB_RIVERS_EAST, d.K = 0, d.kd = 2, d.dt = 1e5, d.steps = 300, d.cell = 10;
    fb_rivers_out o;
    REQUIRE(fb_rivers_run(&d, NULL, NULL, &o) == FB_OK);
    double L = (W - 1) * d.cell, worst = 0;
    for (int i = 0; i < W; i++) {
        double x = i * d.cell, want = d.uplift * x * (L - x) / (2 * d.kd);
        worst = fmax(worst, fabs(o.height[i] - want));
    }
    CHECKF(worst < 1e-6 * d.uplift * L * L / (8 * d.kd), "diffusion: off the parabola by %g", worst);
    fb_rivers_out_free(&o);
}

/* The fill of a random surface against Planchon and Darboux's (Catena 46, 2001, "A fast, simple and
 * versatile algorithm to fill the depressions of digital elevation models"): w starts at +infinity
 * off the outlets and lowers, sweep after sweep, to max(h, the lowest neighbouring w) until nothing
 * changes: the lowest surface that drains, by another road than a priority queue. */
static double *planchon_darboux(const float *h, const bool *outlet, int W, int H)
{
    size_t N = (size_t)W * H;
    double *w = malloc(N * sizeof *w);
    REQUIRE(w);
    for (size_t i = 0; i < N; i++) w[i] = outlet[i] ? h[i] : INFINITY;
    for (bool changed = true; changed;) {
        changed = false;
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                size_t i = (size_t)y * W + x;
                if (outlet[i]) continue;
                double lo = INFINITY;
                for (int dy = -1; dy <= 1; dy++)
                    for (int dx = -1; dx <= 1; dx++) {
                        int nx = x + dx, ny = y + dy;
                        if ((dx || dy) && nx >= 0 && ny >= 0 && nx < W && ny < H) lo = fmin(lo, w[(size_t)ny * W + nx]);
                    }
                double v = fmax(h[i], lo);
                if (v < w[i]) w[i] = v, changed = true;
            }
    }
    return w;
}

/* Every cell but the outlets (and those under standing water) has a strictly lower neighbour. */
static long undrained(const float *z, const bool *outlet, const float *lake, int W, int H)
{
    long n = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            size_t i = (size_t)y * W + x;
            if (outlet[i] || (lake && lake[i] > 0)) continue;
            bool lower = false;
            for (int dy = -1; dy <= 1; dy++)
                for (int dx = -1; dx <= 1; dx++) {
                    int nx = x + dx, ny = y + dy;
                    if ((dx || dy) && nx >= 0 && ny >= 0 && nx < W && ny < H) lower |= z[(size_t)ny * W + nx] < z[i];
                }
            n += !lower;
        }
    return n;
}

/* One step with nothing but the fill (no uplift, no incision, no diffusion) on random heights, with
 * open edges or with a sea: filled, a cell is its Planchon-Darboux height where that lies above it
 * (and above by no more than the epsilons of a chain across the depression), exactly its own
 * height elsewhere, and drains; kept, the heights are the input's and the lake channel is the
 * water's depth, and the surface drains but for the water. */
static void test_fill(bool keep, bool sea)
{
    const int W = 60, H = 50;
    const size_t N = (size_t)W * H;
    float *h = malloc(N * sizeof *h);
    bool *outlet = malloc(N);
    REQUIRE(h && outlet);
    th_rng = sea ? 777 : 4242;
    for (size_t i = 0; i < N; i++) h[i] = (float)(100 * th_unif());
    fb_rivers_desc d = base(W, H);
    d.initial = h, d.steps = 1, d.uplift = 0, d.K = 0, d.keep_lakes = keep;
    if (sea) d.outlets = 0, d.has_sea = true, d.sea_level = 5;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            size_t i = (size_t)y * W + x;
            outlet[i] = sea ? h[i] < 5 : x == 0 || y == 0 || x == W - 1 || y == H - 1;
        }
    double *w = planchon_darboux(h, outlet, W, H);
    fb_rivers_out o;
    REQUIRE(fb_rivers_run(&d, NULL, NULL, &o) == FB_OK);
    long kept = 0, exact = 0, raised = 0, water = 0, depth_off = 0, depressed = 0;
    for (size_t i = 0; i < N; i++) {
        bool under = w[i] > h[i];
        depressed += under;
        if (keep) {
            kept += o.height[i] == h[i];
            double want = outlet[i] && sea ? 5 - h[i] : w[i] - h[i];
            water += (o.lake[i] > 0) == (under || (sea && outlet[i]));
            depth_off += fabs(o.lake[i] - want) > 1e-4 * fmax(1, w[i]);
        } else if (under) {
            raised += o.height[i] >= w[i] && o.height[i] - w[i] <= 1e-4 * w[i];
        } else {
            exact += o.height[i] == h[i];
            water += o.lake[i] == (sea && outlet[i] ? (float)(5 - h[i]) : 0);
        }
    }
    CHECKF(depressed > (long)N / 20, "the random surface has %ld cells in depressions", depressed);
    if (keep) {
        CHECKF(kept == (long)N && water == (long)N && depth_off == 0,
               "kept lakes (sea %d): %ld heights kept, %ld water cells right, %ld depths off", sea, kept, water,
               depth_off);
        CHECKF(undrained(o.height, outlet, o.lake, W, H) == 0,
               "kept lakes (sea %d): a cell out of the water drains "
               "nowhere",
               sea);
    } else {
        CHECKF(raised == depressed && exact + depressed == (long)N && water + depressed == (long)N,
               "filled (sea %d): %ld of %ld depressed cells at their fill, %ld of %ld others kept", sea, raised,
               depressed, exact, (long)N - depressed);
        CHECKF(undrained(o.height, outlet, NULL, W, H) == 0, "filled (sea %d): a cell drains nowhere", sea);
    }
    fb_rivers_out_free(&o);
    free(w), free(h), free(outlet);
}

static bool same_out(const fb_rivers_out *a, const fb_rivers_out *b, size_t n)
{
    return !memcmp(a->height, b->height, n * 4) && !memcmp(a->area, b->area, n * 4) &&
           !memcmp(a->river, b->river, n * 4) && !memcmp(a->lake, b->lake, n * 4);
}

/* The same bits on 1, 2 and 3 threads (row bands and column blocks of other sizes), with filled and
 * with kept lakes, a sea, an uplift map, diffusion, and n != 1. */
static void test_threads(void)
{
    const int W = 97, H = 83;
    float *map = malloc((size_t)W * H * sizeof *map), *start = malloc((size_t)W * H * sizeof *start);
    REQUIRE(map && start);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            map[y * W + x] = (float)(0.5 + 0.5 * sin(0.11 * x) * cos(0.07 * y));
            start[y * W + x] = (float)(20 * sin(0.05 * x + 0.3) + 0.2 * y);
        }
    for (int variant = 0; variant < 3; variant++) {
        fb_rivers_desc d = base(W, H);
        d.steps = 40, d.kd = 0.5, d.noise = 5, d.uplift_map = map, d.initial = start;
        if (variant == 1) d.keep_lakes = true, d.outlets = FB_RIVERS_SOUTH, d.has_sea = true, d.sea_level = -5;
        if (variant == 2) d.n = 1.5, d.m = 0.6;
        fb_rivers_out ref, o;
        REQUIRE(fb_rivers_run(&d, NULL, NULL, &ref) == FB_OK);
        for (int t = 1; t <= 3; t++) {
            fb_pool *pool = NULL;
            REQUIRE(fb_pool_create(t, &pool) == FB_OK);
            REQUIRE(fb_rivers_run(&d, pool, NULL, &o) == FB_OK);
            CHECKF(same_out(&ref, &o, (size_t)W * H), "variant %d: %d threads differ", variant, t);
            fb_rivers_out_free(&o);
            fb_pool_destroy(&pool);
        }
        fb_rivers_out_free(&ref);
    }
    free(map), free(start);
}

/* The amplification of a coarse solution, 4 times as wide: every pixel off the border and out of
 * standing water has a strictly lower neighbour of its 8 (counted here from the output alone), but
 * for at most 1 in 10^4; the sea's pixels lie below the sea level, with their depth; rows computed
 * one at a time, or from another start, are the same bits as all at once; the detail changes them. */
static void test_amplify(bool keep, bool sea)
{
    const int cw = 64, ch = 48, k = 4, W = cw * k, H = ch * k;
    fb_rivers_desc d = base(cw, ch);
    d.steps = 60, d.kd = 0.5, d.noise = 5, d.receivers = true, d.keep_lakes = keep;
    float *start = malloc((size_t)cw * ch * sizeof *start);
    REQUIRE(start);
    for (int i = 0; i < cw * ch; i++) start[i] = 0.5f * (ch - 1 - i / cw) - 2; /* the south's rows below 0 */
    if (sea) d.outlets = FB_RIVERS_SOUTH, d.has_sea = true, d.sea_level = 0, d.initial = start;
    fb_rivers_out o;
    REQUIRE(fb_rivers_run(&d, NULL, NULL, &o) == FB_OK);
    REQUIRE(o.receiver != NULL);
    fb_rivers_amp a;
    REQUIRE(fb_rivers_amp_init(&a, &d, &o, W, H, 0.6) == FB_OK);
    size_t n = (size_t)W * H;
    float *Y = malloc(n * 4), *area = malloc(n * 4), *river = malloc(n * 4), *lake = malloc(n * 4),
          *row = malloc(W * 4);
    REQUIRE(Y && area && river && lake && row);
    fb_rivers_amp_rows(&a, 0, H, Y, area, river, lake);
    size_t pits = 0, wet = 0, bad_sea = 0, rivers = 0;
    for (int y = 1; y < H - 1; y++)
        for (int x = 1; x < W - 1; x++) {
            size_t i = (size_t)y * W + x;
            bool lower = false;
            for (int dy = -1; dy <= 1; dy++)
                for (int dx = -1; dx <= 1; dx++) lower = lower || Y[i + (ptrdiff_t)dy * W + dx] < Y[i];
            pits += !lower && !(lake[i] > 0);
            wet += lake[i] > 0, rivers += river[i] > 0;
            if (sea && Y[i] < d.sea_level) bad_sea += !(lake[i] > 0 && fabsf(lake[i] - (0 - Y[i])) <= 1e-3f);
        }
    CHECKF(pits * 10000 <= n, "keep %d sea %d: %zu pits in %zu pixels", keep, sea, pits, n);
    CHECKF(!sea || (wet > 0 && bad_sea == 0), "sea: %zu wet pixels, %zu below the level without its depth", wet,
           bad_sea);
    CHECKF(rivers > 0, "keep %d sea %d: no river pixel (%zu wet)", keep, sea, wet);
    bool same = true;
    for (int y = 0; y < H; y += 7) {
        fb_rivers_amp_rows(&a, y, 1, row, NULL, NULL, NULL);
        same = same && !memcmp(row, Y + (size_t)y * W, (size_t)W * 4);
    }
    CHECKF(same, "keep %d sea %d: a row alone differs", keep, sea);
    fb_rivers_amp_fini(&a);
    REQUIRE(fb_rivers_amp_init(&a, &d, &o, W, H, 0) == FB_OK);
    fb_rivers_amp_rows(&a, H / 2, 1, row, NULL, NULL, NULL);
    CHECKF(memcmp(row, Y + (size_t)(H / 2) * W, (size_t)W * 4) != 0, "the detail changes nothing");
    fb_rivers_amp_fini(&a);
    free(Y), free(area), free(river), free(lake), free(row), free(start);
    fb_rivers_out_free(&o);
}

/* Bad descriptions are refused, with nothing allocated for the caller. */
static void test_check(void)
{
    fb_rivers_desc d = base(8, 8);
    CHECK(fb_rivers_check(&d) == NULL);
    const double nan = NAN;
    struct {
        double *field, value;
    } bad[] = {{&d.K, -1}, {&d.m, 0}, {&d.m, 2.5}, {&d.n, 0}, {&d.dt, 0}, {&d.dt, nan}, {&d.kd, -1}, {&d.uplift, nan}};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        double keep = *bad[k].field;
        *bad[k].field = bad[k].value;
        CHECKF(fb_rivers_check(&d) != NULL, "case %zu accepted", k);
        *bad[k].field = keep;
    }
    d.steps = 0;
    CHECK(fb_rivers_check(&d) != NULL);
    d.steps = 1, d.outlets = 0;
    CHECK(fb_rivers_check(&d) != NULL);
    d.has_sea = true, d.sea_level = -1; /* a sea below every cell: no outlet at run time */
    fb_rivers_out o;
    CHECK(fb_rivers_run(&d, NULL, NULL, &o) == FB_ERR_INPUT);
}

int main(void)
{
    test_profile(1);
    test_profile(2);
    test_profile(0.7);
    test_diffusion();
    test_fill(false, false);
    test_fill(true, false);
    test_fill(false, true);
    test_fill(true, true);
    test_threads();
    test_amplify(false, false);
    test_amplify(true, false);
    test_amplify(false, true);
    test_check();
    TEST_REPORT();
}
