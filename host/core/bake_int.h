/*
 * The bake's insides, shared by bake.c (the driver: layers, memory, sizes), pieces.c (the producer,
 * the ring of pieces and the consumer) and sinks.c (what the pieces are fed to). Nothing outside
 * host/core/bake*.c, pieces.c and sinks.c includes this header.
 */
#ifndef FB_BAKE_INT_H
#define FB_BAKE_INT_H

#include "bake.h"
#include "sink.h"

/* Where a layer's rows come from. */
typedef enum run_where {
    RUN_POOL = 0, /* native_rows on the host's pool (native layers, and prepared ones on any backend) */
    RUN_GPU,      /* its shader on the Vulkan device */
    RUN_HOST,     /* host_rows from other layers' planes of the piece (an op layer), on the producer */
} run_where;

/* One layer as the bake runs it. */
typedef struct layer_run {
    fb_gen gen;
    fb_engine e; /* the bake's engine as this layer uses it: its kind is the layer's backend */
    run_where where;
    int offset; /* its first stored channel among a piece's planes */
} layer_run;

/* How the bake cuts its window into pieces. */
typedef struct bake_shape {
    int region[4]; /* the window: x, y, w, h */
    int rows;      /* rows of a piece (the last may have fewer) */
    int slots;     /* pieces in flight: the ring between the producer and the sinks */
    /* the GPU's pieces come back through host buffers (a discrete GPU, or FB_VK_STAGING): device
     * buffers, copies after each dispatch, the sinks' bands on every core */
    bool staged;
    bool held;   /* pieces make whole batches of the EXR writer: it reads them in place (held) */
    int nplanes; /* stored channels of every layer */
    int threads; /* the sinks' band workers */
} bake_shape;

/* The piece rows a GPU piece aims at on a discrete device: millions of invocations a dispatch. */
#define BAKE_GPU_PIECE_PIXELS (1u << 22)

/* ---- pieces.c ---- */

typedef struct pieces pieces;

/* The ring of `shape->slots` pieces for the layers: their GPU pipelines, jobs and buffers, their host
 * planes. */
fb_result pieces_create(fb_engine *e, layer_run *runs, int nlayers, const bake_shape *shape, pieces **out);

/* Produces every piece of the window in order and feeds them to the sinks on a consumer thread,
 * at most shape->slots in flight; returns once every piece has gone through every sink (or at the
 * first failure, the producer's or a sink's). *gpu_seconds adds the dispatches' device time. */
fb_result pieces_run(pieces *p, fb_sink *const *sinks, int nsinks, bool progress, double *gpu_seconds);

/* Waits for what is in flight and frees the ring. Null-safe. */
void pieces_destroy(pieces **p);

/* The bytes of one slot: host memory (its planes, or its host buffers) and device memory (a staged
 * GPU layer's device buffers), for a piece of `rows` rows. */
void pieces_slot_bytes(const fb_engine *e, const layer_run *runs, int nlayers, int width, int rows, bool staged,
                       uint64_t *host, uint64_t *device);

/* ---- sinks.c ---- */

/* The bake's view of its layers for the sinks. */
typedef struct bake_view {
    const fb_bake_desc *d;
    const fb_scene *s;
    const fb_engine *e;
    const layer_run *runs;
    const int *region;
} bake_view;

/* No NaN or infinity in a float or half channel: an error naming the layer, channel and pixel. */
fb_result sink_check_create(const bake_view *v, fb_sink *out);
/* The layers' heightmaps: their Y channels kept whole, written at end (stats: what was written). */
fb_result sink_heightmaps_create(const bake_view *v, fb_bake_stats *stats, fb_sink *out);
/* The PNG preview (note: what it shows, for the user). */
fb_result sink_previews_create(const bake_view *v, char *note, size_t note_size, fb_sink *out);
/* The EXR file, opened at begin with the bake's attributes; pieces held when shape->held. */
fb_result sink_exr_create(const bake_view *v, const bake_shape *shape, const exrio_channel *channels, int nch,
                          fb_sink *out);
/* A cube's engine face sets (render --cube-faces). */
fb_result sink_faces_create(const bake_view *v, const exrio_channel *channels, int nch, fb_sink *out);

#endif
