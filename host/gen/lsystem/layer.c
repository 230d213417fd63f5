/*
 * The L-system plant generator: the string is derived and drawn by the turtle on the host
 * (lsys.c), its segments framed into pixel space, binned into square tiles, and rasterised
 * with anti-aliased coverage per pixel by kernels/lsys.h, natively or by shaders/lsys.comp.
 *
 * Channels: NAME.A (coverage) and NAME.R, .G, .B (premultiplied by A).
 */
#include "bake.h"
#include "gen_lsystem.h"
#include "lsys.h"
#include "palette.h"

#include "kernels/lsys.h"
#include "lsys_comp.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- the scene keys and their parser ---------------------------------------------------------- */

static const fb_keyspec lsystem_keys[] = {
    {"type", FB_K_TYPE, 0, 0, false, NULL, NULL, "generator: \"lsystem\"", FB_CORE},
    {"name", FB_K_NAME, 0, 0, false, NULL, "\"plants\"",
     "layer name; channels NAME.A (coverage), .R, .G, .B (flag: --layer)", FB_CORE},
    {"preset", FB_K_ENUM, 0, 0, false, FB_LSYS_PRESETS, NULL,
     "built-in L-system (default bush when no axiom); axiom, rules, iterations and angle override it", FB_PARSE},
    {"axiom", FB_K_STRING, 0, 0, false, NULL, NULL, "the starting string", FB_FIELD(fb_lsystem_params, sys.axiom)},
    {"rules", FB_K_RULES, 0, FB_LSYS_MAX_RULES, false, NULL, NULL,
     "productions \"X=successor\" or stochastic \"X(0.3)=successor\" (flag: --rule, repeatable)", FB_LSYS_MAX_RULES,
     "rule", NULL, fb_lsystem_check_rule, .value = &fb_lsystem_rules_value, FB_FIELD(fb_lsystem_params, sys)},
    {"iterations", FB_K_INT, 0, 64, false, NULL, NULL, "parallel rewriting steps",
     FB_FIELD(fb_lsystem_params, sys.iterations)},
    {"angle", FB_K_NUM, -360, 360, false, NULL, NULL, "degrees turned by + and -",
     FB_FIELD(fb_lsystem_params, sys.angle)},
    {"heading", FB_K_NUM, -360, 360, false, NULL, "90.0", "initial heading, degrees counter-clockwise from +x (90: up)",
     FB_FIELD(fb_lsystem_params, heading)},
    {"step", FB_K_NUM, 0, 1e6, true, NULL, "1.0", "length of F and f, turtle units", FB_FIELD(fb_lsystem_params, step)},
    {"width", FB_K_NUM, 0, 100, false, NULL, "0.6", "branch width at the base (bracket depth 0), in steps",
     FB_FIELD(fb_lsystem_params, width)},
    {"taper", FB_K_NUM, 0, 1, true, NULL, "0.65", "width factor per bracket depth", FB_FIELD(fb_lsystem_params, taper)},
    {"max-symbols", FB_K_INT, 1, 2147483648.0, false, NULL, "268435456",
     "longest string allowed while rewriting (a longer one stops with an error)",
     FB_FIELD(fb_lsystem_params, max_symbols)},
    {"bounds", FB_K_BOUNDS, -1e9, 1e9, false, NULL, "\"auto\"",
     "frame XMIN,XMAX,YMIN,YMAX in turtle units, or auto (the drawing, padded 4%, square units)",
     FB_FIELD(fb_lsystem_params, bounds)},
    {"palette", FB_K_ENUM, 0, 0, false, FB_PALETTE_NAMES, "\"foliage\"", "named colour map, by bracket depth", 0, NULL,
     "cosine|stops", FB_CORE},
    {"cosine", FB_K_NUMLIST, -10, 10, false, NULL, NULL,
     "cosine palette a + b cos(2 pi (c t + d)): 12 numbers aR,aG,aB,bR,bG,bB,cR,cG,cB,dR,dG,dB", 12, FB_CORE},
    {"stops", FB_K_STOPS, 0, 1e3, false, NULL, NULL,
     "gradient: [[t, r, g, b], ...], t rising from 0 to 1 (flag: \"t,r,g,b;t,r,g,b\")", FB_CORE},
    {"half", FB_K_BOOL, 0, 0, false, NULL, "true", "store A, R, G, B as half (flags: --half, --float)", FB_CORE},
    FB_COMPRESSION_KEY,
};

