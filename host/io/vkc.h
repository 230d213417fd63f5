/*
 * vkc: the Vulkan compute context. The only module that talks to Vulkan.
 *
 * The loader (libvulkan.so.1) is opened at run time, so that fractalbake runs its native backend
 * on a machine with no Vulkan at all. One instance, one device, one compute queue. Buffers are of
 * three kinds (vkc_buffer_kind): shared storage buffers the host reads after a job (device memory
 * mapped directly where the device shares memory with the host, a CPU or integrated device such as
 * lavapipe; otherwise device-local memory copied to a staging buffer of its own inside every job),
 * device-local storage buffers the host never maps, and host-cached buffers that a job's copies
 * fill (the staging ring of a bake on a discrete GPU). A job is one submission: a dispatch, then
 * copies between buffers, with timestamps around either.
 */
#ifndef FB_VKC_H
#define FB_VKC_H

#include "fb.h"

#include <stdbool.h>
#include <stddef.h>

typedef struct vkc_context vkc_context;
typedef struct vkc_pipeline vkc_pipeline;
typedef struct vkc_buffer vkc_buffer;
typedef struct vkc_job vkc_job;

typedef struct vkc_device_info {
    char name[256];
    const char *type; /* "discrete", "integrated", "virtual", "cpu", "other" */
    char driver[256];
    uint64_t memory; /* bytes of device-local heaps */
    uint32_t subgroup_size;
    uint32_t api_version;
    uint64_t max_storage_buffer_range;
    uint64_t max_uniform_buffer_range;
    uint32_t max_workgroup_count[3]; /* maxComputeWorkGroupCount */
    uint64_t max_allocation;         /* maxMemoryAllocationSize: the largest buffer of any kind */
    uint64_t heap;                   /* the largest device-local heap, bytes */
    /* The device's memory is the host's (a CPU or integrated device): what it allocates counts against
     * the host's memory. */
    bool unified;
    /* Shared buffers live in device-local memory and reach the host through staging copies (a
     * discrete GPU, or vkc_desc.staging): a bake then reads its pieces back through a ring of
     * host-cached buffers (VKC_BUFFER_DEVICE and VKC_BUFFER_HOST) while the device computes. */
    bool staging;
    bool int64_atomics; /* 64-bit storage-buffer atomics enabled (VK_KHR_shader_atomic_int64); FB_VK_NO_INT64=1: off */
    bool float64;       /* shaderFloat64 enabled (double arithmetic in shaders); FB_VK_NO_FLOAT64=1: off */
    /* Exact arithmetic (kernels/exact.h, docs/usage.md#determinism): the float-controls modes the device
     * lets a shader declare (VK_KHR_shader_float_controls), for 32- and 64-bit floats, and whether its
     * own division and square root are known to be correctly rounded (lavapipe: LLVM's IEEE
     * instructions; elsewhere the kx_ helpers correct the device's estimate exactly). */
    bool float_controls; /* the extension is there and enabled */
    bool rte32, denorm32, szinp32, rte64, denorm64, szinp64;
    bool exact_native;
    bool chosen;
} vkc_device_info;

/* What a context is made with (zero: the defaults). The command line fills it from its flags and the
 * environment (host/cli/env.c: FB_VK_VALIDATION, FB_VK_STAGING, FB_VK_NO_INT64, FB_VK_NO_FLOAT64,
 * FB_NO_PIPELINE_CACHE, XDG_CACHE_HOME); nothing here reads the environment. */
typedef struct vkc_desc {
    const char *device; /* NULL: best by type; all digits: an index; else a name substring */
    bool validation;    /* enable VK_LAYER_KHRONOS_validation */
    bool no_pipeline_cache;
    const char *cache_dir; /* the pipeline cache's folder (made when missing); NULL: none on disk */
    bool staging;          /* device-local memory and staging copies even where memory is shared */
    bool no_int64;         /* as if the device had no 64-bit buffer atomics */
    bool no_float64;       /* as if the device had no shaderFloat64 */
    bool portable;         /* the kx_ helpers' portable code even where the device's division is exact */
} vkc_desc;

/* One line on a device's arithmetic: the float-controls modes its shaders declare and how they
 * divide ("round to nearest, denormals kept, NaN kept; division: the device's own (exact)"). */
void vkc_arith_describe(const vkc_device_info *info, char *buf, size_t size);

/* Lists the Vulkan devices and marks the one `device_sel` (as in vkc_desc.device) would choose.
 * *out is malloc'd; the caller frees it. FB_ERR_NODEVICE when there is no loader or no device. */
fb_result vkc_enumerate(const char *device_sel, vkc_device_info **out, int *count);

/* Creates the context. On failure *out is untouched and the logger has one line. */
fb_result vkc_create(const vkc_desc *desc, vkc_context **out);

/* Destroys the context (saving the pipeline cache). Null-safe; sets *ctx to NULL. */
void vkc_destroy(vkc_context **ctx);

const vkc_device_info *vkc_info(const vkc_context *ctx);

/* Number of messages VK_LAYER_KHRONOS_validation has sent so far (0 when it is off). */
uint32_t vkc_validation_messages(const vkc_context *ctx);

/* True when the validation layer was requested and is active. */
bool vkc_validation_enabled(const vkc_context *ctx);

