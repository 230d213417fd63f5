#define _GNU_SOURCE /* dl_iterate_phdr, in sanitizer builds */
/*
 * The Vulkan compute context. See vkc.h for the model.
 */
#define VK_NO_PROTOTYPES
#include "vkc.h"

#include <vulkan/vulkan.h>

#include <ctype.h>
#include <dlfcn.h>
#include <link.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

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

static const char *vk_result_name(VkResult r)
{
    switch (r) {
#define R(x)                                                                                                           \
    case x:                                                                                                            \
        return #x;
        R(VK_SUCCESS)
        R(VK_NOT_READY)
        R(VK_TIMEOUT)
        R(VK_INCOMPLETE)
        R(VK_ERROR_OUT_OF_HOST_MEMORY)
        R(VK_ERROR_OUT_OF_DEVICE_MEMORY)
        R(VK_ERROR_INITIALIZATION_FAILED)
        R(VK_ERROR_DEVICE_LOST)
        R(VK_ERROR_MEMORY_MAP_FAILED)
        R(VK_ERROR_LAYER_NOT_PRESENT)
        R(VK_ERROR_EXTENSION_NOT_PRESENT)
        R(VK_ERROR_FEATURE_NOT_PRESENT)
        R(VK_ERROR_INCOMPATIBLE_DRIVER)
        R(VK_ERROR_TOO_MANY_OBJECTS)
        R(VK_ERROR_FORMAT_NOT_SUPPORTED)
        R(VK_ERROR_FRAGMENTED_POOL)
        R(VK_ERROR_OUT_OF_POOL_MEMORY)
        R(VK_ERROR_INVALID_SHADER_NV)
#undef R
    default:
        return "VK_ERROR_UNKNOWN";
    }
}

/* The one check for Vulkan calls: logs the call text, the VkResult name, file and line, and jumps
 * to the function's unwind label with `rc` set. */
