/*
 * The stars generator: a star field on the sphere (catalog.c) binned into the image's tiles and
 * spread by kernels/stars.h, natively or by shaders/stars.comp.
 */
#include "bake.h"
#include "catalog.h"
#include "gen_stars.h"

#include "kernels/stars.h"
#include "stars_comp.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- the scene keys and their parser ---------------------------------------------------------- */

static const fb_keyspec stars_keys[] = {
    {"type", FB_K_TYPE, 0, 0, false, NULL, NULL, "generator: \"stars\"", FB_CORE},
    {"name", FB_K_NAME, 0, 0, false, NULL, "\"stars\"",
     "layer name; the channels are NAME.R, NAME.G, NAME.B and NAME.mag (flag: --layer)", FB_CORE},
    {"mapping", FB_K_ENUM, 0, 0, false, "latlong|cube|polar", "\"latlong\"",
     "the sky's layout: latlong (2N x N), cube (N x 6N, faces +X -X +Y -Y +Z -Z) or polar (the upper "
     "hemisphere as the julia layer's polar grid)",
     FB_FIELD(fb_stars_params, mapping)},
    {"limit", FB_K_NUM, -2, 11, false, NULL, "8.0", "limiting magnitude: the faintest stars drawn",
     FB_FIELD(fb_stars_params, limit)},
    {"slope", FB_K_NUM, 0.05, 1, false, NULL, "0.49", "star counts N(<m) grow as 10^(slope m)",
     FB_FIELD(fb_stars_params, slope)},
    {"count6", FB_K_NUM, 0, 1e6, false, NULL, "4970", "stars brighter than magnitude 6 over the whole sky",
     FB_FIELD(fb_stars_params, count6)},
    {"brightness", FB_K_NUM, 0, 1e12, false, NULL, "1.0", "flux (luminance times steradians) of a magnitude-0 star",
     FB_FIELD(fb_stars_params, brightness)},
    {"psf", FB_K_NUM, 0.5, 4, false, NULL, "1.0", "half width of each star's tent spread, pixels",
     FB_FIELD(fb_stars_params, psf)},
    {"milky-way", FB_K_NUM, 0, 100, false, NULL, "0.0",
     "the Milky Way's star density at its centre line, relative to the sky far from it (0: no band)",
     FB_FIELD(fb_stars_params, milky_way)},
    {"milky-way-width", FB_K_NUM, 0.5, 90, false, NULL, "8.0", "the band's half width, degrees of galactic latitude",
     FB_FIELD(fb_stars_params, mw_width)},
    {"galactic-pole", FB_K_VEC2, -360, 360, false, NULL, "[192.86, 27.13]",
     "the band's north pole: longitude and latitude, degrees (default: the real one for a map in right ascension "
     "and declination)",
     FB_FIELD(fb_stars_params, pole)},
    {"half", FB_K_BOOL, 0, 0, false, NULL, "false", "store R, G, B as half instead of float (flags: --half, --float)",
     FB_CORE},
    FB_COMPRESSION_KEY,
};

/* The smallest sizes a mapping takes (the spread must fit in a face or a period), or a message. */
static const char *size_problem(unsigned mapping, int w, int h)
{
    /* the scene checks an environment map's shape (2N x N, N x 6N) */
    if (mapping == K_ENV_LATLONG && h < 8) return "a lat-long star sky is at least 16 x 8 pixels";
    if (mapping == K_ENV_CUBE && w < 12) return "a cube star sky has faces of at least 12 x 12 pixels";
    if (mapping == K_STARS_POLAR && w < 12) return "a polar star sky is at least 12 pixels wide";
    return NULL;
}

static fb_result parse_stars(const fb_vctx *v, const char *path, json_t *obj, const fb_scene *s, fb_layer *L)
{
    char sub[256];
    fb_stars_params *p = (void *)L->params;
    fb_result rc = fb_schema_check(v, path, obj, stars_keys, FB_NKEYS(stars_keys), "a stars layer", p);
    if (rc) return rc;
    static const unsigned kinds[] = {K_ENV_LATLONG, K_ENV_CUBE, K_STARS_POLAR}; /* by the key's index */
    p->mapping = kinds[p->mapping];
    if (fabs(p->pole[1]) > 90) {
        snprintf(sub, sizeof sub, "%s.galactic-pole", path);
        return fb_schema_error(v, sub, "the pole's latitude %g is outside [-90, 90] degrees", p->pole[1]);
    }
    const char *why = size_problem(p->mapping, s->width, s->height);
    if (why) {
        snprintf(sub, sizeof sub, "%s.mapping", path);
        return fb_schema_error(v, sub, "%s; the scene is %d x %d", why, s->width, s->height);
    }
    if (fb_stars_expected(p) > 2.5e6) {
        snprintf(sub, sizeof sub, "%s.limit", path);
        return fb_schema_error(v, sub,
                               "%.3g stars (count6 %g, slope %g, limit %g) are more than the 2.5 million a sky holds; "
                               "lower the limit",
                               fb_stars_expected(p), p->count6, p->slope, p->limit);
    }
    return FB_OK;
}

