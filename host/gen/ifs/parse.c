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
    {"type", FB_K_TYPE, 0, 0, false, NULL, NULL, "generator: \"ifs\"", FB_CORE},
    {"name", FB_K_NAME, 0, 0, false, NULL, "\"plants\"",
     "layer name; channels NAME.count, .density, .colour, .R, .G, .B, .A (flag: --layer)", FB_CORE},
    {"preset", FB_K_ENUM, 0, 0, false, FB_IFS_PRESETS, NULL, "built-in IFS (default fern when no maps or file)",
     FB_FIELD(fb_ifs_params, preset)},
    {"maps", FB_K_CUSTOM, -1e6, 1e6, false, NULL, NULL,
     "affine maps [[a, b, c, d, e, f, p], ...]: x' = a x + b y + e, y' = c x + d y + f (flag: \"a,b,c,d,e,f,p;...\")",
     FB_IFS_MAX_MAPS, .value = &fb_ifs_maps_value, FB_FIELD(fb_ifs_params, maps)},
    {"file", FB_K_PATH, 0, 0, false, NULL, NULL, "a Fractint .ifs file (its maps are stored in the scene)",
     FB_FIELD(fb_ifs_params, file)},
    {"entry", FB_K_STRING, 0, 0, false, NULL, NULL, "the entry of the .ifs file (flag: --name; default the first)", 0,
     "name", FB_FIELD(fb_ifs_params, entry)},
    {"colors", FB_K_FRACS, 0, 1, false, NULL, NULL, "colour coordinate of each map, in [0, 1] (default spread evenly)",
     FB_IFS_MAX_MAPS, FB_FIELD(fb_ifs_params, colors)},
    {"condensation", FB_K_CUSTOM, -1e6, 1e6, false, "fern|sierpinski|maple|tree|spiral", NULL,
     "condensation set C: an IFS preset name or map list, or an L-system {\"preset\": \"tree\", ...} (flag: "
     "lsystem:tree); w0 sends any point onto C",
     FB_IFS_MAX_MAPS, .value = &fb_ifs_condensation_value, FB_FIELD(fb_ifs_params, cond)},
    {"condensation-probability", FB_K_NUM, 0, 1, true, NULL, "0.5", "probability of the condensation map w0",
     FB_FIELD(fb_ifs_params, cond_p)},
    {"points", FB_K_INT, 0, 1e14, false, NULL, "0",
     "chaos-game steps in all (0: 64 per histogram cell); at about 1e8 a second, 1e14 takes days: "
     "progress is shown and Ctrl-C stops it",
     FB_FIELD(fb_ifs_params, points)},
    {"skip", FB_K_INT, 0, 1000000, false, NULL, "0",
     "transient steps discarded after each (re)start (0: from the maps' mean contraction)",
     FB_FIELD(fb_ifs_params, skip)},
    {"chains", FB_K_INT, 0, 1048576, false, NULL, "0", "independent chains (0: from points and skip, at most 65536)",
     FB_FIELD(fb_ifs_params, chains)},
    {"bounds", FB_K_BOUNDS, -1e9, 1e9, false, NULL, "\"auto\"",
     "frame XMIN,XMAX,YMIN,YMAX, or auto (from a short pre-run, square units)", FB_FIELD(fb_ifs_params, bounds)},
    {"oversample", FB_K_INT, 1, 4, false, NULL, "1", "histogram at K x K the resolution, box-filtered down",
     FB_FIELD(fb_ifs_params, oversample)},
    {"palette", FB_K_ENUM, 0, 0, false, FB_PALETTE_NAMES, "\"foliage\"", "named colour map", 0, NULL, "cosine|stops",
     FB_CORE},
    {"cosine", FB_K_NUMLIST, -10, 10, false, NULL, NULL,
     "cosine palette a + b cos(2 pi (c t + d)): 12 numbers aR,aG,aB,bR,bG,bB,cR,cG,cB,dR,dG,dB", 12, FB_CORE},
    {"stops", FB_K_STOPS, 0, 1e3, false, NULL, NULL,
     "gradient: [[t, r, g, b], ...], t rising from 0 to 1 (flag: \"t,r,g,b;t,r,g,b\")", FB_CORE},
    {"brightness", FB_K_NUM, 0, 1e3, false, NULL, "1.0", "scale of the log density (1: the 99.5th percentile is full)",
     FB_FIELD(fb_ifs_params, brightness)},
    {"gamma", FB_K_NUM, 0, 10, true, NULL, "2.2", "density gamma", FB_FIELD(fb_ifs_params, gamma)},
    {"gamma-threshold", FB_K_NUM, 0, 1, false, NULL, "0.01", "below this alpha the gamma curve is linear",
     FB_FIELD(fb_ifs_params, gamma_threshold)},
    {"vibrancy", FB_K_NUM, 0, 1, false, NULL, "1.0", "1: gamma on alpha (saturated); 0: gamma per channel",
     FB_FIELD(fb_ifs_params, vibrancy)},
    {"highlight-power", FB_K_NUM, -1, 100, false, NULL, "1.0",
     "over-bright pixels: < 0 clip per channel, 0 keep hue, larger fade to white",
     FB_FIELD(fb_ifs_params, highlight_power)},
    {"instances", FB_K_OUTPUT, 0, 0, false, NULL, NULL,
     "also write one point per plant of the population: OUT.ply (binary) or OUT.csv (P, N, pscale, orient, id, "
     "variant)",
     FB_FIELD(fb_ifs_params, instances)},
    {"instances-surface", FB_K_REF, 0, 0, false, NULL, NULL,
     "the height layer the instances stand on (\"terrain\" or \"layer.channel\"), or a constant height (default 0)",
     FB_FIELD(fb_ifs_params, surface)},
    {"instances-min-size", FB_K_NUM, 0, 1e6, true, NULL, NULL,
     "the smallest plant written, in pixels tall in the image (default 1: smaller ones are invisible)",
     FB_FIELD(fb_ifs_params, inst_min_pixels)},
    {"instances-up", FB_K_ENUM, 0, 0, false, "y|z", NULL,
     "the instances' up axis: y (default; Houdini: x east, z south) or z (x east, y north)",
     FB_FIELD(fb_ifs_params, up_z)},
    {"instances-avoid", FB_K_REF, 0, 0, false, NULL, NULL,
     "a mask the plants keep away from (\"rivers.river\", \"layer.channel\"): none stands within "
     "instances-avoid-distance of a pixel where it is 0.5 or more",
     FB_FIELD(fb_ifs_params, avoid)},
    {"instances-avoid-distance", FB_K_NUM, 0, 1e15, false, NULL, NULL,
     "with instances-avoid: the distance in the surface's world units (default 0: not on the 4 pixels around the "
     "base)",
     FB_FIELD(fb_ifs_params, avoid_distance)},
    {"instances-max-slope", FB_K_NUM, 0, 90, false, NULL, NULL,
     "no plant where the surface is steeper than this, degrees (default: any slope)",
     FB_FIELD(fb_ifs_params, max_slope)},
    {"half", FB_K_BOOL, 0, 0, false, NULL, "true", "store R, G, B, A as half (flags: --half, --float)", FB_CORE},
    FB_COMPRESSION_KEY,
};

