/*
 * The ifs layer's scene keys and their parser: presets, map lists, Fractint .ifs files, a
 * condensation set (an IFS or an L-system), the framing and the tone mapping.
 */
#include "gen_ifs.h"
#include "ifs.h"
#include "lsys.h"
#include "palette.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* ---- the scene keys and their parser ---------------------------------------------------------- */

const fb_keyspec fb_ifs_keys[] = {
    {"type", FB_K_TYPE, 0, 0, false, NULL, NULL, "generator: \"ifs\""},
    {"name", FB_K_NAME, 0, 0, false, NULL, "\"plants\"",
     "layer name; channels NAME.count, .density, .colour, .R, .G, .B, .A (flag: --layer)"},
    {"preset", FB_K_ENUM, 0, 0, false, FB_IFS_PRESETS, NULL, "built-in IFS (default fern when no maps or file)"},
    {"maps", FB_K_CUSTOM, -1e6, 1e6, false, NULL, NULL,
     "affine maps [[a, b, c, d, e, f, p], ...]: x' = a x + b y + e, y' = c x + d y + f (flag: \"a,b,c,d,e,f,p;...\")",
     FB_IFS_MAX_MAPS, .value = &fb_ifs_maps_value},
    {"file", FB_K_PATH, 0, 0, false, NULL, NULL, "a Fractint .ifs file (its maps are stored in the scene)"},
    {"entry", FB_K_STRING, 0, 0, false, NULL, NULL, "the entry of the .ifs file (flag: --name; default the first)", 0,
     "name"},
    {"colors", FB_K_FRACS, 0, 1, false, NULL, NULL, "colour coordinate of each map, in [0, 1] (default spread evenly)",
     FB_IFS_MAX_MAPS},
    {"condensation", FB_K_CUSTOM, -1e6, 1e6, false, "fern|sierpinski|maple|tree|spiral", NULL,
     "condensation set C: an IFS preset name or map list, or an L-system {\"preset\": \"tree\", ...} (flag: "
     "lsystem:tree); w0 sends any point onto C",
     FB_IFS_MAX_MAPS, .value = &fb_ifs_condensation_value},
    {"condensation-probability", FB_K_NUM, 0, 1, true, NULL, "0.5", "probability of the condensation map w0"},
    {"points", FB_K_INT, 0, 1e14, false, NULL, "0",
     "chaos-game steps in all (0: 64 per histogram cell); at about 1e8 a second, 1e14 takes days: "
     "progress is shown and Ctrl-C stops it"},
    {"skip", FB_K_INT, 0, 1000000, false, NULL, "0",
     "transient steps discarded after each (re)start (0: from the maps' mean contraction)"},
    {"chains", FB_K_INT, 0, 1048576, false, NULL, "0", "independent chains (0: from points and skip, at most 65536)"},
    {"bounds", FB_K_BOUNDS, -1e9, 1e9, false, NULL, "\"auto\"",
     "frame XMIN,XMAX,YMIN,YMAX, or auto (from a short pre-run, square units)"},
    {"oversample", FB_K_INT, 1, 4, false, NULL, "1", "histogram at K x K the resolution, box-filtered down"},
    {"palette", FB_K_ENUM, 0, 0, false, FB_PALETTE_NAMES, "\"foliage\"", "named colour map", 0, NULL, "cosine|stops"},
    {"cosine", FB_K_NUMLIST, -10, 10, false, NULL, NULL,
     "cosine palette a + b cos(2 pi (c t + d)): 12 numbers aR,aG,aB,bR,bG,bB,cR,cG,cB,dR,dG,dB", 12},
    {"stops", FB_K_STOPS, 0, 1e3, false, NULL, NULL,
     "gradient: [[t, r, g, b], ...], t rising from 0 to 1 (flag: \"t,r,g,b;t,r,g,b\")"},
    {"brightness", FB_K_NUM, 0, 1e3, false, NULL, "1.0", "scale of the log density (1: the 99.5th percentile is full)"},
    {"gamma", FB_K_NUM, 0, 10, true, NULL, "2.2", "density gamma"},
    {"gamma-threshold", FB_K_NUM, 0, 1, false, NULL, "0.01", "below this alpha the gamma curve is linear"},
    {"vibrancy", FB_K_NUM, 0, 1, false, NULL, "1.0", "1: gamma on alpha (saturated); 0: gamma per channel"},
    {"highlight-power", FB_K_NUM, -1, 100, false, NULL, "1.0",
     "over-bright pixels: < 0 clip per channel, 0 keep hue, larger fade to white"},
    {"instances", FB_K_OUTPUT, 0, 0, false, NULL, NULL,
     "also write one point per plant of the population: OUT.ply (binary) or OUT.csv (P, N, pscale, orient, id, "
     "variant)"},
    {"instances-surface", FB_K_REF, 0, 0, false, NULL, NULL,
     "the height layer the instances stand on (\"terrain\" or \"layer.channel\"), or a constant height (default 0)"},
    {"instances-min-size", FB_K_NUM, 0, 1e6, true, NULL, NULL,
     "the smallest plant written, in pixels tall in the image (default 1: smaller ones are invisible)"},
    {"instances-up", FB_K_ENUM, 0, 0, false, "y|z", NULL,
     "the instances' up axis: y (default; Houdini: x east, z south) or z (x east, y north)"},
    {"instances-avoid", FB_K_REF, 0, 0, false, NULL, NULL,
     "a mask the plants keep away from (\"rivers.river\", \"layer.channel\"): none stands within "
     "instances-avoid-distance of a pixel where it is 0.5 or more"},
    {"instances-avoid-distance", FB_K_NUM, 0, 1e15, false, NULL, NULL,
     "with instances-avoid: the distance in the surface's world units (default 0: not on the 4 pixels around the "
     "base)"},
    {"instances-max-slope", FB_K_NUM, 0, 90, false, NULL, NULL,
     "no plant where the surface is steeper than this, degrees (default: any slope)"},
    {"half", FB_K_BOOL, 0, 0, false, NULL, "true", "store R, G, B, A as half (flags: --half, --float)"},
    {"compression", FB_K_ENUM, 0, 0, false, EXRIO_COMPRESSION_NAMES, NULL,
     "this layer's compression (default: the scene's); needs \"parts\": \"per-layer\""},
};

