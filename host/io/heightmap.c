#include "heightmap.h"

#include "output.h"
#include "pngio.h"

#include <geotiff/geotiff.h>
#include <geotiff/geovalues.h>
#include <geotiff/xtiffio.h>

#include <dlfcn.h>
#include <errno.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

bool fb_heightmap_format_of(const char *path, fb_heightmap_format *out)
{
    const char *dot = strrchr(path, '.'), *slash = strrchr(path, '/');
    if (!dot || (slash && dot < slash)) return false;
    if (!strcasecmp(dot, ".png"))
        *out = FB_HEIGHTMAP_PNG16;
    else if (!strcasecmp(dot, ".r16") || !strcasecmp(dot, ".raw"))
        *out = FB_HEIGHTMAP_RAW16;
    else if (!strcasecmp(dot, ".tif") || !strcasecmp(dot, ".tiff"))
        *out = FB_HEIGHTMAP_GEOTIFF;
    else
        return false;
    return true;
}

/* ---- engine presets ------------------------------------------------------------------------------ */

static const int k_unreal[] = {127, 253, 505, 1009, 2017, 4033, 8129};
static const int k_unity[] = {33, 65, 129, 257, 513, 1025, 2049, 4097};

fb_heightmap_engine fb_heightmap_engine_parse(const char *name)
{
    return !name                     ? FB_ENGINE_NONE
           : !strcmp(name, "unreal") ? FB_ENGINE_UNREAL
           : !strcmp(name, "unity")  ? FB_ENGINE_UNITY
                                     : FB_ENGINE_NONE;
}

/* The table as text, largest first: "8129, 4033, ..." */
static void table_list(const int *t, int nt, char *out, size_t size)
{
    out[0] = 0;
    for (int i = nt; i-- > 0;) snprintf(out + strlen(out), size - strlen(out), "%s%d", i < nt - 1 ? ", " : "", t[i]);
}

/* The entries of the table (ascending) nearest to x strictly below and above it (0: none). */
static void table_nearest(const int *t, int nt, double x, int *below, int *above)
{
    *below = *above = 0;
    for (int i = 0; i < nt; i++) {
        if (t[i] < x) *below = t[i];
        if (t[i] > x && !*above) *above = t[i];
    }
}

/* Whether n is in the table; when not, the nearest entries below and above it in msg. */
static bool size_in(const int *t, int nt, int n, const char *what, const char *engine, const char *takes, char *msg,
                    size_t size)
{
    for (int i = 0; i < nt; i++)
        if (t[i] == n) return true;
    int below, above;
    table_nearest(t, nt, n, &below, &above);
    char list[128], near[64];
    table_list(t, nt, list, sizeof list);
    if (below && above)
        snprintf(near, sizeof near, "the nearest are %d and %d", below, above);
    else
        snprintf(near, sizeof near, "the nearest is %d", below ? below : above);
    snprintf(msg, size, "heightmap-engine %s takes %s of %s samples, and the %s %d is not one: %s", engine, takes, list,
             what, n, near);
    return false;
}

/* The file an engine imports; false with msg when f is not it. */
static bool format_check(fb_heightmap_engine e, fb_heightmap_format f, char *msg, size_t size)
{
    if (e == FB_ENGINE_UNREAL && f != FB_HEIGHTMAP_PNG16) {
        snprintf(msg, size, "heightmap-engine unreal imports a 16-bit grey PNG: name the heightmap OUT.png");
        return false;
    }
    if (e == FB_ENGINE_UNITY && f != FB_HEIGHTMAP_RAW16) {
        snprintf(msg, size, "heightmap-engine unity imports 16-bit RAW: name the heightmap OUT.r16 or OUT.raw");
        return false;
    }
    return true;
}