#define VKC_CHECK(call, label)                                                                                         \
    do {                                                                                                               \
        VkResult vkc_r_ = (call);                                                                                      \
        if (vkc_r_ != VK_SUCCESS) {                                                                                    \
            rc = fb_fail(vkc_r_ == VK_ERROR_OUT_OF_HOST_MEMORY || vkc_r_ == VK_ERROR_OUT_OF_DEVICE_MEMORY              \
                             ? FB_ERR_NOMEM                                                                            \
                             : FB_ERR_VULKAN,                                                                          \
                         "vulkan: %s failed: %s (%s:%d)", #call, vk_result_name(vkc_r_), __FILE__, __LINE__);          \
            goto label;                                                                                                \
        }                                                                                                              \
    } while (0)

static void *g_libvulkan;
static vkc_fns g_vk;

/* Opens the loader once per process. */
static fb_result load_loader(void)
{
    if (g_libvulkan) return FB_OK;
    const char *names[] = {"libvulkan.so.1", "libvulkan.so"};
    for (size_t i = 0; i < sizeof names / sizeof names[0] && !g_libvulkan; i++)
        g_libvulkan = dlopen(names[i], RTLD_NOW | RTLD_LOCAL);
    if (!g_libvulkan) return fb_fail(FB_ERR_NODEVICE, "vulkan: no Vulkan loader (libvulkan.so.1) on this machine");
    g_vk.vkGetInstanceProcAddr = (PFN_vkGetInstanceProcAddr)dlsym(g_libvulkan, "vkGetInstanceProcAddr");
    if (!g_vk.vkGetInstanceProcAddr) {
        dlclose(g_libvulkan);
        g_libvulkan = NULL;
        return fb_fail(FB_ERR_NODEVICE, "vulkan: the loader has no vkGetInstanceProcAddr");
    }
#define LOAD(fn) g_vk.fn = (PFN_##fn)g_vk.vkGetInstanceProcAddr(NULL, #fn);
    VKC_GLOBAL_FNS(LOAD)
#undef LOAD
    if (!g_vk.vkCreateInstance) return fb_fail(FB_ERR_NODEVICE, "vulkan: the loader has no vkCreateInstance");
    return FB_OK;
}

static void load_instance_fns(VkInstance inst)
{
#define LOAD(fn) g_vk.fn = (PFN_##fn)g_vk.vkGetInstanceProcAddr(inst, #fn);
    VKC_INSTANCE_FNS(LOAD)
#undef LOAD
}

static fb_result load_device_fns(VkDevice dev)
{
#define LOAD(fn)                                                                                                       \
    g_vk.fn = (PFN_##fn)g_vk.vkGetDeviceProcAddr(dev, #fn);                                                            \
    if (!g_vk.fn) return fb_fail(FB_ERR_VULKAN, "vulkan: the device has no %s", #fn);
    VKC_DEVICE_FNS(LOAD)
#undef LOAD
    return FB_OK;
}

/* ---- context -------------------------------------------------------------------------------- */

struct vkc_context {
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
    const uint32_t *spv;
    size_t spv_size;
    uint32_t spec[8], nspec;
    struct vkc_pipeline *next;
};

static void pipeline_free(vkc_context *ctx, vkc_pipeline *p)
{
    if (p->pipeline) g_vk.vkDestroyPipeline(ctx->device, p->pipeline, NULL);
    if (p->layout) g_vk.vkDestroyPipelineLayout(ctx->device, p->layout, NULL);
    if (p->dsl) g_vk.vkDestroyDescriptorSetLayout(ctx->device, p->dsl, NULL);
    memset(p, 0, sizeof *p);
    free(p);
}

static VKAPI_ATTR VkBool32 VKAPI_CALL debug_cb(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                               VkDebugUtilsMessageTypeFlagsEXT types,
                                               const VkDebugUtilsMessengerCallbackDataEXT *data, void *user)
{
    (void)types;
    vkc_context *ctx = user;
    if (severity & (VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT)) {
        ctx->validation_messages++;
        fb_log(FB_LOG_WARN, "vulkan validation: %s", data && data->pMessage ? data->pMessage : "(no message)");
    }
    return VK_FALSE;
}

static bool env_true(const char *name)
{
    const char *v = getenv(name);
    return v && *v && strcmp(v, "0") != 0;
}

static bool has_layer(const char *name)
{
    uint32_t n = 0;
    if (g_vk.vkEnumerateInstanceLayerProperties(&n, NULL) != VK_SUCCESS || n == 0) return false;
    VkLayerProperties *props = calloc(n, sizeof *props);
    if (!props) return false;
    bool found = false;
    if (g_vk.vkEnumerateInstanceLayerProperties(&n, props) == VK_SUCCESS)
        for (uint32_t i = 0; i < n; i++) found = found || strcmp(props[i].layerName, name) == 0;
    free(props);
    return found;
}

static bool has_instance_ext(const char *name)
{
    uint32_t n = 0;
    if (g_vk.vkEnumerateInstanceExtensionProperties(NULL, &n, NULL) != VK_SUCCESS || n == 0) return false;
    VkExtensionProperties *props = calloc(n, sizeof *props);
    if (!props) return false;
    bool found = false;
    if (g_vk.vkEnumerateInstanceExtensionProperties(NULL, &n, props) == VK_SUCCESS)
        for (uint32_t i = 0; i < n; i++) found = found || strcmp(props[i].extensionName, name) == 0;
    free(props);
    return found;
}

/* Creates the instance, with the validation layer and a debug messenger when asked. */

#if defined(__SANITIZE_ADDRESS__)

static int pin_one(struct dl_phdr_info *info, size_t size, void *user)
{
    (void)size, (void)user;
    if (info->dlpi_name && info->dlpi_name[0]) dlopen(info->dlpi_name, RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE);
    return 0;
}

/* AddressSanitizer builds only: the driver and the libraries it loaded (Mesa's, LLVM's) stay mapped
 * after the instance is destroyed. LeakSanitizer scans memory at exit; memory that a driver keeps
 * from its static data looks leaked once the loader has unloaded the driver (lavapipe on Mesa 22.3:
 * 128 bytes of LLVM's, whatever this program does), which would fail every test of a clean
 * program. Pinned, they are scanned and nothing of ours is hidden. */
static void pin_loaded_modules(void)
{
    dl_iterate_phdr(pin_one, NULL);
}
#else
static void pin_loaded_modules(void) {}
#endif

static fb_result create_instance(vkc_context *ctx, bool validation)
{
    fb_result rc = FB_OK;
    VkApplicationInfo app = {
        .sType = VK_STRUCTURE_TYPE_APPLICATION_INFO,
        .pApplicationName = "fractalbake",
        .applicationVersion = VK_MAKE_VERSION(0, 1, 0),
        .pEngineName = "fractalbake",
        .apiVersion = VK_API_VERSION_1_1,
    };
    const char *layers[1];
    const char *exts[2];
    uint32_t nlayers = 0, nexts = 0;
    if (validation) {
        if (!has_layer("VK_LAYER_KHRONOS_validation")) {
            fb_log(FB_LOG_WARN, "vulkan: validation requested but VK_LAYER_KHRONOS_validation is not installed");
            validation = false;
        } else {
            layers[nlayers++] = "VK_LAYER_KHRONOS_validation";
            if (has_instance_ext(VK_EXT_DEBUG_UTILS_EXTENSION_NAME)) exts[nexts++] = VK_EXT_DEBUG_UTILS_EXTENSION_NAME;
        }
    }
    VkDebugUtilsMessengerCreateInfoEXT dbg = {
        .sType = VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT,
        .messageSeverity =
            VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT,
        .messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                       VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT,
        .pfnUserCallback = debug_cb,
        .pUserData = ctx,
    };
    VkInstanceCreateInfo ici = {
        .sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO,
        /* Chained so that instance creation and destruction are validated too. */
        .pNext = (validation && nexts) ? &dbg : NULL,
        .pApplicationInfo = &app,
        .enabledLayerCount = nlayers,
        .ppEnabledLayerNames = layers,
        .enabledExtensionCount = nexts,
        .ppEnabledExtensionNames = exts,
    };
    VkResult vr = g_vk.vkCreateInstance(&ici, NULL, &ctx->instance);
    if (vr == VK_ERROR_INCOMPATIBLE_DRIVER)
        return fb_fail(FB_ERR_NODEVICE, "vulkan: no Vulkan 1.1 driver found (vkCreateInstance: %s)",
                       vk_result_name(vr));
    VKC_CHECK(vr, out);
    pin_loaded_modules();
    load_instance_fns(ctx->instance);
    ctx->validation = validation;
    if (validation && nexts && g_vk.vkCreateDebugUtilsMessengerEXT)
        VKC_CHECK(g_vk.vkCreateDebugUtilsMessengerEXT(ctx->instance, &dbg, NULL, &ctx->messenger), out);
out:
    return rc;
}

static int type_rank(VkPhysicalDeviceType t)
{
    switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU:
        return 4;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU:
        return 3;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU:
        return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU:
        return 1;
    default:
        return 0;
    }
}

static const char *type_name(VkPhysicalDeviceType t)
{
    switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU:
        return "discrete";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU:
        return "integrated";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU:
        return "virtual";
    case VK_PHYSICAL_DEVICE_TYPE_CPU:
        return "cpu";
    default:
        return "other";
    }
}

static void describe(VkPhysicalDevice pd, vkc_device_info *info)
{
    VkPhysicalDeviceProperties props;
    g_vk.vkGetPhysicalDeviceProperties(pd, &props);
    memset(info, 0, sizeof *info);
    snprintf(info->name, sizeof info->name, "%s", props.deviceName);
    info->type = type_name(props.deviceType);
    info->api_version = props.apiVersion;
    info->max_storage_buffer_range = props.limits.maxStorageBufferRange;
    VkPhysicalDeviceSubgroupProperties sub = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES};
    VkPhysicalDeviceDriverProperties drv = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
    /* VkPhysicalDeviceDriverProperties is core in 1.2; only chain it where the device has 1.2. */
    if (VK_API_VERSION_MINOR(props.apiVersion) >= 2 || VK_API_VERSION_MAJOR(props.apiVersion) > 1) sub.pNext = &drv;
    VkPhysicalDeviceProperties2 p2 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, .pNext = &sub};
    g_vk.vkGetPhysicalDeviceProperties2(pd, &p2);
    info->subgroup_size = sub.subgroupSize;
    if (sub.pNext)
        snprintf(info->driver, sizeof info->driver, "%s %s", drv.driverName, drv.driverInfo);
    else
        snprintf(info->driver, sizeof info->driver, "driver %u", props.driverVersion);
    VkPhysicalDeviceMemoryProperties mem;
    g_vk.vkGetPhysicalDeviceMemoryProperties(pd, &mem);
    for (uint32_t i = 0; i < mem.memoryHeapCount; i++)
        if (mem.memoryHeaps[i].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT) info->memory += mem.memoryHeaps[i].size;
}

