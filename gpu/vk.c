/*
 * vk.c — the internal Vulkan compute layer under GPU synthesis (Haindl &
 * Filip 2007, section II.C, computed by compute shaders; see vk.h and
 * docs/gpu.md):
 * instance and device choice, memory types, storage buffers with upload and
 * download, compute pipelines from SPIR-V, and jobs of dispatches with a
 * barrier after each command.
 *
 * Why this shape: every shader of the library needs the same few things, and
 * the correctness rules (limits checked before Vulkan sees them, a barrier
 * after every command, every VkResult turned into one line naming the call,
 * validation messages counted) are easiest to keep in one file.
 */
#if defined(__SANITIZE_ADDRESS__) && !defined(_GNU_SOURCE)
#define _GNU_SOURCE /* dl_iterate_phdr, RTLD_NODELETE: sanitizer builds only, see below */
#endif
#include <stdio.h>
#include "vk.h"

#include "core/core.h"

#include <stdlib.h>
#include <string.h>
#include <vulkan/vulkan.h>

#if defined(__SANITIZE_ADDRESS__)
#include <dlfcn.h>
#include <link.h>

/* Sanitizer builds only (make asan). When the last instance goes, the
 * loader unloads the driver and layer libraries; LeakSanitizer then sees
 * their never-freed static allocations (lavapipe keeps one 128-byte block
 * from its start-up) as leaks in "<unknown module>", which no suppression
 * can name. Pinning those libraries keeps their data reachable and their
 * frames named, so the leak check judges btfcar's own memory only
 * (tests/lsan.supp). */
static int pin_one(struct dl_phdr_info *info, size_t size, void *user)
{
    (void)size;
    (void)user;
    const char *name = info->dlpi_name;
    if (name && (strstr(name, "libvulkan_") || strstr(name, "libVkLayer_")))
        dlopen(name, RTLD_LAZY | RTLD_NOLOAD | RTLD_NODELETE);
    return 0;
}

static void pin_vulkan_modules(void)
{
    dl_iterate_phdr(pin_one, NULL);
}
#else
static void pin_vulkan_modules(void)
{
}
#endif

#define NEED_API VK_API_VERSION_1_1 /* shaders are built for --target-env vulkan1.1 */
#define DEFAULT_TIMEOUT_MS 600000u  /* 10 minutes */
#define STAGING_CHUNK ((VkDeviceSize)16 << 20)
#define VALIDATION_LAYER "VK_LAYER_KHRONOS_validation"
#define NO_DEVICE_MSG "no Vulkan device found (install mesa-vulkan-drivers for the CPU driver lavapipe)"

struct btf_vk_job;

struct btf_vk {
    VkInstance instance;
    VkDebugUtilsMessengerEXT messenger;
    VkPhysicalDevice phys;
    VkDevice device;
    VkQueue queue;
    uint32_t queue_family;
    VkCommandPool cmd_pool;
    VkFence fence;
    VkPhysicalDeviceMemoryProperties mem;
    uint32_t storage_type;               /* memory type of storage buffers */
    uint32_t upload_type, download_type; /* staging memory types (when not mapped) */
    VkDeviceSize heap_used[VK_MAX_MEMORY_HEAPS];
    btf_vk_device_info info;
    uint64_t timeout_ns;
    uint32_t timeout_ms;
    int validation;
    unsigned n_messages;
    char first_message[1024];
    char broken[512];        /* why the context is unusable ("" while fine) */
    struct btf_vk_job *stuck; /* a job that did not finish: freed after the device idles */
};

struct btf_vk_buffer {
    btf_vk *vk;
    VkBuffer buffer;
    VkDeviceMemory memory;
    VkDeviceSize size, alloc_size;
    uint32_t heap;
    void *mapped;
};

struct btf_vk_pipeline {
    btf_vk *vk;
    VkDescriptorSetLayout set_layout;
    VkPipelineLayout layout;
    VkPipeline pipeline;
    int n_buffers;
    uint32_t push_bytes;
};

struct btf_vk_job {
    btf_vk *vk;
    VkCommandBuffer cmd;
    VkDescriptorPool *pools;  /* descriptor sets live until the job ends */
    int n_pools, cap_pools;
    uint32_t sets_left, descriptors_left;
};

/* ------------------------------------------------------------ messages */

static const char *vk_result_name(VkResult r)
{
    switch (r) {
#define R(x) case x: return #x;
    R(VK_SUCCESS) R(VK_NOT_READY) R(VK_TIMEOUT) R(VK_EVENT_SET) R(VK_EVENT_RESET)
    R(VK_INCOMPLETE) R(VK_ERROR_OUT_OF_HOST_MEMORY) R(VK_ERROR_OUT_OF_DEVICE_MEMORY)
    R(VK_ERROR_INITIALIZATION_FAILED) R(VK_ERROR_DEVICE_LOST) R(VK_ERROR_MEMORY_MAP_FAILED)
    R(VK_ERROR_LAYER_NOT_PRESENT) R(VK_ERROR_EXTENSION_NOT_PRESENT)
    R(VK_ERROR_FEATURE_NOT_PRESENT) R(VK_ERROR_INCOMPATIBLE_DRIVER)
    R(VK_ERROR_TOO_MANY_OBJECTS) R(VK_ERROR_FORMAT_NOT_SUPPORTED) R(VK_ERROR_FRAGMENTED_POOL)
    R(VK_ERROR_UNKNOWN) R(VK_ERROR_OUT_OF_POOL_MEMORY) R(VK_ERROR_INVALID_EXTERNAL_HANDLE)
    R(VK_ERROR_FRAGMENTATION) R(VK_ERROR_INVALID_OPAQUE_CAPTURE_ADDRESS)
    R(VK_PIPELINE_COMPILE_REQUIRED) R(VK_ERROR_SURFACE_LOST_KHR)
    R(VK_ERROR_NATIVE_WINDOW_IN_USE_KHR) R(VK_SUBOPTIMAL_KHR) R(VK_ERROR_OUT_OF_DATE_KHR)
    R(VK_ERROR_INCOMPATIBLE_DISPLAY_KHR) R(VK_ERROR_VALIDATION_FAILED_EXT)
    R(VK_ERROR_INVALID_SHADER_NV) R(VK_ERROR_NOT_PERMITTED_KHR)
#undef R
    default: return "unknown VkResult";
    }
}

/* "vkCreateDevice failed: VK_ERROR_..." (out-of-memory results: BTF_E_NOMEM). */
static int vk_fail(btf_error *err, VkResult r, const char *call)
{
    int code = (r == VK_ERROR_OUT_OF_HOST_MEMORY || r == VK_ERROR_OUT_OF_DEVICE_MEMORY)
                   ? BTF_E_NOMEM
                   : BTF_E_UNSUPPORTED;
    return btf_fail(err, code, "%s failed: %s (%d)", call, vk_result_name(r), (int)r);
}

/* The validation layer's messages: count errors and warnings, keep the first. */
static VKAPI_ATTR VkBool32 VKAPI_CALL on_message(
    VkDebugUtilsMessageSeverityFlagBitsEXT severity, VkDebugUtilsMessageTypeFlagsEXT types,
    const VkDebugUtilsMessengerCallbackDataEXT *data, void *user)
{
    (void)types;
    btf_vk *vk = user;
    if (!(severity & (VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT |
                      VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT)))
        return VK_FALSE;
    if (vk->n_messages++ == 0) {
        snprintf(vk->first_message, sizeof vk->first_message, "%s",
                 data && data->pMessage ? data->pMessage : "(no text)");
        for (char *p = vk->first_message; *p; p++)
            if (*p == '\n' || *p == '\r')
                *p = ' ';
    }
    return VK_FALSE;
}

