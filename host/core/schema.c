/*
 * The schema engine: a generator's key table (schema.h) checks the JSON of its layer, fills in the
 * defaults and names the file and line, the --set or the flag of a bad value. It knows no generator
 * by name; scene.c drives it for the scene and each layer.
 */
#include "schema.h"

#include "gen.h"
#include "scene.h"
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

const fb_keyspec *fb_key_find(const fb_keyspec *keys, int n, const char *key)
{
    for (int i = 0; i < n; i++)
        if (!strcmp(keys[i].key, key)) return &keys[i];
    return NULL;
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
        [FB_K_PATH] = "path",     [FB_K_RULES] = "rules",     [FB_K_REF] = "ref",         [FB_K_REFS] = "refs",
        [FB_K_CUSTOM] = "custom",
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

static fb_result check_name(const fb_vctx *v, const char *path, const fb_keyspec *k, json_t *j, const char *shown)
{
    const char *s = json_is_string(j) ? json_string_value(j) : NULL;
    bool ok = s && *s && strlen(s) < 64;
    for (const char *p = s; ok && *p; p++)
        ok = (*p >= 'a' && *p <= 'z') || (*p >= 'A' && *p <= 'Z') || (*p >= '0' && *p <= '9') || *p == '_' || *p == '-';
    if (!ok) return fb_schema_error(v, path, "expected a name of 1 to 63 letters, digits, '_' or '-', found %s", shown);
    return FB_OK;
}

static fb_result check_pair(const fb_vctx *v, const char *path, const fb_keyspec *k, json_t *j, const char *shown)
{
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
            return fb_schema_error(v, path, "%s is %llu pixels; at most %llu are supported", shown, px, FB_MAX_PIXELS);
    }
    return FB_OK;
}

