/*
 * The Vulkan context's work: compute pipelines (kept and reused), storage buffers (mapped directly
 * or staged), and jobs (a recorded dispatch with timestamps). See vkc.h for the model.
 */
#include "vkc_private.h"

#include "kernels/device.h" /* K_SPEC_CPU_DEVICE */
#include "kernels/exact.h"  /* K_SPEC_EXACT_NATIVE */
#include "spvpatch.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>

void vkc_pipeline_free(vkc_context *ctx, vkc_pipeline *p)
{
    if (p->pipeline) ctx->vk.vkDestroyPipeline(ctx->device, p->pipeline, NULL);
    if (p->layout) ctx->vk.vkDestroyPipelineLayout(ctx->device, p->layout, NULL);
    if (p->dsl) ctx->vk.vkDestroyDescriptorSetLayout(ctx->device, p->dsl, NULL);
    memset(p, 0, sizeof *p);
    free(p);
}

/* The descriptor type of binding i: bit i of `uniform`, a uniform buffer; else a storage buffer. */
static VkDescriptorType desc_type(uint32_t uniform, uint32_t i)
{
    return (uniform >> i) & 1u ? VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER : VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
}

/* ---- pipelines ------------------------------------------------------------------------------ */

fb_result vkc_pipeline_create(vkc_context *ctx, const vkc_pipeline_desc *desc, vkc_pipeline **out)
{
    fb_result rc = FB_OK;
    VkShaderModule module = VK_NULL_HANDLE;
    if (desc->buffers > 8 || desc->push_size > 128 || desc->push_size % 4 != 0)
        return fb_fail(FB_ERR_INTERNAL, "vulkan: pipeline %s: bad description", desc->name);
    uint32_t nspec = desc->nspec < 8 ? desc->nspec : 8;
    for (vkc_pipeline *q = ctx->pipes; q; q = q->next)
        if (q->spv == desc->spv && q->spv_size == desc->spv_size && q->push_size == desc->push_size &&
            q->buffers == desc->buffers && q->uniform == desc->uniform && q->nspec == nspec &&
            !memcmp(q->spec, desc->spec, 4 * nspec)) {
            *out = q;
            return FB_OK;
        }
    vkc_pipeline *p = calloc(1, sizeof *p);
    if (!p) return fb_fail(FB_ERR_NOMEM, "out of memory creating pipeline %s", desc->name);
    p->push_size = desc->push_size;
    p->buffers = desc->buffers;
    p->uniform = desc->uniform;
    p->spv = desc->spv;
    p->spv_size = desc->spv_size;
    p->nspec = nspec;
    if (nspec) memcpy(p->spec, desc->spec, 4 * nspec);

    VkDescriptorSetLayoutBinding bindings[8];
    for (uint32_t i = 0; i < desc->buffers; i++)
        bindings[i] = (VkDescriptorSetLayoutBinding){
            .binding = i,
            .descriptorType = desc_type(desc->uniform, i),
            .descriptorCount = 1,
            .stageFlags = VK_SHADER_STAGE_COMPUTE_BIT,
        };
    VkDescriptorSetLayoutCreateInfo dslci = {
        .sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO,
        .bindingCount = desc->buffers,
        .pBindings = bindings,
    };
    VKC_CHECK(ctx->vk.vkCreateDescriptorSetLayout(ctx->device, &dslci, NULL, &p->dsl), fail);
    VkPushConstantRange range = {.stageFlags = VK_SHADER_STAGE_COMPUTE_BIT, .offset = 0, .size = desc->push_size};
    VkPipelineLayoutCreateInfo plci = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO,
        .setLayoutCount = 1,
        .pSetLayouts = &p->dsl,
        .pushConstantRangeCount = desc->push_size ? 1 : 0,
        .pPushConstantRanges = &range,
    };
    VKC_CHECK(ctx->vk.vkCreatePipelineLayout(ctx->device, &plci, NULL, &p->layout), fail);
    /* The float-controls modes the device offers (round to nearest, denormals and NaN kept), so that
     * it rounds as the native path does (spvpatch.h). */
    const vkc_device_info *in = &ctx->info;
    uint32_t *code = NULL;
    size_t words = 0;
    size_t nmod = 0;
    const uint32_t *mod = spv_variant(desc->spv, desc->spv_size / 4, in->exact_native, &nmod);
    rc = spv_add_float_controls(mod, nmod, (spv_float_modes){in->rte32, in->denorm32, in->szinp32},
                                (spv_float_modes){in->rte64, in->denorm64, in->szinp64}, &code, &words);
    if (rc) goto fail;
    VkShaderModuleCreateInfo smci = {
        .sType = VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO,
        .codeSize = words * 4,
        .pCode = code,
    };
    VkResult made = ctx->vk.vkCreateShaderModule(ctx->device, &smci, NULL, &module);
    free(code);
    VKC_CHECK(made, fail);
    /* Specialization lets the device compiler fold uniform choices (noise kind, style flags) away:
     * on lavapipe every branch it cannot prove uniform costs both sides. Every pipeline also gets
     * K_SPEC_EXACT_NATIVE (kernels/exact.h): the device's own division where it is known exact (the
     * native variant has it as a constant already; the portable one's answer then stays false). */
    VkSpecializationMapEntry entries[10];
    uint32_t data[10];
    for (uint32_t i = 0; i < nspec; i++) {
        entries[i] = (VkSpecializationMapEntry){.constantID = i, .offset = 4 * i, .size = 4};
        data[i] = desc->spec[i];
    }
    entries[nspec] = (VkSpecializationMapEntry){.constantID = K_SPEC_EXACT_NATIVE, .offset = 4 * nspec, .size = 4};
    data[nspec] = in->exact_native ? VK_TRUE : VK_FALSE;
    /* and K_SPEC_CPU_DEVICE (kernels/device.h): the forms that suit a CPU's SIMD lanes */
    entries[nspec + 1] =
        (VkSpecializationMapEntry){.constantID = K_SPEC_CPU_DEVICE, .offset = 4 * (nspec + 1), .size = 4};
    data[nspec + 1] = ctx->direct_map && !strcmp(in->type, "cpu") ? VK_TRUE : VK_FALSE;
    VkSpecializationInfo spec = {
        .mapEntryCount = nspec + 2,
        .pMapEntries = entries,
        .dataSize = 4 * (nspec + 2),
        .pData = data,
    };
    VkComputePipelineCreateInfo cpci = {
        .sType = VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO,
        .stage =
            {
                .sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO,
                .stage = VK_SHADER_STAGE_COMPUTE_BIT,
                .module = module,
                .pName = "main",
                .pSpecializationInfo = &spec,
            },
        .layout = p->layout,
    };
    VKC_CHECK(ctx->vk.vkCreateComputePipelines(ctx->device, ctx->cache, 1, &cpci, NULL, &p->pipeline), fail);
    ctx->vk.vkDestroyShaderModule(ctx->device, module, NULL);
    p->next = ctx->pipes;
    ctx->pipes = p;
    *out = p;
    return FB_OK;