bool fb_heightmap_engine_check(fb_heightmap_engine e, int w, int h, fb_heightmap_format f, char *msg, size_t size)
{
    if (!format_check(e, f, msg, size)) return false;
    if (e == FB_ENGINE_UNREAL)
        return size_in(k_unreal, 7, w, "width", "unreal", "landscapes", msg, size) &&
               size_in(k_unreal, 7, h, "height", "unreal", "landscapes", msg, size);
    if (e == FB_ENGINE_UNITY) {
        if (w != h) {
            snprintf(msg, size, "heightmap-engine unity takes a square heightmap, and this one is %d x %d", w, h);
            return false;
        }
        return size_in(k_unity, 8, w, "size", "unity", "square terrains", msg, size);
    }
    return true;
}

/* One side of a tiling: n samples in `count` tiles sharing their edges, each t samples with
 * count (t - 1) + 1 = n; t from the engine's table when it has one (t, nt), else any t >= 2. When not,
 * msg names the nearest whole sides that split. */
static bool tiles_side(const int *t, int nt, const char *engine, int n, int count, const char *what, char *msg,
                       size_t size)
{
    double tile = (double)(n - 1) / count + 1;
    bool whole = (n - 1) % count == 0;
    for (int i = 0; i < nt && whole; i++)
        if (t[i] == (int)tile) return true;
    if (!nt && whole && tile >= 2) return true;
    int below = 0, above = 0;
    if (nt) {
        table_nearest(t, nt, tile, &below, &above);
    } else {
        below = (n - 1) / count + 1, above = below + 1;
        if (below < 2) below = 0;
    }
    char near[96] = "";
    if (below) snprintf(near, sizeof near, "%d (tiles of %d)", count * (below - 1) + 1, below);
    if (above)
        snprintf(near + strlen(near), sizeof near - strlen(near), "%s%d (tiles of %d)", below ? " and " : "",
                 count * (above - 1) + 1, above);
    const char *nearest = below && above ? "the nearest are" : "the nearest is";
    if (nt) {
        char list[128];
        table_list(t, nt, list, sizeof list);
        snprintf(msg, size,
                 "heightmap-engine %s takes tiles of %s samples, and %d tiles sharing their edges across the %s %d "
                 "would be %.6g samples: %s %s",
                 engine, list, count, what, n, tile, nearest, near);
    } else {
        snprintf(msg, size,
                 "%d tiles sharing their edges need a %s of %d (t - 1) + 1 samples for a whole t of 2 or more, and "
                 "%d is not one: %s %s",
                 count, what, count, n, nearest, near);
    }
    return false;
}

bool fb_heightmap_tiles_check(fb_heightmap_engine e, int w, int h, int cols, int rows, fb_heightmap_format f, char *msg,
                              size_t size)
{
    if (f == FB_HEIGHTMAP_GEOTIFF) {
        snprintf(msg, size, "tiles are 16-bit heightmaps: name the heightmap OUT.png or OUT.r16");
        return false;
    }
    if (!format_check(e, f, msg, size)) return false;
    const char *name = e == FB_ENGINE_UNREAL ? "unreal" : "unity";
    const int *t = e == FB_ENGINE_UNREAL ? k_unreal : e == FB_ENGINE_UNITY ? k_unity : NULL;
    int nt = e == FB_ENGINE_UNREAL ? 7 : e == FB_ENGINE_UNITY ? 8 : 0;
    if (!tiles_side(t, nt, name, w, cols, "width", msg, size) || !tiles_side(t, nt, name, h, rows, "height", msg, size))
        return false;
    int tw = (w - 1) / cols + 1, th = (h - 1) / rows + 1;
    if (e == FB_ENGINE_UNITY && tw != th) {
        snprintf(msg, size, "heightmap-engine unity takes square tiles, and %d x %d tiles of this image are %d x %d",
                 cols, rows, tw, th);
        return false;
    }
    return true;
}