static bool all_digits(const char *s)
{
    if (!*s) return false;
    for (; *s; s++)
        if (!isdigit((unsigned char)*s)) return false;
    return true;
}

static bool contains_nocase(const char *hay, const char *needle)
{
    size_t n = strlen(needle);
    for (; *hay; hay++)
        if (strncasecmp(hay, needle, n) == 0) return true;
    return false;
}

/* Index of the device `sel` picks among `n` described devices, or -1 with the logger told why. */
static int pick_device(const vkc_device_info *infos, const int *ranks, int n, const char *sel)
{
    if (sel && *sel) {
        if (all_digits(sel)) {
            long idx = strtol(sel, NULL, 10);
            if (idx >= n) {
                fb_fail(FB_ERR_USAGE, "--device: index %ld is out of range (found %d Vulkan device%s)", idx, n,
                        n == 1 ? "" : "s");
                return -1;
            }
            return (int)idx;
        }
        for (int i = 0; i < n; i++)
            if (contains_nocase(infos[i].name, sel)) return i;
        fb_fail(FB_ERR_USAGE, "--device: no Vulkan device name contains \"%s\" (run `fractalbake devices`)", sel);
        return -1;
    }
    int best = 0;
    for (int i = 1; i < n; i++)
        if (ranks[i] > ranks[best]) best = i;
    return best;
}

/* Describes every physical device of an instance and picks one. */
static fb_result list_devices(VkInstance inst, const char *sel, VkPhysicalDevice **pds_out, vkc_device_info **out,
                              int *count, int *chosen)
{
    fb_result rc = FB_OK;
    uint32_t n = 0;
    VkPhysicalDevice *pds = NULL;
    vkc_device_info *infos = NULL;
    int *ranks = NULL;
    VKC_CHECK(g_vk.vkEnumeratePhysicalDevices(inst, &n, NULL), fail);
    if (n == 0) {
        rc = fb_fail(FB_ERR_NODEVICE, "vulkan: the loader found no Vulkan device");
        goto fail;
    }
    pds = calloc(n, sizeof *pds);
    infos = calloc(n, sizeof *infos);
    ranks = calloc(n, sizeof *ranks);
    if (!pds || !infos || !ranks) {
        rc = fb_fail(FB_ERR_NOMEM, "out of memory listing Vulkan devices");
        goto fail;
    }
    VKC_CHECK(g_vk.vkEnumeratePhysicalDevices(inst, &n, pds), fail);
    for (uint32_t i = 0; i < n; i++) {
        VkPhysicalDeviceProperties props;
        g_vk.vkGetPhysicalDeviceProperties(pds[i], &props);
        describe(pds[i], &infos[i]);
        ranks[i] = type_rank(props.deviceType);
    }
    int pick = pick_device(infos, ranks, (int)n, sel);
    if (pick < 0) {
        rc = FB_ERR_USAGE;
        goto fail;
    }
    infos[pick].chosen = true;
    free(ranks);
    if (pds_out)
        *pds_out = pds;
    else
        free(pds);
    *out = infos;
    *count = (int)n;
    *chosen = pick;
    return FB_OK;
fail:
    free(ranks);
    free(infos);
    free(pds);
    return rc;
}

fb_result vkc_enumerate(const char *device_sel, vkc_device_info **out, int *count)
{
    fb_result rc = load_loader();
    if (rc) return rc;
    vkc_context tmp = {0};
    rc = create_instance(&tmp, false);
    if (rc) return rc;
    int chosen = 0;
    rc = list_devices(tmp.instance, device_sel, NULL, out, count, &chosen);
    g_vk.vkDestroyInstance(tmp.instance, NULL);
    return rc;
}

/* ---- pipeline cache on disk ----------------------------------------------------------------- */

