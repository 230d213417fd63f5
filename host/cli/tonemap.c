/*
 * fractalbake tonemap: re-runs the tone mapping of an ifs layer from the density and colour
 * channels a bake stored, with new tone parameters, without iterating the chaos game again. The
 * output is the input file with that layer's R, G, B, A recomputed and the scene updated; with the
 * parameters unchanged it reproduces the bake bit for bit (tests/cli.sh).
 */
#include "tonemap.h"

#include "exrio.h"
#include "output.h"
#include "gen_ifs.h"
#include "scene.h"

#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The flags that only change the tone mapping. */
static const char *const k_tone_keys[] = {"brightness",      "gamma",   "gamma-threshold", "vibrancy",
                                          "highlight-power", "palette", "cosine",          "stops"};

static bool tone_key(const char *k)
{
    for (size_t i = 0; i < sizeof k_tone_keys / sizeof k_tone_keys[0]; i++)
        if (!strcmp(k, k_tone_keys[i])) return true;
    return false;
}

/* Merges the tone flags (already validated as ifs flags) into layer object `lj`; a new colour map
 * replaces the old one of whatever kind. */
static fb_result apply_flags(json_t *lj, int argc, char **argv)
{
    char *flags_json = NULL;
    fb_result rc = fb_scene_from_flags("ifs", argc, argv, &flags_json);
    if (rc) return rc;
    json_t *root = json_loads(flags_json, 0, NULL);
    free(flags_json);
    json_t *given = json_array_get(json_object_get(root, "layers"), 0);
    const char *key;
    json_t *val;
    json_object_foreach(given, key, val)
    {
        if (!strcmp(key, "type")) continue;
        if (!tone_key(key)) { /* the message first: `key` belongs to root */
            rc = fb_fail(FB_ERR_USAGE,
                         "--%s: not a tone-mapping flag (tonemap takes --brightness, --gamma, --gamma-threshold, "
                         "--vibrancy, --highlight-power, --palette, --cosine, --stops)",
                         key);
            json_decref(root);
            return rc;
        }
        if (!strcmp(key, "palette") || !strcmp(key, "cosine") || !strcmp(key, "stops")) {
            json_object_del(lj, "cosine");
            json_object_del(lj, "stops");
        }
        json_object_set(lj, key, val);
    }
    json_decref(root);
    return FB_OK;
}

