/*
 * The Vulkan context's insides, shared by its two files: vkc.c (the loader, instance, device,
 * pipeline cache) and vkc_work.c (pipelines, buffers, jobs). Nothing outside host/io/vkc*.c
 * includes this header.
 */
#ifndef FB_VKC_PRIVATE_H
#define FB_VKC_PRIVATE_H

#define VK_NO_PROTOTYPES
#include "vkc.h"

#include <vulkan/vulkan.h>

/* ---- loader --------------------------------------------------------------------------------- */

/* Every entry point fractalbake uses. Global ones are resolved with a NULL instance. */
#define VKC_GLOBAL_FNS(X)                                                                                              \
    X(vkCreateInstance)                                                                                                \
    X(vkEnumerateInstanceLayerProperties)                                                                              \
    X(vkEnumerateInstanceExtensionProperties)

#define VKC_INSTANCE_FNS(X)                                                                                            \
    X(vkDestroyInstance)                                                                                               \
    X(vkEnumeratePhysicalDevices)                                                                                      \
    X(vkGetPhysicalDeviceProperties)                                                                                   \
    X(vkGetPhysicalDeviceProperties2)                                                                                  \
    X(vkGetPhysicalDeviceFeatures2)                                                                                    \
    X(vkEnumerateDeviceExtensionProperties)                                                                            \
    X(vkGetPhysicalDeviceMemoryProperties)                                                                             \
    X(vkGetPhysicalDeviceQueueFamilyProperties)                                                                        \
    X(vkCreateDevice)                                                                                                  \
    X(vkGetDeviceProcAddr)                                                                                             \
    X(vkCreateDebugUtilsMessengerEXT)                                                                                  \
    X(vkDestroyDebugUtilsMessengerEXT)

#define VKC_DEVICE_FNS(X)                                                                                              \
    X(vkDestroyDevice)                                                                                                 \
    X(vkGetDeviceQueue)                                                                                                \
    X(vkDeviceWaitIdle)                                                                                                \
    X(vkCreateCommandPool)                                                                                             \
    X(vkDestroyCommandPool)                                                                                            \
    X(vkAllocateCommandBuffers)                                                                                        \
    X(vkFreeCommandBuffers)                                                                                            \
    X(vkBeginCommandBuffer)                                                                                            \
    X(vkEndCommandBuffer)                                                                                              \
    X(vkResetCommandBuffer)                                                                                            \
    X(vkQueueSubmit)                                                                                                   \
    X(vkCreateFence)                                                                                                   \
    X(vkDestroyFence)                                                                                                  \
    X(vkWaitForFences)                                                                                                 \
    X(vkResetFences)                                                                                                   \
    X(vkCreateBuffer)                                                                                                  \
    X(vkDestroyBuffer)                                                                                                 \
    X(vkGetBufferMemoryRequirements)                                                                                   \
    X(vkAllocateMemory)                                                                                                \
    X(vkFreeMemory)                                                                                                    \
    X(vkBindBufferMemory)                                                                                              \
    X(vkMapMemory)                                                                                                     \
    X(vkUnmapMemory)                                                                                                   \
    X(vkInvalidateMappedMemoryRanges)                                                                                  \
    X(vkFlushMappedMemoryRanges)                                                                                       \
    X(vkCreateShaderModule)                                                                                            \
    X(vkDestroyShaderModule)                                                                                           \
    X(vkCreateDescriptorSetLayout)                                                                                     \
    X(vkDestroyDescriptorSetLayout)                                                                                    \
    X(vkCreatePipelineLayout)                                                                                          \
    X(vkDestroyPipelineLayout)                                                                                         \
    X(vkCreateComputePipelines)                                                                                        \
    X(vkDestroyPipeline)                                                                                               \
    X(vkCreatePipelineCache)                                                                                           \
    X(vkDestroyPipelineCache)                                                                                          \
    X(vkGetPipelineCacheData)                                                                                          \
    X(vkCreateDescriptorPool)                                                                                          \
    X(vkDestroyDescriptorPool)                                                                                         \
    X(vkAllocateDescriptorSets)                                                                                        \
    X(vkUpdateDescriptorSets)                                                                                          \
    X(vkCreateQueryPool)                                                                                               \
    X(vkDestroyQueryPool)                                                                                              \
    X(vkGetQueryPoolResults)                                                                                           \
    X(vkCmdResetQueryPool)                                                                                             \
    X(vkCmdWriteTimestamp)                                                                                             \
    X(vkCmdBindPipeline)                                                                                               \
    X(vkCmdBindDescriptorSets)                                                                                         \
    X(vkCmdPushConstants)                                                                                              \
    X(vkCmdDispatch)                                                                                                   \
    X(vkCmdPipelineBarrier)                                                                                            \
    X(vkCmdCopyBuffer)

