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

fb_result fb_engine_open(const fb_engine_desc *d, fb_engine *e)
{
    memset(e, 0, sizeof *e);
    e->threads = d->threads > 0 ? d->threads : fb_cpu_count();
    if (d->backend != FB_BACKEND_NATIVE) {
        /* lavapipe runs compute on a pool of its own, LP_NUM_THREADS threads (by default one per
         * core), read when the device is created: --threads bounds it too. */
        if (d->threads > 0) {
            char n[16];
            snprintf(n, sizeof n, "%d", d->threads);
            setenv("LP_NUM_THREADS", n, 1);
        }
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
            return rc;
        }
        /* Only a missing loader or device falls back, and only when vulkan was not asked for. */
        if (d->backend == FB_BACKEND_VULKAN || rc != FB_ERR_NODEVICE) return rc;
        fb_log(FB_LOG_WARN, "no Vulkan device available: using the native backend (%d threads)", e->threads);
    }
    e->kind = FB_BACKEND_NATIVE;
    e->scalar = d->scalar;
    /* No thread count here: it is stored in the file, which must not depend on it. */
    snprintf(e->device, sizeof e->device, "native C");
    return fb_pool_create(e->threads, &e->pool);
}

void fb_engine_close(fb_engine *e)
{
    if (!e) return;
    fb_pool_destroy(&e->pool);
    vkc_destroy(&e->vk);
    memset(e, 0, sizeof *e);
}