/* The L-system of `obj` (a layer, or an ifs layer's condensation set): a preset fills in what the
 * object does not give, and the stored scene then spells it out; keys checked against `keys`. */
bool fb_lsystem_check_rule(const char *text, char *msg, size_t size)
{
    fb_lsys_rule rule;
    return fb_lsys_parse_rule(text, &rule, msg, size);
}

/* The rules key's reader: the checked productions into an fb_lsys. */
static fb_result read_rules(const fb_vctx *v, const char *path, const json_t *j, void *field)
{
    fb_lsys *ls = field;
    char msg[256];
    ls->nrules = (int)json_array_size(j);
    for (int k = 0; k < ls->nrules; k++)
        fb_lsys_parse_rule(json_string_value(json_array_get(j, (size_t)k)), &ls->rules[k], msg, sizeof msg);
    return FB_OK;
}

const fb_kvalue fb_lsystem_rules_value = {.read = read_rules};

fb_result fb_lsystem_parse_def(const fb_vctx *v, const char *path, json_t *obj, const fb_keyspec *keys, int nkeys,
                               const char *what, void *params, const fb_lsys *ls)
{
    char sub[256], msg[256];
    json_t *preset = json_object_get(obj, "preset");
    if (!preset && !json_object_get(obj, "axiom")) {
        if (json_object_get(obj, "rules")) {
            snprintf(sub, sizeof sub, "%s.rules", path);
            return fb_schema_error(v, sub, "rules need an axiom (or a preset)");
        }
        json_object_set_new(obj, "preset", json_string("bush"));
        preset = json_object_get(obj, "preset");
    }
    if (preset) {
        fb_lsys ps;
        int idx;
        if (json_is_string(preset) && fb_enum_index(FB_LSYS_PRESETS, json_string_value(preset), &idx) &&
            !fb_lsys_preset(json_string_value(preset), &ps)) {
            json_t *rules = json_array();
            for (int k = 0; k < ps.nrules; k++) {
                char text[FB_LSYS_MAX_SUCC + 64];
                if (ps.rules[k].p >= 0)
                    snprintf(text, sizeof text, "%c(%g)=%s", ps.rules[k].pred, ps.rules[k].p, ps.rules[k].succ);
                else
                    snprintf(text, sizeof text, "%c=%s", ps.rules[k].pred, ps.rules[k].succ);
                json_array_append_new(rules, json_string(text));
            }
            if (!json_object_get(obj, "axiom")) json_object_set_new(obj, "axiom", json_string(ps.axiom));
            if (!json_object_get(obj, "rules"))
                json_object_set_new(obj, "rules", rules);
            else
                json_decref(rules);
            if (!json_object_get(obj, "iterations"))
                json_object_set_new(obj, "iterations", json_integer(ps.iterations));
            if (!json_object_get(obj, "angle")) json_object_set_new(obj, "angle", json_real(ps.angle));
        }
    }
    if (!json_object_get(obj, "rules")) json_object_set_new(obj, "rules", json_array());
    if (!json_object_get(obj, "iterations")) json_object_set_new(obj, "iterations", json_integer(1));
    if (!json_object_get(obj, "angle")) json_object_set_new(obj, "angle", json_real(25.0));
    fb_result rc = fb_schema_check(v, path, obj, keys, nkeys, what, params);
    if (rc) return rc;
    int bad;
    if (!fb_lsys_valid(ls, &bad, msg, sizeof msg)) {
        if (bad >= 0)
            snprintf(sub, sizeof sub, "%s.rules[%d]", path, bad);
        else
            snprintf(sub, sizeof sub, "%s.axiom", path);
        return fb_schema_error(v, sub, "%s", msg);
    }
    return FB_OK;
}

