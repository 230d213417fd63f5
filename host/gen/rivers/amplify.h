/*
 * A river-carved landscape at any size from a coarse solution of the stream power law (Cordonnier,
 * Braun, Cani, Benes, Galin, Peytavie and Guerin 2016, "Large Scale Terrain Generation from Tectonic
 * Uplift and Fluvial Erosion", Eurographics): the model runs on a coarse grid (rivers.h), and each
 * output pixel is a function of that solution and its own absolute coordinates alone, so the image
 * streams in strips, and regions and tasks cut it anywhere with the same bits.
 *
 * The surface is the lowest of two parts:
 *   - the land: the coarse surface interpolated (Catmull-Rom), plus fBm detail whose slope is a share
 *     of the local slope (`detail`), faded out beside the channels;
 *   - the channels: every coarse cell drains by a straight segment from a point of its cell (placed
 *     by the seed, off the grid's lines) to its receiver's point, a bed level falling strictly along
 *     it, a flat bed of a width that grows with the drainage area and banks rising at the local
 *     slope. Bed levels fall strictly downstream (the coarse heights are first raised where they
 *     fall by too little for single precision over the segment's pixels).
 * Each part has a lower neighbour at every pixel where it is the lower (the land but at the coarse
 * cells' own minima, which lie on channels; a bed along its segment), so their minimum drains, as
 * the coarse surface does. Standing water (kept lakes, the sea) is the coarse depth interpolated, or
 * the sea level over the amplified surface.
 */
#ifndef FB_RIVERS_AMPLIFY_H
#define FB_RIVERS_AMPLIFY_H

#include "rivers.h"

/* One coarse cell's channel: from (px, py) to (px + ex, py + ey), coarse units. */
typedef struct fb_rivers_seg {
    float px, py, ex, ey;
    float inv_len2; /* 1 / |e|^2; 0: an outlet, no channel */
    float hb;       /* the bed's half-width, coarse units */
    double c0, c1;  /* the bed's level at its start and at its end */
    double bank;    /* the banks' rise, height per coarse unit */
    float area;     /* the drainage area through it, world units squared */
    float pad;
} fb_rivers_seg;

typedef struct fb_rivers_amp {
    int W, H;           /* the output */
    int cw, ch;         /* the coarse grid */
    double sx, sy;      /* coarse units per output pixel */
    double cell;        /* the output's cell, world units */
    double *h;          /* the coarse surface, raised to drain in single precision */
    float *slope;       /* |grad| of the coarse surface, per node */
    float *lake;        /* the coarse depth of kept lakes, per node (NULL: none) */
    fb_rivers_seg *seg; /* per node */
    bool has_sea;       /* */
    double sea_level;   /* */
    double river_area;  /* world units squared */
    double detail;      /* the detail's slope as a share of the local slope */
    double lambda;      /* the detail's longest wavelength, output pixels */
    int octaves;        /* its octaves */
    uint32_t seed;
} fb_rivers_amp;

/* Bytes an amplification of a cw x ch coarse grid holds. */
uint64_t fb_rivers_amp_memory(int cw, int ch);

/* Builds the amplification of the coarse solution `o` of `d` (d->width x d->height) to W x H
 * (W >= 2 d->width); keep_lakes/has_sea/sea_level/river_area from d, `detail` the fBm's share of the
 * slope. FB_ERR_NOMEM on failure (then *a is zeroed). */
fb_result fb_rivers_amp_init(fb_rivers_amp *a, const fb_rivers_desc *d, const fb_rivers_out *o, int W, int H,
                             double detail);

void fb_rivers_amp_fini(fb_rivers_amp *a);

/* Rows [y0, y0 + n) of the output: the surface, the drainage area, the river mask and the standing
 * water, n x W floats each (any may be NULL). A pure function of (x, y) and the coarse solution. */
void fb_rivers_amp_rows(const fb_rivers_amp *a, int y0, int n, float *Y, float *area, float *river, float *lake);

#endif
