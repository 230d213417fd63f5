/*
 * The machine's ceilings, measured once per `fractalbake bench` run so that every rate can be read
 * against what this machine can do: an FMA-bound kernel (GFLOP/s) and a buffer copy (GB/s), as a
 * compute shader on the Vulkan device and as a native loop on every core, with the driver, its LLVM
 * and the CPU named.
 */
#ifndef FB_CEILINGS_H
#define FB_CEILINGS_H

#include "engine.h"

typedef struct fb_ceilings {
    double vk_gflops, vk_gbps;         /* 0: not measured (no device) */
    double native_gflops, native_gbps; /* on the pool's threads */
    int threads;
    char device[256], driver[256]; /* the Vulkan device and driver ("llvmpipe Mesa 22.3.6 (LLVM 15.0.6)") */
    char cpu[128];                 /* /proc/cpuinfo's model name, or "" */
} fb_ceilings;

/* Measures the ceilings on the Vulkan engine `vk` (NULL: none) and a native engine `native` (its
 * pool; NULL: not measured), each the best of three runs after a warm-up. */
fb_result fb_ceilings_measure(fb_engine *vk, fb_engine *native, fb_ceilings *out);

#endif
