/*
 * The flame's xforms on AVX2 lanes: eight points through one xform at a time (host/gen/flame/game.c
 * groups the chains whose step chose the same xform), its affine map, flam3's precalcs, the
 * variations listed in fl_var_avx2 and the post transform, with kernels/kmath.h's sin, cos, exp,
 * sinh, cosh and atan2 restated on the lanes. Every operation is the scalar kernel's in the same
 * order (add, multiply, divide and square root are correctly rounded per lane, no FMA: the build
 * has -ffp-contract=off), each branch of the scalar code computed on every lane and blended, so each
 * lane's bits are those of k_flame_apply (kernels/flame.h) on that lane's point; tests/test_avx2.c
 * holds them to it. A lane whose result is a bad value is reported, not retried: its step is the
 * scalar one's (game.c replays it through k_flame_step).
 */
#ifndef FB_FLAME_AVX2_H
#define FB_FLAME_AVX2_H

#include "kernels/flame.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>

#define FL_AVX2 __attribute__((target("avx2")))

#define FL_S(v)      _mm256_set1_ps(v)
#define FL_ADD(a, b) _mm256_add_ps(a, b)
#define FL_SUB(a, b) _mm256_sub_ps(a, b)
#define FL_MUL(a, b) _mm256_mul_ps(a, b)
#define FL_DIV(a, b) _mm256_div_ps(a, b)

FL_AVX2 static inline __m256 fl_neg(__m256 a)
{
    return _mm256_xor_ps(a, _mm256_set1_ps(-0.0f));
}

FL_AVX2 static inline __m256 fl_abs(__m256 a)
{
    return _mm256_andnot_ps(_mm256_set1_ps(-0.0f), a);
}

FL_AVX2 static inline __m256 fl_isinf(__m256 a)
{
    return _mm256_cmp_ps(fl_abs(a), _mm256_set1_ps(K_INF), _CMP_EQ_OQ);
}

/* b where m is set, else a */
#define FL_SEL(a, b, m) _mm256_blendv_ps(a, b, m)

FL_AVX2 static inline __m256i fl_hash8(__m256i x)
{
    x = _mm256_xor_si256(x, _mm256_srli_epi32(x, 16));
    x = _mm256_mullo_epi32(x, _mm256_set1_epi32(0x7feb352d));
    x = _mm256_xor_si256(x, _mm256_srli_epi32(x, 15));
    x = _mm256_mullo_epi32(x, _mm256_set1_epi32((int)0x846ca68bu));
    return _mm256_xor_si256(x, _mm256_srli_epi32(x, 16));
}

/* k_flame_u01(key, n) */
FL_AVX2 static inline __m256 fl_u01(__m256i key, __m256i n)
{
    __m256i h = fl_hash8(_mm256_xor_si256(n, key));
    return _mm256_mul_ps(_mm256_cvtepi32_ps(_mm256_srli_epi32(h, 8)), _mm256_set1_ps(1.0f / 16777216.0f));
}

/* k_sincos */
FL_AVX2 static inline void fl_sincos(__m256 x, __m256 *s, __m256 *c)
{
    __m256 q = _mm256_floor_ps(FL_ADD(FL_MUL(x, FL_S(0.636619772f)), FL_S(0.5f)));
    __m256 r = FL_SUB(FL_SUB(FL_SUB(x, FL_MUL(q, FL_S(1.5703125f))), FL_MUL(q, FL_S(4.837512969970703125e-4f))),
                      FL_MUL(q, FL_S(7.54978995489188216e-8f)));
    __m256 big = _mm256_cmp_ps(fl_abs(r), FL_S(0.8f), _CMP_GT_OQ);
    __m256 clamp = FL_SEL(FL_S(-0.8f), FL_S(0.8f), _mm256_cmp_ps(r, _mm256_setzero_ps(), _CMP_GT_OQ));
    r = FL_SEL(r, clamp, big);
    __m256 z = FL_MUL(r, r);
    __m256 sn = FL_ADD(
        r, FL_MUL(FL_MUL(r, z), FL_ADD(FL_S(-1.6666654611e-1f),
                                       FL_MUL(z, FL_ADD(FL_S(8.3321608736e-3f), FL_MUL(z, FL_S(-1.9515295891e-4f)))))));
    __m256 cs =
        FL_ADD(FL_SUB(FL_S(1.0f), FL_MUL(FL_S(0.5f), z)),
               FL_MUL(FL_MUL(z, z),
                      FL_ADD(FL_S(4.166664568298827e-2f),
                             FL_MUL(z, FL_ADD(FL_S(-1.388731625493765e-3f), FL_MUL(z, FL_S(2.443315711809948e-5f)))))));
    __m256i n = _mm256_cvttps_epi32(FL_SUB(q, FL_MUL(FL_S(4.0f), _mm256_floor_ps(FL_MUL(q, FL_S(0.25f))))));
    __m256 e0 = _mm256_castsi256_ps(_mm256_cmpeq_epi32(n, _mm256_setzero_si256()));
    __m256 e1 = _mm256_castsi256_ps(_mm256_cmpeq_epi32(n, _mm256_set1_epi32(1)));
    __m256 e2 = _mm256_castsi256_ps(_mm256_cmpeq_epi32(n, _mm256_set1_epi32(2)));
    __m256 nsn = fl_neg(sn), ncs = fl_neg(cs);
    *s = FL_SEL(FL_SEL(FL_SEL(ncs, nsn, e2), cs, e1), sn, e0);
    *c = FL_SEL(FL_SEL(FL_SEL(sn, ncs, e2), nsn, e1), cs, e0);
}