/* ---- the layer --------------------------------------------------------------------------------- */

typedef struct stars_push {
    K_StarsParams p;
    uint32_t y0;
    uint32_t rows;
} stars_push;

_Static_assert(offsetof(K_StarsParams, mapping) == 8 && offsetof(K_StarsParams, rec_off) == 24, "std430 offset");
_Static_assert(offsetof(K_StarsParams, radius) == 32 && offsetof(K_StarsParams, cube_h) == 48, "std430 offset");
_Static_assert(sizeof(K_StarsParams) == 64 && offsetof(stars_push, y0) == 64, "std430 offset");
_Static_assert(sizeof(stars_push) <= FB_GEN_MAX_PUSH && sizeof(K_StarsParams) <= sizeof(((fb_gen *)0)->params),
               "push constants");
_Static_assert(sizeof(K_StarsRec) == 4 * K_STARS_REC_WORDS, "record words");

#define TILE_SHIFT 3u
#define TILE       (1u << TILE_SHIFT)

static const K_StarsParams *params(const fb_gen *g)
{
    return (const K_StarsParams *)(const void *)g->params;
}

static void stars_rows(const fb_gen *g, int y0, int n, void *const *planes)
{
    const K_StarsParams *p = params(g);
    const uint32_t *w = g->compute.shader.input;
    const K_StarsRec *rec = (const K_StarsRec *)(const void *)(w + p->rec_off);
    float *R = planes[0], *G = planes[1], *B = planes[2], *M = planes[3];
    for (int r = 0; r < n; r++) {
        uint32_t y = (uint32_t)(y0 + r);
        float row_inv = 0;
        if (p->mapping != K_ENV_CUBE) memcpy(&row_inv, w + p->row_off + y, 4);
        for (uint32_t x = 0; x < p->width; x++) {
            uint32_t tile = (y >> p->tile_shift) * p->tiles_x + (x >> p->tile_shift);
            K_StarsPixel px = k_stars_pixel(*p, x, y);
            K_StarsAcc acc = k_stars_init();
            for (uint32_t k = w[tile]; k < w[tile + 1]; k++) acc = k_stars_add(acc, *p, px, rec[k]);
            acc = k_stars_finish(acc, *p, row_inv, x, y);
            size_t i = (size_t)r * p->width + x;
            if (R) R[i] = acc.r;
            if (G) G[i] = acc.g;
            if (B) B[i] = acc.b;
            if (M) M[i] = acc.mag;
        }
    }
}

/* ---- from stars to records ------------------------------------------------------------------------ */

/* A record and the pixels it may reach: columns [x0, x1], rows [y0, y1]. */
typedef struct placed {
    K_StarsRec rec;
    int x0, x1, y0, y1;
} placed;

typedef struct placer {
    const K_StarsParams *p;
    placed *v;
    size_t n, cap;
} placer;

static int clampi(double v, int lo, int hi)
{
    return v < lo ? lo : v > hi ? hi : (int)v;
}

/* Adds a record at (x, y) of the whole image (rows first..last; face: the cube's face or 0). */
static fb_result place(placer *pl, const fb_star *s, const double flux[3], double x, double y, uint32_t flags,
                       int first, int last)
{
    if (pl->n == pl->cap) {
        size_t c = pl->cap ? 2 * pl->cap : 4096;
        placed *v = realloc(pl->v, c * sizeof *v);
        if (!v) return fb_fail(FB_ERR_NOMEM, "out of memory for %zu star records", c);
        pl->v = v, pl->cap = c;
    }
    double m = pl->p->radius + 1.0;
    placed *q = &pl->v[pl->n++];
    q->rec = (K_StarsRec){(float)x, (float)y, (float)flux[0], (float)flux[1], (float)flux[2], (float)s->mag, flags, 0};
    q->x0 = clampi(floor(x - m), 0, (int)pl->p->width - 1), q->x1 = clampi(ceil(x + m), 0, (int)pl->p->width - 1);
    q->y0 = clampi(floor(y - m), first, last), q->y1 = clampi(ceil(y + m), first, last);
    return FB_OK;
}

