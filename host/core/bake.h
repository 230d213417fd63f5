/*
 * The bake driver: scene -> generators -> pieces -> sinks (the EXR writer, the PNG preview, the
 * heightmaps, a cube's faces, the finite check).
 *
 * Every generator computes pieces of rows keyed by absolute pixel coordinates, so the result does
 * not depend on the piece's height, the thread count or the order in which pieces complete. Pieces
 * are sized for the device (a CPU's strips of a few MiB, a discrete GPU's dispatches of millions of
 * invocations), and at most a ring of them is in flight between the producer and the sinks.
 */
#ifndef FB_BAKE_H
#define FB_BAKE_H

#include "engine.h"
#include "gen.h"
#include "scene.h"

/* The predicted peak memory of a bake (bytes), before anything large is allocated. */
typedef struct fb_bake_plan {
    int nlayers;
    struct {
        char name[64];
        uint64_t bytes; /* the layer's own peak (histogram, mesh, grid) and its strip buffers */
    } layers[FB_MAX_LAYERS];
    uint64_t base;    /* the process and its backend (a Vulkan driver is tens of MiB) */
    uint64_t compile; /* a CPU device's compile of its largest pipeline, before the pieces stream */
    uint64_t pieces;  /* the ring of pieces in flight (host memory; a CPU device's buffers included) */
    uint64_t writer;  /* the EXR writer's compressed chunks (and its copies of rows it does not read in place) */
    uint64_t preview; /* the preview's sums */
    uint64_t peak;    /* all of it at the worst moment: base, then the compile or the rest */
    uint64_t planned; /* the peak with the ring the bake takes when memory does not limit it (peak: after
                       * shrinking it to fit limit); --dry-run's prediction and a refusal's figure */
    uint64_t limit;   /* --max-memory */
    uint64_t device;  /* a discrete GPU's own memory: the ring's device buffers (not in peak) */
    int piece_rows;   /* rows of a piece */
    int slots;        /* pieces in flight */
} fb_bake_plan;

typedef struct fb_bake_desc {
    const fb_scene *scene;
    const char *out;     /* EXR path; NULL computes without writing (benchmarks) */
    const char *preview; /* PNG path or NULL */
    /* What the preview shows: a layer's name, or "over" (every layer composited back to front by its
     * coverage channel A; op layers are left out). NULL: the only layer, or "over" when there are several. */
    const char *preview_layer;
    int strip_rows; /* the rows of a piece (a dispatch on a GPU); 0: sized for the device */
    int zip_level;  /* the deflate level of ZIP chunks; 0: EXRIO_ZIP_LEVEL */
    /* The points part {K, N} (1 <= K <= N) of every chaos game to compute (render --points-part
     * K/N), the other layers whole; N == 0: the whole games. */
    int points_part[2];
    /* Only the pixels [x, x + w) x [y, y + h) of the image, as in the full bake, into a file whose
     * data window is that region (fractalbake merge joins such files). w == 0: the whole image. */
    int region[4];
    bool progress; /* draw a progress bar on stderr */
    /* Fill *plan (if not NULL) with the predicted memory; dry_run: stop there, writing nothing. A
     * bake whose peak exceeds max_memory (--max-memory; 0: the default, fb_memory_limit) fails
     * before it allocates (FB_ERR_INPUT). */
    uint64_t max_memory;
    fb_bake_plan *plan;
    bool dry_run;
    /* Called after a successful bake for each layer that reports on its computation (terrain):
     * a human line and a JSON object. NULL: no reports. */
    void (*report)(const char *layer, const char *summary, const char *json, void *user);
    void *user;
    /* More string attributes for the file (a task's: render --task), after the usual ones; and
     * whether to list every layer's backend (fractalbake/layer-backends) even when they agree. */
    const exrio_attr *attrs;
    int nattrs;
    bool layer_backends;
    /* A cube environment map's six faces as engine face sets (faces.h: render --cube-faces); NULL:
     * none. The whole image, no region. */
    const char *cube_faces;
    /* render --from an auto bake's file: each layer on the backend it ran on there (its
     * fractalbake/layer-backends), where this engine has that backend; NULL: the engine's choice */
    const char *layer_kinds;
} fb_bake_desc;

/* A heightmap a bake wrote: its layer, file, format and the heights stored as 0 and 65535. */
typedef struct fb_bake_heightmap {
    const char *layer, *path; /* the scene's strings */
    const char *sidecar;      /* an engine preset's import settings (OUT.import.json), or NULL */
    int format;               /* fb_heightmap_format */
    double lo, hi;
    int engine;             /* fb_heightmap_engine */
    int tiles[2];           /* columns, rows: written as tiles (path names none of them), or 0, 0 */
    const char *tile_paths; /* the scene's tile names (FB_TILE_PATH bytes each), row by row from the north-west */
} fb_bake_heightmap;

typedef struct fb_bake_stats {
    /* where the layers ran: "on llvmpipe (...)", "on native C", or per layer ("with sky on llvmpipe
     * (...), terrain and plants on native C") when --backend auto chose per layer */
    char ran_on[512];
    fb_backend layer_backend[FB_MAX_LAYERS]; /* where each layer ran: FB_BACKEND_VULKAN or _NATIVE */
    char preview[1024];                      /* what the preview shows ("" without one) */
    fb_bake_heightmap heightmaps[FB_MAX_LAYERS];
    int nheightmaps;
    double seconds;     /* wall time of the whole bake */
    double gpu_seconds; /* sum of dispatch timestamps (vulkan), else -1 */
    uint64_t pixels;
} fb_bake_stats;

/* Bakes every layer of the scene with engine `e`. On failure no output file exists. */
fb_result fb_bake(fb_engine *e, const fb_bake_desc *desc, fb_bake_stats *stats);

#endif
