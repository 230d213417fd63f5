/*
 * PNG previews: a box-filtered downscale (at most 2048 pixels on the long side) accumulated strip by
 * strip, so the full image is never held, then normalised to its own min..max and written as 8-bit
 * grey PNG (atomically: temporary file, then rename).
 */
#ifndef FB_PREVIEW_H
#define FB_PREVIEW_H

#include "fb.h"

typedef struct fb_preview fb_preview;

fb_result fb_preview_create(int width, int height, int max_side, fb_preview **out);
void fb_preview_destroy(fb_preview **p);
/* Adds rows [y0, y0 + n) of one float channel (n * width values). */
void fb_preview_add_rows(fb_preview *p, int y0, int n, const float *rows);
fb_result fb_preview_write_png(const fb_preview *p, const char *path);

#endif
