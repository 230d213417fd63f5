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

/* A height layer's colour by height under a light (a relief map; the keys FB_RELIEF_KEYS, read by
 * fb_schema_relief): "palette", "cosine" or "stops" given, R, G, B are the surface lit from `light`
 * (azimuth clockwise from north, y up, and altitude; degrees) with `ambient` light, coloured by the
 * palette from its lowest height (colour-range, or the layer's own) to its highest. */
typedef struct fb_relief_spec {
    bool colour;
    fb_palette_spec palette;
    double light[2], ambient;
    bool range_set;
    double range[2];
} fb_relief_spec;

/* The colouring itself: the palette's table, its heights and the light's unit vector (x east, y north,
 * z up). */
typedef struct fb_relief {
    float table[FB_PALETTE_ENTRIES][4];
    double zlo, zhi, lx, ly, lz, ambient;
} fb_relief;

/* Builds the table and the light; the heights from the spec's range, else zlo and zhi as given. */
void fb_relief_init(fb_relief *r, const fb_relief_spec *spec, double zlo, double zhi);

/* The light a surface rising by (gx, gy) per world unit east and north gets: Lambert's law under the
 * light, ambient + (1 - ambient) max(0, n . l). */
double fb_relief_light(const fb_relief *r, double gx, double gy);

/* The lit colour of a point of height z whose surface rises by (gx, gy) per world unit east and north:
 * Lambert's law under the light, ambient + (1 - ambient) max(0, n . l), times the palette's colour at
 * the height (clamped to its ends). */
void fb_relief_colour(const fb_relief *r, double z, double gx, double gy, float rgb[3]);

#endif
