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

/* Whether n is in the table; when not, the nearest entries below and above it in msg. */
static bool size_in(const int *t, int nt, int n, const char *what, const char *engine, const char *takes, char *msg,
                    size_t size)
{
    for (int i = 0; i < nt; i++)
        if (t[i] == n) return true;
    int below = 0, above = 0;
    for (int i = 0; i < nt; i++) {
        if (t[i] < n) below = t[i];
        if (t[i] > n && !above) above = t[i];
    }
    char list[128] = "";
    for (int i = nt; i-- > 0;)
        snprintf(list + strlen(list), sizeof list - strlen(list), "%s%d", i < nt - 1 ? ", " : "", t[i]);
    char near[64];
    if (below && above)
        snprintf(near, sizeof near, "the nearest are %d and %d", below, above);
    else
        snprintf(near, sizeof near, "the nearest is %d", below ? below : above);
    snprintf(msg, size, "heightmap-engine %s takes %s of %s samples, and the %s %d is not one: %s", engine, takes, list,
             what, n, near);
    return false;
}

bool fb_heightmap_engine_check(fb_heightmap_engine e, int w, int h, fb_heightmap_format f, char *msg, size_t size)
{
    if (e == FB_ENGINE_UNREAL) {
        if (f != FB_HEIGHTMAP_PNG16) {
            snprintf(msg, size, "heightmap-engine unreal imports a 16-bit grey PNG: name the heightmap OUT.png");
            return false;
        }
        return size_in(k_unreal, 7, w, "width", "unreal", "landscapes", msg, size) &&
               size_in(k_unreal, 7, h, "height", "unreal", "landscapes", msg, size);
    }
    if (e == FB_ENGINE_UNITY) {
        if (f != FB_HEIGHTMAP_RAW16) {
            snprintf(msg, size, "heightmap-engine unity imports 16-bit RAW: name the heightmap OUT.r16 or OUT.raw");
            return false;
        }
        if (w != h) {
            snprintf(msg, size, "heightmap-engine unity takes a square heightmap, and this one is %d x %d", w, h);
            return false;
        }
        return size_in(k_unity, 8, w, "size", "unity", "square terrains", msg, size);
    }
    return true;
}

void fb_heightmap_sidecar_path(const char *path, char *out, size_t size)
{
    const char *dot = strrchr(path, '.'), *slash = strrchr(path, '/');
    size_t stem = dot && (!slash || dot > slash) ? (size_t)(dot - path) : strlen(path);
    snprintf(out, size, "%.*s.import.json", (int)stem, path);
}

/* The sidecar: the heightmap's range and the engine's import settings that reproduce it, in world
 * units taken as metres. Sample v of the 16-bit file stands for h = lo + v (hi - lo) / 65535; the
 * samples sit at the pixel centres, dx and dy apart. */
