/*
 * The 99 variations of flam3 3.1.1 (flam3.h's VAR_LINEAR 0 .. VAR_MOBIUS 98), in the common subset of
 * C11 and GLSL: one small function each, with flam3's formula (variations.c) and its quirks, in
 * single precision, and one switch (k_flame_variation) that picks a variation by its number. A
 * variation is a pure function of the point after the xform's affine map with flam3's precalcs
 * (K_FlamePt), its weight and parameters (K_FlameVar, already combined as flam3's precalc functions
 * combine them: host/gen/flame/render.c's fb_flame_var_params), and, for the random ones, the
 * position (key, n) of its draws in the chain's counter-based stream: its i-th draw is
 * k_flame_u01(key, n + i), and the switch says how many it takes.
 *
 * Exactness: the same bits in C and on any conformant Vulkan device. Float `/` and sqrt only
 * through kx_div and kx_sqrt (kernels/exact.h), the transcendentals kernels/kmath.h's float-only
 * ones (k_xsin ... k_xacos), no fused multiply-add (C is built with -ffp-contract=off, the SPIR-V
 * carries NoContraction on every float operation), every float literal one that C and glslang read
 * alike (tests/test_kmath.c). flam3 computes in double: where a float intermediate overflows while
 * flam3's double stays finite and its result is bounded (foci, and the tangents, secants and
 * cosecants of the complex family at a large imaginary part), the function returns flam3's limit
 * instead of a bad value; elsewhere float's narrower range and precision are what they are.
 */
#ifndef FB_KERNELS_FLAME_VAR_H
#define FB_KERNELS_FLAME_VAR_H

#include "common.h"
#include "hash.h"
#include "kmath.h"

#define K_FLAME_EPS 1e-10f       /* flam3's EPS */
#define K_1_PI      0.318309873f /* 1 / pi: the float nearest both 1 / K_PI and M_1_PI */
#define K_2_PI      0.636619747f /* 2 / pi (M_2_PI) */

/* flam3's variation numbers (flam3.h VAR_*). */
#define K_V_LINEAR        0u
#define K_V_SINUSOIDAL    1u
#define K_V_SPHERICAL     2u
#define K_V_SWIRL         3u
#define K_V_HORSESHOE     4u
#define K_V_POLAR         5u
#define K_V_HANDKERCHIEF  6u
#define K_V_HEART         7u
#define K_V_DISC          8u
#define K_V_SPIRAL        9u
#define K_V_HYPERBOLIC    10u
#define K_V_DIAMOND       11u
#define K_V_EX            12u
#define K_V_JULIA         13u
#define K_V_BENT          14u
#define K_V_WAVES         15u
#define K_V_FISHEYE       16u
#define K_V_POPCORN       17u
#define K_V_EXPONENTIAL   18u
#define K_V_POWER         19u
#define K_V_COSINE        20u
#define K_V_RINGS         21u
#define K_V_FAN           22u
#define K_V_BLOB          23u
#define K_V_PDJ           24u
#define K_V_FAN2          25u
#define K_V_RINGS2        26u
#define K_V_EYEFISH       27u
#define K_V_BUBBLE        28u
#define K_V_CYLINDER      29u
#define K_V_PERSPECTIVE   30u
#define K_V_NOISE         31u
#define K_V_JULIAN        32u
#define K_V_JULIASCOPE    33u
#define K_V_BLUR          34u
#define K_V_GAUSSIAN_BLUR 35u
#define K_V_RADIAL_BLUR   36u
#define K_V_PIE           37u
#define K_V_NGON          38u
#define K_V_CURL          39u
#define K_V_RECTANGLES    40u
#define K_V_ARCH          41u
#define K_V_TANGENT       42u
#define K_V_SQUARE        43u
#define K_V_RAYS          44u
#define K_V_BLADE         45u
#define K_V_SECANT2       46u
#define K_V_TWINTRIAN     47u
#define K_V_CROSS         48u
#define K_V_DISC2         49u
#define K_V_SUPER_SHAPE   50u
#define K_V_FLOWER        51u
#define K_V_CONIC         52u
#define K_V_PARABOLA      53u
#define K_V_BENT2         54u
#define K_V_BIPOLAR       55u
#define K_V_BOARDERS      56u
#define K_V_BUTTERFLY     57u
#define K_V_CELL          58u
#define K_V_CPOW          59u
#define K_V_CURVE         60u
#define K_V_EDISC         61u
#define K_V_ELLIPTIC      62u
#define K_V_ESCHER        63u
#define K_V_FOCI          64u
#define K_V_LAZYSUSAN     65u
#define K_V_LOONIE        66u
#define K_V_PRE_BLUR      67u /* applied to (tx, ty) before the precalcs: k_flame_preblur */
#define K_V_MODULUS       68u
#define K_V_OSCILLOSCOPE  69u
#define K_V_POLAR2        70u
#define K_V_POPCORN2      71u
#define K_V_SCRY          72u
#define K_V_SEPARATION    73u
#define K_V_SPLIT         74u
#define K_V_SPLITS        75u
#define K_V_STRIPES       76u
#define K_V_WEDGE         77u
#define K_V_WEDGE_JULIA   78u
#define K_V_WEDGE_SPH     79u
#define K_V_WHORL         80u
#define K_V_WAVES2        81u
#define K_V_EXP           82u
#define K_V_LOG           83u
#define K_V_SIN           84u
#define K_V_COS           85u
#define K_V_TAN           86u
#define K_V_SEC           87u
#define K_V_CSC           88u
#define K_V_COT           89u
#define K_V_SINH          90u
#define K_V_COSH          91u
#define K_V_TANH          92u
#define K_V_SECH          93u
#define K_V_CSCH          94u
#define K_V_COTH          95u
#define K_V_AUGER         96u
#define K_V_FLUX          97u
#define K_V_MOBIUS        98u
#define K_V_COUNT         99u

/* One active variation of an xform: flam3's number, its weight and up to eight parameters, already
 * combined as flam3's precalc functions do (fb_flame_var_params). 12 words: a std140 array's stride. */
K_STRUCT(K_FlameVar)
{
    uint id;
    float w;
    float p0, p1, p2, p3, p4, p5, p6, p7;
    uint pad0, pad1;
}
K_END(K_FlameVar)

/* What a variation reads: the point after the affine map (and pre_blur), and flam3's precalcs:
 * sumsq = tx^2 + ty^2, sq its root, sina = tx / sq and cosa = ty / sq (flam3's names), the angles
 * atan2(tx, ty) and atan2(ty, tx). Those the xform's variations do not read are 0 (the xform's
 * flags, K_FLAME_SQRT ..., say which are computed). */
K_STRUCT(K_FlamePt)
{
    float tx, ty, sumsq, sq, sina, cosa, atxy, atyx;
}
K_END(K_FlamePt)

/* The switch and the step inlined into their callers in C (the switch called through memory with
 * its point and parameters as arguments cost a sixth of the native game's time). */
#ifdef K_GLSL
#define K_FLAME_INLINE
#else
#define K_FLAME_INLINE static inline __attribute__((always_inline))
#endif

/* The i-th draw of a variation whose draws start at n. */
#define K_FLAME_DRAW(i) k_flame_u01(key, n + (i))

/* The key of chain i: the draws of a chain are k_hash(n ^ key). */
K_FN uint k_flame_key(uint seed, uint chain)
{
    return k_hash(chain ^ k_hash(seed ^ 0x9e3779b9u));
}

K_FN float k_flame_u01(uint key, uint n)
{
    return k_u01(k_hash(n ^ key));
}

/* C's (int) conversion as flam3 compiled on x86-64 does it: a value beyond the int range (or NaN)
 * becomes INT_MIN (cvttsd2si's "integer indefinite"). fan2 and rings2 with a zero parameter divide
 * by 1e-10 and land there, and flam3's images depend on it. (A float converted to int beyond the
 * range is undefined in both languages: every such conversion goes through here.) */
K_FN float k_flame_itrunc(float v)
{
    return (v >= 2147483648.0f || v < -2147483648.0f || k_isnan(v)) ? -2147483648.0f : k_trunc(v);
}

