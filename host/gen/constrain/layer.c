/*
 * The constrain layer: the FBM constraint model (constrain.c) over the whole image, on the CPU
 * in prepare (both backends give the same bits); strips are copied out.
 *
 * Channels: NAME.Y (D), NAME.macro (d), NAME.detail (D - d), NAME.T and NAME.H (the fields used),
 * and NAME.A (1 where D >= water) when a water level is given. 1D profiles (height 1) can also be
 * written as CSV (x, d, D), renamed into place after the EXR like a terrain mesh.
 */
#include "constrain.h"
#include "exrio.h"
#include "gen_constrain.h"
#include "output.h"
#include "preview.h"
#include "textin.h"

#include "heightmap.h"

#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* ---- the scene keys and their parser ---------------------------------------------------------- */

/* Constraint points (reg false: a file, or [[x, y], ...] integer pixels) or regions (a file, or [[x, y,
 * "T" or "H", value], ...]). */
static fb_result check_constraints(const fb_vctx *v, const char *path, json_t *j, bool reg)
{
    char shown[64];
    fb_json_show(j, shown, sizeof shown);
    if (json_is_string(j) && *json_string_value(j) && strlen(json_string_value(j)) < 1024) return FB_OK;
    size_t n = json_is_array(j) ? json_array_size(j) : 0;
    if (!n)
        return fb_schema_error(v, path, "expected a file name or a list %s, found %s",
                               reg ? "[[x, y, \"T\" or \"H\", value], ...]" : "[[x, y], ...]", shown);
    for (size_t i = 0; i < n; i++) {
        const json_t *pt = json_array_get(j, i);
        bool good = json_is_array(pt) && json_array_size(pt) == (reg ? 4u : 2u);
        for (size_t c = 0; good && c < 2; c++) good = json_is_integer(json_array_get(pt, c));
        if (good && reg) {
            const char *kind = json_string_value(json_array_get(pt, 2));
            const json_t *val = json_array_get(pt, 3);
            good = kind && (!strcmp(kind, "T") || !strcmp(kind, "H")) && json_is_number(val) &&
                   isfinite(json_number_value(val));
        }
        if (!good) {
            char sub[256];
            snprintf(sub, sizeof sub, "%s[%zu]", path, i);
            fb_json_show(pt, shown, sizeof shown);
            return fb_schema_error(
                v, sub, "expected %s, found %s",
                reg ? "[x, y, \"T\" or \"H\", value] with integer pixel x, y" : "[x, y] integer pixels", shown);
        }
    }
    return FB_OK;
}

static fb_result check_cpoints(const fb_vctx *v, const char *path, const fb_keyspec *k, json_t *j)
{
    return check_constraints(v, path, j, false);
}

static fb_result check_cregions(const fb_vctx *v, const char *path, const fb_keyspec *k, json_t *j)
{
    return check_constraints(v, path, j, true);
}

/* A macro shape: a built-in's name, another layer's channel, or an EXR file ("IN.exr[:layer.channel]"). */
static fb_result check_macro(const fb_vctx *v, const char *path, const fb_keyspec *k, json_t *j)
{
    fb_keyspec text = *k;
    text.type = FB_K_STRING;
    return fb_schema_check_value(v, path, &text, j);
}

static bool macro_names_file(const char *text)
{
    return strstr(text, ".exr") != NULL;
}

static const fb_kvalue macro_value = {.check = check_macro, .names_file = macro_names_file};
static const fb_kvalue cpoints_value = {.check = check_cpoints, .names_file = fb_string_names_file},
                       cregions_value = {.check = check_cregions, .names_file = fb_string_names_file};

