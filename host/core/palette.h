/* Palettes for escape-time colour: named night-sky palettes, cosine palettes and gradient stops,
 * all resampled into one K_PALETTE_SIZE-entry linear-RGB table. */
#ifndef FB_PALETTE_H
#define FB_PALETTE_H

#include "fb.h"

#include <stdbool.h>

#define FB_PALETTE_ENTRIES   256
#define FB_PALETTE_MAX_STOPS 16
#define FB_PALETTE_NAMES     "night|nebula|aurora|ice|ember|grey|foliage|blossom"

typedef struct fb_palette_spec {
    int named;       /* index into FB_PALETTE_NAMES, used when neither below is given */
    bool has_cosine; /* a + b cos(2 pi (c t + d)), per channel: a[3] b[3] c[3] d[3] */
    double cosine[12];
    int nstops; /* gradient: (t, r, g, b) with t increasing from 0 to 1 */
    double stops[FB_PALETTE_MAX_STOPS][4];
} fb_palette_spec;

/* Fills table[i] = (r, g, b, 0) at t = i / (entries - 1). */
void fb_palette_build(const fb_palette_spec *spec, float table[FB_PALETTE_ENTRIES][4]);

#endif
