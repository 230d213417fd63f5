/*
 * What a bake feeds its pieces to (sink.h): the finite check, the heightmaps, the PNG preview, the
 * EXR file and a cube's face sets. Each is made from the bake's view of its layers (bake_int.h) and
 * knows nothing of how the rows were computed.
 */
#include "bake_int.h"
#include "faces.h"

#include "heightmap.h"
#include "output.h"
#include "preview.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- the finite check ---------------------------------------------------------------------- */

/* No stored float or half channel may hold a NaN or an infinity: every generator's inputs are checked
 * so that none can, and this cheap pass over each piece (one compare per value, next to generating
 * and compressing it) turns a breach into an error instead of a silently broken file. Bands look at
 * once; the piece's first bad value (the lowest plane, then row, then column) is reported. */
typedef struct check_sink {
    bake_view v;
    int nplanes;
    int layer[FB_MAX_LAYERS * FB_GEN_MAX_CHANNELS], channel[FB_MAX_LAYERS * FB_GEN_MAX_CHANNELS];
    pthread_mutex_t mu;
    bool bad;
    int plane, y, x; /* the first bad value found */
} check_sink;

/* Whether any of the n values of row is a NaN or an infinity (all exponent bits set). */
static bool any_bad_scalar(const uint32_t *row, int n)
{
    uint32_t any = 0;
    for (int x = 0; x < n; x++) any |= (row[x] & 0x7f800000u) == 0x7f800000u;
    return any != 0;
}

#if defined(__x86_64__) || defined(__i386__)
/* The same on eight values at a time (the scalar loop costs about eight instructions a value: a
 * fifth of a Julia layer's native bake was this check). */
__attribute__((target("avx2"))) static bool any_bad_avx2(const uint32_t *row, int n)
{
    const __m256i e = _mm256_set1_epi32(0x7f800000);
    __m256i any = _mm256_setzero_si256();
    int x = 0;
    for (; x + 32 <= n; x += 32)
        for (int k = 0; k < 4; k++) {
            __m256i v = _mm256_and_si256(_mm256_loadu_si256((const __m256i *)(row + x + 8 * k)), e);
            any = _mm256_or_si256(any, _mm256_cmpeq_epi32(v, e));
        }
    for (; x + 8 <= n; x += 8) {
        __m256i v = _mm256_and_si256(_mm256_loadu_si256((const __m256i *)(row + x)), e);
        any = _mm256_or_si256(any, _mm256_cmpeq_epi32(v, e));
    }
    return !_mm256_testz_si256(any, any) || any_bad_scalar(row + x, n - x);
}

static bool any_bad(const uint32_t *row, int n)
{
    return __builtin_cpu_supports("avx2") ? any_bad_avx2(row, n) : any_bad_scalar(row, n);
}
#else
static bool any_bad(const uint32_t *row, int n)
{
    return any_bad_scalar(row, n);
}
#endif

/* The first non-finite value of rows [y0, y0 + n) of plane k: its row (or -1) and column. */
static int first_bad(const fb_piece *p, int k, int y0, int n, int *x_out)
{
    for (int r = y0 - p->y0; r < y0 - p->y0 + n; r++) {
        const uint32_t *row = (const uint32_t *)p->planes[k] + (size_t)r * p->stride;
        if (!any_bad(row, p->width)) continue;
        for (int x = 0; x < p->width; x++)
            if ((row[x] & 0x7f800000u) == 0x7f800000u) {
                *x_out = x;
                return p->y0 + r;
            }
    }
    return -1;
}

static fb_result check_band(void *self, const fb_piece *p, int y0, int n)
{
    check_sink *c = self;
    for (int k = 0; k < c->nplanes; k++) {
        const fb_gen *g = &c->v.runs[c->layer[k]].gen;
        if (g->store.channel_types[c->channel[k]] == EXRIO_UINT) continue;
        int x, y = first_bad(p, k, y0, n, &x);
        if (y < 0) continue;
        pthread_mutex_lock(&c->mu);
        if (!c->bad || k < c->plane || (k == c->plane && (y < c->y || (y == c->y && x < c->x))))
            c->bad = true, c->plane = k, c->y = y, c->x = x;
        pthread_mutex_unlock(&c->mu);
        break;
    }
    return FB_OK;
}

