/*
 * Rendering a flame genome as flam3 3.1.1 does, after the chaos game: the camera and kernel tables
 * (fb_flame_setup), the fixed-point histogram, density estimation, the spatial filter, and the tone
 * map (fb_flame_tone), which `tonemap` can rerun from the stored accumulations.
 */
#ifndef FB_FLAME_RENDER_H
#define FB_FLAME_RENDER_H

#include "genome.h"
#include "pool.h"

/* One histogram cell: the sums of r, g, b, a (the palette's 0..255 scale times the point's opacity,
 * in units of 2^-4) and of the opacity (255 per opaque hit, the same units), and the hit count.
 * Integers, so that the sum over threads, strips, points parts and devices is the same bits. The
 * chaos game adds into 32-bit cells of its own (half the memory traffic of 64-bit ones: the game
 * waits on its scattered writes); a cell whose opacity sum (the largest of its sums) passes 2^31 is
 * added into the shared 64-bit total at once (atomically) and cleared, so none overflows. */
typedef struct fb_flame_cell32 {
    uint32_t c[5];
    uint32_t hits;
} fb_flame_cell32;

typedef struct fb_flame_cell {
    uint64_t c[5];
    uint64_t hits;
} fb_flame_cell;

/* flam3's tone map of a filtered accumulation (brightness 1): the genome's values. */
typedef struct fb_flame_tone {
    double brightness, gamma, gamma_threshold, vibrancy, highlight_power;
    double background[3];
} fb_flame_tone;

typedef struct fb_flame_setup {
    K_FlameParams p;
    K_FlameXform xf[FB_FLAME_MAX_XFORMS + 1];
    K_FlameVar var[(FB_FLAME_MAX_XFORMS + 1) * K_V_COUNT];
    uint32_t nvar;
    uint32_t *dist; /* (nxf + 1) rows of K_FLAME_GRAIN xform numbers */
    uint32_t ndist;
    uint32_t palq[256][4]; /* the palette times 255, in units of 2^-4 (linear mode interpolates them) */
    bool linear_palette;
    int width, height, ss;
    int gutter, de_offset;
    double *filter; /* fwidth x fwidth, normalised */
    int fwidth;
    double k1, k2;
    double samples; /* points in all (flam3's nsamples) */
    /* density estimation kernels (flam3_create_de_filters) */
    double estimator_curve;
    int de_max_index, de_kernel_size;
    double de_max_counts;
    double *de_coefs, *de_widths;
    fb_flame_tone tone;
} fb_flame_setup;

/* Fills `out` for genome g rendered at width x height (the genome's view, scaled to that width)
 * with `quality` samples per pixel (<= 0: the genome's), seed `seed`. Owns dist, filter, de_*:
 * fb_flame_setup_fini. */
fb_result fb_flame_setup_init(const fb_flame_genome *g, int width, int height, double quality, uint32_t seed,
                              fb_flame_setup *out);
void fb_flame_setup_fini(fb_flame_setup *s);

/* A temporal sample of a frame: the chaos game of genome g (its camera, xforms and palette) on the
 * frame's histogram (size, supersample and gutter from `frame`), `share` of its points and its
 * palette times `scalar` (the temporal filter's weight). No filters: owns dist alone
 * (fb_flame_setup_fini). */
fb_result fb_flame_setup_sample(const fb_flame_genome *g, const fb_flame_setup *frame, double quality, uint32_t seed,
                                double share, double scalar, fb_flame_setup *out);

/* The K_FlameVar of variation v of xform x (its weight and parameters, as flam3's precalc does). */
K_FlameVar fb_flame_var_params(const fb_flame_xform *x, int v);

/* Adds a 32-bit cell into the 64-bit total (atomically: other threads may spill into it) and clears it. */
void fb_flame_spill(fb_flame_cell *total, fb_flame_cell32 *h);

/* From the histogram (hist_w x hist_h cells) to the image: density estimation and the spatial filter
 * give each pixel's accumulation at brightness 1 (acc: 4 planes of width x height, r g b a) and its
 * hits (count). On the threads of pool (NULL: this thread) in bands, each cell's terms added in the
 * one fixed order, so the floats are the same bits for any thread count and on every run. */
fb_result fb_flame_filter(const fb_flame_setup *S, const fb_flame_cell *hist, float *const acc[4], uint32_t *count,
                          fb_pool *pool);

/* flam3's tone map of n pixels' accumulations (brightness 1) into linear R, G, B (the sRGB decoding
 * of flam3's 8-bit output, the background composited under) and alpha. */
void fb_flame_tone_row(const fb_flame_tone *t, size_t n, const float *const acc[4], float *R, float *G, float *B,
                       float *A);

/* n zeroed bytes for a histogram or an accumulation (fb_malloc_large: huge pages, so that the first
 * touch of tens of MiB costs a fault per 2 MiB rather than per 4 KiB), zeroed in 2 MiB chunks on the
 * threads of pool (NULL: this thread); free() it. */
void *fb_flame_zalloc(size_t n, fb_pool *pool);

/* Adds cells [c0, c1) of the 32-bit histogram b into a. */
void fb_flame_hist_fold(fb_flame_cell *a, const fb_flame_cell32 *b, size_t c0, size_t c1);

#endif