static const fb_keyspec constrain_keys[] = {
    {"type", FB_K_TYPE, 0, 0, false, NULL, NULL, "generator: \"constrain\"", FB_CORE},
    {"name", FB_K_NAME, 0, 0, false, NULL, "\"terrain\"", "layer name; channels NAME.Y, .macro, .detail, .T, .H",
     FB_CORE},
    {"macro", FB_K_CUSTOM, 0, 0, false, NULL, NULL,
     "macro shape d: cone | ridge | boss | bowl, or IN.exr[:layer.channel] (default boss)", .value = &macro_value,
     FB_FIELD(fb_constrain_params, macro)},
    {"macro-height", FB_K_NUM, -1e6, 1e6, false, NULL, "10.0", "height of a built-in macro shape",
     FB_FIELD(fb_constrain_params, macro_height)},
    {"profile", FB_K_PATH, 0, 0, false, NULL, NULL, "1D (height 1): a CSV profile (d, or x,d per line) as the macro",
     FB_FIELD(fb_constrain_params, profile)},
    {"T", FB_K_NUM, 0, 1e6, true, NULL, "0.3", "approximation degree T > 0 (small: close to the macro shape)",
     FB_FIELD(fb_constrain_params, T)},
    {"hurst", FB_K_NUM, 0, 1, true, NULL, "0.8", "roughness degree H in (0, 1) (large: smoother)",
     FB_FIELD(fb_constrain_params, hurst)},
    {"sigma", FB_K_NUM, 0, 1e6, true, NULL, "1.0", "standard deviation of P_fbm's first level",
     FB_FIELD(fb_constrain_params, sigma)},
    {"delta", FB_K_NUM, 0, 1e6, true, NULL, "0.01", "delta of Z = 1 / (sqrt(6) sigma + delta)",
     FB_FIELD(fb_constrain_params, delta)},
    {"soften", FB_K_NUM, 0, 2.4, false, NULL, "0",
     "soften the crease of equation 10 along P's zero lines: D - d follows an odd cubic for |P| < soften sigma "
     "(0: the paper)",
     FB_FIELD(fb_constrain_params, soften)},
    {"points", FB_K_CUSTOM, 0, 0, false, NULL, NULL,
     "discrete constraints D = d: a file of x,y per line or [[x, y], ...] (pixels from the top left)",
     .value = &cpoints_value, FB_FIELD(fb_constrain_params, points)},
    {"regions", FB_K_CUSTOM, 0, 0, false, NULL, NULL,
     "continuous constraints: a file of x,y,T|H,value per line or [[x, y, \"H\", 0.95], ...]", .value = &cregions_value,
     FB_FIELD(fb_constrain_params, regions)},
    {"domain", FB_K_INT, 0, 16, false, NULL, "4", "a region reaches pixels within 2^domain (L1 distance, eq. 13)",
     FB_FIELD(fb_constrain_params, domain)},
    {"falloff", FB_K_NUM, 0, 1e6, false, NULL, "0.01", "f_d of eq. 14: fall-off with the squared distance",
     FB_FIELD(fb_constrain_params, falloff)},
    {"buffering", FB_K_ENUM, 0, 0, false, "regional|none|naive", "\"regional\"",
     "discrete constraints: regional buffering, none (zeroed when made), naive (zeroed after)",
     FB_FIELD(fb_constrain_params, buffering)},
    {"interpolation", FB_K_ENUM, 0, 0, false, "smooth|linear", "\"smooth\"",
     "P_fbm's levels: smooth stencils of 16 parents (no creases along the coarse levels' rows and columns) or the "
     "paper's midpoint / diamond-square means",
     FB_FIELD(fb_constrain_params, linear)},
    {"water", FB_K_NUM, -1e15, 1e15, false, NULL, NULL, "a water level: channel NAME.A is 1 where D >= water",
     FB_FIELD(fb_constrain_params, water)},
    {"csv", FB_K_OUTPUT, 0, 0, false, NULL, NULL, "1D: also write x, d, D per line to this CSV file",
     FB_FIELD(fb_constrain_params, csv)},
    {"plot", FB_K_OUTPUT, 0, 0, false, NULL, NULL,
     "1D: also draw d (blue), D (black) and the constraints (red) to this PNG", FB_FIELD(fb_constrain_params, plot)},
    {"heightmap", FB_K_OUTPUT, 0, 0, false, NULL, NULL,
     "also write the heights for engines: OUT.png (16-bit grey) or OUT.r16 (16-bit raw, little-endian)", FB_CORE},
    FB_HEIGHTMAP_KEYS,
    {"half", FB_K_BOOL, 0, 0, false, NULL, "false", "store the channels as half (flags: --half, --float)", FB_CORE},
    FB_COMPRESSION_KEY,
};

