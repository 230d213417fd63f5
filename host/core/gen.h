/*
 * Generators: what the bake driver needs to know about each layer kind. A generator fills the
 * rows [y0, y0 + n) of its layer's channels, either in C (native backend; must be a pure function
 * of the pixel so that any split over threads gives the same bits) or by a compute shader over the
 * same kernel (vulkan backend), one storage buffer per channel.
 */
#ifndef FB_GEN_H
#define FB_GEN_H

#include "exrio.h"
#include "scene.h"
#include "schema.h"

#define FB_GEN_MAX_CHANNELS 64
#define FB_GEN_MAX_PUSH     128

typedef struct fb_gen fb_gen;
struct fb_engine;

/* The run options a bake gives its layers, not part of the scene: the points part {K, N} (1 <= K
 * <= N) of a chaos game this run computes (render --points-part K/N; N == 0: the whole game), what
 * the layer may allocate (the bake's --max-memory and its engine's overhead: a class whose init
 * allocates much checks its peak against it, fb_memory_check(&g->run.budget, ...)), and whether
 * the native path is the portable kernel only, no hand-vectorised path (the benchmark's reference). */
typedef struct fb_gen_run {
    int points_part[2];
    fb_memory budget;
    bool scalar;
} fb_gen_run;

/* What a layer stores: its channels in the file, and how a preview shows them. */
typedef struct fb_gen_store {
    int nchannels;
    char channel_names[FB_GEN_MAX_CHANNELS][80];
    exrio_type channel_types[FB_GEN_MAX_CHANNELS];
    int preview_channel;     /* the float channel a grey preview shows */
    int preview_rgb;         /* if >= 0: the first of three float channels R, G, B shown in colour instead (-1) */
    double preview_shade[2]; /* > 0: the preview shows preview_channel as a hillshade (world units per
                                pixel in x and y) */
    bool preview_light;      /* its R, G, B are light without coverage (a star field): the over composite
                                adds them to the layers behind instead of hiding those */
    int preview_nwater;      /* a grey or hillshade preview draws water where one of these float channels
                                is > 0 (a rivers layer's river and lake) */
    int preview_water[2];
} fb_gen_store;

/* A compute shader over the layer's kernel: what the Vulkan backend dispatches over a piece of rows,
 * one storage buffer per kernel plane (fb_gen_nplanes), then `input` if any. */
typedef struct fb_gen_shader {
    const uint32_t *spv; /* NULL: the layer has no shader */
    size_t spv_size;
    uint32_t push_size; /* params_size + 8: the shader's push block is {params; uint y0; uint rows;} */
    uint32_t params_size;
    const void *input; /* read-only data for the kernel (bound after the kernel's planes: binding
                          fb_gen_nplanes(g)), or NULL */
    uint32_t input_size;
    bool input_uniform; /* the shader reads input as a uniform buffer (std140), not a storage buffer */
    uint32_t spec[8];   /* specialization constants 0..nspec-1 */
    uint32_t nspec;
    int per_invocation; /* pixels of a row per invocation (0: 1) */
    bool needs_float64; /* the shader uses doubles (the device must have shaderFloat64) */
} fb_gen_shader;

/* How a layer's rows are computed: natively (native_rows), by the shader, or on the host from other
 * layers' planes of the same piece (host_rows). */
typedef struct fb_gen_compute {
    /* native: fill rows [y0, y0 + n); planes[k] holds n * width values (4 bytes each) for each of the
     * kernel's planes (see nkernel), NULL for a plane the layer does not store */
    void (*native_rows)(const fb_gen *g, int y0, int n, void *const *planes);
    /* A layer computed on the host from other layers' planes of the same piece (an op layer): count
     * values of its one float channel; neither native_rows nor a shader. */
    void (*host_rows)(const fb_gen *g, size_t count, const void *const *planes, float *out);
    /* A kernel that can compute more channels than the layer stores (a julia layer's `channels`):
     * nkernel planes (the shader's buffers 0..nkernel-1), stored channel c being plane kernel_of[c].
     * Planes not stored are neither computed nor written. nkernel 0: the planes are the channels. */
    int nkernel;
    int kernel_of[FB_GEN_MAX_CHANNELS];
    fb_gen_shader shader;
    /* On a CPU implementation of Vulkan (lavapipe) this layer's shader is faster than its native path
     * (Julia; fBm outside its AVX2 case), so --backend auto runs it there; otherwise the native path
     * wins on such a device (bench/RESULTS.md). A GPU runs every layer. */
    bool lavapipe_faster;
} fb_gen_compute;

