/*
 * The rivers layer: a landscape raised by tectonic uplift and carved by rivers, the stream power law
 * solved by Braun and Willett's implicit method (rivers.h), computed whole on the host in prepare on
 * either backend; strips and regions are copied out of it.
 *
 * Channels: NAME.Y (the surface: the bed, with depressions filled unless lakes are kept), NAME.area
 * (drainage area by steepest descent, world units squared), NAME.river (1 where the area reaches
 * river-area), NAME.lake (depth of standing water: kept lakes and the sea); with a palette also NAME.R,
 * .G, .B, the surface lit and coloured by height, the water in its colour.
 */
#include "engine.h"
#include "exrio.h"
#include "amplify.h"
#include "gen_rivers.h"
#include "heightmap.h"
#include "rivers.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- the scene keys and their parser ---------------------------------------------------------- */

static const fb_keyspec rivers_keys[] = {
    {"type", FB_K_TYPE, 0, 0, false, NULL, NULL, "generator: \"rivers\"", FB_CORE},
    {"name", FB_K_NAME, 0, 0, false, NULL, "\"rivers\"", "layer name; channels NAME.Y, .area, .river, .lake", FB_CORE},
    {"input", FB_K_REF, 0, 0, false, NULL, NULL,
     "the starting heights: another layer's channel (\"layer\": its Y), or a number (flat at that height; default 0)",
     FB_FIELD(fb_rivers_layer_params, input)},
    {"uplift", FB_K_NUM, 0, 1e6, false, NULL, "0.001",
     "U, rock uplift in height per time unit (where uplift-map is 1, with a map)",
     FB_FIELD(fb_rivers_layer_params, uplift)},
    {"uplift-map", FB_K_REF, 0, 0, false, NULL, NULL,
     "where the rock rises: another layer's channel (a survey, a macro shape, fBm), its values from uplift-range "
     "taken as 0 to 1 of U",
     FB_FIELD(fb_rivers_layer_params, map)},
    {"uplift-range", FB_K_VEC2, -1e15, 1e15, false, NULL, NULL,
     "the uplift map's values taken as 0 and 1 of U (LO,HI, clamped; default: the map's lowest and highest)",
     FB_FIELD(fb_rivers_layer_params, range)},
    {"K", FB_K_NUM, 0, 1e6, false, NULL, "5e-6", "erodibility: incision K A^m S^n (A drainage area, S slope)",
     FB_FIELD(fb_rivers_layer_params, K)},
    {"m", FB_K_NUM, 0, 2, true, NULL, "0.5", "the drainage area's exponent, in (0, 2]",
     FB_FIELD(fb_rivers_layer_params, m)},
    {"n", FB_K_NUM, 0, 4, true, NULL, "1",
     "the slope's exponent, in (0, 4] (1: solved directly; else by Newton's iteration, slower)",
     FB_FIELD(fb_rivers_layer_params, n)},
    {"kd", FB_K_NUM, 0, 1e9, false, NULL, "0.03", "hillslope diffusivity, area per time unit (0: none)",
     FB_FIELD(fb_rivers_layer_params, kd)},
    {"dt", FB_K_NUM, 0, 1e12, true, NULL, "50000", "the time step, in time units",
     FB_FIELD(fb_rivers_layer_params, dt)},
    {"steps", FB_K_INT, 1, 1000000, false, NULL, "400", "time steps (the simulated time is dt x steps)",
     FB_FIELD(fb_rivers_layer_params, steps)},
    {"noise", FB_K_NUM, 0, 1e9, false, NULL, "1",
     "the starting heights' perturbation: uniform in [0, noise) at each cell, from the seed",
     FB_FIELD(fb_rivers_layer_params, noise)},
    {"lakes", FB_K_ENUM, 0, 0, false, "fill|keep", "\"fill\"",
     "depressions: filled (the surface drains everywhere) or kept as lakes (NAME.lake holds their depth)",
     FB_FIELD(fb_rivers_layer_params, keep_lakes)},
    {"outlets", FB_K_NAMES, 0, 0, false, "north|south|east|west|none", "[\"north\", \"south\", \"east\", \"west\"]",
     "the edges water leaves by, each held at its height (none: only the sea; flag: a comma list)",
     FB_FIELD(fb_rivers_layer_params, outlets)},
    {"sea-level", FB_K_NUM, -1e15, 1e15, false, NULL, NULL, "cells below this height are the sea: outlets, held",
     FB_FIELD(fb_rivers_layer_params, sea_level)},
    {"extent", FB_K_NUM, 0, 1e12, true, NULL, NULL,
     "the image's width in world units (the heights' unit); default: the input's or the uplift map's world width, "
     "else 100000",
     FB_FIELD(fb_rivers_layer_params, extent)},
    {"river-area", FB_K_NUM, 0, 1e30, true, NULL, NULL,
     "NAME.river is 1 where the drainage area reaches this, world units squared (default: 1/1000 of the image's "
     "area)",
     FB_FIELD(fb_rivers_layer_params, river_area)},
    {"coarse", FB_K_INT, 2, 65536, false, NULL, NULL,
     "the model's grid width in cells (height in proportion); a wider image is the model amplified: its rivers "
     "carved to the pixel, its hillslopes given detail (default: the image's width up to 2047, else 1024 or what "
     "--max-memory holds; a grid over half the image's width is the whole grid)",
     FB_FIELD(fb_rivers_layer_params, coarse)},
    {"detail", FB_K_NUM, 0, 1, false, NULL, "0.6",
     "an amplified image's hillslope detail (fBm): its slope as a share of the local slope (0: none)",
     FB_FIELD(fb_rivers_layer_params, detail)},
    FB_RELIEF_KEYS,
    {"water-colour", FB_K_NUMLIST, 0, 1e3, false, NULL, NULL,
     "with a palette: the colour of rivers and standing water, R,G,B, lit like the land (default 0.03,0.12,0.3)", 3,
     FB_FIELD(fb_rivers_layer_params, water)},
    {"heightmap", FB_K_OUTPUT, 0, 0, false, NULL, NULL,
     "also write the heights (Y) for engines: OUT.png (16-bit grey), OUT.r16 (16-bit raw) or OUT.tif (float GeoTIFF)",
     FB_CORE},
    FB_HEIGHTMAP_KEYS,
    {"half", FB_K_BOOL, 0, 0, false, NULL, "false",
     "store Y and lake as half (area stays float: it exceeds half's range; flags: --half, --float)", FB_CORE},
    FB_COMPRESSION_KEY,
};

