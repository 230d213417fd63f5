/*
 * The scene engine: parsing and validation (jansson), driven by each generator's schema table
 * (schema.h); --set overrides; flags to keys; --help from the tables. Nothing here knows a
 * generator by name: they come from the list (fb_gen_list).
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
    {"layers", FB_K_LAYERS, 1, FB_MAX_LAYERS, false, NULL, NULL, "the layers, each a generator"},
};

#define FB_NKEYS(a) ((int)(sizeof(a) / sizeof((a)[0])))

static const fb_keyspec *find_key(const fb_keyspec *keys, int n, const char *key)
{
    for (int i = 0; i < n; i++)
        if (!strcmp(keys[i].key, key)) return &keys[i];
    return NULL;
}

static const fb_gen_class *kind_class(const char *kind)
{
    return kind ? fb_gen_find(kind) : NULL;
}

/* The flag of a key: its own, --layer for the layer's name, else --KEY. */
static const char *flag_of(const fb_keyspec *k)
{
    return k->flag ? k->flag : !strcmp(k->key, "name") ? "layer" : k->key;
}

const char *fb_key_flag(const fb_keyspec *k)
{
    return flag_of(k);
}

const char *fb_ktype_name(const fb_keyspec *k)
{
    static const char *const names[] = {
        [FB_K_INT] = "int",       [FB_K_NUM] = "number",      [FB_K_BOOL] = "bool",       [FB_K_ENUM] = "enum",
        [FB_K_NAME] = "name",     [FB_K_VEC2] = "vec2",       [FB_K_SIZE] = "size",       [FB_K_LAYERS] = "layers",
        [FB_K_TYPE] = "type",     [FB_K_NUMLIST] = "numbers", [FB_K_STOPS] = "stops",     [FB_K_STRING] = "string",
        [FB_K_OUTPUT] = "output", [FB_K_BOUNDS] = "bounds",   [FB_K_FRACS] = "fractions", [FB_K_NAMES] = "names",
        [FB_K_RULES] = "rules",   [FB_K_REF] = "ref",         [FB_K_REFS] = "refs",       [FB_K_CUSTOM] = "custom",
    };
    return k->type >= 0 && k->type <= FB_K_CUSTOM && names[k->type] ? names[k->type] : "?";
}

/* ---- locating a key path in the source text ------------------------------------------------- */

typedef struct cursor {
    const char *p;
    int line;
} cursor;

static void skip_ws(cursor *c)
{
    while (*c->p == ' ' || *c->p == '\t' || *c->p == '\r' || *c->p == '\n') {
        if (*c->p == '\n') c->line++;
        c->p++;
    }
}

static bool skip_string(cursor *c)
{
    if (*c->p != '"') return false;
    for (c->p++; *c->p && *c->p != '"'; c->p++)
        if (*c->p == '\\' && c->p[1]) c->p++;
    if (*c->p != '"') return false;
    c->p++;
    return true;
}

static bool skip_value(cursor *c)
{
    skip_ws(c);
    char open = *c->p;
    if (open == '"') return skip_string(c);
    if (open == '{' || open == '[') {
        char close = open == '{' ? '}' : ']';
        c->p++;
        skip_ws(c);
        if (*c->p == close) {
            c->p++;
            return true;
        }
        for (;;) {
            if (open == '{') {
                skip_ws(c);
                if (!skip_string(c)) return false;
                skip_ws(c);
                if (*c->p++ != ':') return false;
            }
            if (!skip_value(c)) return false;
            skip_ws(c);
            if (*c->p == ',') {
                c->p++;
                continue;
            }
            if (*c->p == close) {
                c->p++;
                return true;
            }
            return false;
        }
    }
    while (*c->p && !strchr(",]} \t\r\n", *c->p)) c->p++;
    return true;
}

/* The line of the element at `path` ("layers[0].octaves") in JSON text, or of the deepest enclosing
 * element that exists. The text has already been parsed successfully by jansson. */
static int locate(cursor *c, const char *path)
{
    skip_ws(c);
    if (*path == '.') path++;
    if (!*path) return c->line;
    int here = c->line;
    if (*path == '[') {
        long idx = strtol(path + 1, NULL, 10);
        const char *rest = strchr(path, ']');
        if (!rest || *c->p != '[') return here;
        c->p++;
        for (long i = 0; i < idx; i++) {
            if (!skip_value(c)) return here;
            skip_ws(c);
            if (*c->p++ != ',') return here;
        }
        return locate(c, rest + 1);
    }
    size_t klen = strcspn(path, ".[");
    if (*c->p != '{') return here;
    c->p++;
    for (;;) {
        skip_ws(c);
        if (*c->p != '"') return here;
        int key_line = c->line;
        const char *k = c->p + 1;
        if (!skip_string(c)) return here;
        bool match = (size_t)(c->p - 1 - k) == klen && !strncmp(k, path, klen);
        skip_ws(c);
        if (*c->p++ != ':') return here;
        if (match) return path[klen] ? locate(c, path + klen) : key_line;
        if (!skip_value(c)) return here;
        skip_ws(c);
        if (*c->p++ != ',') return here;
    }
}

/* ---- validation ----------------------------------------------------------------------------- */

