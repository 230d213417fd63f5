/*
 * sin and cos in float arithmetic only, so that a shader and C give the same bits: Vulkan allows a
 * device's sin and cos an absolute error of 2^-11, and lavapipe's differ from libm's in the last
 * bits, which an orbit or a noise lattice then amplifies. Cody and Waite's reduction by pi/2 in
 * three parts, then Cephes' single-precision polynomials (Moshier, sinf.c) on [-pi/4, pi/4]:
 * within 2 ulp of the true values for |x| up to a few turns, and in [-1, 1] for any finite x. Every operation `precise`
 * (no fused multiply-add on either side).
 */
#ifndef FB_KERNELS_SINCOS_H
#define FB_KERNELS_SINCOS_H

#include "envmap.h"

/* (sin x, cos x). */
K_FN k_vec2 k_sincos(float x)
{
    K_PRECISE float q = k_floor(x * 0.636619772f + 0.5f); /* x / (pi/2), rounded */
    K_PRECISE float r = ((x - q * 1.5703125f) - q * 4.837512969970703125e-4f) - q * 7.54978995489188216e-8f;
    /* beyond about 2^17 the reduction loses r (q times pi/2 is not exact): keep the polynomials in
     * their range, so that sin and cos stay within [-1, 1] (|r| <= pi/4 otherwise: no change) */
    if (k_abs(r) > 0.8f) r = r > 0.0f ? 0.8f : -0.8f;
    K_PRECISE float z = r * r;
    K_PRECISE float sn = r + r * z * (-1.6666654611e-1f + z * (8.3321608736e-3f + z * -1.9515295891e-4f));
    K_PRECISE float cs =
        1.0f - 0.5f * z + z * z * (4.166664568298827e-2f + z * (-1.388731625493765e-3f + z * 2.443315711809948e-5f));
    /* q mod 4 in float (exact): K_I(q) & 3 would be undefined beyond the int range in both
     * languages, where this gives the same quadrant (0 for |q| >= 2^26, a multiple of 4) */
    int n = K_I(q - 4.0f * k_floor(q * 0.25f));
    float s = n == 0 ? sn : n == 1 ? cs : n == 2 ? -sn : -cs;
    float c = n == 0 ? cs : n == 1 ? -sn : n == 2 ? -cs : sn;
    return k_vec2(s, c);
}

/* k_env_latlong_dir with these sin and cos: the same direction to 2 ulp, the same bits everywhere. */
K_FN k_vec3 k_env_latlong_dir_exact(float px, float py, uint w, uint h)
{
    k_vec2 ll = k_env_latlong_angles(px, py, w, h);
    k_vec2 a = k_sincos(ll.x), o = k_sincos(ll.y);
    return k_vec3(o.x * a.y, a.x, o.y * a.y);
}

/* k_env_dir the same way (cube directions involve no sin or cos). */
K_FN k_vec3 k_env_dir_exact(uint mapping, float px, float py, uint w, uint h)
{
    if (mapping == K_ENV_CUBE) return k_env_cube_dir(px, py, w);
    return k_env_latlong_dir_exact(px, py, w, h);
}

#endif