static VkDebugUtilsMessengerCreateInfoEXT messenger_info(btf_vk *vk)
{
    VkDebugUtilsMessengerCreateInfoEXT mi = {
        .sType = VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT,
        .messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT |
                           VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT,
        .messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                       VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                       VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT,
        .pfnUserCallback = on_message,
        .pUserData = vk,
    };
    return mi;
}

/* ------------------------------------------------------- small helpers */

const char *btf_vk_type_name(int type)
{
    switch (type) {
    case BTF_VK_TYPE_DISCRETE_GPU: return "discrete GPU";
    case BTF_VK_TYPE_INTEGRATED_GPU: return "integrated GPU";
    case BTF_VK_TYPE_VIRTUAL_GPU: return "virtual GPU";
    case BTF_VK_TYPE_CPU: return "CPU";
    default: return "other";
    }
}

void btf_vk_version_text(uint32_t v, char *buf, size_t n)
{
    snprintf(buf, n, "%u.%u.%u", VK_API_VERSION_MAJOR(v), VK_API_VERSION_MINOR(v),
             VK_API_VERSION_PATCH(v));
}

/* ---------------------------------------------------------- instance */

static int has_layer(const char *name, int *found, btf_error *err)
{
    uint32_t n = 0;
    *found = 0;
    VkResult r = vkEnumerateInstanceLayerProperties(&n, NULL);
    if (r != VK_SUCCESS)
        return vk_fail(err, r, "vkEnumerateInstanceLayerProperties");
    VkLayerProperties *lp = btf_calloc(n, sizeof *lp, err);
    if (!lp)
        return BTF_E_NOMEM;
    r = vkEnumerateInstanceLayerProperties(&n, lp);
    for (uint32_t i = 0; r >= 0 && i < n; i++)
        *found |= !strcmp(lp[i].layerName, name);
    free(lp);
    if (r < 0)
        return vk_fail(err, r, "vkEnumerateInstanceLayerProperties");
    return BTF_OK;
}

/* 1 if the instance extension is offered by the loader/drivers or by layer. */
static int has_instance_extension(const char *layer, const char *name)
{
    uint32_t n = 0;
    if (vkEnumerateInstanceExtensionProperties(layer, &n, NULL) != VK_SUCCESS || n == 0)
        return 0;
    VkExtensionProperties *ep = calloc(n, sizeof *ep);
    if (!ep)
        return 0;
    int found = 0;
    if (vkEnumerateInstanceExtensionProperties(layer, &n, ep) >= 0)
        for (uint32_t i = 0; i < n; i++)
            found |= !strcmp(ep[i].extensionName, name);
    free(ep);
    return found;
}

/* The loader must speak Vulkan 1.1 (vkEnumerateInstanceVersion exists). */
static int check_loader(btf_error *err)
{
    PFN_vkEnumerateInstanceVersion ev =
        (PFN_vkEnumerateInstanceVersion)vkGetInstanceProcAddr(NULL, "vkEnumerateInstanceVersion");
    uint32_t v = VK_API_VERSION_1_0;
    if (ev && ev(&v) != VK_SUCCESS)
        v = VK_API_VERSION_1_0;
    if (v < NEED_API) {
        char t[32];
        btf_vk_version_text(v, t, sizeof t);
        return btf_fail(err, BTF_E_UNSUPPORTED,
                        "the Vulkan loader supports Vulkan %s; btfcar needs 1.1", t);
    }
    return BTF_OK;
}

/* The validation layer and the extensions it needs, or a clear error. */
static int check_validation_support(int *sync_validation, btf_error *err)
{
    int found;
    int rc = has_layer(VALIDATION_LAYER, &found, err);
    if (rc)
        return rc;
    if (!found)
        return btf_fail(err, BTF_E_UNSUPPORTED,
                        "Vulkan validation was requested (btf_vk_opts.validation) but the "
                        "layer %s is not installed (Debian: vulkan-validationlayers)",
                        VALIDATION_LAYER);
    if (!has_instance_extension(NULL, VK_EXT_DEBUG_UTILS_EXTENSION_NAME) &&
        !has_instance_extension(VALIDATION_LAYER, VK_EXT_DEBUG_UTILS_EXTENSION_NAME))
        return btf_fail(err, BTF_E_UNSUPPORTED,
                        "Vulkan validation needs the instance extension %s, which is missing",
                        VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
    *sync_validation = has_instance_extension(VALIDATION_LAYER,
                                              VK_EXT_VALIDATION_FEATURES_EXTENSION_NAME);
    return BTF_OK;
}

/* A Vulkan 1.1 instance; with vk != NULL and validation, the layer and a
 * messenger creation chain reporting to vk (also during create/destroy). */
static int make_instance(btf_vk *vk, int validation, VkInstance *out, btf_error *err)
{
    *out = VK_NULL_HANDLE;
    int rc = check_loader(err), sync = 0;
    if (rc)
        return rc;
    if (validation && (rc = check_validation_support(&sync, err)) != 0)
        return rc;
    VkApplicationInfo app = {
        .sType = VK_STRUCTURE_TYPE_APPLICATION_INFO,
        .pApplicationName = "btfcar",
        .applicationVersion = VK_MAKE_API_VERSION(0, BTF_VERSION_MAJOR, BTF_VERSION_MINOR,
                                                  BTF_VERSION_PATCH),
        .pEngineName = "btfcar",
        .apiVersion = NEED_API,
    };
    const char *layers[] = {VALIDATION_LAYER};
    const char *exts[] = {VK_EXT_DEBUG_UTILS_EXTENSION_NAME,
                          VK_EXT_VALIDATION_FEATURES_EXTENSION_NAME};
    VkDebugUtilsMessengerCreateInfoEXT mi = messenger_info(vk);
    VkValidationFeatureEnableEXT enables[] = {
        VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT};
    VkValidationFeaturesEXT vf = {
        .sType = VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT,
        .pNext = &mi,
        .enabledValidationFeatureCount = 1,
        .pEnabledValidationFeatures = enables,
    };
    VkInstanceCreateInfo ci = {
        .sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO,
        .pNext = validation ? (sync ? (const void *)&vf : (const void *)&mi) : NULL,
        .pApplicationInfo = &app,
        .enabledLayerCount = validation ? 1 : 0,
        .ppEnabledLayerNames = layers,
        .enabledExtensionCount = validation ? (sync ? 2 : 1) : 0,
        .ppEnabledExtensionNames = exts,
    };
    VkResult r = vkCreateInstance(&ci, NULL, out);
    if (r == VK_ERROR_INCOMPATIBLE_DRIVER)
        return btf_fail(err, BTF_E_UNSUPPORTED, NO_DEVICE_MSG);
    if (r != VK_SUCCESS) {
        *out = VK_NULL_HANDLE;
        return vk_fail(err, r, "vkCreateInstance");
    }
    return BTF_OK;
}

static int make_messenger(btf_vk *vk, btf_error *err)
{
    PFN_vkCreateDebugUtilsMessengerEXT create = (PFN_vkCreateDebugUtilsMessengerEXT)
        vkGetInstanceProcAddr(vk->instance, "vkCreateDebugUtilsMessengerEXT");
    if (!create)
        return btf_fail(err, BTF_E_UNSUPPORTED,
                        "vkGetInstanceProcAddr found no vkCreateDebugUtilsMessengerEXT");
    VkDebugUtilsMessengerCreateInfoEXT mi = messenger_info(vk);
    VkResult r = create(vk->instance, &mi, NULL, &vk->messenger);
    if (r != VK_SUCCESS) {
        vk->messenger = VK_NULL_HANDLE;
        return vk_fail(err, r, "vkCreateDebugUtilsMessengerEXT");
    }
    return BTF_OK;
}

/* All physical devices (malloc'd array); 0 devices is BTF_E_UNSUPPORTED. */
static int enumerate(VkInstance inst, VkPhysicalDevice **devs, int *count, btf_error *err)
{
    *devs = NULL;
    *count = 0;
    for (;;) {
        uint32_t n = 0;
        VkResult r = vkEnumeratePhysicalDevices(inst, &n, NULL);
        if (r != VK_SUCCESS)
            return r == VK_ERROR_INITIALIZATION_FAILED
                       ? btf_fail(err, BTF_E_UNSUPPORTED, NO_DEVICE_MSG)
                       : vk_fail(err, r, "vkEnumeratePhysicalDevices");
        if (n == 0)
            return btf_fail(err, BTF_E_UNSUPPORTED, NO_DEVICE_MSG);
        VkPhysicalDevice *d = btf_calloc(n, sizeof *d, err);
        if (!d)
            return BTF_E_NOMEM;
        r = vkEnumeratePhysicalDevices(inst, &n, d);
        if (r == VK_SUCCESS) {
            *devs = d;
            *count = (int)n;
            return BTF_OK;
        }
        free(d);
        if (r != VK_INCOMPLETE) /* VK_INCOMPLETE: a device appeared; ask again */
            return vk_fail(err, r, "vkEnumeratePhysicalDevices");
    }
}

/* The first queue family with compute, or -1. */
static int compute_family(VkPhysicalDevice p)
{
    uint32_t n = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(p, &n, NULL);
    VkQueueFamilyProperties q[64];
    if (n > 64)
        n = 64;
    vkGetPhysicalDeviceQueueFamilyProperties(p, &n, q);
    for (uint32_t i = 0; i < n; i++)
        if ((q[i].queueFlags & VK_QUEUE_COMPUTE_BIT) && q[i].queueCount > 0)
            return (int)i;
    return -1;
}

static void fill_info(VkPhysicalDevice p, int index, btf_vk_device_info *di)
{
    VkPhysicalDeviceProperties pr;
    vkGetPhysicalDeviceProperties(p, &pr);
    memset(di, 0, sizeof *di);
    di->index = index;
    snprintf(di->name, sizeof di->name, "%s", pr.deviceName);
    di->type = (int)pr.deviceType;
    di->is_cpu = pr.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU;
    di->vendor_id = pr.vendorID;
    di->device_id = pr.deviceID;
    di->api_version = pr.apiVersion;
    di->usable = pr.apiVersion >= NEED_API && compute_family(p) >= 0;
    const VkPhysicalDeviceLimits *l = &pr.limits;
    di->max_storage_buffer_range = l->maxStorageBufferRange;
    for (int i = 0; i < 3; i++) {
        di->max_workgroup_count[i] = l->maxComputeWorkGroupCount[i];
        di->max_workgroup_size[i] = l->maxComputeWorkGroupSize[i];
    }
    di->max_workgroup_invocations = l->maxComputeWorkGroupInvocations;
    di->max_push_constants_bytes = l->maxPushConstantsSize;
    di->max_storage_buffers = l->maxPerStageDescriptorStorageBuffers;
    if (pr.apiVersion >= NEED_API) { /* 1.1 properties */
        VkPhysicalDeviceMaintenance3Properties m3 = {
            .sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MAINTENANCE_3_PROPERTIES};
        VkPhysicalDeviceSubgroupProperties sg = {
            .sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES, .pNext = &m3};
        VkPhysicalDeviceProperties2 p2 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2,
                                          .pNext = &sg};
        vkGetPhysicalDeviceProperties2(p, &p2);
        di->subgroup_size = sg.subgroupSize;
        di->max_allocation_bytes = m3.maxMemoryAllocationSize;
    }
    VkPhysicalDeviceMemoryProperties mp;
    vkGetPhysicalDeviceMemoryProperties(p, &mp);
    for (uint32_t h = 0; h < mp.memoryHeapCount; h++)
        if ((mp.memoryHeaps[h].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT) &&
            mp.memoryHeaps[h].size > di->device_local_bytes)
            di->device_local_bytes = mp.memoryHeaps[h].size;
}

