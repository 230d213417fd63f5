/*
 * log2, exp2 and pow in float arithmetic only, written once for C and GLSL, so that the scalar
 * kernel, its AVX2 lanes (host/gen/julia/layer_avx2.c: the same operations in the same order, eight
 * at a time) and a shader give the same bits: libm's log2f and powf cannot run on SIMD lanes as
 * they are, and a device's log2 and pow may differ from them by 3 ulp or more (Vulkan's bounds).
 *
 * log2: Moshier's Cephes log2f (single precision): x = m 2^e with m in [sqrt(1/2), sqrt(2)), then
 * log2(m) from a polynomial in f = m - 1 with log2(e) added in parts, e last. exp2: Cephes exp2f's
 * polynomial on [-1/2, 1/2], scaled by 2^k in two factors (so subnormal results round once). pow:
 * exp2(y log2 x) with y e split exactly (Veltkamp) and the integer part taken out before the
 * rounding of the small part, so that the product does not cost |y log2 x| ulp. Measured against
 * double-precision references (tests/test_explog.c): log2 within 1.5 ulp (1.31 found), exp2 within 2;
 * pow within 2 ulp for exponents up to 2 (1.9 found), 3 up to 4 (2.5), 8 up to 16 (7.8), where
 * libm's powf is within 0.51 and the same in 75 to 88% of the inputs for exponents from 1.5 to 4.
 * The polynomials go by Estrin's scheme: the latency of one pixel's tail is what the scalar loop
 * waits on.
 *
 * Every operation `precise` (no fused multiply-add on either side); the constants are written with
 * few enough digits that C and glslang (which reads them as double first) round them alike.
 */
#ifndef FB_KERNELS_EXPLOG_H
#define FB_KERNELS_EXPLOG_H

#include "common.h"

/* log2 x = e + t for x > 0 finite (subnormals included): (e, t), e an integer, |t| <= 0.5. */
K_FN k_vec2 k_log2_parts(float x)
{
    bool sub = x < 1.17549435e-38f;
    K_PRECISE float xs = sub ? x * 16777216.0f : x;
    uint b = k_float_bits(xs);
    int e = K_I(b >> 23u) - (sub ? 150 : 126); /* xs = m 2^e, m in [1/2, 1) */
    float m = k_bits_float((b & 0x007fffffu) | 0x3f000000u);
    bool low = m < 0.70710678f;
    K_PRECISE float f = low ? (m + m) - 1.0f : m - 1.0f; /* exact */
    e = low ? e - 1 : e;
    K_PRECISE float z = f * f;
    /* Cephes' polynomial of degree 8 by Estrin's scheme (pairs, then powers of z): half the
     * dependent steps of Horner's, for the latency of one pixel's tail */
    K_PRECISE float z2 = z * z;
    K_PRECISE float p01 = 7.0376836292e-2f * f + -1.1514610310e-1f;
    K_PRECISE float p23 = 1.1676998740e-1f * f + -1.2420140846e-1f;
    K_PRECISE float p45 = 1.4249322787e-1f * f + -1.6668057665e-1f;
    K_PRECISE float p67 = 2.0000714765e-1f * f + -2.4999993993e-1f;
    K_PRECISE float q = ((p01 * z + p23) * z2 + (p45 * z + p67)) * f + 3.3333331174e-1f;
    K_PRECISE float y = f * (z * q);
    y = y + -0.5f * z;
    /* (y + f) log2(e), with log2(e) = 1 + 0.44269504...: the 1 added exactly last */
    K_PRECISE float t = y * 0.44269504f;
    t = t + f * 0.44269504f;
    t = t + y;
    t = t + f;
    return k_vec2(K_F(e), t);
}

K_FN float k_log2_poly(float x)
{
    k_vec2 l = k_log2_parts(x);
    K_PRECISE float r = l.y + l.x;
    return r;
}

/* 2^(r + k) for |r| <= 1/2 and an integer k in [-151, 129] (beyond: 0 or infinity, as rounded). */
K_FN float k_exp2_split(float r, float k)
{
    K_PRECISE float r2 = r * r;
    K_PRECISE float pa = 1.535336188e-4f * r + 1.339887440e-3f;
    K_PRECISE float pb = 9.618437357e-3f * r + 5.550332471e-2f;
    K_PRECISE float pc = 2.402264791e-1f * r + 6.931472028e-1f;
    K_PRECISE float p = ((pa * r2 + pb) * r2 + pc) * r + 1.0f; /* Estrin's scheme */
    /* 2^k as 2^k1 2^k2, both normal: the second product rounds a subnormal result once */
    float k1 = k_floor(k * 0.5f), k2 = k - k1;
    float s1 = k_bits_float(K_U(K_I(k1) + 127) << 23u), s2 = k_bits_float(K_U(K_I(k2) + 127) << 23u);
    K_PRECISE float v = (p * s1) * s2;
    return v;
}

K_FN float k_exp2_poly(float x)
{
    K_PRECISE float t = k_clamp(x, -151.0f, 129.0f);
    K_PRECISE float k = k_floor(t + 0.5f);
    K_PRECISE float r = t - k; /* exact */
    return k_exp2_split(r, k);
}

/* x^y for x >= 0 and 0 < y <= 10^4: exp2(y (e + t)), y e = a + b exactly (y split into two 12-bit
 * halves, e has at most 8 bits), the integer part of a taken out exactly before the rest is
 * rounded. x = 0 by a select, not a branch (a shader runs both sides of a branch in every lane). */
K_FN float k_pow_poly(float x, float y)
{
    k_vec2 l = k_log2_parts(x);
    K_PRECISE float c = 4097.0f * y;
    K_PRECISE float yh = c - (c - y);
    K_PRECISE float yl = y - yh;
    K_PRECISE float a = yh * l.x;           /* exact */
    K_PRECISE float b = yl * l.x + y * l.y; /* yl e exact; |b| < y */
    K_PRECISE float k1 = k_floor(a + 0.5f); /* |a| < 2^23 */
    K_PRECISE float s = (a - k1) + b;       /* a - k1 exact */
    K_PRECISE float k2 = k_floor(s + 0.5f);
    K_PRECISE float r = s - k2; /* exact */
    K_PRECISE float k = k_clamp(k1 + k2, -151.0f, 129.0f);
    float v = k_exp2_split(r, k);
    return x == 0.0f ? 0.0f : v;
}

#endif