/* The length of a path's stem: up to its extension's dot, or the whole path when it has none. */
static size_t path_stem(const char *path)
{
    const char *dot = strrchr(path, '.'), *slash = strrchr(path, '/');
    return dot && (!slash || dot > slash) ? (size_t)(dot - path) : strlen(path);
}

void fb_heightmap_tile_path(const char *path, fb_heightmap_engine e, int col, int row, int rows, char *out, size_t size)
{
    size_t stem = path_stem(path);
    if (e == FB_ENGINE_UNITY)
        snprintf(out, size, "%.*s_%d_%d%s", (int)stem, path, col, rows - 1 - row, path + stem);
    else
        snprintf(out, size, "%.*s_x%d_y%d%s", (int)stem, path, col, row, path + stem);
}

void fb_heightmap_sidecar_path(const char *path, char *out, size_t size)
{
    snprintf(out, size, "%.*s.import.json", (int)path_stem(path), path);
}

/* A growing text (the sidecar); a failed allocation is remembered and reported once. */
typedef struct text {
    char *p;
    size_t n, cap;
    bool bad;
} text;

__attribute__((format(printf, 2, 3))) static void add(text *t, const char *fmt, ...)
{
    for (int tries = 0; tries < 2 && !t->bad; tries++) {
        va_list ap;
        va_start(ap, fmt);
        int n = vsnprintf(t->p ? t->p + t->n : NULL, t->p ? t->cap - t->n : 0, fmt, ap);
        va_end(ap);
        if (n < 0) t->bad = true;
        if (t->bad || (t->p && (size_t)n < t->cap - t->n)) {
            t->n += t->bad ? 0 : (size_t)n;
            return;
        }
        size_t cap = (t->cap + (size_t)n + 1) * 2;
        char *p = realloc(t->p, cap);
        if (!p)
            t->bad = true;
        else
            t->p = p, t->cap = cap;
    }
}

/* s as a JSON string, quotes included: a file name may hold a quote, a backslash or a control
 * character, which JSON writes escaped. */
static void add_string(text *t, const char *s)
{
    add(t, "\"");
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\')
            add(t, "\\%c", c);
        else if (c < 0x20)
            add(t, "\\u%04x", c);
        else
            add(t, "%c", c);
    }
    add(t, "\"");
}

/* Where a piece of the image goes in the engine's import settings: Unreal's location (centimetres, X
 * east, Y south) of its top-left sample (x, y) (x right, y down from the image's top-left), or Unity's
 * position (metres, x east, z north) of its south-west sample, in column x and image row south_row. */
static void engine_place(text *t, const fb_heightmap_desc *d, int x, int y, int south_row)
{
    const double *w = d->world, dx = (w[1] - w[0]) / d->width, dy = (w[3] - w[2]) / d->height;
    if (d->engine == FB_ENGINE_UNREAL) {
        double zs = 12800.0 * (d->hi - d->lo) / 65535, locz = 100 * d->lo + 32768 * zs / 128;
        add(t, "\"location\": [%.17g, %.17g, %.17g]", 100 * (w[0] + dx / 2 + x * dx), -100 * (w[3] - dy / 2 - y * dy),
            locz);
    } else {
        add(t, "\"position\": [%.17g, %.17g, %.17g]", w[0] + dx / 2 + x * dx, d->lo,
            w[2] + dy / 2 + (d->height - 1 - south_row) * dy);
    }
}

/* The sidecar: the heightmap's range and the engine's import settings that reproduce it, in world
 * units taken as metres; with tiles, each tile's file and where it goes. Sample v of the 16-bit file
 * stands for h = lo + v (hi - lo) / 65535; the samples sit at the pixel centres, dx and dy apart. */
