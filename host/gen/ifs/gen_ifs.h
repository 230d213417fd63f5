/*
 * The ifs generator's parameters (a layer's, as parsed from the scene) and its class.
 */
#ifndef FB_GEN_IFS_H
#define FB_GEN_IFS_H

#include "gen.h"
#include "ifs.h"
#include "vkc.h"
#include "gen_lsystem.h"
#include "lsys.h"
#include "palette.h"

typedef struct fb_ifs_params {
    char preset[32];  /* the maps' preset name, or "" */
    char file[4096];  /* or a Fractint .ifs file's, "" none */
    char entry[4096]; /* its entry ("": the first) */
    fb_ifs maps;      /* w1..wN (probabilities as given, or -1) */
    fb_ifs cond;      /* the condensation set's IFS when has_cond */
    bool has_cond;
    bool cond_lsys;                 /* the condensation set is an L-system drawing instead of cond */
    fb_lsys cond_sys;               /* ... derived with the scene's seed, drawn by the turtle */
    double cond_heading;            /* its initial heading, degrees */
    double cond_height;             /* its largest extent, in the IFS's units (base at the origin) */
    uint64_t cond_max_symbols;      /* its rewriting bound */
    double cond_p;                  /* probability of the condensation map w0 */
    double colors[FB_IFS_MAX_MAPS]; /* colour coordinate of each map of `maps` */
    double cond_colors[FB_IFS_MAX_MAPS];
    double points; /* total chaos-game steps (an integer up to 1e14) */
    int skip;      /* transient steps after each (re)start */
    int chains;
    bool auto_bounds;
    double bounds[4]; /* xmin, xmax, ymin, ymax */
    int oversample;
    fb_palette_spec palette;
    double brightness, gamma, gamma_threshold, vibrancy, highlight_power;
    /* plant instances (instances.h): the file ("" none), the height layer they stand on (or a
     * constant height), the smallest plant written (pixels tall) and the up axis ('y' or 'z') */
    char instances[1024];
    fb_ref surface;
    bool has_surface;
    double inst_min_pixels;
    char inst_up;
    bool up_z;    /* instances-up: z (else y) */
    fb_ref avoid; /* instances-avoid: a mask the plants keep away from */
    bool has_avoid;
    double avoid_distance; /* world units */
    double max_slope;      /* degrees; 90: any */
} fb_ifs_params;

extern const fb_gen_class fb_gen_ifs;

/* Its benchmarks (bench.c). */
fb_result fb_ifs_bench(struct fb_bench *b);

/* Steps a chain the chaos game of ifs layer g plays in one dispatch on device vk (host/gen/ifs/layer.c:
 * a few hundred ms on a CPU device, a fold interval of 2^28 points on a GPU). */
uint32_t fb_ifs_steps_per_dispatch(const fb_gen *g, const vkc_context *vk);

/* The chaos-game statistics of an ifs layer after prepare (NULL for other layers). */
const struct fb_ifs_stats *fb_gen_ifs_stats(const fb_gen *g);

/* fractalbake merge of points parts: an ifs layer's pixels from the parts' summed hits and colour
 * sums (each width x height) and outside count, in place of its chaos game; then native_rows gives
 * the channels the whole game would have. */
fb_result fb_gen_ifs_from_sums(fb_gen *g, const uint64_t *hits, const uint64_t *sums, uint64_t outside);

/* Its scene keys and their parser (parse.c). */
#define FB_IFS_NKEYS 31
extern const fb_keyspec fb_ifs_keys[FB_IFS_NKEYS];
fb_result fb_ifs_parse(const fb_vctx *v, const char *path, json_t *obj, const fb_scene *s, fb_layer *L);

/* Its value types (values.c): affine maps, and a condensation set. */
extern const fb_kvalue fb_ifs_maps_value, fb_ifs_condensation_value;

/* The class's hooks for tonemap and merge (tone.c). */
extern const fb_tone_ops fb_ifs_tone_ops;
extern const fb_points_ops fb_ifs_points_ops;

#endif