/* Logs "FILE:LINE: PATH: message" (file) or "--KEY: message" (command line) and returns FB_ERR_INPUT. */
fb_result fb_schema_error(const fb_vctx *v, const char *path, const char *fmt, ...)
{
    char msg[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    for (int i = v->nsets - 1; i >= 0; i--) { /* a value given by --set is reported as that --set */
        size_t n = strlen(v->set_paths[i]);
        if (!strncmp(path, v->set_paths[i], n) && (!path[n] || path[n] == '.' || path[n] == '['))
            return fb_fail(FB_ERR_USAGE, "--set %s: %s%s%s", v->sets[i], path[n] ? path + n + 1 : "",
                           path[n] ? ": " : "", msg);
    }
    if (v->origin) {
        cursor c = {v->text, 1};
        int line = locate(&c, path);
        return fb_fail(FB_ERR_INPUT, "%s:%d: %s: %s", v->origin, line, path[0] ? path : "(top level)", msg);
    }
    /* The command line: the flag of the layer's (or the scene's) key, and what is inside a value
     * given as one JSON flag (an L-system condensation set) */
    const char *key = path;
    if (!strncmp(key, "layers[", 7) && strchr(key, ']')) key = strchr(key, ']') + 1 + (strchr(key, ']')[1] == '.');
    char name[64];
    size_t len = strcspn(key, ".[");
    snprintf(name, sizeof name, "%.*s", (int)(len < sizeof name ? len : sizeof name - 1), key);
    const fb_keyspec *k = NULL;
    if (v->cls)
        for (int i = 0; i < v->cls->nkeys && !k; i++)
            if (!strcmp(v->cls->keys[i].key, name)) k = &v->cls->keys[i];
    const char *flag = k ? flag_of(k) : name;
    if (key[len] == '.') return fb_fail(FB_ERR_USAGE, "--%s: %s: %s", flag, key + len + 1, msg);
    /* an element of a list (--maps[1]); a repeatable flag's element is that flag (--rule) */
    const char *index = key[len] == '[' && !(k && k->type == FB_K_RULES) ? key + len : "";
    return fb_fail(FB_ERR_USAGE, "--%s%s: %s", flag, index, msg);
}

/* A short rendering of a JSON value for messages. */
void fb_json_show(const json_t *j, char *buf, size_t n)
{
    char *s = json_dumps(j, JSON_ENCODE_ANY | JSON_COMPACT);
    snprintf(buf, n, "%s", s ? s : "?");
    if (strlen(buf) > 40) strcpy(buf + 37, "...");
    free(s);
}

bool fb_enum_index(const char *enums, const char *s, int *idx)
{
    size_t n = strlen(s);
    int i = 0;
    for (const char *p = enums; *p; i++) {
        size_t len = strcspn(p, "|");
        if (len == n && !strncmp(p, s, n)) {
            *idx = i;
            return true;
        }
        p += len + (p[len] == '|');
    }
    return false;
}

static fb_result check_number(const fb_vctx *v, const char *path, const fb_keyspec *k, const json_t *j, bool integer)
{
    char shown[64];
    fb_json_show(j, shown, sizeof shown);
    if (integer ? !json_is_integer(j) : !json_is_number(j))
        return fb_schema_error(v, path, "expected %s, found %s", integer ? "an integer" : "a number", shown);
    double x = json_number_value(j);
    if (!isfinite(x)) return fb_schema_error(v, path, "expected a finite number, found %s", shown);
    bool in_range = (k->lo_open ? x > k->lo : x >= k->lo) && x <= k->hi;
    if (!in_range) {
        if (integer)
            return fb_schema_error(v, path, "expected an integer in %.0f..%.0f, found %s", k->lo, k->hi, shown);
        return fb_schema_error(v, path, "expected a number in %s%g, %g], found %s", k->lo_open ? "(" : "[", k->lo,
                               k->hi, shown);
    }
    return FB_OK;
}

fb_result fb_schema_check_value(const fb_vctx *v, const char *path, const fb_keyspec *k, json_t *j)
{
    char shown[64];
    fb_json_show(j, shown, sizeof shown);
    int idx;
    switch (k->type) {
    case FB_K_INT:
        return check_number(v, path, k, j, true);
    case FB_K_NUM:
        return check_number(v, path, k, j, false);
    case FB_K_BOOL:
        if (!json_is_boolean(j)) return fb_schema_error(v, path, "expected true or false, found %s", shown);
        return FB_OK;
    case FB_K_ENUM:
        if (!json_is_string(j) || !fb_enum_index(k->enums, json_string_value(j), &idx))
            return fb_schema_error(v, path, "expected one of %s, found %s", k->enums, shown);
        return FB_OK;
    case FB_K_TYPE:
        if (!json_is_string(j))
            return fb_schema_error(v, path, "expected a generator name such as \"fbm\", found %s", shown);
        return FB_OK;
    case FB_K_NAME: {
        const char *s = json_is_string(j) ? json_string_value(j) : NULL;
        bool ok = s && *s && strlen(s) < 64;
        for (const char *p = s; ok && *p; p++)
            ok = (*p >= 'a' && *p <= 'z') || (*p >= 'A' && *p <= 'Z') || (*p >= '0' && *p <= '9') || *p == '_' ||
                 *p == '-';
        if (!ok)
            return fb_schema_error(v, path, "expected a name of 1 to 63 letters, digits, '_' or '-', found %s", shown);
        return FB_OK;
    }
    case FB_K_VEC2:
    case FB_K_SIZE: {
        bool isz = k->type == FB_K_SIZE;
        if (!json_is_array(j) || json_array_size(j) != 2)
            return fb_schema_error(v, path, "expected %s, found %s", isz ? "[width, height]" : "[x, y]", shown);
        for (size_t i = 0; i < 2; i++) {
            const json_t *e = json_array_get(j, i);
            bool good = isz ? json_is_integer(e) : json_is_number(e);
            double x = good ? json_number_value(e) : 0;
            if (!good || !isfinite(x) || x < k->lo || x > k->hi)
                return fb_schema_error(v, path, "expected %s with each %s in %g..%g, found %s",
                                       isz ? "[width, height]" : "[x, y]", isz ? "side an integer" : "component", k->lo,
                                       k->hi, shown);
        }
        if (isz) {
            unsigned long long px =
                (unsigned long long)json_integer_value(json_array_get(j, 0)) * json_integer_value(json_array_get(j, 1));
            if (px > FB_MAX_PIXELS)
                return fb_schema_error(v, path, "%s is %llu pixels; at most %llu are supported", shown, px,
                                       FB_MAX_PIXELS);
        }
        return FB_OK;
    }
    case FB_K_NUMLIST: {
        bool good = json_is_array(j) && (int)json_array_size(j) == k->count;
        for (size_t i = 0; good && i < json_array_size(j); i++) {
            const json_t *e = json_array_get(j, i);
            double x = json_is_number(e) ? json_number_value(e) : NAN;
            good = isfinite(x) && x >= k->lo && x <= k->hi;
        }
        if (!good)
            return fb_schema_error(v, path, "expected %d numbers in %g..%g, found %s", k->count, k->lo, k->hi, shown);
        return FB_OK;
    }
    case FB_K_STOPS: {
        size_t n = json_is_array(j) ? json_array_size(j) : 0;
        bool good = n >= 2 && n <= FB_PALETTE_MAX_STOPS;
        double prev = -1;
        for (size_t i = 0; good && i < n; i++) {
            const json_t *e = json_array_get(j, i);
            good = json_is_array(e) && json_array_size(e) == 4;
            for (size_t c = 0; good && c < 4; c++) {
                const json_t *x = json_array_get(e, c);
                double d = json_is_number(x) ? json_number_value(x) : NAN;
                good = isfinite(d) && d >= 0 && (c > 0 ? d <= k->hi : d <= 1.0);
            }
            if (good) {
                double t = json_number_value(json_array_get(e, 0));
                good = t > prev && (i > 0 || t == 0.0) && (i + 1 < n || t == 1.0);
                prev = t;
            }
        }
        if (!good)
            return fb_schema_error(
                v, path,
                "expected 2 to %d stops [t, r, g, b] with t rising from 0 to exactly 1 and colours >= 0, "
                "found %s",
                FB_PALETTE_MAX_STOPS, shown);
        return FB_OK;
    }
    case FB_K_REFS:
        if (!json_is_array(j) || json_array_size(j) < 1 || json_array_size(j) > (size_t)k->count)
            return fb_schema_error(v, path, "expected a list of 1 to %d channels or numbers, found %s", k->count,
                                   shown);
        for (size_t i = 0; i < json_array_size(j); i++) {
            char sub[300];
            snprintf(sub, sizeof sub, "%s[%zu]", path, i);
            fb_result rc = fb_schema_check_value(v, sub, &(fb_keyspec){.type = FB_K_REF}, json_array_get(j, i));
            if (rc) return rc;
        }
        return FB_OK;
    case FB_K_REF: {
        if (json_is_number(j)) {
            if (!isfinite(json_number_value(j)))
                return fb_schema_error(v, path, "expected a finite number, found %s", shown);
            return FB_OK;
        }
        const char *r = json_is_string(j) ? json_string_value(j) : NULL;
        bool ok = r && *r && strlen(r) < 128 && r[0] != '.' && r[strlen(r) - 1] != '.';
        if (!ok) return fb_schema_error(v, path, "expected \"layer.channel\", \"layer\" or a number, found %s", shown);
        return FB_OK;
    }
    case FB_K_STRING:
    case FB_K_OUTPUT:
        if (!json_is_string(j) || !*json_string_value(j) || strlen(json_string_value(j)) >= 4096)
            return fb_schema_error(v, path, "expected a non-empty string, found %s", shown);
        return FB_OK;
    case FB_K_BOUNDS: {
        if (json_is_string(j) && !strcmp(json_string_value(j), "auto")) return FB_OK;
        bool good = json_is_array(j) && json_array_size(j) == 4;
        double b[4] = {0};
        for (size_t i = 0; good && i < 4; i++) {
            const json_t *e = json_array_get(j, i);
            b[i] = json_is_number(e) ? json_number_value(e) : NAN;
            good = isfinite(b[i]) && b[i] >= k->lo && b[i] <= k->hi;
        }
        if (!good || !(b[1] > b[0] && b[3] > b[2]))
            return fb_schema_error(v, path,
                                   "expected \"auto\" or [xmin, xmax, ymin, ymax] with xmin < xmax and ymin < ymax, "
                                   "found %s",
                                   shown);
        return FB_OK;
    }
    case FB_K_FRACS: {
        size_t n = json_is_array(j) ? json_array_size(j) : 0;
        bool good = n >= 1 && n <= (size_t)k->count;
        for (size_t i = 0; good && i < n; i++) {
            const json_t *e = json_array_get(j, i);
            double x = json_is_number(e) ? json_number_value(e) : NAN;
            good = isfinite(x) && x >= k->lo && x <= k->hi;
        }
        if (!good)
            return fb_schema_error(v, path, "expected 1 to %d numbers in %g..%g, found %s", k->count, k->lo, k->hi,
                                   shown);
        return FB_OK;
    }
    case FB_K_NAMES: {
        size_t n = json_is_array(j) ? json_array_size(j) : 0;
        bool good = n >= 1 && n <= 32;
        for (size_t i = 0; good && i < n; i++) {
            const json_t *e = json_array_get(j, i);
            good = json_is_string(e) && fb_enum_index(k->enums, json_string_value(e), &idx);
            for (size_t m = 0; good && m < i; m++)
                good = strcmp(json_string_value(json_array_get(j, m)), json_string_value(e));
        }
        if (!good)
            return fb_schema_error(v, path, "expected a list of distinct names from %s, found %s", k->enums, shown);
        return FB_OK;
    }
    case FB_K_RULES: {
        size_t n = json_is_array(j) ? json_array_size(j) : 0;
        if (!json_is_array(j) || n > (size_t)k->count)
            return fb_schema_error(v, path, "expected a list of at most %d rules \"X=successor\", found %s", k->count,
                                   shown);
        for (size_t i = 0; i < n; i++) {
            const json_t *e = json_array_get(j, i);
            char sub[256], msg[256];
            snprintf(sub, sizeof sub, "%s[%zu]", path, i);
            if (!json_is_string(e)) {
                fb_json_show(e, shown, sizeof shown);
                return fb_schema_error(v, sub, "expected a rule \"X=successor\", found %s", shown);
            }
            if (k->check && !k->check(json_string_value(e), msg, sizeof msg)) return fb_schema_error(v, sub, "%s", msg);
        }
        return FB_OK;
    }
    case FB_K_CUSTOM:
        if (!ALWAYS(k->value && k->value->check))
            return fb_fail(FB_ERR_INTERNAL, "key %s: a value type without a check", k->key);
        return k->value->check(v, path, k, j);
    case FB_K_LAYERS:
        if (!json_is_array(j) || json_array_size(j) < 1 || json_array_size(j) > FB_MAX_LAYERS)
            return fb_schema_error(v, path, "expected an array of 1 to %d layers, found %s", FB_MAX_LAYERS, shown);
        return FB_OK;
    }
    return FB_OK;
}

/* Checks every key of `obj` against `keys` and fills in the defaults. */
fb_result fb_schema_check(const fb_vctx *v, const char *path, json_t *obj, const fb_keyspec *keys, int n,
                          const char *what)
{
    const char *key;
    json_t *val;
    char sub[256];
    json_object_foreach(obj, key, val)
    {
        snprintf(sub, sizeof sub, "%s%s%s", path, path[0] ? "." : "", key);
        const fb_keyspec *k = find_key(keys, n, key);
        if (!k) {
            char known[512] = "", hint[96] = "";
            const char *names[96];
            for (int i = 0; i < n; i++) {
                snprintf(known + strlen(known), sizeof known - strlen(known), "%s%s", i ? ", " : "", keys[i].key);
                if (i < 96) names[i] = keys[i].key;
            }
            const char *near = fb_closest(key, names, n < 96 ? n : 96);
            if (near) snprintf(hint, sizeof hint, "did you mean \"%s\"? ", near);
            if (!v->origin && !strchr(path, '.')) /* a flag (not a key inside a flag's JSON value) */
                return fb_fail(FB_ERR_USAGE, "--%s: unknown flag for %s", key, what);
            return fb_schema_error(v, sub, "unknown key for %s; %s(known keys: %s)", what, hint, known);
        }
        fb_result rc = fb_schema_check_value(v, sub, k, val);
        if (rc) return rc;
    }
    for (int i = 0; i < n; i++) {
        if (!keys[i].def || json_object_get(obj, keys[i].key)) continue;
        bool given = false; /* a key that stands for this one (gain for hurst) */
        for (const char *u = keys[i].unless; u && *u && !given; u += strcspn(u, "|"), u += *u == '|') {
            char other[64];
            snprintf(other, sizeof other, "%.*s", (int)strcspn(u, "|"), u);
            given = json_object_get(obj, other) != NULL;
        }
        if (given) continue;
        json_t *d = json_loads(keys[i].def, JSON_DECODE_ANY, NULL);
        if (!d || json_object_set_new(obj, keys[i].key, d) != 0) return fb_fail(FB_ERR_NOMEM, "out of memory");
    }
    return FB_OK;
}

double fb_json_num(const json_t *obj, const char *key)
{
    return json_number_value(json_object_get(obj, key));
}

bool fb_json_bool(const json_t *obj, const char *key)
{
    return json_is_true(json_object_get(obj, key));
}

void fb_json_vec2(const json_t *obj, const char *key, double out[2])
{
    json_t *a = json_object_get(obj, key);
    out[0] = json_number_value(json_array_get(a, 0));
    out[1] = json_number_value(json_array_get(a, 1));
}

/* The colour map keys shared by julia and ifs layers: palette, cosine, stops. */
fb_result fb_schema_palette(const fb_vctx *v, const char *path, const json_t *obj, fb_palette_spec *pal)
{
    const char *named = json_string_value(json_object_get(obj, "palette")); /* optional where it has no default */
    pal->named = 0;
    if (named) fb_enum_index(FB_PALETTE_NAMES, named, &pal->named);
    json_t *cos_j = json_object_get(obj, "cosine"), *stops_j = json_object_get(obj, "stops");
    if (cos_j && stops_j) {
        char sub[256];
        snprintf(sub, sizeof sub, "%s.stops", path);
        return fb_schema_error(v, sub, "give cosine or stops, not both");
    }
    pal->has_cosine = cos_j != NULL;
    for (size_t i = 0; cos_j && i < 12; i++) pal->cosine[i] = json_number_value(json_array_get(cos_j, i));
    pal->nstops = stops_j ? (int)json_array_size(stops_j) : 0;
    for (int i = 0; i < pal->nstops; i++)
        for (int c = 0; c < 4; c++)
            pal->stops[i][c] = json_number_value(json_array_get(json_array_get(stops_j, (size_t)i), (size_t)c));
    return FB_OK;
}

void fb_json_string(const json_t *obj, const char *key, char *out, size_t size)
{
    const json_t *j = json_object_get(obj, key);
    snprintf(out, size, "%s", json_is_string(j) ? json_string_value(j) : "");
}

void fb_json_ref(const json_t *j, fb_ref *r)
{
    memset(r, 0, sizeof *r);
    r->layer = -1;
    if (json_is_number(j)) {
        r->value = json_number_value(j);
        return;
    }
    r->layer = -2; /* resolved by name in resolve_refs; the whole reference is kept in channel until then */
    snprintf(r->channel, sizeof r->channel, "%s", json_string_value(j));
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

/* The keys every height-producing generator shares (heightmap, heightmap-range), read into L; their
 * types were checked against the generator's table. A GeoTIFF needs world coordinates, which only a
 * generator with a "crs" key has (terrain). */
static fb_result parse_heightmap(const fb_vctx *v, const char *path, const json_t *lj, fb_layer *L)
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
                                   hm, find_key(L->cls->keys, L->cls->nkeys, "crs") ? " or .tif (GeoTIFF)" : "");
        if (f == FB_HEIGHTMAP_GEOTIFF && !find_key(L->cls->keys, L->cls->nkeys, "crs"))
            return fb_schema_error(v, sub,
                                   "\"%s\": a GeoTIFF needs world coordinates, which %s has not (a terrain "
                                   "layer has): write .png or .r16",
                                   hm, L->cls->what);
        snprintf(L->heightmap, sizeof L->heightmap, "%s", hm);
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
    return FB_OK;
}