fail:
    if (module) ctx->vk.vkDestroyShaderModule(ctx->device, module, NULL);
    vkc_pipeline_free(ctx, p);
    return rc;
}

/* The context keeps the pipeline for reuse; it is freed with the context. */
void vkc_pipeline_destroy(vkc_context *ctx, vkc_pipeline **pp)
{
    (void)ctx;
    if (pp) *pp = NULL;
}

/* ---- buffers -------------------------------------------------------------------------------- */

struct vkc_buffer {
    uint64_t size;
    vkc_buffer_kind kind;
    VkBuffer buf; /* the storage buffer the shader writes (a host buffer: the mapped buffer itself) */
    VkDeviceMemory mem;
    VkBuffer staging; /* a shared buffer's host-readable copy, when `buf` is not mapped directly */
    VkDeviceMemory staging_mem;
    void *map;
    bool coherent;
    bool upload_pending; /* staging holds host data to copy into `buf` before the next dispatch */
};

/* The first memory type allowed by `bits` that has all of `want`. */
static int find_memory(const vkc_context *ctx, uint32_t bits, VkMemoryPropertyFlags want)
{
    for (uint32_t i = 0; i < ctx->mem.memoryTypeCount; i++)
        if ((bits & (1u << i)) && (ctx->mem.memoryTypes[i].propertyFlags & want) == want) return (int)i;
    return -1;
}