/* The keys of an L-system condensation set of an ifs layer ("condensation": {"preset": "tree"}). */
static const fb_keyspec cond_lsystem_keys[] = {
    {"preset", FB_K_ENUM, 0, 0, false, FB_LSYS_PRESETS, NULL, "built-in L-system", FB_PARSE},
    {"axiom", FB_K_STRING, 0, 0, false, NULL, NULL, "the starting string", FB_FIELD(fb_ifs_params, cond_sys.axiom)},
    {"rules", FB_K_RULES, 0, FB_LSYS_MAX_RULES, false, NULL, NULL, "productions \"X=successor\"", FB_LSYS_MAX_RULES,
     NULL, NULL, fb_lsystem_check_rule, .value = &fb_lsystem_rules_value, FB_FIELD(fb_ifs_params, cond_sys)},
    {"iterations", FB_K_INT, 0, 64, false, NULL, NULL, "parallel rewriting steps",
     FB_FIELD(fb_ifs_params, cond_sys.iterations)},
    {"angle", FB_K_NUM, -360, 360, false, NULL, NULL, "degrees turned by + and -",
     FB_FIELD(fb_ifs_params, cond_sys.angle)},
    {"heading", FB_K_NUM, -360, 360, false, NULL, "90.0", "initial heading, degrees (90: up)",
     FB_FIELD(fb_ifs_params, cond_heading)},
    {"height", FB_K_NUM, 0, 1e6, true, NULL, "0.25",
     "the drawing's largest extent in the IFS's units, base at the origin", FB_FIELD(fb_ifs_params, cond_height)},
    {"max-symbols", FB_K_INT, 1, 2147483648.0, false, NULL, "268435456", "longest string allowed while rewriting",
     FB_FIELD(fb_ifs_params, cond_max_symbols)},
};

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

