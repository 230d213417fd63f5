#include "preview.h"

#include "output.h"
#include "pngio.h"

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
    int channels; /* 1 (grey or hillshade), 2 (the same and a water mask) or 3 (RGB), plus 1 when `alpha` */
    bool alpha;   /* the last channel is a coverage in [0, 1] (used by the over composite) */
    bool light;   /* colour without coverage, added in the over composite */
    double *sum;  /* channels values per preview pixel */
    uint32_t *count;
    double shade_dx, shade_dy; /* > 0: one channel drawn as a hillshade; world units per source pixel */
};

void fb_preview_set_row_stride(fb_preview *p, int stride)
{
    p->stride = stride;
}

int fb_preview_scale(const fb_preview *p)
{
    return p->scale;
}

void fb_preview_set_light(fb_preview *p)
{
    p->light = true;
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
    p->channels = (channels == 3 || channels == 2 ? channels : 1) + (alpha ? 1 : 0);
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

uint8_t fb_srgb8(double v)
{
    v = v < 0 ? 0 : v > 1 ? 1 : v;
    v = v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1 / 2.4) - 0.055;
    return (uint8_t)lrint(255.0 * v);
}

static fb_result write_png(const char *path, const char *what, int pw, int ph, int nc, const uint8_t *img);

/* Linear ground colour `ground` with the water of pixel i (its mask's mean, s[1] / count) over it: a
 * deep blue, lit a little by the ground's shade `v` so that the valleys keep their relief. */
static void water_over(const fb_preview *p, size_t i, double v, double ground[3])
{
    static const double water[3] = {0.005, 0.04, 0.22};
    double w = p->count[i] ? p->sum[i * p->channels + 1] / p->count[i] : 0;
    w = w < 0 ? 0 : w > 1 ? 1 : w;
    for (int j = 0; j < 3; j++) ground[j] = (1 - w) * ground[j] + w * water[j] * (0.5 + 0.5 * v);
}

/* The preview as 8-bit samples, nc of them a pixel (the preview's 1 or 3; 3 with `rgb`: grey repeated; 3 with
 * water). */
static void render(const fb_preview *p, uint8_t *img, bool rgb)
{
    size_t n = (size_t)p->pw * p->ph;
    int nc = p->channels - (p->alpha ? 1 : 0), out = rgb || nc == 2 ? 3 : nc;
    double lo = INFINITY, hi = -INFINITY;
    if (nc == 1 && p->shade_dx <= 0)
        for (size_t i = 0; i < n; i++) {
            if (!p->count[i]) continue;
            double v = p->sum[i * p->channels] / p->count[i];
            lo = v < lo ? v : lo;
            hi = v > hi ? v : hi;
        }
    double range = hi > lo ? hi - lo : 1.0;
    for (int y = 0; y < p->ph; y++)
        for (int x = 0; x < p->pw; x++) {
            size_t i = (size_t)y * p->pw + x;
            if (nc == 3) {
                for (int c = 0; c < 3; c++)
                    img[i * 3 + c] = p->count[i] ? fb_srgb8(p->sum[i * p->channels + c] / p->count[i]) : 0;
                continue;
            }
            double v = p->shade_dx > 0 ? hillshade(p, x, y)
                       : p->count[i]   ? (p->sum[i * p->channels] / p->count[i] - lo) / range
                                       : 0;
            if (nc == 2) { /* the grey's own levels as light, so that the ground keeps its look */
                double c[3] = {v * v, v * v, v * v};
                water_over(p, i, v, c);
                for (int k = 0; k < 3; k++) img[i * 3 + k] = fb_srgb8(c[k]);
                continue;
            }
            uint8_t g = (uint8_t)lrint(255.0 * v);
            for (int c = 0; c < out; c++) img[i * out + c] = g;
        }
}

