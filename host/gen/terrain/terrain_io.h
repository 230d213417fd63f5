/*
 * Terrain input and output: survey points from XYZ / CSV text or sampled from a height-field EXR,
 * centres of influence from CSV, and the refined mesh as binary PLY or OBJ. Every reader reports a
 * bad line as "FILE:LINE: what was wrong".
 */
#ifndef FB_TERRAIN_IO_H
#define FB_TERRAIN_IO_H

#include "terrain.h"

#include <stddef.h>

#define FB_TERRAIN_MAX_POINTS 50000000ull
/* The largest |coordinate| accepted (as for inline points): products of four coordinates, as the
 * exact predicates and the variances form them, stay far inside double's range. */
#define FB_TERRAIN_MAX_COORD 1e15

/* x y z or x,y,z per line; # starts a comment; the first line may be a header. *xyz is malloc'd
 * (3 doubles per point). At least one point, all finite. */
fb_result fb_terrain_read_points(const char *path, double **xyz, size_t *n);

/* "IN.exr" or "IN.exr:layer.channel": every `step`-th pixel in x and y (the last row and column
 * included), as points (column, height - 1 - row, value): pixel units, y up. Without a channel,
 * the file must have one channel, or exactly one whose name is Y or ends in .Y. */
fb_result fb_terrain_read_heightfield(const char *spec, int step, double **xyz, size_t *n);

/* x,y,D[,sigma] per line (sigma may be empty: estimated from the data); D in (2, 3). */
fb_result fb_terrain_read_centers(const char *path, fb_terrain_center **out, int *n);

/* Writes the finite triangles and all vertices to `path` through the output transaction (output.h:
 * renamed into place with the run's other outputs). Each vertex carries its unit normal (the
 * area-weighted mean of its triangles', pointing up) and texture coordinates u, v: its place in the
 * image's frame `bounds` (xmin, xmax, ymin, ymax; v = 0 at the bottom). The extension picks the
 * format: .ply (binary little endian: x, y, z as double, nx, ny, nz, u, v as float, then faces as
 * uchar-counted int lists) or .obj (v, vn and vt lines, faces v/vt/vn). */
fb_result fb_terrain_write_mesh(const fb_terrain *t, const double bounds[4], const char *path);

/* True when the extension of `path` is .ply or .obj (case-insensitive). */
bool fb_terrain_mesh_format_ok(const char *path);

#endif