static fb_result write_sidecar(const fb_heightmap_desc *d)
{
    char path[1100], lo[40], hi[40], name[1100];
    fb_heightmap_sidecar_path(d->path, path, sizeof path);
    const double *w = d->world, dx = (w[1] - w[0]) / d->width, dy = (w[3] - w[2]) / d->height, r = d->hi - d->lo;
    int tw = d->cols ? (d->width - 1) / d->cols + 1 : d->width,
        th = d->rows ? (d->height - 1) / d->rows + 1 : d->height;
    fb_format_shortest(d->lo, lo, sizeof lo);
    fb_format_shortest(d->hi, hi, sizeof hi);
    const char *file = strrchr(d->path, '/') ? strrchr(d->path, '/') + 1 : d->path;
    text t = {0};
    add(&t, "{\n  \"engine\": \"%s\",\n", d->engine == FB_ENGINE_UNREAL ? "unreal" : "unity");
    if (!d->cols) {
        add(&t, "  \"heightmap\": ");
        add_string(&t, file);
        add(&t, ",\n");
    }
    add(&t, "  \"samples\": [%d, %d],\n  \"height_range\": [%s, %s],\n  \"sample_spacing\": [%.17g, %.17g],\n",
        d->width, d->height, lo, hi, dx, dy);
    if (d->engine == FB_ENGINE_UNREAL) {
        add(&t, "  \"unreal\": {");
        engine_place(&t, d, 0, 0, d->height - 1);
        add(&t, ", \"scale\": [%.17g, %.17g, %.17g]},\n", 100 * dx, 100 * dy, 12800.0 * r / 65535);
        add(&t, "  \"height_of_sample\": \"(location.z + (v - 32768) * scale.z / 128) / 100\",\n");
    } else {
        add(&t,
            "  \"unity\": {\"depth\": 16, \"byte_order\": \"Windows\", \"resolution\": %d, \"terrain_width\": %.17g, "
            "\"terrain_length\": %.17g, \"terrain_height\": %.17g, ",
            tw, (tw - 1) * dx, (th - 1) * dy, r);
        engine_place(&t, d, 0, 0, d->height - 1);
        if (d->cols) /* the Terrain Toolbox's whole grid */
            add(&t, ", \"tiles_x\": %d, \"tiles_z\": %d, \"total_width\": %.17g, \"total_length\": %.17g", d->cols,
                d->rows, (d->width - 1) * dx, (d->height - 1) * dy);
        add(&t, "},\n  \"height_of_sample\": \"position.y + v / 65535 * terrain_height\",\n");
    }
    if (d->cols) {
        add(&t, "  \"tiles\": {\"columns\": %d, \"rows\": %d, \"samples\": [%d, %d], \"files\": [", d->cols, d->rows,
            tw, th);
        for (int row = 0; row < d->rows; row++)
            for (int col = 0; col < d->cols; col++) {
                fb_heightmap_tile_path(file, d->engine, col, row, d->rows, name, sizeof name);
                int x = col * (tw - 1), y = row * (th - 1);
                add(&t, "%s\n    {\"file\": ", row || col ? "," : "");
                add_string(&t, name);
                add(&t, ", \"pixels\": [%d, %d], ", x, y);
                engine_place(&t, d, x, y, y + th - 1);
                add(&t, "}");
            }
        add(&t, "\n  ]},\n");
    }
    if (d->engine == FB_ENGINE_UNREAL)
        add(&t, "  \"note\": \"centimetres; X east, Y south (the image's rows), Z up%s\"\n}\n",
            d->cols ? "; tile _x0_y0 is the north-west one, x counts east and y south; neighbours share a row or "
                      "column of samples"
                    : "");
    else
        add(&t, "  \"note\": \"metres; the file's first row is the north edge (z largest)%s\"\n}\n",
            d->cols ? "; tile _0_0 is the south-west one, the first index counts east (x) and the second north (z); "
                      "neighbours share a row or column of samples"
                    : "");
    if (t.bad) {
        free(t.p);
        return fb_fail(FB_ERR_NOMEM, "out of memory for the heightmap sidecar");
    }
    FILE *f = NULL;
    fb_result rc = fb_output_fopen(path, "heightmap sidecar", (void **)&f);
    if (rc) {
        free(t.p);
        return rc;
    }
    bool bad = fwrite(t.p, 1, t.n, f) != t.n;
    if (fclose(f) != 0) bad = true;
    free(t.p);
    return fb_output_done(path,
                          bad ? fb_fail(FB_ERR_IO, "%s: cannot write the sidecar: %s", path, strerror(errno)) : FB_OK);
}