static fb_result parse_constrain(const fb_vctx *v, const char *path, json_t *obj, const fb_scene *s, fb_layer *L)
{
    fb_constrain_params *c = (void *)L->params;
    fb_result rc = fb_schema_check(v, path, obj, constrain_keys, FB_NKEYS(constrain_keys), "a constrain layer", c);
    if (rc) return rc;
    char sub[256];
    const json_t *macro = json_object_get(obj, "macro"), *prof = json_object_get(obj, "profile");
    if (macro && prof) {
        snprintf(sub, sizeof sub, "%s.profile", path);
        return fb_schema_error(v, sub, "give a macro or a profile, not both");
    }
    if (prof && s->height != 1) {
        snprintf(sub, sizeof sub, "%s.profile", path);
        return fb_schema_error(v, sub, "a CSV profile is a 1D macro: the scene's height must be 1 (it is %d)",
                               s->height);
    }
    for (int k = 0; k < 2; k++)
        if (json_object_get(obj, k ? "plot" : "csv") && s->height != 1) {
            snprintf(sub, sizeof sub, "%s.%s", path, k ? "plot" : "csv");
            return fb_schema_error(v, sub, "%s output is for 1D profiles: the scene's height must be 1 (it is %d)",
                                   k ? "plot" : "CSV", s->height);
        }
    if (!macro && !prof) snprintf(c->macro, sizeof c->macro, "boss");
    c->macro_ref.layer = -1;
    if (macro && !strstr(c->macro, ".exr") && strcmp(c->macro, "cone") && strcmp(c->macro, "ridge") &&
        strcmp(c->macro, "boss") && strcmp(c->macro, "bowl")) {
        /* another layer of the scene, "layer" or "layer.channel": resolved with the op layers' inputs */
        size_t len = strlen(c->macro);
        if (c->macro[0] == '.' || c->macro[len - 1] == '.' || len >= sizeof c->macro_ref.channel) {
            snprintf(sub, sizeof sub, "%s.macro", path);
            return fb_schema_error(
                v, sub,
                "expected cone, ridge, boss, bowl, IN.exr[:layer.channel] or a layer of the scene, found \"%s\"",
                c->macro);
        }
        c->macro_ref.layer = -2;
        snprintf(c->macro_ref.channel, sizeof c->macro_ref.channel, "%s", c->macro);
    }
    if (c->hurst >= 1) {
        snprintf(sub, sizeof sub, "%s.hurst", path);
        return fb_schema_error(v, sub, "expected a roughness H in (0, 1), found %g", c->hurst);
    }
    c->has_water = json_object_get(obj, "water") != NULL;
    const json_t *pts = json_object_get(obj, "points"), *regs = json_object_get(obj, "regions");
    c->points_inline = pts && json_is_array(pts); /* else the fields hold the files */
    c->regions_inline = regs && json_is_array(regs);
    /* inline points and regions: inside the image; region values in range */
    for (size_t i = 0; c->points_inline && i < json_array_size(pts); i++) {
        const json_t *p = json_array_get(pts, i);
        long long x = json_integer_value(json_array_get(p, 0)), y = json_integer_value(json_array_get(p, 1));
        if (x < 0 || y < 0 || x >= s->width || y >= s->height) {
            snprintf(sub, sizeof sub, "%s.points[%zu]", path, i);
            return fb_schema_error(v, sub, "pixel (%lld, %lld) is outside the %d x %d image", x, y, s->width,
                                   s->height);
        }
    }
    for (size_t i = 0; c->regions_inline && i < json_array_size(regs); i++) {
        const json_t *p = json_array_get(regs, i);
        long long x = json_integer_value(json_array_get(p, 0)), y = json_integer_value(json_array_get(p, 1));
        bool is_h = !strcmp(json_string_value(json_array_get(p, 2)), "H");
        double val = json_number_value(json_array_get(p, 3));
        snprintf(sub, sizeof sub, "%s.regions[%zu]", path, i);
        if (x < 0 || y < 0 || x >= s->width || y >= s->height)
            return fb_schema_error(v, sub, "pixel (%lld, %lld) is outside the %d x %d image", x, y, s->width,
                                   s->height);
        if (is_h ? !(val > 0 && val < 1) : !(val > 0))
            return fb_schema_error(v, sub, "%s = %g is out of range (%s)", is_h ? "H" : "T", val,
                                   is_h ? "0 < H < 1" : "T > 0");
    }
    return FB_OK;
}

/* ---- the layer --------------------------------------------------------------------------------- */

static fb_result constrain_resolve(fb_gen *g, const fb_gen *const *gens, const int *plane_offset);

typedef struct constrain_state {
    float *macro;
    fb_cpoint *points;
    int npoints;
    fb_cregion *regions;
    int nregions;
    fb_constrain_out out;
    /* the macro shape from another layer's channel (resolve); .gen NULL: none */
    fb_source macro_src;
} constrain_state;

static constrain_state *state(const fb_gen *g)
{
    return g->owned;
}

