/*
 * The star catalogue (catalog.h): star counts per magnitude as the real sky's, N(<m) growing as
 * 10^(slope m) with about 4,970 stars brighter than magnitude 6 (the Hipparcos catalogue; ESA 1997),
 * an optional Milky Way band, and colours of blackbodies at temperatures drawn by spectral class.
 */
#include "catalog.h"

#include "kernels/envmap.h"
#include "kernels/noise.h"
#include "kernels/stars.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A counter-based stream of uniforms for one cell: the k-th draw is k_hash3(seed, cell, k). */
typedef struct cell_rng {
    uint32_t seed, cell, k;
} cell_rng;

/* Uniform in (0, 1]: never 0, so its logarithm is finite. */
static double draw(cell_rng *r)
{
    return ((double)(k_hash3(r->seed, r->cell, r->k++) >> 8) + 1.0) / 16777216.0;
}

double fb_stars_expected(const fb_stars_params *P)
{
    return P->count6 * pow(10.0, P->slope * (P->limit - 6.0));
}

/* ---- colours ------------------------------------------------------------------------------------ */

/* One lobe of Wyman, Sloan and Shirley's fit to the CIE 1931 colour matching functions ("Simple
 * Analytic Approximations to the CIE XYZ Color Matching Functions", JCGT 2013). */
static double lobe(double l, double mu, double s1, double s2)
{
    double t = (l - mu) / (l < mu ? s1 : s2);
    return exp(-0.5 * t * t);
}

void fb_stars_blackbody(double temp, double rgb[3])
{
    double X = 0, Y = 0, Z = 0;
    for (double l = 360.0; l <= 830.0; l += 1.0) {
        double planck = 1.0 / (pow(l * 1e-3, 5) * expm1(1.4387769e7 / (l * temp)));
        X += planck * (1.056 * lobe(l, 599.8, 37.9, 31.0) + 0.362 * lobe(l, 442.0, 16.0, 26.7) -
                       0.065 * lobe(l, 501.1, 20.4, 26.2));
        Y += planck * (0.821 * lobe(l, 568.8, 46.9, 40.5) + 0.286 * lobe(l, 530.9, 16.3, 31.1));
        Z += planck * (1.217 * lobe(l, 437.0, 11.8, 36.0) + 0.681 * lobe(l, 459.0, 26.0, 13.8));
    }
    /* XYZ to linear Rec. 709 (D65), luminance 1; a colour outside the gamut is clipped to it and
     * scaled back to luminance 1 */
    double c[3] = {3.2404542 * X - 1.5371385 * Y - 0.4985314 * Z, -0.9692660 * X + 1.8760108 * Y + 0.0415560 * Z,
                   0.0556434 * X - 0.2040259 * Y + 1.0572252 * Z};
    for (int i = 0; i < 3; i++) c[i] = c[i] > 0 ? c[i] : 0;
    double lum = 0.2126729 * c[0] + 0.7151522 * c[1] + 0.0721750 * c[2];
    for (int i = 0; i < 3; i++) rgb[i] = c[i] / lum;
}

/* Temperatures by spectral class, in the proportions of the stars seen by eye (about those of the
 * Yale Bright Star Catalogue: many K giants and A and B stars, few M and G), log-uniform within the
 * class's range. */
static double temperature(cell_rng *r)
{
    static const double share[6] = {0.12, 0.20, 0.15, 0.14, 0.33, 0.06};
    static const double lo[6] = {10000, 7500, 6000, 5200, 3700, 2400}, hi[6] = {30000, 10000, 7500, 6000, 5200, 3700};
    double u = draw(r), v = draw(r), acc = 0;
    int c = 5;
    for (int i = 0; i < 6; i++)
        if (u <= (acc += share[i])) {
            c = i;
            break;
        }
    return lo[c] * pow(hi[c] / lo[c], v);
}

/* The colour of temp from a table of 256 temperatures, log-spaced over 2000 to 40000 K. */
#define NTEMP 256
typedef struct colour_table {
    double rgb[NTEMP][3];
} colour_table;

static void colour_table_fill(colour_table *t)
{
    for (int i = 0; i < NTEMP; i++) fb_stars_blackbody(2000.0 * pow(20.0, i / (NTEMP - 1.0)), t->rgb[i]);
}

static void colour_of(const colour_table *t, double temp, double rgb[3])
{
    double f = log(temp / 2000.0) / log(20.0) * (NTEMP - 1);
    f = f < 0 ? 0 : f > NTEMP - 1 ? NTEMP - 1 : f;
    int i = (int)f < NTEMP - 1 ? (int)f : NTEMP - 2;
    double a = f - i;
    for (int c = 0; c < 3; c++) rgb[c] = t->rgb[i][c] * (1 - a) + t->rgb[i + 1][c] * a;
}