fb_result fb_preview_write_png(const fb_preview *p, const char *path, const char *what)
{
    size_t n = (size_t)p->pw * p->ph;
    int nc = p->channels - (p->alpha ? 1 : 0);
    nc = nc == 2 ? 3 : nc;
    uint8_t *img = malloc(n * nc);
    if (!img) return fb_fail(FB_ERR_NOMEM, "out of memory");
    render(p, img, false);
    fb_result rc = write_png(path, what, p->pw, p->ph, nc, img);
    free(img);
    return rc;
}

/* A 5 x 7 pixel font for the contact sheet's labels: capitals (lower case is drawn as upper case),
 * digits, and the few other characters a label holds. Rows from the top, bit 4 the leftmost pixel. */
static const struct glyph {
    char c;
    uint8_t rows[7];
} k_font[] = {
    {'A', {14, 17, 17, 31, 17, 17, 17}}, {'B', {30, 17, 17, 30, 17, 17, 30}}, {'C', {14, 17, 16, 16, 16, 17, 14}},
    {'D', {30, 17, 17, 17, 17, 17, 30}}, {'E', {31, 16, 16, 30, 16, 16, 31}}, {'F', {31, 16, 16, 30, 16, 16, 16}},
    {'G', {14, 17, 16, 23, 17, 17, 15}}, {'H', {17, 17, 17, 31, 17, 17, 17}}, {'I', {14, 4, 4, 4, 4, 4, 14}},
    {'J', {7, 2, 2, 2, 2, 18, 12}},      {'K', {17, 18, 20, 24, 20, 18, 17}}, {'L', {16, 16, 16, 16, 16, 16, 31}},
    {'M', {17, 27, 21, 21, 17, 17, 17}}, {'N', {17, 17, 25, 21, 19, 17, 17}}, {'O', {14, 17, 17, 17, 17, 17, 14}},
    {'P', {30, 17, 17, 30, 16, 16, 16}}, {'Q', {14, 17, 17, 17, 21, 18, 13}}, {'R', {30, 17, 17, 30, 20, 18, 17}},
    {'S', {15, 16, 16, 14, 1, 1, 30}},   {'T', {31, 4, 4, 4, 4, 4, 4}},       {'U', {17, 17, 17, 17, 17, 17, 14}},
    {'V', {17, 17, 17, 17, 17, 10, 4}},  {'W', {17, 17, 17, 21, 21, 21, 10}}, {'X', {17, 17, 10, 4, 10, 17, 17}},
    {'Y', {17, 17, 10, 4, 4, 4, 4}},     {'Z', {31, 1, 2, 4, 8, 16, 31}},     {'0', {14, 17, 19, 21, 25, 17, 14}},
    {'1', {4, 12, 4, 4, 4, 4, 14}},      {'2', {14, 17, 1, 2, 4, 8, 31}},     {'3', {31, 2, 4, 2, 1, 17, 14}},
    {'4', {2, 6, 10, 18, 31, 2, 2}},     {'5', {31, 16, 30, 1, 1, 17, 14}},   {'6', {6, 8, 16, 30, 17, 17, 14}},
    {'7', {31, 1, 2, 4, 8, 8, 8}},       {'8', {14, 17, 17, 14, 17, 17, 14}}, {'9', {14, 17, 17, 15, 1, 2, 12}},
    {'_', {0, 0, 0, 0, 0, 0, 31}},       {'-', {0, 0, 0, 31, 0, 0, 0}},       {' ', {0, 0, 0, 0, 0, 0, 0}},
    {'(', {2, 4, 8, 8, 8, 4, 2}},        {')', {8, 4, 2, 2, 2, 4, 8}},        {'.', {0, 0, 0, 0, 0, 12, 12}},
    {'?', {14, 17, 1, 2, 4, 0, 4}},
};

static const struct glyph *glyph_of(char c)
{
    if (c >= 'a' && c <= 'z') c = (char)(c - 'a' + 'A');
    for (size_t i = 0; i < sizeof k_font / sizeof k_font[0]; i++)
        if (k_font[i].c == c) return &k_font[i];
    return glyph_of('?');
}