static void constrain_fini(fb_gen *g)
{
    constrain_state *s = state(g);
    if (!s) return;
    free(s->macro);
    free(s->points);
    free(s->regions);
    free(s->out.D);
    free(s->out.T);
    free(s->out.H);
    free(s->out.P);
}

/* ---- inputs --------------------------------------------------------------------------------- */

/* Calls fn on each data line of a text file (textin.h: comments, blank lines and a header line by
 * its form skipped; fields split at commas and/or blanks); fn returns an error message or NULL. */
static fb_result each_line(const char *path, const char *what, const char *(*fn)(void *ctx, char **f, int nf),
                           void *ctx)
{
    fb_lines in;
    fb_result rc = fb_lines_open(&in, path, what);
    if (rc) return rc;
    char *fields[8];
    int nf, got;
    while (!rc && (got = fb_lines_next(&in, fields, 7, &nf)) > 0) {
        const char *err = fn(ctx, fields, nf);
        if (err) rc = fb_fail(FB_ERR_INPUT, "%s:%d: %s", path, in.lineno, err);
    }
    if (!rc && got < 0) rc = FB_ERR_INPUT;
    if (!rc && in.contents - in.header == 0) /* an empty set is a mistake, not a bake with nothing asked */
        rc = fb_fail(FB_ERR_INPUT, "%s: no %s in the file (%s)", path, what,
                     in.header ? "a header and no data line" : "no data line");
    fb_lines_close(&in);
    return rc;
}

static bool number(const char *s, double *out)
{
    return fb_text_number(s, out) && isfinite(*out);
}

typedef struct reader {
    constrain_state *s;
    const fb_scene *sc;
    double *xs, *ds; /* a profile */
    int n, cap;
} reader;

static bool grow(reader *r, size_t elem, void **arr)
{
    if (r->n < r->cap) return true;
    int cap = r->cap ? 2 * r->cap : 64;
    void *a = realloc(*arr, (size_t)cap * elem);
    if (!a) return false;
    *arr = a;
    r->cap = cap;
    return true;
}

static const char *pixel_of(const reader *r, char **f, int *x, int *y)
{
    double vx, vy;
    if (!number(f[0], &vx) || !number(f[1], &vy)) return "expected a number for x and y";
    if (vx != floor(vx) || vy != floor(vy)) return "x and y are pixels: whole numbers";
    if (vx < 0 || vy < 0 || vx >= r->sc->width || vy >= r->sc->height) return "the pixel is outside the image";
    *x = (int)vx, *y = (int)vy;
    return NULL;
}

static const char *point_line(void *ctx, char **f, int nf)
{
    reader *r = ctx;
    if (nf != 2) return "expected x,y (a number each)";
    int x, y;
    const char *e = pixel_of(r, f, &x, &y);
    if (e) return e;
    if (!grow(r, sizeof *r->s->points, (void **)&r->s->points)) return "out of memory";
    r->s->points[r->n++] = (fb_cpoint){x, y};
    return NULL;
}

static const char *region_line(void *ctx, char **f, int nf)
{
    reader *r = ctx;
    if (nf != 4) return "expected x,y,T|H,value (number, number, T or H, number)";
    int x, y;
    double val;
    const char *e = pixel_of(r, f, &x, &y);
    if (e) return e;
    bool is_h = !strcmp(f[2], "H");
    if (!is_h && strcmp(f[2], "T")) return "the third field must be T or H";
    if (!number(f[3], &val)) return "expected a number for the value";
    if (is_h ? !(val > 0 && val < 1) : !(val > 0)) return is_h ? "H must be in (0, 1)" : "T must be > 0";
    if (!grow(r, sizeof *r->s->regions, (void **)&r->s->regions)) return "out of memory";
    r->s->regions[r->n++] = (fb_cregion){x, y, is_h, val};
    return NULL;
}

static const char *profile_line(void *ctx, char **f, int nf)
{
    reader *r = ctx;
    double x = r->n, d;
    if (nf > 2) return "expected d, or x,d";
    if ((nf == 2 && !number(f[0], &x)) || !number(f[nf - 1], &d)) return "expected a number";
    if (r->n && x <= r->xs[r->n - 1]) return "x must increase from line to line";
    if (r->n >= r->cap) {
        int cap = r->cap ? 2 * r->cap : 64;
        double *a = realloc(r->xs, (size_t)cap * sizeof *a), *b = a ? realloc(r->ds, (size_t)cap * sizeof *b) : NULL;
        if (a) r->xs = a;
        if (!b) return "out of memory";
        r->ds = b;
        r->cap = cap;
    }
    r->xs[r->n] = x, r->ds[r->n] = d;
    r->n++;
    return NULL;
}