/* ---- cells and density ---------------------------------------------------------------------------- */

/* The solid angle of the cube-face rectangle [0, s] x [0, t] (its corner's antiderivative). */
static double face_F(double s, double t)
{
    return atan(s * t / sqrt(1 + s * s + t * t));
}

static double cell_omega(double s0, double s1, double t0, double t1)
{
    return face_F(s1, t1) - face_F(s0, t1) - face_F(s1, t0) + face_F(s0, t0);
}

/* The direction of face f's point (s, t), normalised (kernels/envmap.h's faces). */
static void face_dir(int f, double s, double t, double d[3])
{
    double v[3];
    switch (f) {
    case 0:
        v[0] = 1, v[1] = s, v[2] = t;
        break;
    case 1:
        v[0] = -1, v[1] = s, v[2] = t;
        break;
    case 2:
        v[0] = s, v[1] = 1, v[2] = t;
        break;
    case 3:
        v[0] = s, v[1] = -1, v[2] = t;
        break;
    case 4:
        v[0] = s, v[1] = t, v[2] = 1;
        break;
    default:
        v[0] = s, v[1] = t, v[2] = -1;
        break;
    }
    double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int i = 0; i < 3; i++) d[i] = v[i] / l;
}

/* The direction of longitude lon, latitude lat (degrees) in the maps' frame. */
static void lonlat_dir(double lon, double lat, double d[3])
{
    double a = lon * M_PI / 180, b = lat * M_PI / 180;
    d[0] = sin(a) * cos(b), d[1] = sin(b), d[2] = cos(a) * cos(b);
}

/* The Milky Way's frame: its pole and two axes in its plane (galactic longitude 0 along e1). */
typedef struct galaxy {
    double pole[3], e1[3], e2[3];
    double contrast, inv_width; /* radians^-1 */
    uint32_t seed;
} galaxy;

static void galaxy_init(const fb_stars_params *P, uint32_t seed, galaxy *g)
{
    lonlat_dir(P->pole[0], P->pole[1], g->pole);
    double *n = g->pole, up[3] = {0, 1, 0};
    if (fabs(n[1]) > 0.9) up[0] = 1, up[1] = 0;
    /* e1 = up x n, normalised; e2 = n x e1 */
    double e1[3] = {up[1] * n[2] - up[2] * n[1], up[2] * n[0] - up[0] * n[2], up[0] * n[1] - up[1] * n[0]};
    double l = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
    for (int i = 0; i < 3; i++) g->e1[i] = e1[i] / l;
    g->e2[0] = n[1] * g->e1[2] - n[2] * g->e1[1];
    g->e2[1] = n[2] * g->e1[0] - n[0] * g->e1[2];
    g->e2[2] = n[0] * g->e1[1] - n[1] * g->e1[0];
    g->contrast = P->milky_way;
    g->inv_width = 180 / (M_PI * P->mw_width);
    g->seed = k_hash3(seed, 0x6a1a7u, 0);
}

/* The star density at d relative to the sky away from the band: 1 + contrast, times a Gaussian in
 * galactic latitude b and fBm clouds along the band (4 octaves of gradient noise over galactic
 * longitude and latitude, periodic in longitude), which are at least 0. */
static double density(const galaxy *g, const double d[3])
{
    if (g->contrast <= 0) return 1;
    double z = d[0] * g->pole[0] + d[1] * g->pole[1] + d[2] * g->pole[2];
    double b = asin(z > 1 ? 1 : z < -1 ? -1 : z);
    double x = d[0] * g->e1[0] + d[1] * g->e1[1] + d[2] * g->e1[2];
    double y = d[0] * g->e2[0] + d[1] * g->e2[1] + d[2] * g->e2[2];
    double l = atan2(y, x) + M_PI; /* [0, 2 pi] */
    double f = 0, amp = 0.5;
    for (uint32_t o = 0; o < 4; o++) {
        uint32_t cells = 16u << o;
        double scale = cells / (2 * M_PI);
        f += amp * k_gradient_noise(k_hash(g->seed + o), (float)(l * scale), (float)(b * scale + 64.0), cells,
                                    K_NOISE_PERIOD);
        amp *= 0.5;
    }
    double clouds = 1 + 1.6 * f;
    double t = b * g->inv_width;
    return 1 + g->contrast * exp(-0.5 * t * t) * (clouds > 0 ? clouds : 0);
}

/* The sky's mean density (the cells' centres weighted by their solid angle), and its largest value
 * (the band's centre with the fullest clouds: 1 + contrast (1 + 1.6)). */
