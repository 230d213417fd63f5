/*
 * Scenes: a JSON file, the embedded default or a command line's JSON, parsed and validated into an
 * fb_scene: the scene's own keys, then each layer by its generator's table (schema.c) and parse,
 * the references between layers resolved and ordered, --set overrides applied first (sets.c).
 * Nothing here knows a generator by name: they come from the list (fb_gen_list).
 */
#include "scene.h"

#include "gen.h"
#include "heightmap.h"
#include "jsonout.h"
#include "schema.h"
#include "textin.h"

#include <jansson.h>

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

static const fb_keyspec scene_keys[] = {
    {"size", FB_K_SIZE, 1, FB_MAX_DIM, false, NULL, "[1024, 1024]", "image size in pixels (flag: --size WxH)"},
    {"seed", FB_K_INT, 0, 4294967295.0, false, NULL, "1", "random seed"},
    {"compression", FB_K_ENUM, 0, 0, false, EXRIO_COMPRESSION_NAMES, "\"zip\"", "EXR compression"},
    {"parts", FB_K_ENUM, 0, 0, false, "single|per-layer", "\"single\"",
     "one EXR part with every layer, or one part per layer (multi-part; each may have its own compression)"},
    {"frames", FB_K_STRING, 0, 0, false, NULL, NULL,
     "a sequence: frames A-B or A-B:STEP, each baked at its time into -o NAME.%04d.exr (flam3-animate's begin, "
     "end, dtime)"},
    {"layers", FB_K_LAYERS, 1, FB_MAX_LAYERS, false, NULL, NULL, "the layers, each a generator"},
};

const fb_keyspec *fb_scene_keys(int *n)
{
    *n = FB_NKEYS(scene_keys);
    return scene_keys;
}

/* The references of layer i to other layers, as its generator lists them. */
static int layer_refs(fb_scene *s, int i, fb_ref_slot *out)
{
    fb_layer *L = &s->layers[i];
    return L->cls && L->cls->refs ? L->cls->refs(L, out) : 0;
}

/* Resolves the references between layers to layer indices and orders the layers so that each comes
 * after those it uses; a missing layer or a cycle is an error that names both layers. */
static fb_result resolve_refs(const fb_vctx *v, fb_scene *s)
{
    char sub[128], names[FB_MAX_LAYERS * 66];
    fb_ref_slot refs[FB_MAX_REFS];
    fb_scene_layer_names(s, names, sizeof names);
    for (int i = 0; i < s->nlayers; i++) {
        int nr = layer_refs(s, i, refs);
        for (int k = 0; k < nr; k++) {
            fb_ref *r = refs[k].ref;
            if (r->layer != -2) continue;
            char name[128];
            snprintf(name, sizeof name, "%s", r->channel);
            char *dot = strchr(name, '.');
            if (dot) *dot = 0;
            r->layer = -1;
            for (int j = 0; j < s->nlayers; j++)
                if (!strcmp(s->layers[j].name, name)) r->layer = j;
            snprintf(sub, sizeof sub, "layers[%d].%s", i, refs[k].key);
            if (r->layer < 0 && refs[k].expected)
                return fb_schema_error(v, sub, "\"%s\" is not %s or a layer of the scene (layers: %s)", r->channel,
                                       refs[k].expected, names);
            if (r->layer < 0)
                return fb_schema_error(v, sub,
                                       "layer \"%s\" refers to \"%s\", but no layer is named \"%s\" (layers: %s)",
                                       s->layers[i].name, r->channel, name, names);
            snprintf(r->channel, sizeof r->channel, "%s", dot ? dot + 1 : ""); /* name was a copy */
        }
    }
    /* depth-first topological order; state 1: on the stack, 2: placed */
    int state[FB_MAX_LAYERS] = {0}, n = 0;
    int stack[FB_MAX_LAYERS], next[FB_MAX_LAYERS], top = 0;
    for (int root = 0; root < s->nlayers; root++) {
        if (state[root]) continue;
        stack[top] = root, next[top++] = 0, state[root] = 1;
        while (top) {
            int cur = stack[top - 1];
            int nr = layer_refs(s, cur, refs);
            if (next[top - 1] >= nr) {
                state[cur] = 2;
                s->order[n++] = cur;
                top--;
                continue;
            }
            const fb_ref *r = refs[next[top - 1]++].ref;
            if (r->layer < 0 || state[r->layer] == 2) continue;
            if (state[r->layer] == 1) {
                snprintf(sub, sizeof sub, "layers[%d]", cur);
                return fb_schema_error(v, sub, "layer \"%s\" uses layer \"%s\", which depends on \"%s\": a cycle",
                                       s->layers[cur].name, s->layers[r->layer].name, s->layers[cur].name);
            }
            stack[top] = r->layer, next[top++] = 0, state[r->layer] = 1;
        }
    }
    return FB_OK;
}