fb_result fb_tonemap_main(int argc, char **argv, bool *quiet, bool *json)
{
    const char *in = NULL, *out = NULL, *layer = NULL;
    char **flags = calloc((size_t)argc + 1, sizeof *flags);
    int nflags = 0;
    fb_result rc = flags ? FB_OK : fb_fail(FB_ERR_NOMEM, "out of memory");
    for (int i = 0; i < argc && !rc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "-o") || !strcmp(a, "--output") || !strcmp(a, "--layer")) {
            if (!v) rc = fb_fail(FB_ERR_USAGE, "%s: missing value", a);
            *(!strcmp(a, "--layer") ? &layer : &out) = v;
            if (v && strcmp(a, "--layer")) rc = fb_output_format(a, v, ".exr");
            i++;
        } else if (!strcmp(a, "--quiet")) {
            *quiet = true;
        } else if (!strcmp(a, "--json")) {
            *json = true;
        } else if (!strcmp(a, "--help")) {
            printf("usage: fractalbake tonemap IN.exr -o OUT.exr [--layer NAME] [--brightness B] [--gamma G]\n"
                   "          [--gamma-threshold T] [--vibrancy V] [--highlight-power P] [--palette NAME |\n"
                   "          --cosine ... | --stops ...]\n"
                   "Recomputes R, G, B, A of an ifs layer from its stored density and colour channels with new\n"
                   "tone parameters (the others keep their stored values). No chaos game is run.\n"
                   "--quiet: no summary line; --json: a JSON summary on standard output.\n");
            free(flags);
            return FB_OK;
        } else if (!strncmp(a, "--", 2)) {
            int arity = fb_scene_flag_arity("ifs", a + 2);
            if (arity < 0) {
                rc = fb_fail(FB_ERR_USAGE, "%s: unknown flag for `fractalbake tonemap`", a);
                break;
            }
            flags[nflags++] = argv[i];
            if (arity == 1 && v) flags[nflags++] = argv[++i];
        } else if (!in) {
            in = a;
        } else {
            rc = fb_fail(FB_ERR_USAGE, "%s: tonemap takes one input file", a);
        }
    }
    if (!rc && !in)
        rc = fb_fail(FB_ERR_USAGE, "tonemap: expected an input EXR (fractalbake tonemap IN.exr -o OUT.exr)");
    if (!rc && !out) rc = fb_fail(FB_ERR_USAGE, "-o: missing output file (fractalbake tonemap IN.exr -o OUT.exr)");

    exrio_reader *r = NULL;
    exrio_writer *w = NULL;
    json_t *root = NULL;
    fb_scene scene = {0};
    float *density = NULL, *strip = NULL;
    void **planes = NULL;
    exrio_channel *chans = NULL;
    char *text = NULL;
    if (!rc) rc = exrio_open(in, &r);
    const char *stored = rc ? NULL : exrio_attr_string(r, "fractalbake/scene");
    if (!rc && !stored) rc = fb_fail(FB_ERR_INPUT, "%s: no fractalbake scene in the header", in);
    if (!rc && !(root = json_loads(stored, 0, NULL)))
        rc = fb_fail(FB_ERR_INPUT, "%s: the stored scene is not valid JSON", in);
    /* the layer: named, or the first ifs layer */
    json_t *lj = NULL;
    size_t li = 0;
    json_t *layers = root ? json_object_get(root, "layers") : NULL;
    for (size_t i = 0; !rc && i < json_array_size(layers) && !lj; i++) {
        json_t *l = json_array_get(layers, i);
        const char *t = json_string_value(json_object_get(l, "type")),
                   *n = json_string_value(json_object_get(l, "name"));
        if (t && !strcmp(t, "ifs") && (!layer || (n && !strcmp(n, layer)))) lj = l, li = i;
    }
    if (!rc && !lj)
        rc = fb_fail(FB_ERR_INPUT, "%s: no ifs layer%s%s in the stored scene", in, layer ? " named " : "",
                     layer ? layer : "");
    if (!rc) rc = apply_flags(lj, nflags, flags);
    if (!rc && !(text = json_dumps(root, JSON_SORT_KEYS | JSON_REAL_PRECISION(17))))
        rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    if (!rc) rc = fb_scene_parse(text, NULL, &scene);

    int width = r ? exrio_width(r) : 0, height = r ? exrio_height(r) : 0, nch = r ? exrio_nchannels(r) : 0;
    const fb_layer *L = rc ? NULL : &scene.layers[li];
    char name[6][96];
    int idx[6];
    static const char *const suffix[6] = {"density", "colour", "R", "G", "B", "A"};
    for (int k = 0; k < 6 && !rc; k++) {
        snprintf(name[k], sizeof name[k], "%s.%s", L->name, suffix[k]);
        if ((idx[k] = exrio_find_channel(r, name[k])) < 0)
            rc = fb_fail(FB_ERR_INPUT, "%s: channel %s is missing", in, name[k]);
    }
    if (!rc && (scene.width != width || scene.height != height))
        rc = fb_fail(FB_ERR_INPUT, "%s: the stored scene's size does not match the image", in);
    /* pass 1: the reference density over the whole image */
    size_t n = (size_t)width * height;
    char who[4200];
    snprintf(who, sizeof who, "tonemap %s (%d x %d)", in, width, height);
    if (!rc) rc = fb_memory_check((uint64_t)n * 4, who);
    if (!rc && !(density = malloc(n * 4))) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    if (!rc) {
        void **one = calloc((size_t)nch, sizeof *one);
        if (!one) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
        for (int y = 0; y < height && !rc; y += 256) {
            int rows = y + 256 <= height ? 256 : height - y;
            one[idx[0]] = density + (size_t)y * width;
            rc = exrio_read_rows(r, y, rows, one);
        }
        free(one);
    }
    fb_ifs_tone tone = {0};
    if (!rc) {
        const fb_ifs_params *f = fb_layer_params(L);
        tone = (fb_ifs_tone){.brightness = f->brightness,
                             .gamma = f->gamma,
                             .threshold = f->gamma_threshold,
                             .vibrancy = f->vibrancy,
                             .highlight = f->highlight_power,
                             .dref = fb_ifs_density_ref(density, n)};
        fb_palette_build(&f->palette, tone.palette);
    }
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
        const char *keys[] = {"fractalbake/seed", "fractalbake/backend", "fractalbake/device", "fractalbake/version"};
        exrio_attr attrs[5] = {{"fractalbake/scene", scene.json}};
        int na = 1;
        for (int k = 0; k < 4; k++) {
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
                                                      .nattrs = na},
                                 &w);
    }
    for (int y = 0; y < height && !rc; y += rows) {
        int m = y + rows <= height ? rows : height - y;
        rc = exrio_read_rows(r, y, m, planes);
        if (rc) break;
        fb_ifs_tonemap_row(&tone, planes[idx[0]], planes[idx[1]], (size_t)m * width, planes[idx[2]], planes[idx[3]],
                           planes[idx[4]], planes[idx[5]]);
        rc = exrio_writer_rows(w, y, m, (const void *const *)planes);
    }
    if (!rc) rc = exrio_writer_finish(&w);
    exrio_writer_abort(&w);
    exrio_close(&r);
    json_decref(root);
    fb_scene_fini(&scene);
    free(text);
    free(density);
    free(strip);
    free(planes);
    free(chans);
    free(flags);
    return rc;
}
