/*
 * kernels/kmath.h, the float-only exp, log, pow, atan2, tan, sinh, cosh, asin, acos (and fmod) that
 * the flame's kernel uses in C and in the shader alike: within a few ulp of libm in double over the
 * ranges a chain visits, and IEEE's answers at the edges (0, infinities, NaN, beyond [-1, 1]). And
 * every float literal of the flame's kernels (flame.h, flame_var.h, kmath.h, sincos.h) reads the same
 * in C (straight to float) as in glslang (a double first, then rounded to float), so that a shader
 * computes with the same constants.
 *
 * Usage: test_kmath SOURCE_DIR
 */
#include "../kernels/hash.h"
#include "../kernels/kmath.h"

#include "testhelp.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Error of got against the double want, in ulps of want's float (relative to the smallest normal
 * below it). */
static double ulps(float got, double want)
{
    float w = (float)want;
    double u = nextafterf(fabsf(w), INFINITY) - fabsf(w);
    if (u < 1.1754944e-38 * 1.1920929e-7) u = 1.1754944e-38 * 1.1920929e-7;
    return fabs(got - want) / u;
}

static void accuracy(void)
{
    enum { N = 12 };
    double worst[N] = {0};
    uint32_t h = 12345;
    for (int i = 0; i < 1000000; i++) {
        float a = k_u01(h = k_hash(h)) * 2 - 1, b = k_u01(h = k_hash(h)) * 2 - 1, c = k_u01(h = k_hash(h));
        float x = a * 80, y = b * 80, p = c * 200 + 1e-30f, s = a * 3, big = b * 88;
        k_vec2 sh = k_xsinhcosh(big);
        double e[N] = {ulps(k_xexp(x), exp(x)),
                       ulps(k_xlog(p), log(p)),
                       ulps(k_xatan2(y, x), atan2(y, x)),
                       ulps(k_xtan(s * 0.5f), tan(s * 0.5f)),
                       ulps(k_xsinh(s), sinh(s)),
                       ulps(k_xcosh(s), cosh(s)),
                       ulps(k_xpow(c * 4, b * 6), pow(c * 4, b * 6)),
                       ulps(k_xsin(x), sin(x)),
                       ulps(k_xasin(a), asin(a)),
                       ulps(k_xacos(a), acos(a)),
                       ulps(sh.x, sinh(big)),
                       ulps(sh.y, cosh(big))};
        for (int k = 0; k < N; k++)
            if (e[k] > worst[k]) worst[k] = e[k];
    }
    const char *name[N] = {"exp", "log", "atan2", "tan",  "sinh",          "cosh",
                           "pow", "sin", "asin",  "acos", "sinhcosh sinh", "sinhcosh cosh"};
    /* pow: e^(y ln x) carries the rounding of y ln x, up to 90 here: about 0.6 ulp a unit of it */
    const double bound[N] = {2, 2, 4, 5, 3, 3, 64, 4, 3, 3, 3, 3};
    for (int k = 0; k < N; k++) {
        CHECKF(worst[k] <= bound[k], "k_x%s: %.2f ulp from libm", name[k], worst[k]);
        printf("k_x%-14s within %.2f ulp of libm (bound %g)\n", name[k], worst[k], bound[k]);
    }
}

