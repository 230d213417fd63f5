#include "preview.h"

#include "output.h"

#include <png.h>

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

struct fb_preview {
    int width, height; /* source */
    int stride;        /* values per source row given to fb_preview_add_rows */
    int scale;         /* source pixels per preview pixel, per axis */
    int pw, ph;
    int channels; /* 1 (grey or hillshade) or 3 (RGB), plus 1 when `alpha` */
    bool alpha;   /* the last channel is a coverage in [0, 1] (used by the over composite) */
    double *sum;  /* channels values per preview pixel */
    uint32_t *count;
    double shade_dx, shade_dy; /* > 0: one channel drawn as a hillshade; world units per source pixel */
};

void fb_preview_set_row_stride(fb_preview *p, int stride)
{
    p->stride = stride;
}

void fb_preview_set_hillshade(fb_preview *p, double dx, double dy)
{
    p->shade_dx = dx;
    p->shade_dy = dy;
}

/* The mean at preview pixel (x, y), the coordinates clamped to the image; NaN where nothing landed. */
static double at_clamped(const fb_preview *p, int x, int y)
{
    x = x < 0 ? 0 : x >= p->pw ? p->pw - 1 : x;
    y = y < 0 ? 0 : y >= p->ph ? p->ph - 1 : y;
    size_t i = (size_t)y * p->pw + x;
    return p->count[i] ? p->sum[i * p->channels] / p->count[i] : NAN;
}

/* Lambertian shading under a light from the north-west, 45 degrees up (the cartographers'
 * convention), from central differences on the preview grid. */
static double hillshade(const fb_preview *p, int x, int y)
{
    double c = at_clamped(p, x, y);
    if (!isfinite(c)) return 0;
    double l = at_clamped(p, x - 1, y), r = at_clamped(p, x + 1, y);
    double u = at_clamped(p, x, y - 1), d = at_clamped(p, x, y + 1);
    l = isfinite(l) ? l : c, r = isfinite(r) ? r : c, u = isfinite(u) ? u : c, d = isfinite(d) ? d : c;
    double gx = (r - l) / (2 * p->shade_dx * p->scale), gy = (u - d) / (2 * p->shade_dy * p->scale); /* y up */
    double nx = -gx, ny = -gy, nz = 1, len = sqrt(nx * nx + ny * ny + nz * nz);
    const double lx = -0.5, ly = 0.5, lz = 0.70710678118654752; /* unit: from the north-west, 45 deg */
    double v = (nx * lx + ny * ly + nz * lz) / len;
    return v < 0 ? 0 : v;
}

fb_result fb_preview_create(int width, int height, int max_side, int channels, fb_preview **out)
{
    return fb_preview_create_alpha(width, height, max_side, channels, false, out);
}

fb_result fb_preview_create_alpha(int width, int height, int max_side, int channels, bool alpha, fb_preview **out)
{
    fb_preview *p = calloc(1, sizeof *p);
    if (!p) return fb_fail(FB_ERR_NOMEM, "out of memory");
    int longest = width > height ? width : height;
    p->width = width;
    p->height = height;
    p->stride = width;
    p->scale = (longest + max_side - 1) / max_side;
    if (p->scale < 1) p->scale = 1;
    p->pw = (width + p->scale - 1) / p->scale;
    p->ph = (height + p->scale - 1) / p->scale;
    p->channels = (channels == 3 ? 3 : 1) + (alpha ? 1 : 0);
    p->alpha = alpha;
    p->sum = calloc((size_t)p->pw * p->ph * p->channels, sizeof *p->sum);
    p->count = calloc((size_t)p->pw * p->ph, sizeof *p->count);
    if (!p->sum || !p->count) {
        fb_preview_destroy(&p);
        return fb_fail(FB_ERR_NOMEM, "out of memory for the preview");
    }
    *out = p;
    return FB_OK;
}

void fb_preview_destroy(fb_preview **pp)
{
    if (!pp || !*pp) return;
    free((*pp)->sum);
    free((*pp)->count);
    free(*pp);
    *pp = NULL;
}

void fb_preview_add_rows(fb_preview *p, int y0, int n, const float *const *rows)
{
    for (int r = 0; r < n; r++) {
        size_t base = (size_t)((y0 + r) / p->scale) * p->pw;
        for (int x = 0; x < p->width; x++) {
            size_t at = base + x / p->scale, src = (size_t)r * p->stride + x;
            bool finite = true;
            for (int c = 0; c < p->channels; c++) finite = finite && isfinite(rows[c][src]);
            if (!finite) continue;
            for (int c = 0; c < p->channels; c++) p->sum[at * p->channels + c] += rows[c][src];
            p->count[at]++;
        }
    }
}

static uint8_t srgb8(double v)
{
    v = v < 0 ? 0 : v > 1 ? 1 : v;
    v = v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1 / 2.4) - 0.055;
    return (uint8_t)lrint(255.0 * v);
}

static fb_result write_png(const char *path, const char *what, int pw, int ph, int nc, const uint8_t *img);

