/*
 * Sinks: what a bake feeds its pieces to. A piece is rows [y0, y0 + n) of every stored channel of
 * every layer; the bake's producer (a GPU, the host's pool, op layers on the host) fills pieces in
 * order into a bounded ring, and one consumer hands each to every sink in turn: the finite check,
 * the heightmaps, the preview, the EXR writer, the cube's face sets. A sink knows nothing of who made
 * the rows (FFmpeg's filter links, OpenImageIO's ImageOutput): begin, then each piece, then end.
 */
#ifndef FB_SINK_H
#define FB_SINK_H

#include "fb.h"

/* A piece of the bake's window. */
typedef struct fb_piece {
    int index;                 /* 0, 1, ... in the order the sinks receive them */
    int y0, n;                 /* image rows [y0, y0 + n) */
    int x0, width;             /* the window's columns: planes[c] points at column x0 of row y0 */
    int top;                   /* the window's first row (y0 - top: the piece's row in a region file) */
    int stride;                /* values from one row to the next (the image's width) */
    const void *const *planes; /* every layer's stored channels, in scene order, 4 bytes a value */
    void *owner;               /* what keeps the planes alive (fb_piece_retain) */
} fb_piece;

/* A sink that reads a piece's planes after its rows hook returns (the EXR writer's workers) holds
 * the piece: retain once before returning, release once when done, from any thread. The ring slot
 * is refilled only when every hold is released. */
void fb_piece_retain(void *owner);
void fb_piece_release(void *owner);

typedef struct fb_sink {
    const char *name; /* "EXR writer", for messages */
    void *self;
    /* Before the first piece (opens what it writes); NULL: nothing to do. */
    fb_result (*begin)(void *self);
    /* The part of a piece that may run on several threads at once: rows [y0, y0 + n) of piece p, bands
     * of one piece disjoint, each starting at a multiple of band_rows from the window's top (band_rows
     * > 0; 0: no band hook). */
    int band_rows;
    fb_result (*band)(void *self, const fb_piece *p, int y0, int n);
    /* Each piece in order, after every band of it (NULL: none). */
    fb_result (*rows)(void *self, const fb_piece *p);
    /* After the last piece: completes what it writes (through the output transaction). NULL: nothing. */
    fb_result (*end)(void *self);
    /* Frees it, abandoning what end did not complete. Null-safe on self. */
    void (*destroy)(void *self);
} fb_sink;

#endif