static fb_result check_rows(void *self, const fb_piece *p)
{
    check_sink *c = self;
    if (!c->bad) return FB_OK;
    const fb_gen *g = &c->v.runs[c->layer[c->plane]].gen;
    const char *name = g->store.channel_names[c->channel[c->plane]];
    float v;
    memcpy(&v, (const uint32_t *)p->planes[c->plane] + (size_t)(c->y - p->y0) * p->stride + c->x, 4);
    fb_log_context("layer %s, rows %d-%d", g->layer->name, p->y0, p->y0 + p->n - 1);
    if (g->compute.host_rows) /* the user's numbers: weights or constants too large for a float */
        return fb_fail(FB_ERR_INPUT,
                       "layer %s: the %s gives %s at pixel (%d, %d) of %s: its inputs, weights or ranges are too "
                       "large for a float (at most 3.4e38)",
                       g->layer->name, g->layer->cls->name, isnan(v) ? "NaN" : "an infinity", p->x0 + c->x, c->y, name);
    return fb_fail(FB_ERR_INTERNAL,
                   "layer %s: channel %s holds %s at pixel (%d, %d): an internal error, please report it with the "
                   "scene",
                   g->layer->name, name, isnan(v) ? "NaN" : "an infinity", p->x0 + c->x, c->y);
}

static void check_destroy(void *self)
{
    check_sink *c = self;
    if (!c) return;
    pthread_mutex_destroy(&c->mu);
    free(c);
}

fb_result sink_check_create(const bake_view *v, fb_sink *out)
{
    check_sink *c = calloc(1, sizeof *c);
    if (!c) return fb_fail(FB_ERR_NOMEM, "out of memory");
    c->v = *v;
    pthread_mutex_init(&c->mu, NULL);
    for (int i = 0; i < v->s->nlayers; i++)
        for (int ch = 0; ch < v->runs[i].gen.store.nchannels; ch++, c->nplanes++)
            c->layer[c->nplanes] = i, c->channel[c->nplanes] = ch;
    *out = (fb_sink){.name = "finite check",
                     .self = c,
                     .band_rows = 1,
                     .band = check_band,
                     .rows = check_rows,
                     .destroy = check_destroy};
    return FB_OK;
}

/* ---- heightmaps: a layer's Y channel kept whole, written at the end ----------------------------- */

typedef struct heightmaps {
    bake_view v;
    fb_bake_stats *stats;
    int rw, rh;
    float *z[FB_MAX_LAYERS];  /* window width x height, or NULL */
    int plane[FB_MAX_LAYERS]; /* the Y channel among all planes of a piece */
    int alpha[FB_MAX_LAYERS]; /* a GeoTIFF's: the A channel (0 outside a terrain's hull: no data), or -1 */
} heightmaps;

/* Layer i's heightmap: checks its size and tiles against the window and makes its array. */
static fb_result heightmap_layer(heightmaps *hm, int i)
{
    const fb_scene *s = hm->v.s;
    const fb_layer *L = &s->layers[i];
    const fb_gen *g = &hm->v.runs[i].gen;
    bool region = hm->v.d->region[2] > 0;
    char msg[256];
    fb_heightmap_format f = FB_HEIGHTMAP_PNG16;
    fb_heightmap_format_of(L->heightmap, &f);
    if (L->tiles[0] && region)
        return fb_fail(FB_ERR_USAGE,
                       "layer %s: its heightmap's tiles (%dx%d) cut the whole image, and this bake is a region of "
                       "it: bake the whole image, or leave the tiles out",
                       L->name, L->tiles[0], L->tiles[1]);
    if (!L->tiles[0] && /* a region's size (the scene checked the whole image's, and the tiles') */
        !fb_heightmap_engine_check(L->heightmap_engine, hm->rw, hm->rh, f, msg, sizeof msg))
        return fb_fail(FB_ERR_USAGE, "layer %s: %s (the region is %d x %d)", L->name, msg, hm->rw, hm->rh);
    int c = fb_gen_channel_of(g, "Y", L->name, "heightmap");
    if (!ALWAYS(c >= 0)) return FB_ERR_INTERNAL;
    hm->plane[i] = hm->v.runs[i].offset + c;
    char alpha[160];
    snprintf(alpha, sizeof alpha, "%s.A", L->name);
    hm->alpha[i] = -1;
    for (int k = 0; k < g->store.nchannels && f == FB_HEIGHTMAP_GEOTIFF; k++)
        if (!strcmp(g->store.channel_names[k], alpha)) hm->alpha[i] = hm->v.runs[i].offset + k;
    if (!(hm->z[i] = fb_malloc_large((size_t)hm->rw * hm->rh * sizeof(float))))
        return fb_fail(FB_ERR_NOMEM, "layer %s: out of memory for its heightmap", L->name);
    return FB_OK;
}

