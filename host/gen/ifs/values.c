/*
 * The ifs layer's value types (schema.h: fb_kvalue): affine maps, and the condensation set (a preset
 * name, a map list or an L-system object), checked for the scene engine and read from flags.
 */
#include "gen_ifs.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

/* [[a, b, c, d, e, f(, p)], ...]: 1..64 maps of 6 or 7 finite numbers, p >= 0. */
static fb_result check_maps(const fb_vctx *v, const char *path, const fb_keyspec *k, json_t *j)
{
    char shown[64], sub[256];
    fb_json_show(j, shown, sizeof shown);
    size_t n = json_is_array(j) ? json_array_size(j) : 0;
    if (n < 1 || n > (size_t)k->count)
        return fb_schema_error(v, path, "expected a list of 1 to %d maps [a, b, c, d, e, f, p], found %s", k->count,
                               shown);
    for (size_t i = 0; i < n; i++) {
        const json_t *m = json_array_get(j, i);
        size_t len = json_is_array(m) ? json_array_size(m) : 0;
        snprintf(sub, sizeof sub, "%s[%zu]", path, i);
        fb_json_show(m, shown, sizeof shown);
        if (len != 6 && len != 7)
            return fb_schema_error(v, sub, "expected a map [a, b, c, d, e, f] or [a, b, c, d, e, f, p], found %s",
                                   shown);
        for (size_t c = 0; c < len; c++) {
            const json_t *e = json_array_get(m, c);
            double x = json_is_number(e) ? json_number_value(e) : NAN;
            if (!isfinite(x) || x < k->lo || x > k->hi)
                return fb_schema_error(v, sub, "coefficient %c is not a finite number in %g..%g (found %s)",
                                       "abcdefp"[c], k -> lo, k -> hi, shown);
            if (c == 6 && x < 0) return fb_schema_error(v, sub, "probability %g is negative", x);
        }
    }
    return FB_OK;
}

/* "a,b,c,d,e,f[,p];...": the maps of a flag. */
static json_t *maps_from_flag(const fb_keyspec *k, const char *flag, const char *s)
{
    json_t *arr = json_array();
    const char *q = s;
    while (*q) {
        json_t *m = json_array();
        for (int c = 0; c < 7; c++) {
            char *e;
            double x = strtod(q, &e);
            if (e == q || !isfinite(x) || (*e != ',' && *e != ';' && *e != 0) || (c == 6 && *e == ',')) {
                json_decref(m);
                json_decref(arr);
                fb_fail(FB_ERR_USAGE, "--%s: expected maps a,b,c,d,e,f[,p];..., found \"%s\"", flag, s);
                return NULL;
            }
            json_array_append_new(m, json_real(x));
            q = *e == ',' ? e + 1 : e;
            if (*e != ',') break;
        }
        json_array_append_new(arr, m);
        if (*q == ';') q++;
    }
    return arr;
}

/* A checked map list into the fb_ifs at field; a missing probability is -1. */
static fb_result read_maps(const fb_vctx *v, const char *path, const json_t *j, void *field)
{
    fb_ifs *out = field;
    memset(out, 0, sizeof *out);
    out->n = (int)json_array_size(j);
    for (int k = 0; k < out->n; k++) {
        const json_t *m = json_array_get(j, (size_t)k);
        double c[7] = {0, 0, 0, 0, 0, 0, -1};
        for (size_t i = 0; i < json_array_size(m); i++) c[i] = json_number_value(json_array_get(m, i));
        out->m[k] = (fb_ifs_map){c[0], c[1], c[2], c[3], c[4], c[5], c[6]};
    }
    return FB_OK;
}

const fb_kvalue fb_ifs_maps_value = {.check = check_maps, .from_flag = maps_from_flag, .read = read_maps};

/* A condensation set: a preset name from `enums`, a map list, or an L-system object (checked by the
 * layer's parse). */
static fb_result check_condensation(const fb_vctx *v, const char *path, const fb_keyspec *k, json_t *j)
{
    if (json_is_object(j)) return FB_OK;
    if (json_is_string(j)) {
        int idx;
        char shown[64];
        fb_json_show(j, shown, sizeof shown);
        if (!fb_enum_index(k->enums, json_string_value(j), &idx))
            return fb_schema_error(v, path,
                                   "expected an IFS preset name (%s), a map list or an L-system {\"preset\": ...}, "
                                   "found %s",
                                   k->enums, shown);
        return FB_OK;
    }
    return check_maps(v, path, k, j);
}

/* "lsystem:tree", a JSON object, a preset name, or maps. */
static json_t *condensation_from_flag(const fb_keyspec *k, const char *flag, const char *s)
{
    if (!strncmp(s, "lsystem:", 8)) return json_pack("{ss}", "preset", s + 8);
    if (*s == '{') {
        json_t *obj = json_loads(s, JSON_REJECT_DUPLICATES, NULL);
        if (json_is_object(obj)) return obj;
        json_decref(obj);
        fb_fail(FB_ERR_USAGE, "--%s: expected a JSON object such as {\"preset\": \"tree\"}, found \"%s\"", flag, s);
        return NULL;
    }
    if (isalpha((unsigned char)*s)) return json_string(s);
    return maps_from_flag(k, flag, s);
}

/* A condensation set's IFS into the fb_ifs at field: a preset's or a map list's (an L-system object is
 * the layer's parse's, with its own keys). */
static fb_result read_condensation(const fb_vctx *v, const char *path, const json_t *j, void *field)
{
    if (json_is_string(j)) return fb_ifs_preset(json_string_value(j), field, NULL, NULL);
    return json_is_array(j) ? read_maps(v, path, j, field) : FB_OK;
}

const fb_kvalue fb_ifs_condensation_value = {
    .check = check_condensation, .from_flag = condensation_from_flag, .read = read_condensation};
