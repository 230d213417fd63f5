/*
 * The device's copy rates, timed by its timestamps: see vkc_bench.h.
 */
#include "vkc_private.h"
#include "vkc_bench.h"

#include <string.h>

typedef struct bench_buf {
    VkBuffer buf;
    VkDeviceMemory mem;
    void *map; /* host-visible buffers: mapped */
} bench_buf;

static void drop(vkc_context *ctx, bench_buf *b)
{
    if (b->buf) ctx->vk.vkDestroyBuffer(ctx->device, b->buf, NULL);
    if (b->mem) ctx->vk.vkFreeMemory(ctx->device, b->mem, NULL); /* unmaps */
    memset(b, 0, sizeof *b);
}

/* A transfer buffer of `size` bytes in the first memory type with all the flags of one of prefs[],
 * in order; mapped when `map`. */
static fb_result make(vkc_context *ctx, uint64_t size, const VkMemoryPropertyFlags *prefs, int nprefs, bool map,
                      bench_buf *b)
{
    fb_result rc = FB_OK;
    VkBufferCreateInfo bci = {
        .sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO,
        .size = size,
        .usage = VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
        .sharingMode = VK_SHARING_MODE_EXCLUSIVE,
    };
    VKC_CHECK(ctx->vk.vkCreateBuffer(ctx->device, &bci, NULL, &b->buf), fail);
    VkMemoryRequirements req;
    ctx->vk.vkGetBufferMemoryRequirements(ctx->device, b->buf, &req);
    int type = -1;
    for (int p = 0; p < nprefs && type < 0; p++)
        for (uint32_t i = 0; i < ctx->mem.memoryTypeCount && type < 0; i++)
            if ((req.memoryTypeBits & (1u << i)) && (ctx->mem.memoryTypes[i].propertyFlags & prefs[p]) == prefs[p])
                type = (int)i;
    if (type < 0) {
        rc = fb_fail(FB_ERR_VULKAN, "vulkan: no memory type for a %llu-byte transfer buffer", (unsigned long long)size);
        goto fail;
    }
    VkMemoryAllocateInfo mai = {
        .sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO,
        .allocationSize = req.size,
        .memoryTypeIndex = (uint32_t)type,
    };
    VKC_CHECK(ctx->vk.vkAllocateMemory(ctx->device, &mai, NULL, &b->mem), fail);
    VKC_CHECK(ctx->vk.vkBindBufferMemory(ctx->device, b->buf, b->mem, 0), fail);
    if (map) {
        VKC_CHECK(ctx->vk.vkMapMemory(ctx->device, b->mem, 0, VK_WHOLE_SIZE, 0, &b->map), fail);
        memset(b->map, 1, size); /* every page touched before any copy is timed */
        if (!(ctx->mem.memoryTypes[type].propertyFlags & VK_MEMORY_PROPERTY_HOST_COHERENT_BIT)) {
            VkMappedMemoryRange r = {
                .sType = VK_STRUCTURE_TYPE_MAPPED_MEMORY_RANGE, .memory = b->mem, .size = VK_WHOLE_SIZE};
            VKC_CHECK(ctx->vk.vkFlushMappedMemoryRanges(ctx->device, 1, &r), fail);
        }
    }
    return FB_OK;
fail:
    drop(ctx, b);
    return rc;
}

typedef struct bench_cmd {
    VkCommandBuffer cmd;
    VkFence fence;
    VkQueryPool queries;
} bench_cmd;

/* One copy of `bytes` from src to dst between two timestamps; *seconds the time between them. A
 * copy into host memory is followed by a transfer-to-host barrier, as a real download is. */
static fb_result timed_copy(vkc_context *ctx, const bench_cmd *c, VkBuffer src, VkBuffer dst, uint64_t bytes,
                            bool to_host, double *seconds)
{
    fb_result rc = FB_OK;
    VKC_CHECK(ctx->vk.vkResetCommandBuffer(c->cmd, 0), out);
    VkCommandBufferBeginInfo cbbi = {
        .sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO,
        .flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT,
    };
    VKC_CHECK(ctx->vk.vkBeginCommandBuffer(c->cmd, &cbbi), out);
    ctx->vk.vkCmdResetQueryPool(c->cmd, c->queries, 0, 2);
    ctx->vk.vkCmdWriteTimestamp(c->cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, c->queries, 0);
    VkBufferCopy region = {.size = bytes};
    ctx->vk.vkCmdCopyBuffer(c->cmd, src, dst, 1, &region);
    ctx->vk.vkCmdWriteTimestamp(c->cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, c->queries, 1);
    if (to_host) {
        VkMemoryBarrier hb = {
            .sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER,
            .srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT,
            .dstAccessMask = VK_ACCESS_HOST_READ_BIT,
        };
        ctx->vk.vkCmdPipelineBarrier(c->cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &hb, 0,
                                     NULL, 0, NULL);
    }
    VKC_CHECK(ctx->vk.vkEndCommandBuffer(c->cmd), out);
    VKC_CHECK(ctx->vk.vkResetFences(ctx->device, 1, &c->fence), out);
    VkSubmitInfo si = {.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO, .commandBufferCount = 1, .pCommandBuffers = &c->cmd};
    VKC_CHECK(ctx->vk.vkQueueSubmit(ctx->queue, 1, &si, c->fence), out);
    VKC_CHECK(ctx->vk.vkWaitForFences(ctx->device, 1, &c->fence, VK_TRUE, UINT64_MAX), out);
    uint64_t ts[2];
    VKC_CHECK(ctx->vk.vkGetQueryPoolResults(ctx->device, c->queries, 0, 2, sizeof ts, ts, sizeof ts[0],
                                            VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT),
              out);
    *seconds = (double)(ts[1] - ts[0]) * (double)ctx->timestamp_period * 1e-9;
out:
    return rc;
}