static fb_result parse_rivers(const fb_vctx *v, const char *path, json_t *obj, const fb_scene *s, fb_layer *L)
{
    (void)s;
    fb_rivers_layer_params *P = (void *)L->params;
    fb_result rc = fb_schema_check(v, path, obj, rivers_keys, FB_NKEYS(rivers_keys), "a rivers layer", P);
    if (rc) return rc;
    char sub[256];
    const json_t *map = json_object_get(obj, "uplift-map");
    P->has_input = json_object_get(obj, "input") != NULL;
    P->has_map = map != NULL;
    if (map && json_is_number(map)) {
        snprintf(sub, sizeof sub, "%s.uplift-map", path);
        return fb_schema_error(v, sub, "expected another layer's channel; a uniform uplift is the number \"uplift\"");
    }
    P->has_range = json_object_get(obj, "uplift-range") != NULL;
    if (P->has_range) {
        snprintf(sub, sizeof sub, "%s.uplift-range", path);
        if (!map) return fb_schema_error(v, sub, "the range of an uplift map, and there is no uplift-map");
        if (!(P->range[1] > P->range[0]))
            return fb_schema_error(v, sub, "expected LO,HI with LO < HI, found %g,%g", P->range[0], P->range[1]);
    }
    /* the outlets' names in the order of their bits (FB_RIVERS_NORTH ...), then none */
    bool none = P->outlets & 16u;
    P->outlets &= 15u;
    snprintf(sub, sizeof sub, "%s.outlets", path);
    if (none && P->outlets) return fb_schema_error(v, sub, "\"none\" with edges: name the edges, or none alone");
    P->has_sea = json_object_get(obj, "sea-level") != NULL;
    if (!P->outlets && !P->has_sea)
        return fb_schema_error(v, sub, "no outlet: water must leave by an edge, or set a sea-level");
    if ((rc = fb_schema_relief(v, path, obj, &P->relief))) return rc;
    const json_t *wc = json_object_get(obj, "water-colour");
    if (wc && !P->relief.colour) {
        snprintf(sub, sizeof sub, "%s.water-colour", path);
        return fb_schema_error(v, sub, "water-colour shapes the colour by height: give palette, cosine or stops too");
    }
    static const double water[3] = {0.03, 0.12, 0.3};
    for (int c = 0; c < 3 && !wc; c++) P->water[c] = water[c];
    return FB_OK;
}