/* rint: to the nearest integer, ties to even (flam3's rint in the default rounding mode). */
#ifdef K_GLSL
#define k_flame_rint(x) roundEven(x)
#else
#define k_flame_rint(x) rintf(x)
#endif

/* ---- 0 .. 54 ---------------------------------------------------------------------------------- */

K_FN k_vec2 k_flame_var_linear(K_FlamePt t, float w)
{
    return k_vec2(w * t.tx, w * t.ty);
}

K_FN k_vec2 k_flame_var_sinusoidal(K_FlamePt t, float w)
{
    return k_vec2(w * k_xsin(t.tx), w * k_xsin(t.ty));
}

K_FN k_vec2 k_flame_var_spherical(K_FlamePt t, float w)
{
    float r2 = kx_div(w, t.sumsq + K_FLAME_EPS);
    return k_vec2(r2 * t.tx, r2 * t.ty);
}

K_FN k_vec2 k_flame_var_swirl(K_FlamePt t, float w)
{
    k_vec2 sc = k_sincos(t.sumsq);
    return k_vec2(w * (sc.x * t.tx - sc.y * t.ty), w * (sc.y * t.tx + sc.x * t.ty));
}

K_FN k_vec2 k_flame_var_horseshoe(K_FlamePt t, float w)
{
    float r = kx_div(w, t.sq + K_FLAME_EPS);
    return k_vec2((t.tx - t.ty) * (t.tx + t.ty) * r, 2.0f * t.tx * t.ty * r);
}

K_FN k_vec2 k_flame_var_polar(K_FlamePt t, float w)
{
    return k_vec2(w * t.atxy * K_1_PI, w * (t.sq - 1.0f));
}

K_FN k_vec2 k_flame_var_handkerchief(K_FlamePt t, float w)
{
    return k_vec2(w * t.sq * k_xsin(t.atxy + t.sq), w * t.sq * k_xcos(t.atxy - t.sq));
}

K_FN k_vec2 k_flame_var_heart(K_FlamePt t, float w)
{
    float r = w * t.sq;
    k_vec2 sc = k_sincos(t.sq * t.atxy);
    return k_vec2(r * sc.x, -r * sc.y);
}

K_FN k_vec2 k_flame_var_disc(K_FlamePt t, float w)
{
    float a = t.atxy * K_1_PI;
    k_vec2 sc = k_sincos(K_PI * t.sq);
    return k_vec2(w * sc.x * a, w * sc.y * a);
}

K_FN k_vec2 k_flame_var_spiral(K_FlamePt t, float w)
{
    float r = t.sq + K_FLAME_EPS, r1 = kx_div(w, r);
    k_vec2 sc = k_sincos(r);
    return k_vec2(r1 * (t.cosa + sc.x), r1 * (t.sina - sc.y));
}

K_FN k_vec2 k_flame_var_hyperbolic(K_FlamePt t, float w)
{
    float r = t.sq + K_FLAME_EPS;
    return k_vec2(kx_div(w * t.sina, r), w * t.cosa * r);
}

K_FN k_vec2 k_flame_var_diamond(K_FlamePt t, float w)
{
    k_vec2 sc = k_sincos(t.sq);
    return k_vec2(w * t.sina * sc.y, w * t.cosa * sc.x);
}

K_FN k_vec2 k_flame_var_ex(K_FlamePt t, float w)
{
    float n0 = k_xsin(t.atxy + t.sq), n1 = k_xcos(t.atxy - t.sq);
    float m0 = n0 * n0 * n0 * t.sq, m1 = n1 * n1 * n1 * t.sq;
    return k_vec2(w * (m0 + m1), w * (m0 - m1));
}

/* julia's random bit is the low bit of the draw's hash */
K_FN k_vec2 k_flame_var_julia(K_FlamePt t, float w, uint key, uint n)
{
    float a = 0.5f * t.atxy;
    if ((k_hash(n ^ key) & 1u) != 0u) a += K_PI;
    float r = w * kx_sqrt(t.sq);
    k_vec2 sc = k_sincos(a);
    return k_vec2(r * sc.y, r * sc.x);
}

K_FN k_vec2 k_flame_var_bent(K_FlamePt t, float w)
{
    float nx = t.tx < 0.0f ? t.tx * 2.0f : t.tx;
    float ny = t.ty < 0.0f ? t.ty * 0.5f : t.ty;
    return k_vec2(w * nx, w * ny);
}

/* p0, p1: the coefficients c10, c11; p2, p3: 1 / (c20^2 + EPS), 1 / (c21^2 + EPS) */
K_FN k_vec2 k_flame_var_waves(K_FlamePt t, K_FlameVar V)
{
    return k_vec2(V.w * (t.tx + V.p0 * k_xsin(t.ty * V.p2)), V.w * (t.ty + V.p1 * k_xsin(t.tx * V.p3)));
}

/* flam3 swaps x and y here */
K_FN k_vec2 k_flame_var_fisheye(K_FlamePt t, float w)
{
    float r = kx_div(2.0f * w, t.sq + 1.0f);
    return k_vec2(r * t.ty, r * t.tx);
}

/* p0, p1: the coefficients c20, c21 */
K_FN k_vec2 k_flame_var_popcorn(K_FlamePt t, K_FlameVar V)
{
    return k_vec2(V.w * (t.tx + V.p0 * k_xsin(k_xtan(3.0f * t.ty))), V.w * (t.ty + V.p1 * k_xsin(k_xtan(3.0f * t.tx))));
}

K_FN k_vec2 k_flame_var_exponential(K_FlamePt t, float w)
{
    float dx = w * k_xexp(t.tx - 1.0f);
    k_vec2 sc = k_sincos(K_PI * t.ty);
    return k_vec2(dx * sc.y, dx * sc.x);
}

K_FN k_vec2 k_flame_var_power(K_FlamePt t, float w)
{
    float r = w * k_xpow(t.sq, t.sina);
    return k_vec2(r * t.cosa, r * t.sina);
}

K_FN k_vec2 k_flame_var_cosine(K_FlamePt t, float w)
{
    k_vec2 sc = k_sincos(t.tx * K_PI), sh = k_xsinhcosh(t.ty);
    return k_vec2(w * sc.y * sh.y, w * -sc.x * sh.x);
}

/* p0: c20^2 + EPS */
K_FN k_vec2 k_flame_var_rings(K_FlamePt t, K_FlameVar V)
{
    float dx = V.p0;
    float r = V.w * (k_xfmod(t.sq + dx, 2.0f * dx) - dx + t.sq * (1.0f - dx));
    return k_vec2(r * t.cosa, r * t.sina);
}

/* p0: pi (c20^2 + EPS); p1: c21 */
K_FN k_vec2 k_flame_var_fan(K_FlamePt t, K_FlameVar V)
{
    float dx = V.p0, dy = V.p1, dx2 = 0.5f * dx;
    float a = t.atxy + (k_xfmod(t.atxy + dy, dx) > dx2 ? -dx2 : dx2);
    float r = V.w * t.sq;
    k_vec2 sc = k_sincos(a);
    return k_vec2(r * sc.y, r * sc.x);
}

/* p0: low; p1: high - low; p2: waves */
K_FN k_vec2 k_flame_var_blob(K_FlamePt t, K_FlameVar V)
{
    float r = t.sq * (V.p0 + V.p1 * (0.5f + 0.5f * k_xsin(V.p2 * t.atxy)));
    return k_vec2(V.w * t.sina * r, V.w * t.cosa * r);
}

/* p0 .. p3: a, b, c, d */
K_FN k_vec2 k_flame_var_pdj(K_FlamePt t, K_FlameVar V)
{
    return k_vec2(V.w * (k_xsin(V.p0 * t.ty) - k_xcos(V.p1 * t.tx)), V.w * (k_xsin(V.p2 * t.tx) - k_xcos(V.p3 * t.ty)));
}

/* p0: pi (x^2 + EPS); p1: y. flam3's (int) of a huge quotient: k_flame_itrunc */
K_FN k_vec2 k_flame_var_fan2(K_FlamePt t, K_FlameVar V)
{
    float dx = V.p0, dy = V.p1, dx2 = 0.5f * dx;
    float tt = t.atxy + dy - dx * k_flame_itrunc(kx_div(t.atxy + dy, dx));
    float a = tt > dx2 ? t.atxy - dx2 : t.atxy + dx2;
    float r = V.w * t.sq;
    k_vec2 sc = k_sincos(a);
    return k_vec2(r * sc.x, r * sc.y);
}

