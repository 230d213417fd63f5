#include "preview.h"

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
    int scale;         /* source pixels per preview pixel, per axis */
    int pw, ph;
    int channels;
    double *sum; /* channels values per preview pixel */
    uint32_t *count;
    double shade_dx, shade_dy; /* > 0: one channel drawn as a hillshade; world units per source pixel */
};

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
    return p->count[i] ? p->sum[i] / p->count[i] : NAN;
}

/* Lambertian shading under a light from the north-west, 45 degrees up (the cartographers'
 * convention), from central differences on the preview grid. */
static uint8_t hillshade(const fb_preview *p, int x, int y)
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
    return (uint8_t)lrint(255.0 * (v < 0 ? 0 : v));
}

fb_result fb_preview_create(int width, int height, int max_side, int channels, fb_preview **out)
{
    fb_preview *p = calloc(1, sizeof *p);
    if (!p) return fb_fail(FB_ERR_NOMEM, "out of memory");
    int longest = width > height ? width : height;
    p->width = width;
    p->height = height;
    p->scale = (longest + max_side - 1) / max_side;
    if (p->scale < 1) p->scale = 1;
    p->pw = (width + p->scale - 1) / p->scale;
    p->ph = (height + p->scale - 1) / p->scale;
    p->channels = channels == 3 ? 3 : 1;
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
            size_t at = base + x / p->scale, src = (size_t)r * p->width + x;
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

fb_result fb_preview_write_png(const fb_preview *p, const char *path)
{
    size_t n = (size_t)p->pw * p->ph;
    int nc = p->channels;
    uint8_t *volatile img = malloc(n * nc); /* volatile: survives libpng's longjmp */
    if (!img) return fb_fail(FB_ERR_NOMEM, "out of memory");
    if (nc == 3) {
        for (size_t i = 0; i < n; i++)
            for (int c = 0; c < 3; c++) img[i * 3 + c] = p->count[i] ? srgb8(p->sum[i * 3 + c] / p->count[i]) : 0;
    } else if (p->shade_dx > 0) {
        for (int y = 0; y < p->ph; y++)
            for (int x = 0; x < p->pw; x++) img[(size_t)y * p->pw + x] = hillshade(p, x, y);
    } else {
        double lo = INFINITY, hi = -INFINITY;
        for (size_t i = 0; i < n; i++) {
            if (!p->count[i]) continue;
            double v = p->sum[i] / p->count[i];
            lo = v < lo ? v : lo;
            hi = v > hi ? v : hi;
        }
        double range = hi > lo ? hi - lo : 1.0;
        for (size_t i = 0; i < n; i++)
            img[i] = p->count[i] ? (uint8_t)lrint(255.0 * (p->sum[i] / p->count[i] - lo) / range) : 0;
    }

    char tmp[4200];
    fb_temp_path(path, tmp, sizeof tmp);
    FILE *f = fopen(tmp, "wb");
    if (!f) {
        free((void *)img);
        return fb_fail(FB_ERR_IO, "%s: cannot create preview: %s", path, strerror(errno));
    }
    fb_result rc = FB_OK;
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    if (!png || !info) {
        rc = fb_fail(FB_ERR_NOMEM, "out of memory writing %s", path);
    } else if (setjmp(png_jmpbuf(png))) {
        rc = fb_fail(FB_ERR_IO, "%s: cannot write preview", path);
    } else {
        png_init_io(png, f);
        png_set_IHDR(png, info, (png_uint_32)p->pw, (png_uint_32)p->ph, 8,
                     nc == 3 ? PNG_COLOR_TYPE_RGB : PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE,
                     PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
        png_write_info(png, info);
        for (int y = 0; y < p->ph; y++) png_write_row(png, (uint8_t *)img + (size_t)y * p->pw * nc);
        png_write_end(png, NULL);
    }
    png_destroy_write_struct(png ? &png : NULL, info ? &info : NULL);
    if (fclose(f) != 0 && !rc) rc = fb_fail(FB_ERR_IO, "%s: cannot write preview: %s", path, strerror(errno));
    if (!rc && rename(tmp, path) != 0) rc = fb_fail(FB_ERR_IO, "%s: cannot move preview into place", path);
    if (rc) unlink(tmp);
    free((void *)img);
    return rc;
}
