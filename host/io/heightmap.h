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

/* Engine presets: the sizes and the file an engine's terrain importer takes, and a JSON sidecar
 * (OUT.import.json beside OUT.png / OUT.r16) with the import settings that reproduce the heights.
 * - unreal: a landscape whose width and height are each one of 8129, 4033, 2017, 1009, 505, 253, 127
 *   (Unreal Engine's recommended landscape sizes), a 16-bit grey PNG; Unreal reads sample v as
 *   (v - 32768) * Z scale / 128 centimetres above the landscape's location, so the sidecar gives the
 *   location (cm) and the X, Y, Z scale (cm per sample, and Z scale per 1/128 cm) for world units
 *   taken as metres.
 * - unity: a square of 2^n + 1 samples from 33 to 4097, 16-bit RAW little-endian ("Windows" byte
 *   order); Unity reads v as v / 65535 of the terrain's height above its position, so the sidecar
 *   gives the terrain width, length and height and its position. */
typedef enum fb_heightmap_engine { FB_ENGINE_NONE, FB_ENGINE_UNREAL, FB_ENGINE_UNITY } fb_heightmap_engine;
#define FB_HEIGHTMAP_ENGINES "unreal|unity"

/* The engine of a name in FB_HEIGHTMAP_ENGINES, or FB_ENGINE_NONE. */
fb_heightmap_engine fb_heightmap_engine_parse(const char *name);

/* Whether engine e takes a w x h heightmap in format f; when not, one line in msg (for the user: what
 * the engine takes, and the nearest valid sizes). */
bool fb_heightmap_engine_check(fb_heightmap_engine e, int w, int h, fb_heightmap_format f, char *msg, size_t size);

/* Tiles (--tiles NxM): the heightmap cut into cols x rows tiles of tw x th samples that share their
 * edge rows and columns, so the image is cols (tw - 1) + 1 by rows (th - 1) + 1 samples; every tile
 * stores the one range of the whole. At most FB_HEIGHTMAP_MAX_TILES a side. */
#define FB_HEIGHTMAP_MAX_TILES 16

/* Whether a w x h heightmap in format f splits into cols x rows such tiles, each of a size engine e
 * takes; when not, one line in msg naming the nearest whole sizes that do. */
bool fb_heightmap_tiles_check(fb_heightmap_engine e, int w, int h, int cols, int rows, fb_heightmap_format f, char *msg,
                              size_t size);

/* The file of the tile in column col (0: west, the image's left) and row row (0: north, the image's
 * top) of rows, named by the engine's convention: PATH's stem + "_x<col>_y<row>" (Unreal, and without
 * an engine: x east, y south, as Unreal's landscape importer reads them) or "_<col>_<rows-1-row>"
 * (Unity's Terrain Toolbox: the index along X, then along Z, which points north), then PATH's
 * extension. */
void fb_heightmap_tile_path(const char *path, fb_heightmap_engine e, int col, int row, int rows, char *out,
                            size_t size);

/* The sidecar's path for a heightmap's: its extension replaced by ".import.json" (out: size bytes). */
void fb_heightmap_sidecar_path(const char *path, char *out, size_t size);

/* The format a file name asks for (.png, .r16 or .raw, .tif or .tiff; case-insensitive); false when
 * none. */
bool fb_heightmap_format_of(const char *path, fb_heightmap_format *out);

typedef struct fb_heightmap_desc {
    const char *path;
    int width, height;
    const float *z;             /* width x height heights, top row first */
    double lo, hi;              /* the 16-bit formats: lo is stored as 0 and hi as 65535 (lo < hi) */
    const double *world;        /* GeoTIFF: the image's frame xmin, xmax, ymin, ymax (x right, y up) */
    int epsg;                   /* GeoTIFF: a projected CRS's EPSG code, or 0 for none stated */
    fb_heightmap_engine engine; /* FB_ENGINE_NONE, or the preset whose sidecar is written too */
    bool nodata;    /* GeoTIFF: heights equal to FB_HEIGHTMAP_NODATA are no data (outside a terrain's hull) */
    int cols, rows; /* 16 bits: the tiles (fb_heightmap_tile_path names them; path is never written); 0: one file */
} fb_heightmap_desc;

/* The GeoTIFF's NoData value (GDAL's GDAL_NODATA tag): the lowest float, written as "-3.4028234663852886e+38". */
#define FB_HEIGHTMAP_NODATA (-3.4028234663852886e+38f)

/* Writes the height field, or its tiles (and an engine's sidecar) through the output transaction (output.h). 16 bits:
 * each height h is stored as round((h - lo) / (hi - lo) * 65535), clamped, so it reads back within half a step
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