static fb_result parse_lsystem(const fb_vctx *v, const char *path, json_t *obj, const fb_scene *s, fb_layer *L)
{
    fb_lsystem_params *f = (void *)L->params;
    fb_result rc =
        fb_lsystem_parse_def(v, path, obj, lsystem_keys, FB_NKEYS(lsystem_keys), "an lsystem layer", f, &f->sys);
    if (rc) return rc;
    f->auto_bounds = json_is_string(json_object_get(obj, "bounds"));
    if ((rc = fb_schema_palette(v, path, obj, &f->palette))) return rc;
    return FB_OK;
}

/* ---- the layer --------------------------------------------------------------------------------- */

_Static_assert(sizeof(K_LsysParams) == 32 && sizeof(K_LsysParams) + 8 <= FB_GEN_MAX_PUSH, "push constants");
_Static_assert(sizeof(K_LsysSeg) == 4 * K_LSYS_SEG_WORDS, "segment words");

#define TILE_SHIFT 4u
#define TILE       (1u << TILE_SHIFT)

static const K_LsysParams *params(const fb_gen *g)
{
    return (const K_LsysParams *)(const void *)g->params;
}

static K_LsysSeg segment(const uint32_t *w, const K_LsysParams *p, uint32_t i)
{
    K_LsysSeg s;
    memcpy(&s, w + p->seg_off + (size_t)i * K_LSYS_SEG_WORDS, sizeof s);
    return s;
}

static void lsystem_rows(const fb_gen *g, int y0, int n, void *const *planes)
{
    const K_LsysParams *p = params(g);
    const uint32_t *w = g->compute.shader.input;
    float *A = planes[0], *R = planes[1], *G = planes[2], *B = planes[3];
    for (int r = 0; r < n; r++) {
        uint32_t y = (uint32_t)(y0 + r);
        for (uint32_t x = 0; x < p->width; x++) {
            uint32_t tile = (y >> p->tile_shift) * p->tiles_x + (x >> p->tile_shift);
            float px = (float)x + 0.5f, py = (float)y + 0.5f;
            K_LsysAcc acc = {0, 0, 0, 0};
            for (uint32_t k = w[tile]; k < w[tile + 1]; k++)
                acc = k_lsys_add(acc, segment(w, p, w[p->idx_off + k]), px, py);
            acc = k_lsys_finish(acc);
            size_t i = (size_t)r * p->width + x;
            R[i] = acc.r, G[i] = acc.g, B[i] = acc.b, A[i] = acc.a;
        }
    }
}

/* ---- from turtle segments to the kernel's input ------------------------------------------------ */

/* The tiles of row band ty that segment s may touch: its part within the band's rows widened by
 * m pixels (a pixel centre it covers lies within hw + 1/2 across and 1/2 beyond an end, so within
 * m = hw + 1 in each axis of the segment), as a column range; false when it misses the band. */
static bool band_columns(const K_LsysSeg *s, double m, uint32_t ty, uint32_t tiles_x, uint32_t *c0, uint32_t *c1)
{
    double ax = s->ax, ay = s->ay, bx = s->ax + s->ux * s->len, by = s->ay + s->uy * s->len;
    double lo = (double)ty * TILE - m, hi = (double)(ty + 1) * TILE + m;
    double t0 = 0, t1 = 1, dy = by - ay;
    if (dy == 0) {
        if (ay < lo || ay > hi) return false;
    } else {
        double ta = (lo - ay) / dy, tb = (hi - ay) / dy;
        if (ta > tb) {
            double t = ta;
            ta = tb, tb = t;
        }
        t0 = fmax(t0, ta), t1 = fmin(t1, tb);
        if (t0 > t1) return false;
    }
    double xa = ax + (bx - ax) * t0, xb = ax + (bx - ax) * t1;
    double x0 = fmin(xa, xb) - m, x1 = fmax(xa, xb) + m;
    if (x1 < 0 || x0 >= (double)tiles_x * TILE) return false;
    *c0 = x0 <= 0 ? 0 : (uint32_t)(x0 / TILE);
    *c1 = x1 >= (double)tiles_x * TILE ? tiles_x - 1 : (uint32_t)(x1 / TILE);
    if (*c1 >= tiles_x) *c1 = tiles_x - 1;
    return true;
}