FL_AVX2 static inline __m256 fl_sin(__m256 x)
{
    __m256 s, c;
    fl_sincos(x, &s, &c);
    return s;
}

FL_AVX2 static inline __m256 fl_cos(__m256 x)
{
    __m256 s, c;
    fl_sincos(x, &s, &c);
    return c;
}

/* k_xexp */
FL_AVX2 static inline __m256 fl_exp(__m256 x)
{
    __m256 z = _mm256_floor_ps(FL_ADD(FL_MUL(FL_S(1.44269504088896341f), x), FL_S(0.5f)));
    __m256 r = FL_SUB(FL_SUB(x, FL_MUL(z, FL_S(0.693359375f))), FL_MUL(z, FL_S(-2.12194440e-4f)));
    __m256 r2 = FL_MUL(r, r);
    __m256 p = FL_ADD(FL_MUL(FL_S(1.9875691500e-4f), r), FL_S(1.3981999507e-3f));
    p = FL_ADD(FL_MUL(p, r), FL_S(8.3334519073e-3f));
    p = FL_ADD(FL_MUL(p, r), FL_S(4.1665795894e-2f));
    p = FL_ADD(FL_MUL(p, r), FL_S(1.6666665459e-1f));
    p = FL_ADD(FL_MUL(p, r), FL_S(5.0000001201e-1f));
    p = FL_ADD(FL_ADD(FL_MUL(p, r2), r), FL_S(1.0f));
    __m256i n = _mm256_cvttps_epi32(z);
    __m256i h = _mm256_srai_epi32(_mm256_add_epi32(n, _mm256_srli_epi32(n, 31)), 1); /* n / 2, truncated */
    __m256i b127 = _mm256_set1_epi32(127);
    __m256 eh = _mm256_castsi256_ps(_mm256_slli_epi32(_mm256_add_epi32(h, b127), 23));
    __m256 enh = _mm256_castsi256_ps(_mm256_slli_epi32(_mm256_add_epi32(_mm256_sub_epi32(n, h), b127), 23));
    __m256 e = FL_MUL(FL_MUL(p, eh), enh);
    e = FL_SEL(e, _mm256_setzero_ps(), _mm256_cmp_ps(fl_abs(e), FL_S(1.17549435e-38f), _CMP_LT_OQ));
    e = FL_SEL(e, _mm256_setzero_ps(), _mm256_cmp_ps(x, FL_S(-87.33654475055310f), _CMP_LT_OQ));
    e = FL_SEL(e, FL_S(K_INF), _mm256_cmp_ps(x, FL_S(88.72283905206835f), _CMP_GT_OQ));
    return FL_SEL(e, x, _mm256_cmp_ps(x, x, _CMP_UNORD_Q));
}

/* k_xsinhcosh */
FL_AVX2 static inline void fl_sinhcosh(__m256 x, __m256 *sh, __m256 *ch)
{
    __m256 a = fl_abs(x);
    __m256 ea = fl_exp(a), ena = fl_exp(fl_neg(a));
    __m256 z = FL_MUL(a, a);
    __m256 sp =
        FL_ADD(FL_MUL(FL_MUL(FL_ADD(FL_MUL(FL_ADD(FL_MUL(FL_S(2.03721912945e-4f), z), FL_S(8.33028376239e-3f)), z),
                                    FL_S(1.66667160211e-1f)),
                             z),
                      a),
               a);
    __m256 sl = FL_SUB(FL_MUL(FL_S(0.5f), ea), FL_MUL(FL_S(0.5f), ena));
    __m256 s = FL_SEL(sl, sp, _mm256_cmp_ps(a, FL_S(1.0f), _CMP_LE_OQ));
    *ch = FL_ADD(FL_MUL(FL_S(0.5f), ea), FL_MUL(FL_S(0.5f), ena));
    *sh = FL_SEL(s, fl_neg(s), _mm256_cmp_ps(x, _mm256_setzero_ps(), _CMP_LT_OQ));
}

/* k_xatan */
FL_AVX2 static inline __m256 fl_atan(__m256 x)
{
    __m256 a = fl_abs(x);
    __m256 big = _mm256_cmp_ps(a, FL_S(2.414213562373095f), _CMP_GT_OQ);
    __m256 mid = _mm256_cmp_ps(a, FL_S(0.4142135623730950f), _CMP_GT_OQ);
    __m256 base = FL_SEL(FL_SEL(_mm256_setzero_ps(), FL_S(K_QUART_PI), mid), FL_S(K_HALF_PI), big);
    __m256 num = FL_SEL(FL_SEL(a, FL_SUB(a, FL_S(1.0f)), mid), FL_S(-1.0f), big);
    __m256 den = FL_SEL(FL_SEL(FL_S(1.0f), FL_ADD(a, FL_S(1.0f)), mid), a, big);
    a = FL_SEL(a, FL_DIV(num, den), mid); /* mid covers big */
    __m256 z = FL_MUL(a, a);
    __m256 p = FL_SUB(FL_MUL(FL_S(8.05374449538e-2f), z), FL_S(1.38776856032e-1f));
    p = FL_ADD(FL_MUL(p, z), FL_S(1.99777106478e-1f));
    p = FL_SUB(FL_MUL(p, z), FL_S(3.33329491539e-1f));
    __m256 r = FL_ADD(base, FL_ADD(FL_MUL(FL_MUL(p, z), a), a));
    return FL_SEL(r, fl_neg(r), _mm256_cmp_ps(x, _mm256_setzero_ps(), _CMP_LT_OQ));
}

