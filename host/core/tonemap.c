/* Re-toning a stored layer: see tonemap.h. */
#include "tonemap.h"

#include "exrio.h"
#include "gen.h"
#include "preview.h"
#include "scene.h"

#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Whether `k` is one of class c's tone keys. */
static bool tone_key(const fb_gen_class *c, const char *k)
{
    for (const char *const *t = c->tone->keys; *t; t++)
        if (!strcmp(k, *t)) return true;
    return false;
}

/* "--brightness, --gamma, ...": class c's tone flags, for messages and help. */
static void tone_flags(const fb_gen_class *c, char *out, size_t size)
{
    out[0] = 0;
    for (const char *const *t = c->tone->keys; *t; t++)
        snprintf(out + strlen(out), size - strlen(out), "%s--%s", t == c->tone->keys ? "" : ", ", *t);
}

int fb_tone_classes(char *out, size_t size)
{
    int n = 0;
    out[0] = 0;
    for (const fb_gen_class *const *c = fb_gen_list; *c; c++)
        if ((*c)->tone) snprintf(out + strlen(out), size - strlen(out), "%s%s", n++ ? ", " : "", (*c)->name);
    return n;
}

/* Merges the new tone keys (d->tone's) into layer object `lj` of class c; a new colour map replaces
 * the old one of whatever kind. */
static fb_result apply_tone(const fb_tonemap_desc *d, const fb_gen_class *c, json_t *lj)
{
    char *flags_json = NULL;
    fb_result rc = d->tone(c, d->user, &flags_json);
    if (rc) return rc;
    json_t *root = json_loads(flags_json, 0, NULL);
    free(flags_json);
    json_t *given = json_array_get(json_object_get(root, "layers"), 0);
    const char *key;
    json_t *val;
    json_object_foreach(given, key, val)
    {
        if (!strcmp(key, "type")) continue;
        if (!tone_key(c, key)) { /* the message first: `key` belongs to root */
            char list[512];
            tone_flags(c, list, sizeof list);
            rc = fb_fail(FB_ERR_USAGE, "--%s: not a tone-mapping flag of %s (tonemap takes %s)", key, c->what, list);
            json_decref(root);
            return rc;
        }
        if (!strcmp(key, "palette") || !strcmp(key, "cosine") || !strcmp(key, "stops")) {
            json_object_del(lj, "palette"); /* the one given replaces the stored colour map */
            json_object_del(lj, "cosine");
            json_object_del(lj, "stops");
        }
        json_object_set(lj, key, val);
    }
    json_decref(root);
    return FB_OK;
}

/* The preview of layer `name`'s colour, R, G and B of the file (their indices into rgb), drawn as a bake draws
 * the layer alone. */
static fb_result preview_of(const exrio_reader *r, const char *name, const char *in, int rgb[3], fb_preview **out)
{
    char want[96];
    for (int k = 0; k < 3; k++) {
        snprintf(want, sizeof want, "%s.%c", name, "RGB"[k]);
        rgb[k] = -1;
        for (int c = 0; c < exrio_nchannels(r); c++)
            if (!strcmp(exrio_channel_name(r, c), want) && exrio_channel_type(r, c) != EXRIO_UINT) rgb[k] = c;
        if (rgb[k] < 0) return fb_fail(FB_ERR_INPUT, "%s: no channel %s for the preview", in, want);
    }
    return fb_preview_create(exrio_width(r), exrio_height(r), 2048, 3, out);
}

