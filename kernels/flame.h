/*
 * Fractal flames (Scott Draves and Erik Reckase, "The Fractal Flame Algorithm", 2003/2008): one
 * iteration of a flame's chaos game, as flam3 3.1.1 runs it, in the common subset of C11 and GLSL.
 *
 * A chain starts at a random point of [-1, 1]^2 with a random colour, runs `fuse` iterations that
 * are not plotted, then `len` that are. An iteration picks an xform by its weight (or, with xaos,
 * by the row of the xform used last), applies its affine coefficients, the weighted sum of its
 * variations and its post transform; a result that is NaN or beyond 1e10 is replaced by a random
 * point and the iteration retried, up to five times in a row (flam3's rule). The final xform, when
 * there is one, is applied to what is plotted, not to the chain.
 *
 * Randomness is counter-based: the n-th draw of chain i is k_hash(n ^ key_i), key_i a hash of the
 * seed and i, so a chain gives the same points on any thread, points part or device.
 *
 * The xform, variation and xform-choice tables are storage buffers in GLSL and pointers in C: a
 * shader defines K_FLAME_BUFFERS (their declarations, k_flame_xf[], k_flame_var[] and
 * k_flame_dist[], emitted here once the structs exist) before including this header; C functions
 * take them through K_FLAME_TABLES_DECL.
 *
 * The transcendentals are kernels/kmath.h's, and every sum and product that feeds a point is
 * `precise`, so that C (built with -ffp-contract=off), lavapipe and a GPU round alike; what a GPU
 * may still do otherwise is divide and take square roots within Vulkan's tolerance (docs/flames.md).
 */
#ifndef FB_KERNELS_FLAME_H
#define FB_KERNELS_FLAME_H

#include "common.h"
#include "hash.h"
#include "kmath.h"

/* The transcendentals of kernels/kmath.h and sincos.h, the same bits in C and GLSL (libm and a
 * device's built-ins differ in the last bits, and the chaos game amplifies that into other points). */
#define k_fsin(x)     k_xsin(x)
#define k_fcos(x)     k_xcos(x)
#define k_atan2(y, x) k_xatan2(y, x)
#define k_tan(x)      k_xtan(x)
#define k_exp(x)      k_xexp(x)
#define k_log(x)      k_xlog(x)
#define k_fpow(x, y)  k_xpow(x, y)
#define k_sinh(x)     k_xsinh(x)
#define k_cosh(x)     k_xcosh(x)
#define k_fmod(x, y)  k_xfmod(x, y)

/* The step inlined into its caller in C: returned through memory, its state is otherwise stored
 * field by field and read back whole, which the processor cannot forward (a stall a point). */
#ifdef K_GLSL
#define K_FLAME_INLINE
#else
#define K_FLAME_INLINE static inline __attribute__((always_inline))
#endif

#define K_FLAME_EPS       1e-10f
#define K_FLAME_GRAIN     16384u /* entries of one row of the xform choice table (flam3's CHOOSE_XFORM_GRAIN) */
#define K_FLAME_NONE      0xffffffffu
#define K_FLAME_ATAN_XY   1u /* flags: the xform's variations use atan2(x, y) */
#define K_FLAME_ATAN_YX   2u /* ... atan2(y, x) */
#define K_FLAME_HAS_POST  4u
#define K_FLAME_SQRT      8u /* ... the length of (tx, ty) and flam3's sina, cosa */
#define K_FLAME_DRAWS_MAX 64u

/* flam3's variation numbers (flam3.h VAR_*), the ones implemented here. */
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
#define K_V_COUNT         55u /* variations 0 .. K_V_COUNT - 1 are implemented */

/* One active variation of an xform: flam3's number, its weight and up to six parameters, already
 * combined as flam3's precalc functions do (fb_flame_var_params). */
K_STRUCT(K_FlameVar)
{
    uint id;
    float w;
    float p0, p1, p2, p3, p4, p5;
}
K_END(K_FlameVar)

/* An xform: tx = ax x + bx y + cx, ty = ay x + by y + cy (flam3's coefs c00 c01 c10 c11 c20 c21 are
 * ax ay bx by cx cy), its post transform the same way, colour, colour speed, adjusted opacity, and
 * its variations k_flame_var[var0 .. var0 + nvar). */