/* k_xatan2(y, x) */
FL_AVX2 static inline __m256 fl_atan2(__m256 y, __m256 x)
{
    const __m256 zero = _mm256_setzero_ps();
    __m256 xneg = _mm256_cmp_ps(x, zero, _CMP_LT_OQ), yneg = _mm256_cmp_ps(y, zero, _CMP_LT_OQ);
    __m256 xpos = _mm256_cmp_ps(x, zero, _CMP_GT_OQ), ypos = _mm256_cmp_ps(y, zero, _CMP_GT_OQ);
    __m256 w = FL_SEL(zero, FL_SEL(FL_S(K_PI), FL_S(-K_PI), yneg), xneg);
    __m256 r = FL_ADD(w, fl_atan(FL_DIV(y, x)));
    /* infinities */
    __m256 xinf = fl_isinf(x), yinf = fl_isinf(y);
    __m256 ax = FL_SEL(zero, FL_SEL(FL_S(K_PI), zero, xpos), xinf);
    __m256 ay = FL_SEL(FL_S(K_HALF_PI), FL_SEL(FL_S(3.0f * K_QUART_PI), FL_S(K_QUART_PI), xpos), xinf);
    ax = FL_SEL(ax, ay, yinf);
    r = FL_SEL(r, FL_SEL(ax, fl_neg(ax), yneg), _mm256_or_ps(xinf, yinf));
    /* zeros */
    r = FL_SEL(r, FL_SEL(zero, FL_S(K_PI), xneg), _mm256_cmp_ps(y, zero, _CMP_EQ_OQ));
    __m256 xz = FL_SEL(FL_SEL(zero, FL_S(-K_HALF_PI), yneg), FL_S(K_HALF_PI), ypos);
    r = FL_SEL(r, xz, _mm256_cmp_ps(x, zero, _CMP_EQ_OQ));
    return FL_SEL(r, FL_ADD(x, y), _mm256_cmp_ps(x, y, _CMP_UNORD_Q));
}

/* k_xlog */
FL_AVX2 static inline __m256 fl_log(__m256 x)
{
    __m256i b = _mm256_castps_si256(x);
    __m256i be = _mm256_and_si256(_mm256_srli_epi32(b, 23), _mm256_set1_epi32(255));
    __m256i e = _mm256_sub_epi32(be, _mm256_set1_epi32(126));
    __m256 m = _mm256_castsi256_ps(
        _mm256_or_si256(_mm256_and_si256(b, _mm256_set1_epi32(0x007fffff)), _mm256_set1_epi32(0x3f000000)));
    __m256 lo = _mm256_cmp_ps(m, FL_S(0.707106781186547524f), _CMP_LT_OQ);
    e = _mm256_add_epi32(e, _mm256_castps_si256(lo)); /* e - 1 where lo */
    m = FL_SEL(FL_SUB(m, FL_S(1.0f)), FL_SUB(FL_ADD(m, m), FL_S(1.0f)), lo);
    __m256 z = FL_MUL(m, m);
    __m256 y = FL_SUB(FL_MUL(FL_S(7.0376836292e-2f), m), FL_S(1.1514610310e-1f));
    y = FL_ADD(FL_MUL(y, m), FL_S(1.1676998740e-1f));
    y = FL_SUB(FL_MUL(y, m), FL_S(1.2420140846e-1f));
    y = FL_ADD(FL_MUL(y, m), FL_S(1.4249322787e-1f));
    y = FL_SUB(FL_MUL(y, m), FL_S(1.6668057665e-1f));
    y = FL_ADD(FL_MUL(y, m), FL_S(2.0000714765e-1f));
    y = FL_SUB(FL_MUL(y, m), FL_S(2.4999993993e-1f));
    y = FL_ADD(FL_MUL(y, m), FL_S(3.3333331174e-1f));
    y = FL_MUL(FL_MUL(y, m), z);
    __m256 fe = _mm256_cvtepi32_ps(e);
    y = FL_ADD(y, FL_MUL(fe, FL_S(-2.12194440e-4f)));
    y = FL_SUB(y, FL_MUL(FL_S(0.5f), z));
    __m256 r = FL_ADD(FL_ADD(m, y), FL_MUL(fe, FL_S(0.693359375f)));
    r = FL_SEL(r, x, _mm256_castsi256_ps(_mm256_cmpeq_epi32(be, _mm256_set1_epi32(255))));
    r = FL_SEL(r, FL_S(K_NAN), _mm256_castsi256_ps(_mm256_srai_epi32(b, 31)));
    r = FL_SEL(r, FL_S(-K_INF), _mm256_castsi256_ps(_mm256_cmpeq_epi32(be, _mm256_setzero_si256())));
    return FL_SEL(r, x, _mm256_cmp_ps(x, x, _CMP_UNORD_Q));
}

/* k_xpow(x, y) */
FL_AVX2 static inline __m256 fl_pow(__m256 x, __m256 y)
{
    const __m256 zero = _mm256_setzero_ps(), one = FL_S(1.0f);
    __m256 r = fl_exp(FL_MUL(y, fl_log(x)));
    r = FL_SEL(r, one, _mm256_cmp_ps(y, zero, _CMP_EQ_OQ));
    __m256 x0 =
        FL_SEL(FL_SEL(FL_S(K_INF), one, _mm256_cmp_ps(y, zero, _CMP_EQ_OQ)), zero, _mm256_cmp_ps(y, zero, _CMP_GT_OQ));
    return FL_SEL(r, x0, _mm256_cmp_ps(x, zero, _CMP_EQ_OQ));
}