/* The macro shape from "IN.exr[:layer.channel]": one channel of the scene's size. */
static fb_result macro_from_exr(const fb_gen *g, const char *spec, float *out)
{
    char path[1024], chan[256] = "";
    const char *colon = strstr(spec, ".exr:");
    snprintf(path, sizeof path, "%.*s", colon ? (int)(colon + 4 - spec) : (int)strlen(spec), spec);
    if (colon) snprintf(chan, sizeof chan, "%s", colon + 5);
    exrio_reader *r = NULL;
    fb_result rc = exrio_open(path, &r);
    if (rc) return rc;
    int c = -1, n = exrio_nchannels(r);
    if (chan[0]) {
        c = exrio_find_channel(r, chan);
        if (c < 0) rc = fb_fail(FB_ERR_INPUT, "%s: no channel %s", path, chan);
    } else {
        for (int i = 0; i < n; i++) {
            size_t len = strlen(exrio_channel_name(r, i));
            if (n == 1 || (len >= 2 && !strcmp(exrio_channel_name(r, i) + len - 2, ".Y"))) c = c < 0 ? i : -2;
        }
        if (c < 0) rc = fb_fail(FB_ERR_INPUT, "%s: name the channel of the macro shape: %s:layer.channel", path, path);
    }
    if (!rc && (exrio_width(r) != g->scene->width || exrio_height(r) != g->scene->height))
        rc = fb_fail(FB_ERR_INPUT, "%s: %d x %d, but the scene is %d x %d (the macro shape must match)", path,
                     exrio_width(r), exrio_height(r), g->scene->width, g->scene->height);
    if (!rc && exrio_channel_type(r, c) == EXRIO_UINT)
        rc = fb_fail(FB_ERR_INPUT, "%s: channel %s holds integers, not heights", path, exrio_channel_name(r, c));
    void **planes = rc ? NULL : calloc((size_t)n, sizeof *planes);
    if (!rc && !planes) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    if (!rc) {
        planes[c] = out;
        rc = exrio_read_rows(r, 0, g->scene->height, planes);
    }
    for (size_t i = 0; !rc && i < (size_t)g->scene->width * g->scene->height; i++)
        if (!isfinite(out[i])) rc = fb_fail(FB_ERR_INPUT, "%s: the macro shape has a NaN or infinite value", path);
    free(planes);
    exrio_close(&r);
    return rc;
}

/* The inline "points" or "regions" array of this layer in the canonical scene. */
static json_t *inline_array(const fb_gen *g, json_t *root, const char *key)
{
    return json_object_get(json_array_get(json_object_get(root, "layers"), (size_t)(g->layer - g->scene->layers)), key);
}

