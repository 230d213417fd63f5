/*
 * A C1 surface over the refined TIN, for `"interpolation": "smooth"`: the reduced Clough-Tocher
 * element (Clough and Tocher, 1965; in Bernstein-Bezier form after Farin, "Triangular
 * Bernstein-Bezier patches", 1986). Each triangle is split at its centroid into three cubic patches
 * that meet with C1 continuity; across the TIN's edges the surfaces of neighbouring triangles agree
 * in value (the edge's cubic comes from the two vertices alone) and in normal derivative (taken
 * linear along the edge, from the vertices' gradients), so the whole surface is C1. It interpolates
 * every vertex's height exactly, and reproduces every plane exactly.
 */
#ifndef FB_TERRAIN_SMOOTH_H
#define FB_TERRAIN_SMOOTH_H

#include "terrain.h"

/* Per-vertex gradients (dz/dx, dz/dy in world units): the slope at the vertex of a quadratic fitted by
 * least squares to its neighbours (weights 1 / distance^2), or where they are too few to fix one,
 * the area-weighted mean of its triangles' planes. Returns malloc'd 2 * nv doubles, or NULL when
 * out of memory. */
double *fb_smooth_gradients(const fb_terrain *t);

/* The cubic patches of one triangle (vertices a, b, c: positions p[3][2], heights z[3], gradients
 * g[3][2]), set up once per triangle. */
typedef struct fb_smooth_tri {
    double p[3][2], cen[2];
    double z[3], zc;     /* corners, centroid */
    double e[3][2];      /* e[i][0] near vertex i on edge i -> i+1, e[i][1] near i+1 */
    double pc[3], qc[3]; /* on the split edge from vertex i to the centroid: near i, near it */
    double m[3];         /* the interior point of micro-triangle (i, i+1, centroid) */
} fb_smooth_tri;

void fb_smooth_setup(fb_smooth_tri *s, const double p[3][2], const double z[3], const double g[3][2]);

/* The height at point (x, y) of the triangle (world units), and its gradient when grad is not NULL.
 * Points outside the triangle extrapolate the nearest patch. */
double fb_smooth_eval(const fb_smooth_tri *s, double x, double y, double grad[2]);

#endif