/* k_xtan */
FL_AVX2 static inline __m256 fl_tan(__m256 x)
{
    __m256 s, c;
    fl_sincos(x, &s, &c);
    return FL_DIV(s, c);
}

FL_AVX2 static inline __m256 fl_trunc(__m256 x)
{
    return _mm256_round_ps(x, _MM_FROUND_TO_ZERO | _MM_FROUND_NO_EXC);
}

/* k_xfmod */
FL_AVX2 static inline __m256 fl_fmod(__m256 x, __m256 y)
{
    return FL_SUB(x, FL_MUL(y, fl_trunc(FL_DIV(x, y))));
}

/* ---- the xform ------------------------------------------------------------------------------------ */

/* Which of the functions below has variation v's form on the lanes (fl_var_lo, fl_var_hi,
 * fl_var_ext: 1, 2, 3), or 0: none. */
static inline int fl_var_kind(uint v)
{
    switch (v) {
    case K_V_LINEAR:
    case K_V_SINUSOIDAL:
    case K_V_SPHERICAL:
    case K_V_SWIRL:
    case K_V_HORSESHOE:
    case K_V_POLAR:
    case K_V_HANDKERCHIEF:
    case K_V_HEART:
    case K_V_DISC:
    case K_V_SPIRAL:
    case K_V_HYPERBOLIC:
    case K_V_DIAMOND:
    case K_V_EX:
    case K_V_JULIA:
    case K_V_BENT:
    case K_V_FISHEYE:
    case K_V_EXPONENTIAL:
        return 1;
    case K_V_COSINE:
    case K_V_BLOB:
    case K_V_EYEFISH:
    case K_V_BUBBLE:
    case K_V_CYLINDER:
    case K_V_NOISE:
    case K_V_BLUR:
    case K_V_SQUARE:
    case K_V_BLADE:
    case K_V_FLOWER:
        return 2;
    case K_V_WAVES:
    case K_V_POPCORN:
    case K_V_POWER:
    case K_V_RINGS:
    case K_V_FAN:
    case K_V_PDJ:
    case K_V_PERSPECTIVE:
    case K_V_JULIAN:
    case K_V_JULIASCOPE:
    case K_V_GAUSSIAN_BLUR:
    case K_V_RADIAL_BLUR:
    case K_V_PIE:
    case K_V_CURL:
    case K_V_ARCH:
    case K_V_TANGENT:
    case K_V_RAYS:
    case K_V_SECANT2:
    case K_V_CROSS:
        return 3;
    default:
        return 0;
    }
}

/* Whether variation v has a form on the lanes here. */
static inline bool fl_var_avx2(uint v)
{
    return fl_var_kind(v) != 0;
}

/* Whether xform X (its variations var[X.var0 ..]) can be applied on the lanes: every variation has
 * a form here, and no pre_blur. */
static inline bool fl_xform_avx2(const K_FlameXform *X, const K_FlameVar *var)
{
    if (X->preblur != 0.0f) return false;
    for (uint k = 0; k < X->nvar; k++)
        if (!fl_var_avx2(var[X->var0 + k].id)) return false;
    return true;
}

/* Eight points and their draw counters. */
typedef struct fl_lanes {
    __m256 x, y, c;
    __m256i n;
} fl_lanes;

/* flam3's precalcs of eight points (K_FlamePt on the lanes). */
typedef struct fl_pt {
    __m256 tx, ty, sumsq, sq, sina, cosa, atxy, atyx;
} fl_pt;

/* A variation V (fl_var_avx2) at the lanes' points t, its draws from counters n: (dx, dy) into *px
 * and *py, the number of draws returned (k_flame_variation's). Two functions, by number. */
#define FL_VAR_ARGS const K_FlameVar *V, const fl_pt *t, __m256i key, __m256i n, __m256 *px, __m256 *py

