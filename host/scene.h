/*
 * Scenes: the validated description of a bake. A scene comes from a JSON file, from the embedded
 * default, or from a single-generator command line (which builds the same JSON: every flag is the
 * scene key of the same name). Every key is checked against a schema; errors name the key path,
 * and for files the line.
 */
#ifndef FB_SCENE_H
#define FB_SCENE_H

#include "exrio.h"
#include "fb.h"
#include "ifs.h"
#include "lsys.h"
#include "palette.h"

#include <stdbool.h>

#define FB_MAX_LAYERS 16
#define FB_MAX_DIM    65536
#define FB_MAX_PIXELS (1ull << 31)

typedef enum fb_layer_kind {
    FB_LAYER_FBM = 0,
    FB_LAYER_JULIA = 1,
    FB_LAYER_IFS = 2,
    FB_LAYER_LSYSTEM = 3,
    FB_LAYER_TERRAIN = 4,
    FB_LAYER_OP = 5,
    FB_LAYER_CONSTRAIN = 6
} fb_layer_kind;

typedef struct fb_fbm_params {
    unsigned noise; /* K_NOISE_* */
    double hurst;   /* used when !gain_given */
    double gain;    /* G = 2^-H */
    bool gain_given;
    int octaves;
    double lacunarity;
    double rotation; /* degrees per octave */
    double frequency;
    double offset[2];
    bool ridged, billow, tileable;
    double warp;
} fb_fbm_params;

typedef struct fb_julia_params {
    bool polar; /* mapping: rect (eq. 7) or polar (eq. 8) */
    double scale[2];
    double radius;
    double center[2];
    double rotation; /* degrees */
    double alpha[2];
    double c[2];
    int max_iter;
    double bailout;
    fb_palette_spec palette;
    double period, palette_offset, brightness, gamma, density, density_count;
    double inside_color[3];
    double turbulence, turb_hurst, turb_frequency;
    int turb_octaves;
    int samples;
    unsigned channels; /* bit k: stored channel k of iter, n, inside, de, R, G, B */
    bool double_precision;
} fb_julia_params;

typedef struct fb_ifs_params {
    fb_ifs maps; /* w1..wN (probabilities as given, or -1) */
    fb_ifs cond; /* the condensation set's IFS when has_cond */
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
} fb_ifs_params;

typedef struct fb_lsystem_params {
    fb_lsys sys;    /* axiom, rules, iterations, angle */
    double heading; /* degrees; 90: up */
    double step;    /* segment length, turtle units */
    double width;   /* branch width at depth 0, in steps */
    double taper;   /* width factor per bracket depth */
    uint64_t max_symbols;
    bool auto_bounds;
    double bounds[4];
    fb_palette_spec palette; /* colour by depth: 0 at the trunk, 1 at the deepest branches */
} fb_lsystem_params;

typedef struct fb_terrain_layer_params {
    bool points_inline;         /* the points are the layer's "points" array in the scene JSON */
    char points[1024];          /* else an XYZ / CSV file, or "" */
    char heightfield[1024];     /* else a height-field EXR[:layer.channel] */
    int sample;                 /* its sampling step, pixels */
    uint64_t insert;            /* points to insert */
    double hurst;               /* H (from hurst or 3 - dimension) */
    double sigma;               /* < 0: estimated from the data */
    bool sweep, local_variance; /* --order sweep, --variance local */
    char centers[1024];         /* CSV of centres, or "" */
    bool auto_bounds;
    double bounds[4];
    char mesh[1024]; /* .ply or .obj, or "" */
} fb_terrain_layer_params;

/* A reference to another layer's channel ("terrain.Y", or "terrain": its Y) or a constant. */
typedef struct fb_ref {
    int layer;        /* index in the scene's layers; -1: the constant `value` */
    char channel[64]; /* "" : the layer's Y */
    double value;
} fb_ref;

#define FB_OP_MAX_INPUTS 8
typedef enum fb_op_kind { FB_OP_ADD = 0, FB_OP_MULTIPLY, FB_OP_MIX, FB_OP_REMAP, FB_OP_THRESHOLD } fb_op_kind;

/* A compositing layer: one channel NAME.Y computed per pixel from other layers' channels. */
typedef struct fb_op_params {
    fb_op_kind op;
    int ninputs;
    fb_ref inputs[FB_OP_MAX_INPUTS];
    double weights[FB_OP_MAX_INPUTS]; /* add: sum of w_i x_i */
    fb_ref mask;                      /* mix: a + (b - a) clamp(m, 0, 1) */
    double from[2], to[2];            /* remap: from[0]..from[1] -> to[0]..to[1] */
    bool clamp;                       /* remap: clamp to the target range */
    double level, width;              /* threshold: smoothstep over level -/+ width/2 (a step if 0) */
} fb_op_params;