static fb_result heightmaps_band(void *self, const fb_piece *p, int y0, int n)
{
    heightmaps *hm = self;
    for (int i = 0; i < hm->v.s->nlayers; i++)
        for (int r = y0 - p->y0; hm->z[i] && r < y0 - p->y0 + n; r++) {
            float *z = hm->z[i] + (size_t)(p->y0 - p->top + r) * hm->rw;
            memcpy(z, (const float *)p->planes[hm->plane[i]] + (size_t)r * p->stride, (size_t)hm->rw * sizeof(float));
            const float *a = hm->alpha[i] >= 0 ? (const float *)p->planes[hm->alpha[i]] + (size_t)r * p->stride : NULL;
            for (int x = 0; a && x < hm->rw; x++)
                if (a[x] < 0.5f) z[x] = FB_HEIGHTMAP_NODATA;
        }
    return FB_OK;
}

/* What the bake reports of a heightmap it wrote. */
static void heightmap_stats(fb_bake_stats *stats, const fb_layer *L, double lo, double hi)
{
    if (!stats || stats->nheightmaps >= FB_MAX_LAYERS) return;
    fb_bake_heightmap *h = &stats->heightmaps[stats->nheightmaps++];
    h->layer = L->name, h->path = L->heightmap, h->lo = lo, h->hi = hi;
    h->sidecar = L->heightmap_sidecar[0] ? L->heightmap_sidecar : NULL;
    h->engine = L->heightmap_engine, h->tiles[0] = L->tiles[0], h->tiles[1] = L->tiles[1];
    h->tile_paths = L->tile_paths;
    fb_heightmap_format f = FB_HEIGHTMAP_PNG16;
    fb_heightmap_format_of(L->heightmap, &f);
    h->format = (int)f;
}

static fb_result heightmap_write(heightmaps *hm, int i)
{
    const fb_scene *s = hm->v.s;
    const int *region = hm->v.region;
    const fb_layer *L = &s->layers[i];
    size_t n = (size_t)region[2] * region[3];
    double lo = L->heightmap_range[0], hi = L->heightmap_range[1];
    if (!L->heightmap_range_set) {
        lo = INFINITY, hi = -INFINITY;
        for (size_t k = 0; k < n; k++)
            lo = hm->z[i][k] < lo ? hm->z[i][k] : lo, hi = hm->z[i][k] > hi ? hm->z[i][k] : hi;
        if (!(hi > lo)) hi = lo + 1; /* a flat image: every height stored as 0 */
    }
    const fb_gen *g = &hm->v.runs[i].gen;
    double world[4] = {0, 1, 0, 1};
    if (g->prepared.has_world) { /* the region's part of the layer's frame */
        const double *gw = g->prepared.world;
        double sx = (gw[1] - gw[0]) / s->width, sy = (gw[3] - gw[2]) / s->height;
        world[0] = gw[0] + region[0] * sx, world[1] = world[0] + region[2] * sx;
        world[3] = gw[3] - region[1] * sy, world[2] = world[3] - region[3] * sy;
    }
    fb_log_context("layer %s", L->name);
    fb_result rc = fb_heightmap_write(&(fb_heightmap_desc){.path = L->heightmap,
                                                           .width = region[2],
                                                           .height = region[3],
                                                           .z = hm->z[i],
                                                           .lo = lo,
                                                           .hi = hi,
                                                           .world = world,
                                                           .epsg = g->prepared.epsg,
                                                           .engine = (fb_heightmap_engine)L->heightmap_engine,
                                                           .nodata = hm->alpha[i] >= 0,
                                                           .cols = L->tiles[0],
                                                           .rows = L->tiles[1]});
    if (!rc) heightmap_stats(hm->stats, L, lo, hi);
    return rc;
}