static fb_result write_sidecar(const fb_heightmap_desc *d)
{
    char path[1100], lo[40], hi[40], buf[2048];
    fb_heightmap_sidecar_path(d->path, path, sizeof path);
    const double *w = d->world, dx = (w[1] - w[0]) / d->width, dy = (w[3] - w[2]) / d->height, r = d->hi - d->lo;
    fb_format_shortest(d->lo, lo, sizeof lo);
    fb_format_shortest(d->hi, hi, sizeof hi);
    const char *file = strrchr(d->path, '/') ? strrchr(d->path, '/') + 1 : d->path;
    int n = snprintf(buf, sizeof buf,
                     "{\n  \"engine\": \"%s\",\n  \"heightmap\": \"%s\",\n  \"samples\": [%d, %d],\n"
                     "  \"height_range\": [%s, %s],\n  \"sample_spacing\": [%.17g, %.17g],\n",
                     d->engine == FB_ENGINE_UNREAL ? "unreal" : "unity", file, d->width, d->height, lo, hi, dx, dy);
    if (d->engine == FB_ENGINE_UNREAL) {
        double zs = 12800.0 * r / 65535, locz = 100 * d->lo + 32768 * zs / 128;
        n += snprintf(buf + n, sizeof buf - n,
                      "  \"unreal\": {\"location\": [%.17g, %.17g, %.17g], \"scale\": [%.17g, %.17g, %.17g]},\n"
                      "  \"height_of_sample\": \"(location.z + (v - 32768) * scale.z / 128) / 100\",\n"
                      "  \"note\": \"centimetres; X east, Y south (the image's rows), Z up\"\n}\n",
                      100 * (w[0] + dx / 2), -100 * (w[3] - dy / 2), locz, 100 * dx, 100 * dy, zs);
    } else {
        n += snprintf(buf + n, sizeof buf - n,
                      "  \"unity\": {\"depth\": 16, \"byte_order\": \"Windows\", \"resolution\": %d, "
                      "\"terrain_width\": %.17g, \"terrain_length\": %.17g, \"terrain_height\": %.17g, "
                      "\"position\": [%.17g, %.17g, %.17g]},\n"
                      "  \"height_of_sample\": \"position.y + v / 65535 * terrain_height\",\n"
                      "  \"note\": \"metres; the file's first row is the north edge (z largest)\"\n}\n",
                      d->width, (d->width - 1) * dx, (d->height - 1) * dy, r, w[0] + dx / 2, d->lo, w[2] + dy / 2);
    }
    FILE *f = NULL;
    fb_result rc = fb_output_fopen(path, "heightmap sidecar", (void **)&f);
    if (rc) return rc;
    bool bad = fwrite(buf, 1, (size_t)n, f) != (size_t)n;
    if (fclose(f) != 0) bad = true;
    return fb_output_done(path,
                          bad ? fb_fail(FB_ERR_IO, "%s: cannot write the sidecar: %s", path, strerror(errno)) : FB_OK);
}

static fb_result write_16(const fb_heightmap_desc *d, bool png)
{
    size_t n = (size_t)d->width * d->height;
    uint16_t *q = malloc(n * sizeof *q);
    if (!q) return fb_fail(FB_ERR_NOMEM, "out of memory for the heightmap");
    for (size_t i = 0; i < n; i++) q[i] = fb_heightmap_quantise(d->z[i], d->lo, d->hi);
    fb_result rc;
    if (png) {
        char lo[40], hi[40];
        fb_format_shortest(d->lo, lo, sizeof lo);
        fb_format_shortest(d->hi, hi, sizeof hi);
        const char *kv[3][2] = {{"fractalbake/height-min", lo},
                                {"fractalbake/height-max", hi},
                                {"Description", "heights: height-min at 0, height-max at 65535, linear between"}};
        rc = fb_png_write(d->path, "heightmap", d->width, d->height, 1, 16, q, (const char *const(*)[2])kv, 3);
    } else {
        FILE *f = NULL;
        rc = fb_output_fopen(d->path, "heightmap", (void **)&f);
        if (!rc) {
            bool bad = false;
            uint8_t *row = malloc((size_t)d->width * 2);
            if (!row) rc = fb_fail(FB_ERR_NOMEM, "out of memory for the heightmap");
            for (int y = 0; y < d->height && !rc && !bad; y++) { /* little-endian, whatever this machine is */
                for (int x = 0; x < d->width; x++) {
                    uint16_t v = q[(size_t)y * d->width + x];
                    row[2 * x] = (uint8_t)v, row[2 * x + 1] = (uint8_t)(v >> 8);
                }
                bad = fwrite(row, 2, (size_t)d->width, f) != (size_t)d->width;
            }
            free(row);
            if (fclose(f) != 0) bad = true;
            if (bad && !rc) rc = fb_fail(FB_ERR_IO, "%s: cannot write the heightmap: %s", d->path, strerror(errno));
            rc = fb_output_done(d->path, rc);
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
    if (f == FB_HEIGHTMAP_GEOTIFF) return write_geotiff(d);
    char msg[256];
    if (!fb_heightmap_engine_check(d->engine, d->width, d->height, f, msg, sizeof msg))
        return fb_fail(FB_ERR_INPUT, "%s: %s", d->path, msg);
    fb_result rc = write_16(d, f == FB_HEIGHTMAP_PNG16);
    return rc || d->engine == FB_ENGINE_NONE ? rc : write_sidecar(d);
}