static fb_result make_buffer(vkc_context *ctx, uint64_t size, VkBufferUsageFlags usage,
                             const VkMemoryPropertyFlags *prefs, int nprefs, VkBuffer *buf, VkDeviceMemory *mem,
                             VkMemoryPropertyFlags *got)
{
    fb_result rc = FB_OK;
    VkBufferCreateInfo bci = {
        .sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO,
        .size = size,
        .usage = usage,
        .sharingMode = VK_SHARING_MODE_EXCLUSIVE,
    };
    VKC_CHECK(ctx->vk.vkCreateBuffer(ctx->device, &bci, NULL, buf), fail);
    VkMemoryRequirements req;
    ctx->vk.vkGetBufferMemoryRequirements(ctx->device, *buf, &req);
    int type = -1;
    for (int i = 0; i < nprefs && type < 0; i++) type = find_memory(ctx, req.memoryTypeBits, prefs[i]);
    if (type < 0) {
        rc = fb_fail(FB_ERR_VULKAN, "vulkan: no suitable memory type for a %llu-byte buffer", (unsigned long long)size);
        goto fail;
    }
    VkMemoryAllocateInfo mai = {
        .sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO,
        .allocationSize = req.size,
        .memoryTypeIndex = (uint32_t)type,
    };
    VKC_CHECK(ctx->vk.vkAllocateMemory(ctx->device, &mai, NULL, mem), fail);
    VKC_CHECK(ctx->vk.vkBindBufferMemory(ctx->device, *buf, *mem, 0), fail);
    *got = ctx->mem.memoryTypes[type].propertyFlags;
    return FB_OK;
fail:
    return rc;
}

static void advise_huge(void *p, uint64_t size);

/* (any storage buffer may be bound as a uniform buffer: vkc_pipeline_desc.uniform; and copied from
 * or to: "VUID-vkCmdCopyBuffer-srcBuffer-00118: srcBuffer must have been created with
 * VK_BUFFER_USAGE_TRANSFER_SRC_BIT usage flag") */
static const VkBufferUsageFlags k_storage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT |
                                            VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
static const VkBufferUsageFlags k_transfer = VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;

/* Host-cached memory if there is any, else coherent: what the host reads after a copy. */
static const VkMemoryPropertyFlags k_host_prefs[] = {
    VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_CACHED_BIT,
    VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT,
};

/* A shared buffer: mapped device memory, or device memory and a staging copy of its own. */
static fb_result make_shared(vkc_context *ctx, vkc_buffer *b, VkMemoryPropertyFlags *got)
{
    fb_result rc = FB_OK;
    if (ctx->direct_map) {
        const VkMemoryPropertyFlags prefs[] = {
            VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT | VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT |
                VK_MEMORY_PROPERTY_HOST_CACHED_BIT,
            VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT | VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT,
            VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT,
        };
        rc = make_buffer(ctx, b->size, k_storage, prefs, 3, &b->buf, &b->mem, got);
        if (rc) return rc;
        VKC_CHECK(ctx->vk.vkMapMemory(ctx->device, b->mem, 0, VK_WHOLE_SIZE, 0, &b->map), out);
        advise_huge(b->map, b->size);
        return FB_OK;
    }
    const VkMemoryPropertyFlags dev_prefs[] = {VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, 0};
    rc = make_buffer(ctx, b->size, k_storage, dev_prefs, 2, &b->buf, &b->mem, got);
    if (rc) return rc;
    /* the staging buffer is the copy's destination after a job, and its source for an upload */
    rc = make_buffer(ctx, b->size, k_transfer, k_host_prefs, 2, &b->staging, &b->staging_mem, got);
    if (rc) return rc;
    VKC_CHECK(ctx->vk.vkMapMemory(ctx->device, b->staging_mem, 0, VK_WHOLE_SIZE, 0, &b->map), out);
out:
    return rc;
}

fb_result vkc_buffer_create(vkc_context *ctx, uint64_t size, vkc_buffer **out)
{
    return vkc_buffer_create_kind(ctx, size, VKC_BUFFER_SHARED, out);
}

