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

#include <stdbool.h>

#define FB_MAX_LAYERS 16
#define FB_MAX_PIXELS (1ull << 32) /* 65536 x 65536: a pixel's index y W + x fits 32 bits */

/* A reference to another layer's channel ("terrain.Y", or "terrain": its Y) or a constant. */
typedef struct fb_ref {
    int layer;        /* index in the scene's layers; -1: the constant `value` */
    char channel[64]; /* "" : the layer's Y */
    double value;
} fb_ref;

/* A layer's references to other layers, as its generator lists them (struct fb_gen_class.refs). */
#define FB_MAX_REFS 16
typedef struct fb_ref_slot {
    fb_ref *ref;
    char key[24];         /* the key that holds it: "inputs[2]", "macro" */
    const char *expected; /* what else the key may name, for the message when no layer has the name (or NULL) */
} fb_ref_slot;

typedef struct fb_layer {
    const struct fb_gen_class *cls; /* its generator */
    char name[64];
    bool half;                     /* store colour/height as half instead of float */
    exrio_compression compression; /* its part's, when the scene has one part per layer */
    /* "heightmap" (a layer of heights, whose class's key table has the key): its Y channel also
     * written as OUT.png / OUT.r16 (16-bit, normalised to heightmap_range or the image's own range)
     * or OUT.tif (a float GeoTIFF); "" none */
    char heightmap[1024];
    int heightmap_engine;         /* fb_heightmap_engine: a preset, whose sidecar is written too */
    char heightmap_sidecar[1040]; /* the preset's sidecar (OUT.import.json), or "" */
    bool heightmap_range_set;
    double heightmap_range[2];
    /* "tiles" [columns, rows] (0, 0: none): the heightmap written as tiles sharing their edges, whose
     * files (fb_heightmap_tile_path) are tile_paths, row by row from the north-west, FB_TILE_PATH bytes
     * each (allocated; fb_scene_fini frees them) */
    int tiles[2];
    char *tile_paths;
    /* What the layer is on the sphere: its "mapping" key when its class's table has one taking
     * "latlong" or "cube" (kernels/envmap.h's conventions); for a class that combines its inputs pixel
     * by pixel (fb_gen_class.envmap_of_refs), its inputs' mapping; otherwise a plane (NONE). */
    exrio_envmap envmap;
    /* the generator's parameters (its fb_NAME_params, cls->params_size bytes, zeroed before its parse;
     * owned by the scene: fb_scene_fini frees them), read with fb_layer_params */
    void *params;
} fb_layer;

#define FB_TILE_PATH 1100

/* The heightmap's keys every height-producing generator lists in its table, after "heightmap". */
struct fb_kvalue;
extern const struct fb_kvalue fb_tiles_value;
/* clang-format off */
#define FB_HEIGHTMAP_KEYS                                                                                              \
    {"heightmap-engine", FB_K_ENUM, 0, 0, false, FB_HEIGHTMAP_ENGINES, NULL,                                           \
     "the heightmap for an engine: unreal (a landscape size, 16-bit PNG) or unity (2^n+1 square, RAW); writes "        \
     "OUT.import.json, the import settings that reproduce the heights", FB_CORE},                                               \
    {"heightmap-range", FB_K_VEC2, -1e15, 1e15, false, NULL, NULL,                                                     \
     "heights stored as 0 and 65535 in a 16-bit heightmap (LO,HI; default: the image's lowest and highest)", FB_CORE},          \
    {"tiles", FB_K_CUSTOM, 1, FB_HEIGHTMAP_MAX_TILES, false, NULL, NULL,                                               \
     "the heightmap as COLSxROWS tiles sharing their edge samples, one height range for all, named by the engine's "   \
     "convention (OUT_x0_y0.png; unity: OUT_0_0.r16) (flag: --tiles NxM)", .value = &fb_tiles_value, FB_CORE}
/* The last key of every layer's table: its own compression, read by the scene engine. */
#define FB_COMPRESSION_KEY                                                                                             \
    {"compression", FB_K_ENUM, 0, 0, false, EXRIO_COMPRESSION_NAMES, NULL,                                             \
     "this layer's compression (default: the scene's); needs \"parts\": \"per-layer\"", FB_CORE}
/* clang-format on */

static inline const void *fb_layer_params(const fb_layer *L)
{
    return L->params;
}

typedef struct fb_scene {
    int width, height;
    uint32_t seed;
    exrio_compression compression;
    bool multipart; /* "parts": "per-layer": one EXR part per layer, named after it */
    /* The file's `envmap` attribute: every layer's envmap, which must agree (one attribute per file);
     * the size is then 2N x N (lat-long) or N x 6N (cube). */
    exrio_envmap envmap;
    int nlayers;
    fb_layer layers[FB_MAX_LAYERS];
    int order[FB_MAX_LAYERS]; /* every layer after the layers it refers to (op layers last, in dependency order) */
    char *json;               /* the scene with every default filled in, canonical (sorted keys); owned */
} fb_scene;

/* Parses and validates JSON text. `origin` names the file for messages (NULL: the command line,
 * where a key is reported as its flag, --key). */
fb_result fb_scene_parse(const char *text, const char *origin, fb_scene *out);

/* Reads a scene file and parses it. The relative file names of its layers (the files they read and write) are
 * relative to the scene file's folder: they are joined to it, and stored so (a scene on stdin, "-": the working
 * folder). */
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
 * as "layers.NAME.KEY=PATH, ..." ("" if nothing); a heightmap's engine, range and tiles go with it
 * ("layers.NAME.heightmap=PATH with its heightmap-engine, tiles"). */
fb_result fb_scene_drop_outputs(const char *text, char **out, char *dropped, size_t size);

/* The scene's own keys (size, seed, compression, parts, layers), for the command line's flags. */
struct fb_keyspec;
const struct fb_keyspec *fb_scene_keys(int *n);

/* Applies one --set "KEY.PATH=VALUE" to a scene's JSON (sets.c); jpath gets the key path it set
 * ("layers[0].c"), for messages. */
struct json_t;
fb_result fb_scene_apply_set(struct json_t *root, const char *set, char jpath[256]);

#endif