K_STRUCT(K_FlameXform)
{
    float ax, bx, cx, ay, by, cy;
    float pax, pbx, pcx, pay, pby, pcy;
    float color, speed, vis;
    uint var0, nvar, flags;
    uint visq; /* vis in units of 2^-15 (the fixed-point weight of its points) */
    uint pad;
}
K_END(K_FlameXform)

K_STRUCT(K_FlameParams)
{
    uint seed;
    uint nxf;      /* ordinary xforms: k_flame_xf[0 .. nxf) */
    uint final_xf; /* the final xform's index, or K_FLAME_NONE */
    uint chaos;    /* 1: xaos, the choice table has a row per xform after the plain row 0 */
    uint fuse;     /* iterations not plotted at a chain's start */
    uint len;      /* iterations plotted per chain */
    uint chains;   /* chains in all */
    uint last_len; /* the last chain's iterations (the points need not divide evenly) */
    uint hist_w, hist_h;
    uint rotate; /* 1: the plotted point is rotated about (rcx, rcy) */
    uint final_always;
    float final_opacity;
    float rot00, rot01, rot10, rot11, rcx, rcy;
    float b0, b1, b2, b3; /* the histogram's frame: xmin, ymin, xmax, ymax */
    float ws0, wb0s0, hs1, hb1s1;
}
K_END(K_FlameParams)

/* A chain's state: the point (x, y, c), the last xform used (+1; 0 before the first), the next
 * draw's counter, and what the iteration plots: (px, py, pc) with xform `vis`'s opacity. */
K_STRUCT(K_FlameChain)
{
    float x, y, c;
    uint last;
    uint n;
    uint vis;
    float px, py, pc;
    uint bad; /* iterations that produced a bad value (flam3's badvals) */
}
K_END(K_FlameChain)

#ifdef K_GLSL
K_FLAME_BUFFERS
#define K_FLAME_TABLES_DECL
#define K_FLAME_TABLES
#else
#define K_FLAME_TABLES_DECL , const K_FlameXform *k_flame_xf, const K_FlameVar *k_flame_var, const uint *k_flame_dist
#define K_FLAME_TABLES      , k_flame_xf, k_flame_var, k_flame_dist
#endif

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
 * by 1e-10 and land there, and flam3's images depend on it. */
K_FN float k_flame_itrunc(float v)
{
    return (v >= 2147483648.0f || v < -2147483648.0f || k_isnan(v)) ? -2147483648.0f : k_trunc(v);
}

K_FN bool k_flame_bad(float v)
{
    return k_isnan(v) || v > 1e10f || v < -1e10f;
}

/* The result of one xform: the point and colour, and whether it was a bad value (then the point
 * is random, as flam3 does). */
K_STRUCT(K_FlameOut)
{
    float x, y, c;
    uint n;
    bool bad;
}
K_END(K_FlameOut)

/* Whether the variations' branch for variation v is compiled: in GLSL a shader may define
 * K_FLAME_VMASK0 and K_FLAME_VMASK1 as specialisation constants, the genome's variations 0-31 and
 * 32-54 as bits, so that a pipeline carries only the genome's variations (lavapipe runs every branch
 * of an if chain that any of its 8 lanes takes, under a mask: with all 55 compiled, a step cost
 * several times as much). In C every branch is there and the compiler's jump decides. */
#ifdef K_GLSL
#ifndef K_FLAME_VMASK0
#define K_FLAME_VMASK0 0xffffffffu
#define K_FLAME_VMASK1 0xffffffffu
#endif
#define K_FLAME_HAS(v) ((((v) < 32u ? (K_FLAME_VMASK0 >> (v)) : (K_FLAME_VMASK1 >> ((v)-32u))) & 1u) != 0u)
#else
#define K_FLAME_HAS(v) true
#endif
/* Whether the final xform's code is there: a shader may define it false for a genome without one
 * (lavapipe runs the code of an if whose condition no lane meets, under a mask). */
#ifndef K_FLAME_FINAL
#define K_FLAME_FINAL true
#endif

