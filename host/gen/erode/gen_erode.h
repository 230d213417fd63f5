/*
 * The erode generator's parameters (a layer's, as parsed from the scene) and its class.
 */
#ifndef FB_GEN_ERODE_H
#define FB_GEN_ERODE_H

#include "gen.h"

/* Erosion of another layer's heights (erode.h); every length in the heights' unit. */
typedef struct fb_erode_layer_params {
    fb_ref input;  /* the heights: another layer's channel */
    double extent; /* the image's width in world units (0: the input's world, else 1024) */
    int iterations;
    double duration, rain, gravity, capacity, dissolve, deposit, evaporate, depth, talus, thermal;
    char prefix[4096];   /* "masks": PREFIX */
    char masks[4][1040]; /* PREFIX.flow.png, .wear, .deposition, .sediment; "" none */
    int mask_bits;       /* 8 or 16 */
} fb_erode_layer_params;

extern const fb_gen_class fb_gen_erode;

/* Its benchmark (bench.c). */
fb_result fb_erode_bench(struct fb_bench *b);

#endif
