/*
 * Plant instances of an ifs population: one point per plant (the condensation set C's image under a
 * composition of the maps w1..wN), placed on a height layer when the scene names one, written as
 * PLY or CSV with Houdini's instance attribute names for an engine or Houdini to scatter.
 */
#ifndef FB_IFS_INSTANCES_H
#define FB_IFS_INSTANCES_H

#include "gen.h"
#include "ifs.h"

#include <stddef.h>
#include <stdint.h>

/* At most this many plants are written (more: refused, naming the smallest size that fits). */
#define FB_IFS_MAX_PLANTS (1u << 20)

/* One plant of the population in the IFS's units: its base (the image of C's base, the origin),
 * its height (C's largest extent times the composed map's sqrt |det|) and its generation (how many
 * maps were composed: 0 for C itself). */
typedef struct fb_ifs_plant {
    double x, y, size;
    int generation;
} fb_ifs_plant;

/* The plants of the population whose height is at least min_size (IFS units) and whose base lies in
 * frame[] = xmin, xmax, ymin, ymax, in depth-first order of the words (w1 before w2, a word before
 * its extensions). cond_size: C's largest extent. *out is malloc'd (NULL when n is 0). */
fb_result fb_ifs_plants(const fb_ifs *maps, double cond_size, const double frame[4], double min_size,
                        fb_ifs_plant **out, size_t *n);

/* The largest extent of an IFS condensation set's attractor, from a deterministic chaos game of
 * the maps alone (hash-driven, doubles). */
double fb_ifs_cond_extent(const fb_ifs *cond, uint32_t seed);

/* Where instances go: the frame they come from (IFS units, as the image shows it), the image size,
 * and optionally a height layer (src's plane `plane`, from its native rows; NULL: the constant
 * height `height`) with the world extent it covers (world[]: xmin, xmax, ymin, ymax, y up; when
 * has_world is false the IFS frame is the world). up: 'y' (x east, y up, z south) or 'z' (x east,
 * y north, z up). Plants are left out where the surface is steeper than max_slope degrees, and
 * within avoid_distance (world units; 0: the four pixels around the base) of a pixel where the mask
 * (avoid's plane avoid_plane; NULL: none) is 0.5 or more. */
typedef struct fb_ifs_place {
    double frame[4];
    int width, height;
    const fb_gen *src;
    int plane;
    double constant;
    bool has_world;
    double world[4];
    char up;
    uint32_t seed;
    double max_slope;
    const fb_gen *avoid;
    int avoid_plane;
    double avoid_distance;
} fb_ifs_place;

/* Places the plants and writes them to path (.ply: binary little-endian, .csv: text with a header)
 * through the output transaction. *written: the plants written (those over a non-finite height
 * are left out and counted in *skipped, those on too steep a slope or near the mask in *avoided). */
fb_result fb_ifs_write_instances(const char *path, const fb_ifs_place *pl, const fb_ifs_plant *plants, size_t n,
                                 size_t *written, size_t *skipped, size_t *avoided);

#endif