static void cache_path(vkc_context *ctx, const VkPhysicalDeviceProperties *props)
{
    const char *base = getenv("XDG_CACHE_HOME");
    char dir[768];
    if (base && *base)
        snprintf(dir, sizeof dir, "%s/fractalbake", base);
    else if ((base = getenv("HOME")) && *base)
        snprintf(dir, sizeof dir, "%s/.cache/fractalbake", base);
    else
        return;
    char parent[768];
    snprintf(parent, sizeof parent, "%s", dir);
    char *slash = strrchr(parent, '/');
    if (slash) {
        *slash = 0;
        mkdir(parent, 0755);
    }
    if (mkdir(dir, 0755) != 0 && errno != EEXIST) return;
    char uuid[2 * VK_UUID_SIZE + 1];
    for (unsigned i = 0; i < VK_UUID_SIZE; i++) snprintf(uuid + 2 * i, 3, "%02x", props->pipelineCacheUUID[i]);
    snprintf(ctx->cache_path, sizeof ctx->cache_path, "%s/pipelines-%08x-%s.bin", dir, props->deviceID, uuid);
}

static void *read_file_all(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    void *data = NULL;
    if (fseek(f, 0, SEEK_END) == 0) {
        long n = ftell(f);
        if (n > 0 && n < (64L << 20) && fseek(f, 0, SEEK_SET) == 0 && (data = malloc((size_t)n))) {
            if (fread(data, 1, (size_t)n, f) != (size_t)n) {
                free(data);
                data = NULL;
            } else {
                *size = (size_t)n;
            }
        }
    }
    fclose(f);
    return data;
}

/* Saves the cache when it grew. Written to a temporary name and renamed, so that two processes
 * saving at once never leave a torn file. A failure only costs a recompile next time. */
static void save_cache(vkc_context *ctx)
{
    if (!ctx->cache || !ctx->cache_path[0]) return;
    size_t size = 0;
    if (g_vk.vkGetPipelineCacheData(ctx->device, ctx->cache, &size, NULL) != VK_SUCCESS || size == 0 ||
        size == ctx->cache_loaded_size)
        return;
    void *data = malloc(size);
    if (!data) return;
    if (g_vk.vkGetPipelineCacheData(ctx->device, ctx->cache, &size, data) == VK_SUCCESS) {
        char tmp[1100];
        snprintf(tmp, sizeof tmp, "%s.XXXXXX", ctx->cache_path);
        int fd = mkstemp(tmp); /* exclusive, unpredictable: nothing planted can be written through */
        FILE *f = fd >= 0 ? fdopen(fd, "wb") : NULL;
        if (fd >= 0 && !f) {
            close(fd);
            unlink(tmp);
        }
        if (f) {
            bool ok = fwrite(data, 1, size, f) == size;
            ok = (fclose(f) == 0) && ok;
            if (!ok || rename(tmp, ctx->cache_path) != 0) unlink(tmp);
        }
    }
    free(data);
}

/* ---- create / destroy ----------------------------------------------------------------------- */