/* p0: val^2 + EPS */
K_FN k_vec2 k_flame_var_rings2(K_FlamePt t, K_FlameVar V)
{
    float dx = V.p0;
    float r = t.sq + (-2.0f * dx * k_flame_itrunc(kx_div(t.sq + dx, 2.0f * dx)) + t.sq * (1.0f - dx));
    return k_vec2(V.w * t.sina * r, V.w * t.cosa * r);
}

K_FN k_vec2 k_flame_var_eyefish(K_FlamePt t, float w)
{
    float r = kx_div(w * 2.0f, t.sq + 1.0f);
    return k_vec2(r * t.tx, r * t.ty);
}

K_FN k_vec2 k_flame_var_bubble(K_FlamePt t, float w)
{
    float r = kx_div(w, 0.25f * t.sumsq + 1.0f);
    return k_vec2(r * t.tx, r * t.ty);
}

K_FN k_vec2 k_flame_var_cylinder(K_FlamePt t, float w)
{
    return k_vec2(w * k_xsin(t.tx), w * t.ty);
}

/* p0: dist; p1: sin(angle pi / 2); p2: dist cos(angle pi / 2) */
K_FN k_vec2 k_flame_var_perspective(K_FlamePt t, K_FlameVar V)
{
    float tt = kx_div(1.0f, V.p0 - t.ty * V.p1);
    return k_vec2(V.w * V.p0 * t.tx * tt, V.w * V.p2 * t.ty * tt);
}

K_FN k_vec2 k_flame_var_noise(K_FlamePt t, float w, uint key, uint n)
{
    k_vec2 sc = k_sincos(K_FLAME_DRAW(0u) * 2.0f * K_PI);
    float r = w * K_FLAME_DRAW(1u);
    return k_vec2(t.tx * r * sc.y, t.ty * r * sc.x);
}

/* p0: power; p1: dist / power / 2; p2: |power| */
K_FN k_vec2 k_flame_var_julian(K_FlamePt t, K_FlameVar V, uint key, uint n)
{
    float tr = k_trunc(V.p2 * K_FLAME_DRAW(0u));
    k_vec2 sc = k_sincos(kx_div(t.atyx + 2.0f * K_PI * tr, V.p0));
    float r = V.w * k_xpow(t.sumsq, V.p1);
    return k_vec2(r * sc.y, r * sc.x);
}

/* as julian */
K_FN k_vec2 k_flame_var_juliascope(K_FlamePt t, K_FlameVar V, uint key, uint n)
{
    int tr = K_I(k_trunc(V.p2 * K_FLAME_DRAW(0u)));
    float a = kx_div((tr & 1) == 0 ? 2.0f * K_PI * K_F(tr) + t.atyx : 2.0f * K_PI * K_F(tr) - t.atyx, V.p0);
    float r = V.w * k_xpow(t.sumsq, V.p1);
    k_vec2 sc = k_sincos(a);
    return k_vec2(r * sc.y, r * sc.x);
}

K_FN k_vec2 k_flame_var_blur(K_FlamePt t, float w, uint key, uint n)
{
    k_vec2 sc = k_sincos(K_FLAME_DRAW(0u) * 2.0f * K_PI);
    float r = w * K_FLAME_DRAW(1u);
    return k_vec2(r * sc.y, r * sc.x);
}

K_FN k_vec2 k_flame_var_gaussian_blur(K_FlamePt t, float w, uint key, uint n)
{
    k_vec2 sc = k_sincos(K_FLAME_DRAW(0u) * 2.0f * K_PI);
    float g = K_FLAME_DRAW(1u);
    g += K_FLAME_DRAW(2u);
    g += K_FLAME_DRAW(3u);
    g += K_FLAME_DRAW(4u);
    float r = w * (g - 2.0f);
    return k_vec2(r * sc.y, r * sc.x);
}

/* p0, p1: sin and cos of angle pi / 2 (spin and zoom) */
K_FN k_vec2 k_flame_var_radial_blur(K_FlamePt t, K_FlameVar V, uint key, uint n)
{
    float g = K_FLAME_DRAW(0u);
    g += K_FLAME_DRAW(1u);
    g += K_FLAME_DRAW(2u);
    g += K_FLAME_DRAW(3u);
    float rnd = V.w * (g - 2.0f);
    k_vec2 sc = k_sincos(t.atyx + V.p0 * rnd);
    float rz = V.p1 * rnd - 1.0f;
    return k_vec2(t.sq * sc.y + rz * t.tx, t.sq * sc.x + rz * t.ty);
}

/* p0: slices; p1: rotation; p2: thickness */
K_FN k_vec2 k_flame_var_pie(K_FlamePt t, K_FlameVar V, uint key, uint n)
{
    float sl = K_F(K_I(K_FLAME_DRAW(0u) * V.p0 + 0.5f));
    float a = V.p1 + kx_div(2.0f * K_PI * (sl + K_FLAME_DRAW(1u) * V.p2), V.p0);
    float r = V.w * K_FLAME_DRAW(2u);
    k_vec2 sc = k_sincos(a);
    return k_vec2(r * sc.y, r * sc.x);
}

/* p0: power / 2; p1: 2 pi / sides; p2: corners; p3: circle */
K_FN k_vec2 k_flame_var_ngon(K_FlamePt t, K_FlameVar V)
{
    float rf = k_xpow(t.sumsq, V.p0);
    float b = V.p1;
    float phi = t.atyx - b * k_floor(kx_div(t.atyx, b));
    if (phi > b * 0.5f) phi -= b;
    float amp = V.p2 * (kx_div(1.0f, k_xcos(phi) + K_FLAME_EPS) - 1.0f) + V.p3;
    amp = kx_div(amp, rf + K_FLAME_EPS);
    return k_vec2(V.w * t.tx * amp, V.w * t.ty * amp);
}

/* p0, p1: c1, c2 */
K_FN k_vec2 k_flame_var_curl(K_FlamePt t, K_FlameVar V)
{
    float re = 1.0f + V.p0 * t.tx + V.p1 * (t.tx * t.tx - t.ty * t.ty);
    float im = V.p0 * t.ty + 2.0f * V.p1 * t.tx * t.ty;
    float r = kx_div(V.w, re * re + im * im);
    return k_vec2((t.tx * re + t.ty * im) * r, (t.ty * re - t.tx * im) * r);
}

/* p0, p1: x, y */
K_FN k_vec2 k_flame_var_rectangles(K_FlamePt t, K_FlameVar V)
{
    float w = V.w;
    return k_vec2(V.p0 == 0.0f ? w * t.tx : w * ((2.0f * k_floor(kx_div(t.tx, V.p0)) + 1.0f) * V.p0 - t.tx),
                  V.p1 == 0.0f ? w * t.ty : w * ((2.0f * k_floor(kx_div(t.ty, V.p1)) + 1.0f) * V.p1 - t.ty));
}

/* the weight inside the angle, as flam3 */
K_FN k_vec2 k_flame_var_arch(K_FlamePt t, float w, uint key, uint n)
{
    k_vec2 sc = k_sincos(K_FLAME_DRAW(0u) * w * K_PI);
    return k_vec2(w * sc.x, kx_div(w * (sc.x * sc.x), sc.y));
}

K_FN k_vec2 k_flame_var_tangent(K_FlamePt t, float w)
{
    return k_vec2(kx_div(w * k_xsin(t.tx), k_xcos(t.ty)), w * k_xtan(t.ty));
}

K_FN k_vec2 k_flame_var_square(K_FlamePt t, float w, uint key, uint n)
{
    return k_vec2(w * (K_FLAME_DRAW(0u) - 0.5f), w * (K_FLAME_DRAW(1u) - 0.5f));
}

K_FN k_vec2 k_flame_var_rays(K_FlamePt t, float w, uint key, uint n)
{
    float a = w * K_FLAME_DRAW(0u) * K_PI;
    float r = kx_div(w, t.sumsq + K_FLAME_EPS);
    float tr = w * k_xtan(a) * r;
    return k_vec2(tr * k_xcos(t.tx), tr * k_xsin(t.ty));
}

