/*
 * --set KEY.PATH=VALUE: an override applied to a scene's JSON before it is validated (scene.h:
 * fb_scene_parse_sets), so that a bad value is reported as the --set that gave it.
 */
#include "scene.h"

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
    const fb_gen_class *cls = fb_gen_find(json_string_value(json_object_get(layer, "type")));
    const fb_keyspec *k = cls ? fb_key_find(cls->keys, cls->nkeys, "name") : NULL;
    const char *def = k && k->def ? k->def : "\"\"";
    snprintf(out, n, "%.*s", (int)strlen(def) - 2, def + 1);
}

/* Applies one override to the scene's JSON, creating intermediate objects as needed; writes the key
 * path it set (layers[2].c) to jpath. In lists, a segment is an index or a layer name. */
fb_result fb_scene_apply_set(struct json_t *root, const char *set, char jpath[256])
{
    const char *eq = strchr(set, '=');
    if (!eq || eq == set)
        return fb_fail(FB_ERR_USAGE, "--set %s: expected KEY.PATH=VALUE (e.g. layers.sky.c=-0.8,0.156)", set);
    if (!fb_text_utf8(set))
        return fb_fail(FB_ERR_USAGE, "--set %.*s: the value is not UTF-8 text (a scene holds JSON strings)",
                       (int)(eq - set), set);
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