/* "tiles": [columns, rows], each a whole number in the key's range; the flag's "NxM". */
static fb_result check_tiles(const fb_vctx *v, const char *path, const fb_keyspec *k, json_t *j)
{
    char shown[64];
    fb_json_show(j, shown, sizeof shown);
    bool good = json_is_array(j) && json_array_size(j) == 2;
    for (size_t i = 0; good && i < 2; i++) {
        const json_t *e = json_array_get(j, i);
        good = json_is_integer(e) && json_integer_value(e) >= k->lo && json_integer_value(e) <= k->hi;
    }
    if (!good)
        return fb_schema_error(v, path, "expected [columns, rows], each a whole number in %g..%g, found %s", k->lo,
                               k->hi, shown);
    return FB_OK;
}

static json_t *tiles_from_flag(const fb_keyspec *k, const char *flag, const char *text)
{
    char *end;
    long c = strtol(text, &end, 10), r = 0;
    bool good = end != text && (*end == 'x' || *end == 'X');
    if (good) {
        const char *rs = end + 1;
        r = strtol(rs, &end, 10);
        good = end != rs && !*end && c >= k->lo && c <= k->hi && r >= k->lo && r <= k->hi;
    }
    if (!good) {
        fb_fail(FB_ERR_USAGE, "--%s: expected COLUMNSxROWS such as 4x4, each 1 to %g, found \"%s\"", flag, k->hi, text);
        return NULL;
    }
    return json_pack("[ii]", (int)c, (int)r);
}

const fb_kvalue fb_tiles_value = {.check = check_tiles, .from_flag = tiles_from_flag};

/* "tiles": the heightmap's split, checked against its size and the engine's sizes, and the names of
 * its files. */
static fb_result parse_tiles(const fb_vctx *v, const char *path, const json_t *lj, const fb_scene *s, fb_layer *L)
{
    const json_t *t = json_object_get(lj, "tiles");
    if (!t) return FB_OK;
    char sub[96], msg[512];
    snprintf(sub, sizeof sub, "%s.tiles", path);
    if (!L->heightmap[0]) return fb_schema_error(v, sub, "tiles of a heightmap, and no \"heightmap\" is written");
    int cols = (int)json_integer_value(json_array_get(t, 0)), rows = (int)json_integer_value(json_array_get(t, 1));
    fb_heightmap_format f = FB_HEIGHTMAP_PNG16;
    fb_heightmap_format_of(L->heightmap, &f);
    if (!fb_heightmap_tiles_check(L->heightmap_engine, s->width, s->height, cols, rows, f, msg, sizeof msg))
        return fb_schema_error(v, sub, "%s (the image is %d x %d)", msg, s->width, s->height);
    if (!(L->tile_paths = malloc((size_t)cols * rows * FB_TILE_PATH))) return fb_fail(FB_ERR_NOMEM, "out of memory");
    for (int r = 0; r < rows; r++)
        for (int c = 0; c < cols; c++)
            fb_heightmap_tile_path(L->heightmap, L->heightmap_engine, c, r, rows,
                                   L->tile_paths + ((size_t)r * cols + c) * FB_TILE_PATH, FB_TILE_PATH);
    L->tiles[0] = cols, L->tiles[1] = rows;
    return FB_OK;
}

/* The keys every height-producing generator shares (heightmap, heightmap-engine, heightmap-range, tiles), read into L;
 * their types were checked against the generator's table. A GeoTIFF needs world coordinates, which only a generator
 * with a "crs" key has (terrain). */