btf_status btf_vk_list_devices(btf_vk_device_info **list, int *count, btf_error *err)
{
    *list = NULL;
    *count = 0;
    VkInstance inst;
    int rc = make_instance(NULL, 0, &inst, err);
    if (rc)
        return rc;
    VkPhysicalDevice *devs;
    int n;
    rc = enumerate(inst, &devs, &n, err);
    if (rc == BTF_E_UNSUPPORTED && n == 0) { /* no device: an empty list */
        rc = BTF_OK;
        devs = NULL;
    }
    btf_vk_device_info *out = rc ? NULL : btf_calloc((size_t)n, sizeof *out, err);
    if (!rc && !out)
        rc = BTF_E_NOMEM;
    for (int i = 0; !rc && i < n; i++)
        fill_info(devs[i], i, &out[i]);
    free(devs);
    pin_vulkan_modules();
    vkDestroyInstance(inst, NULL);
    if (rc) {
        free(out);
        return rc;
    }
    *list = out;
    *count = n;
    return BTF_OK;
}

/* ------------------------------------------------------ device choice */

static int type_rank(int type)
{
    switch (type) {
    case BTF_VK_TYPE_DISCRETE_GPU: return 5;
    case BTF_VK_TYPE_INTEGRATED_GPU: return 4;
    case BTF_VK_TYPE_VIRTUAL_GPU: return 3;
    case BTF_VK_TYPE_CPU: return 2;
    default: return 1;
    }
}

/* A named device (btf_vk_opts.device): it must exist and run our shaders. */
static int named_device(const btf_vk_device_info *in, int n, int index, btf_error *err)
{
    if (index < 0 || index >= n)
        return btf_fail(err, BTF_E_ARG,
                        "Vulkan device %d does not exist (%d device%s: indices 0..%d; see "
                        "btfcar info --devices)",
                        index, n, n == 1 ? "" : "s", n - 1);
    if (!in[index].usable) {
        char v[32];
        btf_vk_version_text(in[index].api_version, v, sizeof v);
        return btf_fail(err, BTF_E_UNSUPPORTED,
                        "Vulkan device %d (%s, Vulkan %s) cannot run btfcar's shaders "
                        "(Vulkan 1.1 and a compute queue needed)",
                        index, in[index].name, v);
    }
    return BTF_OK;
}

/* The best usable device: discrete > integrated > virtual > CPU (if allowed)
 * > other; the first of equals. */
static int best_device(const btf_vk_device_info *in, int n, int allow_cpu, int *chosen,
                       btf_error *err)
{
    int best = -1, cpu = -1;
    for (int i = 0; i < n; i++) {
        if (!in[i].usable)
            continue;
        if (in[i].is_cpu && !allow_cpu) {
            cpu = cpu < 0 ? i : cpu;
            continue;
        }
        if (best < 0 || type_rank(in[i].type) > type_rank(in[best].type))
            best = i;
    }
    *chosen = best;
    if (best >= 0)
        return BTF_OK;
    if (cpu >= 0)
        return btf_fail(err, BTF_E_UNSUPPORTED,
                        "only a CPU Vulkan device was found (%d: %s); allow it "
                        "(btf_gpu_opts.allow_cpu) or name it (btf_gpu_opts.device = %d)",
                        cpu, in[cpu].name, cpu);
    return btf_fail(err, BTF_E_UNSUPPORTED,
                    "no usable Vulkan device (Vulkan 1.1 with a compute queue needed; %d "
                    "found, see btfcar info --devices)",
                    n);
}