static fb_result parse_root(const fb_vctx *v, json_t *root, fb_scene *s)
{
    char path[64];
    if (!json_is_object(root))
        return fb_schema_error(v, "", "expected a JSON object with \"size\", \"seed\" and \"layers\"");
    if (!json_object_get(root, "layers")) return fb_schema_error(v, "", "missing key \"layers\" (an array of layers)");
    fb_result rc = fb_schema_check(v, "", root, scene_keys, FB_NKEYS(scene_keys), "a scene");
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
        if (!type) return fb_schema_error(v, path, "missing key \"type\" (the generator, e.g. \"fbm\")");
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
        if ((rc = parse_heightmap(v, path, lj, L))) return rc;
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
    return resolve_refs(v, s);
}

/* ---- --set KEY.PATH=VALUE -------------------------------------------------------------------- */

/* The value of a --set: JSON when it parses as JSON ("5", "[1, 2]", "\"x\"", "true"); WxH as
 * [W, H]; a comma-separated list as an array of such values; anything else as a string. */
static json_t *set_value(const char *text)
{
    json_t *j = json_loads(text, JSON_DECODE_ANY, NULL);
    if (j) return j;
    int w, h, used = 0;
    if (sscanf(text, "%d%*[x]%d%n", &w, &h, &used) == 2 && !text[used]) return json_pack("[ii]", w, h);
    if (!strchr(text, ',')) return json_string(text);
    json_t *arr = json_array();
    for (const char *p = text; arr;) {
        size_t n = strcspn(p, ",");
        char *item = strndup(p, n);
        json_t *e = item ? json_loads(item, JSON_DECODE_ANY, NULL) : NULL;
        if (!e && item) e = json_string(item);
        free(item);
        if (!e || json_array_append_new(arr, e) != 0) {
            json_decref(arr);
            return NULL;
        }
        if (!p[n]) break;
        p += n + 1;
    }
    return arr;
}