fb_result vkc_create(const vkc_desc *desc, vkc_context **out)
{
    fb_result rc = load_loader();
    if (rc) return rc;
    vkc_context *ctx = calloc(1, sizeof *ctx);
    if (!ctx) return fb_fail(FB_ERR_NOMEM, "out of memory creating the Vulkan context");
    VkPhysicalDevice *pds = NULL;
    vkc_device_info *infos = NULL;
    void *cache_data = NULL;
    int count = 0, chosen = 0;

    rc = create_instance(ctx, desc->validation || env_true("FB_VK_VALIDATION"));
    if (rc) goto fail;
    rc = list_devices(ctx->instance, desc->device, &pds, &infos, &count, &chosen);
    if (rc) goto fail;
    ctx->phys = pds[chosen];
    ctx->info = infos[chosen];

    VkPhysicalDeviceProperties props;
    g_vk.vkGetPhysicalDeviceProperties(ctx->phys, &props);
    g_vk.vkGetPhysicalDeviceMemoryProperties(ctx->phys, &ctx->mem);

    uint32_t nq = 0;
    g_vk.vkGetPhysicalDeviceQueueFamilyProperties(ctx->phys, &nq, NULL);
    VkQueueFamilyProperties qf[32];
    if (nq > 32) nq = 32;
    g_vk.vkGetPhysicalDeviceQueueFamilyProperties(ctx->phys, &nq, qf);
    /* Prefer a compute-only family (async compute on GPUs), else any family with compute. */
    int family = -1;
    for (uint32_t i = 0; i < nq; i++)
        if ((qf[i].queueFlags & VK_QUEUE_COMPUTE_BIT) && !(qf[i].queueFlags & VK_QUEUE_GRAPHICS_BIT)) {
            family = (int)i;
            break;
        }
    for (uint32_t i = 0; i < nq && family < 0; i++)
        if (qf[i].queueFlags & VK_QUEUE_COMPUTE_BIT) family = (int)i;
    if (family < 0) {
        rc = fb_fail(FB_ERR_NODEVICE, "vulkan: device \"%s\" has no compute queue", ctx->info.name);
        goto fail;
    }
    ctx->queue_family = (uint32_t)family;
    ctx->timestamps = qf[family].timestampValidBits > 0 && props.limits.timestampPeriod > 0.0f;
    ctx->timestamp_period = props.limits.timestampPeriod;
    /* FB_VK_STAGING=1 forces the discrete-GPU path (device-local + staging copy) on any device, so
     * that lavapipe in CI exercises it under the validation layer. */
    ctx->direct_map = (props.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU ||
                       props.deviceType == VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU) &&
                      !env_true("FB_VK_STAGING");

    float prio = 1.0f;
    VkDeviceQueueCreateInfo qci = {
        .sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO,
        .queueFamilyIndex = ctx->queue_family,
        .queueCount = 1,
        .pQueuePriorities = &prio,
    };
    /* 64-bit buffer atomics (VK_KHR_shader_atomic_int64, core in 1.2), where the device has them:
     * the chaos game packs a hit and its colour into one atomic add. */
    const char *ext = "VK_KHR_shader_atomic_int64";
    VkPhysicalDeviceShaderAtomicInt64Features a64 = {
        .sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SHADER_ATOMIC_INT64_FEATURES};
    VkPhysicalDeviceFeatures2 f2 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, .pNext = &a64};
    bool has_ext = false;
    uint32_t next = 0;
    if (g_vk.vkEnumerateDeviceExtensionProperties(ctx->phys, NULL, &next, NULL) == VK_SUCCESS && next) {
        VkExtensionProperties *ep = calloc(next, sizeof *ep);
        if (ep && g_vk.vkEnumerateDeviceExtensionProperties(ctx->phys, NULL, &next, ep) == VK_SUCCESS)
            for (uint32_t i = 0; i < next; i++) has_ext = has_ext || !strcmp(ep[i].extensionName, ext);
        free(ep);
    }
    if (!has_ext) f2.pNext = NULL; /* the plain features only */
    g_vk.vkGetPhysicalDeviceFeatures2(ctx->phys, &f2);
    ctx->info.int64_atomics =
        has_ext && f2.features.shaderInt64 && a64.shaderBufferInt64Atomics && !env_true("FB_VK_NO_INT64");
    /* doubles in shaders, for julia layers in double precision */
    ctx->info.float64 = f2.features.shaderFloat64 && !env_true("FB_VK_NO_FLOAT64");
    VkPhysicalDeviceShaderAtomicInt64Features a64_on = {
        .sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SHADER_ATOMIC_INT64_FEATURES, .shaderBufferInt64Atomics = VK_TRUE};
    VkPhysicalDeviceFeatures on = {.shaderInt64 = ctx->info.int64_atomics, .shaderFloat64 = ctx->info.float64};
    VkDeviceCreateInfo dci = {
        .sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO,
        .pNext = ctx->info.int64_atomics ? &a64_on : NULL,
        .queueCreateInfoCount = 1,
        .pQueueCreateInfos = &qci,
        .enabledExtensionCount = ctx->info.int64_atomics ? 1u : 0u,
        .ppEnabledExtensionNames = &ext,
        .pEnabledFeatures = ctx->info.int64_atomics || ctx->info.float64 ? &on : NULL,
    };
    VKC_CHECK(g_vk.vkCreateDevice(ctx->phys, &dci, NULL, &ctx->device), fail);
    rc = load_device_fns(ctx->device);
    if (rc) goto fail;
    g_vk.vkGetDeviceQueue(ctx->device, ctx->queue_family, 0, &ctx->queue);

    VkCommandPoolCreateInfo cpi = {
        .sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO,
        .flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT,
        .queueFamilyIndex = ctx->queue_family,
    };
    VKC_CHECK(g_vk.vkCreateCommandPool(ctx->device, &cpi, NULL, &ctx->pool), fail);

    size_t cache_size = 0;
    if (!desc->no_pipeline_cache && !env_true("FB_NO_PIPELINE_CACHE")) {
        cache_path(ctx, &props);
        if (ctx->cache_path[0]) cache_data = read_file_all(ctx->cache_path, &cache_size);
    }
    /* "If initialDataSize is zero, the pipeline cache will initially be empty"; a cache whose header
     * does not match the device is ignored by the implementation (Vulkan spec, 10.7.4). */
    VkPipelineCacheCreateInfo pcci = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_CACHE_CREATE_INFO,
        .initialDataSize = cache_data ? cache_size : 0,
        .pInitialData = cache_data,
    };
    VKC_CHECK(g_vk.vkCreatePipelineCache(ctx->device, &pcci, NULL, &ctx->cache), fail);
    ctx->cache_loaded_size = cache_data ? cache_size : 0;
    free(cache_data);
    free(infos);
    free(pds);
    *out = ctx;
    return FB_OK;
fail:
    free(cache_data);
    free(infos);
    free(pds);
    vkc_destroy(&ctx);
    return rc;
}

void vkc_destroy(vkc_context **pctx)
{
    if (!pctx || !*pctx) return;
    vkc_context *ctx = *pctx;
    if (ctx->device) {
        g_vk.vkDeviceWaitIdle(ctx->device);
        if (ctx->cache) {
            save_cache(ctx);
            g_vk.vkDestroyPipelineCache(ctx->device, ctx->cache, NULL);
        }
        if (ctx->pool) g_vk.vkDestroyCommandPool(ctx->device, ctx->pool, NULL);
        while (ctx->pipes) {
            vkc_pipeline *p = ctx->pipes;
            ctx->pipes = p->next;
            pipeline_free(ctx, p);
        }
        g_vk.vkDestroyDevice(ctx->device, NULL);
    }
    if (ctx->messenger) g_vk.vkDestroyDebugUtilsMessengerEXT(ctx->instance, ctx->messenger, NULL);
    if (ctx->instance) g_vk.vkDestroyInstance(ctx->instance, NULL);
    memset(ctx, 0, sizeof *ctx);
    free(ctx);
    *pctx = NULL;
}

const vkc_device_info *vkc_info(const vkc_context *ctx)
{
    return &ctx->info;
}

uint32_t vkc_validation_messages(const vkc_context *ctx)
{
    return ctx ? ctx->validation_messages : 0;
}

