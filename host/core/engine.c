/*
 * Engines: a backend opened once and shared by every bake of a run. See engine.h.
 */
#include "engine.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *fb_backend_name(fb_backend b)
{
    return b == FB_BACKEND_VULKAN ? "vulkan" : b == FB_BACKEND_NATIVE ? "native" : "auto";
}

/* The address space a process maps beyond its data (measured VmPeak of small bakes on the 2-core
 * development machine, 2026-12-02, rounded up): natively 149, 232 and 597 MB at 1, 2 and 8 threads
 * (the binary, a stack and a malloc arena per thread); on lavapipe 727, 957 and 1547 MB (LLVM and
 * the driver's own threads). The Vulkan figure covers what the driver needs to start at all: under
 * less it crashes inside vkCreateDevice or the first pipeline (SIGSEGV), past any check of ours. */
static uint64_t native_overhead(int threads)
{
    return ((uint64_t)96 << 20) + (uint64_t)threads * ((uint64_t)72 << 20);
}

static uint64_t vulkan_overhead(int threads)
{
    return ((uint64_t)600 << 20) + (uint64_t)threads * ((uint64_t)120 << 20);
}

fb_result fb_engine_open(const fb_engine_desc *d, fb_engine *e)
{
    memset(e, 0, sizeof *e);
    e->asked = d->backend;
    e->threads = d->threads > 0 ? d->threads : fb_cpu_count();
    e->overhead = native_overhead(e->threads);
    uint64_t as = fb_address_space_limit(), need = vulkan_overhead(e->threads);
    if (d->backend != FB_BACKEND_NATIVE && as != UINT64_MAX && as < need + ((uint64_t)64 << 20)) {
        char have[32], want[32];
        fb_format_bytes(as, have, sizeof have);
        fb_format_bytes(need, want, sizeof want);
        if (d->backend == FB_BACKEND_VULKAN)
            return fb_fail(FB_ERR_USAGE,
                           "--backend vulkan: the address-space limit (ulimit -v) is %s; a Vulkan driver needs "
                           "about %s of it at %d threads: raise the limit, or use --backend native",
                           have, want, e->threads);
        snprintf(e->fallback, sizeof e->fallback,
                 "the address-space limit (ulimit -v) %s is below the about %s a Vulkan driver needs: using the "
                 "native backend (%d threads)",
                 have, want, e->threads);
    } else if (d->backend != FB_BACKEND_NATIVE) {
        vkc_desc vd = d->vk_options;
        vd.device = d->device;
        vd.validation = d->validation || d->vk_options.validation;
        fb_result rc = vkc_create(&vd, &e->vk);
        if (rc == FB_OK) {
            e->kind = FB_BACKEND_VULKAN;
            snprintf(e->device, sizeof e->device, "%s", vkc_info(e->vk)->name);
            /* auto on a CPU implementation (lavapipe): the native path where it is faster */
            e->per_layer = d->backend == FB_BACKEND_AUTO && !strcmp(vkc_info(e->vk)->type, "cpu");
            e->scalar = d->scalar;
            /* the host's own work (chaos-game reductions, rasterised meshes, native layers) on every core */
            rc = fb_pool_create(e->threads, &e->pool);
            if (rc) vkc_destroy(&e->vk);
            if (!rc) e->overhead = need;
            return rc;
        }
        /* Only a missing loader or device falls back, and only when vulkan was not asked for. */
        if (d->backend == FB_BACKEND_VULKAN || rc != FB_ERR_NODEVICE) return rc;
        snprintf(e->fallback, sizeof e->fallback, "no Vulkan device available: using the native backend (%d threads)",
                 e->threads);
    }
    e->kind = FB_BACKEND_NATIVE;
    e->scalar = d->scalar;
    /* No thread count here: it is stored in the file, which must not depend on it. */
    snprintf(e->device, sizeof e->device, "native C");
    return fb_pool_create(e->threads, &e->pool);
}

bool fb_layer_backend_of(const char *list, const char *name, fb_backend *out)
{
    size_t len = strlen(name);
    for (const char *q = list; q && *q; q = strchr(q, ';') ? strchr(q, ';') + 1 : NULL)
        if (!strncmp(q, name, len) && q[len] == '=') {
            const char *v = q + len + 1;
            size_t n = strcspn(v, ";");
            for (fb_backend b = FB_BACKEND_VULKAN; b <= FB_BACKEND_NATIVE; b++)
                if (n == strlen(fb_backend_name(b)) && !strncmp(v, fb_backend_name(b), n)) return *out = b, true;
            return false;
        }
    return false;
}

void fb_engine_say_fallback(fb_engine *e)
{
    if (e->fallback[0]) fb_log(FB_LOG_WARN, "%s", e->fallback);
    e->fallback[0] = 0;
}

void fb_engine_close(fb_engine *e)
{
    if (!e) return;
    fb_pool_destroy(&e->pool);
    vkc_destroy(&e->vk);
    memset(e, 0, sizeof *e);
}
