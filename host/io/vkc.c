#define _GNU_SOURCE /* dl_iterate_phdr, in sanitizer builds */
/*
 * The Vulkan compute context. See vkc.h for the model.
 */
#include "vkc_private.h"

#include <ctype.h>
#include <dlfcn.h>
#include <link.h>
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

const char *vkc_result_name(VkResult r)
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
/* The loader, opened once per process and never closed (a driver may keep threads running). */
static void *g_libvulkan;

/* Opens the loader (once) and resolves its global entry points into *vk. */
static fb_result load_loader(vkc_fns *vk)
{
    if (g_libvulkan) goto resolve;
    const char *names[] = {"libvulkan.so.1", "libvulkan.so"};
    for (size_t i = 0; i < sizeof names / sizeof names[0] && !g_libvulkan; i++)
        g_libvulkan = dlopen(names[i], RTLD_NOW | RTLD_LOCAL);
    if (!g_libvulkan) return fb_fail(FB_ERR_NODEVICE, "vulkan: no Vulkan loader (libvulkan.so.1) on this machine");
    if (!dlsym(g_libvulkan, "vkGetInstanceProcAddr")) {
        dlclose(g_libvulkan);
        g_libvulkan = NULL;
        return fb_fail(FB_ERR_NODEVICE, "vulkan: the loader has no vkGetInstanceProcAddr");
    }
resolve:
    vk->vkGetInstanceProcAddr = (PFN_vkGetInstanceProcAddr)dlsym(g_libvulkan, "vkGetInstanceProcAddr");
#define LOAD(fn) vk->fn = (PFN_##fn)vk->vkGetInstanceProcAddr(NULL, #fn);
    VKC_GLOBAL_FNS(LOAD)
#undef LOAD
    if (!vk->vkCreateInstance) return fb_fail(FB_ERR_NODEVICE, "vulkan: the loader has no vkCreateInstance");
    return FB_OK;
}

static void load_instance_fns(vkc_fns *vk, VkInstance inst)
{
#define LOAD(fn) vk->fn = (PFN_##fn)vk->vkGetInstanceProcAddr(inst, #fn);
    VKC_INSTANCE_FNS(LOAD)
#undef LOAD
}

