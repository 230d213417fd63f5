/*
 * The terrain generator's parameters (a layer's, as parsed from the scene) and its class.
 */
#ifndef FB_GEN_TERRAIN_H
#define FB_GEN_TERRAIN_H

#include "gen.h"
#include "palette.h"

typedef struct fb_terrain_layer_params {
    bool points_inline;         /* the points are the layer's "points" array in the scene JSON */
    char points[1024];          /* else an XYZ / CSV file, or "" */
    char heightfield[1024];     /* else a height-field EXR[:layer.channel] */
    int sample;                 /* its sampling step, pixels */
    uint64_t insert;            /* points to insert */
    double hurst;               /* H (from hurst or 3 - dimension) */
    double dimension;           /* D, when given instead of hurst */
    double sigma;               /* < 0: estimated from the data */
    bool sweep, local_variance; /* --order sweep, --variance local */
    bool additions;             /* --variance additions */
    int variance;               /* the key: 0 stage, 1 local, 2 additions */
    char centers[1024];         /* CSV of centres, or "" */
    bool auto_bounds;
    double bounds[4];
    char mesh[1024];       /* .ply or .obj, or "" */
    bool smooth;           /* "interpolation": "smooth": the Clough-Tocher surface (smooth.h) */
    char crs[4096];        /* the crs key, or "" */
    int epsg;              /* crs "EPSG:N": a projected CRS, recorded in a GeoTIFF heightmap; 0: not stated */
    fb_relief_spec relief; /* colour by height (the lowest and highest: the refined mesh's) */
} fb_terrain_layer_params;

extern const fb_gen_class fb_gen_terrain;

/* Its benchmarks (bench.c). */
fb_result fb_terrain_bench(struct fb_bench *b);

#endif
