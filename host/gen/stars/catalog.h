/*
 * The star catalogue: every star of the sky down to the limiting magnitude, drawn from the sphere's
 * fixed cells (a cube sphere, FB_STARS_CELLS cells along each face's edge) by a hash of the seed and
 * the cell (kernels/hash.h), so the same scene has the same stars whatever the image's size or
 * mapping. Host code, in double precision: both backends read the same records.
 */
#ifndef FB_STARS_CATALOG_H
#define FB_STARS_CATALOG_H

#include "gen_stars.h"

#include <stddef.h>
#include <stdint.h>

#define FB_STARS_CELLS 64

typedef struct fb_star {
    double dir[3]; /* unit direction, the maps' frame (+Y up, longitude 0 at +Z) */
    double mag;
    double temp;   /* kelvin */
    double rgb[3]; /* linear Rec. 709 colour of luminance 1 */
} fb_star;

/* The stars of the whole sky, in cell order; *n of them (free(*out)). */
fb_result fb_stars_catalog(const fb_stars_params *P, uint32_t seed, fb_star **out, size_t *n);

/* The expected number of stars over the whole sky, N(<limit) = count6 10^(slope (limit - 6)). */
double fb_stars_expected(const fb_stars_params *P);

/* The linear Rec. 709 colour of a blackbody at temp kelvin, scaled to luminance 1. */
void fb_stars_blackbody(double temp, double rgb[3]);

#endif
