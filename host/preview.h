/*
 * PNG previews: a box-filtered downscale (at most 2048 pixels on the long side) accumulated strip by
 * strip, so the full image is never held. One channel: normalised to its own min..max, 8-bit grey.
 * Three channels: linear RGB, clamped to [0, 1] and encoded with the sRGB curve. Written atomically.
 */
#ifndef FB_PREVIEW_H
#define FB_PREVIEW_H

#include "fb.h"

typedef struct fb_preview fb_preview;

fb_result fb_preview_create(int width, int height, int max_side, int channels, fb_preview **out);
void fb_preview_destroy(fb_preview **p);
/* One channel drawn as a hillshade instead of grey levels: the channel is a height in the units of
 * the plane, dx and dy world units per source pixel (x right, y up). */
void fb_preview_set_hillshade(fb_preview *p, double dx, double dy);
/* Adds rows [y0, y0 + n) of the preview's 1 or 3 float channels (n * width values each). */
void fb_preview_add_rows(fb_preview *p, int y0, int n, const float *const *rows);
fb_result fb_preview_write_png(const fb_preview *p, const char *path);

#endif
