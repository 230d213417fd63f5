/*
 * Erosion of a height grid (kernels/erode.h): hydraulic erosion with virtual pipes (Mei, Decaudin
 * and Hu 2007) and thermal erosion by talus angle (Musgrave, Kolb and Mace 1989), run natively on a
 * thread pool or on a Vulkan device from the same kernels. Every pass is a pure function of the
 * previous grids, so the result does not depend on the thread count; the native path and lavapipe
 * give the same bits (tests/test_erode.c).
 */
#ifndef FB_ERODE_H
#define FB_ERODE_H

#include "fb.h"
#include "pool.h"
#include "progress.h"
#include "vkc.h"

#include "kernels/erode.h"

#include <stdint.h>

/* The model's parameters, in world units: lengths in the heights' unit, times in one time unit. */
typedef struct fb_erode_desc {
    int width, height;
    double cell;      /* world size of one cell (the layer's extent / width) */
    int iterations;   /* time steps */
    double duration;  /* simulated time; the time step is duration / iterations */
    double rain;      /* water added, height per time unit */
    double gravity;   /* g of the pipes' acceleration */
    double capacity;  /* Kc: sediment carried per unit sin(slope) and unit speed */
    double dissolve;  /* Ks: dissolution rate, per time unit */
    double deposit;   /* Kd: deposition rate, per time unit */
    double evaporate; /* Ke: evaporation rate, per time unit */
    double talus;     /* the talus angle, degrees: steeper slopes slide */
    double thermal;   /* thermal erosion rate, per time unit (0: none) */
    double depth;     /* the water depth that carries the full capacity (shallower: proportionally less) */
    double min_depth; /* the depth the velocity divides by at least (0: 1e-4) */
    const float *bed; /* width * height input heights, row-major */
} fb_erode_desc;

/* The result, width * height floats each (malloc'd; fb_erode_out_free frees them). */
typedef struct fb_erode_out {
    float *bed;         /* the bed after erosion (the settled height is bed + sediment) */
    float *water;       /* the water depth left */
    float *sediment;    /* the sediment still suspended */
    float *flow;        /* the time-averaged discharge per unit width */
    float *wear;        /* the material removed (dissolved or slid away), summed */
    float *deposit;     /* the material laid down (deposited or slid in), summed */
    double gpu_seconds; /* Vulkan: the dispatches' time, else -1 */
} fb_erode_out;

/* The kernel's parameter block for the description (pass 0). */
K_ErodeParams fb_erode_params(const fb_erode_desc *d);

/* Checks the description; NULL when it is good, else what is wrong. */
const char *fb_erode_check(const fb_erode_desc *d);

/* Bytes the run allocates at its peak (the state grids and the result). */
uint64_t fb_erode_memory(int width, int height);

/* Runs the model natively (pool: NULL for the calling thread only). On failure *out is untouched. */
fb_result fb_erode_run_native(const fb_erode_desc *d, fb_pool *pool, fb_progress *prog, fb_erode_out *out);

/* Runs the model on a Vulkan device, one dispatch per pass. FB_ERR_INPUT when a grid is larger than
 * the device's storage buffer range (16 bytes a cell). */
fb_result fb_erode_run_vulkan(const fb_erode_desc *d, vkc_context *vk, fb_progress *prog, fb_erode_out *out);

void fb_erode_out_free(fb_erode_out *o);

#endif