static fb_result heightmaps_end(void *self)
{
    heightmaps *hm = self;
    fb_result rc = FB_OK;
    for (int i = 0; i < hm->v.s->nlayers && !rc; i++)
        if (hm->z[i]) rc = heightmap_write(hm, i);
    return rc;
}

static void heightmaps_destroy(void *self)
{
    heightmaps *hm = self;
    if (!hm) return;
    for (int i = 0; i < FB_MAX_LAYERS; i++) free(hm->z[i]);
    free(hm);
}

fb_result sink_heightmaps_create(const bake_view *v, fb_bake_stats *stats, fb_sink *out)
{
    heightmaps *hm = calloc(1, sizeof *hm);
    if (!hm) return fb_fail(FB_ERR_NOMEM, "out of memory");
    hm->v = *v;
    hm->stats = stats;
    hm->rw = v->region[2], hm->rh = v->region[3];
    fb_result rc = FB_OK;
    for (int i = 0; i < v->s->nlayers && !rc; i++)
        if (v->s->layers[i].heightmap[0]) rc = heightmap_layer(hm, i);
    if (rc) {
        heightmaps_destroy(hm);
        return rc;
    }
    *out = (fb_sink){.name = "heightmaps",
                     .self = hm,
                     .band_rows = 1,
                     .band = heightmaps_band,
                     .end = heightmaps_end,
                     .destroy = heightmaps_destroy};
    return FB_OK;
}

/* ---- the PNG preview ------------------------------------------------------------------------ */

/* One layer's preview: its colour (3 channels from `first`) or scalar channel, and its coverage. */
typedef struct previews {
    const char *path;
    int n;     /* 1: one layer shown alone; more: the over composite of every layer, or the sheet */
    bool over; /* composite (also with a single layer, when asked for by name "over") */
    bool all;  /* a contact sheet: every layer a tile of its own, labelled */
    char labels[FB_MAX_LAYERS][96];
    fb_preview *p[FB_MAX_LAYERS];
    int layer[FB_MAX_LAYERS], first[FB_MAX_LAYERS], alpha[FB_MAX_LAYERS]; /* channel indices; alpha -1: none */
    int offset[FB_MAX_LAYERS]; /* the layer's first plane among all planes of a piece */
    bool uint[FB_MAX_LAYERS];  /* a scalar uint channel (a julia layer's iter alone): shown as float */
    bool three[FB_MAX_LAYERS]; /* colour */
    bool light[FB_MAX_LAYERS]; /* colour added in the composite (preview_light) */
    int nwater[FB_MAX_LAYERS], water[FB_MAX_LAYERS][2]; /* a scalar preview's water masks (preview_water) */
    int width, stride;                                  /* the window's width; the planes' row stride */
} previews;

static int alpha_channel(const fb_gen *g)
{
    for (int c = 0; c < g->store.nchannels; c++) {
        size_t len = strlen(g->store.channel_names[c]);
        if (len >= 2 && !strcmp(g->store.channel_names[c] + len - 2, ".A")) return c;
    }
    return -1;
}

/* Which layer the preview shows (-1: several), or FB_ERR_USAGE naming the layers. */
static fb_result preview_which(const fb_scene *s, const char *which, previews *pv, int *only)
{
    *only = 0;
    pv->all = which && !strcmp(which, "all");
    pv->over = which ? !strcmp(which, "over") : s->nlayers > 1;
    if (!which || pv->over || pv->all) return FB_OK;
    *only = -1;
    for (int i = 0; i < s->nlayers; i++)
        if (!strcmp(s->layers[i].name, which)) *only = i;
    if (*only >= 0) return FB_OK;
    char names[FB_MAX_LAYERS * 66];
    fb_scene_layer_names(s, names, sizeof names);
    return fb_fail(FB_ERR_USAGE, "--preview-layer: no layer named \"%s\" (layers: %s; or \"over\" or \"all\")", which,
                   names);
}