static fb_result load_device_fns(vkc_fns *vk, VkDevice dev)
{
#define LOAD(fn)                                                                                                       \
    vk->fn = (PFN_##fn)vk->vkGetDeviceProcAddr(dev, #fn);                                                              \
    if (!vk->fn) return fb_fail(FB_ERR_VULKAN, "vulkan: the device has no %s", #fn);
    VKC_DEVICE_FNS(LOAD)
#undef LOAD
    return FB_OK;
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

static bool has_layer(const vkc_fns *vk, const char *name)
{
    uint32_t n = 0;
    if (vk->vkEnumerateInstanceLayerProperties(&n, NULL) != VK_SUCCESS || n == 0) return false;
    VkLayerProperties *props = calloc(n, sizeof *props);
    if (!props) return false;
    bool found = false;
    if (vk->vkEnumerateInstanceLayerProperties(&n, props) == VK_SUCCESS)
        for (uint32_t i = 0; i < n; i++) found = found || strcmp(props[i].layerName, name) == 0;
    free(props);
    return found;
}

static bool has_instance_ext(const vkc_fns *vk, const char *name)
{
    uint32_t n = 0;
    if (vk->vkEnumerateInstanceExtensionProperties(NULL, &n, NULL) != VK_SUCCESS || n == 0) return false;
    VkExtensionProperties *props = calloc(n, sizeof *props);
    if (!props) return false;
    bool found = false;
    if (vk->vkEnumerateInstanceExtensionProperties(NULL, &n, props) == VK_SUCCESS)
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
        if (!has_layer(&ctx->vk, "VK_LAYER_KHRONOS_validation")) {
            fb_log(FB_LOG_WARN, "vulkan: validation requested but VK_LAYER_KHRONOS_validation is not installed");
            validation = false;
        } else {
            layers[nlayers++] = "VK_LAYER_KHRONOS_validation";
            if (has_instance_ext(&ctx->vk, VK_EXT_DEBUG_UTILS_EXTENSION_NAME))
                exts[nexts++] = VK_EXT_DEBUG_UTILS_EXTENSION_NAME;
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
    VkResult vr = ctx->vk.vkCreateInstance(&ici, NULL, &ctx->instance);
    if (vr == VK_ERROR_INCOMPATIBLE_DRIVER)
        return fb_fail(FB_ERR_NODEVICE, "vulkan: no Vulkan 1.1 driver found (vkCreateInstance: %s)",
                       vkc_result_name(vr));
    VKC_CHECK(vr, out);
    pin_loaded_modules();
    load_instance_fns(&ctx->vk, ctx->instance);
    ctx->validation = validation;
    if (validation && nexts && ctx->vk.vkCreateDebugUtilsMessengerEXT)
        VKC_CHECK(ctx->vk.vkCreateDebugUtilsMessengerEXT(ctx->instance, &dbg, NULL, &ctx->messenger), out);
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

static bool has_device_ext(const vkc_fns *vk, VkPhysicalDevice pd, const char *name)
{
    uint32_t n = 0;
    bool has = false;
    if (vk->vkEnumerateDeviceExtensionProperties(pd, NULL, &n, NULL) != VK_SUCCESS || !n) return false;
    VkExtensionProperties *ep = calloc(n, sizeof *ep);
    if (ep && vk->vkEnumerateDeviceExtensionProperties(pd, NULL, &n, ep) == VK_SUCCESS)
        for (uint32_t i = 0; i < n; i++) has = has || !strcmp(ep[i].extensionName, name);
    free(ep);
    return has;
}

void vkc_arith_describe(const vkc_device_info *info, char *buf, size_t size)
{
    snprintf(buf, size, "rounding %s, denormals %s, NaN and infinity %s; division and square root: %s",
             info->rte32 ? "to nearest (declared)" : "the device's default",
             info->denorm32 ? "kept (declared)" : "the device's default",
             info->szinp32 ? "kept (declared)" : "the device's default",
             info->exact_native ? "the device's own (correctly rounded)" : "corrected exactly (kernels/exact.h)");
}

static void describe(const vkc_fns *vk, VkPhysicalDevice pd, vkc_device_info *info)
{
    VkPhysicalDeviceProperties props;
    vk->vkGetPhysicalDeviceProperties(pd, &props);
    memset(info, 0, sizeof *info);
    snprintf(info->name, sizeof info->name, "%s", props.deviceName);
    info->type = type_name(props.deviceType);
    info->api_version = props.apiVersion;
    info->max_storage_buffer_range = props.limits.maxStorageBufferRange;
    info->max_uniform_buffer_range = props.limits.maxUniformBufferRange;
    for (int i = 0; i < 3; i++) info->max_workgroup_count[i] = props.limits.maxComputeWorkGroupCount[i];
    info->unified =
        props.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU || props.deviceType == VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU;
    VkPhysicalDeviceMaintenance3Properties m3 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MAINTENANCE_3_PROPERTIES};
    VkPhysicalDeviceSubgroupProperties sub = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES,
                                              .pNext = &m3};
    VkPhysicalDeviceDriverProperties drv = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
    /* VkPhysicalDeviceDriverProperties is core in 1.2; only chain it where the device has 1.2. */
    if (VK_API_VERSION_MINOR(props.apiVersion) >= 2 || VK_API_VERSION_MAJOR(props.apiVersion) > 1) m3.pNext = &drv;
    VkPhysicalDeviceProperties2 p2 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, .pNext = &sub};
    vk->vkGetPhysicalDeviceProperties2(pd, &p2);
    info->subgroup_size = sub.subgroupSize;
    info->max_allocation = m3.maxMemoryAllocationSize;
    if (m3.pNext)
        snprintf(info->driver, sizeof info->driver, "%s %s", drv.driverName, drv.driverInfo);
    else
        snprintf(info->driver, sizeof info->driver, "driver %u", props.driverVersion);
    /* exact arithmetic: the float-controls modes (an extension of its own before 1.2: this instance
     * asks for 1.1) and whether the device's own division is known to be correctly rounded */
    info->float_controls = has_device_ext(vk, pd, "VK_KHR_shader_float_controls");
    if (info->float_controls) {
        VkPhysicalDeviceFloatControlsProperties fc = {.sType =
                                                          VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FLOAT_CONTROLS_PROPERTIES};
        VkPhysicalDeviceProperties2 q = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, .pNext = &fc};
        vk->vkGetPhysicalDeviceProperties2(pd, &q);
        bool dn64 = fc.denormBehaviorIndependence == VK_SHADER_FLOAT_CONTROLS_INDEPENDENCE_ALL;
        bool rn64 = fc.roundingModeIndependence == VK_SHADER_FLOAT_CONTROLS_INDEPENDENCE_ALL;
        /* "NONE": one denormal (rounding) mode for every width: only where both widths offer it */
        bool dn_none = fc.denormBehaviorIndependence == VK_SHADER_FLOAT_CONTROLS_INDEPENDENCE_NONE;
        bool rn_none = fc.roundingModeIndependence == VK_SHADER_FLOAT_CONTROLS_INDEPENDENCE_NONE;
        info->rte32 = fc.shaderRoundingModeRTEFloat32 && (!rn_none || fc.shaderRoundingModeRTEFloat64);
        info->rte64 = fc.shaderRoundingModeRTEFloat64 && (rn64 || rn_none) && info->rte32;
        info->denorm32 = fc.shaderDenormPreserveFloat32 && (!dn_none || fc.shaderDenormPreserveFloat64);
        info->denorm64 = fc.shaderDenormPreserveFloat64 && (dn64 || dn_none) && info->denorm32;
        info->szinp32 = fc.shaderSignedZeroInfNanPreserveFloat32;
        info->szinp64 = fc.shaderSignedZeroInfNanPreserveFloat64;
    }
    info->exact_native = m3.pNext && drv.driverID == VK_DRIVER_ID_MESA_LLVMPIPE;
    VkPhysicalDeviceMemoryProperties mem;
    vk->vkGetPhysicalDeviceMemoryProperties(pd, &mem);
    for (uint32_t i = 0; i < mem.memoryHeapCount; i++)
        if (mem.memoryHeaps[i].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT) {
            info->memory += mem.memoryHeaps[i].size;
            if (mem.memoryHeaps[i].size > info->heap) info->heap = mem.memoryHeaps[i].size;
        }
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
static fb_result list_devices(const vkc_fns *vk, VkInstance inst, const char *sel, VkPhysicalDevice **pds_out,
                              vkc_device_info **out, int *count, int *chosen)
{
    fb_result rc = FB_OK;
    uint32_t n = 0;
    VkPhysicalDevice *pds = NULL;
    vkc_device_info *infos = NULL;
    int *ranks = NULL;
    VKC_CHECK(vk->vkEnumeratePhysicalDevices(inst, &n, NULL), fail);
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
    VKC_CHECK(vk->vkEnumeratePhysicalDevices(inst, &n, pds), fail);
    for (uint32_t i = 0; i < n; i++) {
        VkPhysicalDeviceProperties props;
        vk->vkGetPhysicalDeviceProperties(pds[i], &props);
        describe(vk, pds[i], &infos[i]);
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
    vkc_context tmp = {0};
    fb_result rc = load_loader(&tmp.vk);
    if (rc) return rc;
    rc = create_instance(&tmp, false);
    if (rc) return rc;
    int chosen = 0;
    rc = list_devices(&tmp.vk, tmp.instance, device_sel, NULL, out, count, &chosen);
    tmp.vk.vkDestroyInstance(tmp.instance, NULL);
    return rc;
}

/* ---- pipeline cache on disk ----------------------------------------------------------------- */

/* The cache file in folder `dir` (made, with its parent, when missing) for this device. */
static void cache_path(vkc_context *ctx, const char *dir, const VkPhysicalDeviceProperties *props)
{
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
    /* the cache is a regular file or nothing: a FIFO in its place must not block the run */
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    struct stat st;
    if (fd >= 0 && (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode))) {
        close(fd);
        fd = -1;
    }
    FILE *f = fd >= 0 ? fdopen(fd, "rb") : NULL;
    if (!f) {
        if (fd >= 0) close(fd);
        return NULL;
    }
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
    if (ctx->vk.vkGetPipelineCacheData(ctx->device, ctx->cache, &size, NULL) != VK_SUCCESS || size == 0 ||
        size == ctx->cache_loaded_size)
        return;
    void *data = malloc(size);
    if (!data) return;
    if (ctx->vk.vkGetPipelineCacheData(ctx->device, ctx->cache, &size, data) == VK_SUCCESS) {
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
    vkc_context *ctx = calloc(1, sizeof *ctx);
    if (!ctx) return fb_fail(FB_ERR_NOMEM, "out of memory creating the Vulkan context");
    fb_result rc = load_loader(&ctx->vk);
    if (rc) {
        free(ctx);
        return rc;
    }
    VkPhysicalDevice *pds = NULL;
    vkc_device_info *infos = NULL;
    void *cache_data = NULL;
    int count = 0, chosen = 0;

    rc = create_instance(ctx, desc->validation);
    if (rc) goto fail;
    rc = list_devices(&ctx->vk, ctx->instance, desc->device, &pds, &infos, &count, &chosen);
    if (rc) goto fail;
    ctx->phys = pds[chosen];
    ctx->info = infos[chosen];

    VkPhysicalDeviceProperties props;
    ctx->vk.vkGetPhysicalDeviceProperties(ctx->phys, &props);
    ctx->vk.vkGetPhysicalDeviceMemoryProperties(ctx->phys, &ctx->mem);

    uint32_t nq = 0;
    ctx->vk.vkGetPhysicalDeviceQueueFamilyProperties(ctx->phys, &nq, NULL);
    VkQueueFamilyProperties qf[32];
    if (nq > 32) nq = 32;
    ctx->vk.vkGetPhysicalDeviceQueueFamilyProperties(ctx->phys, &nq, qf);
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
    /* desc->staging forces the discrete-GPU path (device-local + staging copy) on any device, so
     * that lavapipe in CI exercises it under the validation layer. */
    ctx->direct_map = ctx->info.unified && !desc->staging;
    ctx->info.staging = !ctx->direct_map;

    float prio = 1.0f;
    VkDeviceQueueCreateInfo qci = {
        .sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO,
        .queueFamilyIndex = ctx->queue_family,
        .queueCount = 1,
        .pQueuePriorities = &prio,
    };
    /* 64-bit buffer atomics (VK_KHR_shader_atomic_int64, core in 1.2), where the device has them:
     * the chaos game packs a hit and its colour into one atomic add. */
    const char *exts[2], *ext = "VK_KHR_shader_atomic_int64";
    uint32_t nexts = 0;
    VkPhysicalDeviceShaderAtomicInt64Features a64 = {
        .sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SHADER_ATOMIC_INT64_FEATURES};
    VkPhysicalDeviceFeatures2 f2 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, .pNext = &a64};
    bool has_ext = has_device_ext(&ctx->vk, ctx->phys, ext);
    if (!has_ext) f2.pNext = NULL; /* the plain features only */
    ctx->vk.vkGetPhysicalDeviceFeatures2(ctx->phys, &f2);
    ctx->info.int64_atomics = has_ext && f2.features.shaderInt64 && a64.shaderBufferInt64Atomics && !desc->no_int64;
    /* doubles in shaders, for julia layers in double precision */
    ctx->info.float64 = f2.features.shaderFloat64 && !desc->no_float64;
    VkPhysicalDeviceShaderAtomicInt64Features a64_on = {
        .sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SHADER_ATOMIC_INT64_FEATURES, .shaderBufferInt64Atomics = VK_TRUE};
    VkPhysicalDeviceFeatures on = {.shaderInt64 = ctx->info.int64_atomics, .shaderFloat64 = ctx->info.float64};
    if (ctx->info.int64_atomics) exts[nexts++] = ext;
    if (ctx->info.float_controls) exts[nexts++] = "VK_KHR_shader_float_controls";
    /* FB_VK_STAGING's portable arithmetic: the kx_ helpers' correction even where the device is exact */
    if (desc->portable) ctx->info.exact_native = false;
    VkDeviceCreateInfo dci = {
        .sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO,
        .pNext = ctx->info.int64_atomics ? &a64_on : NULL,
        .queueCreateInfoCount = 1,
        .pQueueCreateInfos = &qci,
        .enabledExtensionCount = nexts,
        .ppEnabledExtensionNames = exts,
        .pEnabledFeatures = ctx->info.int64_atomics || ctx->info.float64 ? &on : NULL,
    };
    VKC_CHECK(ctx->vk.vkCreateDevice(ctx->phys, &dci, NULL, &ctx->device), fail);
    rc = load_device_fns(&ctx->vk, ctx->device);
    if (rc) goto fail;
    ctx->vk.vkGetDeviceQueue(ctx->device, ctx->queue_family, 0, &ctx->queue);

    VkCommandPoolCreateInfo cpi = {
        .sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO,
        .flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT,
        .queueFamilyIndex = ctx->queue_family,
    };
    VKC_CHECK(ctx->vk.vkCreateCommandPool(ctx->device, &cpi, NULL, &ctx->pool), fail);

    size_t cache_size = 0;
    if (!desc->no_pipeline_cache && desc->cache_dir && *desc->cache_dir) {
        cache_path(ctx, desc->cache_dir, &props);
        if (ctx->cache_path[0]) cache_data = read_file_all(ctx->cache_path, &cache_size);
    }
    /* "If initialDataSize is zero, the pipeline cache will initially be empty"; a cache whose header
     * does not match the device is ignored by the implementation (Vulkan spec, 10.7.4). */
    VkPipelineCacheCreateInfo pcci = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_CACHE_CREATE_INFO,
        .initialDataSize = cache_data ? cache_size : 0,
        .pInitialData = cache_data,
    };
    VKC_CHECK(ctx->vk.vkCreatePipelineCache(ctx->device, &pcci, NULL, &ctx->cache), fail);
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
        ctx->vk.vkDeviceWaitIdle(ctx->device);
        if (ctx->cache) {
            save_cache(ctx);
            ctx->vk.vkDestroyPipelineCache(ctx->device, ctx->cache, NULL);
        }
        if (ctx->pool) ctx->vk.vkDestroyCommandPool(ctx->device, ctx->pool, NULL);
        while (ctx->pipes) {
            vkc_pipeline *p = ctx->pipes;
            ctx->pipes = p->next;
            vkc_pipeline_free(ctx, p);
        }
        ctx->vk.vkDestroyDevice(ctx->device, NULL);
    }
    if (ctx->messenger) ctx->vk.vkDestroyDebugUtilsMessengerEXT(ctx->instance, ctx->messenger, NULL);
    if (ctx->instance) ctx->vk.vkDestroyInstance(ctx->instance, NULL);
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