/* linear .. exponential (fl_var_kind 1) */
FL_AVX2 static inline __attribute__((always_inline)) uint fl_var_lo(FL_VAR_ARGS)
{
    const __m256 zero = _mm256_setzero_ps(), w = FL_S(V->w), eps = FL_S(K_FLAME_EPS), pi = FL_S(K_PI);
    const __m256 tx = t->tx, ty = t->ty, sumsq = t->sumsq, sq = t->sq, sina = t->sina, cosa = t->cosa;
    const __m256 atxy = t->atxy, atyx = t->atyx;
    __m256 dx, dy, s, c;
    uint draws = 0;
    (void)zero, (void)eps, (void)pi, (void)sumsq, (void)sina, (void)cosa, (void)atxy, (void)atyx, (void)key, (void)n;
#define DRAW(i) fl_u01(key, _mm256_add_epi32(n, _mm256_set1_epi32(i)))
    switch (V->id) {
    case K_V_LINEAR:
        dx = FL_MUL(w, tx), dy = FL_MUL(w, ty);
        break;
    case K_V_SINUSOIDAL:
        dx = FL_MUL(w, fl_sin(tx)), dy = FL_MUL(w, fl_sin(ty));
        break;
    case K_V_SPHERICAL: {
        __m256 r2 = FL_DIV(w, FL_ADD(sumsq, eps));
        dx = FL_MUL(r2, tx), dy = FL_MUL(r2, ty);
        break;
    }
    case K_V_SWIRL:
        fl_sincos(sumsq, &s, &c);
        dx = FL_MUL(w, FL_SUB(FL_MUL(s, tx), FL_MUL(c, ty)));
        dy = FL_MUL(w, FL_ADD(FL_MUL(c, tx), FL_MUL(s, ty)));
        break;
    case K_V_HORSESHOE: {
        __m256 r = FL_DIV(w, FL_ADD(sq, eps));
        dx = FL_MUL(FL_MUL(FL_SUB(tx, ty), FL_ADD(tx, ty)), r);
        dy = FL_MUL(FL_MUL(FL_MUL(FL_S(2.0f), tx), ty), r);
        break;
    }
    case K_V_POLAR:
        dx = FL_MUL(FL_MUL(w, atxy), FL_S(K_1_PI)), dy = FL_MUL(w, FL_SUB(sq, FL_S(1.0f)));
        break;
    case K_V_HANDKERCHIEF:
        dx = FL_MUL(FL_MUL(w, sq), fl_sin(FL_ADD(atxy, sq)));
        dy = FL_MUL(FL_MUL(w, sq), fl_cos(FL_SUB(atxy, sq)));
        break;
    case K_V_HEART: {
        __m256 r = FL_MUL(w, sq);
        fl_sincos(FL_MUL(sq, atxy), &s, &c);
        dx = FL_MUL(r, s), dy = FL_MUL(fl_neg(r), c);
        break;
    }
    case K_V_DISC: {
        __m256 a = FL_MUL(atxy, FL_S(K_1_PI));
        fl_sincos(FL_MUL(pi, sq), &s, &c);
        dx = FL_MUL(FL_MUL(w, s), a), dy = FL_MUL(FL_MUL(w, c), a);
        break;
    }
    case K_V_SPIRAL: {
        __m256 r = FL_ADD(sq, eps), r1 = FL_DIV(w, r);
        fl_sincos(r, &s, &c);
        dx = FL_MUL(r1, FL_ADD(cosa, s)), dy = FL_MUL(r1, FL_SUB(sina, c));
        break;
    }
    case K_V_HYPERBOLIC: {
        __m256 r = FL_ADD(sq, eps);
        dx = FL_DIV(FL_MUL(w, sina), r), dy = FL_MUL(FL_MUL(w, cosa), r);
        break;
    }
    case K_V_DIAMOND:
        fl_sincos(sq, &s, &c);
        dx = FL_MUL(FL_MUL(w, sina), c), dy = FL_MUL(FL_MUL(w, cosa), s);
        break;
    case K_V_EX: {
        __m256 n0 = fl_sin(FL_ADD(atxy, sq)), n1 = fl_cos(FL_SUB(atxy, sq));
        __m256 m0 = FL_MUL(FL_MUL(FL_MUL(n0, n0), n0), sq), m1 = FL_MUL(FL_MUL(FL_MUL(n1, n1), n1), sq);
        dx = FL_MUL(w, FL_ADD(m0, m1)), dy = FL_MUL(w, FL_SUB(m0, m1));
        break;
    }
    case K_V_JULIA: {
        __m256 a = FL_MUL(FL_S(0.5f), atxy);
        __m256i h = fl_hash8(_mm256_xor_si256(n, key));
        __m256 odd =
            _mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_and_si256(h, _mm256_set1_epi32(1)), _mm256_set1_epi32(1)));
        a = FL_SEL(a, FL_ADD(a, pi), odd);
        __m256 r = FL_MUL(w, _mm256_sqrt_ps(sq));
        fl_sincos(a, &s, &c);
        dx = FL_MUL(r, c), dy = FL_MUL(r, s);
        draws = 1;
        break;
    }
    case K_V_BENT: {
        __m256 nx = FL_SEL(tx, FL_MUL(tx, FL_S(2.0f)), _mm256_cmp_ps(tx, zero, _CMP_LT_OQ));
        __m256 ny = FL_SEL(ty, FL_MUL(ty, FL_S(0.5f)), _mm256_cmp_ps(ty, zero, _CMP_LT_OQ));
        dx = FL_MUL(w, nx), dy = FL_MUL(w, ny);
        break;
    }
    case K_V_FISHEYE: {
        __m256 r = FL_DIV(FL_MUL(FL_S(2.0f), w), FL_ADD(sq, FL_S(1.0f)));
        dx = FL_MUL(r, ty), dy = FL_MUL(r, tx);
        break;
    }
    case K_V_EXPONENTIAL: {
        __m256 d = FL_MUL(w, fl_exp(FL_SUB(tx, FL_S(1.0f))));
        fl_sincos(FL_MUL(pi, ty), &s, &c);
        dx = FL_MUL(d, c), dy = FL_MUL(d, s);
        break;
    }
    default: /* not fl_xform_avx2: never here */
        dx = dy = _mm256_set1_ps(K_NAN);
        break;
    }
#undef DRAW
    *px = dx, *py = dy;
    return draws;
}