/* The default name of a layer of type `type` (its keys' "name" default), or "". */
static void default_layer_name(const json_t *layer, char *out, size_t n)
{
    const fb_gen_class *cls = kind_class(json_string_value(json_object_get(layer, "type")));
    const fb_keyspec *k = cls ? find_key(cls->keys, cls->nkeys, "name") : NULL;
    const char *def = k && k->def ? k->def : "\"\"";
    snprintf(out, n, "%.*s", (int)strlen(def) - 2, def + 1);
}

/* Applies one override to the scene's JSON, creating intermediate objects as needed; writes the key
 * path it set (layers[2].c) to jpath. In lists, a segment is an index or a layer name. */
static fb_result apply_set(json_t *root, const char *set, char jpath[256])
{
    const char *eq = strchr(set, '=');
    if (!eq || eq == set)
        return fb_fail(FB_ERR_USAGE, "--set %s: expected KEY.PATH=VALUE (e.g. layers.sky.c=-0.8,0.156)", set);
    json_t *node = root, *val = set_value(eq + 1);
    if (!val) return fb_fail(FB_ERR_NOMEM, "out of memory");
    jpath[0] = 0;
    const char *seg = set;
    size_t created = 0; /* the length of jpath where the first object this override created starts */
    for (;;) {
        size_t n = strcspn(seg, ".=");
        bool last = seg[n] == '=';
        char key[128];
        if (n == 0 || n >= sizeof key) {
            json_decref(val);
            return fb_fail(FB_ERR_USAGE, "--set %s: empty or overlong key in the path", set);
        }
        snprintf(key, sizeof key, "%.*s", (int)n, seg);
        size_t at = strlen(jpath);
        json_t *child = NULL;
        if (json_is_object(node)) {
            snprintf(jpath + at, 256 - at, "%s%s", at ? "." : "", key);
            if (last) {
                if (created) jpath[created] = 0; /* errors inside what it created are this override's */
                return json_object_set_new(node, key, val) ? fb_fail(FB_ERR_NOMEM, "out of memory") : FB_OK;
            }
            child = json_object_get(node, key);
            if (!child) {
                if (!created) created = strlen(jpath);
                child = json_object();
                if (!child || json_object_set_new(node, key, child) != 0) {
                    json_decref(val);
                    return fb_fail(FB_ERR_NOMEM, "out of memory");
                }
            }
        } else if (json_is_array(node)) {
            char *end;
            long idx = strtol(key, &end, 10);
            size_t count = json_array_size(node);
            if (*end || end == key) { /* a name: the element whose "name" (or default name) is key */
                idx = -1;
                for (size_t i = 0; i < count && idx < 0; i++) {
                    json_t *e = json_array_get(node, i);
                    char name[128];
                    if (json_is_string(json_object_get(e, "name")))
                        snprintf(name, sizeof name, "%s", json_string_value(json_object_get(e, "name")));
                    else
                        default_layer_name(e, name, sizeof name);
                    if (!strcmp(name, key)) idx = (long)i;
                }
                if (idx < 0) {
                    json_decref(val);
                    return fb_fail(FB_ERR_USAGE, "--set %s: no element named \"%s\" in %s", set, key,
                                   at ? jpath : "the scene");
                }
            } else if (idx < 0 || (size_t)idx >= count) {
                json_decref(val);
                return fb_fail(FB_ERR_USAGE, "--set %s: index %ld is out of range (%s has %zu)", set, idx,
                               at ? jpath : "the list", count);
            }
            snprintf(jpath + at, 256 - at, "[%ld]", idx);
            if (last)
                return json_array_set_new(node, (size_t)idx, val) ? fb_fail(FB_ERR_NOMEM, "out of memory") : FB_OK;
            child = json_array_get(node, (size_t)idx);
        } else {
            json_decref(val);
            return fb_fail(FB_ERR_USAGE, "--set %s: %s is a value, not an object or a list", set, jpath);
        }
        node = child;
        seg += n + 1;
    }
}