K_FN k_vec2 k_flame_var_blade(K_FlamePt t, float w, uint key, uint n)
{
    k_vec2 sc = k_sincos(K_FLAME_DRAW(0u) * w * t.sq);
    return k_vec2(w * t.tx * (sc.y + sc.x), w * t.tx * (sc.y - sc.x));
}

K_FN k_vec2 k_flame_var_secant2(K_FlamePt t, float w)
{
    float cr = k_xcos(w * t.sq), icr = kx_div(1.0f, cr);
    return k_vec2(w * t.tx, cr < 0.0f ? w * (icr + 1.0f) : w * (icr - 1.0f));
}

/* log10 as ln times log10(e); a bad value becomes -30, as flam3 */
K_FN k_vec2 k_flame_var_twintrian(K_FlamePt t, float w, uint key, uint n)
{
    k_vec2 sc = k_sincos(K_FLAME_DRAW(0u) * w * t.sq);
    float s = sc.x;
    float diff = k_xlog(s * s) * 0.434294492f + sc.y;
    if (k_isnan(diff) || diff > 1e10f || diff < -1e10f) diff = -30.0f;
    return k_vec2(w * t.tx * diff, w * t.tx * (diff - s * K_PI));
}

K_FN k_vec2 k_flame_var_cross(K_FlamePt t, float w)
{
    float s = t.tx * t.tx - t.ty * t.ty;
    float r = w * kx_sqrt(kx_div(1.0f, s * s + K_FLAME_EPS));
    return k_vec2(t.tx * r, t.ty * r);
}

/* p0: rot pi; p1, p2: flam3's sinadd and cosadd of the twist */
K_FN k_vec2 k_flame_var_disc2(K_FlamePt t, K_FlameVar V)
{
    k_vec2 sc = k_sincos(V.p0 * (t.tx + t.ty));
    float r = kx_div(V.w * t.atxy, K_PI);
    return k_vec2((sc.x + V.p2) * r, (sc.y + V.p1) * r);
}

/* p0: m / 4; p1, p2: n2, n3; p3: rnd; p4: holes; p5: -1 / n1 */
K_FN k_vec2 k_flame_var_super_shape(K_FlamePt t, K_FlameVar V, uint key, uint n)
{
    k_vec2 sc = k_sincos(V.p0 * t.atyx + 0.25f * K_PI);
    float t1 = k_xpow(k_abs(sc.y), V.p1);
    float t2 = k_xpow(k_abs(sc.x), V.p2);
    float rnd = V.p3;
    float r = kx_div(V.w * ((rnd * K_FLAME_DRAW(0u) + (1.0f - rnd) * t.sq) - V.p4) * k_xpow(t1 + t2, V.p5), t.sq);
    return k_vec2(r * t.tx, r * t.ty);
}

/* p0: petals; p1: holes */
K_FN k_vec2 k_flame_var_flower(K_FlamePt t, K_FlameVar V, uint key, uint n)
{
    float r = kx_div(V.w * (K_FLAME_DRAW(0u) - V.p1) * k_xcos(V.p0 * t.atyx), t.sq);
    return k_vec2(r * t.tx, r * t.ty);
}

/* p0: eccentricity; p1: holes */
K_FN k_vec2 k_flame_var_conic(K_FlamePt t, K_FlameVar V, uint key, uint n)
{
    float ct = kx_div(t.tx, t.sq);
    float r = kx_div(kx_div(V.w * (K_FLAME_DRAW(0u) - V.p1) * V.p0, 1.0f + V.p0 * ct), t.sq);
    return k_vec2(r * t.tx, r * t.ty);
}

/* p0, p1: height, width */
K_FN k_vec2 k_flame_var_parabola(K_FlamePt t, K_FlameVar V, uint key, uint n)
{
    k_vec2 sc = k_sincos(t.sq);
    return k_vec2(V.p0 * V.w * sc.x * sc.x * K_FLAME_DRAW(0u), V.p1 * V.w * sc.y * K_FLAME_DRAW(1u));
}

/* p0, p1: x, y */
K_FN k_vec2 k_flame_var_bent2(K_FlamePt t, K_FlameVar V)
{
    float nx = t.tx < 0.0f ? t.tx * V.p0 : t.tx;
    float ny = t.ty < 0.0f ? t.ty * V.p1 : t.ty;
    return k_vec2(V.w * nx, V.w * ny);
}

/* ---- 55 .. 98: the Apophysis plugin pack's and later ones that flam3 took in -------------------- */

/* p0: -pi/2 shift */
K_FN k_vec2 k_flame_var_bipolar(K_FlamePt t, K_FlameVar V)
{
    float tt = t.sumsq + 1.0f, x2 = 2.0f * t.tx;
    float y = 0.5f * k_xatan2(2.0f * t.ty, t.sumsq - 1.0f) + V.p0;
    if (y > K_HALF_PI || y < -K_HALF_PI) {
        float f = k_xfmod(y > K_HALF_PI ? y + K_HALF_PI : K_HALF_PI - y, K_PI);
        y = y > K_HALF_PI ? -K_HALF_PI + f : K_HALF_PI - f;
    }
    return k_vec2(V.w * 0.25f * K_2_PI * k_xlog(kx_div(tt + x2, tt - x2)), V.w * K_2_PI * y);
}

K_FN k_vec2 k_flame_var_boarders(K_FlamePt t, float w, uint key, uint n)
{
    float rx = k_flame_rint(t.tx), ry = k_flame_rint(t.ty);
    float ox = t.tx - rx, oy = t.ty - ry;
    if (K_FLAME_DRAW(0u) >= 0.75f) return k_vec2(w * (ox * 0.5f + rx), w * (oy * 0.5f + ry));
    /* flam3's 0.25 oy / ox, or ox / oy then times 0.25: one division (a shader inlines each) */
    bool xbig = k_abs(ox) >= k_abs(oy);
    float q = kx_div(xbig ? 0.25f * oy : ox, xbig ? ox : oy);
    if (!xbig) q = q * 0.25f;
    if (xbig) {
        if (ox >= 0.0f) return k_vec2(w * (ox * 0.5f + rx + 0.25f), w * (oy * 0.5f + ry + q));
        return k_vec2(w * (ox * 0.5f + rx - 0.25f), w * (oy * 0.5f + ry - q));
    }
    if (oy >= 0.0f) return k_vec2(w * (ox * 0.5f + rx + q), w * (oy * 0.5f + ry + 0.25f));
    return k_vec2(w * (ox * 0.5f + rx - q), w * (oy * 0.5f + ry - 0.25f));
}

/* the weight times 4 / sqrt(3 pi) */
K_FN k_vec2 k_flame_var_butterfly(K_FlamePt t, float w)
{
    float wx = w * 1.30294001f;
    float y2 = t.ty * 2.0f;
    float r = wx * kx_sqrt(kx_div(k_abs(t.ty * t.tx), K_FLAME_EPS + t.tx * t.tx + y2 * y2));
    return k_vec2(r * t.tx, r * y2);
}

/* p0: size; p1: 1 / size. flam3's int cells, their interleaving in wrapping int arithmetic */
K_FN k_vec2 k_flame_var_cell(K_FlamePt t, K_FlameVar V)
{
    float fx = k_flame_itrunc(k_floor(t.tx * V.p1)), fy = k_flame_itrunc(k_floor(t.ty * V.p1));
    float dx = t.tx - fx * V.p0, dy = t.ty - fy * V.p0;
    uint ux = K_U(K_I(fx)), uy = K_U(K_I(fy));
    uy = fy >= 0.0f ? 2u * uy : 0u - (2u * uy + 1u);
    ux = fx >= 0.0f ? 2u * ux : 0u - (2u * ux + 1u);
    return k_vec2(V.w * (dx + K_F(K_I(ux)) * V.p0), -(V.w * (dy + K_F(K_I(uy)) * V.p0)));
}

