/*
 * exrio: OpenEXR files through OpenEXRCore (the C library).
 *
 * The writer takes rows in order, as a generator produces them, and never holds the image:
 * rows are gathered into batches of whole chunks, each batch is packed and compressed by one of
 * `threads` workers, and the compressed chunks are written in order by whichever worker finishes
 * the batch that is next. The file is written under a temporary name in the target folder and
 * renamed into place by exrio_writer_finish, so a failed or interrupted bake leaves no partial file.
 */
#ifndef FB_EXRIO_H
#define FB_EXRIO_H

#include "fb.h"

#include <stdbool.h>

typedef enum exrio_type { EXRIO_UINT = 0, EXRIO_HALF = 1, EXRIO_FLOAT = 2 } exrio_type;
/* The compressions fractalbake writes. OpenEXRCore 3.1 (Debian 12) cannot write DWAA or DWAB, and
 * its B44 files end in a partial block row that the OpenEXR 3.1 C++ library decodes as garbage (a
 * 203 x 97 sky: its last row), so neither is offered (docs/usage.md, "Compression"). */
typedef enum exrio_compression { EXRIO_NONE = 0, EXRIO_ZIP = 1, EXRIO_PIZ = 2 } exrio_compression;
#define EXRIO_COMPRESSION_NAMES "zip|piz|none" /* as the scenes' compression keys take them */

/* "none", "zip", "piz" -> enum; -1 when unknown. */
int exrio_compression_parse(const char *s);
const char *exrio_compression_name(exrio_compression c);
const char *exrio_type_name(exrio_type t);

#define EXRIO_MAX_PARTS 16
/* The longest side of an image the reader opens. */
#define EXRIO_MAX_DIM (1 << 20)

typedef struct exrio_channel {
    const char *name; /* "layer.channel" */
    exrio_type type;  /* stored type; rows are given as float for HALF/FLOAT, uint32 for UINT */
    int part;         /* the part it is stored in (multi-part files), 0.. nparts - 1 */
} exrio_channel;

/* The `envmap` attribute (OpenEXR's ImfEnvmap.h): what the image is on the sphere. NONE: a plane, no
 * attribute. The values are kernels/envmap.h's K_ENV_*. */
typedef enum exrio_envmap { EXRIO_ENVMAP_NONE = 0, EXRIO_ENVMAP_LATLONG = 1, EXRIO_ENVMAP_CUBE = 2 } exrio_envmap;

typedef struct exrio_attr {
    const char *name;
    const char *value; /* stored as an EXR string attribute */
} exrio_attr;

typedef struct exrio_writer_desc {
    const char *path;
    const char *what;  /* the output's role in messages ("output", "diff"...); NULL: "output" */
    int width, height; /* the data window's size */
    /* A region file: the data window starts at (x0, y0) of a display window of full_width x
     * full_height (0: the data window is the whole image). */
    int x0, y0, full_width, full_height;
    int row_stride; /* values per row in the planes given to exrio_writer_rows (0: width) */
    /* Multi-part files: nparts parts (0 or 1: one part named "fractalbake"), their names and
     * compressions (NULL: `compression` for every part); each channel says its part. Attributes go
     * to the first part. */
    int nparts;
    const char *const *part_names;
    const exrio_compression *part_compression;
    exrio_compression compression;
    const exrio_channel *channels;
    int nchannels;
    const exrio_attr *attrs;
    int nattrs;
    int threads;         /* compression workers; 0: one per core */
    int zip_level;       /* ZIP: the deflate level, 1 (fastest) to 12 (smallest); 0: EXRIO_ZIP_LEVEL */
    exrio_envmap envmap; /* set on every part as the `envmap` attribute (NONE: not written) */
} exrio_writer_desc;

/* The default deflate level of ZIP chunks (libdeflate's scale; chosen by measurement, bench/RESULTS.md). */
#define EXRIO_ZIP_LEVEL     1
#define EXRIO_ZIP_LEVEL_MAX 12

/* The memory of one compression thread's deflate state at `level` (0: EXRIO_ZIP_LEVEL; measured with
 * libdeflate 1.14: 0.2 MiB at level 1, 0.65 MiB at 2 to 9, 8.6 MiB at 10 to 12). */
uint64_t exrio_zip_state_bytes(int level);

typedef struct exrio_writer exrio_writer;

/* Takes the path's temporary file from the output transaction (output.h) and writes the header. */
fb_result exrio_writer_create(const exrio_writer_desc *desc, exrio_writer **out);

