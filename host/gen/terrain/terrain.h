/*
 * Terrain by Delaunay refinement of known points (SPEC.md section 4): the survey points are
 * triangulated, then new points are inserted one by one at the barycentre of a triangle with the
 * height z_abc + d, d one Gaussian draw whose variance follows equations IV to VI so that height
 * increments grow like dist^(2H); or, with `additions`, the height of an fBm field of the asked H
 * plus the survey's residual interpolated (terrain.c). Everything here runs on the CPU,
 * sequentially, from the counter-based RNG: the same input and seed give the same mesh bit for bit.
 */
#ifndef FB_TERRAIN_H
#define FB_TERRAIN_H

#include "delaunay.h"
#include "fb.h"

#include <stdbool.h>
#include <stdint.h>

#define FB_TERRAIN_MAX_CENTERS 4096
#define FB_TERRAIN_MAX_INSERT  100000000ull

/* A centre of influence: inserted points in its Voronoi cell take its H and sigma. */
typedef struct fb_terrain_center {
    double x, y;
    double hurst; /* H = 3 - D */
    double sigma; /* standard deviation of increments at unit distance; < 0: estimated from the data */
} fb_terrain_center;

typedef struct fb_terrain_opts {
    uint64_t insert;     /* points to insert */
    double hurst;        /* H in (0, 1) */
    double sigma;        /* < 0: estimated from the data */
    bool sweep;          /* ordered sweep over triangle slots instead of random sites */
    bool local_variance; /* var(z_abc - z_*) over the triangle's neighbourhood instead of per stage */
    bool additions;      /* an fBm field plus the survey's residual instead of equations IV to VI (terrain.c) */
    uint32_t seed;
    const fb_terrain_center *centers; /* NULL or ncenters entries; replace hurst and sigma */
    int ncenters;
    void (*progress)(void *user, uint64_t done, uint64_t total);
    void *user;
} fb_terrain_opts;

typedef struct fb_terrain_stats {
    uint32_t input;      /* distinct input points (vertices 0 .. input-1 of the mesh) */
    uint64_t duplicates; /* input points equal to an earlier one, left out */
    uint64_t inserted;
    uint64_t clamped;     /* negative displacement variances set to zero */
    uint64_t rejected;    /* random sites outside the hull, or barycentres equal to a vertex */
    uint64_t hull_splits; /* of the inserted points, those at a hull edge's midpoint (terrain.c) */
    uint32_t stages;      /* stage-variance recomputations */
    double sigma;         /* sigma used without centres (estimated or given) */
    double build_seconds, refine_seconds;
} fb_terrain_stats;

typedef struct fb_terrain {
    fb_dt dt;
    double *z; /* per vertex */
    size_t capz;
    uint32_t ninput;
    double bbox[4]; /* of the input: xmin, xmax, ymin, ymax */
} fb_terrain;

/* Triangulates n points (x, y, z), all finite (the caller reports bad lines). */
fb_result fb_terrain_build(fb_terrain *t, const double *xyz, size_t n, const char *who, fb_terrain_stats *st);

/* sigma^2 estimated from the input: the mean over Delaunay edges between input vertices of
 * (z_k - z_l)^2 / dist^(2H). 0 when the input is flat. */
double fb_terrain_sigma2_estimate(const fb_terrain *t, double hurst);

/* Inserts opts->insert points. */
fb_result fb_terrain_refine(fb_terrain *t, const fb_terrain_opts *o, const char *who, fb_terrain_stats *st);

/* The standard normal draw number `index` of the counter-based RNG (Box-Muller over two 32-bit
 * hashes): the displacement of the index-th inserted point. Exposed for tests. */
double fb_terrain_gauss(uint32_t seed, uint64_t index);

/* The fBm field F that --variance additions adds (terrain.c), without the scales finer than the last
 * vertex spacing, at n points xy: F for the hull and bounding box of t refined to nv_final
 * vertices, with o's seed and H and the given sigma^2 (o's centres are ignored). Exposed for tests. */
fb_result fb_terrain_field(const fb_terrain *t, const fb_terrain_opts *o, double sigma2, uint64_t nv_final,
                           const double *xy, size_t n, double *z);

void fb_terrain_free(fb_terrain *t);

#endif