static int choose_device(btf_vk *vk, const btf_vk_opts *o, btf_error *err)
{
    VkPhysicalDevice *devs;
    int n, chosen = -1;
    int rc = enumerate(vk->instance, &devs, &n, err);
    if (rc)
        return rc;
    btf_vk_device_info *in = btf_calloc((size_t)n, sizeof *in, err);
    rc = in ? BTF_OK : BTF_E_NOMEM;
    for (int i = 0; !rc && i < n; i++)
        fill_info(devs[i], i, &in[i]);
    if (!rc && o->use_device)
        rc = named_device(in, n, chosen = o->device, err);
    else if (!rc)
        rc = best_device(in, n, o->allow_cpu, &chosen, err);
    if (!rc) {
        vk->phys = devs[chosen];
        vk->info = in[chosen];
        vk->queue_family = (uint32_t)compute_family(vk->phys);
    }
    free(in);
    free(devs);
    return rc;
}

static int make_device(btf_vk *vk, btf_error *err)
{
    float prio = 1.0f;
    VkDeviceQueueCreateInfo qi = {
        .sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO,
        .queueFamilyIndex = vk->queue_family,
        .queueCount = 1,
        .pQueuePriorities = &prio,
    };
    VkDeviceCreateInfo di = {
        .sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO,
        .queueCreateInfoCount = 1,
        .pQueueCreateInfos = &qi,
    };
    VkResult r = vkCreateDevice(vk->phys, &di, NULL, &vk->device);
    if (r != VK_SUCCESS) {
        vk->device = VK_NULL_HANDLE;
        return vk_fail(err, r, "vkCreateDevice");
    }
    vkGetDeviceQueue(vk->device, vk->queue_family, 0, &vk->queue);
    VkCommandPoolCreateInfo pi = {
        .sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO,
        .flags = VK_COMMAND_POOL_CREATE_TRANSIENT_BIT,
        .queueFamilyIndex = vk->queue_family,
    };
    r = vkCreateCommandPool(vk->device, &pi, NULL, &vk->cmd_pool);
    if (r != VK_SUCCESS) {
        vk->cmd_pool = VK_NULL_HANDLE;
        return vk_fail(err, r, "vkCreateCommandPool");
    }
    VkFenceCreateInfo fi = {.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    r = vkCreateFence(vk->device, &fi, NULL, &vk->fence);
    if (r != VK_SUCCESS) {
        vk->fence = VK_NULL_HANDLE;
        return vk_fail(err, r, "vkCreateFence");
    }
    return BTF_OK;
}

/* ------------------------------------------------------- memory types */

/* memoryTypeBits of buffers with this usage (the same for every size). */
static int type_bits(btf_vk *vk, VkBufferUsageFlags usage, uint32_t *bits, btf_error *err)
{
    VkBufferCreateInfo bi = {.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO,
                             .size = 256,
                             .usage = usage,
                             .sharingMode = VK_SHARING_MODE_EXCLUSIVE};
    VkBuffer b;
    VkResult r = vkCreateBuffer(vk->device, &bi, NULL, &b);
    if (r != VK_SUCCESS)
        return vk_fail(err, r, "vkCreateBuffer");
    VkMemoryRequirements mr;
    vkGetBufferMemoryRequirements(vk->device, b, &mr);
    vkDestroyBuffer(vk->device, b, NULL);
    *bits = mr.memoryTypeBits;
    return BTF_OK;
}

/* The first (fastest) memory type among bits with all flags of need, on heap
 * (or any heap: -1); -1 if none. */
static int pick_type(const VkPhysicalDeviceMemoryProperties *m, uint32_t bits,
                     VkMemoryPropertyFlags need, int heap)
{
    for (uint32_t i = 0; i < m->memoryTypeCount; i++)
        if ((bits & (1u << i)) && (m->memoryTypes[i].propertyFlags & need) == need &&
            (heap < 0 || m->memoryTypes[i].heapIndex == (uint32_t)heap))
            return (int)i;
    return -1;
}

/* The largest device-local heap, or -1. */
static int main_heap(const VkPhysicalDeviceMemoryProperties *m)
{
    int h = -1;
    for (uint32_t i = 0; i < m->memoryHeapCount; i++)
        if ((m->memoryHeaps[i].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT) &&
            (h < 0 || m->memoryHeaps[i].size > m->memoryHeaps[h].size))
            h = (int)i;
    return h;
}

/* Storage buffers are mapped when host-visible, coherent memory is where the
 * shaders read fast: any such type on a CPU or integrated GPU (one memory),
 * on a discrete GPU only a device-local one on its main heap (resizable BAR;
 * not the small 256 MiB window). Otherwise device-local memory and staging
 * buffers (host-visible, coherent; cached for downloads where offered). */
static int choose_memory(btf_vk *vk, int force_staging, btf_error *err)
{
    const VkMemoryPropertyFlags hv = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT |
                                     VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    const VkMemoryPropertyFlags dl = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
    vkGetPhysicalDeviceMemoryProperties(vk->phys, &vk->mem);
    uint32_t bits, sbits;
    int rc = type_bits(vk, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT |
                               VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
                               VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                       &bits, err);
    if (rc || (rc = type_bits(vk, VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
                                      VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                              &sbits, err)) != 0)
        return rc;
    int uma = vk->info.type == BTF_VK_TYPE_CPU || vk->info.type == BTF_VK_TYPE_INTEGRATED_GPU;
    int t = -1;
    if (!force_staging) {
        t = pick_type(&vk->mem, bits, dl | hv, uma ? -1 : main_heap(&vk->mem));
        if (t < 0 && uma)
            t = pick_type(&vk->mem, bits, hv, -1);
    }
    vk->info.mapped_buffers = t >= 0;
    if (t < 0)
        t = pick_type(&vk->mem, bits, dl, -1);
    if (t < 0)
        t = pick_type(&vk->mem, bits, 0, -1);
    int up = pick_type(&vk->mem, sbits, hv, -1);
    int down = pick_type(&vk->mem, sbits, hv | VK_MEMORY_PROPERTY_HOST_CACHED_BIT, -1);
    if (t < 0 || (!vk->info.mapped_buffers && up < 0))
        return btf_fail(err, BTF_E_UNSUPPORTED,
                        "Vulkan device %s offers no memory type for %s buffers", vk->info.name,
                        t < 0 ? "storage" : "host-visible staging");
    vk->storage_type = (uint32_t)t;
    if (!vk->info.mapped_buffers) {
        vk->upload_type = (uint32_t)up;
        vk->download_type = (uint32_t)(down >= 0 ? down : up);
    }
    return BTF_OK;
}

/* ------------------------------------------------------------ context */

btf_status btf_vk_create(const btf_vk_opts *o, btf_vk **out, btf_error *err)
{
    static const btf_vk_opts defaults;
    *out = NULL;
    if (!o)
        o = &defaults;
    btf_vk *vk = btf_calloc(1, sizeof *vk, err);
    if (!vk)
        return BTF_E_NOMEM;
    int rc;
    vk->validation = o->validation;
    vk->timeout_ms = o->timeout_ms ? o->timeout_ms : DEFAULT_TIMEOUT_MS;
    vk->timeout_ns = (uint64_t)vk->timeout_ms * 1000000u;
    rc = make_instance(vk, vk->validation, &vk->instance, err);
    if (!rc && vk->validation)
        rc = make_messenger(vk, err);
    if (!rc)
        rc = choose_device(vk, o, err);
    if (!rc)
        rc = make_device(vk, err);
    if (!rc)
        rc = choose_memory(vk, o->force_staging, err);
    if (rc) {
        btf_vk_destroy(vk);
        return rc;
    }
    *out = vk;
    return BTF_OK;
}

static void job_free(btf_vk_job *job);

/* After a timeout: wait for the job that did not finish and free it, so
 * that what it uses can be destroyed (the context stays unusable). */
static void settle(btf_vk *vk)
{
    if (vk->stuck) {
        vkDeviceWaitIdle(vk->device);
        job_free(vk->stuck);
        vk->stuck = NULL;
    }
}

unsigned btf_vk_destroy_checked(btf_vk *vk, char *first_message, size_t n)
{
    if (first_message && n)
        first_message[0] = '\0';
    if (!vk)
        return 0;
    if (vk->device) {
        vkDeviceWaitIdle(vk->device);
        settle(vk);
        if (vk->fence)
            vkDestroyFence(vk->device, vk->fence, NULL);
        if (vk->cmd_pool)
            vkDestroyCommandPool(vk->device, vk->cmd_pool, NULL);
        vkDestroyDevice(vk->device, NULL);
    }
    if (vk->messenger) {
        PFN_vkDestroyDebugUtilsMessengerEXT destroy = (PFN_vkDestroyDebugUtilsMessengerEXT)
            vkGetInstanceProcAddr(vk->instance, "vkDestroyDebugUtilsMessengerEXT");
        if (destroy)
            destroy(vk->instance, vk->messenger, NULL);
    }
    if (vk->instance) { /* the messenger given at creation still reports here */
        pin_vulkan_modules();
        vkDestroyInstance(vk->instance, NULL);
    }
    unsigned count = vk->n_messages;
    if (first_message && n)
        snprintf(first_message, n, "%s", vk->first_message);
    free(vk);
    return count;
}

void btf_vk_destroy(btf_vk *vk)
{
    btf_vk_destroy_checked(vk, NULL, 0);
}

const btf_vk_device_info *btf_vk_info(const btf_vk *vk)
{
    return &vk->info;
}

int btf_vk_validating(const btf_vk *vk)
{
    return vk->validation;
}

unsigned btf_vk_validation_errors(const btf_vk *vk)
{
    return vk->n_messages;
}

const char *btf_vk_first_validation_message(const btf_vk *vk)
{
    return vk->first_message;
}

/* BTF_OK, or the reason this context can no longer be used. */
static int check_usable(const btf_vk *vk, btf_error *err)
{
    if (vk->broken[0])
        return btf_fail(err, BTF_E_UNSUPPORTED, "%s", vk->broken);
    return BTF_OK;
}

/* ------------------------------------------------------------ buffers */

/* Allocates and binds memory of type for b (and maps it when map). */
static int bind_memory(btf_vk *vk, btf_vk_buffer *b, uint32_t type, int map, btf_error *err)
{
    VkMemoryRequirements mr;
    vkGetBufferMemoryRequirements(vk->device, b->buffer, &mr);
    if (!(mr.memoryTypeBits & (1u << type)))
        return btf_fail(err, BTF_E_UNSUPPORTED,
                        "vkGetBufferMemoryRequirements: memory type %u not allowed for a "
                        "buffer of %llu bytes",
                        type, (unsigned long long)b->size);
    uint32_t heap = vk->mem.memoryTypes[type].heapIndex;
    VkDeviceSize heap_size = vk->mem.memoryHeaps[heap].size;
    if (mr.size > heap_size)
        return btf_fail(err, BTF_E_NOMEM,
                        "a Vulkan buffer of %llu bytes does not fit in memory heap %u of %s "
                        "(%llu bytes)",
                        (unsigned long long)mr.size, heap, vk->info.name,
                        (unsigned long long)heap_size);
    if (vk->info.max_allocation_bytes && mr.size > vk->info.max_allocation_bytes)
        return btf_fail(err, BTF_E_NOMEM,
                        "a Vulkan buffer of %llu bytes exceeds maxMemoryAllocationSize "
                        "(%llu bytes) of %s",
                        (unsigned long long)mr.size,
                        (unsigned long long)vk->info.max_allocation_bytes, vk->info.name);
    VkMemoryAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO,
                               .allocationSize = mr.size,
                               .memoryTypeIndex = type};
    VkResult r = vkAllocateMemory(vk->device, &ai, NULL, &b->memory);
    if (r != VK_SUCCESS) {
        b->memory = VK_NULL_HANDLE;
        return btf_fail(err, BTF_E_NOMEM,
                        "vkAllocateMemory of %llu bytes failed: %s (heap %u: %llu bytes, "
                        "%llu of them already allocated by btfcar)",
                        (unsigned long long)mr.size, vk_result_name(r), heap,
                        (unsigned long long)heap_size,
                        (unsigned long long)vk->heap_used[heap]);
    }
    b->alloc_size = mr.size;
    b->heap = heap;
    vk->heap_used[heap] += mr.size;
    if ((r = vkBindBufferMemory(vk->device, b->buffer, b->memory, 0)) != VK_SUCCESS)
        return vk_fail(err, r, "vkBindBufferMemory");
    if (map && (r = vkMapMemory(vk->device, b->memory, 0, VK_WHOLE_SIZE, 0, &b->mapped)) !=
                   VK_SUCCESS) {
        b->mapped = NULL;
        return vk_fail(err, r, "vkMapMemory");
    }
    return BTF_OK;
}