/* ---- the layer --------------------------------------------------------------------------------- */

typedef struct rivers_state {
    fb_source src, map; /* the starting heights' and the uplift map's channels (resolve); .gen NULL: none */
    int cw, ch;         /* the model's grid: the image's (whole), or coarse (amplified) */
    fb_rivers_out out;  /* whole: the result */
    fb_rivers_amp amp;  /* amplified: what the rows read */
    fb_relief relief;   /* with a palette: the colour by height */
    double cell;        /* the image's cell, world units */
} rivers_state;

static rivers_state *state(const fb_gen *g)
{
    return g->owned;
}

static bool amplified(const rivers_state *s, const fb_scene *sc)
{
    return s->cw != sc->width;
}

static void rivers_fini(fb_gen *g)
{
    rivers_state *s = state(g);
    if (s) fb_rivers_out_free(&s->out), fb_rivers_amp_fini(&s->amp);
}

/* The model's peak (its state and result, the input and the uplift map sampled on its grid) and, when
 * amplified, what the rows hold. */
static uint64_t grid_memory(int W, int H, int cw, int ch, uint64_t *hold)
{
    uint64_t n = (uint64_t)cw * ch;
    if (cw == W) { /* the result (16 bytes a cell) kept for the strips (the colour is computed in them) */
        *hold = 16 * n;
        return fb_rivers_memory(cw, ch) + 8 * n;
    }
    (void)H;
    *hold = fb_rivers_amp_memory(cw, ch);
    return fb_rivers_memory(cw, ch) + 8 * n + *hold;
}

/* The model's grid: the key's width (over half the image's: the whole grid), else the image's up to
 * 2047 wide, else 1024; narrower where the memory limit would not hold it. */
static void grid_of(const fb_gen *g, int *cw, int *ch)
{
    const fb_rivers_layer_params *P = fb_layer_params(g->layer);
    const int W = g->scene->width, H = g->scene->height;
    int c = P->coarse;
    if (!c) {
        c = W < 2048 ? W : 1024;
        uint64_t limit = fb_memory_limit(&g->run.budget), hold;
        while (c > 64 && grid_memory(W, H, c, (int)fmax(1, round((double)H * c / W)), &hold) > limit / 2) c -= c / 8;
        if (c < W && 2 * c > W) c = W / 2;
    }
    if (2 * c > W) c = W;
    *cw = c;
    *ch = c == W ? H : (int)fmax(1, round((double)H * c / W));
}

/* The layer whose world the image takes: the input's, else the uplift map's (NULL: none has one). */
static const fb_gen *world_of(const fb_gen *g)
{
    const rivers_state *s = state(g);
    if (!s) return NULL;
    if (s->src.gen && s->src.gen->prepared.has_world) return s->src.gen;
    if (s->map.gen && s->map.gen->prepared.has_world) return s->map.gen;
    return NULL;
}

static double extent_of(const fb_gen *g)
{
    const fb_rivers_layer_params *P = fb_layer_params(g->layer);
    const fb_gen *w = world_of(g);
    if (P->extent > 0) return P->extent;
    if (w) return w->prepared.world[1] - w->prepared.world[0];
    return 100000;
}

