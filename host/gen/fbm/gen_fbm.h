/*
 * The fbm generator's parameters (a layer's, as parsed from the scene) and its class.
 */
#ifndef FB_GEN_FBM_H
#define FB_GEN_FBM_H

#include "gen.h"
#include "palette.h"

typedef struct fb_fbm_params {
    unsigned noise; /* K_NOISE_* */
    double hurst;   /* used when !gain_given */
    double gain;    /* G = 2^-H */
    bool gain_given;
    int octaves;
    double lacunarity;
    double rotation; /* degrees per octave */
    double frequency;
    double offset[2];
    bool ridged, billow, tileable;
    double warp;
    unsigned mapping; /* K_ENV_RECT, K_ENV_LATLONG or K_ENV_CUBE (kernels/envmap.h) */
} fb_fbm_params;

extern const fb_gen_class fb_gen_fbm;

/* Its benchmarks (bench.c). */
fb_result fb_fbm_bench(struct fb_bench *b);

/* Completes an fBm parameter block whose frequencies are set: the image size and the reciprocals the
 * kernel multiplies by (kernels never divide). Shared by the fBm layer and Julia's turbulence. */
struct K_FbmParams;
void fb_fbm_params_frame(struct K_FbmParams *p, int width, int height);

/* An upper bound on |lattice index| over every pixel, octave and stream of the block (the domain
 * coordinates grow by the lacunarity and the per-octave offsets, the warp moves them by at most its
 * strength times the octaves' amplitude sum), or infinity for non-finite parameters. Under 2^24 the
 * shader's wrap needs no huge-coordinate path (its specialisation constant 2). */
double fb_fbm_lattice_bound(const struct K_FbmParams *p);

#endif
