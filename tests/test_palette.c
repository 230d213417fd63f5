/* Palettes and sky colour: the table reproduces cosine formulas and gradient stops (computed here
 * independently), the palette position never jumps, and the density weight does what it says. */
#include "../kernels/palette.h"
#include "palette.h"

#include "testhelp.h"

#include <math.h>
#include <string.h>

static float table[FB_PALETTE_ENTRIES][4];

static void test_cosine(void)
{
    fb_palette_spec s = {.has_cosine = true, .cosine = {0.5, 0.4, 0.3, 0.5, 0.2, 0.1, 1, 2, 0.5, 0.0, 0.25, 0.5}};
    fb_palette_build(&s, table);
    double worst = 0;
    for (int i = 0; i < FB_PALETTE_ENTRIES; i++) {
        double t = i / 255.0;
        for (int c = 0; c < 3; c++) {
            double want = s.cosine[c] + s.cosine[3 + c] * cos(2 * M_PI * (s.cosine[6 + c] * t + s.cosine[9 + c]));
            worst = fmax(worst, fabs(table[i][c] - fmax(want, 0)));
        }
    }
    CHECKF(worst < 1e-6, "cosine palette off by %g", worst);
}

static void test_stops(void)
{
    fb_palette_spec s = {.nstops = 3, .stops = {{0, 0, 0, 0}, {0.25, 1, 0.5, 0}, {1, 0, 1, 2}}};
    fb_palette_build(&s, table);
    CHECK(table[0][0] == 0 && table[0][2] == 0);
    CHECK(table[255][0] == 0 && table[255][1] == 1 && table[255][2] == 2);
    /* t = 0.125 sits halfway into the first segment: entry 255 * 0.125 = 31.875, so compare at i = 51
     * (t = 0.2): 0.8 of the way from stop 0 to stop 1 */
    CHECK(fabsf(table[51][0] - 0.8f) < 1e-6f && fabsf(table[51][1] - 0.4f) < 1e-6f);
    /* past the middle stop: t = 0.625 (i ~ 159.4; use i = 170, t = 2/3): (t - 0.25) / 0.75 = 5/9 */
    double f = (170 / 255.0 - 0.25) / 0.75;
    CHECK(fabs(table[170][0] - (1 - f)) < 1e-6 && fabs(table[170][2] - 2 * f) < 1e-6);
    for (int named = 0; named < 6; named++) {
        fb_palette_spec n = {.named = named};
        fb_palette_build(&n, table);
        bool ok = true;
        for (int i = 0; i < FB_PALETTE_ENTRIES; i++)
            for (int c = 0; c < 3; c++) ok = ok && isfinite(table[i][c]) && table[i][c] >= 0;
        CHECKF(ok, "named palette %d has a negative or non-finite entry", named);
    }
}

static K_SkyColour colour(void)
{
    K_SkyColour c;
    memset(&c, 0, sizeof c);
    c.inv_period = 1.0f / 24.0f;
    c.brightness = 1.0f;
    c.gamma = 1.0f;
    c.density = 1.5f;
    c.inv_n_ref = 1.0f / 48.0f;
    return c;
}

/* The palette position is a triangle wave in [0, 255]: continuous, no jump where it repeats. */
static void test_position(void)
{
    K_SkyColour c = colour();
    float prev = k_palette_pos(c, 0.0f), worst = 0, lo = 1e9f, hi = -1e9f;
    for (int i = 1; i < 20000; i++) {
        float p = k_palette_pos(c, i * 0.01f);
        worst = fmaxf(worst, fabsf(p - prev));
        lo = fminf(lo, p), hi = fmaxf(hi, p);
        prev = p;
    }
    /* slope 255 / 24 per count unit: 0.01 units move at most 0.107 */
    CHECKF(worst < 0.11f, "palette position jumps by %g", worst);
    CHECK(lo == 0.0f && hi == 255.0f);
}

/* Weight: 0 at count 0, 1 from n_ref on, rising; a higher density darkens everything below n_ref. */
static void test_density(void)
{
    K_SkyColour c = colour(), d = colour();
    d.density = 4.0f;
    CHECK(k_sky_weight(c, 0.0f) == 0.0f && k_sky_weight(c, 48.0f) == 1.0f && k_sky_weight(c, 500.0f) == 1.0f);
    int bad = 0;
    for (int i = 1; i < 480; i++) {
        float n = i * 0.1f;
        bad += !(k_sky_weight(c, n) > k_sky_weight(c, n - 0.1f));
        bad += !(k_sky_weight(d, n) < k_sky_weight(c, n));
    }
    CHECKF(bad == 0, "%d weight violations", bad);
    c.gamma = 2.0f;
    c.brightness = 2.0f;
    CHECK(fabsf(k_sky_channel(c, 0.5f, 0.5f) - 0.25f) < 1e-6f); /* (2 * 0.5 * 0.5)^2 */
}

int main(void)
{
    test_cosine();
    test_stops();
    test_position();
    test_density();
    TEST_REPORT();
}