/* The uplift map as factors in [0, 1]: its values from the range (or its own lowest and highest). */
static void normalise(float *map, size_t n, const fb_rivers_layer_params *P)
{
    double lo = P->range[0], hi = P->range[1];
    if (!P->has_range) {
        lo = INFINITY, hi = -INFINITY;
        for (size_t i = 0; i < n; i++) lo = fmin(lo, map[i]), hi = fmax(hi, map[i]);
    }
    for (size_t i = 0; i < n; i++) {
        double t = hi > lo ? (map[i] - lo) / (hi - lo) : 1; /* a flat map: uplift everywhere */
        map[i] = (float)(t < 0 ? 0 : t > 1 ? 1 : t);
    }
}

static void rivers_rows(const fb_gen *g, int y0, int n, void *const *planes);

/* The summary: the model's grid and steps, its relief, largest basin, rivers and water (amplified: the
 * coarse model's). */
static void summarise(fb_gen *g, double secs, double model_cell)
{
    rivers_state *s = state(g);
    const fb_rivers_layer_params *P = fb_layer_params(g->layer);
    const fb_scene *sc = g->scene;
    size_t n = (size_t)s->cw * s->ch;
    float lo = INFINITY, hi = -INFINITY;
    uint64_t rivers = 0, lakes = 0;
    for (size_t i = 0; i < n; i++) {
        lo = fminf(lo, s->out.height[i]), hi = fmaxf(hi, s->out.height[i]);
        rivers += s->out.river[i] > 0, lakes += s->out.lake[i] > 0;
    }
    char amp[96] = "";
    if (amplified(s, sc))
        snprintf(amp, sizeof amp, " amplified to %d x %d (detail %.3g)", sc->width, sc->height, P->detail);
    double work = (double)n * P->steps;
    snprintf(g->prepared.summary, sizeof g->prepared.summary,
             "%s: %d x %d cells of %.4g%s, %d steps of %.4g; relief %.6g, largest basin %.3g%% of the cells, river "
             "cells %.3g%%, standing water %.3g%%, depressions filled in %d steps (%llu cells); %.3f s, %.3g "
             "Mcell-steps/s",
             g->layer->name, s->cw, s->ch, model_cell, amp, P->steps, P->dt, (double)hi - lo,
             100 * s->out.largest_basin, 100.0 * rivers / n, 100.0 * lakes / n, s->out.flood_steps,
             (unsigned long long)s->out.flooded, secs, work / secs * 1e-6);
    snprintf(g->prepared.summary_json, sizeof g->prepared.summary_json,
             "{\"layer\": \"%s\", \"generator\": \"rivers\", \"width\": %d, \"height\": %d, \"model\": [%d, %d], "
             "\"cell\": %.9g, \"steps\": %d, \"relief\": %.9g, \"largest_basin\": %.6g, \"river_cells\": %llu, "
             "\"water_cells\": %llu, \"flood_steps\": %d, \"flooded\": %llu, \"seconds\": %.6f}",
             g->layer->name, sc->width, sc->height, s->cw, s->ch, s->cell, P->steps, (double)hi - lo,
             s->out.largest_basin, (unsigned long long)rivers, (unsigned long long)lakes, s->out.flood_steps,
             (unsigned long long)s->out.flooded, secs);
    if (P->relief.colour) fb_relief_init(&s->relief, &P->relief, lo, hi);
}