static fb_result read_inputs(fb_gen *g, constrain_state *s)
{
    const fb_constrain_params *P = fb_layer_params(g->layer);
    const fb_scene *sc = g->scene;
    size_t n = (size_t)sc->width * sc->height;
    fb_result rc = FB_OK;
    if (!(s->macro = malloc(n * sizeof *s->macro))) return fb_fail(FB_ERR_NOMEM, "out of memory");
    if (P->profile[0]) {
        reader r = {.s = s, .sc = sc};
        rc = each_line(P->profile, "profile", profile_line, &r);
        if (!rc && r.n < 2) rc = fb_fail(FB_ERR_INPUT, "%s: a profile needs at least two values", P->profile);
        for (int x = 0; !rc && x < sc->width; x++) { /* linear resampling of x onto the pixels */
            double u = r.xs[0] + (r.xs[r.n - 1] - r.xs[0]) * (sc->width > 1 ? (double)x / (sc->width - 1) : 0);
            int k = 0;
            while (k + 2 < r.n && r.xs[k + 1] < u) k++;
            double t = (u - r.xs[k]) / (r.xs[k + 1] - r.xs[k]);
            s->macro[x] = (float)(r.ds[k] + (r.ds[k + 1] - r.ds[k]) * t);
        }
        free(r.xs);
        free(r.ds);
    } else if (P->macro_ref.layer != -1) {
        /* another layer: read in prepare, once that layer is computed */
    } else if (strstr(P->macro, ".exr")) {
        rc = macro_from_exr(g, P->macro, s->macro);
    } else {
        fb_constrain_macro(P->macro, sc->width, sc->height, P->macro_height, s->macro);
    }
    json_t *root = (P->points_inline || P->regions_inline) ? json_loads(sc->json, 0, NULL) : NULL;
    if (!rc && P->points_inline) {
        json_t *a = inline_array(g, root, "points");
        s->npoints = (int)json_array_size(a);
        if (!(s->points = malloc((size_t)s->npoints * sizeof *s->points))) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
        for (int i = 0; !rc && i < s->npoints; i++)
            s->points[i] = (fb_cpoint){(int)json_integer_value(json_array_get(json_array_get(a, (size_t)i), 0)),
                                       (int)json_integer_value(json_array_get(json_array_get(a, (size_t)i), 1))};
    } else if (!rc && P->points[0]) {
        reader r = {.s = s, .sc = sc};
        rc = each_line(P->points, "constraint points", point_line, &r);
        s->npoints = r.n;
    }
    if (!rc && P->regions_inline) {
        json_t *a = inline_array(g, root, "regions");
        s->nregions = (int)json_array_size(a);
        if (!(s->regions = malloc((size_t)s->nregions * sizeof *s->regions)))
            rc = fb_fail(FB_ERR_NOMEM, "out of memory");
        for (int i = 0; !rc && i < s->nregions; i++) {
            const json_t *e = json_array_get(a, (size_t)i);
            s->regions[i] = (fb_cregion){
                (int)json_integer_value(json_array_get(e, 0)), (int)json_integer_value(json_array_get(e, 1)),
                !strcmp(json_string_value(json_array_get(e, 2)), "H"), json_number_value(json_array_get(e, 3))};
        }
    } else if (!rc && P->regions[0]) {
        reader r = {.s = s, .sc = sc};
        rc = each_line(P->regions, "regions", region_line, &r);
        s->nregions = r.n;
    }
    json_decref(root);
    return rc;
}

/* ---- 1D plot ------------------------------------------------------------------------------------ */

static void dot(uint8_t *img, int w, int h, int x, int y, const uint8_t c[3])
{
    if (x < 0 || y < 0 || x >= w || y >= h) return;
    memcpy(img + 3 * ((size_t)y * w + x), c, 3);
}

/* d in blue, D in black (one line segment per pixel column), constraints as red crosses. */
static fb_result write_plot(const constrain_state *s, int n, const char *path)
{
    const int w = n < 256 ? 256 : n > 4096 ? 4096 : n, h = 240, m = 10;
    uint8_t *img = malloc((size_t)w * h * 3);
    if (!img) return fb_fail(FB_ERR_NOMEM, "out of memory");
    memset(img, 255, (size_t)w * h * 3);
    double lo = INFINITY, hi = -INFINITY;
    for (int i = 0; i < n; i++) {
        lo = fmin(lo, fmin(s->macro[i], s->out.D[i]));
        hi = fmax(hi, fmax(s->macro[i], s->out.D[i]));
    }
    if (!(hi > lo)) hi = lo + 1;
    static const uint8_t blue[3] = {40, 90, 220}, black[3] = {0, 0, 0}, red[3] = {220, 30, 30};
    for (int pass = 0; pass < 2; pass++) {
        const float *v = pass ? s->out.D : s->macro;
        int prev = -1;
        for (int px = 0; px < w; px++) {
            double u = n > 1 ? (double)px * (n - 1) / (w - 1) : 0;
            int i = (int)u;
            double t = u - i, val = i + 1 < n ? v[i] + (v[i + 1] - v[i]) * t : v[i];
            int py = h - 1 - m - (int)lrint((val - lo) / (hi - lo) * (h - 1 - 2 * m));
            int a = prev < 0 ? py : prev, b = py;
            for (int y = a < b ? a : b; y <= (a < b ? b : a); y++) dot(img, w, h, px, y, pass ? black : blue);
            prev = py;
        }
    }
    for (int k = 0; k < s->npoints; k++) {
        int px = n > 1 ? (int)lrint((double)s->points[k].x * (w - 1) / (n - 1)) : 0;
        int py = h - 1 - m - (int)lrint((s->out.D[s->points[k].x] - lo) / (hi - lo) * (h - 1 - 2 * m));
        for (int e = -3; e <= 3; e++) dot(img, w, h, px + e, py + e, red), dot(img, w, h, px + e, py - e, red);
    }
    fb_result rc = fb_png_write_rgb(path, "plot", w, h, img);
    free(img);
    return rc;
}