static void buffer_free(btf_vk_buffer *b)
{
    if (!b)
        return;
    btf_vk *vk = b->vk;
    settle(vk);
    if (b->buffer)
        vkDestroyBuffer(vk->device, b->buffer, NULL);
    if (b->memory) {
        if (b->mapped)
            vkUnmapMemory(vk->device, b->memory);
        vkFreeMemory(vk->device, b->memory, NULL);
        vk->heap_used[b->heap] -= b->alloc_size;
    }
    free(b);
}

static int buffer_make(btf_vk *vk, VkDeviceSize bytes, VkBufferUsageFlags usage, uint32_t type,
                       int map, btf_vk_buffer **out, btf_error *err)
{
    *out = NULL;
    btf_vk_buffer *b = btf_calloc(1, sizeof *b, err);
    if (!b)
        return BTF_E_NOMEM;
    b->vk = vk;
    b->size = bytes;
    VkBufferCreateInfo bi = {.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO,
                             .size = bytes,
                             .usage = usage,
                             .sharingMode = VK_SHARING_MODE_EXCLUSIVE};
    VkResult r = vkCreateBuffer(vk->device, &bi, NULL, &b->buffer);
    int rc = BTF_OK;
    if (r != VK_SUCCESS) {
        b->buffer = VK_NULL_HANDLE;
        rc = vk_fail(err, r, "vkCreateBuffer");
    }
    if (!rc)
        rc = bind_memory(vk, b, type, map, err);
    if (rc) {
        buffer_free(b);
        return rc;
    }
    *out = b;
    return BTF_OK;
}

btf_status btf_vk_buffer_create(btf_vk *vk, uint64_t bytes, btf_vk_buffer **out, btf_error *err)
{
    *out = NULL;
    int rc = check_usable(vk, err);
    if (rc)
        return rc;
    if (bytes == 0 || bytes > vk->info.max_storage_buffer_range)
        return btf_fail(err, BTF_E_ARG,
                        "a Vulkan storage buffer of %llu bytes: %s holds 1 to %llu bytes "
                        "(maxStorageBufferRange; larger data must be split)",
                        (unsigned long long)bytes, vk->info.name,
                        (unsigned long long)vk->info.max_storage_buffer_range);
    return buffer_make(vk, bytes,
                       VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
                           VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                       vk->storage_type, vk->info.mapped_buffers, out, err);
}

void btf_vk_buffer_destroy(btf_vk_buffer *buf)
{
    buffer_free(buf);
}

uint64_t btf_vk_buffer_size(const btf_vk_buffer *buf)
{
    return buf->size;
}

void *btf_vk_buffer_mapped(btf_vk_buffer *buf)
{
    return buf->mapped;
}