static fb_result parse_heightmap(const fb_vctx *v, const char *path, const json_t *lj, const fb_scene *s, fb_layer *L)
{
    char sub[96];
    const char *hm = json_string_value(json_object_get(lj, "heightmap"));
    if (hm) {
        fb_heightmap_format f;
        snprintf(sub, sizeof sub, "%s.heightmap", path);
        if (strlen(hm) >= sizeof L->heightmap - 1)
            return fb_schema_error(v, sub, "file name longer than %zu characters", sizeof L->heightmap - 2);
        if (!fb_heightmap_format_of(hm, &f))
            return fb_schema_error(v, sub,
                                   "\"%s\": the format comes from the extension: .png (16-bit grey), .r16 "
                                   "(16-bit raw)%s",
                                   hm, fb_key_find(L->cls->keys, L->cls->nkeys, "crs") ? " or .tif (GeoTIFF)" : "");
        if (f == FB_HEIGHTMAP_GEOTIFF && !fb_key_find(L->cls->keys, L->cls->nkeys, "crs"))
            return fb_schema_error(v, sub,
                                   "\"%s\": a GeoTIFF needs world coordinates, which %s has not (a terrain "
                                   "layer has): write .png or .r16",
                                   hm, L->cls->what);
        snprintf(L->heightmap, sizeof L->heightmap, "%s", hm);
    }
    const char *engine = json_string_value(json_object_get(lj, "heightmap-engine"));
    if (engine) {
        char msg[256];
        fb_heightmap_format f = FB_HEIGHTMAP_PNG16;
        snprintf(sub, sizeof sub, "%s.heightmap-engine", path);
        if (!hm) return fb_schema_error(v, sub, "a preset for a heightmap, and no \"heightmap\" is written");
        fb_heightmap_format_of(hm, &f);
        L->heightmap_engine = (int)fb_heightmap_engine_parse(engine);
        if (!json_object_get(lj, "tiles") && /* with tiles, each tile's size is the engine's */
            !fb_heightmap_engine_check(L->heightmap_engine, s->width, s->height, f, msg, sizeof msg))
            return fb_schema_error(v, sub, "%s (the image is %d x %d)", msg, s->width, s->height);
        fb_heightmap_sidecar_path(hm, L->heightmap_sidecar, sizeof L->heightmap_sidecar);
    }
    if (json_object_get(lj, "heightmap-range")) {
        fb_json_vec2(lj, "heightmap-range", L->heightmap_range);
        L->heightmap_range_set = true;
        snprintf(sub, sizeof sub, "%s.heightmap-range", path);
        if (!(L->heightmap_range[0] < L->heightmap_range[1]))
            return fb_schema_error(v, sub, "expected LO,HI with LO < HI, found %g,%g", L->heightmap_range[0],
                                   L->heightmap_range[1]);
        if (!hm) return fb_schema_error(v, sub, "a range for a heightmap, and no \"heightmap\" is written");
    }
    return parse_tiles(v, path, lj, s, L);
}

/* The mapping a layer declares with its "mapping" key, where its class's table has one (gen.h). */
static exrio_envmap layer_envmap_key(const fb_layer *L, const json_t *lj)
{
    if (!fb_key_find(L->cls->keys, L->cls->nkeys, "mapping")) return EXRIO_ENVMAP_NONE;
    const char *m = json_string_value(json_object_get(lj, "mapping"));
    if (m && !strcmp(m, "latlong")) return EXRIO_ENVMAP_LATLONG;
    if (m && !strcmp(m, "cube")) return EXRIO_ENVMAP_CUBE;
    return EXRIO_ENVMAP_NONE;
}

static const char *envmap_words(exrio_envmap e)
{
    return e == EXRIO_ENVMAP_LATLONG ? "a lat-long environment map"
           : e == EXRIO_ENVMAP_CUBE  ? "a cube environment map"
                                     : "a plane";
}

/* Where a layer's mapping comes from, for messages: its "mapping" key, or the layer. */
static void envmap_path(const fb_scene *s, int i, char *out, size_t size)
{
    const fb_layer *L = &s->layers[i];
    bool key = fb_key_find(L->cls->keys, L->cls->nkeys, "mapping") != NULL;
    snprintf(out, size, "layers[%d]%s", i, key ? ".mapping" : "");
}