/* p0: 2 pi / power; p1: r / power; p2: i / power; p3: power */
K_FN k_vec2 k_flame_var_cpow(K_FlamePt t, K_FlameVar V, uint key, uint n)
{
    float a = t.atyx, lnr = 0.5f * k_xlog(t.sumsq);
    float ang = V.p1 * a + V.p2 * lnr + V.p0 * k_floor(V.p3 * K_FLAME_DRAW(0u));
    float m = V.w * k_xexp(V.p1 * lnr - V.p2 * a);
    k_vec2 sc = k_sincos(ang);
    return k_vec2(m * sc.y, m * sc.x);
}

/* p0, p1: xamp, yamp; p2, p3: 1 / max(xlength^2, 1e-20), 1 / max(ylength^2, 1e-20) */
K_FN k_vec2 k_flame_var_curve(K_FlamePt t, K_FlameVar V)
{
    return k_vec2(V.w * (t.tx + V.p0 * k_xexp(-t.ty * t.ty * V.p2)), V.w * (t.ty + V.p1 * k_xexp(-t.tx * t.tx * V.p3)));
}

/* p0: the weight / 11.57034632 */
K_FN k_vec2 k_flame_var_edisc(K_FlamePt t, K_FlameVar V)
{
    float tmp = t.sumsq + 1.0f, tmp2 = 2.0f * t.tx;
    float r1 = kx_sqrt(tmp + tmp2), r2 = kx_sqrt(tmp - tmp2);
    float xmax = (r1 + r2) * 0.5f;
    float a1 = k_xlog(xmax + kx_sqrt(xmax - 1.0f));
    float a2 = -k_xacos(kx_div(t.tx, xmax));
    k_vec2 sc = k_sincos(a1);
    k_vec2 sh = k_xsinhcosh(a2);
    float snv = t.ty > 0.0f ? -sc.x : sc.x;
    return k_vec2(V.p0 * sh.y * sc.y, V.p0 * sh.x * snv);
}

/* p0: the weight / (pi / 2) */
K_FN k_vec2 k_flame_var_elliptic(K_FlamePt t, K_FlameVar V)
{
    float tmp = t.sumsq + 1.0f, x2 = 2.0f * t.tx;
    float xmax = 0.5f * (kx_sqrt(tmp + x2) + kx_sqrt(tmp - x2));
    float a = kx_div(t.tx, xmax);
    float b = 1.0f - a * a, ssx = xmax - 1.0f;
    b = b < 0.0f ? 0.0f : kx_sqrt(b);
    ssx = ssx < 0.0f ? 0.0f : kx_sqrt(ssx);
    float l = V.p0 * k_xlog(xmax + ssx);
    return k_vec2(V.p0 * k_xatan2(a, b), t.ty > 0.0f ? l : -l);
}

/* p0, p1: (1 + cos beta) / 2, sin(beta) / 2 */
K_FN k_vec2 k_flame_var_escher(K_FlamePt t, K_FlameVar V)
{
    float a = t.atyx, lnr = 0.5f * k_xlog(t.sumsq);
    float m = V.w * k_xexp(V.p0 * lnr - V.p1 * a);
    k_vec2 sc = k_sincos(V.p0 * a + V.p1 * lnr);
    return k_vec2(m * sc.y, m * sc.x);
}

/* where e^tx / 2 leaves float's range flam3's double gives (+-w, ~0) */
K_FN k_vec2 k_flame_var_foci(K_FlamePt t, float w)
{
    float expx = k_xexp(t.tx) * 0.5f;
    if (expx == 0.0f || k_isinf(expx)) return k_vec2(t.tx > 0.0f ? w : -w, 0.0f);
    float expnx = kx_div(0.25f, expx);
    k_vec2 sc = k_sincos(t.ty);
    float tmp = kx_div(w, expx + expnx - sc.y);
    return k_vec2(tmp * (expx - expnx), tmp * sc.x);
}

/* p0, p1: x, y; p2: spin; p3: space; p4: twist */
K_FN k_vec2 k_flame_var_lazysusan(K_FlamePt t, K_FlameVar V)
{
    float w = V.w, x = t.tx - V.p0, y = t.ty + V.p1;
    float r = kx_sqrt(x * x + y * y);
    if (r < w) {
        float a = k_xatan2(y, x) + V.p2 + V.p4 * (w - r);
        k_vec2 sc = k_sincos(a);
        r = w * r;
        return k_vec2(r * sc.y + V.p0, r * sc.x - V.p1);
    }
    r = w * (1.0f + kx_div(V.p3, r));
    return k_vec2(r * x + V.p0, r * y - V.p1);
}

/* the weight inside, as flam3 */
K_FN k_vec2 k_flame_var_loonie(K_FlamePt t, float w)
{
    float w2 = w * w;
    if (t.sumsq < w2) {
        float r = w * kx_sqrt(kx_div(w2, t.sumsq) - 1.0f);
        return k_vec2(r * t.tx, r * t.ty);
    }
    return k_vec2(w * t.tx, w * t.ty);
}

/* pre_blur: a pseudo-gaussian displacement of (tx, ty) itself, before the precalcs (flam3 applies
 * it ahead of the xform's other variations, with the variation's weight) */
K_FN k_vec2 k_flame_preblur(float tx, float ty, float w, uint key, uint n)
{
    float g = K_FLAME_DRAW(0u) + K_FLAME_DRAW(1u) + K_FLAME_DRAW(2u) + K_FLAME_DRAW(3u) - 2.0f;
    float rg = w * g;
    k_vec2 sc = k_sincos(K_FLAME_DRAW(4u) * 2.0f * K_PI);
    return k_vec2(tx + rg * sc.y, ty + rg * sc.x);
}

/* one axis of modulus: m, its parameter (one fmod: a shader inlines each) */
K_FN float k_flame_modulus1(float v, float m, float w)
{
    if (v > m || v < -m) {
        float f = k_xfmod(v > m ? v + m : m - v, 2.0f * m);
        return v > m ? w * (-m + f) : w * (m - f);
    }
    return w * v;
}

/* p0, p1: x, y */
K_FN k_vec2 k_flame_var_modulus(K_FlamePt t, K_FlameVar V)
{
    return k_vec2(k_flame_modulus1(t.tx, V.p0, V.w), k_flame_modulus1(t.ty, V.p1, V.w));
}

/* p0: 2 pi frequency; p1: amplitude; p2: damping; p3: separation */
K_FN k_vec2 k_flame_var_oscilloscope(K_FlamePt t, K_FlameVar V)
{
    float c = k_xcos(V.p0 * t.tx);
    float tt = V.p2 == 0.0f ? V.p1 * c + V.p3 : V.p1 * k_xexp(-k_abs(t.tx) * V.p2) * c + V.p3;
    return k_vec2(V.w * t.tx, k_abs(t.ty) <= tt ? -(V.w * t.ty) : V.w * t.ty);
}

/* p0: the weight / pi */
K_FN k_vec2 k_flame_var_polar2(K_FlamePt t, K_FlameVar V)
{
    return k_vec2(V.p0 * t.atxy, V.p0 * 0.5f * k_xlog(t.sumsq));
}

/* p0, p1: x, y; p2: c */
K_FN k_vec2 k_flame_var_popcorn2(K_FlamePt t, K_FlameVar V)
{
    return k_vec2(V.w * (t.tx + V.p0 * k_xsin(k_xtan(t.ty * V.p2))), V.w * (t.ty + V.p1 * k_xsin(k_xtan(t.tx * V.p2))));
}

/* p0: 1 / (weight + EPS); the weight used only there, as flam3 */
K_FN k_vec2 k_flame_var_scry(K_FlamePt t, K_FlameVar V)
{
    float r = kx_div(1.0f, t.sq * (t.sumsq + V.p0));
    return k_vec2(t.tx * r, t.ty * r);
}

/* one axis of separation: s2, its parameter squared; in, its inside */
K_FN float k_flame_separation1(float v, float s2, float ins, float w)
{
    float r = kx_sqrt(v * v + s2);
    return v > 0.0f ? w * (r - v * ins) : -(w * (r + v * ins));
}

/* p0, p1: x^2, xinside; p2, p3: y^2, yinside */
K_FN k_vec2 k_flame_var_separation(K_FlamePt t, K_FlameVar V)
{
    return k_vec2(k_flame_separation1(t.tx, V.p0, V.p1, V.w), k_flame_separation1(t.ty, V.p2, V.p3, V.w));
}