static fb_result rivers_prepare(fb_gen *g, struct fb_engine *e, bool progress)
{
    rivers_state *s = state(g);
    const fb_rivers_layer_params *P = fb_layer_params(g->layer);
    const fb_scene *sc = g->scene;
    size_t n = (size_t)s->cw * s->ch;
    float *initial = s->src.gen ? malloc(n * sizeof *initial) : NULL,
          *map = s->map.gen ? malloc(n * sizeof *map) : NULL;
    fb_result rc = (s->src.gen && !initial) || (s->map.gen && !map) ? fb_fail(FB_ERR_NOMEM, "out of memory") : FB_OK;
    if (!rc && s->src.gen) rc = fb_source_read_grid(&s->src, g, "input", s->cw, s->ch, initial);
    if (!rc && s->map.gen) rc = fb_source_read_grid(&s->map, g, "uplift-map", s->cw, s->ch, map);
    if (!rc && map) normalise(map, n, P);
    double extent = extent_of(g), cell = extent / s->cw;
    fb_rivers_desc d = {.width = s->cw,
                        .height = s->ch,
                        .cell = cell,
                        .initial = initial,
                        .base = P->has_input && P->input.layer < 0 ? P->input.value : 0,
                        .noise = P->noise,
                        .seed = sc->seed,
                        .uplift = P->uplift,
                        .uplift_map = map,
                        .K = P->K,
                        .m = P->m,
                        .n = P->n,
                        .kd = P->kd,
                        .dt = P->dt,
                        .steps = P->steps,
                        .keep_lakes = P->keep_lakes,
                        .outlets = P->outlets,
                        .has_sea = P->has_sea,
                        .sea_level = P->sea_level,
                        .river_area = P->river_area > 0 ? P->river_area : 1e-3 * extent * cell * s->ch,
                        .receivers = amplified(s, sc)};
    fb_progress prog;
    char label[96];
    snprintf(label, sizeof label, "%s: stream-power erosion", g->layer->name);
    fb_progress_init(&prog, progress, label, "cell-steps");
    double t0 = fb_now();
    if (!rc) rc = fb_rivers_run(&d, e->pool, &prog, &s->out);
    fb_progress_finish(&prog);
    free(initial), free(map);
    if (!rc && amplified(s, sc)) rc = fb_rivers_amp_init(&s->amp, &d, &s->out, sc->width, sc->height, P->detail);
    double secs = fb_now() - t0;
    if (rc) return rc;
    /* the world the image covers: the source's top-left corner (else the origin), extent wide */
    const fb_gen *w = world_of(g);
    s->cell = extent / sc->width;
    g->prepared.has_world = true;
    g->prepared.world[0] = w ? w->prepared.world[0] : 0, g->prepared.world[1] = g->prepared.world[0] + extent;
    g->prepared.world[3] = w ? w->prepared.world[3] : extent * sc->height / sc->width,
    g->prepared.world[2] = g->prepared.world[3] - s->cell * sc->height;
    g->prepared.epsg = w ? w->prepared.epsg : 0;
    if (sc->height > 1) g->store.preview_shade[0] = g->store.preview_shade[1] = s->cell;
    summarise(g, secs, cell);
    if (amplified(s, sc)) fb_rivers_out_free(&s->out); /* the rows read the amplification alone */
    return FB_OK;
}

/* The colour of rows [y0, y0 + n): the land by height under the light, rivers and standing water in
 * the water's colour under the same light; the slope by central differences of the surface (one-sided
 * at the edges), in world units. z holds the surface's rows from zy0 on (y0 - 1 where there is one,
 * through y0 + n where there is one); river and lake rows y0 on. */
static void colour_rows(const fb_gen *g, int y0, int n, const float *z, int zy0, const float *river, const float *lake,
                        float *R, float *G, float *B)
{
    const rivers_state *s = state(g);
    const fb_rivers_layer_params *P = fb_layer_params(g->layer);
    const int W = g->scene->width, H = g->scene->height;
    for (int y = y0; y < y0 + n; y++)
        for (int x = 0; x < W; x++) {
            size_t i = (size_t)(y - zy0) * W + x, o = (size_t)(y - y0) * W + x;
            int xl = x > 0 ? x - 1 : x, xr = x + 1 < W ? x + 1 : x, yu = y > 0 ? y - 1 : y, yd = y + 1 < H ? y + 1 : y;
            const float *row = z + (size_t)(y - zy0) * W;
            double gx = xr > xl ? ((double)row[xr] - row[xl]) / ((xr - xl) * s->cell) : 0;
            double gy = yd > yu ? ((double)z[(size_t)(yu - zy0) * W + x] - z[(size_t)(yd - zy0) * W + x]) /
                                      ((yd - yu) * s->cell)
                                : 0;
            float c[3];
            if (river[o] > 0 || lake[o] > 0) {
                double light = fb_relief_light(&s->relief, gx, gy);
                for (int k = 0; k < 3; k++) c[k] = (float)(P->water[k] * light);
            } else {
                fb_relief_colour(&s->relief, z[i], gx, gy, c);
            }
            R[o] = c[0], G[o] = c[1], B[o] = c[2];
        }
}