/* Layer i's preview, the k-th shown. */
static fb_result preview_layer(previews *pv, const bake_view *v, int i)
{
    const fb_scene *s = v->s;
    const fb_gen *g = &v->runs[i].gen;
    int k = pv->n++, cols = 1;
    while (cols * cols < s->nlayers) cols++;
    pv->layer[k] = i;
    pv->offset[k] = v->runs[i].offset;
    pv->three[k] = g->store.preview_rgb >= 0;
    pv->first[k] = pv->three[k] ? g->store.preview_rgb : g->store.preview_channel;
    pv->alpha[k] = pv->over ? alpha_channel(g) : -1;
    snprintf(pv->labels[k], sizeof pv->labels[k], "%s (%s)", s->layers[i].name, s->layers[i].cls->name);
    /* a sheet's tiles share about 2048 pixels across */
    int side = pv->all ? (2048 / cols > 256 ? 2048 / cols : 256) : 2048;
    pv->nwater[k] = pv->three[k] ? 0 : g->store.preview_nwater;
    for (int w = 0; w < pv->nwater[k]; w++) pv->water[k][w] = g->store.preview_water[w];
    fb_result rc = fb_preview_create_alpha(v->region[2], v->region[3], side,
                                           pv->three[k]    ? 3
                                           : pv->nwater[k] ? 2
                                                           : 1,
                                           pv->alpha[k] >= 0, &pv->p[k]);
    if (rc) return rc;
    fb_preview_set_row_stride(pv->p[k], s->width);
    pv->uint[k] = !pv->three[k] && g->store.channel_types[g->store.preview_channel] == EXRIO_UINT;
    if (!pv->three[k] && g->store.preview_shade[0] > 0)
        fb_preview_set_hillshade(pv->p[k], g->store.preview_shade[0], g->store.preview_shade[1]);
    pv->light[k] = pv->over && pv->three[k] && g->store.preview_light;
    if (pv->light[k]) fb_preview_set_light(pv->p[k]);
    return FB_OK;
}

/* "a, b and c": the names of the layers shown (or, with `drawn` false, those not shown). */
static void preview_names(const previews *pv, const fb_scene *s, bool drawn, char *out, size_t size)
{
    out[0] = 0;
    int n = 0, total = 0;
    for (int i = 0; i < s->nlayers; i++) {
        bool shown = false;
        for (int k = 0; k < pv->n; k++) shown = shown || pv->layer[k] == i;
        total += shown == drawn;
    }
    for (int i = 0; i < s->nlayers; i++) {
        bool shown = false;
        for (int k = 0; k < pv->n; k++) shown = shown || pv->layer[k] == i;
        if (shown != drawn) continue;
        n++;
        snprintf(out + strlen(out), size - strlen(out), "%s%s",
                 n == 1       ? ""
                 : n == total ? (drawn ? " and " : ", ")
                              : ", ",
                 s->layers[i].name);
    }
}

/* One line for the user: what the picture shows, and what it leaves out. */
static void preview_note(const previews *pv, const fb_scene *s, char *note, size_t note_size)
{
    char list[FB_MAX_LAYERS * 70], left[FB_MAX_LAYERS * 70], hid[FB_MAX_LAYERS * 140] = "";
    preview_names(pv, s, true, list, sizeof list);
    if (pv->all) {
        snprintf(note, note_size, "a contact sheet of every layer (%s)", list);
        return;
    }
    if (!pv->over) {
        snprintf(note, note_size, "layer %s alone", list);
        return;
    }
    preview_names(pv, s, false, left, sizeof left);
    char added[FB_MAX_LAYERS * 70] = "";
    for (int k = 0; k < pv->n; k++)
        if (pv->light[k])
            snprintf(added + strlen(added), sizeof added - strlen(added), "%s%s", added[0] ? ", " : "",
                     s->layers[pv->layer[k]].name);
    for (int k = pv->n - 1; k > 0; k--) /* the frontmost opaque layer hides every layer behind it */
        if (pv->alpha[k] < 0 && !pv->light[k]) {
            char behind[FB_MAX_LAYERS * 70] = "";
            for (int j = 0; j < k; j++)
                snprintf(behind + strlen(behind), sizeof behind - strlen(behind), "%s%s", j ? ", " : "",
                         s->layers[pv->layer[j]].name);
            snprintf(hid, sizeof hid, "; %s has no coverage (A) and hides %s", s->layers[pv->layer[k]].name, behind);
            break;
        }
    snprintf(note, note_size, "%s composited back to front by their coverage%s%s%s%s%s%s%s", list,
             added[0] ? " (light added: " : "", added, added[0] ? ")" : "", hid,
             left[0] ? "; not drawn (op layers, and data with no colour or coverage in front): " : "", left,
             pv->n > 1 || left[0] ? " (--preview-layer NAME shows one, all a sheet of every layer)" : "");
}

