/*
 * flam3 3.1.1's variations (flam3.h's numbers) in the common subset of C11 and GLSL: one small
 * function each, with flam3's formula (variations.c) and its quirks, in single precision, and one
 * switch (k_flame_variation) that picks a variation by its number. A variation is a pure function of
 * the point after the xform's affine map with flam3's precalcs (K_FlamePt), its weight and
 * parameters (K_FlameVar, already combined as flam3's precalc functions combine them:
 * host/gen/flame/render.c's fb_flame_var_params), and, for the random ones, the position (key, n) of
 * its draws in the chain's counter-based stream: its i-th draw is k_flame_u01(key, n + i), and the
 * switch says how many it takes.
 *
 * Exactness: the same bits in C and on any conformant Vulkan device. Float `/` and sqrt only
 * through kx_div and kx_sqrt (kernels/exact.h), the transcendentals kernels/kmath.h's float-only
 * ones, no fused multiply-add (C is built with -ffp-contract=off, the SPIR-V carries NoContraction on
 * every float operation), every float literal one that C and glslang read alike
 * (tests/test_kmath.c).
 */
#ifndef FB_KERNELS_FLAME_VAR_H
#define FB_KERNELS_FLAME_VAR_H

#include "common.h"
#include "hash.h"
#include "kmath.h"

#define K_FLAME_EPS 1e-10f       /* flam3's EPS */
#define K_1_PI      0.318309873f /* 1 / pi: the float nearest both 1 / K_PI and M_1_PI */

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
#define K_V_COUNT         55u

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

/* ---- the switch ----------------------------------------------------------------------------------- */

/* Whether variation v's code is compiled: a shader may define K_FLAME_VMASK0 .. K_FLAME_VMASK3 as
 * specialisation constants, the genome's variations as bits (0-31, 32-63 ...), so that a
 * pipeline carries only the genome's variations (lavapipe runs every branch that any of its 8
 * lanes takes, and compiles every branch it is given: pipeline creation time). In C every variation
 * is there. */
#ifdef K_GLSL
#ifndef K_FLAME_VMASK0
#define K_FLAME_VMASK0 0xffffffffu
#define K_FLAME_VMASK1 0xffffffffu
#define K_FLAME_VMASK2 0u
#define K_FLAME_VMASK3 0u
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

/* case V: variation V's function (where compiled), and its number of draws */
#define K_FLAME_CASE(v, call, nd)                                                                                      \
    case v:                                                                                                            \
        if (K_FLAME_HAS(v)) {                                                                                          \
            d = call;                                                                                                  \
            r.draws = nd;                                                                                              \
        }                                                                                                              \
        break;

/* Variation number v (V's, or in a shader's pass over the genome's variations the pass's) at point
 * t, its draws from (key, n): flam3's apply_xform switch. */