#define VKC_DECLARE(fn) PFN_##fn fn;
typedef struct vkc_fns {
    PFN_vkGetInstanceProcAddr vkGetInstanceProcAddr;
    VKC_GLOBAL_FNS(VKC_DECLARE)
    VKC_INSTANCE_FNS(VKC_DECLARE)
    VKC_DEVICE_FNS(VKC_DECLARE)
} vkc_fns;
#undef VKC_DECLARE

/* "VK_ERROR_DEVICE_LOST": a VkResult's name, for messages. */
const char *vkc_result_name(VkResult r);

/* The one check for Vulkan calls: logs the call text, the VkResult name, file and line, and jumps
 * to the function's unwind label with `rc` set. */
#define VKC_CHECK(call, label)                                                                                         \
    do {                                                                                                               \
        VkResult vkc_r_ = (call);                                                                                      \
        if (vkc_r_ != VK_SUCCESS) {                                                                                    \
            rc = fb_fail(vkc_r_ == VK_ERROR_OUT_OF_HOST_MEMORY || vkc_r_ == VK_ERROR_OUT_OF_DEVICE_MEMORY              \
                             ? FB_ERR_NOMEM                                                                            \
                             : FB_ERR_VULKAN,                                                                          \
                         "vulkan: %s failed: %s (%s:%d)", #call, vkc_result_name(vkc_r_), __FILE__, __LINE__);         \
            goto label;                                                                                                \
        }                                                                                                              \
    } while (0)
/* ---- context -------------------------------------------------------------------------------- */

struct vkc_context {
    vkc_fns vk; /* this context's entry points (Monado's vk_bundle): two contexts share nothing */
    VkInstance instance;
    VkDebugUtilsMessengerEXT messenger;
    VkPhysicalDevice phys;
    VkDevice device;
    VkQueue queue;
    uint32_t queue_family;
    VkCommandPool pool;
    VkPipelineCache cache;
    size_t cache_loaded_size;
    char cache_path[1024];
    VkPhysicalDeviceMemoryProperties mem;
    vkc_device_info info;
    bool direct_map; /* storage memory is host-visible and cheap to read: no staging */
    bool timestamps;
    float timestamp_period;
    bool validation;
    uint32_t validation_messages;
    struct vkc_pipeline *pipes; /* every pipeline made, for reuse (freed with the context) */
};

/* Pipelines are kept by the context and reused: a compute pipeline's compilation is a large share
 * of a small bake on lavapipe (0.1 to 0.3 s for the Julia shader), and lavapipe's VkPipelineCache
 * does not keep compiled code. The key is the whole description (the SPIR-V by address: it is
 * embedded in the binary). */
struct vkc_pipeline {
    VkDescriptorSetLayout dsl;
    VkPipelineLayout layout;
    VkPipeline pipeline;
    uint32_t push_size;
    uint32_t buffers;
    uint32_t uniform; /* bit i: binding i is a uniform buffer */
    const uint32_t *spv;
    size_t spv_size;
    uint32_t spec[8], nspec;
    struct vkc_pipeline *next;
};
/* Frees a pipeline the context kept (vkc_work.c). */
void vkc_pipeline_free(vkc_context *ctx, vkc_pipeline *p);

#endif
