/*
 * Stream-power erosion with tectonic uplift: dh/dt = U - K A^m S^n + kd lap(h), solved implicitly
 * along the drainage tree each time step (Braun and Willett 2013, "A very efficient O(n), implicit and
 * parallel method to solve the stream power equation governing fluvial incision and landscape
 * evolution", Geomorphology 180-181), with depressions filled or kept as lakes by priority-flood
 * (Barnes, Lehman and Mulla 2014, "Priority-flood: An optimal depression-filling and
 * watershed-labeling algorithm for digital elevation models", Computers & Geosciences) and hillslope
 * diffusion implicit in x then y. The whole grid is one computation: the result is the same bits for
 * any thread count (the parallel passes are row or column solves, each a pure function of the
 * previous step), and the layer's strips and regions are cut from it.
 */
#ifndef FB_RIVERS_H
#define FB_RIVERS_H

#include "fb.h"
#include "pool.h"
#include "progress.h"

#include <stdbool.h>
#include <stdint.h>

/* The image's edges that are outlets (open: water leaves, the edge is held at its height). */
enum { FB_RIVERS_NORTH = 1, FB_RIVERS_SOUTH = 2, FB_RIVERS_EAST = 4, FB_RIVERS_WEST = 8 };

/* The model, in world units: lengths in the heights' unit, times in one time unit. */
typedef struct fb_rivers_desc {
    int width, height;
    double cell;             /* world size of one cell */
    const float *initial;    /* width * height starting heights, row-major; NULL: flat at `base` */
    double base;             /* the flat start's height (initial NULL) */
    double noise;            /* added to the start: uniform in [0, noise) per cell, from the seed */
    uint32_t seed;           /* the noise's */
    double uplift;           /* U, height per time unit, times uplift_map where there is one */
    const float *uplift_map; /* width * height factors in [0, 1], or NULL (1 everywhere) */
    double K, m, n;          /* the stream power law's erodibility and exponents: K A^m S^n */
    double kd;               /* hillslope diffusivity, area per time unit (0: none) */
    double dt;               /* the time step */
    int steps;               /* time steps */
    bool keep_lakes;         /* depressions: kept as lakes (routed across) rather than filled */
    unsigned outlets;        /* FB_RIVERS_NORTH | ...: the open edges */
    bool has_sea;            /* cells below sea_level are the sea: outlets, held */
    double sea_level;        /* */
    double river_area;       /* the river mask: drainage area at least this (world units squared) */
    bool receivers;          /* also return each cell's receiver (fb_rivers_out.receiver) */
} fb_rivers_desc;

/* The result, width * height floats each (malloc'd; fb_rivers_out_free frees them), and what the
 * run found. */
typedef struct fb_rivers_out {
    float *height;        /* the surface: the bed, or with filled depressions the filled bed */
    float *area;          /* drainage area (world units squared) by steepest descent on the surface */
    float *river;         /* 1 where area >= river_area (not in the sea), else 0 */
    float *lake;          /* depth of standing water (a kept lake's, the sea's), else 0 */
    int32_t *receiver;    /* with desc.receivers: the cell each drains to on the surface (itself: an outlet) */
    double largest_basin; /* the share of the cells draining to one outlet */
    uint64_t flooded;     /* cells routed by priority-flood, summed over the steps */
    int flood_steps;      /* steps that had depressions */
    uint64_t final_fill;  /* cells the final (single-precision) fill raised */
    uint64_t outlets;     /* outlet cells at the end (open edges and the sea) */
} fb_rivers_out;

/* Checks the description; NULL when it is good, else what is wrong. */
const char *fb_rivers_check(const fb_rivers_desc *d);

/* Bytes the run allocates at its peak (its state and the result, with the receivers). */
uint64_t fb_rivers_memory(int width, int height);

/* Runs the model (pool: NULL for the calling thread only). FB_ERR_INPUT when no cell is an outlet (no
 * open edge and no cell below the sea level). On failure *out is untouched. */
fb_result fb_rivers_run(const fb_rivers_desc *d, fb_pool *pool, fb_progress *prog, fb_rivers_out *out);

void fb_rivers_out_free(fb_rivers_out *o);

#endif
