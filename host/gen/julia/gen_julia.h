/*
 * The julia generator's parameters (a layer's, as parsed from the scene) and its class.
 */
#ifndef FB_GEN_JULIA_H
#define FB_GEN_JULIA_H

#include "gen.h"
#include "palette.h"

typedef struct fb_julia_params {
    unsigned mapping; /* K_JULIA_RECT (eq. 7), _POLAR (eq. 8), _LATLONG or _CUBE (environment maps) */
    double scale[2];
    double radius;
    double center[2];
    double rotation; /* degrees */
    double alpha[2];
    double c[2];
    int max_iter;
    double bailout;
    fb_palette_spec palette;
    double period, palette_offset, brightness, gamma, density, density_count;
    double inside_color[3];
    double turbulence, turb_hurst, turb_frequency;
    int turb_octaves;
    int samples;
    unsigned channels; /* bit k: stored channel k of iter, n, inside, de, R, G, B */
    bool double_precision;
} fb_julia_params;

extern const fb_gen_class fb_gen_julia;

/* Its benchmarks (bench.c). */
fb_result fb_julia_bench(struct fb_bench *b);

#endif