/* An environment map's size (2N x N lat-long, N x 6N cube, as OpenEXR's ImfEnvmap.h lays them out);
 * the message names the nearest valid size (least squares in both sides). */
static fb_result check_envmap_size(const fb_vctx *v, const fb_scene *s)
{
    int w = s->width, h = s->height;
    bool ll = s->envmap == EXRIO_ENVMAP_LATLONG;
    if (s->envmap == EXRIO_ENVMAP_NONE || (ll ? w == 2 * h : h == 6 * w)) return FB_OK;
    long n = lround(ll ? (2.0 * w + h) / 5.0 : (w + 6.0 * h) / 37.0);
    long lim = ll ? FB_MAX_DIM / 2 : FB_MAX_DIM / 6;
    n = n < 1 ? 1 : n > lim ? lim : n;
    return fb_schema_error(v, "size", "%s is %s pixels%s, found %d x %d: the nearest is %ld x %ld",
                           envmap_words(s->envmap), ll ? "2N x N" : "N x 6N", ll ? "" : " (six faces stacked)", w, h,
                           ll ? 2 * n : n, ll ? n : 6 * n);
}

/* Each layer's mapping (a layer of an envmap_of_refs class takes its inputs'), then the file's: every
 * layer's, which must agree, since a file has one envmap attribute; then its size. */
static fb_result check_envmaps(const fb_vctx *v, fb_scene *s)
{
    char sub[96], other[96];
    fb_ref_slot refs[FB_MAX_REFS];
    for (int k = 0; k < s->nlayers; k++) {
        int i = s->order[k], first = -1;
        fb_layer *L = &s->layers[i];
        if (!L->cls->envmap_of_refs) continue;
        int nr = layer_refs(s, i, refs);
        for (int r = 0; r < nr; r++) {
            int j = refs[r].ref->layer;
            if (j < 0) continue;
            if (first < 0) first = j, L->envmap = s->layers[j].envmap;
            if (s->layers[j].envmap == L->envmap) continue;
            snprintf(sub, sizeof sub, "layers[%d].%s", i, refs[r].key);
            return fb_schema_error(
                v, sub, "layer \"%s\" combines \"%s\", %s, with \"%s\", %s: a pixel is not the same point in both",
                L->name, s->layers[first].name, envmap_words(s->layers[first].envmap), s->layers[j].name,
                envmap_words(s->layers[j].envmap));
        }
    }
    s->envmap = s->layers[0].envmap;
    for (int i = 1; i < s->nlayers; i++) {
        if (s->layers[i].envmap == s->envmap) continue;
        envmap_path(s, i, sub, sizeof sub);
        envmap_path(s, 0, other, sizeof other);
        return fb_schema_error(v, sub,
                               "layer \"%s\" is %s but layer \"%s\" (%s) is %s: one EXR file is one environment "
                               "map or none (its envmap attribute); bake them into separate files",
                               s->layers[i].name, envmap_words(s->layers[i].envmap), s->layers[0].name, other,
                               envmap_words(s->envmap));
    }
    return check_envmap_size(v, s);
}

