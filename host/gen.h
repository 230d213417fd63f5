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

#define FB_GEN_MAX_CHANNELS 10
#define FB_GEN_MAX_PUSH     128

typedef struct fb_gen fb_gen;
struct fb_engine;

struct fb_gen {
    const fb_scene *scene;
    const fb_layer *layer;
    int nchannels;
    int preview_channel; /* the float channel a grey preview shows */
    int preview_rgb;     /* if >= 0: the first of three float channels R, G, B shown in colour instead (-1) */
    char channel_names[FB_GEN_MAX_CHANNELS][80];
    exrio_type channel_types[FB_GEN_MAX_CHANNELS];

    /* native: fill rows [y0, y0 + n); planes[k] holds n * width values (4 bytes each) for each of the
     * kernel's planes (see nkernel), NULL for a plane the layer does not store */
    void (*native_rows)(const fb_gen *g, int y0, int n, void *const *planes);

    /* A kernel that can compute more channels than the layer stores (a julia layer's `channels`):
     * nkernel planes (the shader's buffers 0..nkernel-1), stored channel c being plane kernel_of[c].
     * Planes not stored are neither computed nor written. nkernel 0: the planes are the channels. */
    int nkernel;
    int kernel_of[FB_GEN_MAX_CHANNELS];

    /* vulkan: the shader, its push constants for a strip, and its workgroup counts */
    const uint32_t *spv;
    size_t spv_size;
    uint32_t push_size; /* params_size + 8: the shader's push block is {params; uint y0; uint rows;} */
    uint32_t params_size;
    const void *input; /* read-only data for the kernel (bound after the kernel's planes: binding
                          fb_gen_nplanes(g)), or NULL */
    uint32_t input_size;
    uint32_t spec[8]; /* specialization constants 0..nspec-1 */
    uint32_t nspec;

    /* Layers that are not a function of the pixel (the chaos game) compute everything here, once, on
     * the engine's backend before the first strip; their strips then come from native_rows on the
     * host whatever the backend. NULL for per-pixel generators. */
    fb_result (*prepare)(fb_gen *g, struct fb_engine *e, bool progress);
    double prepare_gpu_seconds; /* set by prepare: dispatch time on the GPU, else -1 */

    /* The bytes this layer will allocate besides the bake's strips, predicted before it does (after
     * init, which reads the inputs): returns the peak (prepare's arrays and what it keeps) and sets
     * *hold to what it keeps while the strips are produced. NULL: nothing worth counting. */
    uint64_t (*memory)(const fb_gen *g, const struct fb_engine *e, uint64_t *hold);

    /* Side outputs (a mesh, a CSV) are written by prepare through the output transaction
     * (output.h), which renames them with the EXR when the whole run succeeds. */
    double preview_shade[2]; /* > 0: the preview shows preview_channel as a hillshade (world units per
                                pixel in x and y) */
    char summary[512];       /* set by prepare: one human line about the layer's computation, or "" */
    char summary_json[1024]; /* the same as a JSON object, or "" */

    /* An op layer: computed on the host from other layers' planes of the same strip (fb_gen_op_rows)
     * once fb_gen_op_resolve has found its inputs; neither native_rows nor a shader. */
    bool host_op;

    /* A constrain layer whose macro shape is another layer's channel: set by the bake before the
     * prepares, which run in dependency order (the source's first). */
    const struct fb_gen *macro_src;
    int macro_channel;

    int per_invocation; /* vulkan: pixels of a row per invocation (0: 1) */
    bool needs_float64; /* vulkan: the shader uses doubles (the device must have shaderFloat64) */

    bool scalar; /* native: the portable kernel only, no hand-vectorised path (benchmark reference) */
    _Alignas(16) unsigned char params[256]; /* generator-private, e.g. K_FbmParams */
    void *owned;                            /* generator-owned memory (freed by fb_gen_fini) */
    void (*fini)(fb_gen *g);                /* frees what `owned` points to, before owned itself */
};

/* Sets up the generator of `layer`. */
fb_result fb_gen_init(fb_gen *g, const fb_scene *scene, const fb_layer *layer);

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

/* Completes an fBm parameter block whose frequencies are set: the image size and the reciprocals the
 * kernel multiplies by (kernels never divide). Shared by the fBm layer and Julia's turbulence. */
struct K_FbmParams;
void fb_fbm_params_frame(struct K_FbmParams *p, int width, int height);

/* Per kind. */
fb_result fb_gen_fbm_init(fb_gen *g);
fb_result fb_gen_julia_init(fb_gen *g);
fb_result fb_gen_ifs_init(fb_gen *g);
fb_result fb_gen_lsystem_init(fb_gen *g);
fb_result fb_gen_terrain_init(fb_gen *g);
fb_result fb_gen_op_init(fb_gen *g);
fb_result fb_gen_constrain_init(fb_gen *g);

/* Op layers: finds the planes of the inputs among every generator's (gens, all of the scene's, in
 * scene order; plane_offset[i] is the first plane of layer i in a strip). */
fb_result fb_gen_op_resolve(fb_gen *g, const fb_gen *const *gens, const int *plane_offset);
/* The index of channel "LAYER.channel" ("" : LAYER.Y) of generator src, or -1 with an error logged
 * that names the layer `who` and the channels src has. */
int fb_gen_channel_of(const fb_gen *src, const char *channel, const char *who, const char *what);
/* Computes count values of the op layer from the strip's planes (of every layer). */
void fb_gen_op_rows(const fb_gen *g, size_t count, const void *const *planes, float *out);

/* The chaos-game statistics of an ifs layer after prepare (NULL for other layers). */
struct fb_ifs_stats;
const struct fb_ifs_stats *fb_gen_ifs_stats(const fb_gen *g);

/* fractalbake merge of points parts: an ifs layer's pixels from the parts' summed hits and colour
 * sums (each width x height) and outside count, in place of its chaos game; then native_rows gives
 * the channels the whole game would have. */
fb_result fb_gen_ifs_from_sums(fb_gen *g, const uint64_t *hits, const uint64_t *sums, uint64_t outside);

#endif