static double mean_density(const galaxy *g)
{
    if (g->contrast <= 0) return 1;
    double sum = 0;
    const int m = 4 * FB_STARS_CELLS;
    for (int f = 0; f < 6; f++)
        for (int j = 0; j < m; j++)
            for (int i = 0; i < m; i++) {
                double s0 = -1 + 2.0 * i / m, s1 = -1 + 2.0 * (i + 1) / m;
                double t0 = -1 + 2.0 * j / m, t1 = -1 + 2.0 * (j + 1) / m, d[3];
                face_dir(f, 0.5 * (s0 + s1), 0.5 * (t0 + t1), d);
                sum += density(g, d) * cell_omega(s0, s1, t0, t1);
            }
    return sum / (4 * M_PI);
}

/* ---- the stars of one cell ------------------------------------------------------------------------ */

typedef struct sky {
    const fb_stars_params *P;
    galaxy gal;
    double per_sr;  /* candidates per steradian: N / (4 pi) times the largest relative density */
    double max_rel; /* the largest density relative to the mean */
    double mean;
    colour_table colours;
    uint32_t seed;
} sky;

/* Appends the stars of cell (f, i, j) to *stars (growing it). Candidates arrive as a Poisson process
 * of per_sr times the cell's solid angle (exponential gaps, so any rate is exact), each uniform in
 * solid angle over the cell (uniform on the face, kept with probability J / J_max), and each kept with
 * probability density / (largest density): the stars are a Poisson process of the density. */
static fb_result cell_stars(const sky *k, int f, int i, int j, fb_star **stars, size_t *n, size_t *cap)
{
    const int M = FB_STARS_CELLS;
    double s0 = -1 + 2.0 * i / M, s1 = -1 + 2.0 * (i + 1) / M, t0 = -1 + 2.0 * j / M, t1 = -1 + 2.0 * (j + 1) / M;
    double lambda = k->per_sr * cell_omega(s0, s1, t0, t1);
    /* J is largest at the cell's point nearest the face's centre */
    double sn = s0 > 0 ? s0 : s1 < 0 ? s1 : 0, tn = t0 > 0 ? t0 : t1 < 0 ? t1 : 0;
    double jmax = pow(1 + sn * sn + tn * tn, -1.5);
    cell_rng r = {k->seed, (uint32_t)((f * M + j) * M + i), 0};
    for (double time = -log(draw(&r)); time < lambda; time -= log(draw(&r))) {
        double s, t, d[3];
        int tries = 0;
        do {
            s = s0 + (s1 - s0) * draw(&r), t = t0 + (t1 - t0) * draw(&r);
        } while (draw(&r) * jmax > pow(1 + s * s + t * t, -1.5) && ++tries < 64);
        face_dir(f, s, t, d);
        double keep = draw(&r), mag = k->P->limit + log10(draw(&r)) / k->P->slope, temp = temperature(&r);
        if (keep * k->max_rel > density(&k->gal, d) / k->mean) continue;
        if (*n == *cap) {
            size_t c = *cap ? 2 * *cap : 4096;
            fb_star *p = realloc(*stars, c * sizeof *p);
            if (!p) return fb_fail(FB_ERR_NOMEM, "out of memory for %zu stars", c);
            *stars = p, *cap = c;
        }
        fb_star *st = &(*stars)[(*n)++];
        memcpy(st->dir, d, sizeof d);
        st->mag = mag;
        st->temp = temp;
        colour_of(&k->colours, temp, st->rgb);
    }
    return FB_OK;
}

fb_result fb_stars_catalog(const fb_stars_params *P, uint32_t seed, fb_star **out, size_t *n)
{
    sky *k = calloc(1, sizeof *k);
    if (!k) return fb_fail(FB_ERR_NOMEM, "out of memory");
    k->P = P;
    k->seed = k_hash3(seed, 0x57a55u, 0);
    galaxy_init(P, seed, &k->gal);
    k->mean = mean_density(&k->gal);
    k->max_rel = (1 + P->milky_way * 2.6) / k->mean;
    k->per_sr = fb_stars_expected(P) / (4 * M_PI) * k->max_rel;
    colour_table_fill(&k->colours);
    fb_star *stars = NULL;
    size_t cap = 0;
    *n = 0;
    fb_result rc = FB_OK;
    const int M = FB_STARS_CELLS;
    for (int f = 0; f < 6 && !rc; f++)
        for (int j = 0; j < M && !rc; j++)
            for (int i = 0; i < M && !rc; i++) rc = cell_stars(k, f, i, j, &stars, n, &cap);
    free(k);
    if (rc) {
        free(stars);
        *n = 0;
        return rc;
    }
    *out = stars;
    return FB_OK;
}