static fb_result check_numlist(const fb_vctx *v, const char *path, const fb_keyspec *k, json_t *j, const char *shown)
{
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

static fb_result check_stops(const fb_vctx *v, const char *path, const fb_keyspec *k, json_t *j, const char *shown)
{
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

static fb_result check_ref(const fb_vctx *v, const char *path, const fb_keyspec *k, json_t *j, const char *shown)
{
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

static fb_result check_bounds(const fb_vctx *v, const char *path, const fb_keyspec *k, json_t *j, const char *shown)
{
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

static fb_result check_fracs(const fb_vctx *v, const char *path, const fb_keyspec *k, json_t *j, const char *shown)
{
    size_t n = json_is_array(j) ? json_array_size(j) : 0;
    bool good = n >= 1 && n <= (size_t)k->count;
    for (size_t i = 0; good && i < n; i++) {
        const json_t *e = json_array_get(j, i);
        double x = json_is_number(e) ? json_number_value(e) : NAN;
        good = isfinite(x) && x >= k->lo && x <= k->hi;
    }
    if (!good)
        return fb_schema_error(v, path, "expected 1 to %d numbers in %g..%g, found %s", k->count, k->lo, k->hi, shown);
    return FB_OK;
}

static fb_result check_names(const fb_vctx *v, const char *path, const fb_keyspec *k, json_t *j, const char *shown)
{
    size_t n = json_is_array(j) ? json_array_size(j) : 0;
    bool good = n >= 1 && n <= 32;
    int idx;
    for (size_t i = 0; good && i < n; i++) {
        const json_t *e = json_array_get(j, i);
        good = json_is_string(e) && fb_enum_index(k->enums, json_string_value(e), &idx);
        for (size_t m = 0; good && m < i; m++)
            good = strcmp(json_string_value(json_array_get(j, m)), json_string_value(e));
    }
    if (!good) return fb_schema_error(v, path, "expected a list of distinct names from %s, found %s", k->enums, shown);
    return FB_OK;
}

static fb_result check_rules(const fb_vctx *v, const char *path, const fb_keyspec *k, json_t *j, const char *shown)
{
    size_t n = json_is_array(j) ? json_array_size(j) : 0;
    if (!json_is_array(j) || n > (size_t)k->count)
        return fb_schema_error(v, path, "expected a list of at most %d rules \"X=successor\", found %s", k->count,
                               shown);
    for (size_t i = 0; i < n; i++) {
        const json_t *e = json_array_get(j, i);
        char sub[256], msg[256];
        snprintf(sub, sizeof sub, "%s[%zu]", path, i);
        if (!json_is_string(e)) {
            char rule[64];
            fb_json_show(e, rule, sizeof rule);
            return fb_schema_error(v, sub, "expected a rule \"X=successor\", found %s", rule);
        }
        if (k->check && !k->check(json_string_value(e), msg, sizeof msg)) return fb_schema_error(v, sub, "%s", msg);
    }
    return FB_OK;
}

static fb_result check_refs(const fb_vctx *v, const char *path, const fb_keyspec *k, json_t *j, const char *shown)
{
    if (!json_is_array(j) || json_array_size(j) < 1 || json_array_size(j) > (size_t)k->count)
        return fb_schema_error(v, path, "expected a list of 1 to %d channels or numbers, found %s", k->count, shown);
    for (size_t i = 0; i < json_array_size(j); i++) {
        char sub[300];
        snprintf(sub, sizeof sub, "%s[%zu]", path, i);
        fb_result rc = fb_schema_check_value(v, sub, &(fb_keyspec){.type = FB_K_REF}, json_array_get(j, i));
        if (rc) return rc;
    }
    return FB_OK;
}

/* One switch over the key types: a value's shape and its one message, the longer ones in their own
 * functions above (a value type of a generator's own is its fb_kvalue's check). */
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
            return fb_schema_error(v, path, "expected a generator name (`fractalbake generators` lists them), found %s",
                                   shown);
        return FB_OK;
    case FB_K_NAME:
        return check_name(v, path, k, j, shown);
    case FB_K_VEC2:
    case FB_K_SIZE:
        return check_pair(v, path, k, j, shown);
    case FB_K_NUMLIST:
        return check_numlist(v, path, k, j, shown);
    case FB_K_STOPS:
        return check_stops(v, path, k, j, shown);
    case FB_K_REFS:
        return check_refs(v, path, k, j, shown);
    case FB_K_REF:
        return check_ref(v, path, k, j, shown);
    case FB_K_STRING:
    case FB_K_OUTPUT:
    case FB_K_PATH:
        if (!json_is_string(j) || !*json_string_value(j) || strlen(json_string_value(j)) >= 4096)
            return fb_schema_error(v, path, "expected a non-empty string, found %s", shown);
        return FB_OK;
    case FB_K_BOUNDS:
        return check_bounds(v, path, k, j, shown);
    case FB_K_FRACS:
        return check_fracs(v, path, k, j, shown);
    case FB_K_NAMES:
        return check_names(v, path, k, j, shown);
    case FB_K_RULES:
        return check_rules(v, path, k, j, shown);
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

/* A reference: a number, or a layer's channel resolved by name after parsing (scene.c). */
static void read_ref(const json_t *j, fb_ref *r)
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

/* ---- the fields the keys fill ---------------------------------------------------------------- */

/* Whether a key of type t may fill a field of kind f of `size` bytes (a list holds what it may take). */
static bool fits(const fb_keyspec *k)
{
    size_t nd = k->size / sizeof(double), nr = k->size / sizeof(fb_ref);
    switch (k->field) {
    case FB_F_NONE:
        return false;
    case FB_F_CORE:
    case FB_F_PARSE:
        return true;
    case FB_F_DOUBLE:
        return k->type == FB_K_NUM || k->type == FB_K_INT;
    case FB_F_INT:
    case FB_F_UNSIGNED:
        return k->type == FB_K_INT || k->type == FB_K_ENUM || (k->field == FB_F_UNSIGNED && k->type == FB_K_NAMES);
    case FB_F_U64:
        return k->type == FB_K_INT;
    case FB_F_BOOL:
        return k->type == FB_K_BOOL ||
               (k->type == FB_K_ENUM && k->enums && strchr(k->enums, '|') && !strchr(strchr(k->enums, '|') + 1, '|'));
    case FB_F_DOUBLES:
        return (k->type == FB_K_VEC2 && nd >= 2) || (k->type == FB_K_BOUNDS && nd >= 4) ||
               ((k->type == FB_K_NUMLIST || k->type == FB_K_FRACS) && k->count >= 1 && nd >= (size_t)k->count);
    case FB_F_CHARS:
        return k->size > 1 && (k->type == FB_K_STRING || k->type == FB_K_PATH || k->type == FB_K_OUTPUT ||
                               k->type == FB_K_ENUM || k->type == FB_K_CUSTOM);
    case FB_F_REF:
        return k->type == FB_K_REF;
    case FB_F_REFS:
        return k->type == FB_K_REFS && k->count >= 1 && nr >= (size_t)k->count;
    case FB_F_VALUE:
        return k->value && k->value->read;
    }
    return false;
}

bool fb_schema_declared(const fb_keyspec *keys, int n, size_t params_size, char *msg, size_t size)
{
    for (int i = 0; i < n; i++) {
        const fb_keyspec *k = &keys[i];
        const char *why =
            k->field == FB_F_NONE ? "fills no field and is not the engine's"
            : !fits(k)            ? "fills a field of a type its values do not fit"
            : k->field != FB_F_CORE && k->field != FB_F_PARSE && (k->size == 0 || k->off + k->size > params_size)
                ? "fills a field outside the parameters"
                : NULL;
        if (why) {
            snprintf(msg, size, "key \"%s\" (%s) %s", k->key, fb_ktype_name(k), why);
            return false;
        }
    }
    return true;
}

/* Writes checked value j of key k into its field of params. */
static fb_result fill(const fb_vctx *v, const char *path, const fb_keyspec *k, const json_t *j, void *params)
{
    if (k->field == FB_F_CORE || k->field == FB_F_PARSE) return FB_OK;
    if (!ALWAYS(fits(k))) return fb_fail(FB_ERR_INTERNAL, "key %s: its field does not fit its values", k->key);
    char *at = (char *)params + k->off;
    int idx = 0;
    if (k->type == FB_K_ENUM && json_is_string(j)) fb_enum_index(k->enums, json_string_value(j), &idx);
    switch (k->field) {
    case FB_F_DOUBLE:
        *(double *)(void *)at = json_number_value(j);
        break;
    case FB_F_INT:
        *(int *)(void *)at = k->type == FB_K_ENUM ? idx : (int)json_integer_value(j);
        break;
    case FB_F_UNSIGNED:
        if (k->type == FB_K_NAMES) {
            unsigned bits = 0;
            for (size_t i = 0; i < json_array_size(j); i++)
                if (fb_enum_index(k->enums, json_string_value(json_array_get(j, i)), &idx)) bits |= 1u << idx;
            *(unsigned *)(void *)at = bits;
        } else {
            *(unsigned *)(void *)at = k->type == FB_K_ENUM ? (unsigned)idx : (unsigned)json_integer_value(j);
        }
        break;
    case FB_F_U64:
        *(uint64_t *)(void *)at = (uint64_t)json_integer_value(j);
        break;
    case FB_F_BOOL:
        *(bool *)(void *)at = k->type == FB_K_ENUM ? idx == 1 : json_is_true(j);
        break;
    case FB_F_DOUBLES:
        for (size_t i = 0; json_is_array(j) && i < json_array_size(j) && i < k->size / sizeof(double); i++)
            ((double *)(void *)at)[i] = json_number_value(json_array_get(j, i));
        break;
    case FB_F_CHARS:
        if (json_is_string(j) && strlen(json_string_value(j)) >= k->size)
            return fb_schema_error(v, path, "longer than %zu characters", k->size - 1);
        snprintf(at, k->size, "%s", json_is_string(j) ? json_string_value(j) : "");
        break;
    case FB_F_REF:
        read_ref(j, (fb_ref *)(void *)at);
        break;
    case FB_F_REFS:
        for (size_t i = 0; i < json_array_size(j) && i < k->size / sizeof(fb_ref); i++)
            read_ref(json_array_get(j, i), (fb_ref *)(void *)at + i);
        break;
    case FB_F_VALUE:
        return k->value->read(v, path, j, at);
    case FB_F_NONE:
    case FB_F_CORE:
    case FB_F_PARSE:
        break;
    }
    return FB_OK;
}

/* Checks every key of `obj` against `keys`, fills in the defaults and the fields of params. */
fb_result fb_schema_check(const fb_vctx *v, const char *path, json_t *obj, const fb_keyspec *keys, int n,
                          const char *what, void *params)
{
    const char *key;
    json_t *val;
    char sub[256];
    json_object_foreach(obj, key, val)
    {
        snprintf(sub, sizeof sub, "%s%s%s", path, path[0] ? "." : "", key);
        const fb_keyspec *k = fb_key_find(keys, n, key);
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
    for (int i = 0; params && i < n; i++) {
        json_t *j = json_object_get(obj, keys[i].key);
        if (!j) continue;
        snprintf(sub, sizeof sub, "%s%s%s", path, path[0] ? "." : "", keys[i].key);
        fb_result rc = fill(v, sub, &keys[i], j, params);
        if (rc) return rc;
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

/* A named palette beside a cosine or gradient one, which would be ignored: reported at the key a
 * --set gave (either), else at the gradient's key in the file. */
static fb_result palette_twice(const fb_vctx *v, const char *path, const json_t *obj, const char *other)
{
    char sub[256], at_palette[256];
    snprintf(sub, sizeof sub, "%s.%s", path, other);
    snprintf(at_palette, sizeof at_palette, "%s.palette", path);
    for (int i = 0; i < v->nsets; i++)
        if (!strcmp(v->set_paths[i], at_palette)) snprintf(sub, sizeof sub, "%s", at_palette);
    const char *name = json_string_value(json_object_get(obj, "name"));
    return fb_schema_error(v, sub,
                           "layer \"%s\" gives palette and %s: the named palette would be ignored; give one "
                           "of them",
                           name ? name : "?", other);
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
    if (named && (cos_j || stops_j)) return palette_twice(v, path, obj, cos_j ? "cosine" : "stops");
    pal->has_cosine = cos_j != NULL;
    for (size_t i = 0; cos_j && i < 12; i++) pal->cosine[i] = json_number_value(json_array_get(cos_j, i));
    pal->nstops = stops_j ? (int)json_array_size(stops_j) : 0;
    for (int i = 0; i < pal->nstops; i++)
        for (int c = 0; c < 4; c++)
            pal->stops[i][c] = json_number_value(json_array_get(json_array_get(stops_j, (size_t)i), (size_t)c));
    return FB_OK;
}

fb_result fb_schema_relief(const fb_vctx *v, const char *path, const json_t *obj, fb_relief_spec *t)
{
    char sub[256];
    memset(t, 0, sizeof *t);
    t->colour = json_object_get(obj, "palette") || json_object_get(obj, "cosine") || json_object_get(obj, "stops");
    static const char *const needs_palette[3] = {"light", "ambient", "colour-range"};
    for (int k = 0; k < 3; k++)
        if (!t->colour && json_object_get(obj, needs_palette[k])) {
            snprintf(sub, sizeof sub, "%s.%s", path, needs_palette[k]);
            return fb_schema_error(v, sub, "%s shapes the colour by height: give palette, cosine or stops too",
                                   needs_palette[k]);
        }
    fb_result rc = t->colour ? fb_schema_palette(v, path, obj, &t->palette) : FB_OK;
    if (rc) return rc;
    const json_t *lj = json_object_get(obj, "light"), *cr = json_object_get(obj, "colour-range");
    t->light[0] = lj ? json_number_value(json_array_get(lj, 0)) : 315;
    t->light[1] = lj ? json_number_value(json_array_get(lj, 1)) : 45;
    if (t->light[1] < 0 || t->light[1] > 90) {
        snprintf(sub, sizeof sub, "%s.light", path);
        return fb_schema_error(v, sub, "the light's altitude must lie in 0..90 degrees, found %g", t->light[1]);
    }
    t->ambient = json_object_get(obj, "ambient") ? fb_json_num(obj, "ambient") : 0.2;
    t->range_set = cr != NULL;
    if (cr) {
        t->range[0] = json_number_value(json_array_get(cr, 0));
        t->range[1] = json_number_value(json_array_get(cr, 1));
        if (!(t->range[1] > t->range[0])) {
            snprintf(sub, sizeof sub, "%s.colour-range", path);
            return fb_schema_error(v, sub, "the second height must be above the first");
        }
    }
    return FB_OK;
}

bool fb_string_names_file(const char *text)
{
    (void)text;
    return true;
}