fb_result fb_scene_parse(const char *text, const char *origin, fb_scene *out)
{
    return fb_scene_parse_sets(text, origin, NULL, 0, out);
}

fb_result fb_scene_parse_sets(const char *text, const char *origin, const char *const *sets, int nsets, fb_scene *out)
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
    for (int i = 0; i < nsets && !rc; i++) rc = apply_set(root, sets[i], paths[i]);
    fb_vctx v = {origin, text, sets, paths, nsets, NULL};
    if (!origin) /* a command line: one generator's flags */
        v.cls =
            kind_class(json_string_value(json_object_get(json_array_get(json_object_get(root, "layers"), 0), "type")));
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

fb_result fb_scene_load(const char *path, fb_scene *out)
{
    return fb_scene_load_sets(path, NULL, 0, out);
}

fb_result fb_scene_load_sets(const char *path, const char *const *sets, int nsets, fb_scene *out)
{
    memset(out, 0, sizeof *out);
    FILE *f = NULL;
    fb_result orc = fb_input_open(path, "scene", &f);
    if (orc) return orc;
    char *text = NULL;
    size_t len = 0, cap = 0;
    for (;;) {
        if (len + 4096 + 1 > cap) {
            cap = cap ? 2 * cap : 8192;
            if (cap > (16u << 20)) {
                free(text);
                fclose(f);
                return fb_fail(FB_ERR_INPUT, "%s: scene file larger than 16 MiB", path);
            }
            char *t = realloc(text, cap);
            if (!t) {
                free(text);
                fclose(f);
                return fb_fail(FB_ERR_NOMEM, "out of memory");
            }
            text = t;
        }
        size_t n = fread(text + len, 1, 4096, f);
        len += n;
        if (n < 4096) break;
    }
    bool bad = ferror(f);
    fclose(f);
    if (bad) {
        free(text);
        return fb_fail(FB_ERR_INPUT, "%s: cannot read scene: %s", path, strerror(errno));
    }
    text[len] = 0;
    if (strlen(text) != len) {
        free(text);
        return fb_fail(FB_ERR_INPUT, "%s: scene contains a NUL byte (not a JSON text file)", path);
    }
    fb_result rc = fb_scene_parse_sets(text, strcmp(path, "-") ? path : "(stdin)", sets, nsets, out);
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
        if (l->heightmap[0] && n < max) paths[n] = l->heightmap, what[n++] = "heightmap";
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
        const fb_gen_class *cls = kind_class(type);
        if (!cls) continue;
        const fb_keyspec *keys = cls->keys;
        for (int k = 0; k < cls->nkeys; k++) {
            const char *v = keys[k].type == FB_K_OUTPUT ? json_string_value(json_object_get(l, keys[k].key)) : NULL;
            if (!v) continue;
            snprintf(dropped + strlen(dropped), size - strlen(dropped), "%slayers.%s.%s=%s", dropped[0] ? ", " : "",
                     name ? name : "?", keys[k].key, v);
            json_object_del(l, keys[k].key);
        }
    }
    *out = json_dumps(root, JSON_COMPACT);
    json_decref(root);
    return *out ? FB_OK : fb_fail(FB_ERR_NOMEM, "out of memory");
}

