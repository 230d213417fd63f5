/*
 * Division and square root rounded the same on every device.
 *
 * A Vulkan device computes add, subtract and multiply correctly rounded (with NoContraction on every
 * operation: the build's SPIR-V pass, cmake/spvexact.c, decorates each one), but OpFDiv only to
 * 2.5 ulp and sqrt as 1 / inversesqrt ("Precision of Individual Operations", the Vulkan
 * specification's SPIR-V environment appendix). C's `/` and sqrtf are IEEE 754's correctly rounded
 * operations. So a kernel divides and takes square roots only through these helpers:
 *
 *   kx_div(a, b)   a / b, correctly rounded (to nearest, ties to even), subnormals kept
 *   kx_sqrt(x)     sqrt(x), the same
 *
 * In C they are the operators themselves. In a shader they are the device's own operation where
 * the host knows it to be correctly rounded (the specialisation constant K_EXACT_NATIVE: lavapipe,
 * whose LLVM code divides with the CPU's IEEE instructions), and elsewhere an exact residual
 * correction: the device's quotient (or root) of the significands gives a candidate integer
 * significand q, the exact remainder N - q d (or N - q^2) corrects it to the true floor, and the
 * remainder then decides the rounding, the tie and a subnormal result's shift. The remainder is
 * small (a few times the divisor), so the low 32 bits of both 48-bit products carry it exactly:
 * plain uint arithmetic, which wraps the same in both languages. NaN, infinity and zero give x86's
 * answers (a NaN operand comes back quieted, 0/0, inf/inf and sqrt(-x) the default NaN
 * 0xffc00000), so that the bits match the native path's SSE instructions.
 *
 * Functions named kx_* are the only places where the SPIR-V audit (tests/spirv_audit.py) lets an
 * inexact instruction stand, and no inexact result leaves them uncorrected.
 */
#ifndef FB_KERNELS_EXACT_H
#define FB_KERNELS_EXACT_H

#include "common.h"

/* The specialisation constant that says the device's division and square root are correctly
 * rounded (host/io/vkc_work.c sets it on every pipeline). */
#define K_SPEC_EXACT_NATIVE 127

#ifdef K_GLSL
#define K_DOUBLE(x) double(x)
#else
#define K_DOUBLE(x) ((double)(x))
#endif

#ifdef K_GLSL
layout(constant_id = K_SPEC_EXACT_NATIVE) const bool K_EXACT_NATIVE = false;
#define kx_msb(x) findMSB(x)
#else
#define kx_msb(x) (31 - __builtin_clz(x))
#endif

/* The device's own quotient and root, used only as the first estimate of the portable paths (a
 * test build perturbs them by a few ulp through KX_TEST_ESTIMATE to exercise the correction). */
#ifdef KX_TEST_ESTIMATE
#define kx_estimate(v) KX_TEST_ESTIMATE(v)
#else
#define kx_estimate(v) (v)
#endif

/* The quotient of a NaN, infinite or zero operand (x86's answers), or 1u where both operands are
 * finite and nonzero (1u is no such answer: a positive subnormal never comes out of here). */
K_FN uint kx_div_special(uint ua, uint ub)
{
    uint s = (ua ^ ub) & 0x80000000u;
    uint aa = ua & 0x7fffffffu, ab = ub & 0x7fffffffu;
    if (aa > 0x7f800000u) return ua | 0x400000u; /* a NaN operand, quieted: a's first */
    if (ab > 0x7f800000u) return ub | 0x400000u;
    if (aa == 0x7f800000u) return ab == 0x7f800000u ? 0xffc00000u : s | 0x7f800000u;
    if (ab == 0x7f800000u) return s;
    if (ab == 0u) return aa == 0u ? 0xffc00000u : s | 0x7f800000u;
    if (aa == 0u) return s;
    return 1u;
}

/* |x| = m 2^(e - 150) for finite nonzero bits ux, m in [2^23, 2^24): the pair (m, e + 1024). */
K_FN uint kx_significand(uint ux)
{
    uint ex = (ux >> 23u) & 255u, f = ux & 0x7fffffu;
    if (ex != 0u) return f | 0x800000u;
    return f << K_U(23 - kx_msb(f));
}
K_FN int kx_exponent(uint ux)
{
    uint ex = (ux >> 23u) & 255u, f = ux & 0x7fffffu;
    if (ex != 0u) return K_I(ex);
    return 1 - (23 - kx_msb(f));
}

/* The bits of s q 2^(E - 150) (q in [2^23, 2^24), E the biased exponent it would have) plus the
 * fraction rem / den < 1 of a unit of q, rounded to nearest even, subnormal or infinite as it falls. */