/* The fastest of `reps` copies after a warm-up, as GB/s of `bytes` times `factor`. */
static fb_result best_rate(vkc_context *ctx, const bench_cmd *c, VkBuffer src, VkBuffer dst, uint64_t bytes,
                           bool to_host, int reps, double factor, double *gbps)
{
    double best = 0;
    fb_result rc = FB_OK;
    for (int r = -1; r < reps && !rc; r++) {
        double s = 0;
        rc = timed_copy(ctx, c, src, dst, bytes, to_host, &s);
        if (!rc && r >= 0 && s > 0 && (best == 0 || s < best)) best = s;
    }
    if (!rc) *gbps = best > 0 ? factor * (double)bytes / best * 1e-9 : 0;
    return rc;
}

fb_result vkc_bench_copies(vkc_context *ctx, uint64_t bytes, int reps, vkc_copy_rates *out)
{
    if (!ctx->timestamps) {
        *out = (vkc_copy_rates){.bytes = bytes};
        return FB_OK;
    }
    fb_result rc = FB_OK;
    bench_buf a = {0}, b = {0}, up = {0}, down = {0};
    bench_cmd c = {0};
    vkc_copy_rates r = {.bytes = bytes};
    const VkMemoryPropertyFlags dev[] = {VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, 0};
    /* what a staging ring uses: write-combined (coherent, uncached) memory to send, cached to read back */
    const VkMemoryPropertyFlags send[] = {
        VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT,
        VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT,
    };
    const VkMemoryPropertyFlags recv[] = {
        VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_CACHED_BIT,
        VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT,
    };
    rc = make(ctx, bytes, dev, 2, false, &a);
    if (!rc) rc = make(ctx, bytes, dev, 2, false, &b);
    if (!rc) rc = make(ctx, bytes, send, 2, true, &up);
    if (!rc) rc = make(ctx, bytes, recv, 2, true, &down);
    if (rc) goto out;
    VkCommandBufferAllocateInfo cbai = {
        .sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO,
        .commandPool = ctx->pool,
        .level = VK_COMMAND_BUFFER_LEVEL_PRIMARY,
        .commandBufferCount = 1,
    };
    VKC_CHECK(ctx->vk.vkAllocateCommandBuffers(ctx->device, &cbai, &c.cmd), out);
    VkFenceCreateInfo fci = {.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    VKC_CHECK(ctx->vk.vkCreateFence(ctx->device, &fci, NULL, &c.fence), out);
    VkQueryPoolCreateInfo qpci = {
        .sType = VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO,
        .queryType = VK_QUERY_TYPE_TIMESTAMP,
        .queryCount = 2,
    };
    VKC_CHECK(ctx->vk.vkCreateQueryPool(ctx->device, &qpci, NULL, &c.queries), out);
    /* the upload first: it also fills the device buffer the other copies read */
    rc = best_rate(ctx, &c, up.buf, a.buf, bytes, false, reps, 1.0, &r.upload);
    if (!rc) rc = best_rate(ctx, &c, a.buf, b.buf, bytes, false, reps, 2.0, &r.device);
    if (!rc) rc = best_rate(ctx, &c, a.buf, down.buf, bytes, true, reps, 1.0, &r.download);
    if (!rc) *out = r;
out:
    if (c.queries) ctx->vk.vkDestroyQueryPool(ctx->device, c.queries, NULL);
    if (c.fence) ctx->vk.vkDestroyFence(ctx->device, c.fence, NULL);
    if (c.cmd) ctx->vk.vkFreeCommandBuffers(ctx->device, ctx->pool, 1, &c.cmd);
    drop(ctx, &a);
    drop(ctx, &b);
    drop(ctx, &up);
    drop(ctx, &down);
    return rc;
}