/* Amplified rows: with a colour, the surface a row beyond each side too (the slope's). Out of memory
 * for those rows, the colour is NaN, which the bake's finite check reports. */
static void amplified_rows(const fb_gen *g, int y0, int n, void *const *planes)
{
    const rivers_state *s = state(g);
    const int W = g->scene->width, H = g->scene->height;
    if (g->store.nchannels == 4) {
        fb_rivers_amp_rows(&s->amp, y0, n, planes[0], planes[1], planes[2], planes[3]);
        return;
    }
    int ya = y0 > 0 ? y0 - 1 : 0, yb = y0 + n < H ? y0 + n : H - 1, m = yb - ya + 1;
    size_t len = (size_t)m * W, at = (size_t)(y0 - ya) * W, part = (size_t)n * W;
    float *buf = malloc(4 * len * sizeof *buf);
    if (!buf) {
        for (int c = 4; c < 7; c++)
            for (size_t i = 0; i < part; i++) ((float *)planes[c])[i] = NAN;
        return;
    }
    float *z = buf, *area = buf + len, *river = buf + 2 * len, *lake = buf + 3 * len;
    fb_rivers_amp_rows(&s->amp, ya, m, z, area, river, lake);
    const float *src[4] = {z + at, area + at, river + at, lake + at};
    for (int c = 0; c < 4; c++)
        if (planes[c]) memcpy(planes[c], src[c], part * sizeof *buf);
    colour_rows(g, y0, n, z, ya, river + at, lake + at, planes[4], planes[5], planes[6]);
    free(buf);
}

static void rivers_rows(const fb_gen *g, int y0, int n, void *const *planes)
{
    const rivers_state *s = state(g);
    if (amplified(s, g->scene)) {
        amplified_rows(g, y0, n, planes);
        return;
    }
    size_t at = (size_t)y0 * g->scene->width, len = (size_t)n * g->scene->width * 4;
    const float *src[4] = {s->out.height, s->out.area, s->out.river, s->out.lake};
    for (int c = 0; c < 4; c++)
        if (planes[c]) memcpy(planes[c], src[c] + at, len);
    if (g->store.nchannels > 4)
        colour_rows(g, y0, n, s->out.height, 0, s->out.river + at, s->out.lake + at, planes[4], planes[5], planes[6]);
}

static uint64_t rivers_memory(const fb_gen *g, const struct fb_engine *e, uint64_t *hold)
{
    (void)e;
    int cw, ch;
    grid_of(g, &cw, &ch);
    return grid_memory(g->scene->width, g->scene->height, cw, ch, hold);
}

static fb_result rivers_resolve(fb_gen *g, const fb_gen *const *gens, const int *plane_offset);