K_FN uint kx_round(uint s, uint q, int E, uint rem2, uint den)
{
    /* rem2 = 2 rem: compared with den it says below, at or above half a unit */
    if (E >= 1) {
        bool up = rem2 > den || (rem2 == den && (q & 1u) != 0u);
        q += up ? 1u : 0u;
        if (q == 0x1000000u) {
            q = 0x800000u;
            E += 1;
        }
        if (E >= 255) return s | 0x7f800000u;
        return s | (K_U(E) << 23u) | (q & 0x7fffffu);
    }
    int k = 1 - E; /* the subnormal's shift */
    if (k > 24) return s;
    uint m = q >> K_U(k);
    uint low = q & ((1u << K_U(k)) - 1u), halfway = 1u << K_U(k - 1);
    bool up = low > halfway || (low == halfway && (rem2 != 0u || (m & 1u) != 0u));
    return s | (m + (up ? 1u : 0u)); /* m + 1 = 2^23 is the smallest normal's bits: right */
}

/* a / b on the portable path. */
K_FN float kx_div_soft(float a, float b)
{
    uint ua = k_float_bits(a), ub = k_float_bits(b);
    uint sp = kx_div_special(ua, ub);
    if (sp != 1u) return k_bits_float(sp);
    uint ma = kx_significand(ua), mb = kx_significand(ub);
    int e = kx_exponent(ua) - kx_exponent(ub); /* a / b = (ma / mb) 2^e */
    if (ma < mb) {
        ma = ma << 1u; /* ma / mb in [1, 2) */
        e -= 1;
    }
    /* the estimate: both significands are exact floats, their quotient in [1, 2] within a few ulp */
    float est = kx_estimate(K_F(ma) / K_F(mb));
    uint q = K_U(k_clamp(est, 1.0f, 1.99999988f) * 8388608.0f); /* ~ floor(ma 2^23 / mb) */
    /* the remainder ma 2^23 - q mb, exact in the low 32 bits (|r| < 2^31) */
    int r = K_I((ma << 23u) - q * mb);
    int d = K_I(mb);
    while (r < 0) {
        q -= 1u;
        r += d;
    }
    while (r >= d) {
        q += 1u;
        r -= d;
    }
    uint s = (ua ^ ub) & 0x80000000u;
    return k_bits_float(kx_round(s, q, e + 127, K_U(r) << 1u, mb));
}

/* sqrt(x) on the portable path. */
K_FN float kx_sqrt_soft(float x)
{
    uint ux = k_float_bits(x);
    uint ax = ux & 0x7fffffffu;
    if (ax > 0x7f800000u) return k_bits_float(ux | 0x400000u); /* NaN, quieted */
    if (ax == 0u) return x;                                    /* +-0 */
    if ((ux >> 31u) != 0u) return k_bits_float(0xffc00000u);   /* negative */
    if (ax == 0x7f800000u) return x;                           /* +inf */
    uint m = kx_significand(ux);
    int t = kx_exponent(ux) - 150; /* x = m 2^t */
    /* N = m 2^k in [2^46, 2^48) with t - k even: sqrt(x) = sqrt(N) 2^((t - k) / 2) */
    uint k = 23u + K_U((t + 1) & 1);
    float est = kx_estimate(k_sqrt(K_F(m) * (k == 23u ? 8388608.0f : 16777216.0f)));
    uint q = K_U(k_clamp(est, 8388608.0f, 16777215.0f));
    /* N - q^2, exact in the low 32 bits: the estimate is within a few ulp of sqrt(N) < 2^24 */
    uint nlo = m << k;
    int r = K_I(nlo - q * q);
    while (r < 0) {
        q -= 1u;
        r += K_I(2u * q + 1u);
    }
    while (r >= K_I(2u * q + 1u)) {
        r -= K_I(2u * q + 1u);
        q += 1u;
    }
    /* sqrt(N) rounds up when N > (q + 1/2)^2 = q^2 + q + 1/4, that is r > q (never a tie) */
    if (K_U(r) > q) q += 1u;
    int E = (t - K_I(k) + 512) / 2 - 256 + 23 + 127;
    if (q == 0x1000000u) {
        q = 0x800000u;
        E += 1;
    }
    return k_bits_float((K_U(E) << 23u) | (q & 0x7fffffu));
}

/* ---- double precision (shaders that define K_F64: a julia layer's "precision": "double") -------
 * kx_ddiv(a, b): a / b in double, correctly rounded. A device's double operations are only required
 * to be as precise as its single ones, but add, subtract and multiply are correctly rounded on every
 * device with shaderFloat64 we know of; division is not. The portable path scales both significands
 * into [1, 2), refines the device's quotient twice with Dekker's exact product (Veltkamp's split:
 * no fma, whose fusion Vulkan leaves open), then settles the last ulp from the exact remainder
 * a - q b against half an ulp of b: the nearest double, ties to even. Subnormal quotients (below
 * 2^-1022) are the one case it may round twice; no kernel divides into that range. */
#if !defined(K_GLSL) || defined(K_F64)

