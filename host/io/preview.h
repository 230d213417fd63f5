/*
 * PNG previews: a box-filtered downscale (at most 2048 pixels on the long side) accumulated strip by
 * strip, so the full image is never held. One channel: normalised to its own min..max, 8-bit grey.
 * Three channels: linear RGB, clamped to [0, 1] and encoded with the sRGB curve. Written atomically.
 */
#ifndef FB_PREVIEW_H
#define FB_PREVIEW_H

#include "fb.h"

#include <stdbool.h>
#include <stdint.h>

typedef struct fb_preview fb_preview;

fb_result fb_preview_create(int width, int height, int max_side, int channels, fb_preview **out);
/* The same with one more channel after the 1 or 3: a coverage in [0, 1], used by the over composite. channels 2:
 * a grey or hillshade channel and a water mask in [0, 1] after it, drawn as water over the ground (an RGB PNG). */
fb_result fb_preview_create_alpha(int width, int height, int max_side, int channels, bool alpha, fb_preview **out);
void fb_preview_destroy(fb_preview **p);
/* One channel drawn as a hillshade instead of grey levels: the channel is a height in the units of
 * the plane, dx and dy world units per source pixel (x right, y up). */
void fb_preview_set_hillshade(fb_preview *p, double dx, double dy);
/* The rows given to fb_preview_add_rows are `stride` values apart (default: the width). */
void fb_preview_set_row_stride(fb_preview *p, int stride);
/* Source rows per preview row: calls of fb_preview_add_rows for bands that start at multiples of it
 * touch disjoint preview pixels (and may run at once). */
int fb_preview_scale(const fb_preview *p);
/* The colour is light with no coverage (a star field): the over composite adds it to what lies behind
 * (premultiplied colour with alpha 0) instead of covering it. */
void fb_preview_set_light(fb_preview *p);
/* Adds rows [y0, y0 + n) of the preview's 1 or 3 float channels, then its coverage if it has one
 * (n * width values each). */
void fb_preview_add_rows(fb_preview *p, int y0, int n, const float *const *rows);
fb_result fb_preview_write_png(const fb_preview *p, const char *path, const char *what);
/* Composites previews of the same size back to front (layers[0] at the back) with the "over"
 * operator and writes an RGB PNG. Per layer: 3 channels are colour (premultiplied when the preview
 * has a coverage), 1 channel a hillshade (tinted) or grey levels of its own range; the coverage is
 * the alpha, 1 without one, 0 for light (fb_preview_set_light). */
fb_result fb_preview_write_over(const fb_preview *const *layers, int n, const char *path);

/* A contact sheet: each preview a tile of its own (colour, grey or hillshade, as fb_preview_write_png
 * draws it alone) under its label, in a grid of about as many columns as rows; an RGB PNG. */
fb_result fb_preview_write_sheet(const fb_preview *const *tiles, const char *const *labels, int n, const char *path);

/* Linear v in [0, 1] (clamped) as an 8-bit sRGB value (IEC 61966-2-1's curve). */
uint8_t fb_srgb8(double v);

/* Writes 8-bit RGB pixels (row by row) as a PNG, through the output transaction (output.h); `what`
 * names the output in messages ("plot", "diff picture"). */
fb_result fb_png_write_rgb(const char *path, const char *what, int width, int height, const uint8_t *rgb);

#endif