/* A lat-long or polar star: its position, and a copy a period away where it reaches the seam. */
static fb_result place_wrapped(placer *pl, const fb_star *s, const double flux[3])
{
    const K_StarsParams *p = pl->p;
    const double *d = s->dir;
    double W = p->width, H = p->height, x, y, period;
    double lon = (d[0] == 0 && d[2] == 0) ? 0 : atan2(d[0], d[2]);
    if (p->mapping == K_ENV_LATLONG) {
        double lat = asin(d[1] > 1 ? 1 : d[1] < -1 ? -1 : d[1]);
        x = (lon / (-2 * M_PI) + 0.5) * (W - 1), y = (lat / (-M_PI) + 0.5) * (H - 1), period = W - 1;
    } else {
        if (d[1] <= 0) return FB_OK;               /* below the horizon */
        double u = atan2(d[2], d[0]) / (2 * M_PI); /* the julia layer's polar grid: d.x + i d.z ~ exp(i 2 pi u) */
        x = (u < 0 ? u + 1 : u) * W - 0.5;
        y = (1 - sqrt((1 - d[1]) / (1 + d[1]))) * H - 0.5, period = W;
    }
    fb_result rc = place(pl, s, flux, x, y, K_STARS_CLAMP_Y, 0, p->height - 1);
    double m = p->radius + 1.0;
    if (!rc && x < m) rc = place(pl, s, flux, x + period, y, K_STARS_CLAMP_Y, 0, p->height - 1);
    if (!rc && x > W - 1 - m) rc = place(pl, s, flux, x - period, y, K_STARS_CLAMP_Y, 0, p->height - 1);
    return rc;
}

static uint32_t face_of(const double d[3])
{
    k_vec3 v = k_vec3((float)d[0], (float)d[1], (float)d[2]);
    return k_env_cube_face_of(v);
}

/* A cube star: on its own face, and on each neighbouring face its spread reaches, at its place in
 * the cube's unfolding about their shared edge (beyond that face's edge by as much as it lies inside
 * its own), so that the mass beyond its face's edge falls on the neighbour's pixels. */
static fb_result place_cube(placer *pl, const fb_star *s, const double flux[3])
{
    const K_StarsParams *p = pl->p;
    uint32_t g = face_of(s->dir), n = p->n;
    int ga = (int)g / 2;
    double gs = g % 2 ? -1 : 1, q[3];
    for (int i = 0; i < 3; i++) q[i] = s->dir[i] / fabs(s->dir[ga]);
    k_vec2 pos = k_env_cube_pos_face(k_vec3((float)q[0], (float)q[1], (float)q[2]), g, n);
    fb_result rc = place(pl, s, flux, pos.x, pos.y, K_STARS_HOME_CUBE | g << 8, (int)(g * n), (int)(g * n + n - 1));
    for (uint32_t f = 0; f < 6 && !rc; f++) {
        int fa = (int)f / 2;
        if (fa == ga) continue;
        double fs = f % 2 ? -1 : 1, alpha = q[fa] * fs;
        if ((1 - alpha) * (n - 1) / 2 > p->radius + 1.0) continue;
        double u[3] = {q[0], q[1], q[2]};
        u[fa] += (1 - alpha) * fs;
        u[ga] += (1 - alpha) * gs;
        pos = k_env_cube_pos_face(k_vec3((float)u[0], (float)u[1], (float)u[2]), f, n);
        rc = place(pl, s, flux, pos.x, pos.y, f << 8, (int)(f * n), (int)(f * n + n - 1));
    }
    return rc;
}

/* The most input words (4 bytes each): 128 MiB, the smallest maxStorageBufferRange Vulkan allows. */
#define MAX_INPUT_WORDS (1ull << 25)

/* The tiles' lists: tile_start[tiles + 1], then the records tile by tile (a record reaching several
 * tiles is in each), then each row's 1/omega (lat-long and polar). */