/* The keys of an L-system condensation set of an ifs layer ("condensation": {"preset": "tree"}). */
static const fb_keyspec cond_lsystem_keys[] = {
    {"preset", FB_K_ENUM, 0, 0, false, FB_LSYS_PRESETS, NULL, "built-in L-system"},
    {"axiom", FB_K_STRING, 0, 0, false, NULL, NULL, "the starting string"},
    {"rules", FB_K_RULES, 0, FB_LSYS_MAX_RULES, false, NULL, NULL, "productions \"X=successor\"", FB_LSYS_MAX_RULES,
     NULL, NULL, fb_lsystem_check_rule},
    {"iterations", FB_K_INT, 0, 64, false, NULL, NULL, "parallel rewriting steps"},
    {"angle", FB_K_NUM, -360, 360, false, NULL, NULL, "degrees turned by + and -"},
    {"heading", FB_K_NUM, -360, 360, false, NULL, "90.0", "initial heading, degrees (90: up)"},
    {"height", FB_K_NUM, 0, 1e6, true, NULL, "0.25",
     "the drawing's largest extent in the IFS's units, base at the origin"},
    {"max-symbols", FB_K_INT, 1, 2147483648.0, false, NULL, "268435456", "longest string allowed while rewriting"},
};

/* A validated map list (fb_ifs_maps_value) into an fb_ifs; a missing probability is -1. */
static void maps_of(const json_t *j, fb_ifs *out)
{
    memset(out, 0, sizeof *out);
    out->n = (int)json_array_size(j);
    for (int k = 0; k < out->n; k++) {
        const json_t *m = json_array_get(j, (size_t)k);
        double c[7] = {0, 0, 0, 0, 0, 0, -1};
        for (size_t i = 0; i < json_array_size(m); i++) c[i] = json_number_value(json_array_get(m, i));
        out->m[k] = (fb_ifs_map){c[0], c[1], c[2], c[3], c[4], c[5], c[6]};
    }
}

static json_t *maps_json(const fb_ifs *ifs)
{
    json_t *arr = json_array();
    for (int k = 0; arr && k < ifs->n; k++) {
        const fb_ifs_map *m = &ifs->m[k];
        json_t *e = json_pack("[ffffff]", m->a, m->b, m->c, m->d, m->e, m->f);
        if (e && m->p != -1) json_array_append_new(e, json_real(m->p));
        json_array_append_new(arr, e);
    }
    return arr;
}