/* p0, p1: xsize, ysize */
K_FN k_vec2 k_flame_var_split(K_FlamePt t, K_FlameVar V)
{
    float y = k_xcos(t.tx * V.p0 * K_PI) >= 0.0f ? V.w * t.ty : -(V.w * t.ty);
    float x = k_xcos(t.ty * V.p1 * K_PI) >= 0.0f ? V.w * t.tx : -(V.w * t.tx);
    return k_vec2(x, y);
}

/* p0, p1: x, y */
K_FN k_vec2 k_flame_var_splits(K_FlamePt t, K_FlameVar V)
{
    return k_vec2(t.tx >= 0.0f ? V.w * (t.tx + V.p0) : V.w * (t.tx - V.p0),
                  t.ty >= 0.0f ? V.w * (t.ty + V.p1) : V.w * (t.ty - V.p1));
}

/* p0: 1 - space; p1: warp */
K_FN k_vec2 k_flame_var_stripes(K_FlamePt t, K_FlameVar V)
{
    float rx = k_floor(t.tx + 0.5f), ox = t.tx - rx;
    return k_vec2(V.w * (ox * V.p0 + rx), V.w * (t.ty + ox * ox * V.p1));
}

/* wedge's and wedge_sph's common end: the angle a folded into count wedges (comp, flam3's comp_fac)
 * and the radius r */
K_FN k_vec2 k_flame_wedge(float a, float r, float count, float angle, float comp)
{
    float c = k_floor((count * a + K_PI) * K_1_PI * 0.5f);
    k_vec2 sc = k_sincos(a * comp + c * angle);
    return k_vec2(r * sc.y, r * sc.x);
}

/* p0: angle; p1: hole; p2: count; p3: swirl; p4: 1 - angle count / (2 pi) */
K_FN k_vec2 k_flame_var_wedge(K_FlamePt t, K_FlameVar V)
{
    return k_flame_wedge(t.atyx + V.p3 * t.sq, V.w * (t.sq + V.p1), V.p2, V.p0, V.p4);
}

/* p0: power; p1: dist / power / 2; p2: |power|; p3: count; p4: angle; p5: 1 - angle count / (2 pi) */
K_FN k_vec2 k_flame_var_wedge_julia(K_FlamePt t, K_FlameVar V, uint key, uint n)
{
    float r = V.w * k_xpow(t.sumsq, V.p1);
    float tr = k_flame_itrunc(V.p2 * K_FLAME_DRAW(0u));
    float a = kx_div(t.atyx + 2.0f * K_PI * tr, V.p0);
    return k_flame_wedge(a, r, V.p3, V.p4, V.p5);
}

/* as wedge */
K_FN k_vec2 k_flame_var_wedge_sph(K_FlamePt t, K_FlameVar V)
{
    float r = kx_div(1.0f, t.sq + K_FLAME_EPS);
    return k_flame_wedge(t.atyx + V.p3 * r, V.w * (r + V.p1), V.p2, V.p0, V.p4);
}

/* p0, p1: inside, outside; the weight as a radius too, as flam3 */
K_FN k_vec2 k_flame_var_whorl(K_FlamePt t, K_FlameVar V)
{
    float r = t.sq;
    float a = t.atyx + kx_div(r < V.w ? V.p0 : V.p1, V.w - r);
    k_vec2 sc = k_sincos(a);
    return k_vec2(V.w * r * sc.y, V.w * r * sc.x);
}

/* p0, p1: scalex, scaley; p2, p3: freqx, freqy */
K_FN k_vec2 k_flame_var_waves2(K_FlamePt t, K_FlameVar V)
{
    return k_vec2(V.w * (t.tx + V.p0 * k_xsin(t.ty * V.p2)), V.w * (t.ty + V.p1 * k_xsin(t.tx * V.p3)));
}

/* ---- the complex functions (exp, log, sin ... coth) --------------------------------------------- */

K_FN k_vec2 k_flame_var_exp(K_FlamePt t, float w)
{
    float e = k_xexp(t.tx);
    k_vec2 sc = k_sincos(t.ty);
    return k_vec2(w * e * sc.y, w * e * sc.x);
}

K_FN k_vec2 k_flame_var_log(K_FlamePt t, float w)
{
    return k_vec2(w * 0.5f * k_xlog(t.sumsq), w * t.atyx);
}

K_FN k_vec2 k_flame_var_sin(K_FlamePt t, float w)
{
    k_vec2 sc = k_sincos(t.tx), sh = k_xsinhcosh(t.ty);
    return k_vec2(w * sc.x * sh.y, w * sc.y * sh.x);
}

K_FN k_vec2 k_flame_var_cos(K_FlamePt t, float w)
{
    k_vec2 sc = k_sincos(t.tx), sh = k_xsinhcosh(t.ty);
    return k_vec2(w * sc.y * sh.y, -(w * sc.x * sh.x));
}

/* The parts of the complex tangents (tan and cot: a = x, b = y; tanh and coth: a = y, b = x):
 * (sin 2a, sinh 2b, 1 / (cosh 2b + s cos 2a)), s = 1 for tan and tanh, -1 for cot and coth. The third
 * is 0 where cosh 2b leaves float's range: there the functions tend to +-i or +-1, and the callers
 * return flam3's double limit, not 0 x inf. */
K_FN k_vec3 k_flame_tangents(float a, float b, float s)
{
    k_vec2 sc = k_sincos(2.0f * a), sh = k_xsinhcosh(2.0f * b);
    return k_vec3(sc.x, sh.x, k_isinf(sh.y) ? 0.0f : kx_div(1.0f, sh.y + s * sc.y));
}

/* 2 / (cosh 2b + s cos 2a), the secants' (sec and csc: a = x, b = y; sech and csch: a = y, b = x;
 * s = 1 for sec and sech, -1 for csc and csch); 0 where cosh 2b leaves float's range (the
 * functions tend to 0 there, and the callers return 0, not 0 x inf). */
K_FN float k_flame_secants(float a, float b, float s)
{
    float ch2 = k_xcosh(2.0f * b);
    return k_isinf(ch2) ? 0.0f : kx_div(2.0f, ch2 + s * k_xcos(2.0f * a));
}

K_FN k_vec2 k_flame_var_tan(K_FlamePt t, float w)
{
    k_vec3 p = k_flame_tangents(t.tx, t.ty, 1.0f);
    if (p.z == 0.0f) return k_vec2(0.0f, t.ty > 0.0f ? w : -w);
    return k_vec2(w * p.z * p.x, w * p.z * p.y);
}

K_FN k_vec2 k_flame_var_sec(K_FlamePt t, float w)
{
    float den = k_flame_secants(t.tx, t.ty, 1.0f);
    if (den == 0.0f) return k_vec2(0.0f, 0.0f);
    k_vec2 sc = k_sincos(t.tx), sh = k_xsinhcosh(t.ty);
    return k_vec2(w * den * sc.y * sh.y, w * den * sc.x * sh.x);
}

K_FN k_vec2 k_flame_var_csc(K_FlamePt t, float w)
{
    float den = k_flame_secants(t.tx, t.ty, -1.0f);
    if (den == 0.0f) return k_vec2(0.0f, 0.0f);
    k_vec2 sc = k_sincos(t.tx), sh = k_xsinhcosh(t.ty);
    return k_vec2(w * den * sc.x * sh.y, -(w * den * sc.y * sh.x));
}

K_FN k_vec2 k_flame_var_cot(K_FlamePt t, float w)
{
    k_vec3 p = k_flame_tangents(t.tx, t.ty, -1.0f);
    if (p.z == 0.0f) return k_vec2(0.0f, t.ty > 0.0f ? -w : w);
    return k_vec2(w * p.z * p.x, w * p.z * -1.0f * p.y);
}

K_FN k_vec2 k_flame_var_sinh(K_FlamePt t, float w)
{
    k_vec2 sc = k_sincos(t.ty), sh = k_xsinhcosh(t.tx);
    return k_vec2(w * sh.x * sc.y, w * sh.y * sc.x);
}

K_FN k_vec2 k_flame_var_cosh(K_FlamePt t, float w)
{
    k_vec2 sc = k_sincos(t.ty), sh = k_xsinhcosh(t.tx);
    return k_vec2(w * sh.y * sc.y, w * sh.x * sc.x);
}

