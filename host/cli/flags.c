/*
 * Flags: a single-generator command line (`fractalbake fbm --octaves 12`) into the JSON scene it stands
 * for, every flag the scene key of the same name, checked against the generator's table; and --help
 * from the same table.
 */
#include "flags.h"

#include "gen.h"
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

/* ---- command-line flags --------------------------------------------------------------------- */

static const fb_keyspec *flag_spec(const char *kind, const char *flag, bool *scene_level)
{
    int nscene;
    const fb_keyspec *scene_keys = fb_scene_keys(&nscene);
    *scene_level = false;
    if (!strcmp(flag, "type") || !strcmp(flag, "layers")) return NULL;
    if (!strcmp(flag, "compression") || !strcmp(flag, "parts")) { /* the file's, not the layer's */
        *scene_level = true;
        return fb_key_find(scene_keys, nscene, flag);
    }
    const fb_gen_class *cls = fb_gen_find(kind);
    for (int i = 0; cls && i < cls->nkeys; i++)
        if (!strcmp(fb_key_flag(&cls->keys[i]), flag)) return &cls->keys[i];
    for (int i = 0; cls && i < cls->nkeys; i++) /* a key without a flag of its own also answers to its name */
        if (!cls->keys[i].flag && !strcmp(cls->keys[i].key, flag)) return &cls->keys[i];
    *scene_level = true;
    return fb_key_find(scene_keys, nscene, flag);
}

int fb_scene_flags(const char *kind, const char **out, int max)
{
    int nscene;
    const fb_keyspec *scene_keys = fb_scene_keys(&nscene);
    int n = 0;
    const fb_gen_class *cls = fb_gen_find(kind);
    for (int i = 0; cls && i < cls->nkeys && n < max; i++)
        if (cls->keys[i].type != FB_K_TYPE && strcmp(cls->keys[i].key, "compression"))
            out[n++] = fb_key_flag(&cls->keys[i]);
    for (int i = 0; i < nscene && n < max; i++)
        if (scene_keys[i].type != FB_K_LAYERS) out[n++] = scene_keys[i].key;
    if (n < max) out[n++] = "float";
    return n;
}

int fb_scene_flag_arity(const char *kind, const char *flag)
{
    bool scene_level;
    if (!strcmp(flag, "float") || !strcmp(flag, "half")) return 0; /* the layer's output type */
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
        if (k->type != FB_K_BOOL && i + 1 < argc && !fb_text_utf8(argv[i + 1])) {
            rc = fb_fail(FB_ERR_USAGE, "--%s: the value is not UTF-8 text (a scene holds JSON strings)", flag);
            goto out;
        }
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
    /* a named palette beside a cosine or gradient one would be ignored */
    if (json_object_get(layer, "palette") && (json_object_get(layer, "stops") || json_object_get(layer, "cosine"))) {
        rc = fb_fail(FB_ERR_USAGE, "--palette with --%s: the named palette would be ignored; give one of them",
                     json_object_get(layer, "stops") ? "stops" : "cosine");
        goto out;
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
    int nscene;
    const fb_keyspec *scene_keys = fb_scene_keys(&nscene);
    const fb_gen_class *cls = fb_gen_find(kind);
    char line[512];
    if (!cls) return;
    int width = 0; /* the flag column: as wide as the longest flag */
    for (int pass = 0; pass < 2; pass++) {
        const fb_keyspec *ks = pass ? scene_keys : cls->keys;
        int nk = pass ? nscene : cls->nkeys;
        for (int i = 0; i < nk; i++)
            if ((int)strlen(fb_key_flag(&ks[i])) > width) width = (int)strlen(fb_key_flag(&ks[i]));
    }
    for (int pass = 0; pass < 2; pass++) {
        const fb_keyspec *ks = pass ? scene_keys : cls->keys;
        int nk = pass ? nscene : cls->nkeys;
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
            snprintf(line, sizeof line, "  --%-*s  %s%s%s%s", width, fb_key_flag(k), k->help, range,
                     k->def ? "; default " : "", k->def ? k->def : "");
            print(line, user);
        }
    }
}
