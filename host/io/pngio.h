/*
 * PNG files: reading any PNG as float channels (for `compare`), and writing 8- or 16-bit grey or RGB
 * images (previews, plots, heightmaps), through the output transaction (output.h). libpng's messages
 * go into the one error line, never to stderr.
 */
#ifndef FB_PNGIO_H
#define FB_PNGIO_H

#include "fb.h"

#include <stdint.h>

/* A decoded PNG: 1 to 4 channels named Y, Y A, R G B or R G B A, each a plane of width * height
 * floats, the stored value divided by the largest one of the bit depth (so 0..1, no gamma
 * applied). */
typedef struct fb_png {
    int width, height, channels, depth; /* depth: 1, 2, 4, 8 or 16 bits per sample, as stored */
    const char *names[4];
    float *plane[4];
} fb_png;

/* Reads the PNG at path. Bad input (not a PNG, truncated, too large for --max-memory) is
 * FB_ERR_INPUT with a message naming the file. */
fb_result fb_png_read(const char *path, fb_png *out);
void fb_png_fini(fb_png *png);

/* Writes a PNG of width x height pixels of 1 (grey) or 3 (RGB) channels at 8 or 16 bits: pix holds
 * the samples row by row (bytes, or uint16_t in this machine's order), with tEXt chunks key=value
 * (nkv pairs, may be 0). Through the output transaction (output.h); `what` names it in messages. */
fb_result fb_png_write(const char *path, const char *what, int width, int height, int channels, int bits,
                       const void *pix, const char *const (*kv)[2], int nkv);

/* The same as PNG bytes in memory (8 bits, 1 or 3 channels): *out (malloc'd) and *size. */
fb_result fb_png_encode(int width, int height, int channels, const uint8_t *pix, uint8_t **out, size_t *size);

#endif
