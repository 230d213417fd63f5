/*
 * Colour for escape-time images. The host resamples every palette (named, cosine a + b cos(2 pi (c t
 * + d)), or gradient stops) into K_PALETTE_SIZE linear-RGB entries; the kernel maps the smooth count
 * to a palette position and a brightness weight. Fetching the two table entries is the caller's
 * (a buffer in the shader, an array in C): kernels take no arrays.
 */
#ifndef FB_KERNELS_PALETTE_H
#define FB_KERNELS_PALETTE_H

#include "common.h"

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
 * only the pixels nearest the set bright: clusters of stars rather than a flat fill. */
K_FN float k_sky_weight(K_SkyColour c, float n)
{
    float w = k_clamp(n * c.inv_n_ref, 0.0f, 1.0f);
    return c.density > 0.0f ? k_pow(w, c.density) : 1.0f;
}

/* The final channel value from a palette value and the weight. */
K_FN float k_sky_channel(K_SkyColour c, float palette_value, float weight)
{
    float v = c.brightness * weight * palette_value;
    return c.gamma != 1.0f ? k_pow(k_max(v, 0.0f), c.gamma) : v;
}

#endif