/* cosine .. flower (fl_var_kind 2) */
FL_AVX2 static inline __attribute__((always_inline)) uint fl_var_hi(FL_VAR_ARGS)
{
    const __m256 zero = _mm256_setzero_ps(), w = FL_S(V->w), eps = FL_S(K_FLAME_EPS), pi = FL_S(K_PI);
    const __m256 tx = t->tx, ty = t->ty, sumsq = t->sumsq, sq = t->sq, sina = t->sina, cosa = t->cosa;
    const __m256 atxy = t->atxy, atyx = t->atyx;
    __m256 dx, dy, s, c;
    uint draws = 0;
    (void)zero, (void)eps, (void)pi, (void)sumsq, (void)sina, (void)cosa, (void)atxy, (void)atyx, (void)key, (void)n;
#define DRAW(i) fl_u01(key, _mm256_add_epi32(n, _mm256_set1_epi32(i)))
    switch (V->id) {
    case K_V_COSINE: {
        __m256 hs, hc;
        fl_sincos(FL_MUL(tx, pi), &s, &c);
        fl_sinhcosh(ty, &hs, &hc);
        dx = FL_MUL(FL_MUL(w, c), hc), dy = FL_MUL(FL_MUL(w, fl_neg(s)), hs);
        break;
    }
    case K_V_BLOB: {
        __m256 r = FL_MUL(
            sq, FL_ADD(FL_S(V->p0),
                       FL_MUL(FL_S(V->p1), FL_ADD(FL_S(0.5f), FL_MUL(FL_S(0.5f), fl_sin(FL_MUL(FL_S(V->p2), atxy)))))));
        dx = FL_MUL(FL_MUL(w, sina), r), dy = FL_MUL(FL_MUL(w, cosa), r);
        break;
    }
    case K_V_EYEFISH: {
        __m256 r = FL_DIV(FL_MUL(w, FL_S(2.0f)), FL_ADD(sq, FL_S(1.0f)));
        dx = FL_MUL(r, tx), dy = FL_MUL(r, ty);
        break;
    }
    case K_V_BUBBLE: {
        __m256 r = FL_DIV(w, FL_ADD(FL_MUL(FL_S(0.25f), sumsq), FL_S(1.0f)));
        dx = FL_MUL(r, tx), dy = FL_MUL(r, ty);
        break;
    }
    case K_V_CYLINDER:
        dx = FL_MUL(w, fl_sin(tx)), dy = FL_MUL(w, ty);
        break;
    case K_V_NOISE: {
        fl_sincos(FL_MUL(FL_MUL(DRAW(0), FL_S(2.0f)), pi), &s, &c);
        __m256 r = FL_MUL(w, DRAW(1));
        dx = FL_MUL(FL_MUL(tx, r), c), dy = FL_MUL(FL_MUL(ty, r), s);
        draws = 2;
        break;
    }
    case K_V_BLUR: {
        fl_sincos(FL_MUL(FL_MUL(DRAW(0), FL_S(2.0f)), pi), &s, &c);
        __m256 r = FL_MUL(w, DRAW(1));
        dx = FL_MUL(r, c), dy = FL_MUL(r, s);
        draws = 2;
        break;
    }
    case K_V_SQUARE:
        dx = FL_MUL(w, FL_SUB(DRAW(0), FL_S(0.5f))), dy = FL_MUL(w, FL_SUB(DRAW(1), FL_S(0.5f)));
        draws = 2;
        break;
    case K_V_BLADE: {
        fl_sincos(FL_MUL(FL_MUL(DRAW(0), w), sq), &s, &c);
        __m256 wx = FL_MUL(w, tx);
        dx = FL_MUL(wx, FL_ADD(c, s)), dy = FL_MUL(wx, FL_SUB(c, s));
        draws = 1;
        break;
    }
    case K_V_FLOWER: {
        __m256 r = FL_DIV(FL_MUL(FL_MUL(w, FL_SUB(DRAW(0), FL_S(V->p1))), fl_cos(FL_MUL(FL_S(V->p0), atyx))), sq);
        dx = FL_MUL(r, tx), dy = FL_MUL(r, ty);
        draws = 1;
        break;
    }
    default: /* not fl_xform_avx2: never here */
        dx = dy = _mm256_set1_ps(K_NAN);
        break;
    }
#undef DRAW
    *px = dx, *py = dy;
    return draws;
}