K_FN k_vec2 k_flame_var_tanh(K_FlamePt t, float w)
{
    k_vec3 p = k_flame_tangents(t.ty, t.tx, 1.0f);
    if (p.z == 0.0f) return k_vec2(t.tx > 0.0f ? w : -w, 0.0f);
    return k_vec2(w * p.z * p.y, w * p.z * p.x);
}

K_FN k_vec2 k_flame_var_sech(K_FlamePt t, float w)
{
    float den = k_flame_secants(t.ty, t.tx, 1.0f);
    if (den == 0.0f) return k_vec2(0.0f, 0.0f);
    k_vec2 sc = k_sincos(t.ty), sh = k_xsinhcosh(t.tx);
    return k_vec2(w * den * sc.y * sh.y, -(w * den * sc.x * sh.x));
}

K_FN k_vec2 k_flame_var_csch(K_FlamePt t, float w)
{
    float den = k_flame_secants(t.ty, t.tx, -1.0f);
    if (den == 0.0f) return k_vec2(0.0f, 0.0f);
    k_vec2 sc = k_sincos(t.ty), sh = k_xsinhcosh(t.tx);
    return k_vec2(w * den * sh.x * sc.y, -(w * den * sh.y * sc.x));
}

K_FN k_vec2 k_flame_var_coth(K_FlamePt t, float w)
{
    k_vec3 p = k_flame_tangents(t.ty, t.tx, -1.0f);
    if (p.z == 0.0f) return k_vec2(t.tx > 0.0f ? w : -w, 0.0f);
    return k_vec2(w * p.z * p.y, w * p.z * p.x);
}

/* ---- auger, flux, mobius ------------------------------------------------------------------------ */

/* p0: freq; p1: weight (auger's own); p2: sym; p3: scale */
K_FN k_vec2 k_flame_var_auger(K_FlamePt t, K_FlameVar V)
{
    float s = k_xsin(V.p0 * t.tx), u = k_xsin(V.p0 * t.ty);
    float dy = t.ty + V.p1 * (V.p3 * s * 0.5f + k_abs(t.ty) * s);
    float dx = t.tx + V.p1 * (V.p3 * u * 0.5f + k_abs(t.tx) * u);
    return k_vec2(V.w * (t.tx + V.p2 * (dx - t.tx)), V.w * dy);
}

/* p0: 2 + spread; the weight as a distance too, as flam3 */
K_FN k_vec2 k_flame_var_flux(K_FlamePt t, K_FlameVar V)
{
    float xpw = t.tx + V.w, xmw = t.tx - V.w;
    float q = kx_div(kx_sqrt(t.ty * t.ty + xpw * xpw), kx_sqrt(t.ty * t.ty + xmw * xmw));
    float avgr = V.w * V.p0 * kx_sqrt(q);
    float avga = (k_xatan2(t.ty, xmw) - k_xatan2(t.ty, xpw)) * 0.5f;
    k_vec2 sc = k_sincos(avga);
    return k_vec2(avgr * sc.y, avgr * sc.x);
}

/* p0 .. p7: re_a, im_a, re_b, im_b, re_c, im_c, re_d, im_d: w (a z + b) / (c z + d) */
K_FN k_vec2 k_flame_var_mobius(K_FlamePt t, K_FlameVar V)
{
    float re_u = V.p0 * t.tx - V.p1 * t.ty + V.p2, im_u = V.p0 * t.ty + V.p1 * t.tx + V.p3;
    float re_v = V.p4 * t.tx - V.p5 * t.ty + V.p6, im_v = V.p4 * t.ty + V.p5 * t.tx + V.p7;
    float rad_v = kx_div(V.w, re_v * re_v + im_v * im_v);
    return k_vec2(rad_v * (re_u * re_v + im_u * im_v), rad_v * (im_u * re_v - re_u * im_v));
}

/* ---- the switch ----------------------------------------------------------------------------------- */

/* Whether variation v's code is compiled: a shader may define K_FLAME_VMASK0 .. K_FLAME_VMASK3 as
 * specialisation constants, the genome's variations 0-31, 32-63, 64-95 and 96-98 as bits, so that a
 * pipeline carries only the genome's variations (lavapipe runs every branch that any of its 8
 * lanes takes, and compiles every branch it is given: pipeline creation time). In C every variation
 * is there. */
#ifdef K_GLSL
#ifndef K_FLAME_VMASK0
#define K_FLAME_VMASK0 0xffffffffu
#define K_FLAME_VMASK1 0xffffffffu
#define K_FLAME_VMASK2 0xffffffffu
#define K_FLAME_VMASK3 0x7u
#endif
#define K_FLAME_VWORD(w)                                                                                               \
    ((w) == 0u ? K_FLAME_VMASK0 : (w) == 1u ? K_FLAME_VMASK1 : (w) == 2u ? K_FLAME_VMASK2 : K_FLAME_VMASK3)
#define K_FLAME_HAS(v) (((K_FLAME_VWORD((v) >> 5u) >> ((v)&31u)) & 1u) != 0u)
#else
#define K_FLAME_HAS(v) true
#endif

/* A variation's contribution to the xform's sums and the draws it took. */
K_STRUCT(K_FlameD)
{
    float x, y;
    uint draws;
}
K_END(K_FlameD)

/* Every variation but pre_blur, in ascending order of number: X(number, its function at t with weight w,
 * parameters V and draws from (key, n), the number of draws). The switch below is made of it, and a
 * shader's pass over the genome's variations (kernels/flame.h, K_FLAME_ONCE). */