/* What a layer's preparation produced (set by prepare). */
typedef struct fb_gen_prepared {
    double gpu_seconds; /* dispatch time on the GPU, else -1 */
    bool has_world;     /* the image covers world[] = xmin, xmax, ymin, ymax (y up) */
    double world[4];
    int epsg;                /* ... in this projected CRS (EPSG code; 0: not stated) */
    char summary[512];       /* one human line about the layer's computation, or "" */
    char summary_json[1024]; /* the same as a JSON object, or "" */
    /* A layer split by chaos-game points (render --points-part): the points that fell outside the
     * frame (merge needs them for the density). */
    bool points_split;
    uint64_t points_outside;
} fb_gen_prepared;

/* A layer's generator, as its class's init fills it: what it stores, how it is computed, and what
 * its preparation produced, with the hooks that run around the pieces. */
struct fb_gen {
    const fb_scene *scene;
    const fb_layer *layer;
    fb_gen_run run;
    fb_gen_store store;
    fb_gen_compute compute;
    fb_gen_prepared prepared;

    /* Layers that are not a function of the pixel (the chaos game) compute everything here, once, on
     * the engine's backend before the first piece; their pieces then come from native_rows on the
     * host whatever the backend. NULL for per-pixel generators. Side outputs (a mesh, a CSV) are
     * written here through the output transaction (output.h), which renames them with the EXR when
     * the whole run succeeds. */
    fb_result (*prepare)(fb_gen *g, struct fb_engine *e, bool progress);
    /* The bytes this layer will allocate besides the bake's pieces, predicted before it does (after
     * init, which reads the inputs): returns the peak (prepare's arrays and what it keeps) and sets
     * *hold to what it keeps while the pieces are produced. NULL: nothing worth counting. */
    uint64_t (*memory)(const fb_gen *g, const struct fb_engine *e, uint64_t *hold);
    /* Layers that use other layers (struct fb_gen_class.refs): called once every layer's generator is
     * set up, with all of the scene's (gens, in scene order; plane_offset[i] is the first plane of
     * layer i in a piece), to find their sources. Prepares run in dependency order (sources first). */
    fb_result (*resolve)(fb_gen *g, const fb_gen *const *gens, const int *plane_offset);

    _Alignas(16) unsigned char params[256]; /* generator-private, e.g. K_FbmParams */
    void *owned;                            /* generator-owned memory (freed by fb_gen_fini) */
    void (*fini)(fb_gen *g);                /* frees what `owned` points to, before owned itself */
};

/* How a layer's work may be shared between the tasks of a split bake (core/plan.c). */
typedef enum fb_share {
    FB_SHARE_WHOLE = 0,  /* computed by one task: its cost does not shrink with a band (the default) */
    FB_SHARE_BAND = 1,   /* a function of the pixel: cut into row bands */
    FB_SHARE_POINTS = 2, /* a chaos game: split into points parts (render --points-part), summed by merge */
} fb_share;

/* Merging points parts (fractalbake merge): a chaos game split by points (FB_SHARE_POINTS) stores in
 * each part its sums, which add over the parts, and the points that fell outside the frame
 * (fb_gen.points_outside). Sum k is width x height values: the uint channel LAYER.SUFFIX, or, wide,
 * the pair LAYER.SUFFIX_lo and LAYER.SUFFIX_hi of one 64-bit sum. The class sizes them to the layer
 * (a histogram larger than the image takes several). */