static fb_result parse_root(const fb_vctx *v, json_t *root, fb_scene *s)
{
    char path[64];
    if (!json_is_object(root))
        return fb_schema_error(v, "", "expected a JSON object with \"size\", \"seed\" and \"layers\"");
    if (!json_object_get(root, "layers")) return fb_schema_error(v, "", "missing key \"layers\" (an array of layers)");
    fb_result rc = fb_schema_check(v, "", root, scene_keys, FB_NKEYS(scene_keys), "a scene", NULL);
    if (rc) return rc;
    json_t *size = json_object_get(root, "size");
    s->width = (int)json_integer_value(json_array_get(size, 0));
    s->height = (int)json_integer_value(json_array_get(size, 1));
    s->seed = (uint32_t)json_integer_value(json_object_get(root, "seed"));
    s->compression =
        (exrio_compression)exrio_compression_parse(json_string_value(json_object_get(root, "compression")));
    s->multipart = !strcmp(json_string_value(json_object_get(root, "parts")), "per-layer");
    json_t *layers = json_object_get(root, "layers");
    s->nlayers = (int)json_array_size(layers);
    for (int i = 0; i < s->nlayers; i++) {
        json_t *lj = json_array_get(layers, (size_t)i);
        snprintf(path, sizeof path, "layers[%d]", i);
        if (!json_is_object(lj)) return fb_schema_error(v, path, "expected a layer object with a \"type\"");
        json_t *type = json_object_get(lj, "type");
        if (!type)
            return fb_schema_error(v, path,
                                   "missing key \"type\" (the generator; `fractalbake generators` lists them)");
        const char *t = json_is_string(type) ? json_string_value(type) : "";
        fb_layer *L = &s->layers[i];
        memset(L, 0, sizeof *L);
        L->cls = fb_gen_find(t);
        if (!L->cls) {
            char sub[80], shown[64], avail[256];
            snprintf(sub, sizeof sub, "%s.type", path);
            fb_json_show(type, shown, sizeof shown);
            fb_gen_names(avail, sizeof avail);
            return fb_schema_error(v, sub, "unknown generator %s (available: %s)", shown, avail);
        }
        L->params = calloc(1, L->cls->params_size ? L->cls->params_size : 1);
        if (!L->params) return fb_fail(FB_ERR_NOMEM, "out of memory");
        rc = L->cls->parse(v, path, lj, s, L);
        if (rc) return rc;
        snprintf(L->name, sizeof L->name, "%s", json_string_value(json_object_get(lj, "name")));
        L->half = fb_json_bool(lj, "half");
        if ((rc = parse_heightmap(v, path, lj, s, L))) return rc;
        L->envmap = layer_envmap_key(L, lj);
        const json_t *lc = json_object_get(lj, "compression");
        L->compression = lc ? (exrio_compression)exrio_compression_parse(json_string_value(lc)) : s->compression;
        if (lc && !s->multipart) {
            char sub[80];
            snprintf(sub, sizeof sub, "%s.compression", path);
            return fb_schema_error(v, sub,
                                   "a compression per layer needs \"parts\": \"per-layer\" (an EXR part has one)");
        }
        for (int k = 0; k < i; k++)
            if (!strcmp(s->layers[k].name, L->name)) {
                char sub[80];
                snprintf(sub, sizeof sub, "%s.name", path);
                return fb_schema_error(v, sub, "layer name \"%s\" is already used by layers[%d]", L->name, k);
            }
    }
    if ((rc = resolve_refs(v, s))) return rc;
    return check_envmaps(v, s);
}

fb_result fb_scene_parse(const char *text, const char *origin, fb_scene *out)
{
    return fb_scene_parse_sets(text, origin, NULL, 0, out);
}

/* Whether the value `text` of key k of a layer names a file: one it reads or one it writes. */
static bool names_file(const fb_keyspec *k, const char *text)
{
    if (k->type == FB_K_CUSTOM) return k->value && k->value->names_file && k->value->names_file(text);
    return k->type == FB_K_PATH || k->type == FB_K_OUTPUT;
}

/* Every relative file name of a scene file's layers joined to the file's folder `dir`, so that the scene reads and
 * writes the same files from any working folder; what --set gives afterwards stays relative to the working folder.
 * The joined names are what the scene stores in its EXR, where --from reads them from the working folder, as before.
 * Values of the wrong shape are left for the checks to report. */
static fb_result join_paths(json_t *root, const char *dir)
{
    json_t *layers = json_object_get(root, "layers");
    for (size_t i = 0; i < json_array_size(layers); i++) {
        json_t *l = json_array_get(layers, i);
        const fb_gen_class *cls = fb_gen_find(json_string_value(json_object_get(l, "type")));
        for (int k = 0; cls && k < cls->nkeys; k++) {
            const fb_keyspec *key = &cls->keys[k];
            const char *name = json_string_value(json_object_get(l, key->key));
            if (!name || !*name || name[0] == '/' || !strcmp(name, "-") || !names_file(key, name)) continue;
            size_t n = strlen(dir) + strlen(name) + 2;
            char *joined = malloc(n);
            if (!joined) return fb_fail(FB_ERR_NOMEM, "out of memory");
            snprintf(joined, n, "%s%s%s", dir, strcmp(dir, "/") ? "/" : "", name);
            int bad = json_object_set_new(l, key->key, json_string(joined));
            free(joined);
            if (bad) return fb_fail(FB_ERR_NOMEM, "out of memory");
        }
    }
    return FB_OK;
}

