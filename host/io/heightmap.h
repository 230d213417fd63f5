/*
 * Height fields for the tools terrain users have: a 16-bit grey PNG or a 16-bit RAW (what game
 * engines import: Unity's and Unreal's .r16 are little-endian rows, top row first), normalised
 * from a height range to 0..65535, or a float GeoTIFF of the heights themselves with the
 * geotransform (and the projected CRS) of the world frame, for GIS tools.
 */
#ifndef FB_HEIGHTMAP_H
#define FB_HEIGHTMAP_H

#include "fb.h"

#include <stdbool.h>

typedef enum fb_heightmap_format { FB_HEIGHTMAP_PNG16, FB_HEIGHTMAP_RAW16, FB_HEIGHTMAP_GEOTIFF } fb_heightmap_format;

/* The format a file name asks for (.png, .r16 or .raw, .tif or .tiff; case-insensitive); false when
 * none. */
bool fb_heightmap_format_of(const char *path, fb_heightmap_format *out);

typedef struct fb_heightmap_desc {
    const char *path;
    int width, height;
    const float *z;      /* width x height heights, top row first */
    double lo, hi;       /* the 16-bit formats: lo is stored as 0 and hi as 65535 (lo < hi) */
    const double *world; /* GeoTIFF: the image's frame xmin, xmax, ymin, ymax (x right, y up) */
    int epsg;            /* GeoTIFF: a projected CRS's EPSG code, or 0 for none stated */
} fb_heightmap_desc;

/* Writes the height field through the output transaction (output.h). 16 bits: each height h is
 * stored as round((h - lo) / (hi - lo) * 65535), clamped, so it reads back within half a step
 * ((hi - lo) / 131070); the PNG also holds lo and hi as text chunks "fractalbake/height-min" and
 * "fractalbake/height-max". */
fb_result fb_heightmap_write(const fb_heightmap_desc *d);

/* The 16-bit value of height h. */
static inline uint16_t fb_heightmap_quantise(double h, double lo, double hi)
{
    double q = (h - lo) / (hi - lo) * 65535.0 + 0.5;
    return q <= 0 ? 0 : q >= 65535 ? 65535 : (uint16_t)q;
}

#endif
