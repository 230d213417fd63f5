/*
 * The stars generator's parameters (a layer's, as parsed from the scene) and its class.
 */
#ifndef FB_GEN_STARS_H
#define FB_GEN_STARS_H

#include "gen.h"

#include <stdbool.h>

typedef struct fb_stars_params {
    unsigned mapping;  /* K_ENV_LATLONG, K_ENV_CUBE or K_STARS_POLAR */
    double limit;      /* limiting magnitude: the faintest star drawn */
    double slope;      /* log10 N(<m) grows by slope per magnitude */
    double count6;     /* stars brighter than magnitude 6 over the whole sky */
    double brightness; /* the luminance flux of a magnitude-0 star */
    double psf;        /* the tent's half width, pixels */
    double milky_way;  /* the band's density contrast at its centre (0: none) */
    double mw_width;   /* the band's half width at e^-1/2, degrees of galactic latitude */
    double pole[2];    /* the north galactic pole: longitude and latitude in degrees, the map's frame */
} fb_stars_params;

extern const fb_gen_class fb_gen_stars;

/* Its benchmarks (bench.c). */
fb_result fb_stars_bench(struct fb_bench *b);

#endif