bool vkc_validation_enabled(const vkc_context *ctx)
{
    return ctx && ctx->validation;
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
            q->buffers == desc->buffers && q->nspec == nspec && !memcmp(q->spec, desc->spec, 4 * nspec)) {
            *out = q;
            return FB_OK;
        }
    vkc_pipeline *p = calloc(1, sizeof *p);
    if (!p) return fb_fail(FB_ERR_NOMEM, "out of memory creating pipeline %s", desc->name);
    p->push_size = desc->push_size;
    p->buffers = desc->buffers;
    p->spv = desc->spv;
    p->spv_size = desc->spv_size;
    p->nspec = nspec;
    if (nspec) memcpy(p->spec, desc->spec, 4 * nspec);

    VkDescriptorSetLayoutBinding bindings[8];
    for (uint32_t i = 0; i < desc->buffers; i++)
        bindings[i] = (VkDescriptorSetLayoutBinding){
            .binding = i,
            .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
            .descriptorCount = 1,
            .stageFlags = VK_SHADER_STAGE_COMPUTE_BIT,
        };
    VkDescriptorSetLayoutCreateInfo dslci = {
        .sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO,
        .bindingCount = desc->buffers,
        .pBindings = bindings,
    };
    VKC_CHECK(g_vk.vkCreateDescriptorSetLayout(ctx->device, &dslci, NULL, &p->dsl), fail);
    VkPushConstantRange range = {.stageFlags = VK_SHADER_STAGE_COMPUTE_BIT, .offset = 0, .size = desc->push_size};
    VkPipelineLayoutCreateInfo plci = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO,
        .setLayoutCount = 1,
        .pSetLayouts = &p->dsl,
        .pushConstantRangeCount = desc->push_size ? 1 : 0,
        .pPushConstantRanges = &range,
    };
    VKC_CHECK(g_vk.vkCreatePipelineLayout(ctx->device, &plci, NULL, &p->layout), fail);
    VkShaderModuleCreateInfo smci = {
        .sType = VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO,
        .codeSize = desc->spv_size,
        .pCode = desc->spv,
    };
    VKC_CHECK(g_vk.vkCreateShaderModule(ctx->device, &smci, NULL, &module), fail);
    /* Specialization lets the device compiler fold uniform choices (noise kind, style flags) away:
     * on lavapipe every branch it cannot prove uniform costs both sides. */
    VkSpecializationMapEntry entries[8];
    for (uint32_t i = 0; i < nspec; i++)
        entries[i] = (VkSpecializationMapEntry){.constantID = i, .offset = 4 * i, .size = 4};
    VkSpecializationInfo spec = {
        .mapEntryCount = nspec,
        .pMapEntries = entries,
        .dataSize = 4 * nspec,
        .pData = desc->spec,
    };
    VkComputePipelineCreateInfo cpci = {
        .sType = VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO,
        .stage =
            {
                .sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO,
                .stage = VK_SHADER_STAGE_COMPUTE_BIT,
                .module = module,
                .pName = "main",
                .pSpecializationInfo = nspec ? &spec : NULL,
            },
        .layout = p->layout,
    };
    VKC_CHECK(g_vk.vkCreateComputePipelines(ctx->device, ctx->cache, 1, &cpci, NULL, &p->pipeline), fail);
    g_vk.vkDestroyShaderModule(ctx->device, module, NULL);
    p->next = ctx->pipes;
    ctx->pipes = p;
    *out = p;
    return FB_OK;
fail:
    if (module) g_vk.vkDestroyShaderModule(ctx->device, module, NULL);
    pipeline_free(ctx, p);
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
    VkBuffer buf; /* the storage buffer the shader writes */
    VkDeviceMemory mem;
    VkBuffer staging; /* host-readable copy, when `buf` is not mapped directly */
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
    VKC_CHECK(g_vk.vkCreateBuffer(ctx->device, &bci, NULL, buf), fail);
    VkMemoryRequirements req;
    g_vk.vkGetBufferMemoryRequirements(ctx->device, *buf, &req);
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
    VKC_CHECK(g_vk.vkAllocateMemory(ctx->device, &mai, NULL, mem), fail);
    VKC_CHECK(g_vk.vkBindBufferMemory(ctx->device, *buf, *mem, 0), fail);
    *got = ctx->mem.memoryTypes[type].propertyFlags;
    return FB_OK;
fail:
    return rc;
}

static void advise_huge(void *p, uint64_t size);

fb_result vkc_buffer_create(vkc_context *ctx, uint64_t size, vkc_buffer **out)
{
    fb_result rc = FB_OK;
    if (size == 0 || size > ctx->info.max_storage_buffer_range)
        return fb_fail(FB_ERR_INTERNAL,
                       "vulkan: a %llu-byte storage buffer exceeds the device's maxStorageBufferRange (%llu)",
                       (unsigned long long)size, (unsigned long long)ctx->info.max_storage_buffer_range);
    vkc_buffer *b = calloc(1, sizeof *b);
    if (!b) return fb_fail(FB_ERR_NOMEM, "out of memory");
    b->size = size;
    VkMemoryPropertyFlags got = 0;
    const VkBufferUsageFlags storage =
        VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    if (ctx->direct_map) {
        const VkMemoryPropertyFlags prefs[] = {
            VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT | VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT |
                VK_MEMORY_PROPERTY_HOST_CACHED_BIT,
            VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT | VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT,
            VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT,
        };
        rc = make_buffer(ctx, size, storage, prefs, 3, &b->buf, &b->mem, &got);
        if (rc) goto fail;
        VKC_CHECK(g_vk.vkMapMemory(ctx->device, b->mem, 0, VK_WHOLE_SIZE, 0, &b->map), fail);
        advise_huge(b->map, size);
    } else {
        const VkMemoryPropertyFlags dev_prefs[] = {VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, 0};
        rc = make_buffer(ctx, size, storage, dev_prefs, 2, &b->buf, &b->mem, &got);
        if (rc) goto fail;
        const VkMemoryPropertyFlags host_prefs[] = {
            VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_CACHED_BIT,
            VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT,
        };
        rc =
            make_buffer(ctx, size, VK_BUFFER_USAGE_TRANSFER_DST_BIT, host_prefs, 2, &b->staging, &b->staging_mem, &got);
        if (rc) goto fail;
        VKC_CHECK(g_vk.vkMapMemory(ctx->device, b->staging_mem, 0, VK_WHOLE_SIZE, 0, &b->map), fail);
    }
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
    if (b->staging) g_vk.vkDestroyBuffer(ctx->device, b->staging, NULL);
    if (b->staging_mem) g_vk.vkFreeMemory(ctx->device, b->staging_mem, NULL);
    if (b->buf) g_vk.vkDestroyBuffer(ctx->device, b->buf, NULL);
    if (b->mem) g_vk.vkFreeMemory(ctx->device, b->mem, NULL); /* freeing unmaps implicitly */
    memset(b, 0, sizeof *b);
    free(b);
    *pb = NULL;
}