typedef struct fb_points_ops {
    /* The number of sums of layer g (initialised for the whole game by fb_gen_init). */
    int (*nsums)(const fb_gen *g);
    /* Sum k's channel suffix (into suffix, of `size` bytes); returns whether it is wide. */
    bool (*sum)(const fb_gen *g, int k, char *suffix, size_t size);
    /* Sets up g (initialised for the whole game's layer) from the sums over every part (sums[k]: width
     * x height values) and the outside count, in place of its chaos game; its native_rows then gives
     * the channels the whole game would have. */
    fb_result (*from_sums)(fb_gen *g, const uint64_t *const *sums, uint64_t outside);
} fb_points_ops;

/* Re-toning (fractalbake tonemap): a layer whose colour channels are a function of channels it also
 * stores (the chaos game's density and colour), recomputed with new tone keys without computing the
 * layer again. */
typedef struct fb_tone_ops {
    const char *const *keys; /* its scene keys that change only the tone mapping, NULL-terminated */
    /* Reads what the tone map needs of the whole image from `r` (a file holding the layer) for layer
     * L (its new parameters) into a new *state. */
    fb_result (*begin)(const fb_layer *L, exrio_reader *r, const char *path, void **state);
    /* Recomputes the layer's tone-mapped channels in the strip planes[c] (every channel c of r, m *
     * width values each). */
    void (*rows)(const void *state, int m, void *const *planes);
    void (*end)(void *state); /* null-safe */
} fb_tone_ops;

/* A generator: everything the scene engine, the bake and the commands know of one layer kind. Each
 * lives in its folder host/gen/NAME/ (layer.c defines it); host/gen/list.c names them all. */
struct fb_bench;
typedef struct fb_gen_class {
    const char *name;     /* the scene's "type", the command and the benchmark's --generator: "fbm" */
    const char *synopsis; /* the command in the top-level help: "fbm [options] -o OUT.exr"; NULL: no command */
    const char *summary;  /* what it makes, one line */
    const char *what;     /* its layer in messages: "an fbm layer" */
    const fb_keyspec *keys;
    int nkeys;
    size_t params_size; /* its parameters in fb_layer.params */
    /* Reads the layer object `obj` at `path` into L->params: checks it against the keys first
     * (fb_schema_check), then what involves several keys. s: the scene so far (size, seed). */
    fb_result (*parse)(const fb_vctx *v, const char *path, json_t *obj, const fb_scene *s, fb_layer *L);
    /* Its references to other layers (NULL: none): up to FB_MAX_REFS slots; returns the count. */
    int (*refs)(fb_layer *L, fb_ref_slot *out);
    /* The files it writes besides the EXR (NULL: none): paths (pointers into L) and what each is. */
    int (*outputs)(const fb_layer *L, const char **paths, const char **what, int max);
    /* Sets up a layer's generator: channels, kernel, push constants, prepare (fb_gen_init calls it). */
    fb_result (*init)(fb_gen *g);
    /* Planning a split bake (core/plan.c). `share`: how its layers may be shared between tasks (a
     * layer that writes a heightmap is computed whole whatever its class says). `cost`: the layer's
     * cost in seconds of one core of the reference machine (docs/scenes.md), written channels
     * included, into *total; a banded class also fills rows[0 .. s->height) (zeroed by the caller)
     * with each row's share. `part_pixel_seconds`: a points-split class's image cost per pixel,
     * which every points part pays whatever its share of the points. */
    fb_share share;
    fb_result (*cost)(const fb_scene *s, int layer, double *rows, double *total);
    double part_pixel_seconds;
    const fb_points_ops *points; /* FB_SHARE_POINTS: how merge adds the parts */
    /* For `fractalbake generators` and the conformance test (tests/conformance.py): a small scene's
     * "layers" that bake it (JSON; NULL: [{"type": NAME}]), and how far its Vulkan result may be from
     * its native one (the largest |difference|, and the share of pixels in percent allowed beyond
     * it; both 0: the same bits). */
    const char *example;
    struct {
        double max_abs, fail_percent;
    } tolerance;
    const fb_tone_ops *tone; /* NULL: tonemap does not apply */
    /* Environment maps: a layer whose class's keys include "mapping" with the values "latlong" or
     * "cube" is one when its key says so (the scene engine reads the key into fb_layer.envmap, checks
     * that a file's layers agree and the size fits; the bake writes the `envmap` attribute). The
     * class then computes pixel (x, y) at the direction k_env_dir gives (kernels/envmap.h).
     * envmap_of_refs: a layer of this class takes the mapping of the layers it refers to (an op layer,
     * which combines them pixel by pixel); false: a layer without such a key is a plane. */
    bool envmap_of_refs;
    /* Its benchmarks (cli/bench.c runs them; NULL: none). */
    fb_result (*bench)(struct fb_bench *b);
} fb_gen_class;

