/*
 * Hull edges in the refinement (terrain.c). A barycentre never lies on the hull, so without help a
 * hull edge keeps its input length for ever: the triangles along it become slivers ever thinner
 * towards the edge (rarely chosen, for their area is small), the points inserted next to the edge
 * are displaced at the scale of that long edge (|p - x|^(2H) of its far ends), and the pixels along
 * the edge are interpolated over it: spikes and pits all along the image's edge. So, as in Ruppert's
 * refinement (J. Ruppert, "A Delaunay refinement algorithm for quality 2-dimensional mesh
 * generation", 1995), a barycentre that encroaches upon a hull edge (lies inside its diametral
 * circle) is not inserted: the edge's midpoint is, and no hull triangle becomes a sliver.
 *
 * The midpoint's height is universal kriging (kriging with a linear drift) from the vertices of
 * the edge triangle's neighbourhood under the fBm variogram (sigma^2 / 2) |p - q|^(2H) (A. G.
 * Journel and Ch. J. Huijbregts, "Mining Geostatistics", 1978): the weights favour the near
 * vertices over the far ends of the edge, and reproduce planes, as the barycentre's mean does. Its
 * displacement's variance is a third of the kriging variance, as the paper's rule is a third of the
 * barycentre's: (1/9) sum_k (|p - x_k|^(2H) sigma^2 - var_abc) = (1/3) Var(z_p - z_abc) when var_abc
 * is the triangle's expected value. With additions, the residual is kriged with the same weights.
 */
#ifndef FB_TERRAIN_HULL_H
#define FB_TERRAIN_HULL_H

#include "delaunay.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define FB_HULL_KRIGE_MAX 20 /* vertices a midpoint's height is kriged from, at most */

/* The finite triangle tr, its finite neighbours and theirs (at most 10), into list; returns how many. */
size_t fb_terrain_neighbourhood(const fb_dt *d, uint32_t tr, uint32_t list[16]);

/* The hull edge that point p encroaches upon (strictly inside its diametral circle), among the hull
 * edges of tr's neighbourhood: the longest, as its triangle in *owner and the index of its opposite
 * corner; -1 when none. */
int fb_terrain_encroached(const fb_dt *d, uint32_t tr, const double *p, uint32_t *owner);

/* A point m exactly on hull edge a -> b near its middle: the rounded midpoint, or one within an ULP
 * of it in x and y that lies on the edge. A point off the edge would be trouble either way: a hair
 * inside, it leaves the edge whole beside a sliver; a hair outside, it sees the many nearly
 * collinear vertices of an edge split before and joins all of them in a fan of flat triangles,
 * whose slopes the smooth interpolation takes from differences of 1e-13. Axis-parallel edges always
 * have their midpoint; a slanted one may have none after a few splits, and then is not split
 * (false). False too when m falls within 1e-6 of the edge's length from a vertex of the
 * neighbourhood of the edge's triangle `owner`. */
bool fb_terrain_hull_midpoint(const fb_dt *d, uint32_t owner, const double *a, const double *b, double m[2]);

/* Universal kriging weights for point p from the distinct vertices of owner's neighbourhood. */
typedef struct fb_hull_weights {
    uint32_t v[FB_HULL_KRIGE_MAX];
    double w[FB_HULL_KRIGE_MAX];
    int n;
    double kvar; /* the kriging variance in units of sigma^2 / 2 */
} fb_hull_weights;

/* False when the system is singular (the vertices do not fix a plane). */
bool fb_terrain_hull_krige(const fb_dt *d, uint32_t owner, const double *p, double H, fb_hull_weights *out);

#endif