fb_result vkc_buffer_upload(vkc_context *ctx, vkc_buffer *b, const void *data, uint64_t size)
{
    fb_result rc = FB_OK;
    if (NEVER(size > b->size)) return fb_fail(FB_ERR_INTERNAL, "vulkan: upload larger than its buffer");
    memcpy(b->map, data, size);
    if (!b->coherent) {
        VkMappedMemoryRange r = {
            .sType = VK_STRUCTURE_TYPE_MAPPED_MEMORY_RANGE,
            .memory = b->staging ? b->staging_mem : b->mem,
            .size = VK_WHOLE_SIZE,
        };
        VKC_CHECK(g_vk.vkFlushMappedMemoryRanges(ctx->device, 1, &r), out);
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

struct vkc_job {
    vkc_pipeline *pipe;
    VkCommandBuffer cmd;
    VkFence fence;
    VkDescriptorPool dpool;
    VkDescriptorSet set;
    VkQueryPool queries;
    bool in_flight;
    vkc_buffer *bufs[8];
    uint32_t nbufs;
};

fb_result vkc_job_create(vkc_context *ctx, vkc_pipeline *pipe, vkc_job **out)
{
    fb_result rc = FB_OK;
    vkc_job *job = calloc(1, sizeof *job);
    if (!job) return fb_fail(FB_ERR_NOMEM, "out of memory");
    job->pipe = pipe;
    VkCommandBufferAllocateInfo cbai = {
        .sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO,
        .commandPool = ctx->pool,
        .level = VK_COMMAND_BUFFER_LEVEL_PRIMARY,
        .commandBufferCount = 1,
    };
    VKC_CHECK(g_vk.vkAllocateCommandBuffers(ctx->device, &cbai, &job->cmd), fail);
    VkFenceCreateInfo fci = {.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    VKC_CHECK(g_vk.vkCreateFence(ctx->device, &fci, NULL, &job->fence), fail);
    if (pipe->buffers) {
        VkDescriptorPoolSize ps = {.type = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, .descriptorCount = pipe->buffers};
        VkDescriptorPoolCreateInfo dpci = {
            .sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO,
            .maxSets = 1,
            .poolSizeCount = 1,
            .pPoolSizes = &ps,
        };
        VKC_CHECK(g_vk.vkCreateDescriptorPool(ctx->device, &dpci, NULL, &job->dpool), fail);
        VkDescriptorSetAllocateInfo dsai = {
            .sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO,
            .descriptorPool = job->dpool,
            .descriptorSetCount = 1,
            .pSetLayouts = &pipe->dsl,
        };
        VKC_CHECK(g_vk.vkAllocateDescriptorSets(ctx->device, &dsai, &job->set), fail);
    }
    if (ctx->timestamps) {
        VkQueryPoolCreateInfo qpci = {
            .sType = VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO,
            .queryType = VK_QUERY_TYPE_TIMESTAMP,
            .queryCount = 2,
        };
        VKC_CHECK(g_vk.vkCreateQueryPool(ctx->device, &qpci, NULL, &job->queries), fail);
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
    if (job->in_flight) g_vk.vkWaitForFences(ctx->device, 1, &job->fence, VK_TRUE, UINT64_MAX);
    if (job->queries) g_vk.vkDestroyQueryPool(ctx->device, job->queries, NULL);
    if (job->dpool) g_vk.vkDestroyDescriptorPool(ctx->device, job->dpool, NULL);
    if (job->fence) g_vk.vkDestroyFence(ctx->device, job->fence, NULL);
    if (job->cmd) g_vk.vkFreeCommandBuffers(ctx->device, ctx->pool, 1, &job->cmd);
    memset(job, 0, sizeof *job);
    free(job);
    *pjob = NULL;
}

fb_result vkc_job_submit(vkc_context *ctx, vkc_job *job, vkc_buffer *const *bufs, uint32_t nbufs, const void *push,
                         const uint32_t groups[3])
{
    fb_result rc = FB_OK;
    vkc_pipeline *p = job->pipe;
    if (NEVER(job->in_flight) || NEVER(nbufs != p->buffers))
        return fb_fail(FB_ERR_INTERNAL, "vulkan: job submitted while in flight or with wrong buffer count");

    VkDescriptorBufferInfo infos[8];
    VkWriteDescriptorSet writes[8];
    for (uint32_t i = 0; i < nbufs; i++) {
        infos[i] = (VkDescriptorBufferInfo){.buffer = bufs[i]->buf, .offset = 0, .range = VK_WHOLE_SIZE};
        writes[i] = (VkWriteDescriptorSet){
            .sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET,
            .dstSet = job->set,
            .dstBinding = i,
            .descriptorCount = 1,
            .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
            .pBufferInfo = &infos[i],
        };
        job->bufs[i] = bufs[i];
    }
    job->nbufs = nbufs;
    /* Legal here: the set is not in use by any pending command buffer (the job is not in flight). */
    if (nbufs) g_vk.vkUpdateDescriptorSets(ctx->device, nbufs, writes, 0, NULL);

    VKC_CHECK(g_vk.vkResetCommandBuffer(job->cmd, 0), out);
    VkCommandBufferBeginInfo cbbi = {
        .sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO,
        .flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT,
    };
    VKC_CHECK(g_vk.vkBeginCommandBuffer(job->cmd, &cbbi), out);
    if (job->queries) {
        g_vk.vkCmdResetQueryPool(job->cmd, job->queries, 0, 2);
        g_vk.vkCmdWriteTimestamp(job->cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, job->queries, 0);
    }
    /* Host data for staged input buffers goes to the device buffer first. */
    bool uploads = false;
    for (uint32_t i = 0; i < nbufs; i++) {
        if (!bufs[i]->upload_pending) continue;
        VkBufferCopy region = {.size = bufs[i]->size};
        g_vk.vkCmdCopyBuffer(job->cmd, bufs[i]->staging, bufs[i]->buf, 1, &region);
        bufs[i]->upload_pending = false;
        uploads = true;
    }
    if (uploads) {
        VkMemoryBarrier ub = {
            .sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER,
            .srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT,
            .dstAccessMask = VK_ACCESS_SHADER_READ_BIT,
        };
        g_vk.vkCmdPipelineBarrier(job->cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1,
                                  &ub, 0, NULL, 0, NULL);
    }
    g_vk.vkCmdBindPipeline(job->cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p->pipeline);
    if (nbufs)
        g_vk.vkCmdBindDescriptorSets(job->cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p->layout, 0, 1, &job->set, 0, NULL);
    if (p->push_size) g_vk.vkCmdPushConstants(job->cmd, p->layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, p->push_size, push);
    g_vk.vkCmdDispatch(job->cmd, groups[0], groups[1], groups[2]);
    if (job->queries) g_vk.vkCmdWriteTimestamp(job->cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, job->queries, 1);

    bool staged = false;
    for (uint32_t i = 0; i < nbufs; i++) staged = staged || bufs[i]->staging;
    if (staged) {
        VkMemoryBarrier mb = {
            .sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER,
            .srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT,
            .dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT,
        };
        g_vk.vkCmdPipelineBarrier(job->cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 1,
                                  &mb, 0, NULL, 0, NULL);
        for (uint32_t i = 0; i < nbufs; i++) {
            if (!bufs[i]->staging) continue;
            VkBufferCopy region = {.size = bufs[i]->size};
            g_vk.vkCmdCopyBuffer(job->cmd, bufs[i]->buf, bufs[i]->staging, 1, &region);
        }
    }
    /* Make shader (or copy) writes available to host reads after the fence: "a fence signal
     * operation does not make writes available to the host" without a host-access barrier. */
    VkMemoryBarrier hb = {
        .sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER,
        .srcAccessMask = staged ? VK_ACCESS_TRANSFER_WRITE_BIT : VK_ACCESS_SHADER_WRITE_BIT,
        .dstAccessMask = VK_ACCESS_HOST_READ_BIT,
    };
    g_vk.vkCmdPipelineBarrier(job->cmd, staged ? VK_PIPELINE_STAGE_TRANSFER_BIT : VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                              VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &hb, 0, NULL, 0, NULL);
    VKC_CHECK(g_vk.vkEndCommandBuffer(job->cmd), out);

    VKC_CHECK(g_vk.vkResetFences(ctx->device, 1, &job->fence), out);
    VkSubmitInfo si = {
        .sType = VK_STRUCTURE_TYPE_SUBMIT_INFO,
        .commandBufferCount = 1,
        .pCommandBuffers = &job->cmd,
    };
    VKC_CHECK(g_vk.vkQueueSubmit(ctx->queue, 1, &si, job->fence), out);
    job->in_flight = true;
out:
    return rc;
}

fb_result vkc_job_wait(vkc_context *ctx, vkc_job *job, double *gpu_seconds)
{
    fb_result rc = FB_OK;
    if (gpu_seconds) *gpu_seconds = -1.0;
    if (!job->in_flight) return FB_OK;
    VKC_CHECK(g_vk.vkWaitForFences(ctx->device, 1, &job->fence, VK_TRUE, UINT64_MAX), out);
    job->in_flight = false;
    for (uint32_t i = 0; i < job->nbufs; i++) {
        vkc_buffer *b = job->bufs[i];
        if (b->coherent) continue;
        VkMappedMemoryRange r = {
            .sType = VK_STRUCTURE_TYPE_MAPPED_MEMORY_RANGE,
            .memory = b->staging ? b->staging_mem : b->mem,
            .offset = 0,
            .size = VK_WHOLE_SIZE,
        };
        VKC_CHECK(g_vk.vkInvalidateMappedMemoryRanges(ctx->device, 1, &r), out);
    }
    if (gpu_seconds && job->queries) {
        uint64_t ts[2];
        VKC_CHECK(g_vk.vkGetQueryPoolResults(ctx->device, job->queries, 0, 2, sizeof ts, ts, sizeof ts[0],
                                             VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT),
                  out);
        *gpu_seconds = (double)(ts[1] - ts[0]) * (double)ctx->timestamp_period * 1e-9;
    }
out:
    return rc;
}
