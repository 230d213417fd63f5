/*
 * Colour for escape-time images. The host resamples every palette (named, cosine a + b cos(2 pi (c t
 * + d)), or gradient stops) into K_PALETTE_SIZE linear-RGB entries; the kernel maps the smooth count
 * to a palette position and a brightness weight. Fetching the two table entries is the caller's
 * (a buffer in the shader, an array in C): kernels take no arrays.
 */
#ifndef FB_KERNELS_PALETTE_H
#define FB_KERNELS_PALETTE_H

#include "common.h"
#include "explog.h"

#define K_PALETTE_SIZE 256u

K_STRUCT(K_SkyColour)
{
    float inv_period; /* 1 / smooth-count units per palette sweep (kernels never divide) */
    float offset;     /* palette position at count 0, in sweeps */
    float brightness; /* linear scale of the colour */
    float gamma;      /* exponent on the weighted colour */
    float density;    /* contrast exponent: weight = clamp(n / n_ref, 0, 1)^density */
    float inv_n_ref;  /* 1 / the count at which the weight reaches 1 */
    float inside_r, inside_g, inside_b;
    uint samples; /* colour samples per pixel (1: the centre only) */
    uint seed;    /* jitter seed */
    float inv_samples;
}
K_END(K_SkyColour)

/* Palette position in [0, K_PALETTE_SIZE - 1] for a smooth count: a triangle wave (0 -> 1 -> 0) with
 * one sweep per `period`, so that a gradient never jumps where it repeats. */
K_FN float k_palette_pos(K_SkyColour c, float n)
{
    float x = n * c.inv_period + c.offset;
    float f = x - 2.0f * k_floor(x * 0.5f);
    float t = f < 1.0f ? f : 2.0f - f;
    return k_clamp(t, 0.0f, 1.0f) * K_F(K_PALETTE_SIZE - 1u);
}

/* Brightness weight: far from the set (small counts) dark, near it bright. A larger density keeps
 * only the pixels nearest the set bright: clusters of stars rather than a flat fill. pow is
 * kernels/explog.h's (here and below): the same bits in C, on AVX2 lanes and on a device. */
K_FN float k_sky_weight(K_SkyColour c, float n)
{
    float w = k_clamp(n * c.inv_n_ref, 0.0f, 1.0f);
    return c.density > 0.0f ? k_pow_poly(w, c.density) : 1.0f;
}

/* The final channel value from a palette value and the weight. */
K_FN float k_sky_channel(K_SkyColour c, float palette_value, float weight)
{
    float v = c.brightness * weight * palette_value;
    return c.gamma != 1.0f ? k_pow_poly(k_max(v, 0.0f), c.gamma) : v;
}

/* The two palette entries around a smooth count's position: the caller fetches entries[k_sky_i0]
 * and entries[k_sky_i1] (a buffer in GLSL, an array in C) and hands them to k_sky_rgb. */
K_FN uint k_sky_i0(K_SkyColour c, float n)
{
    return K_U(k_palette_pos(c, n));
}

K_FN uint k_sky_i1(uint i0)
{
    return i0 + 1u < K_PALETTE_SIZE ? i0 + 1u : i0;
}

/* A Julia sample's linear colour: the inside colour, or the palette entries e0 and e1 (at k_sky_i0
 * and k_sky_i1) mixed at the position's fraction, weighted by the distance to the set. The one
 * colour lookup of the shader and of the native backend. */
K_FN k_vec3 k_sky_rgb(K_SkyColour c, uint inside, float n, k_vec4 e0, k_vec4 e1)
{
    if (inside != 0u) return k_vec3(c.inside_r, c.inside_g, c.inside_b);
    float pos = k_palette_pos(c, n);
    float f = pos - K_F(K_U(pos)), w = k_sky_weight(c, n);
    return k_vec3(k_sky_channel(c, k_mix(e0.x, e1.x, f), w), k_sky_channel(c, k_mix(e0.y, e1.y, f), w),
                  k_sky_channel(c, k_mix(e0.z, e1.z, f), w));
}

#endif