fb_result vkc_buffer_create_kind(vkc_context *ctx, uint64_t size, vkc_buffer_kind kind, vkc_buffer **out)
{
    fb_result rc = FB_OK;
    uint64_t most = kind == VKC_BUFFER_HOST ? ctx->info.max_allocation : ctx->info.max_storage_buffer_range;
    if (size == 0 || size > most)
        return fb_fail(FB_ERR_INTERNAL, "vulkan: a %llu-byte %s buffer exceeds the device's %s (%llu)",
                       (unsigned long long)size, kind == VKC_BUFFER_HOST ? "host" : "storage",
                       kind == VKC_BUFFER_HOST ? "maxMemoryAllocationSize" : "maxStorageBufferRange",
                       (unsigned long long)most);
    vkc_buffer *b = calloc(1, sizeof *b);
    if (!b) return fb_fail(FB_ERR_NOMEM, "out of memory");
    b->size = size;
    b->kind = kind;
    VkMemoryPropertyFlags got = VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    if (kind == VKC_BUFFER_SHARED) {
        rc = make_shared(ctx, b, &got);
    } else if (kind == VKC_BUFFER_DEVICE) {
        const VkMemoryPropertyFlags dev_prefs[] = {VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, 0};
        rc = make_buffer(ctx, size, k_storage, dev_prefs, 2, &b->buf, &b->mem, &got);
        got |= VK_MEMORY_PROPERTY_HOST_COHERENT_BIT; /* never mapped: nothing to flush */
    } else {
        rc = make_buffer(ctx, size, k_transfer, k_host_prefs, 2, &b->buf, &b->mem, &got);
        if (!rc) VKC_CHECK(ctx->vk.vkMapMemory(ctx->device, b->mem, 0, VK_WHOLE_SIZE, 0, &b->map), fail);
    }
    if (rc) goto fail;
    b->coherent = (got & VK_MEMORY_PROPERTY_HOST_COHERENT_BIT) != 0;
    *out = b;
    return FB_OK;
fail:
    vkc_buffer_destroy(ctx, &b);
    return rc;
}

/* On a CPU device the buffer is host memory: ask for transparent huge pages on large ones, before
 * they are first touched. Random access over a 64 MiB histogram otherwise misses the TLB on nearly
 * every point. Only a hint: ignored where THP is off or the memory is not anonymous. */
static void advise_huge(void *p, uint64_t size)
{
#ifdef MADV_HUGEPAGE
    const uintptr_t huge = 2u << 20;
    if (size < 4 * huge) return;
    uintptr_t a = ((uintptr_t)p + huge - 1) & ~(huge - 1), e = ((uintptr_t)p + size) & ~(huge - 1);
    if (e > a) madvise((void *)a, e - a, MADV_HUGEPAGE);
#else
    (void)p, (void)size;
#endif
}

void vkc_buffer_destroy(vkc_context *ctx, vkc_buffer **pb)
{
    if (!pb || !*pb) return;
    vkc_buffer *b = *pb;
    if (b->staging) ctx->vk.vkDestroyBuffer(ctx->device, b->staging, NULL);
    if (b->staging_mem) ctx->vk.vkFreeMemory(ctx->device, b->staging_mem, NULL);
    if (b->buf) ctx->vk.vkDestroyBuffer(ctx->device, b->buf, NULL);
    if (b->mem) ctx->vk.vkFreeMemory(ctx->device, b->mem, NULL); /* freeing unmaps implicitly */
    memset(b, 0, sizeof *b);
    free(b);
    *pb = NULL;
}

/* A device buffer's contents, through a host buffer of the same size and a job of one copy. */
static fb_result upload_device(vkc_context *ctx, vkc_buffer *b, const void *data, uint64_t size)
{
    vkc_buffer *host = NULL;
    vkc_job *job = NULL;
    fb_result rc = vkc_buffer_create_kind(ctx, size, VKC_BUFFER_HOST, &host);
    if (!rc) rc = vkc_buffer_upload(ctx, host, data, size);
    if (!rc) rc = vkc_job_create(ctx, NULL, &job);
    if (!rc)
        rc = vkc_job_run(ctx, job,
                         &(vkc_submit){.copies = &(vkc_copy){.src = host, .dst = b, .size = size}, .ncopies = 1});
    if (!rc) rc = vkc_job_wait(ctx, job, NULL);
    vkc_job_destroy(ctx, &job);
    vkc_buffer_destroy(ctx, &host);
    return rc;
}