/* Draws text at (x0, y0) of an RGB image w pixels wide, each font pixel a scale x scale square. */
static void draw_text(uint8_t *rgb, int w, int h, int x0, int y0, int scale, const char *text, const uint8_t colour[3])
{
    for (int k = 0; text[k]; k++) {
        const struct glyph *g = glyph_of(text[k]);
        for (int r = 0; r < 7; r++)
            for (int c = 0; c < 5; c++) {
                if (!(g->rows[r] >> (4 - c) & 1)) continue;
                for (int dy = 0; dy < scale; dy++)
                    for (int dx = 0; dx < scale; dx++) {
                        int x = x0 + (k * 6 + c) * scale + dx, y = y0 + r * scale + dy;
                        if (x >= 0 && x < w && y >= 0 && y < h) memcpy(rgb + ((size_t)y * w + x) * 3, colour, 3);
                    }
            }
    }
}

fb_result fb_preview_write_sheet(const fb_preview *const *tiles, const char *const *labels, int n, const char *path)
{
    const int scale = 2, band = 7 * scale + 8, gap = 8;
    int cols = 1;
    while (cols * cols < n) cols++;
    int rows = (n + cols - 1) / cols, tw = 0, th = 0;
    for (int k = 0; k < n; k++) {
        tw = tiles[k]->pw > tw ? tiles[k]->pw : tw;
        th = tiles[k]->ph > th ? tiles[k]->ph : th;
    }
    int w = gap + cols * (tw + gap), h = gap + rows * (band + th + gap);
    uint8_t *sheet = malloc((size_t)w * h * 3), *tile = malloc((size_t)tw * th * 3);
    if (!sheet || !tile) {
        free(sheet), free(tile);
        return fb_fail(FB_ERR_NOMEM, "out of memory for the preview sheet");
    }
    memset(sheet, 24, (size_t)w * h * 3);
    static const uint8_t ink[3] = {235, 235, 225};
    for (int k = 0; k < n; k++) {
        int x0 = gap + (k % cols) * (tw + gap), y0 = gap + (k / cols) * (band + th + gap);
        draw_text(sheet, w, h, x0, y0 + 3, scale, labels[k], ink);
        render(tiles[k], tile, true);
        for (int y = 0; y < tiles[k]->ph; y++)
            memcpy(sheet + ((size_t)(y0 + band + y) * w + x0) * 3, tile + (size_t)y * tiles[k]->pw * 3,
                   (size_t)tiles[k]->pw * 3);
    }
    fb_result rc = write_png(path, "preview", w, h, 3, sheet);
    free(sheet);
    free(tile);
    return rc;
}

static fb_result write_png(const char *path, const char *what, int pw, int ph, int nc, const uint8_t *img)
{
    return fb_png_write(path, what, pw, ph, nc, 8, img, NULL, 0);
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
                double a = p->light ? 0.0 : p->alpha ? s[p->channels - 1] * inv : 1.0;
                a = a < 0 ? 0 : a > 1 ? 1 : a;
                double c[3];
                if (p->channels - (p->alpha ? 1 : 0) == 3) {
                    /* colour layers with a coverage hold premultiplied colour; opaque ones plain colour */
                    for (int j = 0; j < 3; j++) c[j] = s[j] * inv;
                } else {
                    double v =
                        p->shade_dx > 0 ? hillshade(p, x, y) : (s[0] * inv - lohi[k][0]) / (lohi[k][1] - lohi[k][0]);
                    for (int j = 0; j < 3; j++) c[j] = p->shade_dx > 0 ? earth[j] * v : v;
                    if (p->channels - (p->alpha ? 1 : 0) == 2) water_over(p, i, v, c);
                    for (int j = 0; j < 3; j++) c[j] *= a;
                }
                for (int j = 0; j < 3; j++) out[j] = c[j] + (1 - a) * out[j];
            }
            for (int j = 0; j < 3; j++) img[i * 3 + j] = fb_srgb8(out[j]);
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