/* ---- prepare and rows ----------------------------------------------------------------------- */

static fb_result constrain_prepare(fb_gen *g, struct fb_engine *e, bool progress)
{
    (void)e, (void)progress;
    constrain_state *s = state(g);
    const fb_constrain_params *P = fb_layer_params(g->layer);
    const fb_scene *sc = g->scene;
    fb_constrain_desc d = {.width = sc->width,
                           .height = sc->height,
                           .seed = sc->seed,
                           .hurst = P->hurst,
                           .T = P->T,
                           .sigma = P->sigma,
                           .delta = P->delta,
                           .soften = P->soften,
                           .macro = s->macro,
                           .points = s->points,
                           .npoints = s->npoints,
                           .regions = s->regions,
                           .nregions = s->nregions,
                           .domain = P->domain,
                           .falloff = P->falloff,
                           .buffering = (fb_buffering)P->buffering,
                           .linear = P->linear};
    double t0 = fb_now();
    fb_result rc = FB_OK;
    if (s->macro_src.gen) rc = fb_source_read(&s->macro_src, g, "macro", s->macro);
    if (!rc) rc = fb_constrain_run(&d, false, &s->out);
    if (rc) return rc;
    double secs = fb_now() - t0, maxdev = 0;
    for (size_t i = 0; i < (size_t)sc->width * sc->height; i++) maxdev = fmax(maxdev, fabs(s->out.D[i] - s->macro[i]));
    /* Both go through the output transaction (output.h): renamed with the EXR when the run succeeds. */
    if (P->csv[0]) {
        FILE *f = NULL;
        if ((rc = fb_output_fopen(P->csv, "csv", (void **)&f))) return rc;
        fprintf(f, "x,d,D\n");
        for (int x = 0; x < sc->width; x++) fprintf(f, "%d,%.9g,%.9g\n", x, s->macro[x], s->out.D[x]);
        bool bad = ferror(f) != 0;
        if (fclose(f) != 0 || bad) rc = fb_fail(FB_ERR_IO, "%s: cannot write the csv: %s", P->csv, strerror(errno));
        if ((rc = fb_output_done(P->csv, rc))) return rc;
    }
    if (P->plot[0] && (rc = write_plot(s, sc->width, P->plot))) return rc;
    snprintf(g->prepared.summary, sizeof g->prepared.summary,
             "layer %s (constrain): %d x %d, %d discrete and %d continuous constraints, T %.3g, H %.3g; max |D - d| "
             "%.4g; %.3f s%s%.150s%s%.150s",
             g->layer->name, sc->width, sc->height, s->npoints, s->nregions, P->T, P->hurst, maxdev, secs,
             P->csv[0] ? "; csv " : "", P->csv, P->plot[0] ? "; plot " : "", P->plot);
    snprintf(g->prepared.summary_json, sizeof g->prepared.summary_json,
             "{\"layer\": \"%s\", \"generator\": \"constrain\", \"width\": %d, \"height\": %d, \"points\": %d, "
             "\"regions\": %d, \"max_deviation\": %.9g, \"seconds\": %.6f}",
             g->layer->name, sc->width, sc->height, s->npoints, s->nregions, maxdev, secs);
    return FB_OK;
}

static void constrain_rows(const fb_gen *g, int y0, int n, void *const *planes)
{
    const constrain_state *s = state(g);
    size_t at = (size_t)y0 * g->scene->width, len = (size_t)n * g->scene->width;
    float *Y = planes[0], *M = planes[1], *Dt = planes[2];
    for (size_t i = 0; i < len; i++) {
        Y[i] = s->out.D[at + i];
        M[i] = s->macro[at + i];
        Dt[i] = s->out.D[at + i] - s->macro[at + i];
    }
    memcpy(planes[3], s->out.T + at, len * 4);
    memcpy(planes[4], s->out.H + at, len * 4);
    if (g->store.nchannels > 5)
        for (size_t i = 0; i < len; i++)
            ((float *)planes[5])[i] =
                s->out.D[at + i] >= ((const fb_constrain_params *)fb_layer_params(g->layer))->water;
}

/* The model's arrays (constrain.c): the grid of N x N nodes (N = 2^k + 1 >= the longer side, 4
 * bytes each), the H and T fields, the macro shape and the result D (4 bytes a pixel each); H, T,
 * the macro and D are kept for the strips. */