fb_result vkc_buffer_upload(vkc_context *ctx, vkc_buffer *b, const void *data, uint64_t size)
{
    fb_result rc = FB_OK;
    if (NEVER(size > b->size) || NEVER(size == 0))
        return fb_fail(FB_ERR_INTERNAL, "vulkan: an upload of %llu bytes into a buffer of %llu",
                       (unsigned long long)size, (unsigned long long)b->size);
    if (b->kind == VKC_BUFFER_DEVICE) return upload_device(ctx, b, data, size);
    memcpy(b->map, data, size);
    if (!b->coherent) {
        VkMappedMemoryRange r = {
            .sType = VK_STRUCTURE_TYPE_MAPPED_MEMORY_RANGE,
            .memory = b->staging ? b->staging_mem : b->mem,
            .size = VK_WHOLE_SIZE,
        };
        VKC_CHECK(ctx->vk.vkFlushMappedMemoryRanges(ctx->device, 1, &r), out);
    }
    b->upload_pending = b->staging != VK_NULL_HANDLE;
out:
    return rc;
}

const void *vkc_buffer_data(const vkc_buffer *b)
{
    return b->map;
}

uint64_t vkc_buffer_size(const vkc_buffer *b)
{
    return b->size;
}

/* ---- jobs ----------------------------------------------------------------------------------- */

#define VKC_MAX_COPIES 128 /* copies a job records (a piece's planes: one each) */

struct vkc_job {
    vkc_pipeline *pipe; /* NULL: copies alone */
    VkCommandBuffer cmd;
    VkFence fence;
    VkDescriptorPool dpool;
    VkDescriptorSet set;
    VkQueryPool queries; /* 0, 1: around the dispatch; 2, 3: around the copies */
    bool in_flight;
    bool dispatched, copied; /* what the job in flight records */
    double copy_seconds;
    vkc_buffer *bufs[8];
    uint32_t nbufs;
    vkc_buffer *dsts[VKC_MAX_COPIES]; /* the copies' host buffers, invalidated after the wait */
    uint32_t ndsts;
};

static fb_result make_descriptors(vkc_context *ctx, vkc_job *job, const vkc_pipeline *pipe)
{
    fb_result rc = FB_OK;
    uint32_t nuni = 0;
    for (uint32_t i = 0; i < pipe->buffers; i++) nuni += (pipe->uniform >> i) & 1u;
    VkDescriptorPoolSize ps[2] = {
        {.type = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, .descriptorCount = pipe->buffers - nuni},
        {.type = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, .descriptorCount = nuni},
    };
    VkDescriptorPoolCreateInfo dpci = {
        .sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO,
        .maxSets = 1,
        .poolSizeCount = nuni == 0 || nuni == pipe->buffers ? 1u : 2u,
        .pPoolSizes = nuni == pipe->buffers ? &ps[1] : ps,
    };
    VKC_CHECK(ctx->vk.vkCreateDescriptorPool(ctx->device, &dpci, NULL, &job->dpool), out);
    VkDescriptorSetAllocateInfo dsai = {
        .sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO,
        .descriptorPool = job->dpool,
        .descriptorSetCount = 1,
        .pSetLayouts = &pipe->dsl,
    };
    VKC_CHECK(ctx->vk.vkAllocateDescriptorSets(ctx->device, &dsai, &job->set), out);
out:
    return rc;
}