static fb_result build_input(fb_gen *g, const placer *pl, const double *row_inv)
{
    K_StarsParams *p = (K_StarsParams *)(void *)g->params;
    uint32_t tiles_y = (p->height + TILE - 1) / TILE;
    size_t tiles = (size_t)p->tiles_x * tiles_y;
    uint64_t entries = 0;
    for (size_t i = 0; i < pl->n; i++) {
        const placed *q = &pl->v[i];
        entries += (uint64_t)((q->x1 >> TILE_SHIFT) - (q->x0 >> TILE_SHIFT) + 1) *
                   (uint64_t)((q->y1 >> TILE_SHIFT) - (q->y0 >> TILE_SHIFT) + 1);
    }
    uint64_t rows = p->mapping == K_ENV_CUBE ? 0 : p->height;
    uint64_t words = tiles + 1 + entries * K_STARS_REC_WORDS + rows;
    if (words > MAX_INPUT_WORDS)
        return fb_fail(FB_ERR_INPUT,
                       "layer %s: %zu star records over %zu tiles need %llu MiB, more than the %llu MiB "
                       "supported; lower the limit or the size",
                       g->layer->name, pl->n, tiles, (unsigned long long)(words >> 18),
                       (unsigned long long)(MAX_INPUT_WORDS >> 18));
    uint32_t *w = calloc((size_t)words, 4), *fill = calloc(tiles, sizeof *fill);
    if (!w || !fill) {
        free(w), free(fill);
        return fb_fail(FB_ERR_NOMEM, "out of memory for the star records (%llu MiB)",
                       (unsigned long long)(words >> 18));
    }
#define FOR_TILES(q, BODY)                                                                                             \
    for (int ty_ = (q)->y0 >> TILE_SHIFT; ty_ <= (q)->y1 >> TILE_SHIFT; ty_++)                                         \
        for (int tx_ = (q)->x0 >> TILE_SHIFT; tx_ <= (q)->x1 >> TILE_SHIFT; tx_++) {                                   \
            size_t tile = (size_t)ty_ * p->tiles_x + (size_t)tx_;                                                      \
            BODY;                                                                                                      \
        }
    for (size_t i = 0; i < pl->n; i++) FOR_TILES(&pl->v[i], w[tile + 1]++);
    for (size_t t = 0; t < tiles; t++) w[t + 1] += w[t];
    p->rec_off = (uint32_t)(tiles + 1);
    p->row_off = (uint32_t)(tiles + 1 + entries * K_STARS_REC_WORDS);
    K_StarsRec *rec = (K_StarsRec *)(void *)(w + p->rec_off);
    memcpy(fill, w, tiles * sizeof *fill);
    for (size_t i = 0; i < pl->n; i++) FOR_TILES(&pl->v[i], rec[fill[tile]++] = pl->v[i].rec);
#undef FOR_TILES
    free(fill);
    for (uint64_t y = 0; y < rows; y++) {
        float f = (float)row_inv[y];
        memcpy(w + p->row_off + y, &f, 4);
    }
    g->owned = w;
    g->compute.shader.input = w;
    g->compute.shader.input_size = (uint32_t)(words * 4);
    return FB_OK;
}

/* 1 / the solid angle of a full pixel of each row: lat-long, 2 pi / (W - 1) of longitude times the
 * row's band of latitude (half bands at the poles); polar, 2 pi / W of azimuth times the band of
 * zenith angle 2 atan(v) between its radii. */
static void row_solid_angles(const K_StarsParams *p, double *inv)
{
    double W = p->width, H = p->height;
    for (uint32_t y = 0; y < p->height; y++) {
        double omega;
        if (p->mapping == K_ENV_LATLONG) {
            double c = M_PI / 2 - y * M_PI / (H - 1), h = 0.5 * M_PI / (H - 1);
            double hi = fmin(c + h, M_PI / 2), lo = fmax(c - h, -M_PI / 2);
            omega = 2 * M_PI / (W - 1) * (sin(hi) - sin(lo));
        } else {
            double v0 = 1 - (y + 1.0) / H, v1 = 1 - y / H; /* cos(2 atan v) = (1 - v^2) / (1 + v^2) */
            omega = 2 * M_PI / W * ((1 - v0 * v0) / (1 + v0 * v0) - (1 - v1 * v1) / (1 + v1 * v1));
        }
        inv[y] = 1 / omega;
    }
}

/* The records of every star for this image. */
static fb_result place_stars(fb_gen *g, const fb_star *stars, size_t n, placer *pl, double *total)
{
    const fb_stars_params *P = fb_layer_params(g->layer);
    fb_result rc = FB_OK;
    *total = 0;
    for (size_t i = 0; i < n && !rc; i++) {
        double f = P->brightness * pow(10.0, -0.4 * stars[i].mag), flux[3];
        for (int c = 0; c < 3; c++) flux[c] = f * stars[i].rgb[c];
        size_t before = pl->n;
        rc = P->mapping == K_ENV_CUBE ? place_cube(pl, &stars[i], flux) : place_wrapped(pl, &stars[i], flux);
        if (pl->n > before) *total += f;
    }
    return rc;
}

static uint64_t stars_memory(const fb_gen *g, const struct fb_engine *e, uint64_t *hold)
{
    *hold = (uint64_t)g->compute.shader.input_size * (e->kind == FB_BACKEND_VULKAN ? 2u : 1u);
    return *hold;
}

