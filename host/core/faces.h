/*
 * Engine face sets of a cube environment map (render --cube-faces PATTERN): the six faces of the
 * bake as six files named and turned the way a game engine's six-sided skybox takes them, written
 * as the bake's strips complete each face, through the run's output transaction.
 *
 * PATTERN holds one of {unity} (_front _back _left _right _up _down) or {source} (ft bk lf rt up dn,
 * the names Source and Unreal skybox sets use), and ends in .exr (every channel of the bake, as
 * stored) or .png (the first colour layer's R, G, B, sRGB-encoded, for LDR previews). Each face is
 * the view from the centre of the cube: forward is +Z (longitude 0), left +X, up +Y (OpenEXR's
 * ImfEnvmap.h convention, which the cube bake follows); the side faces upright, the up face with
 * forward along its bottom edge, the down face with forward along its top edge (docs/sky.md).
 */
#ifndef FB_FACES_H
#define FB_FACES_H

#include "exrio.h"
#include "fb.h"

typedef struct fb_faces fb_faces;

/* The six paths of PATTERN (names[k]: PATH_MAX bytes each, in the order the faces are written), or
 * FB_ERR_USAGE with one line naming what is wrong with it. */
#define FB_FACES_PATH 1024
fb_result fb_faces_paths(const char *pattern, char names[6][FB_FACES_PATH]);

typedef struct fb_faces_desc {
    const char *pattern;
    int n; /* the face size: the bake is n x 6n */
    const exrio_channel *channels;
    int nchannels;
    int rgb; /* the first of three colour channels (R, G, B) for a PNG set; -1: none */
    exrio_compression compression;
    int threads, zip_level;
} fb_faces_desc;

/* Checks the pattern (a PNG set needs rgb >= 0) and reserves the six outputs. */
fb_result fb_faces_create(const fb_faces_desc *d, fb_faces **out);

/* Rows [y0, y0 + n) of the cube, planes[c] holding channel c, `stride` values a row; a face whose
 * last row arrives is written. */
fb_result fb_faces_rows(fb_faces *f, int y0, int n, const void *const *planes, int stride);

/* The bytes fb_faces_create will hold: one face of every channel. */
uint64_t fb_faces_bytes(int n, int nchannels);

/* Null-safe; a set not complete is discarded by the transaction. */
void fb_faces_destroy(fb_faces **f);

#endif