/* [offset, offset + bytes) lies inside the buffer (overflow-safe). */
static int check_range(const btf_vk_buffer *b, uint64_t offset, uint64_t bytes,
                       const char *what, btf_error *err)
{
    if (offset > b->size || bytes > b->size - offset)
        return btf_fail(err, BTF_E_ARG,
                        "%s: bytes %llu..%llu are outside the Vulkan buffer of %llu bytes",
                        what, (unsigned long long)offset,
                        (unsigned long long)offset + (unsigned long long)bytes,
                        (unsigned long long)b->size);
    return BTF_OK;
}

static void record_copy(btf_vk_job *job, VkBuffer src, uint64_t src_off, VkBuffer dst,
                        uint64_t dst_off, uint64_t bytes);

/* One staging copy of bytes (<= the staging size): to the buffer (up) or
 * from it. */
static int staged_copy(btf_vk *vk, btf_vk_buffer *stage, VkBuffer buf, uint64_t offset,
                       uint64_t bytes, int up, btf_error *err)
{
    btf_vk_job *job;
    int rc = btf_vk_job_begin(vk, &job, err);
    if (rc)
        return rc;
    if (up)
        record_copy(job, stage->buffer, 0, buf, offset, bytes);
    else
        record_copy(job, buf, offset, stage->buffer, 0, bytes);
    return btf_vk_job_submit_wait(job, err);
}

/* Upload (up) or download through a staging buffer, STAGING_CHUNK at a time. */
static int staged(btf_vk *vk, VkBuffer buf, uint64_t offset, unsigned char *host,
                  uint64_t bytes, int up, btf_error *err)
{
    btf_vk_buffer *stage;
    VkDeviceSize chunk = bytes < STAGING_CHUNK ? bytes : STAGING_CHUNK;
    int rc = buffer_make(vk, chunk,
                         VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                         up ? vk->upload_type : vk->download_type, 1, &stage, err);
    for (uint64_t done = 0; !rc && done < bytes; done += chunk) {
        uint64_t n = bytes - done < chunk ? bytes - done : chunk;
        if (up)
            memcpy(stage->mapped, host + done, n);
        rc = staged_copy(vk, stage, buf, offset + done, n, up, err);
        if (!rc && !up)
            memcpy(host + done, stage->mapped, n);
    }
    buffer_free(stage);
    return rc;
}

btf_status btf_vk_buffer_upload(btf_vk *vk, btf_vk_buffer *buf, uint64_t offset, const void *data,
                         uint64_t bytes, btf_error *err)
{
    int rc = check_usable(vk, err);
    if (!rc)
        rc = check_range(buf, offset, bytes, "btf_vk_buffer_upload", err);
    if (rc || bytes == 0)
        return rc;
    if (buf->mapped) {
        memcpy((unsigned char *)buf->mapped + offset, data, bytes);
        return BTF_OK;
    }
    return staged(vk, buf->buffer, offset, (unsigned char *)(uintptr_t)data, bytes, 1, err);
}

btf_status btf_vk_buffer_download(btf_vk *vk, const btf_vk_buffer *buf, uint64_t offset, void *data,
                           uint64_t bytes, btf_error *err)
{
    int rc = check_usable(vk, err);
    if (!rc)
        rc = check_range(buf, offset, bytes, "btf_vk_buffer_download", err);
    if (rc || bytes == 0)
        return rc;
    if (buf->mapped) {
        memcpy(data, (const unsigned char *)buf->mapped + offset, bytes);
        return BTF_OK;
    }
    return staged(vk, buf->buffer, offset, data, bytes, 0, err);
}

/* ---------------------------------------------------------- pipelines */

static int check_pipeline_args(const btf_vk *vk, const uint32_t *spirv, size_t spirv_bytes,
                               int n_buffers, uint32_t push_bytes, const uint32_t *spec,
                               int n_spec, btf_error *err)
{
    if (!spirv || spirv_bytes < 20 || spirv_bytes % 4 || spirv[0] != 0x07230203u)
        return btf_fail(err, BTF_E_ARG,
                        "btf_vk_pipeline_create: not a SPIR-V module (%zu bytes)", spirv_bytes);
    int max_buffers = (int)(vk->info.max_storage_buffers < BTF_VK_MAX_BUFFERS
                                ? vk->info.max_storage_buffers
                                : BTF_VK_MAX_BUFFERS);
    if (n_buffers < 0 || n_buffers > max_buffers)
        return btf_fail(err, BTF_E_ARG,
                        "btf_vk_pipeline_create: %d storage buffers (0..%d allowed on %s)",
                        n_buffers, max_buffers, vk->info.name);
    if (push_bytes % 4 || push_bytes > vk->info.max_push_constants_bytes)
        return btf_fail(err, BTF_E_ARG,
                        "btf_vk_pipeline_create: %u push constant bytes (a multiple of 4, at "
                        "most maxPushConstantsSize = %u)",
                        push_bytes, vk->info.max_push_constants_bytes);
    if (n_spec < 0 || n_spec > BTF_VK_MAX_SPEC || (n_spec > 0 && !spec))
        return btf_fail(err, BTF_E_ARG,
                        "btf_vk_pipeline_create: %d specialisation constants (0..%d, values "
                        "given)",
                        n_spec, BTF_VK_MAX_SPEC);
    return BTF_OK;
}

static int make_layouts(btf_vk_pipeline *p, uint32_t push_bytes, btf_error *err)
{
    VkDevice dev = p->vk->device;
    VkDescriptorSetLayoutBinding b[BTF_VK_MAX_BUFFERS];
    for (int i = 0; i < p->n_buffers; i++)
        b[i] = (VkDescriptorSetLayoutBinding){.binding = (uint32_t)i,
                                              .descriptorType =
                                                  VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                                              .descriptorCount = 1,
                                              .stageFlags = VK_SHADER_STAGE_COMPUTE_BIT};
    VkDescriptorSetLayoutCreateInfo si = {
        .sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO,
        .bindingCount = (uint32_t)p->n_buffers,
        .pBindings = b,
    };
    VkResult r = vkCreateDescriptorSetLayout(dev, &si, NULL, &p->set_layout);
    if (r != VK_SUCCESS) {
        p->set_layout = VK_NULL_HANDLE;
        return vk_fail(err, r, "vkCreateDescriptorSetLayout");
    }
    VkPushConstantRange pr = {.stageFlags = VK_SHADER_STAGE_COMPUTE_BIT, .size = push_bytes};
    VkPipelineLayoutCreateInfo li = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO,
        .setLayoutCount = 1,
        .pSetLayouts = &p->set_layout,
        .pushConstantRangeCount = push_bytes ? 1 : 0,
        .pPushConstantRanges = &pr,
    };
    r = vkCreatePipelineLayout(dev, &li, NULL, &p->layout);
    if (r != VK_SUCCESS) {
        p->layout = VK_NULL_HANDLE;
        return vk_fail(err, r, "vkCreatePipelineLayout");
    }
    return BTF_OK;
}

static int make_pipeline(btf_vk_pipeline *p, const uint32_t *spirv, size_t spirv_bytes,
                         const uint32_t *spec, int n_spec, btf_error *err)
{
    VkDevice dev = p->vk->device;
    VkShaderModuleCreateInfo mi = {.sType = VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO,
                                   .codeSize = spirv_bytes,
                                   .pCode = spirv};
    VkShaderModule module;
    VkResult r = vkCreateShaderModule(dev, &mi, NULL, &module);
    if (r != VK_SUCCESS)
        return vk_fail(err, r, "vkCreateShaderModule");
    VkSpecializationMapEntry map[BTF_VK_MAX_SPEC];
    for (int i = 0; i < n_spec; i++)
        map[i] = (VkSpecializationMapEntry){
            .constantID = (uint32_t)i, .offset = 4u * (uint32_t)i, .size = 4};
    VkSpecializationInfo spi = {.mapEntryCount = (uint32_t)n_spec,
                                .pMapEntries = map,
                                .dataSize = 4u * (size_t)n_spec,
                                .pData = spec};
    VkComputePipelineCreateInfo ci = {
        .sType = VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO,
        .stage = {.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO,
                  .stage = VK_SHADER_STAGE_COMPUTE_BIT,
                  .module = module,
                  .pName = "main",
                  .pSpecializationInfo = n_spec ? &spi : NULL},
        .layout = p->layout,
    };
    r = vkCreateComputePipelines(dev, VK_NULL_HANDLE, 1, &ci, NULL, &p->pipeline);
    vkDestroyShaderModule(dev, module, NULL);
    if (r != VK_SUCCESS) {
        p->pipeline = VK_NULL_HANDLE;
        return vk_fail(err, r, "vkCreateComputePipelines");
    }
    return BTF_OK;
}