/* A scene's text parsed with the overrides, its file names joined to `dir` (the scene file's folder; NULL: none). */
static fb_result parse_in(const char *text, const char *origin, const char *dir, const char *const *sets, int nsets,
                          fb_scene *out)
{
    memset(out, 0, sizeof *out);
    json_error_t err;
    json_t *root = json_loads(text, JSON_REJECT_DUPLICATES, &err);
    if (!root) {
        if (origin)
            return fb_fail(FB_ERR_INPUT, "%s:%d:%d: malformed JSON: %s", origin, err.line, err.column, err.text);
        return fb_fail(FB_ERR_INPUT, "scene: malformed JSON: %s", err.text);
    }
    char(*paths)[256] = nsets > 0 ? calloc((size_t)nsets, sizeof *paths) : NULL;
    fb_result rc = nsets > 0 && !paths ? fb_fail(FB_ERR_NOMEM, "out of memory") : FB_OK;
    if (!rc && nsets > 0 && !json_is_object(root))
        rc = fb_fail(FB_ERR_INPUT, "%s: expected a JSON object with \"size\", \"seed\" and \"layers\"",
                     origin ? origin : "scene");
    if (!rc && dir && strcmp(dir, ".") && json_is_object(root)) rc = join_paths(root, dir);
    for (int i = 0; i < nsets && !rc; i++) rc = fb_scene_apply_set(root, sets[i], paths[i]);
    fb_vctx v = {origin, text, sets, paths, nsets, NULL};
    if (!origin) /* a command line: one generator's flags */
        v.cls =
            fb_gen_find(json_string_value(json_object_get(json_array_get(json_object_get(root, "layers"), 0), "type")));
    if (!rc) rc = parse_root(&v, root, out);
    if (!rc) {
        out->json = fb_json_dumps(root, 0); /* compact, shortest numbers: stored in every file */
        if (!out->json) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    }
    free(paths);
    json_decref(root);
    if (rc) fb_scene_fini(out);
    return rc;
}

fb_result fb_scene_parse_sets(const char *text, const char *origin, const char *const *sets, int nsets, fb_scene *out)
{
    return parse_in(text, origin, NULL, sets, nsets, out);
}

fb_result fb_scene_load(const char *path, fb_scene *out)
{
    return fb_scene_load_sets(path, NULL, 0, out);
}

fb_result fb_scene_load_sets(const char *path, const char *const *sets, int nsets, fb_scene *out)
{
    memset(out, 0, sizeof *out);
    char *text = NULL;
    size_t len = 0;
    fb_result orc = fb_input_slurp(path, "scene", (size_t)16 << 20, &text, &len);
    if (orc) return orc;
    if (strlen(text) != len) {
        free(text);
        return fb_fail(FB_ERR_INPUT, "%s: scene contains a NUL byte (not a JSON text file)", path);
    }
    char *dir = strcmp(path, "-") ? strdup(path) : NULL; /* a scene on stdin: the working folder */
    char *slash = dir ? strrchr(dir, '/') : NULL;
    if (slash) slash[slash == dir] = 0; /* "/s.json": "/" */
    fb_result rc = parse_in(text, dir ? path : "(stdin)", slash ? dir : NULL, sets, nsets, out);
    free(dir);
    free(text);
    return rc;
}

void fb_scene_layer_names(const fb_scene *s, char *out, size_t size)
{
    out[0] = 0;
    for (int i = 0; i < s->nlayers; i++)
        snprintf(out + strlen(out), size - strlen(out), "%s%s", i ? ", " : "", s->layers[i].name);
}