/* A w x h piece of the heights (rows `stride` floats apart) as a 16-bit PNG or RAW at path. */
static fb_result write_16(const char *path, const float *z, int w, int h, size_t stride, double lo, double hi, bool png)
{
    size_t n = (size_t)w * h;
    uint16_t *q = malloc(n * sizeof *q);
    if (!q) return fb_fail(FB_ERR_NOMEM, "out of memory for the heightmap");
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) q[(size_t)y * w + x] = fb_heightmap_quantise(z[y * stride + x], lo, hi);
    fb_result rc;
    if (png) {
        char slo[40], shi[40];
        fb_format_shortest(lo, slo, sizeof slo);
        fb_format_shortest(hi, shi, sizeof shi);
        const char *kv[3][2] = {{"fractalbake/height-min", slo},
                                {"fractalbake/height-max", shi},
                                {"Description", "heights: height-min at 0, height-max at 65535, linear between"}};
        rc = fb_png_write(path, "heightmap", w, h, 1, 16, q, (const char *const(*)[2])kv, 3);
    } else {
        FILE *f = NULL;
        rc = fb_output_fopen(path, "heightmap", (void **)&f);
        if (!rc) {
            bool bad = false;
            uint8_t *row = malloc((size_t)w * 2);
            if (!row) rc = fb_fail(FB_ERR_NOMEM, "out of memory for the heightmap");
            for (int y = 0; y < h && !rc && !bad; y++) { /* little-endian, whatever this machine is */
                for (int x = 0; x < w; x++) {
                    uint16_t v = q[(size_t)y * w + x];
                    row[2 * x] = (uint8_t)v, row[2 * x + 1] = (uint8_t)(v >> 8);
                }
                bad = fwrite(row, 2, (size_t)w, f) != (size_t)w;
            }
            free(row);
            if (fclose(f) != 0) bad = true;
            if (bad && !rc) rc = fb_fail(FB_ERR_IO, "%s: cannot write the heightmap: %s", path, strerror(errno));
            rc = fb_output_done(path, rc);
        }
    }
    free(q);
    return rc;
}

/* libtiff reports through handlers: the first error goes into the one error line. */
static _Thread_local char t_tiff_msg[256];

static void tiff_error(const char *module, const char *fmt, va_list ap)
{
    (void)module;
    if (!t_tiff_msg[0]) vsnprintf(t_tiff_msg, sizeof t_tiff_msg, fmt, ap);
}

static void tiff_warning(const char *module, const char *fmt, va_list ap)
{
    (void)module, (void)fmt, (void)ap;
}

/* libgeotiff and libtiff are loaded when a GeoTIFF is first written, not linked: they pull in some
 * 30 more libraries (PROJ, curl, GnuTLS, Kerberos...), about 10 ms at every start of the program,
 * and a split bake (render --task) starts it once per task. */
#define TIFF_API(X)                                                                                                    \
    X(TIFFSetErrorHandler);                                                                                            \
    X(TIFFSetWarningHandler);                                                                                          \
    X(TIFFSetField);                                                                                                   \
    X(TIFFMergeFieldInfo);                                                                                             \
    X(TIFFWriteScanline);                                                                                              \
    X(TIFFFlush);                                                                                                      \
    X(XTIFFFdOpen);                                                                                                    \
    X(XTIFFClose);                                                                                                     \
    X(GTIFNew);                                                                                                        \
    X(GTIFKeySet);                                                                                                     \
    X(GTIFWriteKeys);                                                                                                  \
    X(GTIFFree)
