/*
 * The constrain generator's parameters (a layer's, as parsed from the scene) and its class.
 */
#ifndef FB_GEN_CONSTRAIN_H
#define FB_GEN_CONSTRAIN_H

#include "gen.h"

/* The FBM constraint model (constrain.h). Points and regions come from the scene's JSON (inline)
 * or from files, read when the layer is set up. */
typedef struct fb_constrain_params {
    char macro[1024];    /* "cone" | "ridge" | "boss" | "bowl" | IN.exr[:layer.channel] */
    fb_ref macro_ref;    /* the macro shape from another layer of the scene (layer -1: none) */
    double macro_height; /* built-in shapes */
    char profile[1024];  /* 1D: a CSV profile instead of macro, or "" */
    double T, hurst, sigma, delta;
    double soften; /* "soften": the zero lines' blend width, in sigma (0: equation 10 as it is) */
    bool points_inline, regions_inline;
    char points[1024], regions[1024]; /* files, or "" */
    int domain;
    double falloff;
    int buffering; /* fb_buffering */
    bool linear;   /* "interpolation": "linear" */
    bool has_water;
    double water;
    char csv[1024];  /* 1D: write x, d, D here, or "" */
    char plot[1024]; /* 1D: a PNG plot of d and D here, or "" */
} fb_constrain_params;

extern const fb_gen_class fb_gen_constrain;

/* Its benchmarks (bench.c). */
fb_result fb_constrain_bench(struct fb_bench *b);

#endif