typedef struct vkc_pipeline_desc {
    const uint32_t *spv;  /* SPIR-V words, embedded at build time */
    size_t spv_size;      /* bytes */
    uint32_t push_size;   /* bytes of push constants (<= 128) */
    uint32_t buffers;     /* storage buffers at set 0, bindings 0..buffers-1 */
    uint32_t uniform;     /* bit i: binding i is a uniform buffer instead (read-only, at most the device's
                             maxUniformBufferRange bytes; on lavapipe a read at an index that differs by
                             lane is a gather, where a storage buffer's is a loop over the lanes) */
    const uint32_t *spec; /* specialization constants: constant_id i takes spec[i] (32-bit each) */
    uint32_t nspec;
    const char *name; /* for messages */
} vkc_pipeline_desc;

#define FB_SPV(arr) .spv = (arr), .spv_size = sizeof(arr)

/* A pipeline for the description: made once per context and then reused (the context owns it, and
 * frees it in vkc_destroy). vkc_pipeline_destroy gives the handle back and sets it to NULL. */
fb_result vkc_pipeline_create(vkc_context *ctx, const vkc_pipeline_desc *desc, vkc_pipeline **out);
void vkc_pipeline_destroy(vkc_context *ctx, vkc_pipeline **p);

/* What a buffer is for. */
typedef enum vkc_buffer_kind {
    /* A storage buffer whose contents the host reads after a job completes and may write before one
     * (vkc_buffer_upload): mapped directly where the device shares memory with the host, else
     * device-local with a host-cached staging copy of its own, copied inside every job that binds it. */
    VKC_BUFFER_SHARED = 0,
    /* A device-local storage buffer the host never maps: written and read by shaders, read back by a
     * job's copies (vkc_submit.copies) into a host buffer. At most maxStorageBufferRange bytes. */
    VKC_BUFFER_DEVICE,
    /* Host-cached memory, mapped, the destination (or source) of a job's copies: a staging ring's
     * slot. Never bound to a shader; up to max_allocation bytes. */
    VKC_BUFFER_HOST,
} vkc_buffer_kind;

/* A VKC_BUFFER_SHARED buffer of `size` bytes (at most maxStorageBufferRange). */
fb_result vkc_buffer_create(vkc_context *ctx, uint64_t size, vkc_buffer **out);
/* A buffer of `size` bytes of the given kind. */
fb_result vkc_buffer_create_kind(vkc_context *ctx, uint64_t size, vkc_buffer_kind kind, vkc_buffer **out);
void vkc_buffer_destroy(vkc_context *ctx, vkc_buffer **b);

/* Writes `size` bytes of input for the shader: into a shared buffer directly where it is
 * host-visible, else into its staging buffer, copied to the device buffer at the start of the next
 * submitted job that binds it; into a host buffer now; into a device buffer now, through a transient
 * host buffer and a copy (waited for). */
fb_result vkc_buffer_upload(vkc_context *ctx, vkc_buffer *b, const void *data, uint64_t size);

/* Host pointer to a shared or host buffer's contents, valid after vkc_job_wait of a job that wrote
 * it; NULL for a device buffer. */
const void *vkc_buffer_data(const vkc_buffer *b);
uint64_t vkc_buffer_size(const vkc_buffer *b);

/* A reusable submission: one command buffer, fence, descriptor set and timestamps. pipe NULL: a job
 * of copies alone. */
fb_result vkc_job_create(vkc_context *ctx, vkc_pipeline *pipe, vkc_job **out);
void vkc_job_destroy(vkc_context *ctx, vkc_job **job);

/* A copy of `size` bytes between two buffers (device to host, device to device, host to device). */
typedef struct vkc_copy {
    vkc_buffer *src, *dst;
    uint64_t src_offset, dst_offset, size;
} vkc_copy;

/* What a job records: a dispatch of `groups` workgroups (0 in any: none) with `push` constants over
 * the pipeline's buffers `bufs`, then `copies` in order, each reading what the dispatch wrote. */
typedef struct vkc_submit {
    vkc_buffer *const *bufs;
    uint32_t nbufs;
    const void *push;
    uint32_t groups[3];
    const vkc_copy *copies;
    uint32_t ncopies;
} vkc_submit;

/* Records and submits the job's work. The job must not be in flight. */
fb_result vkc_job_run(vkc_context *ctx, vkc_job *job, const vkc_submit *work);

/* vkc_job_run of one dispatch over `bufs` and no copies. */
fb_result vkc_job_submit(vkc_context *ctx, vkc_job *job, vkc_buffer *const *bufs, uint32_t nbufs, const void *push,
                         const uint32_t groups[3]);

/* Waits for the job; afterwards the data of its shared buffers and its copies' host buffers is
 * visible to the host. *gpu_seconds (optional) is the time between the dispatch's timestamps, or -1
 * where the queue has no timestamps (or the job had no dispatch). */
fb_result vkc_job_wait(vkc_context *ctx, vkc_job *job, double *gpu_seconds);

/* The device time of the last waited job's copies (all of them, from the timestamps around them), or
 * -1 where the queue has no timestamps or the job made no copies. */
double vkc_job_copy_seconds(const vkc_job *job);

/* Copies `size` bytes from src to dst (any kinds; offsets 0) in a submission of its own and waits:
 * *gpu_seconds is the copy's device time from timestamps (-1 where the queue has none). The
 * device's own memory bandwidth, for two device buffers: 2 * size / *gpu_seconds. */
fb_result vkc_copy_timed(vkc_context *ctx, vkc_buffer *src, vkc_buffer *dst, uint64_t size, double *gpu_seconds);

#endif
