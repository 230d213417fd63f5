/*
 * Engines: the backend a bake runs on (a Vulkan device, or native C on a thread pool), opened once
 * per run and shared by its bakes.
 */
#ifndef FB_ENGINE_H
#define FB_ENGINE_H

#include "pool.h"
#include "vkc.h"

typedef enum fb_backend { FB_BACKEND_AUTO = 0, FB_BACKEND_VULKAN, FB_BACKEND_NATIVE } fb_backend;

/* The compute backend in use: a Vulkan context, or a thread pool for the native kernels. */
typedef struct fb_engine {
    fb_backend kind;
    fb_backend asked; /* the desc's backend (AUTO, VULKAN, NATIVE): what the file records */
    vkc_context *vk;
    fb_pool *pool;
    int threads;
    bool scalar; /* native: portable kernels only (the benchmark's scalar reference) */
    /* --backend auto found only a CPU implementation of Vulkan (lavapipe): each layer runs on the
     * backend that is faster for it (fb_gen.lavapipe_faster; measured in bench/RESULTS.md), the
     * same bits as that backend alone. */
    bool per_layer;
    char device[256];
    /* Why --backend auto runs natively (no Vulkan device; an address-space limit too small for a
     * driver): the first bake says it once its memory is known to fit (fb_engine_say_fallback), so
     * that a bake refused at once gives its one line only. */
    char fallback[256];
    /* The address space this engine maps beyond the data a bake predicts (its threads' stacks and
     * arenas, a Vulkan driver's mappings): fb_memory.overhead of the bakes it runs. */
    uint64_t overhead;
} fb_engine;

typedef struct fb_engine_desc {
    fb_backend backend; /* AUTO: a GPU if one exists; on lavapipe, per layer (per_layer); no device: native */
    const char *device;
    int threads; /* native workers and EXR compression threads; 0: one per core */
    bool validation;
    bool scalar;         /* native: no hand-vectorised paths */
    vkc_desc vk_options; /* the Vulkan context's other options (its device and validation: the fields above) */
} fb_engine_desc;

fb_result fb_engine_open(const fb_engine_desc *desc, fb_engine *out);

/* The backend layer `name` ran on, from a "fractalbake/layer-backends" list ("a=vulkan;b=native"):
 * false when the list names no such layer or gives it no backend this version knows. */
bool fb_layer_backend_of(const char *list, const char *name, fb_backend *out);

/* Logs the engine's fallback note as a warning, once (then clears it). */
void fb_engine_say_fallback(fb_engine *e);
void fb_engine_close(fb_engine *e);
const char *fb_backend_name(fb_backend b);

#endif