#ifdef K_GLSL
#define kx_dhi(d)        unpackDouble2x32(d).y
#define kx_dlo(d)        unpackDouble2x32(d).x
#define kx_dbits(hi, lo) packDouble2x32(uvec2(lo, hi))
#define kx_destimate(v)  (v)
#else
static inline uint kx_dhi(double d)
{
    uint64_t u;
    memcpy(&u, &d, 8);
    return (uint)(u >> 32);
}
static inline uint kx_dlo(double d)
{
    uint64_t u;
    memcpy(&u, &d, 8);
    return (uint)u;
}
static inline double kx_dbits(uint hi, uint lo)
{
    uint64_t u = ((uint64_t)hi << 32) | lo;
    double d;
    memcpy(&d, &u, 8);
    return d;
}
#ifdef KX_TEST_DESTIMATE
#define kx_destimate(v) KX_TEST_DESTIMATE(v)
#else
#define kx_destimate(v) (v)
#endif
#endif

/* x y - p exactly, for p the rounded product x y (Dekker's TwoProduct, |x|, |y| < 2^900). */
K_FN double kx_dprod_err(double x, double y, double p)
{
    K_PRECISE double c = K_DOUBLE(134217728.0f) + K_DOUBLE(1.0f); /* 2^27 + 1 */
    K_PRECISE double t = c * x;
    K_PRECISE double xh = t - (t - x);
    K_PRECISE double xl = x - xh;
    t = c * y;
    K_PRECISE double yh = t - (t - y);
    K_PRECISE double yl = y - yh;
    K_PRECISE double e = (((xh * yh - p) + xh * yl) + xl * yh) + xl * yl;
    return e;
}

/* a - q b exactly, where q b is within a factor 2 of a and the difference is a double. */
K_FN double kx_dremainder(double a, double q, double b)
{
    K_PRECISE double p = q * b;
    K_PRECISE double r = (a - p) - kx_dprod_err(q, b, p);
    return r;
}

K_FN double kx_ddiv_soft(double a, double b)
{
    uint ha = kx_dhi(a), hb = kx_dhi(b);
    uint ea = (ha >> 20u) & 2047u, eb = (hb >> 20u) & 2047u;
    /* zero, subnormal, infinite or NaN operands: the device's own answer (exact for these) */
    if (ea == 0u || eb == 0u || ea == 2047u || eb == 2047u) return a / b;
    /* A = |a| and B = |b| scaled into [1, 2): a / b = +-(A / B) 2^(ea - eb) */
    K_PRECISE double A = kx_dbits((ha & 0xfffffu) | 0x3ff00000u, kx_dlo(a));
    K_PRECISE double B = kx_dbits((hb & 0xfffffu) | 0x3ff00000u, kx_dlo(b));
    K_PRECISE double q = kx_destimate(A / B);
    q = q + kx_destimate(kx_dremainder(A, q, B) / B);
    q = q + kx_destimate(kx_dremainder(A, q, B) / B);
    /* q is now within an ulp of A / B, in [1/2, 2]: the remainders below are exact */
    for (int i = 0; i < 2; i++) {
        uint hq = kx_dhi(q), lq = kx_dlo(q);
        uint eq = (hq >> 20u) & 2047u;
        K_PRECISE double hu = kx_dbits((eq - 53u) << 20u, 0u) * B; /* half an ulp of q, times B */
        bool pow2 = (hq & 0xfffffu) == 0u && lq == 0u;
        K_PRECISE double hd = pow2 ? hu * K_DOUBLE(0.5f) : hu;
        K_PRECISE double r = kx_dremainder(A, q, B);
        bool odd = (lq & 1u) != 0u;
        if (r > hu || (r == hu && odd)) /* the next double up */
            q = kx_dbits(hq + (lq == 0xffffffffu ? 1u : 0u), lq + 1u);
        else if (-r > hd || (-r == hd && odd)) /* the next one down */
            q = kx_dbits(hq - (lq == 0u ? 1u : 0u), lq - 1u);
    }
    /* the exponent back: q 2^(ea - eb), as long as the result stays normal */
    int e = K_I((kx_dhi(q) >> 20u) & 2047u) + K_I(ea) - K_I(eb);
    if (e <= 0 || e >= 2047) return a / b;
    uint s = (ha ^ hb) & 0x80000000u;
    return kx_dbits(s | (K_U(e) << 20u) | (kx_dhi(q) & 0xfffffu), kx_dlo(q));
}

#ifdef K_GLSL
K_FN double kx_ddiv(double a, double b)
{
    if (K_EXACT_NATIVE) return a / b;
    return kx_ddiv_soft(a, b);
}
#else
K_FN double kx_ddiv(double a, double b)
{
    return a / b;
}
#endif

#endif

#ifdef K_GLSL
K_FN float kx_div(float a, float b)
{
    if (K_EXACT_NATIVE) return a / b;
    return kx_div_soft(a, b);
}
K_FN float kx_sqrt(float x)
{
    if (K_EXACT_NATIVE) return sqrt(x);
    return kx_sqrt_soft(x);
}
#else
K_FN float kx_div(float a, float b)
{
    return a / b;
}
K_FN float kx_sqrt(float x)
{
    return sqrtf(x);
}
#endif

#endif