static uint64_t constrain_memory(const fb_gen *g, const struct fb_engine *e, uint64_t *hold)
{
    (void)e;
    const fb_scene *sc = g->scene;
    uint64_t side = (uint64_t)(sc->width > sc->height ? sc->width : sc->height), N = 2;
    while (N - 1 < side - 1 || N < 3) N = 2 * (N - 1) + 1;
    uint64_t npx = (uint64_t)sc->width * sc->height, nodes = sc->height > 1 ? N * N : N;
    *hold = 16 * npx;
    return 4 * nodes + 16 * npx;
}

static fb_result constrain_init(fb_gen *g)
{
    uint64_t hold, peak = constrain_memory(g, NULL, &hold);
    char who[96]; /* checked before the macro shape, 4 bytes a pixel, is allocated */
    snprintf(who, sizeof who, "layer %s", g->layer->name);
    fb_result mrc = fb_memory_check(&g->run.budget, peak, who);
    if (mrc) return mrc;
    constrain_state *s = calloc(1, sizeof *s);
    if (!s) return fb_fail(FB_ERR_NOMEM, "out of memory");
    g->owned = s;
    g->fini = constrain_fini;
    fb_result rc = read_inputs(g, s);
    if (rc) return rc;
    static const char *const suffix[6] = {"Y", "macro", "detail", "T", "H", "A"};
    g->store.nchannels = ((const fb_constrain_params *)fb_layer_params(g->layer))->has_water ? 6 : 5;
    for (int c = 0; c < g->store.nchannels; c++) {
        snprintf(g->store.channel_names[c], sizeof g->store.channel_names[c], "%s.%s", g->layer->name, suffix[c]);
        g->store.channel_types[c] = g->layer->half || c == 5 ? EXRIO_HALF : EXRIO_FLOAT;
    }
    g->store.preview_channel = 0;
    if (g->scene->height > 1) { /* the preview: a hillshade, the grid taken as 40 units across */
        int side = g->scene->width > g->scene->height ? g->scene->width : g->scene->height;
        g->store.preview_shade[0] = g->store.preview_shade[1] = 40.0 / side;
    }
    g->compute.native_rows = constrain_rows;
    g->prepare = constrain_prepare;
    g->memory = constrain_memory;
    g->resolve = constrain_resolve;
    g->prepared.gpu_seconds = -1;
    return FB_OK;
}

/* The macro shape from another layer: its channel, found once every layer's generator is set up
 * (the bake then prepares the source first). */
static fb_result constrain_resolve(fb_gen *g, const fb_gen *const *gens, const int *plane_offset)
{
    const fb_constrain_params *P = fb_layer_params(g->layer);
    const fb_ref *m = &P->macro_ref;
    if (m->layer < 0) return FB_OK;
    return fb_source_find(&state(g)->macro_src, g, gens, m, "macro", "bake it, then give IN.exr:layer.Y");
}

static int constrain_refs(fb_layer *L, fb_ref_slot *out)
{
    fb_constrain_params *P = (void *)L->params;
    if (P->macro_ref.layer == -1) return 0;
    out[0] = (fb_ref_slot){&P->macro_ref, "macro", "cone, ridge, boss, bowl, IN.exr[:layer.channel]"};
    return 1;
}

static int constrain_outputs(const fb_layer *L, const char **paths, const char **what, int max)
{
    const fb_constrain_params *P = fb_layer_params(L);
    int n = 0;
    if (P->csv[0] && n < max) paths[n] = P->csv, what[n++] = "csv";
    if (P->plot[0] && n < max) paths[n] = P->plot, what[n++] = "plot";
    return n;
}

/* The plan's cost model: seconds of one core of the reference machine (docs/scenes.md). */
static fb_result constrain_cost(const fb_scene *s, int layer, double *rows, double *total)
{
    *total = (double)s->width * s->height * 6.0e-8 /* a pixel */;
    return FB_OK;
}

const fb_gen_class fb_gen_constrain = {
    .name = "constrain",
    .synopsis = "constrain [options] -o OUT.exr",
    .summary = "fBm detail on a macro shape under discrete/continuous constraints",
    .what = "a constrain layer",
    .keys = constrain_keys,
    .nkeys = FB_NKEYS(constrain_keys),
    .params_size = sizeof(fb_constrain_params),
    .parse = parse_constrain,
    .refs = constrain_refs,
    .outputs = constrain_outputs,
    .init = constrain_init,
    .share = FB_SHARE_WHOLE,
    .cost = constrain_cost,
    .bench = fb_constrain_bench,
};