static void edges(void)
{
    CHECK(k_xexp(-100.0f) == 0.0f && isinf(k_xexp(100.0f)) && k_xexp(0.0f) == 1.0f && isnan(k_xexp(NAN)));
    CHECK(isinf(k_xlog(0.0f)) && k_xlog(0.0f) < 0 && isnan(k_xlog(-1.0f)) && k_xlog(1.0f) == 0.0f);
    CHECK(isinf(k_xlog(INFINITY)) && isnan(k_xlog(NAN)) && isinf(k_xlog(1e-40f))); /* a subnormal reads as 0 */
    CHECK(k_xpow(0.0f, 2.0f) == 0.0f && k_xpow(0.0f, 0.0f) == 1.0f && isinf(k_xpow(0.0f, -1.0f)));
    CHECK(k_xpow(2.0f, 0.0f) == 1.0f && isnan(k_xpow(-2.0f, 0.5f)));
    CHECK(k_xatan2(0.0f, 0.0f) == 0.0f && k_xatan2(0.0f, -1.0f) == K_PI && k_xatan2(1.0f, 0.0f) == K_HALF_PI);
    CHECK(k_xatan2(-1.0f, 0.0f) == -K_HALF_PI && isnan(k_xatan2(NAN, 1.0f)));
    CHECK(fabsf(k_xatan2(INFINITY, INFINITY) - K_QUART_PI) < 1e-7f && k_xatan2(1.0f, INFINITY) == 0.0f);
    CHECK(k_xfmod(7.5f, 2.0f) == 1.5f && k_xfmod(-7.5f, 2.0f) == -1.5f);
    /* asin and acos: exact at 0 and +-1, NaN beyond */
    CHECK(k_xasin(0.0f) == 0.0f && k_xasin(1.0f) == K_HALF_PI && k_xasin(-1.0f) == -K_HALF_PI);
    CHECK(k_xacos(1.0f) == 0.0f && k_xacos(-1.0f) == K_PI && k_xacos(0.0f) == K_HALF_PI);
    CHECK(isnan(k_xasin(1.0000001f)) && isnan(k_xacos(-1.0000001f)) && isnan(k_xacos(NAN)) && isnan(k_xasin(NAN)));
    /* sinh and cosh past float's range: infinite, with sinh's sign */
    k_vec2 sh = k_xsinhcosh(-90.0f);
    CHECK(isinf(sh.x) && sh.x < 0 && isinf(sh.y) && sh.y > 0);
    CHECK(k_xsinhcosh(0.0f).x == 0.0f && k_xsinhcosh(0.0f).y == 1.0f);
    /* sincos beyond the int range (its quadrant was undefined as K_I(q) & 3, its reduction loses
     * everything): in [-1, 1] */
    for (float x = 3e9f; x < 1e12f; x *= 3.7f) {
        k_vec2 sc = k_sincos(x);
        CHECKF(fabsf(sc.x) <= 1 && fabsf(sc.y) <= 1, "k_sincos(%g) = (%g, %g)", x, sc.x, sc.y);
    }
}

/* Every float literal (digits, a point or an exponent, then f) of file `name` under dir. */
static void literals(const char *dir, const char *name)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/kernels/%s", dir, name);
    FILE *f = fopen(path, "rb");
    REQUIRE(f);
    static char text[1 << 20];
    size_t n = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[n] = 0;
    int seen = 0, same = 0;
    for (size_t i = 0; i < n; i++) {
        if (!isdigit((unsigned char)text[i]) || (i > 0 && (isalnum((unsigned char)text[i - 1]) || text[i - 1] == '_')))
            continue;
        char *end;
        strtod(text + i, &end);
        size_t len = (size_t)(end - (text + i));
        bool fl = *end == 'f' && memchr(text + i, '.', len) != NULL;
        fl |= *end == 'f' && (memchr(text + i, 'e', len) != NULL || memchr(text + i, 'E', len) != NULL);
        if (fl) {
            char lit[64];
            snprintf(lit, sizeof lit, "%.*s", (int)len, text + i);
            bool ok = strtof(lit, NULL) == (float)strtod(lit, NULL);
            CHECKF(ok, "%s: %s reads differently as float and as double then float", name, lit);
            seen++;
            same += ok;
        }
        i += len;
    }
    printf("%s: %d float literals, %d read alike\n", name, seen, same);
    CHECKF(seen > 0, "%s: no float literals found", name);
}

int main(int argc, char **argv)
{
    REQUIRE(argc == 2);
    accuracy();
    edges();
    const char *files[] = {"flame.h", "flame_var.h", "kmath.h", "sincos.h"};
    for (int k = 0; k < 4; k++) literals(argv[1], files[k]);
    TEST_REPORT();
}