void fb_scene_fini(fb_scene *s)
{
    if (!s) return;
    for (int i = 0; i < FB_MAX_LAYERS; i++) free(s->layers[i].params);
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

/* ---- command-line flags --------------------------------------------------------------------- */

static const fb_keyspec *flag_spec(const char *kind, const char *flag, bool *scene_level)
{
    *scene_level = false;
    if (!strcmp(flag, "type") || !strcmp(flag, "layers")) return NULL;
    if (!strcmp(flag, "compression") || !strcmp(flag, "parts")) { /* the file's, not the layer's */
        *scene_level = true;
        return find_key(scene_keys, FB_NKEYS(scene_keys), flag);
    }
    const fb_gen_class *cls = kind_class(kind);
    for (int i = 0; cls && i < cls->nkeys; i++)
        if (!strcmp(flag_of(&cls->keys[i]), flag)) return &cls->keys[i];
    for (int i = 0; cls && i < cls->nkeys; i++) /* a key without a flag of its own also answers to its name */
        if (!cls->keys[i].flag && !strcmp(cls->keys[i].key, flag)) return &cls->keys[i];
    *scene_level = true;
    return find_key(scene_keys, FB_NKEYS(scene_keys), flag);
}

int fb_scene_flags(const char *kind, const char **out, int max)
{
    int n = 0;
    const fb_gen_class *cls = kind_class(kind);
    for (int i = 0; cls && i < cls->nkeys && n < max; i++)
        if (cls->keys[i].type != FB_K_TYPE && strcmp(cls->keys[i].key, "compression"))
            out[n++] = flag_of(&cls->keys[i]);
    for (int i = 0; i < FB_NKEYS(scene_keys) && n < max; i++)
        if (scene_keys[i].type != FB_K_LAYERS) out[n++] = scene_keys[i].key;
    if (n < max) out[n++] = "float";
    return n;
}

int fb_scene_flag_arity(const char *kind, const char *flag)
{
    bool scene_level;
    if (!strcmp(flag, "float")) return 0;
    const fb_keyspec *k = flag_spec(kind, flag, &scene_level);
    if (!k) return -1;
    return k->type == FB_K_BOOL ? 0 : 1;
}

static bool parse_double(const char *s, double *out)
{
    char *end;
    errno = 0;
    *out = strtod(s, &end);
    return *s && !*end && errno == 0;
}

/* Converts one flag's text to the JSON value its key takes; logs and returns NULL on failure. */
static json_t *flag_value(const fb_keyspec *k, const char *flag, const char *s)
{
    double a, b;
    char *end;
    switch (k->type) {
    case FB_K_INT: {
        errno = 0;
        long long x = strtoll(s, &end, 10);
        if (*s && *end && !errno && parse_double(s, &a) && a == floor(a) && fabs(a) <= 9007199254740992.0)
            return json_integer((json_int_t)a); /* 1e9: an integer written in exponent form */
        if (!*s || *end || errno) {
            fb_fail(FB_ERR_USAGE, "--%s: expected an integer, found \"%s\"", flag, s);
            return NULL;
        }
        return json_integer(x);
    }
    case FB_K_NUM:
        if (!parse_double(s, &a) || !isfinite(a)) {
            fb_fail(FB_ERR_USAGE, "--%s: expected a finite number, found \"%s\"", flag, s);
            return NULL;
        }
        return json_real(a);
    case FB_K_VEC2: {
        const char *comma = strchr(s, ',');
        char first[64];
        if (!comma || comma - s >= 63) goto bad_vec;
        snprintf(first, sizeof first, "%.*s", (int)(comma - s), s);
        if (!parse_double(first, &a) || !parse_double(comma + 1, &b) || !isfinite(a) || !isfinite(b)) goto bad_vec;
        return json_pack("[ff]", a, b);
    bad_vec:
        fb_fail(FB_ERR_USAGE, "--%s: expected two finite numbers X,Y, found \"%s\"", flag, s);
        return NULL;
    }
    case FB_K_SIZE: {
        errno = 0;
        long long w = strtoll(s, &end, 10);
        if (end == s || (*end != 'x' && *end != 'X') || errno) goto bad_size;
        const char *hs = end + 1;
        long long h = strtoll(hs, &end, 10);
        if (end == hs || *end || errno) goto bad_size;
        if (w < 1 || h < 1 || w > FB_MAX_DIM || h > FB_MAX_DIM) {
            fb_fail(FB_ERR_USAGE, "--%s: each side must be in 1..%d, found \"%s\"", flag, FB_MAX_DIM, s);
            return NULL;
        }
        return json_pack("[II]", (json_int_t)w, (json_int_t)h);
    bad_size:
        fb_fail(FB_ERR_USAGE, "--%s: expected WIDTHxHEIGHT such as 1024x512, found \"%s\"", flag, s);
        return NULL;
    }
    case FB_K_NUMLIST: {
        json_t *arr = json_array();
        const char *q = s;
        for (int i = 0; i < k->count; i++) {
            char *e;
            double x = strtod(q, &e);
            if (e == q || !isfinite(x) || (i + 1 < k->count ? *e != ',' : *e != 0)) {
                json_decref(arr);
                fb_fail(FB_ERR_USAGE, "--%s: expected %d comma-separated finite numbers, found \"%s\"", flag, k->count,
                        s);
                return NULL;
            }
            json_array_append_new(arr, json_real(x));
            q = e + 1;
        }
        return arr;
    }
    case FB_K_STOPS: {
        /* "t,r,g,b;t,r,g,b;...": the scene's [[t, r, g, b], ...] on one line */
        json_t *arr = json_array();
        const char *q = s;
        while (*q) {
            double t[4];
            for (int c = 0; c < 4; c++) {
                char *e;
                t[c] = strtod(q, &e);
                if (e == q || !isfinite(t[c]) || (c < 3 && *e != ',') || (c == 3 && *e != ';' && *e != 0)) {
                    json_decref(arr);
                    fb_fail(FB_ERR_USAGE, "--%s: expected stops t,r,g,b;t,r,g,b;..., found \"%s\"", flag, s);
                    return NULL;
                }
                q = *e ? e + 1 : e;
            }
            json_array_append_new(arr, json_pack("[ffff]", t[0], t[1], t[2], t[3]));
        }
        return arr;
    }
    case FB_K_CUSTOM:
        if (k->value && k->value->from_flag) return k->value->from_flag(k, flag, s);
        return json_string(s);
    case FB_K_NAMES: { /* "iter,n,R,G,B": the names are checked with the scene */
        json_t *arr = json_array();
        for (const char *q = s;;) {
            const char *e = strchr(q, ',');
            size_t len = e ? (size_t)(e - q) : strlen(q);
            json_array_append_new(arr, json_stringn(q, len));
            if (!e) break;
            q = e + 1;
        }
        return arr;
    }
    case FB_K_BOUNDS:
    case FB_K_FRACS: {
        if (k->type == FB_K_BOUNDS && !strcmp(s, "auto")) return json_string(s);
        json_t *arr = json_array();
        const char *q = s;
        while (*q) {
            char *e;
            double x = strtod(q, &e);
            if (e == q || !isfinite(x) || (*e != ',' && *e != 0)) {
                json_decref(arr);
                fb_fail(FB_ERR_USAGE, "--%s: expected comma-separated finite numbers%s, found \"%s\"", flag,
                        k->type == FB_K_BOUNDS ? " XMIN,XMAX,YMIN,YMAX or auto" : "", s);
                return NULL;
            }
            json_array_append_new(arr, json_real(x));
            q = *e ? e + 1 : e;
        }
        return arr;
    }
    default:
        return json_string(s);
    }
}

fb_result fb_scene_from_flags(const char *kind, int argc, char **argv, char **json)
{
    fb_result rc = FB_OK;
    json_t *root = json_object(), *layer = json_object(), *layers = json_array();
    if (!root || !layer || !layers) {
        rc = fb_fail(FB_ERR_NOMEM, "out of memory");
        goto out;
    }
    json_object_set_new(layer, "type", json_string(kind));
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i];
        if (strncmp(a, "--", 2) != 0) {
            rc = fb_fail(FB_ERR_USAGE, "%s: unexpected argument (flags start with --)", a);
            goto out;
        }
        const char *flag = a + 2;
        if (!strcmp(flag, "float") || !strcmp(flag, "half")) {
            json_object_set_new(layer, "half", json_boolean(!strcmp(flag, "half")));
            continue;
        }
        bool scene_level;
        const fb_keyspec *k = flag_spec(kind, flag, &scene_level);
        if (!k) {
            rc = fb_fail(FB_ERR_USAGE, "--%s: unknown flag for `fractalbake %s` (see fractalbake %s --help)", flag,
                         kind, kind);
            goto out;
        }
        json_t *target = scene_level ? root : layer;
        json_t *val;
        if (k->type == FB_K_RULES) { /* repeatable: each --rule adds one production */
            if (i + 1 >= argc) {
                rc = fb_fail(FB_ERR_USAGE, "--%s: missing value", flag);
                goto out;
            }
            json_t *list = json_object_get(layer, k->key);
            if (!list) json_object_set_new(layer, k->key, list = json_array());
            json_array_append_new(list, json_string(argv[++i]));
            continue;
        }
        if (k->type == FB_K_BOOL) {
            val = json_true();
        } else {
            if (i + 1 >= argc) {
                rc = fb_fail(FB_ERR_USAGE, "--%s: missing value", flag);
                goto out;
            }
            val = flag_value(k, flag, argv[++i]);
            if (!val) {
                rc = FB_ERR_USAGE;
                goto out;
            }
        }
        json_object_set_new(target, k->key, val);
    }
    json_array_append_new(layers, layer);
    layer = NULL;
    json_object_set_new(root, "layers", layers);
    layers = NULL;
    *json = json_dumps(root, JSON_SORT_KEYS | JSON_REAL_PRECISION(17));
    if (!*json) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