btf_status btf_vk_pipeline_create(btf_vk *vk, const uint32_t *spirv, size_t spirv_bytes,
                           int n_buffers, uint32_t push_constant_bytes,
                           const uint32_t *spec_values, int n_spec, btf_vk_pipeline **out,
                           btf_error *err)
{
    *out = NULL;
    int rc = check_usable(vk, err);
    if (!rc)
        rc = check_pipeline_args(vk, spirv, spirv_bytes, n_buffers, push_constant_bytes,
                                 spec_values, n_spec, err);
    if (rc)
        return rc;
    btf_vk_pipeline *p = btf_calloc(1, sizeof *p, err);
    if (!p)
        return BTF_E_NOMEM;
    p->vk = vk;
    p->n_buffers = n_buffers;
    p->push_bytes = push_constant_bytes;
    rc = make_layouts(p, push_constant_bytes, err);
    if (!rc)
        rc = make_pipeline(p, spirv, spirv_bytes, spec_values, n_spec, err);
    if (rc) {
        btf_vk_pipeline_destroy(p);
        return rc;
    }
    *out = p;
    return BTF_OK;
}

void btf_vk_pipeline_destroy(btf_vk_pipeline *p)
{
    if (!p)
        return;
    settle(p->vk);
    VkDevice dev = p->vk->device;
    if (p->pipeline)
        vkDestroyPipeline(dev, p->pipeline, NULL);
    if (p->layout)
        vkDestroyPipelineLayout(dev, p->layout, NULL);
    if (p->set_layout)
        vkDestroyDescriptorSetLayout(dev, p->set_layout, NULL);
    free(p);
}

/* --------------------------------------------------------------- jobs */

static void job_free(btf_vk_job *job)
{
    if (!job)
        return;
    VkDevice dev = job->vk->device;
    for (int i = 0; i < job->n_pools; i++)
        vkDestroyDescriptorPool(dev, job->pools[i], NULL);
    free(job->pools);
    if (job->cmd)
        vkFreeCommandBuffers(dev, job->vk->cmd_pool, 1, &job->cmd);
    free(job);
}

btf_status btf_vk_job_begin(btf_vk *vk, btf_vk_job **out, btf_error *err)
{
    *out = NULL;
    int rc = check_usable(vk, err);
    if (rc)
        return rc;
    btf_vk_job *job = btf_calloc(1, sizeof *job, err);
    if (!job)
        return BTF_E_NOMEM;
    job->vk = vk;
    VkCommandBufferAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO,
                                      .commandPool = vk->cmd_pool,
                                      .level = VK_COMMAND_BUFFER_LEVEL_PRIMARY,
                                      .commandBufferCount = 1};
    VkResult r = vkAllocateCommandBuffers(vk->device, &ai, &job->cmd);
    if (r != VK_SUCCESS) {
        job->cmd = VK_NULL_HANDLE;
        job_free(job);
        return vk_fail(err, r, "vkAllocateCommandBuffers");
    }
    VkCommandBufferBeginInfo bi = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO,
                                   .flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT};
    if ((r = vkBeginCommandBuffer(job->cmd, &bi)) != VK_SUCCESS) {
        job_free(job);
        return vk_fail(err, r, "vkBeginCommandBuffer");
    }
    *out = job;
    return BTF_OK;
}

void btf_vk_job_abort(btf_vk_job *job)
{
    job_free(job);
}

/* After a command: its writes are made available and visible to later
 * shaders, transfers and the host; later writes wait for its reads. */
static void barrier_after(VkCommandBuffer cmd, VkPipelineStageFlags stage, VkAccessFlags writes)
{
    VkMemoryBarrier mb = {
        .sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER,
        .srcAccessMask = writes,
        .dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT |
                         VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT |
                         VK_ACCESS_HOST_READ_BIT,
    };
    vkCmdPipelineBarrier(cmd, stage,
                         VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT |
                             VK_PIPELINE_STAGE_HOST_BIT,
                         0, 1, &mb, 0, NULL, 0, NULL);
}

/* Room in the job's descriptor pools for one set of n buffers: pools grow
 * (64, 128, ... 4096 sets of up to 8 buffers each). */
static int reserve_set(btf_vk_job *job, uint32_t n, btf_error *err)
{
    if (job->sets_left >= 1 && job->descriptors_left >= n)
        return BTF_OK;
    if (job->n_pools == job->cap_pools) {
        int cap = job->cap_pools ? 2 * job->cap_pools : 4;
        VkDescriptorPool *np = realloc(job->pools, (size_t)cap * sizeof *np);
        if (!np)
            return btf_fail(err, BTF_E_NOMEM, "out of memory for Vulkan descriptor pools");
        job->pools = np;
        job->cap_pools = cap;
    }
    uint32_t sets = 64u << (job->n_pools < 6 ? job->n_pools : 6);
    uint32_t per = n > 8 ? n : 8;
    VkDescriptorPoolSize size = {.type = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                                 .descriptorCount = sets * per};
    VkDescriptorPoolCreateInfo pi = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO,
                                     .maxSets = sets,
                                     .poolSizeCount = 1,
                                     .pPoolSizes = &size};
    VkResult r = vkCreateDescriptorPool(job->vk->device, &pi, NULL, &job->pools[job->n_pools]);
    if (r != VK_SUCCESS)
        return vk_fail(err, r, "vkCreateDescriptorPool");
    job->n_pools++;
    job->sets_left = sets;
    job->descriptors_left = sets * per;
    return BTF_OK;
}

/* A descriptor set with bufs at bindings 0..n-1. */
static int make_set(btf_vk_job *job, const btf_vk_pipeline *pipe, btf_vk_buffer *const *bufs,
                    VkDescriptorSet *set, btf_error *err)
{
    uint32_t n = (uint32_t)pipe->n_buffers;
    int rc = reserve_set(job, n, err);
    if (rc)
        return rc;
    VkDescriptorSetAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO,
                                      .descriptorPool = job->pools[job->n_pools - 1],
                                      .descriptorSetCount = 1,
                                      .pSetLayouts = &pipe->set_layout};
    VkResult r = vkAllocateDescriptorSets(job->vk->device, &ai, set);
    if (r != VK_SUCCESS)
        return vk_fail(err, r, "vkAllocateDescriptorSets");
    job->sets_left--;
    job->descriptors_left -= n;
    VkDescriptorBufferInfo bi[BTF_VK_MAX_BUFFERS];
    VkWriteDescriptorSet w[BTF_VK_MAX_BUFFERS];
    for (uint32_t i = 0; i < n; i++) {
        bi[i] = (VkDescriptorBufferInfo){.buffer = bufs[i]->buffer, .range = VK_WHOLE_SIZE};
        w[i] = (VkWriteDescriptorSet){.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET,
                                      .dstSet = *set,
                                      .dstBinding = i,
                                      .descriptorCount = 1,
                                      .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                                      .pBufferInfo = &bi[i]};
    }
    vkUpdateDescriptorSets(job->vk->device, n, w, 0, NULL);
    return BTF_OK;
}