/* Calls visit(tile) for every tile segment s may touch, row band by row band. */
#define FOR_TILES(s, tiles_x, tiles_y, BODY)                                                                           \
    do {                                                                                                               \
        double m_ = (double)(s)->hw + 1.0;                                                                             \
        double ya_ = (s)->ay, yb_ = (s)->ay + (s)->uy * (s)->len;                                                      \
        double ylo_ = fmin(ya_, yb_) - m_, yhi_ = fmax(ya_, yb_) + m_;                                                 \
        if (yhi_ < 0 || ylo_ >= (double)(tiles_y)*TILE) break;                                                         \
        uint32_t ty0_ = ylo_ <= 0 ? 0 : (uint32_t)(ylo_ / TILE);                                                       \
        uint32_t ty1_ = yhi_ >= (double)(tiles_y)*TILE ? (tiles_y)-1 : (uint32_t)(yhi_ / TILE);                        \
        for (uint32_t ty_ = ty0_; ty_ <= ty1_; ty_++) {                                                                \
            uint32_t c0_, c1_;                                                                                         \
            if (!band_columns((s), m_, ty_, (tiles_x), &c0_, &c1_)) continue;                                          \
            for (uint32_t tx_ = c0_; tx_ <= c1_; tx_++) {                                                              \
                size_t tile = (size_t)ty_ * (tiles_x) + tx_;                                                           \
                BODY;                                                                                                  \
            }                                                                                                          \
        }                                                                                                              \
    } while (0)

/* The most input words (4 bytes each) the rasteriser takes: 128 MiB, the smallest maxStorageBufferRange
 * Vulkan allows (and lavapipe's), whatever the backend, so that a drawing that one backend accepts
 * every other does too. About 3.3 million segments. */
#define MAX_INPUT_WORDS (1ull << 25)

static fb_result build_input(fb_gen *g, const K_LsysSeg *segs, size_t nsegs)
{
    K_LsysParams *p = (K_LsysParams *)(void *)g->params;
    uint32_t tiles_y = (p->height + TILE - 1) / TILE;
    size_t tiles = (size_t)p->tiles_x * tiles_y;
    uint64_t entries = 0;
    for (size_t i = 0; i < nsegs; i++)
        FOR_TILES(&segs[i], p->tiles_x, tiles_y, {
            (void)tile;
            entries++;
        });
    uint64_t words = tiles + 1 + entries + (uint64_t)nsegs * K_LSYS_SEG_WORDS;
    if (words > MAX_INPUT_WORDS)
        return fb_fail(FB_ERR_INPUT,
                       "layer %s: %zu segments over %zu tiles need %llu MiB of raster input, more than the %llu MiB "
                       "supported; use fewer iterations or a smaller size",
                       g->layer->name, nsegs, tiles, (unsigned long long)(words * 4 >> 20),
                       (unsigned long long)(MAX_INPUT_WORDS * 4 >> 20));
    uint32_t *w = calloc((size_t)words, 4);
    if (!w)
        return fb_fail(FB_ERR_NOMEM, "out of memory for the raster input (%llu MiB)",
                       (unsigned long long)(words >> 18));
    /* counts, then exclusive offsets, then the lists filled in segment order */
    for (size_t i = 0; i < nsegs; i++) FOR_TILES(&segs[i], p->tiles_x, tiles_y, w[tile + 1]++);
    for (size_t t = 0; t < tiles; t++) w[t + 1] += w[t];
    p->idx_off = (uint32_t)(tiles + 1);
    p->seg_off = (uint32_t)(tiles + 1 + entries);
    uint32_t *fill = malloc(tiles * sizeof *fill);
    if (!fill) {
        free(w);
        return fb_fail(FB_ERR_NOMEM, "out of memory");
    }
    memcpy(fill, w, tiles * sizeof *fill);
    for (size_t i = 0; i < nsegs; i++)
        FOR_TILES(&segs[i], p->tiles_x, tiles_y, w[p->idx_off + fill[tile]++] = (uint32_t)i);
    free(fill);
    memcpy(w + p->seg_off, segs, nsegs * sizeof *segs);
    g->owned = w;
    g->compute.shader.input = w;
    g->compute.shader.input_size = (uint32_t)(words * 4);
    return FB_OK;
}

