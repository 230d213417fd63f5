/*
 * The FBM constraint model (SPEC.md section 5): a macro shape d plus fBm detail whose strength is
 * controlled pointwise. P_fbm comes from random midpoint displacement (1D) or diamond-square (2D),
 * smooth stencils by default, on a (2^k + 1) grid covering the image, clamped to
 * [-sqrt(6) sigma, sqrt(6) sigma]; then Z P_d = 1 - Z |P_fbm| with Z = 1 / (sqrt(6) sigma + delta),
 * and D = d -/+ sqrt(-2 T ln(Z P_d)) (equations 5 to 10). Discrete constraints pin D = d exactly;
 * continuous constraints set T or H near points with the fall-off of equation 14, overlapping
 * domains averaged by equation 15. docs/constrain.md states the readings chosen where the paper is
 * ambiguous.
 */
#ifndef FB_CONSTRAIN_H
#define FB_CONSTRAIN_H

#include "fb.h"

#include <stdbool.h>
#include <stdint.h>

typedef enum fb_buffering {
    FB_BUFFER_REGIONAL = 0, /* the paper's regional buffering (our reading: the buffer points move with
                               the constraint, so local increments are kept) */
    FB_BUFFER_NONE = 1,     /* P_fbm(p*) = 0 at the level p* is created, its neighbours interpolated */
    FB_BUFFER_NAIVE = 2,    /* P_fbm(p*) = 0 forced after the whole field is generated (for comparison) */
} fb_buffering;

typedef struct fb_cpoint {
    int x, y; /* pixel: column, row from the top left */
} fb_cpoint;

typedef struct fb_cregion {
    int x, y;     /* the constraint point */
    bool is_h;    /* the value is a roughness H, else an approximation degree T */
    double value; /* F(p*) */
} fb_cregion;

typedef struct fb_constrain_desc {
    int width, height; /* height 1: a 1D profile */
    uint32_t seed;
    double hurst, T, sigma, delta; /* the base roughness H, approximation T, sigma, delta */
    const float *macro;            /* d, width * height values */
    const fb_cpoint *points;
    int npoints;
    const fb_cregion *regions;
    int nregions;
    int domain;     /* n of equation 13: a region reaches points within 2^n pixels (L1) */
    double falloff; /* f_d of equation 14, per pixel^2 */
    fb_buffering buffering;
    double soften; /* > 0: D - d as an odd cubic of P for |P| < soften sigma, C1 with equation 10 (0: the paper) */
    bool linear;   /* the paper's midpoint / diamond-square averages instead of the smooth stencils */
    int threads;   /* 0: one per core (the result does not depend on it) */
} fb_constrain_desc;

typedef struct fb_constrain_out {
    float *D, *T, *H; /* width * height each (malloc'd; the caller frees) */
    float *P;         /* P_fbm after the constraints, before clamping (for tests), or NULL if not asked */
} fb_constrain_out;

/* Computes D, and the T and H fields used. want_p: also return P. */
fb_result fb_constrain_run(const fb_constrain_desc *d, bool want_p, fb_constrain_out *out);

/* Equation 15 at one pixel: the base value plus the mean of the fall-offs of the regions of that
 * kind whose domain reaches it (F0 when none does). Used by fb_constrain_run and by the tests. */
double fb_constrain_field(const fb_constrain_desc *d, bool is_h, int x, int y);

/* The standard normal deviate the recursion uses for node `index` (row-major on the grid): the
 * normal quantile (Acklam's approximation) of a 32-bit hash of (seed, index). For the tests. */
double fb_constrain_normal(uint32_t seed, uint32_t index);

/* Built-in macro shapes over the image ("cone", "ridge", "boss", "bowl"), height h; 1D profiles
 * use the row. Returns false for an unknown name. */
bool fb_constrain_macro(const char *name, int width, int height, double h, float *out);

#endif