#define K_FLAME_VARIATIONS(X)                                                                                          \
    X(K_V_LINEAR, k_flame_var_linear(t, w), 0u)                                                                        \
    X(K_V_SINUSOIDAL, k_flame_var_sinusoidal(t, w), 0u)                                                                \
    X(K_V_SPHERICAL, k_flame_var_spherical(t, w), 0u)                                                                  \
    X(K_V_SWIRL, k_flame_var_swirl(t, w), 0u)                                                                          \
    X(K_V_HORSESHOE, k_flame_var_horseshoe(t, w), 0u)                                                                  \
    X(K_V_POLAR, k_flame_var_polar(t, w), 0u)                                                                          \
    X(K_V_HANDKERCHIEF, k_flame_var_handkerchief(t, w), 0u)                                                            \
    X(K_V_HEART, k_flame_var_heart(t, w), 0u)                                                                          \
    X(K_V_DISC, k_flame_var_disc(t, w), 0u)                                                                            \
    X(K_V_SPIRAL, k_flame_var_spiral(t, w), 0u)                                                                        \
    X(K_V_HYPERBOLIC, k_flame_var_hyperbolic(t, w), 0u)                                                                \
    X(K_V_DIAMOND, k_flame_var_diamond(t, w), 0u)                                                                      \
    X(K_V_EX, k_flame_var_ex(t, w), 0u)                                                                                \
    X(K_V_JULIA, k_flame_var_julia(t, w, key, n), 1u)                                                                  \
    X(K_V_BENT, k_flame_var_bent(t, w), 0u)                                                                            \
    X(K_V_WAVES, k_flame_var_waves(t, V), 0u)                                                                          \
    X(K_V_FISHEYE, k_flame_var_fisheye(t, w), 0u)                                                                      \
    X(K_V_POPCORN, k_flame_var_popcorn(t, V), 0u)                                                                      \
    X(K_V_EXPONENTIAL, k_flame_var_exponential(t, w), 0u)                                                              \
    X(K_V_POWER, k_flame_var_power(t, w), 0u)                                                                          \
    X(K_V_COSINE, k_flame_var_cosine(t, w), 0u)                                                                        \
    X(K_V_RINGS, k_flame_var_rings(t, V), 0u)                                                                          \
    X(K_V_FAN, k_flame_var_fan(t, V), 0u)                                                                              \
    X(K_V_BLOB, k_flame_var_blob(t, V), 0u)                                                                            \
    X(K_V_PDJ, k_flame_var_pdj(t, V), 0u)                                                                              \
    X(K_V_FAN2, k_flame_var_fan2(t, V), 0u)                                                                            \
    X(K_V_RINGS2, k_flame_var_rings2(t, V), 0u)                                                                        \
    X(K_V_EYEFISH, k_flame_var_eyefish(t, w), 0u)                                                                      \
    X(K_V_BUBBLE, k_flame_var_bubble(t, w), 0u)                                                                        \
    X(K_V_CYLINDER, k_flame_var_cylinder(t, w), 0u)                                                                    \
    X(K_V_PERSPECTIVE, k_flame_var_perspective(t, V), 0u)                                                              \
    X(K_V_NOISE, k_flame_var_noise(t, w, key, n), 2u)                                                                  \
    X(K_V_JULIAN, k_flame_var_julian(t, V, key, n), 1u)                                                                \
    X(K_V_JULIASCOPE, k_flame_var_juliascope(t, V, key, n), 1u)                                                        \
    X(K_V_BLUR, k_flame_var_blur(t, w, key, n), 2u)                                                                    \
    X(K_V_GAUSSIAN_BLUR, k_flame_var_gaussian_blur(t, w, key, n), 5u)                                                  \
    X(K_V_RADIAL_BLUR, k_flame_var_radial_blur(t, V, key, n), 4u)                                                      \
    X(K_V_PIE, k_flame_var_pie(t, V, key, n), 3u)                                                                      \
    X(K_V_NGON, k_flame_var_ngon(t, V), 0u)                                                                            \
    X(K_V_CURL, k_flame_var_curl(t, V), 0u)                                                                            \
    X(K_V_RECTANGLES, k_flame_var_rectangles(t, V), 0u)                                                                \
    X(K_V_ARCH, k_flame_var_arch(t, w, key, n), 1u)                                                                    \
    X(K_V_TANGENT, k_flame_var_tangent(t, w), 0u)                                                                      \
    X(K_V_SQUARE, k_flame_var_square(t, w, key, n), 2u)                                                                \
    X(K_V_RAYS, k_flame_var_rays(t, w, key, n), 1u)                                                                    \
    X(K_V_BLADE, k_flame_var_blade(t, w, key, n), 1u)                                                                  \
    X(K_V_SECANT2, k_flame_var_secant2(t, w), 0u)                                                                      \
    X(K_V_TWINTRIAN, k_flame_var_twintrian(t, w, key, n), 1u)                                                          \
    X(K_V_CROSS, k_flame_var_cross(t, w), 0u)                                                                          \
    X(K_V_DISC2, k_flame_var_disc2(t, V), 0u)                                                                          \
    X(K_V_SUPER_SHAPE, k_flame_var_super_shape(t, V, key, n), 1u)                                                      \
    X(K_V_FLOWER, k_flame_var_flower(t, V, key, n), 1u)                                                                \
    X(K_V_CONIC, k_flame_var_conic(t, V, key, n), 1u)                                                                  \
    X(K_V_PARABOLA, k_flame_var_parabola(t, V, key, n), 2u)                                                            \
    X(K_V_BENT2, k_flame_var_bent2(t, V), 0u)                                                                          \
    X(K_V_BIPOLAR, k_flame_var_bipolar(t, V), 0u)                                                                      \
    X(K_V_BOARDERS, k_flame_var_boarders(t, w, key, n), 1u)                                                            \
    X(K_V_BUTTERFLY, k_flame_var_butterfly(t, w), 0u)                                                                  \
    X(K_V_CELL, k_flame_var_cell(t, V), 0u)                                                                            \
    X(K_V_CPOW, k_flame_var_cpow(t, V, key, n), 1u)                                                                    \
    X(K_V_CURVE, k_flame_var_curve(t, V), 0u)                                                                          \
    X(K_V_EDISC, k_flame_var_edisc(t, V), 0u)                                                                          \
    X(K_V_ELLIPTIC, k_flame_var_elliptic(t, V), 0u)                                                                    \
    X(K_V_ESCHER, k_flame_var_escher(t, V), 0u)                                                                        \
    X(K_V_FOCI, k_flame_var_foci(t, w), 0u)                                                                            \
    X(K_V_LAZYSUSAN, k_flame_var_lazysusan(t, V), 0u)                                                                  \
    X(K_V_LOONIE, k_flame_var_loonie(t, w), 0u)                                                                        \
    X(K_V_MODULUS, k_flame_var_modulus(t, V), 0u)                                                                      \
    X(K_V_OSCILLOSCOPE, k_flame_var_oscilloscope(t, V), 0u)                                                            \
    X(K_V_POLAR2, k_flame_var_polar2(t, V), 0u)                                                                        \
    X(K_V_POPCORN2, k_flame_var_popcorn2(t, V), 0u)                                                                    \
    X(K_V_SCRY, k_flame_var_scry(t, V), 0u)                                                                            \
    X(K_V_SEPARATION, k_flame_var_separation(t, V), 0u)                                                                \
    X(K_V_SPLIT, k_flame_var_split(t, V), 0u)                                                                          \
    X(K_V_SPLITS, k_flame_var_splits(t, V), 0u)                                                                        \
    X(K_V_STRIPES, k_flame_var_stripes(t, V), 0u)                                                                      \
    X(K_V_WEDGE, k_flame_var_wedge(t, V), 0u)                                                                          \
    X(K_V_WEDGE_JULIA, k_flame_var_wedge_julia(t, V, key, n), 1u)                                                      \
    X(K_V_WEDGE_SPH, k_flame_var_wedge_sph(t, V), 0u)                                                                  \
    X(K_V_WHORL, k_flame_var_whorl(t, V), 0u)                                                                          \
    X(K_V_WAVES2, k_flame_var_waves2(t, V), 0u)                                                                        \
    X(K_V_EXP, k_flame_var_exp(t, w), 0u)                                                                              \
    X(K_V_LOG, k_flame_var_log(t, w), 0u)                                                                              \
    X(K_V_SIN, k_flame_var_sin(t, w), 0u)                                                                              \
    X(K_V_COS, k_flame_var_cos(t, w), 0u)                                                                              \
    X(K_V_TAN, k_flame_var_tan(t, w), 0u)                                                                              \
    X(K_V_SEC, k_flame_var_sec(t, w), 0u)                                                                              \
    X(K_V_CSC, k_flame_var_csc(t, w), 0u)                                                                              \
    X(K_V_COT, k_flame_var_cot(t, w), 0u)                                                                              \
    X(K_V_SINH, k_flame_var_sinh(t, w), 0u)                                                                            \
    X(K_V_COSH, k_flame_var_cosh(t, w), 0u)                                                                            \
    X(K_V_TANH, k_flame_var_tanh(t, w), 0u)                                                                            \
    X(K_V_SECH, k_flame_var_sech(t, w), 0u)                                                                            \
    X(K_V_CSCH, k_flame_var_csch(t, w), 0u)                                                                            \
    X(K_V_COTH, k_flame_var_coth(t, w), 0u)                                                                            \
    X(K_V_AUGER, k_flame_var_auger(t, V), 0u)                                                                          \
    X(K_V_FLUX, k_flame_var_flux(t, V), 0u)                                                                            \
    X(K_V_MOBIUS, k_flame_var_mobius(t, V), 0u)

/* case V: variation V's function (where compiled), and its number of draws */
#define K_FLAME_CASE(v, call, nd)                                                                                      \
    case v:                                                                                                            \
        if (K_FLAME_HAS(v)) {                                                                                          \
            d = call;                                                                                                  \
            r.draws = nd;                                                                                              \
        }                                                                                                              \
        break;

/* Variation number v (V's, or in a shader's pass over the genome's variations the pass's) at point
 * t, its draws from (key, n): flam3's apply_xform switch. pre_blur is not among them (it moves the
 * point before the precalcs: k_flame_preblur). */
K_FLAME_INLINE K_FlameD k_flame_variation(uint v, K_FlamePt t, K_FlameVar V, uint key, uint n)
{
    K_FlameD r;
    r.draws = 0u;
    k_vec2 d = k_vec2(0.0f, 0.0f);
    float w = V.w;
    switch (v) {
        K_FLAME_VARIATIONS(K_FLAME_CASE)
    default:
        break;
    }
    r.x = d.x;
    r.y = d.y;
    return r;
}

#endif
