/*
 * vkc_bench: what the Vulkan device's memory moves, for `fractalbake bench`'s ceilings (host/core/
 * ceilings.c). Copies recorded with vkCmdCopyBuffer and timed by the device's own timestamps, so
 * that neither the submission, the fence nor a staging copy is in the figure:
 *   - device: a device-local buffer into another (on a discrete GPU, its own memory's bandwidth);
 *   - upload: a host-visible buffer the host wrote into a device-local one (host to device);
 *   - download: a device-local buffer into a host-cached one the host then reads (device to host).
 * On a CPU device (lavapipe) every buffer is host memory and the three are memcpy.
 */
#ifndef FB_VKC_BENCH_H
#define FB_VKC_BENCH_H

#include "vkc.h"

typedef struct vkc_copy_rates {
    uint64_t bytes;  /* the size of each copy */
    double device;   /* GB/s read plus written (2 bytes a byte copied), device-local to device-local */
    double upload;   /* GB/s copied, host-visible to device-local */
    double download; /* GB/s copied, device-local to host-cached */
} vkc_copy_rates;

/* Times each copy of `bytes` bytes `reps` times after a warm-up and keeps the fastest. All rates 0
 * where the queue has no timestamps (FB_OK). Failures: FB_ERR_NOMEM when the buffers do not fit,
 * FB_ERR_VULKAN; *out is written only on success. */
fb_result vkc_bench_copies(vkc_context *ctx, uint64_t bytes, int reps, vkc_copy_rates *out);

#endif