static fb_result previews_band(void *self, const fb_piece *p, int y0, int n)
{
    previews *pv = self;
    const void *const *planes = p->planes;
    size_t at = (size_t)(y0 - p->y0) * p->stride;
    float *conv = NULL, *wet = NULL;
    for (int k = 0; k < pv->n; k++) {
        const void *const *lp = planes + pv->offset[k];
        int f = pv->first[k], three = pv->three[k];
        const float *rows[4] = {(const float *)lp[f] + at, (const float *)lp[three ? f + 1 : f] + at,
                                (const float *)lp[three ? f + 2 : f] + at, NULL};
        int nc = three ? 3 : pv->nwater[k] ? 2 : 1;
        if (pv->nwater[k]) { /* 1 where any mask is > 0, in rows of the same stride */
            if (!wet && !(wet = malloc((size_t)n * pv->stride * sizeof *wet)))
                return fb_fail(FB_ERR_NOMEM, "out of memory for the preview");
            for (int r = 0; r < n; r++)
                for (int x = 0; x < pv->width; x++) {
                    size_t o = (size_t)r * pv->stride + x;
                    bool w = false;
                    for (int m = 0; m < pv->nwater[k]; m++) w = w || ((const float *)lp[pv->water[k][m]] + at)[o] > 0;
                    wet[o] = w;
                }
            rows[1] = wet;
        }
        if (pv->alpha[k] >= 0) rows[nc] = (const float *)lp[pv->alpha[k]] + at;
        if (pv->uint[k]) { /* converted into rows of the same stride */
            if (!conv && !(conv = malloc((size_t)n * pv->stride * sizeof *conv)))
                return fb_fail(FB_ERR_NOMEM, "out of memory for the preview");
            const uint32_t *src = (const uint32_t *)lp[f] + at;
            for (int r = 0; r < n; r++)
                for (int x = 0; x < pv->width; x++)
                    conv[(size_t)r * pv->stride + x] = (float)src[(size_t)r * pv->stride + x];
            rows[0] = conv;
        }
        fb_preview_add_rows(pv->p[k], y0 - p->top, n, rows);
    }
    free(conv);
    free(wet);
    return FB_OK;
}

static fb_result previews_end(void *self)
{
    const previews *pv = self;
    if (pv->all) {
        const char *labels[FB_MAX_LAYERS];
        for (int k = 0; k < pv->n; k++) labels[k] = pv->labels[k];
        return fb_preview_write_sheet((const fb_preview *const *)pv->p, labels, pv->n, pv->path);
    }
    if (pv->over) return fb_preview_write_over((const fb_preview *const *)pv->p, pv->n, pv->path);
    return fb_preview_write_png(pv->p[0], pv->path, "preview");
}

static void previews_destroy(void *self)
{
    previews *pv = self;
    if (!pv) return;
    for (int k = 0; k < pv->n; k++) fb_preview_destroy(&pv->p[k]);
    free(pv);
}

fb_result sink_previews_create(const bake_view *v, char *note, size_t note_size, fb_sink *out)
{
    const fb_scene *s = v->s;
    previews *pv = calloc(1, sizeof *pv);
    if (!pv) return fb_fail(FB_ERR_NOMEM, "out of memory");
    pv->path = v->d->preview;
    int only;
    fb_result rc = preview_which(s, v->d->preview_layer, pv, &only);
    for (int i = 0; i < s->nlayers && !rc; i++) {
        /* op layers are data (masks, sums): shown by name, left out of the composite; so is a layer of data with no
         * colour and no coverage (an fBm field) in front of another, which it would hide: drawn only at the back */
        const fb_gen *g = &v->runs[i].gen;
        bool host = g->compute.host_rows != NULL, opaque_data = g->store.preview_rgb < 0 && alpha_channel(g) < 0;
        bool composite = (!host && (!opaque_data || pv->n == 0)) || (i == s->nlayers - 1 && pv->n == 0);
        if (pv->all ? true : pv->over ? composite : i == only) rc = preview_layer(pv, v, i);
    }
    if (rc) {
        previews_destroy(pv);
        return rc;
    }
    pv->width = v->region[2];
    pv->stride = s->width;
    if (note) preview_note(pv, s, note, note_size);
    *out = (fb_sink){.name = "preview",
                     .self = pv,
                     .band_rows = fb_preview_scale(pv->p[0]),
                     .band = previews_band,
                     .end = previews_end,
                     .destroy = previews_destroy};
    return FB_OK;
}