K_FLAME_INLINE K_FlameD k_flame_variation(uint v, K_FlamePt t, K_FlameVar V, uint key, uint n)
{
    K_FlameD r;
    r.draws = 0u;
    k_vec2 d = k_vec2(0.0f, 0.0f);
    float w = V.w;
    switch (v) {
        K_FLAME_CASE(K_V_LINEAR, k_flame_var_linear(t, w), 0u)
        K_FLAME_CASE(K_V_SINUSOIDAL, k_flame_var_sinusoidal(t, w), 0u)
        K_FLAME_CASE(K_V_SPHERICAL, k_flame_var_spherical(t, w), 0u)
        K_FLAME_CASE(K_V_SWIRL, k_flame_var_swirl(t, w), 0u)
        K_FLAME_CASE(K_V_HORSESHOE, k_flame_var_horseshoe(t, w), 0u)
        K_FLAME_CASE(K_V_POLAR, k_flame_var_polar(t, w), 0u)
        K_FLAME_CASE(K_V_HANDKERCHIEF, k_flame_var_handkerchief(t, w), 0u)
        K_FLAME_CASE(K_V_HEART, k_flame_var_heart(t, w), 0u)
        K_FLAME_CASE(K_V_DISC, k_flame_var_disc(t, w), 0u)
        K_FLAME_CASE(K_V_SPIRAL, k_flame_var_spiral(t, w), 0u)
        K_FLAME_CASE(K_V_HYPERBOLIC, k_flame_var_hyperbolic(t, w), 0u)
        K_FLAME_CASE(K_V_DIAMOND, k_flame_var_diamond(t, w), 0u)
        K_FLAME_CASE(K_V_EX, k_flame_var_ex(t, w), 0u)
        K_FLAME_CASE(K_V_JULIA, k_flame_var_julia(t, w, key, n), 1u)
        K_FLAME_CASE(K_V_BENT, k_flame_var_bent(t, w), 0u)
        K_FLAME_CASE(K_V_WAVES, k_flame_var_waves(t, V), 0u)
        K_FLAME_CASE(K_V_FISHEYE, k_flame_var_fisheye(t, w), 0u)
        K_FLAME_CASE(K_V_POPCORN, k_flame_var_popcorn(t, V), 0u)
        K_FLAME_CASE(K_V_EXPONENTIAL, k_flame_var_exponential(t, w), 0u)
        K_FLAME_CASE(K_V_POWER, k_flame_var_power(t, w), 0u)
        K_FLAME_CASE(K_V_COSINE, k_flame_var_cosine(t, w), 0u)
        K_FLAME_CASE(K_V_RINGS, k_flame_var_rings(t, V), 0u)
        K_FLAME_CASE(K_V_FAN, k_flame_var_fan(t, V), 0u)
        K_FLAME_CASE(K_V_BLOB, k_flame_var_blob(t, V), 0u)
        K_FLAME_CASE(K_V_PDJ, k_flame_var_pdj(t, V), 0u)
        K_FLAME_CASE(K_V_FAN2, k_flame_var_fan2(t, V), 0u)
        K_FLAME_CASE(K_V_RINGS2, k_flame_var_rings2(t, V), 0u)
        K_FLAME_CASE(K_V_EYEFISH, k_flame_var_eyefish(t, w), 0u)
        K_FLAME_CASE(K_V_BUBBLE, k_flame_var_bubble(t, w), 0u)
        K_FLAME_CASE(K_V_CYLINDER, k_flame_var_cylinder(t, w), 0u)
        K_FLAME_CASE(K_V_PERSPECTIVE, k_flame_var_perspective(t, V), 0u)
        K_FLAME_CASE(K_V_NOISE, k_flame_var_noise(t, w, key, n), 2u)
        K_FLAME_CASE(K_V_JULIAN, k_flame_var_julian(t, V, key, n), 1u)
        K_FLAME_CASE(K_V_JULIASCOPE, k_flame_var_juliascope(t, V, key, n), 1u)
        K_FLAME_CASE(K_V_BLUR, k_flame_var_blur(t, w, key, n), 2u)
        K_FLAME_CASE(K_V_GAUSSIAN_BLUR, k_flame_var_gaussian_blur(t, w, key, n), 5u)
        K_FLAME_CASE(K_V_RADIAL_BLUR, k_flame_var_radial_blur(t, V, key, n), 4u)
        K_FLAME_CASE(K_V_PIE, k_flame_var_pie(t, V, key, n), 3u)
        K_FLAME_CASE(K_V_NGON, k_flame_var_ngon(t, V), 0u)
        K_FLAME_CASE(K_V_CURL, k_flame_var_curl(t, V), 0u)
        K_FLAME_CASE(K_V_RECTANGLES, k_flame_var_rectangles(t, V), 0u)
        K_FLAME_CASE(K_V_ARCH, k_flame_var_arch(t, w, key, n), 1u)
        K_FLAME_CASE(K_V_TANGENT, k_flame_var_tangent(t, w), 0u)
        K_FLAME_CASE(K_V_SQUARE, k_flame_var_square(t, w, key, n), 2u)
        K_FLAME_CASE(K_V_RAYS, k_flame_var_rays(t, w, key, n), 1u)
        K_FLAME_CASE(K_V_BLADE, k_flame_var_blade(t, w, key, n), 1u)
        K_FLAME_CASE(K_V_SECANT2, k_flame_var_secant2(t, w), 0u)
        K_FLAME_CASE(K_V_TWINTRIAN, k_flame_var_twintrian(t, w, key, n), 1u)
        K_FLAME_CASE(K_V_CROSS, k_flame_var_cross(t, w), 0u)
        K_FLAME_CASE(K_V_DISC2, k_flame_var_disc2(t, V), 0u)
        K_FLAME_CASE(K_V_SUPER_SHAPE, k_flame_var_super_shape(t, V, key, n), 1u)
        K_FLAME_CASE(K_V_FLOWER, k_flame_var_flower(t, V, key, n), 1u)
        K_FLAME_CASE(K_V_CONIC, k_flame_var_conic(t, V, key, n), 1u)
        K_FLAME_CASE(K_V_PARABOLA, k_flame_var_parabola(t, V, key, n), 2u)
        K_FLAME_CASE(K_V_BENT2, k_flame_var_bent2(t, V), 0u)
    default:
        break;
    }
    r.x = d.x;
    r.y = d.y;
    return r;
}

#endif