/* waves .. cross (fl_var_kind 3) */
FL_AVX2 static inline __attribute__((always_inline)) uint fl_var_ext(FL_VAR_ARGS)
{
    const __m256 zero = _mm256_setzero_ps(), w = FL_S(V->w), eps = FL_S(K_FLAME_EPS), pi = FL_S(K_PI);
    const __m256 tx = t->tx, ty = t->ty, sumsq = t->sumsq, sq = t->sq, sina = t->sina, cosa = t->cosa;
    const __m256 atxy = t->atxy, atyx = t->atyx, p0 = FL_S(V->p0), p1 = FL_S(V->p1), p2 = FL_S(V->p2);
    const __m256 one = FL_S(1.0f), two = FL_S(2.0f), twopi = FL_S(2.0f * K_PI);
    __m256 dx, dy, s, c;
    uint draws = 0;
    (void)zero, (void)eps, (void)sumsq, (void)sina, (void)cosa, (void)atxy, (void)atyx, (void)key, (void)n;
#define DRAW(i) fl_u01(key, _mm256_add_epi32(n, _mm256_set1_epi32(i)))
    switch (V->id) {
    case K_V_WAVES:
        dx = FL_MUL(w, FL_ADD(tx, FL_MUL(p0, fl_sin(FL_MUL(ty, p2)))));
        dy = FL_MUL(w, FL_ADD(ty, FL_MUL(p1, fl_sin(FL_MUL(tx, FL_S(V->p3))))));
        break;
    case K_V_POPCORN:
        dx = FL_MUL(w, FL_ADD(tx, FL_MUL(p0, fl_sin(fl_tan(FL_MUL(FL_S(3.0f), ty))))));
        dy = FL_MUL(w, FL_ADD(ty, FL_MUL(p1, fl_sin(fl_tan(FL_MUL(FL_S(3.0f), tx))))));
        break;
    case K_V_POWER: {
        __m256 r = FL_MUL(w, fl_pow(sq, sina));
        dx = FL_MUL(r, cosa), dy = FL_MUL(r, sina);
        break;
    }
    case K_V_RINGS: {
        __m256 r = FL_MUL(w, FL_ADD(FL_SUB(fl_fmod(FL_ADD(sq, p0), FL_MUL(two, p0)), p0), FL_MUL(sq, FL_SUB(one, p0))));
        dx = FL_MUL(r, cosa), dy = FL_MUL(r, sina);
        break;
    }
    case K_V_FAN: {
        __m256 dx2 = FL_MUL(FL_S(0.5f), p0);
        __m256 big = _mm256_cmp_ps(fl_fmod(FL_ADD(atxy, p1), p0), dx2, _CMP_GT_OQ);
        fl_sincos(FL_ADD(atxy, FL_SEL(dx2, fl_neg(dx2), big)), &s, &c);
        __m256 r = FL_MUL(w, sq);
        dx = FL_MUL(r, c), dy = FL_MUL(r, s);
        break;
    }
    case K_V_PDJ:
        dx = FL_MUL(w, FL_SUB(fl_sin(FL_MUL(p0, ty)), fl_cos(FL_MUL(p1, tx))));
        dy = FL_MUL(w, FL_SUB(fl_sin(FL_MUL(p2, tx)), fl_cos(FL_MUL(FL_S(V->p3), ty))));
        break;
    case K_V_PERSPECTIVE: {
        __m256 tt = FL_DIV(one, FL_SUB(p0, FL_MUL(ty, p1)));
        dx = FL_MUL(FL_MUL(FL_MUL(w, p0), tx), tt), dy = FL_MUL(FL_MUL(FL_MUL(w, p2), ty), tt);
        break;
    }
    case K_V_JULIAN: {
        __m256 tr = fl_trunc(FL_MUL(p2, DRAW(0)));
        fl_sincos(FL_DIV(FL_ADD(atyx, FL_MUL(twopi, tr)), p0), &s, &c);
        __m256 r = FL_MUL(w, fl_pow(sumsq, p1));
        dx = FL_MUL(r, c), dy = FL_MUL(r, s), draws = 1;
        break;
    }
    case K_V_JULIASCOPE: {
        __m256i tr = _mm256_cvttps_epi32(fl_trunc(FL_MUL(p2, DRAW(0))));
        __m256 odd =
            _mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_and_si256(tr, _mm256_set1_epi32(1)), _mm256_set1_epi32(1)));
        __m256 ft = FL_MUL(twopi, _mm256_cvtepi32_ps(tr));
        __m256 a = FL_DIV(FL_SEL(FL_ADD(ft, atyx), FL_SUB(ft, atyx), odd), p0);
        __m256 r = FL_MUL(w, fl_pow(sumsq, p1));
        fl_sincos(a, &s, &c);
        dx = FL_MUL(r, c), dy = FL_MUL(r, s), draws = 1;
        break;
    }
    case K_V_GAUSSIAN_BLUR: {
        fl_sincos(FL_MUL(FL_MUL(DRAW(0), two), pi), &s, &c);
        __m256 g = FL_ADD(FL_ADD(FL_ADD(DRAW(1), DRAW(2)), DRAW(3)), DRAW(4));
        __m256 r = FL_MUL(w, FL_SUB(g, two));
        dx = FL_MUL(r, c), dy = FL_MUL(r, s), draws = 5;
        break;
    }
    case K_V_RADIAL_BLUR: {
        __m256 g = FL_ADD(FL_ADD(FL_ADD(DRAW(0), DRAW(1)), DRAW(2)), DRAW(3));
        __m256 rnd = FL_MUL(w, FL_SUB(g, two));
        fl_sincos(FL_ADD(atyx, FL_MUL(p0, rnd)), &s, &c);
        __m256 rz = FL_SUB(FL_MUL(p1, rnd), one);
        dx = FL_ADD(FL_MUL(sq, c), FL_MUL(rz, tx)), dy = FL_ADD(FL_MUL(sq, s), FL_MUL(rz, ty)), draws = 4;
        break;
    }
    case K_V_PIE: {
        __m256 sl = _mm256_cvtepi32_ps(_mm256_cvttps_epi32(FL_ADD(FL_MUL(DRAW(0), p0), FL_S(0.5f))));
        __m256 a = FL_ADD(p1, FL_DIV(FL_MUL(twopi, FL_ADD(sl, FL_MUL(DRAW(1), p2))), p0));
        __m256 r = FL_MUL(w, DRAW(2));
        fl_sincos(a, &s, &c);
        dx = FL_MUL(r, c), dy = FL_MUL(r, s), draws = 3;
        break;
    }
    case K_V_CURL: {
        __m256 re = FL_ADD(FL_ADD(one, FL_MUL(p0, tx)), FL_MUL(p1, FL_SUB(FL_MUL(tx, tx), FL_MUL(ty, ty))));
        __m256 im = FL_ADD(FL_MUL(p0, ty), FL_MUL(FL_MUL(FL_MUL(two, p1), tx), ty));
        __m256 r = FL_DIV(w, FL_ADD(FL_MUL(re, re), FL_MUL(im, im)));
        dx = FL_MUL(FL_ADD(FL_MUL(tx, re), FL_MUL(ty, im)), r);
        dy = FL_MUL(FL_SUB(FL_MUL(ty, re), FL_MUL(tx, im)), r);
        break;
    }
    case K_V_ARCH:
        fl_sincos(FL_MUL(FL_MUL(DRAW(0), w), pi), &s, &c);
        dx = FL_MUL(w, s), dy = FL_DIV(FL_MUL(w, FL_MUL(s, s)), c), draws = 1;
        break;
    case K_V_TANGENT:
        dx = FL_DIV(FL_MUL(w, fl_sin(tx)), fl_cos(ty)), dy = FL_MUL(w, fl_tan(ty));
        break;
    case K_V_RAYS: {
        __m256 a = FL_MUL(FL_MUL(w, DRAW(0)), pi);
        __m256 r = FL_DIV(w, FL_ADD(sumsq, eps));
        __m256 tr = FL_MUL(FL_MUL(w, fl_tan(a)), r);
        dx = FL_MUL(tr, fl_cos(tx)), dy = FL_MUL(tr, fl_sin(ty)), draws = 1;
        break;
    }
    case K_V_SECANT2: {
        __m256 cr = fl_cos(FL_MUL(w, sq)), icr = FL_DIV(one, cr);
        dx = FL_MUL(w, tx);
        dy = FL_SEL(FL_MUL(w, FL_SUB(icr, one)), FL_MUL(w, FL_ADD(icr, one)), _mm256_cmp_ps(cr, zero, _CMP_LT_OQ));
        break;
    }
    case K_V_CROSS: {
        __m256 q = FL_SUB(FL_MUL(tx, tx), FL_MUL(ty, ty));
        __m256 r = FL_MUL(w, _mm256_sqrt_ps(FL_DIV(one, FL_ADD(FL_MUL(q, q), eps))));
        dx = FL_MUL(tx, r), dy = FL_MUL(ty, r);
        break;
    }
    default: /* not fl_xform_avx2: never here */
        dx = dy = _mm256_set1_ps(K_NAN);
        break;
    }
