#include "palette.h"

#include <math.h>
#include <string.h>

typedef struct named_palette {
    bool cosine;
    double v[12]; /* cosine coefficients */
    int nstops;
    double stops[6][4];
} named_palette;

/* In FB_PALETTE_NAMES order. Gradients for the deep-sky looks, cosines for nebular colour cycles. */
static const named_palette k_named[] = {
    /* night: black sky, deep blue, pale blue, white stars */
    {false,
     {0},
     5,
     {{0, 0.0, 0.0, 0.02},
      {0.35, 0.04, 0.07, 0.30},
      {0.7, 0.40, 0.52, 0.95},
      {0.9, 0.88, 0.9, 1.0},
      {1, 1.0, 0.97, 0.88}}},
    /* nebula: magenta, teal and gold cycling */
    {true, {0.5, 0.4, 0.55, 0.5, 0.4, 0.45, 1.0, 1.0, 1.0, 0.80, 0.90, 0.30}, 0, {{0}}},
    /* aurora: greens and violets */
    {true, {0.3, 0.5, 0.45, 0.3, 0.45, 0.4, 1.0, 1.0, 1.0, 0.55, 0.3, 0.65}, 0, {{0}}},
    /* ice */
    {false, {0}, 3, {{0, 0.0, 0.02, 0.05}, {0.5, 0.2, 0.6, 0.8}, {1, 0.9, 1.0, 1.0}}},
    /* ember */
    {false, {0}, 4, {{0, 0.02, 0.0, 0.0}, {0.4, 0.5, 0.1, 0.02}, {0.75, 1.0, 0.55, 0.1}, {1, 1.0, 0.95, 0.7}}},
    /* grey */
    {false, {0}, 2, {{0, 0, 0, 0}, {1, 1, 1, 1}}},
    /* foliage: bark brown through olive to leaf green and a light new-growth green */
    {false, {0}, 4, {{0, 0.16, 0.07, 0.02}, {0.35, 0.22, 0.25, 0.04}, {0.7, 0.06, 0.40, 0.05}, {1, 0.45, 0.85, 0.20}}},
    /* blossom: dark stems, green leaves, pink and white flowers */
    {false, {0}, 4, {{0, 0.10, 0.06, 0.03}, {0.4, 0.08, 0.35, 0.06}, {0.75, 0.95, 0.35, 0.55}, {1, 1.0, 0.92, 0.95}}},
};

static void cosine_at(const double *v, double t, float out[4])
{
    for (int ch = 0; ch < 3; ch++) {
        double x = v[ch] + v[3 + ch] * cos(2 * M_PI * (v[6 + ch] * t + v[9 + ch]));
        out[ch] = (float)(x > 0 ? x : 0); /* linear colour is never negative */
    }
    out[3] = 0;
}

static void stops_at(int n, const double (*s)[4], double t, float out[4])
{
    int k = 0;
    while (k + 1 < n && s[k + 1][0] < t) k++;
    if (k + 1 >= n || t <= s[0][0]) {
        const double *e = t <= s[0][0] ? s[0] : s[n - 1];
        for (int ch = 0; ch < 3; ch++) out[ch] = (float)e[1 + ch];
    } else {
        double f = (t - s[k][0]) / (s[k + 1][0] - s[k][0]);
        for (int ch = 0; ch < 3; ch++) out[ch] = (float)(s[k][1 + ch] + (s[k + 1][1 + ch] - s[k][1 + ch]) * f);
    }
    out[3] = 0;
}

void fb_palette_build(const fb_palette_spec *spec, float table[FB_PALETTE_ENTRIES][4])
{
    for (int i = 0; i < FB_PALETTE_ENTRIES; i++) {
        double t = (double)i / (FB_PALETTE_ENTRIES - 1);
        if (spec->has_cosine)
            cosine_at(spec->cosine, t, table[i]);
        else if (spec->nstops >= 2)
            stops_at(spec->nstops, (const double(*)[4])spec->stops, t, table[i]);
        else if (k_named[spec->named].cosine)
            cosine_at(k_named[spec->named].v, t, table[i]);
        else
            stops_at(k_named[spec->named].nstops, k_named[spec->named].stops, t, table[i]);
    }
}

void fb_relief_init(fb_relief *r, const fb_relief_spec *spec, double zlo, double zhi)
{
    fb_palette_build(&spec->palette, r->table);
    double az = spec->light[0] * (M_PI / 180), alt = spec->light[1] * (M_PI / 180);
    r->lx = sin(az) * cos(alt), r->ly = cos(az) * cos(alt), r->lz = sin(alt), r->ambient = spec->ambient;
    r->zlo = spec->range_set ? spec->range[0] : zlo, r->zhi = spec->range_set ? spec->range[1] : zhi;
    if (!(r->zhi > r->zlo)) r->zhi = r->zlo + 1;
}

double fb_relief_light(const fb_relief *r, double gx, double gy)
{
    double len = sqrt(gx * gx + gy * gy + 1), d = (-gx * r->lx - gy * r->ly + r->lz) / len;
    return r->ambient + (1 - r->ambient) * (d > 0 ? d : 0);
}

void fb_relief_colour(const fb_relief *r, double z, double gx, double gy, float rgb[3])
{
    double light = fb_relief_light(r, gx, gy);
    double t = (z - r->zlo) / (r->zhi - r->zlo) * (FB_PALETTE_ENTRIES - 1);
    t = t < 0 ? 0 : t > FB_PALETTE_ENTRIES - 1 ? FB_PALETTE_ENTRIES - 1 : t;
    int i = (int)t;
    int j = i + 1 < FB_PALETTE_ENTRIES ? i + 1 : i;
    double f = t - i;
    for (int c = 0; c < 3; c++) rgb[c] = (float)(light * (r->table[i][c] * (1 - f) + r->table[j][c] * f));
}