/* ---- the EXR file --------------------------------------------------------------------------- */

typedef struct exr_sink {
    bake_view v;
    bool held;
    const exrio_channel *channels;
    int nch;
    exrio_writer *w;
} exr_sink;

/* The file's backend: the one asked for (auto, vulkan, native); where each layer ran goes in
 * per_layer ("a=vulkan;b=native") for auto, where the layers ran on different ones (a layer with no
 * Vulkan path), or when d asks for the list. Returns how many layers ran on Vulkan. */
static int file_backend(const bake_view *v, char backend[16], char *per_layer, size_t size)
{
    const fb_scene *s = v->s;
    int nvk = 0;
    for (int i = 0; i < s->nlayers; i++) nvk += v->runs[i].e.kind == FB_BACKEND_VULKAN;
    snprintf(backend, 16, "%s", fb_backend_name(v->e->asked));
    per_layer[0] = 0;
    bool list = v->d->layer_backends || v->e->asked == FB_BACKEND_AUTO || (nvk > 0 && nvk < s->nlayers);
    for (int i = 0; i < s->nlayers && list; i++)
        snprintf(per_layer + strlen(per_layer), size - strlen(per_layer), "%s%s=%s", i ? ";" : "", s->layers[i].name,
                 fb_backend_name(v->runs[i].e.kind));
    return nvk;
}

/* The writer for the window, with the attributes that let `render --from` and merge read the file
 * back: the scene, seed, backend, device, version, region, a task's or points part's own. */
static fb_result exr_begin(void *self)
{
    exr_sink *x = self;
    const bake_view *v = &x->v;
    const fb_bake_desc *d = v->d;
    const fb_scene *s = v->s;
    const int *region = v->region;
    char backend[16], per_layer[FB_MAX_LAYERS * 80], seed[16], reg[64];
    int nvk = file_backend(v, backend, per_layer, sizeof per_layer);
    snprintf(seed, sizeof seed, "%u", s->seed);
    snprintf(reg, sizeof reg, "%d,%d,%d,%d", region[0], region[1], region[2], region[3]);
    bool partial = d->region[2] > 0;
    exrio_attr attrs[16] = {
        {"fractalbake/scene", s->json},      {"fractalbake/seed", seed},
        {"fractalbake/backend", backend},    {"fractalbake/device", nvk ? v->e->device : "native C"},
        {"fractalbake/version", FB_VERSION},
    };
    int nattrs = 5;
    if (partial) attrs[nattrs++] = (exrio_attr){"fractalbake/region", reg};
    if (per_layer[0]) attrs[nattrs++] = (exrio_attr){"fractalbake/layer-backends", per_layer};
    for (int a = 0; a < d->nattrs && nattrs < 14; a++) attrs[nattrs++] = d->attrs[a];
    /* a points part: which, and each chaos-game layer's points outside the frame (merge needs them
     * for the density; merge also reads the attribute's first name, fractalbake/ifs-outside) */
    char part[32], outside[FB_MAX_LAYERS * 90] = "";
    if (d->points_part[1] > 0) {
        snprintf(part, sizeof part, "%d/%d", d->points_part[0], d->points_part[1]);
        for (int i = 0; i < s->nlayers; i++)
            if (v->runs[i].gen.prepared.points_split)
                snprintf(outside + strlen(outside), sizeof outside - strlen(outside), "%s%s=%llu",
                         outside[0] ? ";" : "", s->layers[i].name,
                         (unsigned long long)v->runs[i].gen.prepared.points_outside);
        attrs[nattrs++] = (exrio_attr){"fractalbake/points-part", part};
        attrs[nattrs++] = (exrio_attr){"fractalbake/points-outside", outside};
    }
    const char *part_names[FB_MAX_LAYERS];
    exrio_compression part_comp[FB_MAX_LAYERS];
    for (int i = 0; i < s->nlayers; i++) part_names[i] = s->layers[i].name, part_comp[i] = s->layers[i].compression;
    return exrio_writer_create(&(exrio_writer_desc){.path = d->out,
                                                    .width = region[2],
                                                    .height = region[3],
                                                    .x0 = region[0],
                                                    .y0 = region[1],
                                                    .full_width = partial ? s->width : 0,
                                                    .full_height = partial ? s->height : 0,
                                                    .row_stride = s->width,
                                                    .nparts = s->multipart ? s->nlayers : 1,
                                                    .part_names = s->multipart ? part_names : NULL,
                                                    .part_compression = s->multipart ? part_comp : NULL,
                                                    .compression = s->compression,
                                                    .channels = x->channels,
                                                    .nchannels = x->nch,
                                                    .attrs = attrs,
                                                    .nattrs = nattrs,
                                                    .threads = v->e->threads,
                                                    .zip_level = d->zip_level,
                                                    .envmap = s->envmap},
                               &x->w);
}

