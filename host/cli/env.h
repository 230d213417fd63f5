/*
 * The environment, read in this one place (the command line's) and passed down in descriptors:
 * nothing below host/cli reads an environment variable.
 *   FB_VK_VALIDATION=1     the Vulkan validation layer on every context (the test suite sets it)
 *   FB_VK_STAGING=1        a discrete GPU's path on any device: device-local memory and staging copies,
 *                          and the portable exact division and square root (kernels/exact.h)
 *   FB_VK_PORTABLE=1       the portable exact division and square root alone
 *   FB_VK_NO_INT64=1       as if the device had no 64-bit buffer atomics
 *   FB_VK_NO_FLOAT64=1     as if the device had no shaderFloat64
 *   FB_NO_PIPELINE_CACHE=1 no pipeline cache on disk
 *   LP_NUM_THREADS, LP_NATIVE_VECTOR_WIDTH   lavapipe's own (read by it; recorded by the bench)
 *   XDG_CACHE_HOME, HOME   the pipeline cache's folder: $XDG_CACHE_HOME/fractalbake, else
 *                          $HOME/.cache/fractalbake
 *   TMPDIR                 where standard output's data ("-o -") waits for the commit (/tmp
 *                          when unset: output.h)
 */
#ifndef FB_ENV_H
#define FB_ENV_H

#include "vkc.h"

typedef struct fb_env {
    vkc_desc vk;          /* validation, staging, portable, no_int64, no_float64, no_pipeline_cache, cache_dir */
    char cache_dir[1024]; /* vk.cache_dir points here ("" and NULL: none) */
    /* lavapipe's own settings, which change its speed (LP_NUM_THREADS: its threads) or its results
     * (LP_NATIVE_VECTOR_WIDTH: 256 gives subgroups of 8, 128 of 4), as given ("" when unset); the
     * bench records them on every line */
    char lp_num_threads[32], lp_vector_width[32];
    char tmpdir[1024]; /* TMPDIR as given ("" when unset) */
} fb_env;

/* Reads the variables above into *env. */
void fb_env_read(fb_env *env);

/* lavapipe runs compute on a pool of its own, LP_NUM_THREADS threads (by default one per core), read
 * when it creates a device: a command with --threads N sets it to N before it opens a Vulkan engine,
 * so that N bounds lavapipe's threads too. threads <= 0: left as it is. */
void fb_env_lavapipe_threads(int threads);

#endif