out:
    json_decref(layer);
    json_decref(layers);
    json_decref(root);
    return rc;
}

/* A number as a user writes it: integers in full (4294967295, not 4.29497e+09), else the shortest
 * text that reads back as the same double (0.1, 1.01). */
static void fmt_num(double x, char *out, size_t size)
{
    if (x == floor(x) && fabs(x) < 1e15) {
        snprintf(out, size, "%.0f", x);
        return;
    }
    fb_format_shortest(x, out, size);
}

void fb_scene_print_keys(const char *kind, void (*print)(const char *line, void *user), void *user)
{
    const fb_gen_class *cls = kind_class(kind);
    char line[512];
    if (!cls) return;
    int width = 0; /* the flag column: as wide as the longest flag */
    for (int pass = 0; pass < 2; pass++) {
        const fb_keyspec *ks = pass ? scene_keys : cls->keys;
        int nk = pass ? FB_NKEYS(scene_keys) : cls->nkeys;
        for (int i = 0; i < nk; i++)
            if ((int)strlen(flag_of(&ks[i])) > width) width = (int)strlen(flag_of(&ks[i]));
    }
    for (int pass = 0; pass < 2; pass++) {
        const fb_keyspec *ks = pass ? scene_keys : cls->keys;
        int nk = pass ? FB_NKEYS(scene_keys) : cls->nkeys;
        for (int i = 0; i < nk; i++) {
            const fb_keyspec *k = &ks[i];
            if (k->type == FB_K_TYPE || k->type == FB_K_LAYERS) continue;
            if (!pass && !strcmp(k->key, "compression")) continue; /* the flag sets the scene's (listed below) */
            char range[96] = "", lo[32], hi[32];
            fmt_num(k->lo, lo, sizeof lo);
            fmt_num(k->hi, hi, sizeof hi);
            if (k->type == FB_K_INT || k->type == FB_K_NUM)
                snprintf(range, sizeof range, " %s%s..%s]", k->lo_open ? "(" : "[", lo, hi);
            else if (k->type == FB_K_ENUM)
                snprintf(range, sizeof range, " %s", k->enums);
            else if (k->type == FB_K_NAMES)
                snprintf(range, sizeof range, " (comma list of %s)", k->enums);
            snprintf(line, sizeof line, "  --%-*s  %s%s%s%s", width, flag_of(k), k->help, range,
                     k->def ? "; default " : "", k->def ? k->def : "");
            print(line, user);
        }
    }
}