static fb_result check_ifs(const fb_vctx *v, const char *path, const fb_ifs *ifs)
{
    int bad;
    char msg[256], sub[256];
    if (fb_ifs_valid(ifs, &bad, msg, sizeof msg)) return FB_OK;
    if (bad >= 0)
        snprintf(sub, sizeof sub, "%s[%d]", path, bad);
    else
        snprintf(sub, sizeof sub, "%s", path);
    return fb_schema_error(v, sub, "%s", msg);
}

static void spread_colors(const json_t *given, int n, double *out)
{
    for (int k = 0; k < n; k++)
        out[k] = given ? json_number_value(json_array_get(given, (size_t)k)) : n > 1 ? (double)k / (n - 1) : 0.5;
}

/* The instance keys: a file named .ply or .csv, of a population, the other keys only with it. */
static fb_result parse_instances(const fb_vctx *v, const char *path, json_t *obj, fb_ifs_params *f)
{
    char sub[256];
    static const char *const with[] = {"instances-surface", "instances-min-size",       "instances-up",
                                       "instances-avoid",   "instances-avoid-distance", "instances-max-slope"};
    fb_json_string(obj, "instances", f->instances, sizeof f->instances);
    for (int k = 0; k < 6 && !f->instances[0]; k++)
        if (json_object_get(obj, with[k])) {
            snprintf(sub, sizeof sub, "%s.%s", path, with[k]);
            return fb_schema_error(v, sub, "only with instances (the file the plants are written to)");
        }
    if (!f->instances[0]) return FB_OK;
    snprintf(sub, sizeof sub, "%s.instances", path);
    const char *dot = strrchr(f->instances, '.');
    if (strlen(f->instances) >= sizeof f->instances - 1)
        return fb_schema_error(v, sub, "file name longer than %zu characters", sizeof f->instances - 2);
    if (!dot || (strcasecmp(dot, ".ply") && strcasecmp(dot, ".csv")))
        return fb_schema_error(v, sub, "\"%s\": the instances' format comes from the extension, .ply or .csv",
                               f->instances);
    if (!f->has_cond)
        return fb_schema_error(v, sub,
                               "instances need a plant population: a condensation set (preset population, "
                               "or condensation)");
    json_t *surf = json_object_get(obj, "instances-surface");
    f->has_surface = surf != NULL;
    if (surf) fb_json_ref(surf, &f->surface);
    f->inst_min_pixels = json_object_get(obj, "instances-min-size") ? fb_json_num(obj, "instances-min-size") : 1.0;
    const char *up = json_string_value(json_object_get(obj, "instances-up"));
    f->inst_up = up && !strcmp(up, "z") ? 'z' : 'y';
    json_t *avoid = json_object_get(obj, "instances-avoid");
    f->has_avoid = avoid != NULL;
    if (avoid && json_is_number(avoid)) {
        snprintf(sub, sizeof sub, "%s.instances-avoid", path);
        return fb_schema_error(v, sub, "expected a mask: another layer's channel, not a number");
    }
    if (avoid) fb_json_ref(avoid, &f->avoid);
    if (json_object_get(obj, "instances-avoid-distance") && !avoid) {
        snprintf(sub, sizeof sub, "%s.instances-avoid-distance", path);
        return fb_schema_error(v, sub, "the distance from instances-avoid's mask, and there is no instances-avoid");
    }
    f->avoid_distance =
        json_object_get(obj, "instances-avoid-distance") ? fb_json_num(obj, "instances-avoid-distance") : 0;
    f->max_slope = json_object_get(obj, "instances-max-slope") ? fb_json_num(obj, "instances-max-slope") : 90;
    return FB_OK;
}

