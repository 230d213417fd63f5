/*
 * The rivers generator's parameters (a layer's, as parsed from the scene) and its class.
 */
#ifndef FB_GEN_RIVERS_H
#define FB_GEN_RIVERS_H

#include "gen.h"
#include "palette.h"

/* Stream-power erosion with uplift (rivers.h); lengths in the heights' unit, times in one time unit. */
typedef struct fb_rivers_layer_params {
    bool has_input;  /* "input": the starting heights (a layer, or a number: flat at that height) */
    fb_ref input;    /* */
    double uplift;   /* U where the map is 1 (everywhere without a map) */
    bool has_map;    /* "uplift-map": a layer whose values scale U */
    fb_ref map;      /* */
    bool has_range;  /* "uplift-range": the map's values taken as 0 and 1 (else its lowest and highest) */
    double range[2]; /* */
    double K, m, n, kd, dt;
    int steps;
    double noise;
    bool keep_lakes;       /* "lakes": "keep" (else "fill") */
    unsigned outlets;      /* FB_RIVERS_NORTH | ... */
    bool has_sea;          /* "sea-level" */
    double sea_level;      /* */
    double extent;         /* the image's width in world units (0: the input's world, else 100000) */
    double river_area;     /* the river mask's threshold, world units squared (0: 1/1000 of the image's area) */
    int coarse;            /* "coarse": the model's grid width (0: the default; the image's width: the whole grid) */
    double detail;         /* "detail": the amplified land's fBm slope, a share of the local slope */
    fb_relief_spec relief; /* colour by height: R, G, B */
    double water[3];       /* the colour of rivers and standing water (lit like the land) */
} fb_rivers_layer_params;

extern const fb_gen_class fb_gen_rivers;

/* Its benchmark (bench.c). */
fb_result fb_rivers_bench(struct fb_bench *b);

#endif