/* Every generator, NULL-terminated, in the order the help lists them (host/gen/list.c). */
extern const fb_gen_class *const fb_gen_list[];

/* The generator named `name`, or NULL (also for a NULL name). */
const fb_gen_class *fb_gen_find(const char *name);

/* "\"fbm\", \"julia\", ...": the names, for messages. */
void fb_gen_names(char *out, size_t size);

/* Sets up the generator of `layer`. */
fb_result fb_gen_init(fb_gen *g, const fb_scene *scene, const fb_layer *layer);

/* fb_gen_init with run options (fb_gen_init: {0}, the whole game and the default memory limit). */
fb_result fb_gen_init_run(fb_gen *g, const fb_scene *scene, const fb_layer *layer, const fb_gen_run *run);

/* The kernel's planes (nkernel, or the channels), the plane of stored channel c, and whether plane k
 * is stored. */
int fb_gen_nplanes(const fb_gen *g);
int fb_gen_plane_of(const fb_gen *g, int c);
bool fb_gen_plane_stored(const fb_gen *g, int k);

/* The push constants of a strip: the generator's parameter block, then y0 and the row count. */
void fb_gen_push(const fb_gen *g, int y0, int n, void *out);

/* Workgroups for a strip of n rows: 64 invocations wide, each for `per_invocation` pixels (1 unless
 * the generator says), one row of groups per row. */
void fb_gen_groups(const fb_gen *g, int n, uint32_t out[3]);

/* Frees what the generator owns. Null-safe, idempotent. */
void fb_gen_fini(fb_gen *g);

/* The index of channel "LAYER.channel" ("" : LAYER.Y) of generator src, or -1 with an error logged
 * that names the layer `who` and the channels src has. */
int fb_gen_channel_of(const fb_gen *src, const char *channel, const char *who, const char *what);

/* Another layer's channel that a layer reads whole before it computes (erode's heights, rivers' input
 * and uplift map, constrain's macro shape). */
typedef struct fb_source {
    const fb_gen *gen; /* the layer; NULL: none */
    int channel;       /* its stored channel */
} fb_source;

/* The rows of a source read at once: its native rows fill a band of this many, then the band is copied. */
#define FB_SOURCE_BAND 64

/* For g's resolve: the channel reference r (of key `key`) names among gens, a float channel of a layer
 * with native rows. An op layer (host rows) or a channel of integers is refused with one line naming
 * g, key and the channel; `op_hint` says what to do instead of an op layer (NULL: bake it, or name
 * the layer it reads). */
fb_result fb_source_find(fb_source *out, const fb_gen *g, const fb_gen *const *gens, const struct fb_ref *r,
                         const char *key, const char *op_hint);

/* The source's channel over the whole image into out (width x height floats), FB_SOURCE_BAND rows at a
 * time through its native rows (its prepare has run: the bake prepares sources first), so that it is
 * the same on every backend. A value that is not finite is refused with one line naming layer g, the
 * source's key and the pixel. */
fb_result fb_source_read(const fb_source *src, const fb_gen *g, const char *key, float *out);

/* The same on a cw x ch grid over the image: the whole image when it is the image's size, else each
 * cell the source's pixel at the cell's centre (one native row a grid row): a coarse model's input. */
fb_result fb_source_read_grid(const fb_source *src, const fb_gen *g, const char *key, int cw, int ch, float *out);

#endif