int fb_scene_outputs(const fb_scene *s, const char **paths, const char **what, int max)
{
    int n = 0;
    for (int i = 0; i < s->nlayers; i++) {
        const fb_layer *l = &s->layers[i];
        if (l->cls && l->cls->outputs) n += l->cls->outputs(l, paths + n, what + n, max - n);
        for (int t = 0; t < l->tiles[0] * l->tiles[1] && n < max; t++)
            paths[n] = l->tile_paths + (size_t)t * FB_TILE_PATH, what[n++] = "heightmap tile";
        if (l->heightmap[0] && !l->tiles[0] && n < max) paths[n] = l->heightmap, what[n++] = "heightmap";
        if (l->heightmap_sidecar[0] && n < max) paths[n] = l->heightmap_sidecar, what[n++] = "heightmap sidecar";
    }
    return n;
}

fb_result fb_scene_drop_outputs(const char *text, char **out, char *dropped, size_t size)
{
    dropped[0] = 0;
    *out = NULL;
    json_t *root = json_loads(text, 0, NULL);
    if (!root) return fb_fail(FB_ERR_INPUT, "the stored scene is not JSON");
    json_t *layers = json_object_get(root, "layers");
    for (size_t i = 0; i < json_array_size(layers); i++) {
        json_t *l = json_array_get(layers, i);
        const char *type = json_string_value(json_object_get(l, "type"));
        const char *name = json_string_value(json_object_get(l, "name"));
        const fb_gen_class *cls = fb_gen_find(type);
        if (!cls) continue;
        const fb_keyspec *keys = cls->keys;
        int said = 0; /* the heightmap's qualifiers named so far */
        for (int k = 0; k < cls->nkeys; k++) {
            const char *v = keys[k].type == FB_K_OUTPUT ? json_string_value(json_object_get(l, keys[k].key)) : NULL;
            if (!v) continue;
            snprintf(dropped + strlen(dropped), size - strlen(dropped), "%slayers.%s.%s=%s", dropped[0] ? ", " : "",
                     name ? name : "?", keys[k].key, v);
            json_object_del(l, keys[k].key);
            /* the keys that only say how to write it go with it ("instances-surface", "heightmap-range": they
             * are refused without it), named after it */
            size_t len = strlen(keys[k].key);
            int n = 0;
            for (int q = 0; q < cls->nkeys; q++)
                if (!strncmp(keys[q].key, keys[k].key, len) && keys[q].key[len] == '-' &&
                    json_object_get(l, keys[q].key)) {
                    snprintf(dropped + strlen(dropped), size - strlen(dropped), "%s%s", n++ ? ", " : " with its ",
                             keys[q].key);
                    json_object_del(l, keys[q].key);
                }
            if (!strcmp(keys[k].key, "heightmap")) said = n;
        }
        /* what only says how to write the heightmap goes with it (it is refused without one) */
        static const char *const qualifiers[] = {"heightmap-engine", "heightmap-range", "tiles"};
        for (int q = 0, n = said; q < 3 && !json_object_get(l, "heightmap"); q++)
            if (json_object_get(l, qualifiers[q])) {
                snprintf(dropped + strlen(dropped), size - strlen(dropped), "%s%s", n++ ? ", " : " with its ",
                         qualifiers[q]);
                json_object_del(l, qualifiers[q]);
            }
    }
    *out = json_dumps(root, JSON_COMPACT);
    json_decref(root);
    return *out ? FB_OK : fb_fail(FB_ERR_NOMEM, "out of memory");
}

void fb_scene_fini(fb_scene *s)
{
    if (!s) return;
    for (int i = 0; i < FB_MAX_LAYERS; i++) free(s->layers[i].params), free(s->layers[i].tile_paths);
    free(s->json);
    memset(s, 0, sizeof *s);
}

/* The showcase, a night landscape (docs/scenes.md): a polar Julia sky whose spirals read as galaxies,
 * a terrain refined from a small built-in survey, lit by a low moon and coloured by height, plants
 * as silhouettes, and data layers behind them. The text is docs/examples/gallery-night.json, embedded
 * at build time (cmake/embed.cmake), so the file and the default cannot differ. */
#include "default_scene.h"

const char *fb_scene_default_json(void)
{
    return fb_default_scene_text;
}