/* The FBM constraint model (host/constrain.h). Points and regions come from the scene's JSON (inline)
 * or from files, read when the layer is set up. */
typedef struct fb_constrain_params {
    char macro[1024];    /* "cone" | "ridge" | "boss" | "bowl" | IN.exr[:layer.channel] */
    fb_ref macro_ref;    /* the macro shape from another layer of the scene (layer -1: none) */
    double macro_height; /* built-in shapes */
    char profile[1024];  /* 1D: a CSV profile instead of macro, or "" */
    double T, hurst, sigma, delta;
    bool points_inline, regions_inline;
    char points[1024], regions[1024]; /* files, or "" */
    int domain;
    double falloff;
    int buffering; /* fb_buffering */
    bool has_water;
    double water;
    char csv[1024];  /* 1D: write x, d, D here, or "" */
    char plot[1024]; /* 1D: a PNG plot of d and D here, or "" */
} fb_constrain_params;

typedef struct fb_layer {
    fb_layer_kind kind;
    char name[64];
    bool half;                     /* store colour/height as half instead of float */
    exrio_compression compression; /* its part's, when the scene has one part per layer */
    fb_fbm_params fbm;
    fb_julia_params julia;
    fb_ifs_params ifs;
    fb_lsystem_params lsystem;
    fb_terrain_layer_params terrain;
    fb_op_params op;
    fb_constrain_params constrain;
} fb_layer;

typedef struct fb_scene {
    int width, height;
    uint32_t seed;
    exrio_compression compression;
    bool multipart; /* "parts": "per-layer": one EXR part per layer, named after it */
    int nlayers;
    fb_layer layers[FB_MAX_LAYERS];
    int order[FB_MAX_LAYERS]; /* every layer after the layers it refers to (op layers last, in dependency order) */
    char *json;               /* the scene with every default filled in, canonical (sorted keys); owned */
    /* Not part of the scene text: a points part {K, N} (1 <= K <= N) of a bake split by chaos-game
     * points (render --points-part K/N); N == 0: the whole game. */
    int points_part[2];
} fb_scene;

/* Parses and validates JSON text. `origin` names the file for messages (NULL: the command line,
 * where a key is reported as its flag, --key). */
fb_result fb_scene_parse(const char *text, const char *origin, fb_scene *out);

/* Reads a scene file and parses it. */
fb_result fb_scene_load(const char *path, fb_scene *out);

/* The same with overrides applied before validation, in order: "KEY.PATH=VALUE" as given to --set.
 * The path's segments are object keys, or in a list an index or a layer name (layers.sky.c);
 * missing objects on the way are created. VALUE is JSON if it parses as JSON, WxH a size, a
 * comma-separated list an array, else a string. Errors in an overridden value name the --set. */
fb_result fb_scene_parse_sets(const char *text, const char *origin, const char *const *sets, int nsets, fb_scene *out);
fb_result fb_scene_load_sets(const char *path, const char *const *sets, int nsets, fb_scene *out);

/* The embedded default scene. */
const char *fb_scene_default_json(void);

void fb_scene_fini(fb_scene *s);

/* "a, b, c": the scene's layer names, for messages. */
void fb_scene_layer_names(const fb_scene *s, char *out, size_t size);

/* The files the scene's layers write besides the EXR (a terrain's mesh, a constrain layer's CSV and
 * plot): up to max paths (pointers into s) and what each is. Returns the count. */
int fb_scene_outputs(const fb_scene *s, const char **paths, const char **what, int max);

/* A stored scene (JSON text) without the output paths of its layers: a file baked elsewhere must not
 * choose which files this run writes. *out is the new text (free()); `dropped` lists what was removed
 * as "layers.NAME.KEY=PATH, ..." ("" if nothing). */
fb_result fb_scene_drop_outputs(const char *text, char **out, char *dropped, size_t size);

/* For the command line: converts `--flag value` of a single-generator command into the JSON scene
 * it stands for. `kind` is the generator ("fbm"). argv holds only the generator's flags. Returns
 * malloc'd JSON text in *json. Global flags (--size, --seed, --compression) become scene keys. */
fb_result fb_scene_from_flags(const char *kind, int argc, char **argv, char **json);

/* For the command line: how many values flag `flag` (without the dashes) of generator `kind` takes:
 * 0 for a switch (--tileable), 1 for a valued flag (--octaves 8), -1 when it is not a flag of
 * `kind` or of the scene. */
int fb_scene_flag_arity(const char *kind, const char *flag);

/* Prints the keys of a generator with their types, ranges and defaults (for --help). */
void fb_scene_print_keys(const char *kind, void (*print)(const char *line, void *user), void *user);

#endif