/* Colour coordinates spread evenly over n maps. */
static void spread_colors(int n, double *out)
{
    for (int k = 0; k < n; k++) out[k] = n > 1 ? (double)k / (n - 1) : 0.5;
}

/* The instance keys: a file named .ply or .csv, of a population, the other keys only with it. */
static fb_result parse_instances(const fb_vctx *v, const char *path, json_t *obj, fb_ifs_params *f)
{
    char sub[256];
    static const char *const with[] = {"instances-surface", "instances-min-size",       "instances-up",
                                       "instances-avoid",   "instances-avoid-distance", "instances-max-slope"};
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
    f->has_surface = json_object_get(obj, "instances-surface") != NULL;
    if (!json_object_get(obj, "instances-min-size")) f->inst_min_pixels = 1.0;
    f->inst_up = f->up_z ? 'z' : 'y';
    json_t *avoid = json_object_get(obj, "instances-avoid");
    f->has_avoid = avoid != NULL;
    if (avoid && json_is_number(avoid)) {
        snprintf(sub, sizeof sub, "%s.instances-avoid", path);
        return fb_schema_error(v, sub, "expected a mask: another layer's channel, not a number");
    }
    if (json_object_get(obj, "instances-avoid-distance") && !avoid) {
        snprintf(sub, sizeof sub, "%s.instances-avoid-distance", path);
        return fb_schema_error(v, sub, "the distance from instances-avoid's mask, and there is no instances-avoid");
    }
    if (!json_object_get(obj, "instances-max-slope")) f->max_slope = 90;
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
    fb_result rc = fb_schema_check(v, path, obj, fb_ifs_keys, FB_IFS_NKEYS, "an ifs layer", f);
    if (rc) return rc;
    snprintf(sub, sizeof sub, "%s.maps", path);
    if (file) {
        /* The file's maps go into the stored scene, so that the bake can be reproduced without it. */
        rc = fb_ifs_read_file(f->file, entry ? f->entry : NULL, &f->maps);
        if (rc) return rc;
        json_t *mj = maps_json(&f->maps);
        if (!mj) return fb_fail(FB_ERR_NOMEM, "out of memory");
        json_object_set_new(obj, "maps", mj);
        json_object_del(obj, "file");
        json_object_del(obj, "entry");
        snprintf(sub, sizeof sub, "%s.file", path);
    } else if (f->preset[0]) {
        rc = fb_ifs_preset(f->preset, &f->maps, &f->cond, &f->has_cond);
        if (rc) return rc;
    }
    if ((rc = check_ifs(v, sub, &f->maps))) return rc;

    json_t *cond = json_object_get(obj, "condensation");
    snprintf(sub, sizeof sub, "%s.condensation", path);
    if (cond && f->has_cond) return fb_schema_error(v, sub, "the population preset has its own condensation set");
    if (cond && json_is_object(cond)) {
        f->has_cond = f->cond_lsys = true;
        rc = fb_lsystem_parse_def(v, sub, cond, cond_lsystem_keys, FB_NKEYS(cond_lsystem_keys),
                                  "an L-system condensation set", f, &f->cond_sys);
        if (rc) return rc;
    } else if (cond) {
        f->has_cond = true; /* its IFS read by its value type (values.c) */
        if ((rc = check_ifs(v, sub, &f->cond))) return rc;
    }
    json_t *colors = json_object_get(obj, "colors");
    if (colors && (int)json_array_size(colors) != f->maps.n) {
        snprintf(sub, sizeof sub, "%s.colors", path);
        return fb_schema_error(v, sub, "%zu colour coordinates for %d maps", json_array_size(colors), f->maps.n);
    }
    if (!colors) spread_colors(f->maps.n, f->colors);
    spread_colors(f->cond.n, f->cond_colors);
    f->auto_bounds = json_is_string(json_object_get(obj, "bounds"));
    if ((rc = fb_schema_palette(v, path, obj, &f->palette))) return rc;
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