static struct {
#define X(f) __typeof__(&f) f
    TIFF_API(X);
#undef X
} g_tiff;
static char g_tiff_error[300];
static pthread_once_t g_tiff_once = PTHREAD_ONCE_INIT;

static void tiff_load(void)
{
    static const char *const names[] = {"libgeotiff.so.5", "libgeotiff.so"};
    void *h = NULL;
    for (size_t i = 0; i < sizeof names / sizeof names[0] && !h; i++) h = dlopen(names[i], RTLD_NOW | RTLD_LOCAL);
    if (!h) {
        snprintf(g_tiff_error, sizeof g_tiff_error, "cannot load libgeotiff (Debian: libgeotiff5): %s", dlerror());
        return;
    }
#define X(f)                                                                                                           \
    if (!(*(void **)&g_tiff.f = dlsym(h, #f)) && !g_tiff_error[0])                                                     \
    snprintf(g_tiff_error, sizeof g_tiff_error, "libgeotiff has no %s", #f)
    TIFF_API(X);
#undef X
}

static fb_result write_geotiff(const fb_heightmap_desc *d)
{
    pthread_once(&g_tiff_once, tiff_load);
    if (g_tiff_error[0]) return fb_fail(FB_ERR_IO, "%s: cannot write the GeoTIFF: %s", d->path, g_tiff_error);
    int fd = -1;
    fb_result rc = fb_output_open(d->path, "heightmap", &fd);
    if (rc) return rc;
    t_tiff_msg[0] = 0;
    TIFFErrorHandler old_e = g_tiff.TIFFSetErrorHandler(tiff_error), old_w = g_tiff.TIFFSetWarningHandler(tiff_warning);
    TIFF *tif = g_tiff.XTIFFFdOpen(fd, d->path, "w");
    GTIF *gt = tif ? g_tiff.GTIFNew(tif) : NULL;
    if (!tif || !gt) {
        rc = fb_fail(FB_ERR_IO, "%s: cannot write the GeoTIFF: %s", d->path, t_tiff_msg);
    } else {
        const int rows = 16;
        g_tiff.TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, (uint32_t)d->width);
        g_tiff.TIFFSetField(tif, TIFFTAG_IMAGELENGTH, (uint32_t)d->height);
        g_tiff.TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, 32);
        g_tiff.TIFFSetField(tif, TIFFTAG_SAMPLEFORMAT, SAMPLEFORMAT_IEEEFP);
        g_tiff.TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, 1);
        g_tiff.TIFFSetField(tif, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
        g_tiff.TIFFSetField(tif, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
        g_tiff.TIFFSetField(tif, TIFFTAG_COMPRESSION, COMPRESSION_ADOBE_DEFLATE);
        g_tiff.TIFFSetField(tif, TIFFTAG_PREDICTOR, PREDICTOR_FLOATINGPOINT);
        g_tiff.TIFFSetField(tif, TIFFTAG_ROWSPERSTRIP, (uint32_t)rows);
        g_tiff.TIFFSetField(tif, TIFFTAG_SOFTWARE, "fractalbake " FB_VERSION);
        /* libtiff does not know GDAL's tag: it is registered as GDAL registers it */
        static const TIFFFieldInfo nodata = {TIFFTAG_GDAL_NODATA, -1, -1, TIFF_ASCII,
                                             FIELD_CUSTOM,        1,  0,  "GDALNoDataValue"};
        if (d->nodata && g_tiff.TIFFMergeFieldInfo(tif, &nodata, 1) == 0)
            g_tiff.TIFFSetField(tif, TIFFTAG_GDAL_NODATA, "-3.4028234663852886e+38");
        /* the geotransform: pixel corner (0, 0) at (xmin, ymax), pixels (dx, dy) of the world apart */
        const double *w = d->world;
        double scale[3] = {(w[1] - w[0]) / d->width, (w[3] - w[2]) / d->height, 0};
        double tie[6] = {0, 0, 0, w[0], w[3], 0};
        g_tiff.TIFFSetField(tif, TIFFTAG_GEOPIXELSCALE, 3, scale);
        g_tiff.TIFFSetField(tif, TIFFTAG_GEOTIEPOINTS, 6, tie);
        g_tiff.GTIFKeySet(gt, GTModelTypeGeoKey, TYPE_SHORT, 1, ModelTypeProjected);
        g_tiff.GTIFKeySet(gt, GTRasterTypeGeoKey, TYPE_SHORT, 1, RasterPixelIsArea);
        g_tiff.GTIFKeySet(gt, ProjectedCSTypeGeoKey, TYPE_SHORT, 1, d->epsg > 0 ? d->epsg : KvUserDefined);
        if (d->epsg <= 0) g_tiff.GTIFKeySet(gt, GTCitationGeoKey, TYPE_ASCII, 0, "fractalbake terrain: CRS not stated");
        g_tiff.GTIFWriteKeys(gt);
        for (int y = 0; y < d->height && !rc; y++)
            if (g_tiff.TIFFWriteScanline(tif, (void *)(d->z + (size_t)y * d->width), (uint32_t)y, 0) < 0)
                rc = fb_fail(FB_ERR_IO, "%s: cannot write the GeoTIFF: %s", d->path, t_tiff_msg);
    }
    if (gt) g_tiff.GTIFFree(gt);
    if (tif) {
        g_tiff.TIFFFlush(tif);
        if (t_tiff_msg[0] && !rc) rc = fb_fail(FB_ERR_IO, "%s: cannot write the GeoTIFF: %s", d->path, t_tiff_msg);
        g_tiff.XTIFFClose(tif); /* closes fd */
    } else {
        close(fd);
    }
    g_tiff.TIFFSetErrorHandler(old_e);
    g_tiff.TIFFSetWarningHandler(old_w);
    return fb_output_done(d->path, rc);
}

fb_result fb_heightmap_write(const fb_heightmap_desc *d)
{
    fb_heightmap_format f;
    if (!fb_heightmap_format_of(d->path, &f))
        return fb_fail(FB_ERR_USAGE, "%s: a heightmap is .png, .r16 or .tif", d->path);
    char msg[512];
    if (d->cols ? !fb_heightmap_tiles_check(d->engine, d->width, d->height, d->cols, d->rows, f, msg, sizeof msg)
                : f != FB_HEIGHTMAP_GEOTIFF &&
                      !fb_heightmap_engine_check(d->engine, d->width, d->height, f, msg, sizeof msg))
        return fb_fail(FB_ERR_INPUT, "%s: %s", d->path, msg);
    if (f == FB_HEIGHTMAP_GEOTIFF) return write_geotiff(d);
    bool png = f == FB_HEIGHTMAP_PNG16;
    fb_result rc = FB_OK;
    if (!d->cols) {
        rc = write_16(d->path, d->z, d->width, d->height, (size_t)d->width, d->lo, d->hi, png);
    } else { /* every tile from the one range: neighbours store their shared samples alike */
        int tw = (d->width - 1) / d->cols + 1, th = (d->height - 1) / d->rows + 1;
        char tile[1100];
        for (int row = 0; row < d->rows && !rc; row++)
            for (int col = 0; col < d->cols && !rc; col++) {
                fb_heightmap_tile_path(d->path, d->engine, col, row, d->rows, tile, sizeof tile);
                const float *z = d->z + (size_t)row * (th - 1) * d->width + (size_t)col * (tw - 1);
                rc = write_16(tile, z, tw, th, (size_t)d->width, d->lo, d->hi, png);
            }
    }
    return rc || d->engine == FB_ENGINE_NONE ? rc : write_sidecar(d);
}