fb_result vkc_job_create(vkc_context *ctx, vkc_pipeline *pipe, vkc_job **out)
{
    fb_result rc = FB_OK;
    vkc_job *job = calloc(1, sizeof *job);
    if (!job) return fb_fail(FB_ERR_NOMEM, "out of memory");
    job->pipe = pipe;
    job->copy_seconds = -1;
    VkCommandBufferAllocateInfo cbai = {
        .sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO,
        .commandPool = ctx->pool,
        .level = VK_COMMAND_BUFFER_LEVEL_PRIMARY,
        .commandBufferCount = 1,
    };
    VKC_CHECK(ctx->vk.vkAllocateCommandBuffers(ctx->device, &cbai, &job->cmd), fail);
    VkFenceCreateInfo fci = {.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    VKC_CHECK(ctx->vk.vkCreateFence(ctx->device, &fci, NULL, &job->fence), fail);
    if (pipe && pipe->buffers && (rc = make_descriptors(ctx, job, pipe))) goto fail;
    if (ctx->timestamps) {
        VkQueryPoolCreateInfo qpci = {
            .sType = VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO,
            .queryType = VK_QUERY_TYPE_TIMESTAMP,
            .queryCount = 4,
        };
        VKC_CHECK(ctx->vk.vkCreateQueryPool(ctx->device, &qpci, NULL, &job->queries), fail);
    }
    *out = job;
    return FB_OK;
fail:
    vkc_job_destroy(ctx, &job);
    return rc;
}

void vkc_job_destroy(vkc_context *ctx, vkc_job **pjob)
{
    if (!pjob || !*pjob) return;
    vkc_job *job = *pjob;
    if (job->in_flight) ctx->vk.vkWaitForFences(ctx->device, 1, &job->fence, VK_TRUE, UINT64_MAX);
    if (job->queries) ctx->vk.vkDestroyQueryPool(ctx->device, job->queries, NULL);
    if (job->dpool) ctx->vk.vkDestroyDescriptorPool(ctx->device, job->dpool, NULL);
    if (job->fence) ctx->vk.vkDestroyFence(ctx->device, job->fence, NULL);
    if (job->cmd) ctx->vk.vkFreeCommandBuffers(ctx->device, ctx->pool, 1, &job->cmd);
    memset(job, 0, sizeof *job);
    free(job);
    *pjob = NULL;
}

static void barrier(vkc_context *ctx, VkCommandBuffer cmd, VkPipelineStageFlags src, VkAccessFlags src_access,
                    VkPipelineStageFlags dst, VkAccessFlags dst_access)
{
    VkMemoryBarrier mb = {
        .sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER, .srcAccessMask = src_access, .dstAccessMask = dst_access};
    ctx->vk.vkCmdPipelineBarrier(cmd, src, dst, 0, 1, &mb, 0, NULL, 0, NULL);
}

/* The dispatch: host data for staged inputs copied in first, then the shader between timestamps 0
 * and 1. */
static void record_dispatch(vkc_context *ctx, vkc_job *job, const vkc_submit *w)
{
    const vkc_pipeline *p = job->pipe;
    VkDescriptorBufferInfo infos[8];
    VkWriteDescriptorSet writes[8];
    for (uint32_t i = 0; i < w->nbufs; i++) {
        infos[i] = (VkDescriptorBufferInfo){.buffer = w->bufs[i]->buf, .offset = 0, .range = VK_WHOLE_SIZE};
        writes[i] = (VkWriteDescriptorSet){
            .sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET,
            .dstSet = job->set,
            .dstBinding = i,
            .descriptorCount = 1,
            .descriptorType = desc_type(p->uniform, i),
            .pBufferInfo = &infos[i],
        };
    }
    /* Legal here: the set is not in use by any pending command buffer (the job is not in flight). */
    if (w->nbufs) ctx->vk.vkUpdateDescriptorSets(ctx->device, w->nbufs, writes, 0, NULL);
    bool uploads = false;
    for (uint32_t i = 0; i < w->nbufs; i++) {
        if (!w->bufs[i]->upload_pending) continue;
        VkBufferCopy region = {.size = w->bufs[i]->size};
        ctx->vk.vkCmdCopyBuffer(job->cmd, w->bufs[i]->staging, w->bufs[i]->buf, 1, &region);
        w->bufs[i]->upload_pending = false;
        uploads = true;
    }
    /* The shader may read an uploaded buffer (storage or uniform) and write it too (erosion's
     * heights, water and flux are uploaded, then updated in place): the copy's writes are made
     * visible to both, or the dispatch's writes race the copy's (SYNC-HAZARD-WRITE-AFTER-WRITE). */
    if (uploads)
        barrier(ctx, job->cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_UNIFORM_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
    if (job->queries) ctx->vk.vkCmdWriteTimestamp(job->cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, job->queries, 0);
    ctx->vk.vkCmdBindPipeline(job->cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p->pipeline);
    if (w->nbufs)
        ctx->vk.vkCmdBindDescriptorSets(job->cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p->layout, 0, 1, &job->set, 0, NULL);
    if (p->push_size)
        ctx->vk.vkCmdPushConstants(job->cmd, p->layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, p->push_size, w->push);
    ctx->vk.vkCmdDispatch(job->cmd, w->groups[0], w->groups[1], w->groups[2]);
    if (job->queries) ctx->vk.vkCmdWriteTimestamp(job->cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, job->queries, 1);
}

/* The copies after the dispatch (the shared buffers' own staging copies, then the caller's), between
 * timestamps 2 and 3, and the barrier that makes every write visible to the host. */
static void record_copies(vkc_context *ctx, vkc_job *job, const vkc_submit *w)
{
    bool staged = false;
    for (uint32_t i = 0; i < w->nbufs && job->dispatched; i++) staged = staged || w->bufs[i]->staging;
    job->copied = staged || w->ncopies > 0;
    if (job->copied) {
        if (job->dispatched)
            barrier(ctx, job->cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                    VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_READ_BIT);
        if (job->queries) ctx->vk.vkCmdWriteTimestamp(job->cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, job->queries, 2);
        for (uint32_t i = 0; i < w->nbufs && staged; i++) {
            if (!w->bufs[i]->staging) continue;
            VkBufferCopy region = {.size = w->bufs[i]->size};
            ctx->vk.vkCmdCopyBuffer(job->cmd, w->bufs[i]->buf, w->bufs[i]->staging, 1, &region);
        }
        for (uint32_t i = 0; i < w->ncopies; i++) {
            const vkc_copy *c = &w->copies[i];
            VkBufferCopy region = {.srcOffset = c->src_offset, .dstOffset = c->dst_offset, .size = c->size};
            ctx->vk.vkCmdCopyBuffer(job->cmd, c->src->buf, c->dst->buf, 1, &region);
        }
        if (job->queries) ctx->vk.vkCmdWriteTimestamp(job->cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, job->queries, 3);
    }
    /* Make shader (or copy) writes available to host reads after the fence: "a fence signal
     * operation does not make writes available to the host" without a host-access barrier. */
    barrier(ctx, job->cmd, job->copied ? VK_PIPELINE_STAGE_TRANSFER_BIT : VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
            job->copied ? VK_ACCESS_TRANSFER_WRITE_BIT : VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_HOST_BIT,
            VK_ACCESS_HOST_READ_BIT);
}

fb_result vkc_job_run(vkc_context *ctx, vkc_job *job, const vkc_submit *w)
{
    fb_result rc = FB_OK;
    bool dispatch = w->groups[0] && w->groups[1] && w->groups[2];
    if (NEVER(job->in_flight) || NEVER(dispatch && (!job->pipe || w->nbufs != job->pipe->buffers)) ||
        NEVER(w->nbufs > 8) || NEVER(w->ncopies > VKC_MAX_COPIES))
        return fb_fail(FB_ERR_INTERNAL, "vulkan: job submitted while in flight, or with a wrong buffer count");
    job->nbufs = dispatch ? w->nbufs : 0;
    for (uint32_t i = 0; i < job->nbufs; i++) job->bufs[i] = w->bufs[i];
    job->ndsts = 0;
    for (uint32_t i = 0; i < w->ncopies; i++) {
        bool seen = false;
        for (uint32_t k = 0; k < job->ndsts; k++) seen = seen || job->dsts[k] == w->copies[i].dst;
        if (!seen && w->copies[i].dst->map) job->dsts[job->ndsts++] = w->copies[i].dst;
    }
    job->dispatched = dispatch;
    VKC_CHECK(ctx->vk.vkResetCommandBuffer(job->cmd, 0), out);
    VkCommandBufferBeginInfo cbbi = {
        .sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO,
        .flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT,
    };
    VKC_CHECK(ctx->vk.vkBeginCommandBuffer(job->cmd, &cbbi), out);
    if (job->queries) ctx->vk.vkCmdResetQueryPool(job->cmd, job->queries, 0, 4);
    if (dispatch) record_dispatch(ctx, job, w);
    record_copies(ctx, job, w);
    VKC_CHECK(ctx->vk.vkEndCommandBuffer(job->cmd), out);
    VKC_CHECK(ctx->vk.vkResetFences(ctx->device, 1, &job->fence), out);
    VkSubmitInfo si = {
        .sType = VK_STRUCTURE_TYPE_SUBMIT_INFO,
        .commandBufferCount = 1,
        .pCommandBuffers = &job->cmd,
    };
    VKC_CHECK(ctx->vk.vkQueueSubmit(ctx->queue, 1, &si, job->fence), out);
    job->in_flight = true;
out:
    return rc;
}

fb_result vkc_job_submit(vkc_context *ctx, vkc_job *job, vkc_buffer *const *bufs, uint32_t nbufs, const void *push,
                         const uint32_t groups[3])
{
    return vkc_job_run(
        ctx, job,
        &(vkc_submit){.bufs = bufs, .nbufs = nbufs, .push = push, .groups = {groups[0], groups[1], groups[2]}});
}

static fb_result invalidate(vkc_context *ctx, const vkc_buffer *b)
{
    fb_result rc = FB_OK;
    if (b->coherent || !b->map) return FB_OK;
    VkMappedMemoryRange r = {
        .sType = VK_STRUCTURE_TYPE_MAPPED_MEMORY_RANGE,
        .memory = b->staging ? b->staging_mem : b->mem,
        .offset = 0,
        .size = VK_WHOLE_SIZE,
    };
    VKC_CHECK(ctx->vk.vkInvalidateMappedMemoryRanges(ctx->device, 1, &r), out);
out:
    return rc;
}

fb_result vkc_job_wait(vkc_context *ctx, vkc_job *job, double *gpu_seconds)
{
    fb_result rc = FB_OK;
    if (gpu_seconds) *gpu_seconds = -1.0;
    if (!job->in_flight) return FB_OK;
    VKC_CHECK(ctx->vk.vkWaitForFences(ctx->device, 1, &job->fence, VK_TRUE, UINT64_MAX), out);
    job->in_flight = false;
    for (uint32_t i = 0; i < job->nbufs && !rc; i++) rc = invalidate(ctx, job->bufs[i]);
    for (uint32_t i = 0; i < job->ndsts && !rc; i++) rc = invalidate(ctx, job->dsts[i]);
    if (rc) goto out;
    job->copy_seconds = -1;
    /* only the queries this job wrote: waiting on one never written would not return */
    double tick = (double)ctx->timestamp_period * 1e-9;
    uint64_t ts[4];
    if (job->queries && job->dispatched && gpu_seconds) {
        VKC_CHECK(ctx->vk.vkGetQueryPoolResults(ctx->device, job->queries, 0, 2, 2 * sizeof ts[0], ts, sizeof ts[0],
                                                VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT),
                  out);
        *gpu_seconds = (double)(ts[1] - ts[0]) * tick;
    }
    if (job->queries && job->copied) {
        VKC_CHECK(ctx->vk.vkGetQueryPoolResults(ctx->device, job->queries, 2, 2, 2 * sizeof ts[0], ts + 2, sizeof ts[0],
                                                VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT),
                  out);
        job->copy_seconds = (double)(ts[3] - ts[2]) * tick;
    }
out:
    return rc;
}

double vkc_job_copy_seconds(const vkc_job *job)
{
    return job->copy_seconds;
}

fb_result vkc_copy_timed(vkc_context *ctx, vkc_buffer *src, vkc_buffer *dst, uint64_t size, double *gpu_seconds)
{
    vkc_job *job = NULL;
    *gpu_seconds = -1;
    fb_result rc = vkc_job_create(ctx, NULL, &job);
    if (!rc)
        rc = vkc_job_run(ctx, job,
                         &(vkc_submit){.copies = &(vkc_copy){.src = src, .dst = dst, .size = size}, .ncopies = 1});
    if (!rc) rc = vkc_job_wait(ctx, job, NULL);
    if (!rc) *gpu_seconds = vkc_job_copy_seconds(job);
    vkc_job_destroy(ctx, &job);
    return rc;
}