static fb_result exr_rows(void *self, const fb_piece *p)
{
    exr_sink *x = self;
    if (!x->held) return exrio_writer_rows(x->w, p->y0 - p->top, p->n, p->planes);
    exrio_hold hold = {fb_piece_retain, fb_piece_release, p->owner};
    return exrio_writer_rows_held(x->w, p->y0 - p->top, p->n, p->planes, &hold);
}

static fb_result exr_end(void *self)
{
    exr_sink *x = self;
    return exrio_writer_finish(&x->w);
}

static void exr_destroy(void *self)
{
    exr_sink *x = self;
    if (!x) return;
    exrio_writer_abort(&x->w);
    free(x);
}

fb_result sink_exr_create(const bake_view *v, const bake_shape *shape, const exrio_channel *channels, int nch,
                          fb_sink *out)
{
    exr_sink *x = calloc(1, sizeof *x);
    if (!x) return fb_fail(FB_ERR_NOMEM, "out of memory");
    *x = (exr_sink){.v = *v, .held = shape->held, .channels = channels, .nch = nch};
    *out = (fb_sink){
        .name = "EXR writer", .self = x, .begin = exr_begin, .rows = exr_rows, .end = exr_end, .destroy = exr_destroy};
    return FB_OK;
}

/* ---- a cube's engine face sets -------------------------------------------------------------- */

static fb_result faces_rows(void *self, const fb_piece *p)
{
    return fb_faces_rows(self, p->y0, p->n, p->planes, p->stride);
}

static void faces_destroy(void *self)
{
    fb_faces *f = self;
    fb_faces_destroy(&f);
}

/* The whole cube, every channel; PNG faces show the first colour layer. */
fb_result sink_faces_create(const bake_view *v, const exrio_channel *channels, int nch, fb_sink *out)
{
    const fb_scene *s = v->s;
    if (s->envmap != EXRIO_ENVMAP_CUBE || v->d->region[2] > 0)
        return fb_fail(FB_ERR_USAGE,
                       "--cube-faces: needs the whole of a cube environment map (mapping cube, no --region)");
    int rgb = -1;
    for (int i = 0; i < s->nlayers && rgb < 0; i++)
        if (v->runs[i].gen.store.preview_rgb >= 0) rgb = v->runs[i].offset + v->runs[i].gen.store.preview_rgb;
    fb_faces *f = NULL;
    fb_result rc = fb_faces_create(&(fb_faces_desc){.pattern = v->d->cube_faces,
                                                    .n = s->width,
                                                    .channels = channels,
                                                    .nchannels = nch,
                                                    .rgb = rgb,
                                                    .compression = s->compression,
                                                    .threads = v->e->threads,
                                                    .zip_level = v->d->zip_level},
                                   &f);
    if (rc) return rc;
    *out = (fb_sink){.name = "cube faces", .self = f, .rows = faces_rows, .destroy = faces_destroy};
    return FB_OK;
}