#undef DRAW
    *px = dx, *py = dy;
    return draws;
}

/* k_flame_apply of xform X (fl_xform_avx2) to the eight lanes of p, chain keys key, n0 the counter
 * of its first draw: the result into p; the lanes whose result is a bad value are set in the mask
 * returned (their p is not the scalar result: the caller replays them). */
FL_AVX2 static inline __m256 fl_apply8(const K_FlameXform *X, const K_FlameVar *var, __m256i key, fl_lanes *p)
{
    const __m256 zero = _mm256_setzero_ps();
    __m256i n = p->n;
    __m256 oc = FL_ADD(FL_S(X->speed * X->color), FL_MUL(FL_S(1.0f - X->speed), p->c));
    fl_pt t;
    t.tx = FL_ADD(FL_ADD(FL_MUL(FL_S(X->ax), p->x), FL_MUL(FL_S(X->bx), p->y)), FL_S(X->cx));
    t.ty = FL_ADD(FL_ADD(FL_MUL(FL_S(X->ay), p->x), FL_MUL(FL_S(X->by), p->y)), FL_S(X->cy));
    /* k_flame_point */
    uint flags = X->flags;
    t.sumsq = FL_ADD(FL_MUL(t.tx, t.tx), FL_MUL(t.ty, t.ty));
    t.sq = t.sina = t.cosa = t.atxy = t.atyx = zero;
    if (flags & (K_FLAME_SQRT | K_FLAME_ANGLES)) t.sq = _mm256_sqrt_ps(t.sumsq);
    if (flags & K_FLAME_ANGLES) t.sina = FL_DIV(t.tx, t.sq), t.cosa = FL_DIV(t.ty, t.sq);
    if (flags & K_FLAME_ATAN_XY) t.atxy = fl_atan2(t.tx, t.ty);
    if (flags & K_FLAME_ATAN_YX) t.atyx = fl_atan2(t.ty, t.tx);
    __m256 p0 = zero, p1 = zero;
    for (uint k = 0; k < X->nvar; k++) {
        const K_FlameVar *V = &var[X->var0 + k];
        __m256 dx, dy;
        int kind = fl_var_kind(V->id);
        uint draws = kind == 1   ? fl_var_lo(V, &t, key, n, &dx, &dy)
                     : kind == 2 ? fl_var_hi(V, &t, key, n, &dx, &dy)
                                 : fl_var_ext(V, &t, key, n, &dx, &dy);
        p0 = FL_ADD(p0, dx);
        p1 = FL_ADD(p1, dy);
        n = _mm256_add_epi32(n, _mm256_set1_epi32((int)draws));
    }
    if (flags & K_FLAME_HAS_POST) {
        __m256 qx = FL_ADD(FL_ADD(FL_MUL(FL_S(X->pax), p0), FL_MUL(FL_S(X->pbx), p1)), FL_S(X->pcx));
        __m256 qy = FL_ADD(FL_ADD(FL_MUL(FL_S(X->pay), p0), FL_MUL(FL_S(X->pby), p1)), FL_S(X->pcy));
        p0 = qx, p1 = qy;
    }
    p->x = p0, p->y = p1, p->c = oc, p->n = n;
    __m256 bad = _mm256_or_ps(_mm256_cmp_ps(p0, p0, _CMP_UNORD_Q), _mm256_cmp_ps(p1, p1, _CMP_UNORD_Q));
    bad = _mm256_or_ps(bad, _mm256_cmp_ps(fl_abs(p0), FL_S(1e10f), _CMP_GT_OQ));
    return _mm256_or_ps(bad, _mm256_cmp_ps(fl_abs(p1), FL_S(1e10f), _CMP_GT_OQ));
}

#endif

#endif