fb_result fb_ifs_parse(const fb_vctx *v, const char *path, json_t *obj, const fb_scene *s, fb_layer *L)
{
    char sub[256];
    fb_ifs_params *f = (void *)L->params;
    json_t *file = json_object_get(obj, "file"), *entry = json_object_get(obj, "entry");
    int sources = (json_object_get(obj, "preset") != NULL) + (json_object_get(obj, "maps") != NULL) + (file != NULL);
    if (sources > 1) {
        snprintf(sub, sizeof sub, "%s.%s", path, file ? "file" : "maps");
        return fb_schema_error(v, sub, "give one of preset, maps or file");
    }
    if (entry && !file) {
        snprintf(sub, sizeof sub, "%s.entry", path);
        return fb_schema_error(v, sub, "an entry name needs a file");
    }
    if (!sources) json_object_set_new(obj, "preset", json_string("fern"));
    fb_result rc = fb_schema_check(v, path, obj, fb_ifs_keys, FB_IFS_NKEYS, "an ifs layer");
    if (rc) return rc;
    snprintf(sub, sizeof sub, "%s.maps", path);
    const char *preset = json_string_value(json_object_get(obj, "preset"));
    if (file) {
        /* The file's maps go into the stored scene, so that the bake can be reproduced without it. */
        rc = fb_ifs_read_file(json_string_value(file), entry ? json_string_value(entry) : NULL, &f->maps);
        if (rc) return rc;
        json_t *mj = maps_json(&f->maps);
        if (!mj) return fb_fail(FB_ERR_NOMEM, "out of memory");
        json_object_set_new(obj, "maps", mj);
        json_object_del(obj, "file");
        json_object_del(obj, "entry");
        snprintf(sub, sizeof sub, "%s.file", path);
    } else if (preset) {
        rc = fb_ifs_preset(preset, &f->maps, &f->cond, &f->has_cond);
        if (rc) return rc;
    } else {
        maps_of(json_object_get(obj, "maps"), &f->maps);
    }
    if ((rc = check_ifs(v, sub, &f->maps))) return rc;

    json_t *cond = json_object_get(obj, "condensation");
    snprintf(sub, sizeof sub, "%s.condensation", path);
    if (cond && f->has_cond) return fb_schema_error(v, sub, "the population preset has its own condensation set");
    if (cond && json_is_object(cond)) {
        f->has_cond = f->cond_lsys = true;
        rc = fb_lsystem_parse_def(v, sub, cond, cond_lsystem_keys, FB_NKEYS(cond_lsystem_keys),
                                  "an L-system condensation set", &f->cond_sys);
        if (rc) return rc;
        f->cond_heading = fb_json_num(cond, "heading");
        f->cond_height = fb_json_num(cond, "height");
        f->cond_max_symbols = (uint64_t)json_integer_value(json_object_get(cond, "max-symbols"));
    } else if (cond) {
        f->has_cond = true;
        if (json_is_string(cond))
            rc = fb_ifs_preset(json_string_value(cond), &f->cond, NULL, NULL);
        else
            maps_of(cond, &f->cond);
        if (rc || (rc = check_ifs(v, sub, &f->cond))) return rc;
    }
    f->cond_p = fb_json_num(obj, "condensation-probability");
    json_t *colors = json_object_get(obj, "colors");
    if (colors && (int)json_array_size(colors) != f->maps.n) {
        snprintf(sub, sizeof sub, "%s.colors", path);
        return fb_schema_error(v, sub, "%zu colour coordinates for %d maps", json_array_size(colors), f->maps.n);
    }
    spread_colors(colors, f->maps.n, f->colors);
    spread_colors(NULL, f->cond.n, f->cond_colors);
    f->points = (double)json_integer_value(json_object_get(obj, "points"));
    f->skip = (int)json_integer_value(json_object_get(obj, "skip"));
    f->chains = (int)json_integer_value(json_object_get(obj, "chains"));
    f->oversample = (int)json_integer_value(json_object_get(obj, "oversample"));
    json_t *b = json_object_get(obj, "bounds");
    f->auto_bounds = json_is_string(b);
    for (size_t i = 0; !f->auto_bounds && i < 4; i++) f->bounds[i] = json_number_value(json_array_get(b, i));
    if ((rc = fb_schema_palette(v, path, obj, &f->palette))) return rc;
    f->brightness = fb_json_num(obj, "brightness");
    f->gamma = fb_json_num(obj, "gamma");
    f->gamma_threshold = fb_json_num(obj, "gamma-threshold");
    f->vibrancy = fb_json_num(obj, "vibrancy");
    f->highlight_power = fb_json_num(obj, "highlight-power");
    if ((rc = parse_instances(v, path, obj, f))) return rc;
    uint64_t cells = (uint64_t)s->width * s->height * (uint64_t)(f->oversample * f->oversample);
    if (cells > (1ull << 28)) {
        snprintf(sub, sizeof sub, "%s.oversample", path);
        return fb_schema_error(v, sub,
                               "the histogram would have %llu cells (size x oversample^2); at most 2^28 are supported",
                               (unsigned long long)cells);
    }
    return FB_OK;
}

_Static_assert(FB_NKEYS(fb_ifs_keys) == FB_IFS_NKEYS, "FB_IFS_NKEYS counts the keys");
