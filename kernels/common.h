/*
 * The common subset of C11 and GLSL 450 that every kernel is written in.
 *
 * A kernel header is included twice: by a compute shader (which defines K_GLSL before the
 * include) and by the host's native backend, compiled as C11 with -ffp-contract=off. The rules:
 * scalar code and small structs passed by value, no pointers, arrays, recursion or globals, float
 * literals with an explicit `f`, unsigned literals with `u`, and conversions through K_U/K_I/K_F so
 * that both languages spell them the same. uint32 arithmetic wraps identically in both.
 *
 * Math functions go through k_* names because C's <math.h> spells them floorf, sqrtf, ...
 */
#ifndef FB_KERNELS_COMMON_H
#define FB_KERNELS_COMMON_H

#ifdef K_GLSL

#define K_FN
#define K_U(x)      uint(x)
#define K_I(x)      int(x)
#define K_F(x)      float(x)
#define k_floor(x)  floor(x)
#define k_sqrt(x)   sqrt(x)
#define k_abs(x)    abs(x)
#define k_sin(x)    sin(x)
#define k_cos(x)    cos(x)
#define k_exp2(x)   exp2(x)
#define k_log2(x)   log2(x)
#define k_pow(x, y) pow(x, y)
#define k_min(a, b) min(a, b)
#define k_max(a, b) max(a, b)
#define k_isnan(x)  isnan(x)
#define k_isinf(x)  isinf(x)
#define K_STRUCT(n) struct n
#define K_END(n)    ;
#define K_MAKE(n)   n
/* No fused multiply-add in computations that produce this variable (SPIR-V NoContraction), so
 * that the device rounds every operation as C built with -ffp-contract=off does. */
#define K_PRECISE precise

/* A float's bits and back. */
#define k_float_bits(x) floatBitsToUint(x)
#define k_bits_float(u) uintBitsToFloat(u)

#else /* C11 */

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

typedef uint32_t uint;

#define K_FN        static inline
#define K_U(x)      ((uint)(x))
#define K_I(x)      ((int)(x))
#define K_F(x)      ((float)(x))
#define k_floor(x)  floorf(x)
#define k_sqrt(x)   sqrtf(x)
#define k_abs(x)    fabsf(x)
#define k_sin(x)    sinf(x)
#define k_cos(x)    cosf(x)
#define k_exp2(x)   exp2f(x)
#define k_log2(x)   log2f(x)
#define k_pow(x, y) powf(x, y)
#define k_min(a, b) fminf(a, b)
#define k_max(a, b) fmaxf(a, b)
#define k_isnan(x)  isnan(x)
#define k_isinf(x)  isinf(x)
#define K_STRUCT(n) typedef struct n
#define K_END(n)    n;
#define K_MAKE(n)   (n)
#define K_PRECISE

/* A float's bits and back (GLSL's floatBitsToUint and uintBitsToFloat). */
static inline uint k_float_bits(float x)
{
    uint u;
    memcpy(&u, &x, sizeof u);
    return u;
}
static inline float k_bits_float(uint u)
{
    float x;
    memcpy(&x, &u, sizeof x);
    return x;
}

#endif

/* Environment-map code (lat-long and cube mappings, 3D noise): always in C; in GLSL only in the
 * shaders that define K_ENVMAP (fbm_env.comp, julia_env.comp). A plane's pipeline then carries
 * none of it: lavapipe compiled it even where a specialisation constant made it unreachable, at
 * three times the pipeline's creation time and 80 MiB more memory. */
#if !defined(K_GLSL) || defined(K_ENVMAP)
#define K_WITH_ENVMAP 1
#else
#define K_WITH_ENVMAP 0
#endif

#define K_PI  3.14159265358979f
#define K_TAU 6.28318530717959f

/* A 2-component float vector: `k_vec2` is the type and `k_vec2(x, y)` the constructor in both
 * languages (a function-like macro in C only expands when followed by a parenthesis). */
#ifdef K_GLSL
#define k_vec2 vec2
#else
typedef struct k_vec2 {
    float x, y;
} k_vec2;
static inline k_vec2 k_vec2_make(float x, float y)
{
    k_vec2 v = {x, y};
    return v;
}
#define k_vec2(x, y) k_vec2_make(x, y)
#endif

/* Colours: `k_vec3` (r, g, b as x, y, z) and `k_vec4` the same way. */
#ifdef K_GLSL
#define k_vec3 vec3
#define k_vec4 vec4
#else
typedef struct k_vec3 {
    float x, y, z;
} k_vec3;
typedef struct k_vec4 {
    float x, y, z, w;
} k_vec4;
static inline k_vec3 k_vec3_make(float x, float y, float z)
{
    k_vec3 v = {x, y, z};
    return v;
}
#define k_vec3(x, y, z)    k_vec3_make(x, y, z)
static inline k_vec4 k_vec4_make(float x, float y, float z, float w)
{
    k_vec4 v = {x, y, z, w};
    return v;
}
#define k_vec4(x, y, z, w) k_vec4_make(x, y, z, w)
#endif

K_FN float k_clamp(float x, float lo, float hi)
{
    return k_min(k_max(x, lo), hi);
}

/* Quintic fade 6t^5 - 15t^4 + 10t^3: C2-continuous interpolation weight (Perlin 2002). */
K_FN float k_fade(float t)
{
    return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f);
}

K_FN float k_mix(float a, float b, float t)
{
    return a + (b - a) * t;
}

#endif
