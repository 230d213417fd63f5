/*
 * Incremental Delaunay triangulation in the plane (Bowyer-Watson cavities over exact predicates).
 *
 * The triangulation is closed by an infinite vertex: every hull edge (a, b) has a "ghost" triangle
 * (a, b, DT_INF), so every triangle has three neighbours and points outside the hull are inserted
 * like any other. Triangles are counter-clockwise; neighbour i lies across the edge opposite
 * vertex i. A point is in conflict with a finite triangle when it lies strictly inside its
 * circumcircle, and with a ghost (a, b, inf) when it lies strictly beyond the hull edge a-b, or on
 * the open segment a-b itself; the conflicting triangles form a star-shaped cavity that the new
 * vertex retriangulates.
 *
 * Batch construction sorts the points spatially (BRIO rounds, Hilbert order within a round) and
 * walks from the previous insertion; single insertions locate by a visibility walk from a hint.
 * Everything is sequential and deterministic: the same points give the same triangles, in the
 * same slots.
 */
#ifndef FB_DELAUNAY_H
#define FB_DELAUNAY_H

#include "fb.h"

#include <stddef.h>
#include <stdint.h>

#define DT_INF  UINT32_MAX /* the infinite vertex */
#define DT_NONE UINT32_MAX

typedef struct fb_dt {
    double *xy;  /* 2 per vertex */
    uint32_t nv; /* vertices stored (duplicates are not stored) */
    uint32_t capv;
    uint32_t *vt; /* a triangle incident to each vertex */
    uint32_t *tv; /* 3 vertices per triangle slot (counter-clockwise) */
    uint32_t *tn; /* 3 neighbours per triangle slot: tn[3t+i] is across the edge opposite tv[3t+i] */
    uint32_t nt;  /* triangle slots in use (a cavity's slots are reused; none is ever freed) */
    uint32_t capt;
    uint32_t nfinite; /* live finite triangles */
    uint32_t nghost;  /* live ghost triangles (= hull edges) */
    uint32_t last;    /* a live triangle: the walk's default start */
    /* scratch for insertions */
    uint32_t *stack, *cavity, *bnd; /* bnd: 3 per boundary edge (u, w, outer triangle) */
    size_t cap_scratch;
    uint32_t stamp;    /* the current insertion's mark (the marks live after tn's 3 * capt words) */
    uint32_t *newt_of; /* per vertex (and one for DT_INF): the new triangle starting there */
    uint64_t walk_steps;
    uint64_t duplicates; /* points not inserted because an equal point exists */
} fb_dt;

/* The triangle slot's vertices and neighbours. */
static inline int fb_dt_is_ghost(const fb_dt *d, uint32_t t)
{
    const uint32_t *v = d->tv + 3 * (size_t)t;
    return v[0] == DT_INF || v[1] == DT_INF || v[2] == DT_INF;
}

/* Builds the triangulation of n points (xy[2i], xy[2i+1]), all finite. Vertex i of the result is
 * input point perm_out[i] (perm_out may be NULL; it has n entries, of which d->nv are used: points
 * equal to an earlier one are left out and counted in d->duplicates). Fails (FB_ERR_INPUT) with a
 * message naming `who` when fewer than three distinct points exist or all are collinear. */
fb_result fb_dt_build(fb_dt *d, const double *xy, size_t n, uint32_t *perm_out, const char *who);

/* Inserts one point; *vertex gets its index, or the index of an equal existing vertex (then
 * returns 1 instead of 0). `hint` is a triangle to start the walk from (DT_NONE: the last one).
 * Returns -1 when out of memory. */
int fb_dt_insert(fb_dt *d, double x, double y, uint32_t hint, uint32_t *vertex);

/* The live triangle containing (x, y) (a finite one when the point is in the hull, on an edge or a
 * vertex included; a ghost when it is outside), walking from `hint` (DT_NONE: the last). */
uint32_t fb_dt_locate(fb_dt *d, const double *p, uint32_t hint);

/* The exact oracle: counts finite triangles that are not counter-clockwise, edges whose opposite
 * vertex lies strictly inside the circumcircle, hull corners that turn the wrong way, and broken
 * adjacency. 0 for a valid Delaunay triangulation. The counts go to the optional outputs. */
typedef struct fb_dt_check_report {
    uint64_t orientation, empty_circle, hull_convexity, adjacency;
    uint32_t triangles, hull; /* live finite triangles and hull edges */
} fb_dt_check_report;
uint64_t fb_dt_check(const fb_dt *d, fb_dt_check_report *report);

void fb_dt_free(fb_dt *d);

#endif
