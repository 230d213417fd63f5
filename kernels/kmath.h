/*
 * exp, log, pow, atan2, tan, sinh, cosh, asin and acos in float arithmetic only (with sin and cos from
 * sincos.h), so that a shader and C give the same bits: libm and a device's built-ins differ in the
 * last bits (Vulkan allows exp and log 3 ulp, atan 4096 ulp, pow and the hyperbolics "inherited"
 * from exp and log), and a chaotic orbit amplifies any difference into other points. The algorithms
 * and coefficients are Cephes' single-precision ones (Stephen Moshier: expf.c, logf.c, atanf.c,
 * sinhf.c, asinf.c): within a few ulp of the true values. Every intermediate is `precise` (no fused
 * multiply-add on either side: C is built with -ffp-contract=off), and division and square root are
 * kernels/exact.h's kx_div and kx_sqrt, correctly rounded on every device. Exponents are taken and built
 * through the float's bits, never through ldexp or frexp (whose edge cases the two languages spell
 * differently); subnormal results are flushed to zero and subnormal arguments read as zero, as a
 * device with denormals flushed does.
 *
 * explog.h has log2, exp2 and pow too, for the Julia layer: they keep subnormals and come in an
 * AVX2 restatement, where these flush them (the flame's chaos game, scalar per chain). The two give
 * different bits, and each backend's output depends on its own, so merging them is a change of
 * output for one generator (its goldens and its tolerances), not a cleanup.
 */
#ifndef FB_KERNELS_KMATH_H
#define FB_KERNELS_KMATH_H

#include "exact.h"
#include "sincos.h"

#ifdef K_GLSL
#define k_trunc(x) trunc(x)
#else
#define k_trunc(x) truncf(x)
#endif

#define K_INF      k_bits_float(0x7f800000u)
#define K_NAN      k_bits_float(0x7fc00000u)
#define K_HALF_PI  1.5707963267948966f
#define K_QUART_PI 0.7853981633974483f

/* 2^n for n in [-126, 127], from its bits. */
K_FN float k_xexp2i(int n)
{
    return k_bits_float(K_U(n + 127) << 23u);
}

/* e^x (Cephes expf): x = n ln 2 + r, |r| <= ln 2 / 2, e^r by a polynomial, times 2^n. */
K_FN float k_xexp(float x)
{
    if (k_isnan(x)) return x;
    if (x > 88.72283905206835f) return K_INF;
    if (x < -87.33654475055310f) return 0.0f; /* below the smallest normal float */
    K_PRECISE float z = k_floor(1.44269504088896341f * x + 0.5f);
    K_PRECISE float r = (x - z * 0.693359375f) - z * -2.12194440e-4f;
    K_PRECISE float r2 = r * r;
    K_PRECISE float p =
        ((((((1.9875691500e-4f * r + 1.3981999507e-3f) * r + 8.3334519073e-3f) * r + 4.1665795894e-2f) * r +
           1.6666665459e-1f) *
              r +
          5.0000001201e-1f) *
             r2 +
         r) +
        1.0f;
    int n = K_I(z); /* -126 .. 128 */
    int h = n / 2;  /* both factors normal: 2^h 2^(n - h) */
    K_PRECISE float e = (p * k_xexp2i(h)) * k_xexp2i(n - h);
    return k_abs(e) < 1.17549435e-38f ? 0.0f : e;
}

/* ln x (Cephes logf): x = m 2^e with m in [sqrt(1/2), sqrt 2), ln m by a polynomial in m - 1. */
K_FN float k_xlog(float x)
{
    if (k_isnan(x)) return x;
    uint b = k_float_bits(x);
    uint be = (b >> 23u) & 255u;
    if (be == 0u) return -K_INF; /* zero or subnormal (read as zero), either sign */
    if ((b >> 31u) != 0u) return K_NAN;
    if (be == 255u) return x; /* +inf */
    int e = K_I(be) - 126;
    K_PRECISE float m = k_bits_float((b & 0x007fffffu) | 0x3f000000u); /* [0.5, 1) */
    if (m < 0.707106781186547524f) {
        e -= 1;
        m = (m + m) - 1.0f;
    } else {
        m = m - 1.0f;
    }
    K_PRECISE float z = m * m;
    K_PRECISE float y =
        ((((((((7.0376836292e-2f * m - 1.1514610310e-1f) * m + 1.1676998740e-1f) * m - 1.2420140846e-1f) * m +
             1.4249322787e-1f) *
                m -
            1.6668057665e-1f) *
               m +
           2.0000714765e-1f) *
              m -
          2.4999993993e-1f) *
             m +
         3.3333331174e-1f) *
        m * z;
    K_PRECISE float fe = K_F(e);
    y = y + fe * -2.12194440e-4f;
    y = y - 0.5f * z;
    K_PRECISE float r = m + y;
    r = r + fe * 0.693359375f;
    return r;
}

/* x^y for x >= 0 (every use in the kernels): e^(y ln x); 0^y is 0, 1 or inf; a negative x gives NaN. */
K_FN float k_xpow(float x, float y)
{
    if (x == 0.0f) return y > 0.0f ? 0.0f : y == 0.0f ? 1.0f : K_INF;
    if (y == 0.0f) return 1.0f;
    K_PRECISE float t = y * k_xlog(x);
    return k_xexp(t);
}