/* The turtle's segments in pixel space: framed (auto: the drawing's extent plus its widths, padded
 * 4% and centred with square units; or the layer's bounds), widths tapered with bracket depth and
 * colours from the palette by depth (0 at the trunk, 1 at the deepest branches). */
static fb_result frame_segments(fb_gen *g, const fb_lsys_seg *in, size_t n, int max_depth, K_LsysSeg **out,
                                double bounds[4])
{
    const fb_lsystem_params *L = fb_layer_params(g->layer);
    const double W = g->scene->width, H = g->scene->height;
    double hw_units = 0.5 * L->width * L->step; /* half width at depth 0, turtle units */
    if (L->auto_bounds) {
        double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
        for (size_t i = 0; i < n; i++) {
            double h = hw_units * pow(L->taper, in[i].depth);
            x0 = fmin(x0, fmin(in[i].x0, in[i].x1) - h), x1 = fmax(x1, fmax(in[i].x0, in[i].x1) + h);
            y0 = fmin(y0, fmin(in[i].y0, in[i].y1) - h), y1 = fmax(y1, fmax(in[i].y0, in[i].y1) + h);
        }
        if (!n) x0 = -1, x1 = 1, y0 = -1, y1 = 1;
        double w = (x1 - x0) * 1.08, h = (y1 - y0) * 1.08, cx = (x0 + x1) / 2, cy = (y0 + y1) / 2;
        if (w / h < W / H)
            w = h * W / H;
        else
            h = w * H / W;
        bounds[0] = cx - w / 2, bounds[1] = cx + w / 2, bounds[2] = cy - h / 2, bounds[3] = cy + h / 2;
    } else {
        memcpy(bounds, L->bounds, sizeof L->bounds);
    }
    double sx = W / (bounds[1] - bounds[0]), sy = H / (bounds[3] - bounds[2]), s = sqrt(sx * sy);
    float table[FB_PALETTE_ENTRIES][4];
    fb_palette_build(&L->palette, table);
    K_LsysSeg *o = malloc((n ? n : 1) * sizeof *o);
    if (!o) return fb_fail(FB_ERR_NOMEM, "out of memory for %zu segments", n);
    for (size_t i = 0; i < n; i++) {
        double ax = (in[i].x0 - bounds[0]) * sx, ay = (bounds[3] - in[i].y0) * sy;
        double bx = (in[i].x1 - bounds[0]) * sx, by = (bounds[3] - in[i].y1) * sy;
        double len = hypot(bx - ax, by - ay);
        double t = max_depth ? (double)in[i].depth / max_depth : 0.0;
        const float *c = table[(int)lround(t * (FB_PALETTE_ENTRIES - 1))];
        o[i] = (K_LsysSeg){
            .ax = (float)ax,
            .ay = (float)ay,
            .ux = (float)(len > 0 ? (bx - ax) / len : 1.0),
            .uy = (float)(len > 0 ? (by - ay) / len : 0.0),
            .len = (float)len,
            .hw = (float)(hw_units * pow(L->taper, in[i].depth) * s),
            .r = c[0],
            .g = c[1],
            .b = c[2],
        };
    }
    *out = o;
    return FB_OK;
}

/* What the L-system keeps: its raster input (the tiles' segment lists), and on Vulkan the device's
 * copy. The rewriting and the turtle ran in init, their strings checked against the memory limit
 * before each was allocated (fb_lsys_derive). */
static uint64_t lsystem_memory(const fb_gen *g, const struct fb_engine *e, uint64_t *hold)
{
    *hold = (uint64_t)g->compute.shader.input_size * (e->kind == FB_BACKEND_VULKAN ? 2u : 1u);
    return *hold;
}

