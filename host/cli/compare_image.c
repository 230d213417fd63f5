/* compare's images (compare_int.h): an EXR read in blocks of rows, or a PNG held whole. */
#include "compare_int.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static bool has_png_signature(const char *path)
{
    static const uint8_t sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    uint8_t b[8];
    FILE *f = fopen(path, "rb");
    if (!f) return false;
    bool png = fread(b, 1, 8, f) == 8 && !memcmp(b, sig, 8);
    fclose(f);
    return png;
}

fb_result image_open(const char *path, image *im)
{
    memset(im, 0, sizeof *im);
    im->path = path;
    if (has_png_signature(path)) {
        im->is_png = true;
        return fb_png_read(path, &im->png);
    }
    return exrio_open(path, &im->exr);
}

void image_close(image *im)
{
    exrio_close(&im->exr);
    fb_png_fini(&im->png);
}

int image_width(const image *im)
{
    return im->is_png ? im->png.width : exrio_width(im->exr);
}

int image_height(const image *im)
{
    return im->is_png ? im->png.height : exrio_height(im->exr);
}

void image_window(const image *im, int w[4])
{
    if (im->is_png)
        w[0] = w[1] = 0, w[2] = im->png.width, w[3] = im->png.height;
    else
        exrio_window(im->exr, &w[0], &w[1], &w[2], &w[3]);
}

int image_nchannels(const image *im)
{
    return im->is_png ? im->png.channels : exrio_nchannels(im->exr);
}

const char *image_channel(const image *im, int c)
{
    return im->is_png ? im->png.names[c] : exrio_channel_name(im->exr, c);
}

bool image_uint(const image *im, int c)
{
    return !im->is_png && exrio_channel_type(im->exr, c) == EXRIO_UINT;
}

int image_find(const image *im, const char *name)
{
    for (int c = 0; c < image_nchannels(im); c++)
        if (!strcmp(image_channel(im, c), name)) return c;
    return -1;
}

fb_result image_read_rows(image *im, int y0, int n, void *const *planes)
{
    if (!im->is_png) return exrio_read_rows(im->exr, y0, n, planes);
    size_t w = (size_t)im->png.width;
    for (int c = 0; c < im->png.channels; c++)
        if (planes[c]) memcpy(planes[c], im->png.plane[c] + (size_t)y0 * w, (size_t)n * w * sizeof(float));
    return FB_OK;
}
