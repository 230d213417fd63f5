/*
 * kernels/explog.h against double-precision references: the accuracy its header states (log2
 * within 1.5 ulp, exp2 within 2 ulp, pow within 2, 3 and 8 ulp for exponents up to 2, 4 and 16),
 * the exact values (log2 of powers of two, exp2 of integers, pow(0, y), pow(1, y)), subnormal inputs
 * and results, and that every constant in it reads the same in C and as glslang reads it (a double
 * first, then rounded to float), so a shader gets the same polynomial.
 */
#include "../kernels/explog.h"

#include "testhelp.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The error of got in ulps of the float nearest to want (subnormals: in units of 2^-149). */
static double ulps(float got, double want)
{
    double a = fabs(want);
    double u = ldexp(1.0, -149);
    if (a >= ldexp(1.0, -126)) {
        int e;
        frexp(a, &e);
        u = ldexp(1.0, e - 24);
    }
    return fabs((double)got - want) / u;
}

static float from_bits(uint32_t b)
{
    float x;
    memcpy(&x, &b, 4);
    return x;
}

int main(void)
{
    /* log2 on a stride through every positive finite float, subnormals included */
    double worst = 0;
    float at = 0;
    for (uint32_t b = 1; b < 0x7f800000u; b += 1021) {
        float x = from_bits(b);
        double e = ulps(k_log2_poly(x), log2((double)x));
        if (e > worst) worst = e, at = x;
    }
    CHECKF(worst <= 1.5, "log2: %.3f ulp at %a", worst, at);
    int exact = 0;
    for (int k = -149; k <= 127; k++) exact += k_log2_poly(ldexpf(1.0f, k)) == (float)k;
    CHECKF(exact == 277, "log2 of powers of two: %d of 277 exact", exact);

    /* exp2 over its whole range, down into subnormal results */
    worst = 0;
    for (float x = -149.0f; x < 127.99f; x += 0.00371f) {
        double e = ulps(k_exp2_poly(x), exp2((double)x));
        if (e > worst) worst = e, at = x;
    }
    CHECKF(worst <= 2.0, "exp2: %.3f ulp at %a", worst, at);
    exact = 0;
    for (int k = -149; k <= 127; k++) exact += k_exp2_poly((float)k) == ldexpf(1.0f, k);
    CHECKF(exact == 277, "exp2 of integers: %d of 277 exact", exact);
    CHECK(k_exp2_poly(128.5f) == INFINITY && k_exp2_poly(-200.0f) == 0.0f && k_exp2_poly(1e30f) == INFINITY);

    /* pow: the colour's weights (x in [2^-6, 1]) and gammas (x up to 32), several exponents */
    static const float ys[] = {0.25f, 0.5f, 1.0f, 1.5f, 2.0f, 2.2f, 2.5f, 3.0f, 4.0f, 7.3f, 10.0f, 16.0f};
    for (int k = 0; k < (int)(sizeof ys / sizeof ys[0]); k++) {
        const float y = ys[k];
        const double bound = y <= 2.0f ? 2.0 : y <= 4.0f ? 3.0 : 8.0;
        double w = 0;
        for (uint32_t b = 0x3c800000u; b <= 0x42000000u; b += 53) {
            float x = from_bits(b);
            double ref = pow((double)x, (double)y);
            if (ref > 3.0e38) break;
            double e = ulps(k_pow_poly(x, y), ref);
            if (e > w) w = e, at = x;
        }
        CHECKF(w <= bound, "pow(x, %g): %.3f ulp at %a (bound %g)", y, w, at, bound);
        CHECKF(k_pow_poly(0.0f, y) == 0.0f && k_pow_poly(1.0f, y) == 1.0f, "pow(0 or 1, %g)", y);
    }
    /* results in the subnormal range and beyond the largest float */
    CHECKF(ulps(k_pow_poly(1e-20f, 2.0f), 1e-40) <= 2.0, "pow(1e-20, 2) = %a", k_pow_poly(1e-20f, 2.0f));
    CHECK(k_pow_poly(1e-30f, 2.0f) == 0.0f && k_pow_poly(1e20f, 2.0f) == INFINITY);
    CHECKF(ulps(k_pow_poly(1e-40f, 0.5f), sqrt((double)1e-40f)) <= 2.0, "pow(1e-40, 0.5) = %a",
           k_pow_poly(1e-40f, 0.5f));

    /* the constants as C and glslang read them */
    static const char *const lits[] = {"1.17549435e-38",  "16777216.0",      "0.70710678",      "7.0376836292e-2",
                                       "1.1514610310e-1", "1.1676998740e-1", "1.2420140846e-1", "1.4249322787e-1",
                                       "1.6668057665e-1", "2.0000714765e-1", "2.4999993993e-1", "3.3333331174e-1",
                                       "0.44269504",      "1.535336188e-4",  "1.339887440e-3",  "9.618437357e-3",
                                       "5.550332471e-2",  "2.402264791e-1",  "6.931472028e-1",  "4097.0"};
    int same = 0;
    for (int i = 0; i < 20; i++) same += strtof(lits[i], NULL) == (float)strtod(lits[i], NULL);
    CHECKF(same == 20, "%d of 20 constants read alike as float and as double then float", same);
    TEST_REPORT();
}