fb_result fb_preview_write_png(const fb_preview *p, const char *path, const char *what)
{
    size_t n = (size_t)p->pw * p->ph;
    int nc = p->channels - (p->alpha ? 1 : 0);
    uint8_t *volatile img = malloc(n * nc); /* volatile: survives libpng's longjmp */
    if (!img) return fb_fail(FB_ERR_NOMEM, "out of memory");
    if (nc == 3) {
        for (size_t i = 0; i < n; i++)
            for (int c = 0; c < 3; c++)
                img[i * 3 + c] = p->count[i] ? srgb8(p->sum[i * p->channels + c] / p->count[i]) : 0;
    } else if (p->shade_dx > 0) {
        for (int y = 0; y < p->ph; y++)
            for (int x = 0; x < p->pw; x++) img[(size_t)y * p->pw + x] = (uint8_t)lrint(255.0 * hillshade(p, x, y));
    } else {
        double lo = INFINITY, hi = -INFINITY;
        for (size_t i = 0; i < n; i++) {
            if (!p->count[i]) continue;
            double v = p->sum[i * p->channels] / p->count[i];
            lo = v < lo ? v : lo;
            hi = v > hi ? v : hi;
        }
        double range = hi > lo ? hi - lo : 1.0;
        for (size_t i = 0; i < n; i++)
            img[i] = p->count[i] ? (uint8_t)lrint(255.0 * (p->sum[i * p->channels] / p->count[i] - lo) / range) : 0;
    }
    fb_result rc = write_png(path, what, p->pw, p->ph, nc, img);
    free((void *)img);
    return rc;
}

static fb_result write_png(const char *path, const char *what, int pw, int ph, int nc, const uint8_t *img)
{
    FILE *f = NULL;
    fb_result rc = fb_output_fopen(path, what, (void **)&f);
    if (rc) return rc;
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    if (!png || !info) {
        rc = fb_fail(FB_ERR_NOMEM, "out of memory writing %s", path);
    } else if (setjmp(png_jmpbuf(png))) {
        rc = fb_fail(FB_ERR_IO, "%s: cannot write %s", path, what);
    } else {
        png_init_io(png, f);
        png_set_IHDR(png, info, (png_uint_32)pw, (png_uint_32)ph, 8, nc == 3 ? PNG_COLOR_TYPE_RGB : PNG_COLOR_TYPE_GRAY,
                     PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
        png_write_info(png, info);
        for (int y = 0; y < ph; y++) png_write_row(png, img + (size_t)y * pw * nc);
        png_write_end(png, NULL);
    }
    png_destroy_write_struct(png ? &png : NULL, info ? &info : NULL);
    if (fclose(f) != 0 && !rc) rc = fb_fail(FB_ERR_IO, "%s: cannot write %s: %s", path, what, strerror(errno));
    return fb_output_done(path, rc); /* renamed with the run's other outputs (output.h) */
}

/* The range of channel 0 over the pixels that received a value (for grey levels). */
static void grey_range(const fb_preview *p, double *lo, double *hi)
{
    *lo = INFINITY, *hi = -INFINITY;
    for (size_t i = 0; i < (size_t)p->pw * p->ph; i++) {
        if (!p->count[i]) continue;
        double v = p->sum[i * p->channels] / p->count[i];
        *lo = v < *lo ? v : *lo;
        *hi = v > *hi ? v : *hi;
    }
    if (!(*hi > *lo)) *hi = *lo + 1.0;
}

fb_result fb_preview_write_over(const fb_preview *const *layers, int n, const char *path)
{
    const fb_preview *p0 = layers[0];
    size_t npix = (size_t)p0->pw * p0->ph;
    uint8_t *img = malloc(npix * 3);
    double(*lohi)[2] = calloc((size_t)n, sizeof *lohi);
    if (!img || !lohi) {
        free(img);
        free(lohi);
        return fb_fail(FB_ERR_NOMEM, "out of memory");
    }
    for (int k = 0; k < n; k++) grey_range(layers[k], &lohi[k][0], &lohi[k][1]);
    static const double earth[3] = {0.45, 0.41, 0.35}; /* the hillshade's tint, linear */
    for (int y = 0; y < p0->ph; y++)
        for (int x = 0; x < p0->pw; x++) {
            size_t i = (size_t)y * p0->pw + x;
            double out[3] = {0, 0, 0};
            for (int k = 0; k < n; k++) {
                const fb_preview *p = layers[k];
                if (!p->count[i]) continue;
                const double *s = p->sum + i * p->channels;
                double inv = 1.0 / p->count[i];
                double a = p->alpha ? s[p->channels - 1] * inv : 1.0;
                a = a < 0 ? 0 : a > 1 ? 1 : a;
                double c[3];
                if (p->channels - (p->alpha ? 1 : 0) == 3) {
                    /* colour layers with a coverage hold premultiplied colour; opaque ones plain colour */
                    for (int j = 0; j < 3; j++) c[j] = s[j] * inv;
                } else {
                    double v =
                        p->shade_dx > 0 ? hillshade(p, x, y) : (s[0] * inv - lohi[k][0]) / (lohi[k][1] - lohi[k][0]);
                    for (int j = 0; j < 3; j++) c[j] = a * (p->shade_dx > 0 ? earth[j] * v : v);
                }
                for (int j = 0; j < 3; j++) out[j] = c[j] + (1 - a) * out[j];
            }
            for (int j = 0; j < 3; j++) img[i * 3 + j] = srgb8(out[j]);
        }
    fb_result rc = write_png(path, "preview", p0->pw, p0->ph, 3, img);
    free(img);
    free(lohi);
    return rc;
}

fb_result fb_png_write_rgb(const char *path, const char *what, int width, int height, const uint8_t *rgb)
{
    return write_png(path, what, width, height, 3, rgb);
}