static fb_result lsystem_init(fb_gen *g)
{
    const fb_scene *sc = g->scene;
    const fb_lsystem_params *L = fb_layer_params(g->layer);
    K_LsysParams *p = (K_LsysParams *)(void *)g->params;
    memset(p, 0, sizeof *p);
    p->width = (uint32_t)sc->width;
    p->height = (uint32_t)sc->height;
    p->tiles_x = (p->width + TILE - 1) / TILE;
    p->tile_shift = TILE_SHIFT;

    char *str = NULL;
    size_t len = 0, nsegs = 0;
    fb_lsys_seg *segs = NULL;
    K_LsysSeg *px = NULL;
    int max_depth = 0;
    double bounds[4];
    char who[80];
    snprintf(who, sizeof who, "layer %s", g->layer->name);
    uint64_t tiles = (uint64_t)p->tiles_x * ((p->height + TILE - 1) / TILE);
    uint64_t max_f = tiles + 1 < MAX_INPUT_WORDS ? (MAX_INPUT_WORDS - tiles - 1) / (K_LSYS_SEG_WORDS + 1) : 1;
    fb_result rc = fb_lsys_derive(&L->sys, sc->seed, L->max_symbols, max_f, &g->run.budget, who, &str, &len);
    if (rc) return rc;
    /* Refuse a drawing the rasteriser cannot take before the turtle allocates its segments. */
    size_t nf = 0;
    for (size_t i = 0; i < len; i++) nf += str[i] == 'F';
    if (tiles + 1 + (uint64_t)nf * (K_LSYS_SEG_WORDS + 1) > MAX_INPUT_WORDS) {
        free(str);
        return fb_fail(FB_ERR_INPUT,
                       "layer %s: %zu segments (F symbols) are more than the rasteriser's %llu MiB input holds; use "
                       "fewer iterations",
                       g->layer->name, nf, (unsigned long long)(MAX_INPUT_WORDS * 4 >> 20));
    }
    rc = fb_lsys_turtle(str, len, L->sys.angle, L->heading, L->step, who, &segs, &nsegs, &max_depth);
    free(str);
    if (!rc) rc = frame_segments(g, segs, nsegs, max_depth, &px, bounds);
    free(segs);
    if (!rc) rc = build_input(g, px, nsegs);
    free(px);
    if (rc) return rc;
    if (!nsegs)
        fb_log(FB_LOG_WARN, "layer %s: the L-system draws nothing (no F in the derived string)", g->layer->name);
    fb_log(FB_LOG_INFO, "%s: %zu symbols, %zu segments, frame %g,%g,%g,%g", g->layer->name, len, nsegs, bounds[0],
           bounds[1], bounds[2], bounds[3]);

    static const char *const suffix[4] = {"A", "R", "G", "B"};
    g->store.nchannels = 4;
    for (int c = 0; c < 4; c++) {
        snprintf(g->store.channel_names[c], sizeof g->store.channel_names[c], "%s.%s", g->layer->name, suffix[c]);
        g->store.channel_types[c] = g->layer->half ? EXRIO_HALF : EXRIO_FLOAT;
    }
    g->store.preview_channel = 0; /* A */
    g->store.preview_rgb = 1;     /* R, G, B */
    g->compute.native_rows = lsystem_rows;
    g->memory = lsystem_memory;
    g->compute.shader.spv = lsys_comp;
    g->compute.shader.spv_size = sizeof lsys_comp;
    g->compute.shader.params_size = sizeof(K_LsysParams);
    g->compute.shader.push_size = sizeof(K_LsysParams) + 8;
    return FB_OK;
}

/* The plan's cost model: seconds of one core of the reference machine (docs/scenes.md). */
static fb_result lsystem_cost(const fb_scene *s, int layer, double *rows, double *total)
{
    *total = (double)s->width * s->height * 6.0e-8 /* a pixel */;
    return FB_OK;
}

const fb_gen_class fb_gen_lsystem = {
    .name = "lsystem",
    .synopsis = "lsystem [options] -o OUT.exr",
    .summary = "an L-system plant (bush, tree, ... or --axiom/--rule), one layer",
    .what = "an lsystem layer",
    .keys = lsystem_keys,
    .nkeys = FB_NKEYS(lsystem_keys),
    .params_size = sizeof(fb_lsystem_params),
    .parse = parse_lsystem,
    .init = lsystem_init,
    .share = FB_SHARE_WHOLE,
    .cost = lsystem_cost,
};
