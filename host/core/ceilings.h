/*
 * The machine's ceilings, measured once per `fractalbake bench` run so that every rate can be read
 * against what this machine can do: an FMA-bound kernel (GFLOP/s) and a buffer copy (GB/s), as a
 * compute shader on the Vulkan device and as a native loop on every core, with the driver, its LLVM
 * and the CPU named; and on the device, what its memory moves: a device-local copy and the host
 * transfer both ways (vkc_bench.h), each timed by the device's timestamps.
 *
 * The device's rates come from its timestamps wherever the queue has them: a host clock around a
 * submission on a discrete GPU also counts the submission, the fence and vkc's copy of every buffer
 * a job wrote back to its host staging buffer. The copy ceiling of earlier runs ("copy", 48.6 GB/s
 * on an NVIDIA H200 whose memory moves about 4.3 TB/s) was that: the shader's 2 x 64 MiB timed by
 * the host clock, which on a discrete device included the download of both 64 MiB buffers, so it
 * measured the PCIe transfer. It is still reported, as "shader-copy-readback".
 */
#ifndef FB_CEILINGS_H
#define FB_CEILINGS_H

#include "engine.h"

typedef struct fb_ceilings {
    double vk_gflops;      /* 0: not measured (no device) */
    double vk_gbps;        /* the copy shader, device-local buffers, timestamps: read plus written */
    double vk_gbps_wall;   /* the same dispatch by the host clock, with the staging readback (the old "copy") */
    double vk_copy_gbps;   /* vkCmdCopyBuffer device-local to device-local, read plus written */
    double vk_upload_gbps; /* host to device, copied */
    double vk_download_gbps;
    uint64_t vk_copy_bytes;            /* the size of each of those copies */
    double native_gflops, native_gbps; /* on the pool's threads */
    int threads;
    char device[256], driver[256]; /* the Vulkan device and driver ("llvmpipe Mesa 22.3.6 (LLVM 15.0.6)") */
    char cpu[128];                 /* /proc/cpuinfo's model name, or "" */
} fb_ceilings;

/* Measures the ceilings on the Vulkan engine `vk` (NULL: none) and a native engine `native` (its
 * pool; NULL: not measured), each the best of three runs after a warm-up. */
fb_result fb_ceilings_measure(fb_engine *vk, fb_engine *native, fb_ceilings *out);

#endif