/* atan x (Cephes atanf): the argument reduced to |x| <= tan(pi/8), then a polynomial. */
K_FN float k_xatan(float x)
{
    K_PRECISE float a = k_abs(x);
    K_PRECISE float base = 0.0f;
    K_PRECISE float num = a;
    K_PRECISE float den = 1.0f;
    if (a > 2.414213562373095f) {
        base = K_HALF_PI;
        num = -1.0f;
        den = a;
    } else if (a > 0.4142135623730950f) {
        base = K_QUART_PI;
        num = a - 1.0f;
        den = a + 1.0f;
    }
    /* one division for both reductions (a shader inlines each call of kx_div) */
    if (base != 0.0f) a = kx_div(num, den);
    K_PRECISE float z = a * a;
    K_PRECISE float r =
        base +
        ((((8.05374449538e-2f * z - 1.38776856032e-1f) * z + 1.99777106478e-1f) * z - 3.33329491539e-1f) * z * a + a);
    return x < 0.0f ? -r : r;
}

/* atan2(y, x) in (-pi, pi] (Cephes atan2f's quadrants); NaN in, NaN out. */
K_FN float k_xatan2(float y, float x)
{
    if (k_isnan(x) || k_isnan(y)) return x + y;
    if (x == 0.0f) return y > 0.0f ? K_HALF_PI : y < 0.0f ? -K_HALF_PI : 0.0f;
    if (y == 0.0f) return x < 0.0f ? K_PI : 0.0f;
    if (k_isinf(x) || k_isinf(y)) {
        float ax = k_isinf(x) ? (x > 0.0f ? 0.0f : K_PI) : 0.0f;
        if (k_isinf(y)) ax = k_isinf(x) ? (x > 0.0f ? K_QUART_PI : 3.0f * K_QUART_PI) : K_HALF_PI;
        return y < 0.0f ? -ax : ax;
    }
    K_PRECISE float q = kx_div(y, x);
    K_PRECISE float w = x < 0.0f ? (y < 0.0f ? -K_PI : K_PI) : 0.0f;
    K_PRECISE float r = w + k_xatan(q);
    return r;
}

/* x - y trunc(x / y): C's fmod for moderate quotients (fmodf is exact, GLSL has only mod, which
 * floors); the same bits in both languages. */
K_FN float k_xfmod(float x, float y)
{
    K_PRECISE float r = x - y * k_trunc(kx_div(x, y));
    return r;
}

K_FN float k_xsin(float x)
{
    return k_sincos(x).x;
}

K_FN float k_xcos(float x)
{
    return k_sincos(x).y;
}

/* tan x = sin x / cos x. */
K_FN float k_xtan(float x)
{
    k_vec2 sc = k_sincos(x);
    K_PRECISE float t = kx_div(sc.x, sc.y);
    return t;
}

/* (sinh x, cosh x): sinh by a polynomial for |x| <= 1 (Cephes sinhf), (e^|x| - e^-|x|) / 2 beyond
 * (no division); cosh = (e^|x| + e^-|x|) / 2. */
K_FN k_vec2 k_xsinhcosh(float x)
{
    K_PRECISE float a = k_abs(x);
    K_PRECISE float ea = k_xexp(a);
    K_PRECISE float ena = k_xexp(-a);
    K_PRECISE float s;
    if (a <= 1.0f) {
        K_PRECISE float z = a * a;
        s = ((2.03721912945e-4f * z + 8.33028376239e-3f) * z + 1.66667160211e-1f) * z * a + a;
    } else {
        s = 0.5f * ea - 0.5f * ena;
    }
    K_PRECISE float c = 0.5f * ea + 0.5f * ena;
    return k_vec2(x < 0.0f ? -s : s, c);
}

K_FN float k_xsinh(float x)
{
    return k_xsinhcosh(x).x;
}

K_FN float k_xcosh(float x)
{
    return k_xsinhcosh(x).y;
}

/* asin x (Cephes asinf): a polynomial in x^2 for |x| <= 1/2, pi/2 - 2 asin(sqrt((1 - |x|) / 2))
 * beyond; NaN outside [-1, 1]. */
K_FN float k_xasin(float x)
{
    K_PRECISE float a = k_abs(x);
    if (!(a <= 1.0f)) return K_NAN;
    bool big = a > 0.5f;
    K_PRECISE float z = big ? 0.5f * (1.0f - a) : a * a;
    K_PRECISE float v = big ? kx_sqrt(z) : a;
    K_PRECISE float r = v;
    if (a >= 1e-4f)
        r = ((((4.2163199048e-2f * z + 2.4181311049e-2f) * z + 4.5470025998e-2f) * z + 7.4953002686e-2f) * z +
             1.6666752422e-1f) *
                z * v +
            v;
    if (big) r = K_HALF_PI - (r + r);
    return x < 0.0f ? -r : r;
}

/* acos x (Cephes acosf): pi - 2 asin(sqrt((1 + x) / 2)) below -1/2, 2 asin(sqrt((1 - x) / 2)) above
 * 1/2, pi/2 - asin x between; NaN outside [-1, 1]. */
K_FN float k_xacos(float x)
{
    if (!(x >= -1.0f && x <= 1.0f)) return K_NAN;
    K_PRECISE float r;
    if (x < -0.5f)
        r = K_PI - 2.0f * k_xasin(kx_sqrt(0.5f * (1.0f + x)));
    else if (x > 0.5f)
        r = 2.0f * k_xasin(kx_sqrt(0.5f * (1.0f - x)));
    else
        r = K_HALF_PI - k_xasin(x);
    return r;
}

#endif