fb_result fb_tonemap(const fb_tonemap_desc *d)
{
    const char *in = d->in, *out = d->out, *layer = d->layer;
    fb_result rc = FB_OK;
    exrio_reader *r = NULL;
    exrio_writer *w = NULL;
    json_t *root = NULL;
    fb_scene scene = {0};
    float *strip = NULL;
    void **planes = NULL;
    exrio_channel *chans = NULL;
    char *text = NULL;
    if (!rc) rc = exrio_open(in, &r);
    const char *stored = rc ? NULL : exrio_attr_string(r, "fractalbake/scene");
    if (!rc && !stored) rc = fb_fail(FB_ERR_INPUT, "%s: no fractalbake scene in the header", in);
    if (!rc && !(root = json_loads(stored, 0, NULL)))
        rc = fb_fail(FB_ERR_INPUT, "%s: the stored scene is not valid JSON", in);
    /* the layer: named, or the first that can be re-toned */
    json_t *lj = NULL;
    size_t li = 0;
    const fb_gen_class *cls = NULL;
    json_t *layers = root ? json_object_get(root, "layers") : NULL;
    for (size_t i = 0; !rc && i < json_array_size(layers) && !lj; i++) {
        json_t *l = json_array_get(layers, i);
        const char *t = json_string_value(json_object_get(l, "type")),
                   *n = json_string_value(json_object_get(l, "name"));
        const fb_gen_class *c = t ? fb_gen_find(t) : NULL;
        if (c && c->tone && (!layer || (n && !strcmp(n, layer)))) lj = l, li = i, cls = c;
    }
    if (!rc && !lj) {
        char classes[256];
        fb_tone_classes(classes, sizeof classes);
        rc = fb_fail(FB_ERR_INPUT, "%s: no layer%s%s in the stored scene that tonemap can re-tone (%s layers)", in,
                     layer ? " named " : "", layer ? layer : "", classes);
    }
    if (!rc) rc = apply_tone(d, cls, lj);
    if (!rc && !(text = json_dumps(root, JSON_SORT_KEYS | JSON_REAL_PRECISION(17))))
        rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    if (!rc) rc = fb_scene_parse(text, NULL, &scene);

    int width = r ? exrio_width(r) : 0, height = r ? exrio_height(r) : 0, nch = r ? exrio_nchannels(r) : 0;
    const fb_layer *L = rc ? NULL : &scene.layers[li];
    if (!rc && (scene.width != width || scene.height != height))
        rc = fb_fail(FB_ERR_INPUT, "%s: the stored scene's size does not match the image", in);
    /* pass 1: what the tone map reads of the whole image */
    void *tone = NULL;
    if (!rc) rc = cls->tone->begin(L, r, in, &tone);
    /* pass 2: every channel, strip by strip, the layer's colour recomputed */
    const int rows = 64;
    if (!rc) {
        planes = calloc((size_t)nch, sizeof *planes);
        chans = calloc((size_t)nch, sizeof *chans);
        strip = malloc((size_t)nch * rows * width * 4);
        if (!planes || !chans || !strip) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    }
    for (int c = 0; !rc && c < nch; c++) {
        planes[c] = strip + (size_t)c * rows * width;
        chans[c] = (exrio_channel){exrio_channel_name(r, c), exrio_channel_type(r, c)};
    }
    if (!rc) {
        /* the bake's own attributes, in the bake's order, so that unchanged parameters give the same bytes */
        const char *keys[] = {"fractalbake/seed",    "fractalbake/backend", "fractalbake/device",
                              "fractalbake/version", "fractalbake/region",  "fractalbake/layer-backends"};
        exrio_attr attrs[7] = {{"fractalbake/scene", scene.json}};
        int na = 1;
        for (int k = 0; k < 6; k++) {
            const char *v = exrio_attr_string(r, keys[k]);
            if (v) attrs[na++] = (exrio_attr){keys[k], v};
        }
        exrio_compression comp = (exrio_compression)exrio_compression_parse(exrio_compression_of(r));
        rc = exrio_writer_create(&(exrio_writer_desc){.path = out,
                                                      .width = width,
                                                      .height = height,
                                                      .compression = comp,
                                                      .channels = chans,
                                                      .nchannels = nch,
                                                      .attrs = attrs,
                                                      .nattrs = na,
                                                      .envmap = scene.envmap},
                                 &w);
    }
    fb_preview *pv = NULL;
    int rgb[3];
    if (!rc && d->preview) rc = preview_of(r, L->name, in, rgb, &pv);
    for (int y = 0; y < height && !rc; y += rows) {
        int m = y + rows <= height ? rows : height - y;
        rc = exrio_read_rows(r, y, m, planes);
        if (rc) break;
        cls->tone->rows(tone, m, planes);
        rc = exrio_writer_rows(w, y, m, (const void *const *)planes);
        if (pv) fb_preview_add_rows(pv, y, m, (const float *const[]){planes[rgb[0]], planes[rgb[1]], planes[rgb[2]]});
    }
    if (!rc) rc = exrio_writer_finish(&w);
    if (!rc && pv) rc = fb_preview_write_png(pv, d->preview, "preview");
    fb_preview_destroy(&pv);
    exrio_writer_abort(&w);
    if (cls && tone) cls->tone->end(tone);
    exrio_close(&r);
    json_decref(root);
    fb_scene_fini(&scene);
    free(text);
    free(strip);
    free(planes);
    free(chans);
    return rc;
}