/* The variations' branches: `if (K_FLAME_IS(first)) { ... } K_FLAME_ELIF (next) { ... } ...`. In C (and
 * GLSL by default) an else-if chain on the id of variation slot k, inside a loop over the xform's
 * slots. A shader that defines K_FLAME_ONCE gets one pass of independent ifs instead, each taking
 * the xform's next variation when it is that one (an xform's variations are in ascending order, the
 * order of the chain): lavapipe runs every branch any of its 8 lanes takes, so a loop over slots ran
 * each of the genome's variations once a slot, and this runs it once a step; the terms are added in
 * the same order, so the sums are the same bits. */
#ifdef K_FLAME_ONCE
/* Whether xform X's variation k is v: then V and w are it, and k moves on to the next. */
bool k_flame_take(K_FlameXform X, uint v, inout uint k, out K_FlameVar V, out float w)
{
    if (k >= X.nvar) return false;
    V = k_flame_var[X.var0 + k];
    w = V.w;
    if (V.id != v) return false;
    k++;
    return true;
}
#define K_FLAME_IS(v)   (K_FLAME_HAS(v) && k_flame_take(X, v, k, V, w))
#define K_FLAME_ELIF(v) if (K_FLAME_IS(v))
#else
#define K_FLAME_IS(v)   (K_FLAME_HAS(v) && id == (v))
#define K_FLAME_ELIF(v) else if (K_FLAME_IS(v))
#endif

/* Draws inside k_flame_apply: n is its local counter. */
#define K_FLAME_RAND() k_flame_u01(key, n++)