static fb_result rivers_init(fb_gen *g)
{
    int cw, ch;
    grid_of(g, &cw, &ch);
    uint64_t hold, peak = grid_memory(g->scene->width, g->scene->height, cw, ch, &hold);
    char who[128];
    snprintf(who, sizeof who, "stream-power erosion of %d x %d cells", cw, ch);
    fb_result rc = fb_memory_check(&g->run.budget, peak, who);
    if (rc) return rc;
    rivers_state *s = calloc(1, sizeof *s);
    if (!s) return fb_fail(FB_ERR_NOMEM, "out of memory");
    g->owned = s;
    g->fini = rivers_fini;
    s->cw = cw, s->ch = ch;
    static const char *const suffix[7] = {"Y", "area", "river", "lake", "R", "G", "B"};
    const fb_rivers_layer_params *P = fb_layer_params(g->layer);
    g->store.nchannels = P->relief.colour ? 7 : 4;
    for (int c = 0; c < g->store.nchannels; c++) {
        snprintf(g->store.channel_names[c], sizeof g->store.channel_names[c], "%s.%s", g->layer->name, suffix[c]);
        g->store.channel_types[c] = (g->layer->half && c != 1) || c == 2 ? EXRIO_HALF : EXRIO_FLOAT;
    }
    g->store.preview_channel = 0;
    if (P->relief.colour) g->store.preview_rgb = 4; /* the preview shows the lit colour */
    g->store.preview_nwater = 2;                    /* else the hillshade, its rivers and lakes over it */
    g->store.preview_water[0] = 2, g->store.preview_water[1] = 3;
    if (g->scene->height > 1) g->store.preview_shade[0] = g->store.preview_shade[1] = extent_of(g) / g->scene->width;
    g->compute.native_rows = rivers_rows;
    g->prepare = rivers_prepare;
    g->memory = rivers_memory;
    g->resolve = rivers_resolve;
    g->prepared.gpu_seconds = -1;
    return FB_OK;
}

static fb_result rivers_resolve(fb_gen *g, const fb_gen *const *gens, const int *plane_offset)
{
    (void)plane_offset;
    const fb_rivers_layer_params *P = fb_layer_params(g->layer);
    rivers_state *s = state(g);
    fb_result rc = FB_OK;
    if (P->has_input && P->input.layer >= 0) rc = fb_source_find(&s->src, g, gens, &P->input, "input", NULL);
    if (!rc && P->has_map) rc = fb_source_find(&s->map, g, gens, &P->map, "uplift-map", NULL);
    return rc;
}

static int rivers_refs(fb_layer *L, fb_ref_slot *out)
{
    fb_rivers_layer_params *P = (void *)L->params;
    int n = 0;
    if (P->has_input && P->input.layer != -1) out[n++] = (fb_ref_slot){&P->input, "input", "a number"};
    if (P->has_map) out[n++] = (fb_ref_slot){&P->map, "uplift-map", NULL};
    return n;
}

/* The plan's cost model: seconds of one core of the reference machine (docs/scenes.md): about 60 ns a
 * cell-step of the model once the depressions of the first steps are filled, the final fill and copy
 * per pixel, and an amplified pixel's channels and detail (bench/RESULTS.md). Banded: a pure function
 * of the pixel once the model has run; each task runs the model (the same bits), counted here once. */
static fb_result rivers_cost(const fb_scene *s, int layer, double *rows, double *total)
{
    const fb_rivers_layer_params *P = fb_layer_params(&s->layers[layer]);
    int c = P->coarse ? P->coarse : s->width < 2048 ? s->width : 1024;
    if (c < s->width && 2 * c > s->width) c = s->width / 2;
    if (2 * c > s->width) c = s->width;
    double cells = (double)c * fmax(1, round((double)s->height * c / s->width));
    double model = cells * (P->steps * 6.0e-8 /* a cell-step */ + 4.0e-7 /* a cell */);
    double px = c == s->width ? 0 : 1.5e-6; /* an amplified pixel */
    *total = 0;
    for (int y = 0; y < s->height; y++) rows[y] = model / s->height + px * s->width, *total += rows[y];
    return FB_OK;
}

const fb_gen_class fb_gen_rivers = {
    .name = "rivers",
    .synopsis = "rivers [options] -o OUT.exr",
    .summary = "a landscape raised by uplift and carved by rivers: the stream power law with hillslope diffusion",
    .what = "a rivers layer",
    .keys = rivers_keys,
    .nkeys = FB_NKEYS(rivers_keys),
    .params_size = sizeof(fb_rivers_layer_params),
    .parse = parse_rivers,
    .refs = rivers_refs,
    .init = rivers_init,
    .share = FB_SHARE_BAND,
    .cost = rivers_cost,
    .example = "[{\"type\": \"rivers\", \"name\": \"r\", \"extent\": 6400, \"steps\": 30, \"dt\": 20000}]",
    .bench = fb_rivers_bench,
};
