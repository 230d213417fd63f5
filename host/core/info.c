/* `fractalbake info`: an EXR's size, compression, parts, channels, attributes and stored scene. */
#include "info.h"

#include "exrio.h"
#include "jsonout.h"

#include <jansson.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The layer of a channel: the text before its last dot ("" for none). */
static int layer_len(const char *name)
{
    const char *dot = strrchr(name, '.');
    return dot ? (int)(dot - name) : 0;
}

fb_result fb_info(const char *path, bool json, void (*print)(const char *line, void *user), void *user)
{
    exrio_reader *r = NULL;
    fb_result rc = exrio_open(path, &r);
    if (rc) return rc;
    json_t *o = json_object(), *layers = json_array(), *attrs = json_object(), *parts = json_array();
    char line[4096];
#define P(...)                                                                                                         \
    do {                                                                                                               \
        if (!json) {                                                                                                   \
            snprintf(line, sizeof line, __VA_ARGS__);                                                                  \
            print(line, user);                                                                                         \
        }                                                                                                              \
    } while (0)
    P("file:        %s", path);
    json_object_set_new(o, "file", json_string(path));
    int win[4];
    exrio_window(r, &win[0], &win[1], &win[2], &win[3]);
    json_object_set_new(o, "size", json_pack("[ii]", exrio_width(r), exrio_height(r)));
    if (win[0] || win[1] || win[2] != exrio_width(r) || win[3] != exrio_height(r)) {
        P("size:        %d x %d: the region %d,%d,%d,%d of a %d x %d image", exrio_width(r), exrio_height(r), win[0],
          win[1], exrio_width(r), exrio_height(r), win[2], win[3]);
        json_object_set_new(o, "region", json_pack("[iiii]", win[0], win[1], exrio_width(r), exrio_height(r)));
        json_object_set_new(o, "full_size", json_pack("[ii]", win[2], win[3]));
    } else {
        P("size:        %d x %d", exrio_width(r), exrio_height(r));
    }
    int np = exrio_nparts(r);
    if (np > 1) {
        P("parts:       %d", np);
        for (int p = 0; p < np; p++) {
            P("  part %-2d %-12s compression %s, %s", p, exrio_part_name(r, p), exrio_part_compression(r, p),
              exrio_part_storage(r, p));
            json_array_append_new(parts, json_pack("{ssssss}", "name", exrio_part_name(r, p), "compression",
                                                   exrio_part_compression(r, p), "storage", exrio_part_storage(r, p)));
        }
        json_object_set_new(o, "parts", parts);
        parts = NULL;
    } else {
        P("compression: %s", exrio_compression_of(r));
        json_object_set_new(o, "compression", json_string(exrio_compression_of(r)));
        P("storage:     %s", exrio_part_storage(r, 0));
        json_object_set_new(o, "storage", json_string(exrio_part_storage(r, 0)));
    }
    exrio_envmap env = exrio_envmap_of(r);
    if (env != EXRIO_ENVMAP_NONE) {
        const char *ename = env == EXRIO_ENVMAP_LATLONG ? "latlong" : "cube";
        P("envmap:      %s", ename);
        json_object_set_new(o, "envmap", json_string(ename));
    }
    P("channels:    %d", exrio_nchannels(r));
    /* Channels grouped by layer (the text before the last dot) within each part; the layer is named
     * in full, and a part's channels without a dot are its part's (a multi-part file) or "(no
     * layer)". */
    for (int c = 0; c < exrio_nchannels(r); c++) {
        const char *name = exrio_channel_name(r, c);
        int part = exrio_channel_part(r, c), llen = layer_len(name);
        bool first = true;
        for (int k = 0; k < c && first; k++) {
            const char *q = exrio_channel_name(r, k);
            first = !(exrio_channel_part(r, k) == part && layer_len(q) == llen && !strncmp(q, name, (size_t)llen));
        }
        if (!first) continue;
        char lname[300];
        if (llen)
            snprintf(lname, sizeof lname, "%.*s", llen, name);
        else
            snprintf(lname, sizeof lname, "%s",
                     np > 1 && exrio_part_name(r, part)[0] ? exrio_part_name(r, part) : "(no layer)");
        char chans[2048] = "";
        json_t *jl = json_object(), *jc = json_array();
        for (int k = c; k < exrio_nchannels(r); k++) {
            const char *q = exrio_channel_name(r, k);
            if (exrio_channel_part(r, k) != part || layer_len(q) != llen || strncmp(q, name, (size_t)llen)) continue;
            const char *short_name = llen ? q + llen + 1 : q, *type = exrio_type_name(exrio_channel_type(r, k));
            snprintf(chans + strlen(chans), sizeof chans - strlen(chans), "%s%s (%s)", chans[0] ? ", " : "", short_name,
                     type);
            json_array_append_new(jc, json_pack("{ssssss}", "name", q, "channel", short_name, "type", type));
        }
        P("  layer %-10s %s", lname, chans);
        json_object_set_new(jl, "layer", json_string(llen ? lname : ""));
        if (np > 1) json_object_set_new(jl, "part", json_integer(part));
        json_object_set_new(jl, "channels", jc);
        json_array_append_new(layers, jl);
    }
    json_object_set_new(o, "layers", layers);
    P("attributes:");
    for (int i = 0; i < exrio_attr_count(r); i++) {
        const char *name, *type;
        exrio_attr_at(r, i, &name, &type);
        if (!strcmp(name, "fractalbake/scene")) continue;
        char val[2048];
        exrio_attr_text(r, i, val, sizeof val);
        json_object_set_new(attrs, name, json_pack("{ssss}", "type", type, "value", val));
        char shown[2048], *o = shown; /* one line each: control characters as \n, \t, ? */
        for (const char *c = val; *c && o < shown + sizeof shown - 3; c++)
            if ((unsigned char)*c >= 0x20)
                *o++ = *c;
            else
                *o++ = '\\', *o++ = *c == '\n' ? 'n' : *c == '\t' ? 't' : '?';
        *o = 0;
        P("  %-26s %-12s %s", name, type, shown);
    }
    json_object_set_new(o, "attributes", attrs);
    const char *scene = exrio_attr_string(r, "fractalbake/scene");
    json_t *sj = scene ? json_loads(scene, 0, NULL) : NULL;
    if (scene) {
        P("stored scene:");
        char *pretty = sj ? fb_json_dumps(sj, 2) : NULL;
        if (!json) print(pretty ? pretty : scene, user);
        free(pretty);
        json_object_set_new(o, "scene", sj ? sj : json_string(scene));
    } else {
        P("stored scene: none (not written by fractalbake)");
        json_object_set_new(o, "scene", json_null());
    }
#undef P
    if (json) {
        char *text = fb_json_dumps(o, 0);
        print(text ? text : "{}", user);
        free(text);
    }
    json_decref(o);
    json_decref(parts);
    exrio_close(&r);
    return FB_OK;
}