static int check_dispatch(const btf_vk_job *job, const btf_vk_pipeline *pipe,
                          btf_vk_buffer *const *bufs, int nbufs, const void *push,
                          uint32_t push_bytes, const uint32_t g[3], btf_error *err)
{
    const btf_vk_device_info *in = &job->vk->info;
    if (pipe->vk != job->vk)
        return btf_fail(err, BTF_E_ARG, "btf_vk_job_dispatch: pipeline of another context");
    if (nbufs != pipe->n_buffers || (nbufs > 0 && !bufs))
        return btf_fail(err, BTF_E_ARG,
                        "btf_vk_job_dispatch: %d buffers given, the pipeline binds %d", nbufs,
                        pipe->n_buffers);
    for (int i = 0; i < nbufs; i++)
        if (!bufs[i] || bufs[i]->vk != job->vk)
            return btf_fail(err, BTF_E_ARG, "btf_vk_job_dispatch: buffer %d is %s", i,
                            bufs[i] ? "of another context" : "NULL");
    if (push_bytes != pipe->push_bytes || (push_bytes && !push))
        return btf_fail(err, BTF_E_ARG,
                        "btf_vk_job_dispatch: %u push constant bytes given, the pipeline "
                        "declares %u",
                        push_bytes, pipe->push_bytes);
    for (int i = 0; i < 3; i++)
        if (g[i] > in->max_workgroup_count[i])
            return btf_fail(err, BTF_E_ARG,
                            "btf_vk_job_dispatch: %u x %u x %u workgroups exceed "
                            "maxComputeWorkGroupCount %u x %u x %u of %s",
                            g[0], g[1], g[2], in->max_workgroup_count[0],
                            in->max_workgroup_count[1], in->max_workgroup_count[2], in->name);
    return BTF_OK;
}

btf_status btf_vk_job_dispatch(btf_vk_job *job, const btf_vk_pipeline *pipe,
                        btf_vk_buffer *const *bufs, int nbufs, const void *push,
                        uint32_t push_bytes, uint32_t gx, uint32_t gy, uint32_t gz,
                        btf_error *err)
{
    const uint32_t g[3] = {gx, gy, gz};
    int rc = check_usable(job->vk, err);
    if (!rc)
        rc = check_dispatch(job, pipe, bufs, nbufs, push, push_bytes, g, err);
    if (rc || gx == 0 || gy == 0 || gz == 0)
        return rc;
    VkDescriptorSet set = VK_NULL_HANDLE;
    if (nbufs > 0 && (rc = make_set(job, pipe, bufs, &set, err)) != 0)
        return rc;
    VkCommandBuffer cmd = job->cmd;
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipe->pipeline);
    if (nbufs > 0)
        vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipe->layout, 0, 1, &set, 0,
                                NULL);
    if (push_bytes)
        vkCmdPushConstants(cmd, pipe->layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, push_bytes, push);
    vkCmdDispatch(cmd, gx, gy, gz);
    barrier_after(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT);
    return BTF_OK;
}

btf_status btf_vk_job_fill(btf_vk_job *job, btf_vk_buffer *buf, uint64_t offset, uint64_t bytes,
                    uint32_t value, btf_error *err)
{
    int rc = check_usable(job->vk, err);
    if (!rc && buf->vk != job->vk)
        rc = btf_fail(err, BTF_E_ARG, "btf_vk_job_fill: buffer of another context");
    if (!rc)
        rc = check_range(buf, offset, bytes, "btf_vk_job_fill", err);
    if (!rc && (offset % 4 || bytes % 4))
        rc = btf_fail(err, BTF_E_ARG,
                      "btf_vk_job_fill: offset %llu and size %llu must be multiples of 4",
                      (unsigned long long)offset, (unsigned long long)bytes);
    if (rc || bytes == 0)
        return rc;
    vkCmdFillBuffer(job->cmd, buf->buffer, offset, bytes, value);
    barrier_after(job->cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT);
    return BTF_OK;
}

static void record_copy(btf_vk_job *job, VkBuffer src, uint64_t src_off, VkBuffer dst,
                        uint64_t dst_off, uint64_t bytes)
{
    VkBufferCopy region = {.srcOffset = src_off, .dstOffset = dst_off, .size = bytes};
    vkCmdCopyBuffer(job->cmd, src, dst, 1, &region);
    barrier_after(job->cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT);
}

btf_status btf_vk_job_copy(btf_vk_job *job, const btf_vk_buffer *src, uint64_t src_offset,
                    btf_vk_buffer *dst, uint64_t dst_offset, uint64_t bytes, btf_error *err)
{
    int rc = check_usable(job->vk, err);
    if (!rc && (src->vk != job->vk || dst->vk != job->vk))
        rc = btf_fail(err, BTF_E_ARG, "btf_vk_job_copy: buffer of another context");
    if (!rc)
        rc = check_range(src, src_offset, bytes, "btf_vk_job_copy (source)", err);
    if (!rc)
        rc = check_range(dst, dst_offset, bytes, "btf_vk_job_copy (destination)", err);
    if (!rc && src == dst && src_offset < dst_offset + bytes && dst_offset < src_offset + bytes)
        rc = btf_fail(err, BTF_E_ARG, "btf_vk_job_copy: source and destination overlap");
    if (rc || bytes == 0)
        return rc;
    record_copy(job, src->buffer, src_offset, dst->buffer, dst_offset, bytes);
    return BTF_OK;
}

/* A timeout or a lost device: the job may still run, so it is kept for
 * btf_vk_destroy and the context refuses further work. */
static int job_stuck(btf_vk_job *job, VkResult r, btf_error *err)
{
    btf_vk *vk = job->vk;
    vk->stuck = job;
    if (r == VK_TIMEOUT)
        snprintf(vk->broken, sizeof vk->broken,
                 "vkWaitForFences: a Vulkan job on %s did not finish within %u ms "
                 "(VK_TIMEOUT); the Vulkan context is unusable now",
                 vk->info.name, vk->timeout_ms);
    else
        snprintf(vk->broken, sizeof vk->broken,
                 "vkWaitForFences failed: %s (%d) on %s; the Vulkan context is unusable now",
                 vk_result_name(r), (int)r, vk->info.name);
    return btf_fail(err, BTF_E_UNSUPPORTED, "%s", vk->broken);
}

btf_status btf_vk_job_submit_wait(btf_vk_job *job, btf_error *err)
{
    btf_vk *vk = job->vk;
    int rc = check_usable(vk, err);
    if (rc) {
        job_free(job);
        return rc;
    }
    VkResult r = vkEndCommandBuffer(job->cmd);
    if (r != VK_SUCCESS) {
        job_free(job);
        return vk_fail(err, r, "vkEndCommandBuffer");
    }
    if ((r = vkResetFences(vk->device, 1, &vk->fence)) != VK_SUCCESS) {
        job_free(job);
        return vk_fail(err, r, "vkResetFences");
    }
    VkSubmitInfo si = {.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO,
                       .commandBufferCount = 1,
                       .pCommandBuffers = &job->cmd};
    r = vkQueueSubmit(vk->queue, 1, &si, vk->fence);
    if (r == VK_ERROR_DEVICE_LOST)
        return job_stuck(job, r, err);
    if (r != VK_SUCCESS) {
        job_free(job);
        return vk_fail(err, r, "vkQueueSubmit");
    }
    r = vkWaitForFences(vk->device, 1, &vk->fence, VK_TRUE, vk->timeout_ns);
    if (r != VK_SUCCESS)
        return job_stuck(job, r, err);
    job_free(job);
    return BTF_OK;
}