/* Applies xform `fn` to (x, y, c): flam3's apply_xform, each variation with flam3's formula. */
K_FLAME_INLINE K_FlameOut k_flame_apply(uint fn, float x, float y, float c, uint key, uint n0 K_FLAME_TABLES_DECL)
{
    K_FlameXform X = k_flame_xf[fn];
    uint n = n0;
    K_FlameOut o;
    K_PRECISE float oc = X.speed * X.color + (1.0f - X.speed) * c;
    o.c = oc;
    K_PRECISE float tx = X.ax * x + X.bx * y + X.cx;
    K_PRECISE float ty = X.ay * x + X.by * y + X.cy;
    K_PRECISE float sumsq = tx * tx + ty * ty;
    float sq = 0.0f, sina = 0.0f, cosa = 0.0f; /* sina, cosa: flam3's precalc_sina and precalc_cosa, its naming */
    if ((X.flags & K_FLAME_SQRT) != 0u) {
        sq = k_sqrt(sumsq);
        sina = tx / sq;
        cosa = ty / sq;
    }
    float atxy = 0.0f, atyx = 0.0f;
    if ((X.flags & K_FLAME_ATAN_XY) != 0u) atxy = k_atan2(tx, ty);
    if ((X.flags & K_FLAME_ATAN_YX) != 0u) atyx = k_atan2(ty, tx);
    K_PRECISE float p0 = 0.0f;
    K_PRECISE float p1 = 0.0f;
#ifdef K_FLAME_ONCE
    uint k = 0u;
    K_FlameVar V;
    float w = 0.0f;
    {
#else
    for (uint k = 0u; k < X.nvar; k++) {
        K_FlameVar V = k_flame_var[X.var0 + k];
        float w = V.w;
        uint id = V.id;
#endif
        if (K_FLAME_IS(K_V_LINEAR)) {
            p0 += w * tx;
            p1 += w * ty;
        }
        K_FLAME_ELIF (K_V_SINUSOIDAL) {
            p0 += w * k_fsin(tx);
            p1 += w * k_fsin(ty);
        }
        K_FLAME_ELIF (K_V_SPHERICAL) {
            float r2 = w / (sumsq + K_FLAME_EPS);
            p0 += r2 * tx;
            p1 += r2 * ty;
        }
        K_FLAME_ELIF (K_V_SWIRL) {
            float c1 = k_fsin(sumsq), c2 = k_fcos(sumsq);
            p0 += w * (c1 * tx - c2 * ty);
            p1 += w * (c2 * tx + c1 * ty);
        }
        K_FLAME_ELIF (K_V_HORSESHOE) {
            float r = w / (sq + K_FLAME_EPS);
            p0 += (tx - ty) * (tx + ty) * r;
            p1 += 2.0f * tx * ty * r;
        }
        K_FLAME_ELIF (K_V_POLAR) {
            p0 += w * atxy * (1.0f / K_PI);
            p1 += w * (sq - 1.0f);
        }
        K_FLAME_ELIF (K_V_HANDKERCHIEF) {
            p0 += w * sq * k_fsin(atxy + sq);
            p1 += w * sq * k_fcos(atxy - sq);
        }
        K_FLAME_ELIF (K_V_HEART) {
            float a = sq * atxy, r = w * sq;
            p0 += r * k_fsin(a);
            p1 += -r * k_fcos(a);
        }
        K_FLAME_ELIF (K_V_DISC) {
            float a = atxy * (1.0f / K_PI), r = K_PI * sq;
            p0 += w * k_fsin(r) * a;
            p1 += w * k_fcos(r) * a;
        }
        K_FLAME_ELIF (K_V_SPIRAL) {
            float r = sq + K_FLAME_EPS, r1 = w / r;
            p0 += r1 * (cosa + k_fsin(r));
            p1 += r1 * (sina - k_fcos(r));
        }
        K_FLAME_ELIF (K_V_HYPERBOLIC) {
            float r = sq + K_FLAME_EPS;
            p0 += w * sina / r;
            p1 += w * cosa * r;
        }
        K_FLAME_ELIF (K_V_DIAMOND) {
            p0 += w * sina * k_fcos(sq);
            p1 += w * cosa * k_fsin(sq);
        }
        K_FLAME_ELIF (K_V_EX) {
            float n0 = k_fsin(atxy + sq), n1 = k_fcos(atxy - sq);
            float m0 = n0 * n0 * n0 * sq, m1 = n1 * n1 * n1 * sq;
            p0 += w * (m0 + m1);
            p1 += w * (m0 - m1);
        }
        K_FLAME_ELIF (K_V_JULIA) {
            float a = 0.5f * atxy;
            if ((k_hash(n++ ^ key) & 1u) != 0u) a += K_PI;
            float r = w * k_sqrt(sq);
            p0 += r * k_fcos(a);
            p1 += r * k_fsin(a);
        }
        K_FLAME_ELIF (K_V_BENT) {
            float nx = tx < 0.0f ? tx * 2.0f : tx;
            float ny = ty < 0.0f ? ty / 2.0f : ty;
            p0 += w * nx;
            p1 += w * ny;
        }
        K_FLAME_ELIF (K_V_WAVES) {
            p0 += w * (tx + V.p0 * k_fsin(ty * V.p2));
            p1 += w * (ty + V.p1 * k_fsin(tx * V.p3));
        }
        K_FLAME_ELIF (K_V_FISHEYE) {
            float r = 2.0f * w / (sq + 1.0f);
            p0 += r * ty; /* flam3 swaps x and y here */
            p1 += r * tx;
        }
        K_FLAME_ELIF (K_V_POPCORN) {
            p0 += w * (tx + V.p0 * k_fsin(k_tan(3.0f * ty)));
            p1 += w * (ty + V.p1 * k_fsin(k_tan(3.0f * tx)));
        }
        K_FLAME_ELIF (K_V_EXPONENTIAL) {
            float dx = w * k_exp(tx - 1.0f), dy = K_PI * ty;
            p0 += dx * k_fcos(dy);
            p1 += dx * k_fsin(dy);
        }
        K_FLAME_ELIF (K_V_POWER) {
            float r = w * k_fpow(sq, sina);
            p0 += r * cosa;
            p1 += r * sina;
        }
        K_FLAME_ELIF (K_V_COSINE) {
            float a = tx * K_PI;
            p0 += w * k_fcos(a) * k_cosh(ty);
            p1 += w * -k_fsin(a) * k_sinh(ty);
        }
        K_FLAME_ELIF (K_V_RINGS) {
            float dx = V.p0;
            float r = w * (k_fmod(sq + dx, 2.0f * dx) - dx + sq * (1.0f - dx));
            p0 += r * cosa;
            p1 += r * sina;
        }
        K_FLAME_ELIF (K_V_FAN) {
            float dx = V.p0, dy = V.p1, dx2 = 0.5f * dx;
            float a = atxy + (k_fmod(atxy + dy, dx) > dx2 ? -dx2 : dx2);
            float r = w * sq;
            p0 += r * k_fcos(a);
            p1 += r * k_fsin(a);
        }
        K_FLAME_ELIF (K_V_BLOB) {
            float r = sq * (V.p0 + V.p1 * (0.5f + 0.5f * k_fsin(V.p2 * atxy)));
            p0 += w * sina * r;
            p1 += w * cosa * r;
        }
        K_FLAME_ELIF (K_V_PDJ) {
            p0 += w * (k_fsin(V.p0 * ty) - k_fcos(V.p1 * tx));
            p1 += w * (k_fsin(V.p2 * tx) - k_fcos(V.p3 * ty));
        }
        K_FLAME_ELIF (K_V_FAN2) {
            float dx = V.p0, dy = V.p1, dx2 = 0.5f * dx;
            float t = atxy + dy - dx * k_flame_itrunc((atxy + dy) / dx);
            float a = t > dx2 ? atxy - dx2 : atxy + dx2;
            float r = w * sq;
            p0 += r * k_fsin(a);
            p1 += r * k_fcos(a);
        }
        K_FLAME_ELIF (K_V_RINGS2) {
            float dx = V.p0;
            float r = sq + (-2.0f * dx * k_flame_itrunc((sq + dx) / (2.0f * dx)) + sq * (1.0f - dx));
            p0 += w * sina * r;
            p1 += w * cosa * r;
        }
        K_FLAME_ELIF (K_V_EYEFISH) {
            float r = (w * 2.0f) / (sq + 1.0f);
            p0 += r * tx;
            p1 += r * ty;
        }
        K_FLAME_ELIF (K_V_BUBBLE) {
            float r = w / (0.25f * sumsq + 1.0f);
            p0 += r * tx;
            p1 += r * ty;
        }
        K_FLAME_ELIF (K_V_CYLINDER) {
            p0 += w * k_fsin(tx);
            p1 += w * ty;
        }
        K_FLAME_ELIF (K_V_PERSPECTIVE) {
            float t = 1.0f / (V.p0 - ty * V.p1);
            p0 += w * V.p0 * tx * t;
            p1 += w * V.p2 * ty * t;
        }
        K_FLAME_ELIF (K_V_NOISE) {
            float a = K_FLAME_RAND() * 2.0f * K_PI;
            float r = w * K_FLAME_RAND();
            p0 += tx * r * k_fcos(a);
            p1 += ty * r * k_fsin(a);
        }
        K_FLAME_ELIF (K_V_JULIAN) {
            float t = k_trunc(V.p2 * K_FLAME_RAND());
            float a = (atyx + 2.0f * K_PI * t) / V.p0;
            float r = w * k_fpow(sumsq, V.p1);
            p0 += r * k_fcos(a);
            p1 += r * k_fsin(a);
        }
        K_FLAME_ELIF (K_V_JULIASCOPE) {
            int t = K_I(k_trunc(V.p2 * K_FLAME_RAND()));
            float a = (t & 1) == 0 ? (2.0f * K_PI * K_F(t) + atyx) / V.p0 : (2.0f * K_PI * K_F(t) - atyx) / V.p0;
            float r = w * k_fpow(sumsq, V.p1);
            p0 += r * k_fcos(a);
            p1 += r * k_fsin(a);
        }
        K_FLAME_ELIF (K_V_BLUR) {
            float a = K_FLAME_RAND() * 2.0f * K_PI;
            float r = w * K_FLAME_RAND();
            p0 += r * k_fcos(a);
            p1 += r * k_fsin(a);
        }
        K_FLAME_ELIF (K_V_GAUSSIAN_BLUR) {
            float a = K_FLAME_RAND() * 2.0f * K_PI;
            float g = K_FLAME_RAND();
            g += K_FLAME_RAND();
            g += K_FLAME_RAND();
            g += K_FLAME_RAND();
            float r = w * (g - 2.0f);
            p0 += r * k_fcos(a);
            p1 += r * k_fsin(a);
        }
        K_FLAME_ELIF (K_V_RADIAL_BLUR) {
            float g = K_FLAME_RAND();
            g += K_FLAME_RAND();
            g += K_FLAME_RAND();
            g += K_FLAME_RAND();
            float rnd = w * (g - 2.0f);
            float a = atyx + V.p0 * rnd;
            float rz = V.p1 * rnd - 1.0f;
            p0 += sq * k_fcos(a) + rz * tx;
            p1 += sq * k_fsin(a) + rz * ty;
        }
        K_FLAME_ELIF (K_V_PIE) {
            float sl = K_F(K_I(K_FLAME_RAND() * V.p0 + 0.5f));
            float a = V.p1 + 2.0f * K_PI * (sl + K_FLAME_RAND() * V.p2) / V.p0;
            float r = w * K_FLAME_RAND();
            p0 += r * k_fcos(a);
            p1 += r * k_fsin(a);
        }
        K_FLAME_ELIF (K_V_NGON) {
            float rf = k_fpow(sumsq, V.p0);
            float b = V.p1;
            float phi = atyx - b * k_floor(atyx / b);
            if (phi > b / 2.0f) phi -= b;
            float amp = V.p2 * (1.0f / (k_fcos(phi) + K_FLAME_EPS) - 1.0f) + V.p3;
            amp /= (rf + K_FLAME_EPS);
            p0 += w * tx * amp;
            p1 += w * ty * amp;
        }
        K_FLAME_ELIF (K_V_CURL) {
            float re = 1.0f + V.p0 * tx + V.p1 * (tx * tx - ty * ty);
            float im = V.p0 * ty + 2.0f * V.p1 * tx * ty;
            float r = w / (re * re + im * im);
            p0 += (tx * re + ty * im) * r;
            p1 += (ty * re - tx * im) * r;
        }
        K_FLAME_ELIF (K_V_RECTANGLES) {
            p0 += V.p0 == 0.0f ? w * tx : w * ((2.0f * k_floor(tx / V.p0) + 1.0f) * V.p0 - tx);
            p1 += V.p1 == 0.0f ? w * ty : w * ((2.0f * k_floor(ty / V.p1) + 1.0f) * V.p1 - ty);
        }
        K_FLAME_ELIF (K_V_ARCH) {
            float a = K_FLAME_RAND() * w * K_PI;
            float s = k_fsin(a), cs = k_fcos(a);
            p0 += w * s;
            p1 += w * (s * s) / cs;
        }
        K_FLAME_ELIF (K_V_TANGENT) {
            p0 += w * k_fsin(tx) / k_fcos(ty);
            p1 += w * k_tan(ty);
        }
        K_FLAME_ELIF (K_V_SQUARE) {
            p0 += w * (K_FLAME_RAND() - 0.5f);
            p1 += w * (K_FLAME_RAND() - 0.5f);
        }
        K_FLAME_ELIF (K_V_RAYS) {
            float a = w * K_FLAME_RAND() * K_PI;
            float r = w / (sumsq + K_FLAME_EPS);
            float tr = w * k_tan(a) * r;
            p0 += tr * k_fcos(tx);
            p1 += tr * k_fsin(ty);
        }
        K_FLAME_ELIF (K_V_BLADE) {
            float r = K_FLAME_RAND() * w * sq;
            float s = k_fsin(r), cs = k_fcos(r);
            p0 += w * tx * (cs + s);
            p1 += w * tx * (cs - s);
        }
        K_FLAME_ELIF (K_V_SECANT2) {
            float cr = k_fcos(w * sq), icr = 1.0f / cr;
            p0 += w * tx;
            p1 += cr < 0.0f ? w * (icr + 1.0f) : w * (icr - 1.0f);
        }
        K_FLAME_ELIF (K_V_TWINTRIAN) {
            float r = K_FLAME_RAND() * w * sq;
            float s = k_fsin(r), cs = k_fcos(r);
            float diff = k_log(s * s) * 0.434294481903252f + cs; /* log10 */
            if (k_flame_bad(diff)) diff = -30.0f;
            p0 += w * tx * diff;
            p1 += w * tx * (diff - s * K_PI);
        }
        K_FLAME_ELIF (K_V_CROSS) {
            float s = tx * tx - ty * ty;
            float r = w * k_sqrt(1.0f / (s * s + K_FLAME_EPS));
            p0 += tx * r;
            p1 += ty * r;
        }
        K_FLAME_ELIF (K_V_DISC2) {
            float t = V.p0 * (tx + ty);
            float r = w * atxy / K_PI;
            p0 += (k_fsin(t) + V.p2) * r;
            p1 += (k_fcos(t) + V.p1) * r;
        }
        K_FLAME_ELIF (K_V_SUPER_SHAPE) {
            float th = V.p0 * atyx + 0.25f * K_PI;
            float t1 = k_fpow(k_abs(k_fcos(th)), V.p1);
            float t2 = k_fpow(k_abs(k_fsin(th)), V.p2);
            float rnd = V.p3;
            float r = w * ((rnd * K_FLAME_RAND() + (1.0f - rnd) * sq) - V.p4) * k_fpow(t1 + t2, V.p5) / sq;
            p0 += r * tx;
            p1 += r * ty;
        }
        K_FLAME_ELIF (K_V_FLOWER) {
            float r = w * (K_FLAME_RAND() - V.p1) * k_fcos(V.p0 * atyx) / sq;
            p0 += r * tx;
            p1 += r * ty;
        }
        K_FLAME_ELIF (K_V_CONIC) {
            float ct = tx / sq;
            float r = w * (K_FLAME_RAND() - V.p1) * V.p0 / (1.0f + V.p0 * ct) / sq;
            p0 += r * tx;
            p1 += r * ty;
        }
        K_FLAME_ELIF (K_V_PARABOLA) {
            float s = k_fsin(sq), cs = k_fcos(sq);
            p0 += V.p0 * w * s * s * K_FLAME_RAND();
            p1 += V.p1 * w * cs * K_FLAME_RAND();
        }
        K_FLAME_ELIF (K_V_BENT2) {
            float nx = tx < 0.0f ? tx * V.p0 : tx;
            float ny = ty < 0.0f ? ty * V.p1 : ty;
            p0 += w * nx;
            p1 += w * ny;
        }
    }
    if ((X.flags & K_FLAME_HAS_POST) != 0u) {
        K_PRECISE float qx = X.pax * p0 + X.pbx * p1 + X.pcx;
        K_PRECISE float qy = X.pay * p0 + X.pby * p1 + X.pcy;
        o.x = qx;
        o.y = qy;
    } else {
        o.x = p0;
        o.y = p1;
    }
    o.bad = k_flame_bad(o.x) || k_flame_bad(o.y);
    if (o.bad) {
        o.x = K_FLAME_RAND() * 2.0f - 1.0f;
        o.y = K_FLAME_RAND() * 2.0f - 1.0f;
    }
    o.n = n;
    return o;
}

/* A chain's start: a random point of [-1, 1]^2 and colour of [0, 1). */
K_FN K_FlameChain k_flame_init(uint key)
{
    K_FlameChain s;
    s.x = k_flame_u01(key, 0u) * 2.0f - 1.0f;
    s.y = k_flame_u01(key, 1u) * 2.0f - 1.0f;
    s.c = k_flame_u01(key, 2u);
    s.last = 0u;
    s.n = 3u;
    s.vis = 0u;
    s.px = s.x;
    s.py = s.y;
    s.pc = s.c;
    s.bad = 0u;
    return s;
}

/* The camera's rotation of a plotted point about (rcx, rcy). (A function of its own: glslang's
 * propagation of `precise` through k_flame_step's loops takes minutes.) */
K_FN k_vec2 k_flame_rotate(K_FlameParams P, float px, float py)
{
    K_PRECISE float qx = px - P.rcx;
    K_PRECISE float qy = py - P.rcy;
    K_PRECISE float rx = qx * P.rot00 + qy * P.rot01 + P.rcx;
    K_PRECISE float ry = qx * P.rot10 + qy * P.rot11 + P.rcy;
    return k_vec2(rx, ry);
}

/* The end of a step, once its xform is applied: the final xform (when the genome has one, at its
 * opacity) and the camera's rotation give the point plotted (px, py, pc); the chain goes on from
 * (x, y, c). Shared by k_flame_step and the native game's step with its linear fast path. */
K_FLAME_INLINE K_FlameChain k_flame_plot(K_FlameParams P, K_FlameChain s, uint key K_FLAME_TABLES_DECL)
{
    float px = s.x, py = s.y, pc = s.c;
    if (K_FLAME_FINAL && P.final_xf != K_FLAME_NONE) {
        bool apply = P.final_always != 0u;
        if (!apply) {
            apply = k_flame_u01(key, s.n) < P.final_opacity;
            s.n++;
        }
        if (apply) {
            K_FlameOut f = k_flame_apply(P.final_xf, s.x, s.y, s.c, key, s.n K_FLAME_TABLES);
            s.n = f.n;
            px = f.x;
            py = f.y;
            pc = f.c;
        }
    }
    if (P.rotate != 0u) {
        k_vec2 r = k_flame_rotate(P, px, py);
        px = r.x;
        py = r.y;
    }
    s.px = px;
    s.py = py;
    s.pc = pc;
    return s;
}

/* One iteration of the chain (flam3_iterate's loop body): the xform chosen and applied, retried on
 * a bad value at most four times, then the final xform and the camera's rotation for the plot. */
K_FLAME_INLINE K_FlameChain k_flame_step(K_FlameParams P, K_FlameChain s, uint key K_FLAME_TABLES_DECL)
{
    uint fn = 0u;
    K_FlameOut o;
    for (uint tries = 0u; tries < 5u; tries++) {
        uint row = P.chaos != 0u ? s.last : 0u;
        fn = k_flame_dist[row * K_FLAME_GRAIN + (k_hash(s.n ^ key) & (K_FLAME_GRAIN - 1u))];
        o = k_flame_apply(fn, s.x, s.y, s.c, key, s.n + 1u K_FLAME_TABLES);
        s.n = o.n;
        s.x = o.x;
        s.y = o.y;
        s.c = o.c;
        if (!o.bad) break;
        s.bad++;
    }
    s.last = fn + 1u;
    s.vis = fn;
    return k_flame_plot(P, s, key K_FLAME_TABLES);
}

/* The histogram cell the plotted point falls in, or K_FLAME_NONE outside the frame (or invisible). */
K_FN uint k_flame_cell(K_FlameParams P, K_FlameChain s)
{
    if (!(s.px >= P.b0 && s.py >= P.b1 && s.px <= P.b2 && s.py <= P.b3)) return K_FLAME_NONE;
    K_PRECISE float fx = P.ws0 * s.px - P.wb0s0;
    K_PRECISE float fy = P.hs1 * s.py - P.hb1s1;
    int ix = K_I(fx), iy = K_I(fy);
    if (ix < 0 || iy < 0 || ix >= K_I(P.hist_w) || iy >= K_I(P.hist_h)) return K_FLAME_NONE;
    return K_U(iy) * P.hist_w + K_U(ix);
}

/* The palette entry of colour coordinate c (flam3's step mode over 256 entries). */
K_FN uint k_flame_index(float c)
{
    int i = K_I(c * 256.0f);
    return K_U(i < 0 ? 0 : i > 255 ? 255 : i);
}

/* flam3's linear palette mode: colour coordinate c between entries i and i + 1 (i in 0 .. 254)
 * with the weight of i + 1 in units of 2^-16 (0 below the palette, all of it past its end). */
K_FN uint k_flame_lin_index(float c)
{
    int i = K_I(c * 256.0f);
    return K_U(i < 0 ? 0 : i >= 255 ? 254 : i);
}

K_FN uint k_flame_lin_frac(float c)
{
    float v = c * 256.0f;
    int i = K_I(v);
    if (i < 0) return 0u;
    if (i >= 255) return 65536u;
    return K_U((v - K_F(i)) * 65536.0f); /* both exact */
}

/* The interpolated palette value (a and b in 2^-4 units, up to 4080: the sum fits 32 bits). */
K_FN uint k_flame_lerp(uint a, uint b, uint frac)
{
    return (a * (65536u - frac) + b * frac + 32768u) >> 16u;
}

/* A palette value (up to 4080) times an opacity visq (2^-15 units), rounded. */
K_FN uint k_flame_vis(uint q, uint visq)
{
    return (q * visq + 16384u) >> 15u;
}

/* The opacity sum of a point: 255 (4080 in 2^-4 units) times its opacity. */
#define K_FLAME_OPAQUE 4080u

#endif