/* Appends rows [y0, y0 + nrows) of the data window (y0 counts from its top and must be the next row
 * not yet written). planes[c] points to nrows rows of channel c, row_stride values apart, of which
 * the first width are taken, 4 bytes each. The data is copied; the call may wait while
 * the compression queue is full. */
fb_result exrio_writer_rows(exrio_writer *w, int y0, int nrows, const void *const *planes);

/* Who keeps alive the rows the writer reads in place (exrio_writer_rows_held): retain(ctx) is called
 * once for each batch made of them before the call returns, and release(ctx) once for each when the
 * batch no longer reads them (encoded, or abandoned), from any thread. */
typedef struct exrio_hold {
    void (*retain)(void *ctx);
    void (*release)(void *ctx);
    void *ctx;
} exrio_hold;

/* The writer's batch: rows compressed together by one worker (a multiple of every chunk height). */
int exrio_writer_batch_rows(const exrio_writer *w);

/* As exrio_writer_rows, but rows that make whole batches (starting at a multiple of the batch rows
 * with nothing half-filled before them, and as many rows or up to the image's last) are not copied:
 * the workers read them in place, held through `hold` until encoded. The rest is copied. */
fb_result exrio_writer_rows_held(exrio_writer *w, int y0, int nrows, const void *const *planes, const exrio_hold *hold);

/* Waits for the last chunks and completes the temporary file, which the output transaction renames
 * into place with the run's other outputs. Frees the writer, whatever the result; on failure the
 * temporary file is removed. */
fb_result exrio_writer_finish(exrio_writer **w);

/* Abandons the file: the temporary file is removed, nothing is renamed. Null-safe. */
void exrio_writer_abort(exrio_writer **w);

/* ---- reading -------------------------------------------------------------------------------- */

typedef struct exrio_reader exrio_reader;

/* Scanline or tiled parts (tiled: the top level of a mip- or rip-map), one or several; "-" reads
 * standard input, whole, first (within --max-memory). Deep parts are refused. */
fb_result exrio_open(const char *path, exrio_reader **out);
void exrio_close(exrio_reader **r);

/* The data window's size and origin, and the display window's size (its origin must be 0, 0). */
int exrio_width(const exrio_reader *r);
int exrio_height(const exrio_reader *r);
void exrio_window(const exrio_reader *r, int *x0, int *y0, int *full_width, int *full_height);
int exrio_nchannels(const exrio_reader *r);
const char *exrio_channel_name(const exrio_reader *r, int c);
exrio_type exrio_channel_type(const exrio_reader *r, int c);
/* Index of the channel named `name`, or -1. */
int exrio_find_channel(const exrio_reader *r, const char *name);
const char *exrio_compression_of(const exrio_reader *r); /* of the first part */

/* Multi-part files appear as one list of channels, the parts' one after the other; every part must
 * have the same data and display windows. */
int exrio_nparts(const exrio_reader *r);
int exrio_channel_part(const exrio_reader *r, int c);
const char *exrio_part_name(const exrio_reader *r, int p);
const char *exrio_part_compression(const exrio_reader *r, int p);
/* "scanline", or "tiled W x H" with ", mip-mapped: the top level read" (or rip-mapped): tiled parts
 * are read at their full-resolution level. */
const char *exrio_part_storage(const exrio_reader *r, int p);

/* The value of a string attribute, or NULL. Valid until exrio_close. */
const char *exrio_attr_string(const exrio_reader *r, const char *name);

/* The first part's `envmap` attribute (EXRIO_ENVMAP_NONE where it has none or another value). */
exrio_envmap exrio_envmap_of(const exrio_reader *r);

/* Attribute i of exrio_attr_count: its name and type name. */
int exrio_attr_count(const exrio_reader *r);
void exrio_attr_at(const exrio_reader *r, int i, const char **name, const char **type);

/* The value of attribute i of exrio_attr_count as text (numbers in their shortest form, boxes as
 * "xmin,ymin,xmax,ymax", vectors and matrices comma-separated, a channel list by name and type,
 * enumerations by name; a preview or opaque data by its size). */
void exrio_attr_text(const exrio_reader *r, int i, char *out, size_t size);

/* Reads rows [y0, y0 + nrows) of the channels whose planes[c] is not NULL; UINT channels as
 * uint32, the others as float. */
fb_result exrio_read_rows(exrio_reader *r, int y0, int nrows, void *const *planes);

#endif