static void params_fill(const fb_scene *sc, const fb_stars_params *P, K_StarsParams *p)
{
    memset(p, 0, sizeof *p);
    p->width = (uint32_t)sc->width;
    p->height = (uint32_t)sc->height;
    p->mapping = P->mapping;
    p->n = P->mapping == K_ENV_CUBE ? p->width : p->height;
    p->tiles_x = (p->width + TILE - 1) / TILE;
    p->tile_shift = TILE_SHIFT;
    p->radius = (float)P->psf;
    p->inv_2r2 = (float)(1 / (2 * P->psf * P->psf));
    p->x_lo = P->mapping == K_STARS_POLAR ? -0.5f : 0.0f;
    p->x_hi = P->mapping == K_STARS_POLAR ? (float)p->width - 0.5f : (float)(p->width - 1);
    p->cube_h = P->mapping == K_ENV_CUBE ? (float)(2.0 / (p->n - 1)) : 0.0f;
}

static fb_result stars_init(fb_gen *g)
{
    const fb_stars_params *P = fb_layer_params(g->layer);
    K_StarsParams *p = (K_StarsParams *)(void *)g->params;
    params_fill(g->scene, P, p);
    fb_star *stars = NULL;
    size_t n = 0;
    fb_result rc = fb_stars_catalog(P, g->scene->seed, &stars, &n);
    placer pl = {p, NULL, 0, 0};
    double total = 0, *row_inv = calloc(p->height, sizeof *row_inv);
    if (!rc && !row_inv) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    if (!rc) rc = place_stars(g, stars, n, &pl, &total);
    if (!rc && p->mapping != K_ENV_CUBE) row_solid_angles(p, row_inv);
    if (!rc) rc = build_input(g, &pl, row_inv);
    free(stars), free(pl.v), free(row_inv);
    if (rc) return rc;
    snprintf(g->prepared.summary, sizeof g->prepared.summary, "%zu stars, total flux %.9g", n, total);
    snprintf(g->prepared.summary_json, sizeof g->prepared.summary_json, "{\"stars\": %zu, \"flux\": %.17g}", n, total);

    static const char *const suffix[4] = {"R", "G", "B", "mag"};
    g->store.nchannels = 4;
    for (int c = 0; c < 4; c++) {
        snprintf(g->store.channel_names[c], sizeof g->store.channel_names[c], "%s.%s", g->layer->name, suffix[c]);
        g->store.channel_types[c] = g->layer->half ? EXRIO_HALF : EXRIO_FLOAT;
    }
    g->store.preview_channel = 1;  /* G */
    g->store.preview_rgb = 0;      /* R, G, B */
    g->store.preview_light = true; /* starlight: added over the sky behind it */
    g->compute.native_rows = stars_rows;
    g->memory = stars_memory;
    g->compute.shader.spv = stars_comp;
    g->compute.shader.spv_size = sizeof stars_comp;
    g->compute.shader.params_size = sizeof(K_StarsParams);
    g->compute.shader.push_size = sizeof(stars_push);
    /* the mapping as a specialisation constant too (stars.comp): the compiler drops the other
     * mappings' code (the cube's face test and corners) from the loop over the records */
    g->compute.shader.spec[0] = p->mapping;
    g->compute.shader.nspec = 1;
    return FB_OK;
}

/* The plan's cost model: seconds of one core of the reference machine (docs/scenes.md): the
 * catalogue (every task draws it whole) and the pixels. */
static fb_result stars_cost(const fb_scene *s, int layer, double *rows, double *total)
{
    const fb_stars_params *P = fb_layer_params(&s->layers[layer]);
    double row = (double)s->width * 4.0e-8;
    *total = fb_stars_expected(P) * 1.5e-6 * (1 + P->milky_way);
    for (int y = 0; y < s->height; y++) rows[y] = row, *total += row;
    return FB_OK;
}

const fb_gen_class fb_gen_stars = {
    .name = "stars",
    .synopsis = "stars [options] -o OUT.exr",
    .summary = "a star field on the sphere (lat-long, cube or polar), one layer",
    .what = "a stars layer",
    .keys = stars_keys,
    .nkeys = FB_NKEYS(stars_keys),
    .params_size = sizeof(fb_stars_params),
    .parse = parse_stars,
    .init = stars_init,
    .share = FB_SHARE_BAND,
    .cost = stars_cost,
    .example = "[{\"type\": \"stars\", \"limit\": 7}]",
    .bench = fb_stars_bench,
};
