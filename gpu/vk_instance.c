/*
 * vk_instance.c — the bottom of the Vulkan compute layer (gpu/vk.h; the
 * files: gpu/vk_internal.h): the loader check, the instance with the
 * optional validation layer and the messenger counting its messages, the
 * device list (btf__vk_list_devices) and the choice of one device, the
 * logical device with its compute queue, command pool and fence, and the
 * one-line messages every Vulkan failure of the layer becomes.
 */
#if defined(__SANITIZE_ADDRESS__) && !defined(_GNU_SOURCE)
#define _GNU_SOURCE /* dl_iterate_phdr, RTLD_NODELETE: sanitizer builds only, see below */
#endif
#include <stdio.h>
#include "vk_internal.h"

#include "core/core.h"

#include <stdlib.h>
#include <string.h>

#if defined(__SANITIZE_ADDRESS__)
#include <dlfcn.h>
#include <link.h>

/* Sanitizer builds only (make asan). When the last instance goes, the
 * loader unloads the driver and layer libraries; LeakSanitizer then sees
 * their never-freed static allocations (lavapipe keeps one 128-byte block
 * from its start-up) as leaks in "<unknown module>", which no suppression
 * can name. Pinning those libraries keeps their data reachable and their
 * frames named, so the leak check judges btfcar's own memory only
 * (tests/unit/lsan.supp). */
static int pin_one(struct dl_phdr_info *info, size_t size, void *user)
{
    (void)size;
    (void)user;
    const char *name = info->dlpi_name;
    if (name && (strstr(name, "libvulkan_") || strstr(name, "libVkLayer_")))
        dlopen(name, RTLD_LAZY | RTLD_NOLOAD | RTLD_NODELETE);
    return 0;
}

void btf__vk_pin_modules(void)
{
    dl_iterate_phdr(pin_one, NULL);
}
#else
void btf__vk_pin_modules(void)
{
}
#endif

#define NEED_API VK_API_VERSION_1_1 /* shaders are built for --target-env vulkan1.1 */
#define VALIDATION_LAYER "VK_LAYER_KHRONOS_validation"
#define NO_DEVICE_MSG "no Vulkan device found (install mesa-vulkan-drivers for the CPU driver lavapipe)"

/* ------------------------------------------------------------ messages */

const char *btf__vk_result_name(VkResult r)
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
int btf__vk_fail(btf_error *err, VkResult r, const char *call)
{
    int code = (r == VK_ERROR_OUT_OF_HOST_MEMORY || r == VK_ERROR_OUT_OF_DEVICE_MEMORY)
                   ? BTF_E_NOMEM
                   : BTF_E_UNSUPPORTED;
    return btf__fail(err, code, "%s failed: %s (%d)", call, btf__vk_result_name(r), (int)r);
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

const char *btf__vk_type_name(int type)
{
    switch (type) {
    case BTF_VK_TYPE_DISCRETE_GPU: return "discrete GPU";
    case BTF_VK_TYPE_INTEGRATED_GPU: return "integrated GPU";
    case BTF_VK_TYPE_VIRTUAL_GPU: return "virtual GPU";
    case BTF_VK_TYPE_CPU: return "CPU";
    default: return "other";
    }
}

void btf__vk_version_text(uint32_t v, char *buf, size_t n)
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
        return btf__vk_fail(err, r, "vkEnumerateInstanceLayerProperties");
    VkLayerProperties *lp = btf__calloc(n, sizeof *lp, err);
    if (!lp)
        return BTF_E_NOMEM;
    r = vkEnumerateInstanceLayerProperties(&n, lp);
    for (uint32_t i = 0; r >= 0 && i < n; i++)
        *found |= !strcmp(lp[i].layerName, name);
    free(lp);
    if (r < 0)
        return btf__vk_fail(err, r, "vkEnumerateInstanceLayerProperties");
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
        btf__vk_version_text(v, t, sizeof t);
        return btf__fail(err, BTF_E_UNSUPPORTED,
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
        return btf__fail(err, BTF_E_UNSUPPORTED,
                         "Vulkan validation was requested (btf_vk_opts.validation) but the "
                         "layer %s is not installed (Debian: vulkan-validationlayers)",
                         VALIDATION_LAYER);
    if (!has_instance_extension(NULL, VK_EXT_DEBUG_UTILS_EXTENSION_NAME) &&
        !has_instance_extension(VALIDATION_LAYER, VK_EXT_DEBUG_UTILS_EXTENSION_NAME))
        return btf__fail(err, BTF_E_UNSUPPORTED,
                         "Vulkan validation needs the instance extension %s, which is missing",
                         VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
    *sync_validation = has_instance_extension(VALIDATION_LAYER,
                                              VK_EXT_VALIDATION_FEATURES_EXTENSION_NAME);
    return BTF_OK;
}

/* A Vulkan 1.1 instance; with vk != NULL and validation, the layer and a
 * messenger creation chain reporting to vk (also during create/destroy). */
int btf__vk_make_instance(btf_vk *vk, int validation, VkInstance *out, btf_error *err)
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
        return btf__fail(err, BTF_E_UNSUPPORTED, NO_DEVICE_MSG);
    if (r != VK_SUCCESS) {
        *out = VK_NULL_HANDLE;
        return btf__vk_fail(err, r, "vkCreateInstance");
    }
    return BTF_OK;
}

int btf__vk_make_messenger(btf_vk *vk, btf_error *err)
{
    PFN_vkCreateDebugUtilsMessengerEXT create = (PFN_vkCreateDebugUtilsMessengerEXT)
        vkGetInstanceProcAddr(vk->instance, "vkCreateDebugUtilsMessengerEXT");
    if (!create)
        return btf__fail(err, BTF_E_UNSUPPORTED,
                         "vkGetInstanceProcAddr found no vkCreateDebugUtilsMessengerEXT");
    VkDebugUtilsMessengerCreateInfoEXT mi = messenger_info(vk);
    VkResult r = create(vk->instance, &mi, NULL, &vk->messenger);
    if (r != VK_SUCCESS) {
        vk->messenger = VK_NULL_HANDLE;
        return btf__vk_fail(err, r, "vkCreateDebugUtilsMessengerEXT");
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
                       ? btf__fail(err, BTF_E_UNSUPPORTED, NO_DEVICE_MSG)
                       : btf__vk_fail(err, r, "vkEnumeratePhysicalDevices");
        if (n == 0)
            return btf__fail(err, BTF_E_UNSUPPORTED, NO_DEVICE_MSG);
        VkPhysicalDevice *d = btf__calloc(n, sizeof *d, err);
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
            return btf__vk_fail(err, r, "vkEnumeratePhysicalDevices");
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
        /* 16-bit storage is optional in 1.1: half-float buffers need it */
        VkPhysicalDevice16BitStorageFeatures s16 = {
            .sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_16BIT_STORAGE_FEATURES};
        VkPhysicalDeviceFeatures2 f2 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2,
                                        .pNext = &s16};
        vkGetPhysicalDeviceFeatures2(p, &f2);
        di->storage_16bit = s16.storageBuffer16BitAccess == VK_TRUE;
    }
    VkPhysicalDeviceMemoryProperties mp;
    vkGetPhysicalDeviceMemoryProperties(p, &mp);
    for (uint32_t h = 0; h < mp.memoryHeapCount; h++)
        if ((mp.memoryHeaps[h].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT) &&
            mp.memoryHeaps[h].size > di->device_local_bytes)
            di->device_local_bytes = mp.memoryHeaps[h].size;
}

btf_status btf__vk_list_devices(btf_vk_device_info **list, int *count, btf_error *err)
{
    *list = NULL;
    *count = 0;
    VkInstance inst;
    int rc = btf__vk_make_instance(NULL, 0, &inst, err);
    if (rc)
        return rc;
    VkPhysicalDevice *devs;
    int n;
    rc = enumerate(inst, &devs, &n, err);
    if (rc == BTF_E_UNSUPPORTED && n == 0) { /* no device: an empty list */
        rc = BTF_OK;
        devs = NULL;
    }
    btf_vk_device_info *out = rc ? NULL : btf__calloc((size_t)n, sizeof *out, err);
    if (!rc && !out)
        rc = BTF_E_NOMEM;
    for (int i = 0; !rc && i < n; i++)
        fill_info(devs[i], i, &out[i]);
    free(devs);
    btf__vk_pin_modules();
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
        return btf__fail(err, BTF_E_ARG,
                         "Vulkan device %d does not exist (%d device%s: indices 0..%d; see "
                         "btfcar info --devices)",
                         index, n, n == 1 ? "" : "s", n - 1);
    if (!in[index].usable) {
        char v[32];
        btf__vk_version_text(in[index].api_version, v, sizeof v);
        return btf__fail(err, BTF_E_UNSUPPORTED,
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
        return btf__fail(err, BTF_E_UNSUPPORTED,
                         "only a CPU Vulkan device was found (%d: %s); allow it "
                         "(btf_gpu_opts.allow_cpu) or name it (btf_gpu_opts.device = %d)",
                         cpu, in[cpu].name, cpu);
    return btf__fail(err, BTF_E_UNSUPPORTED,
                     "no usable Vulkan device (Vulkan 1.1 with a compute queue needed; %d "
                     "found, see btfcar info --devices)",
                     n);
}

int btf__vk_choose_device(btf_vk *vk, const btf_vk_opts *o, btf_error *err)
{
    VkPhysicalDevice *devs;
    int n, chosen = -1;
    int rc = enumerate(vk->instance, &devs, &n, err);
    if (rc)
        return rc;
    btf_vk_device_info *in = btf__calloc((size_t)n, sizeof *in, err);
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

int btf__vk_make_device(btf_vk *vk, btf_error *err)
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
        return btf__vk_fail(err, r, "vkCreateDevice");
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
        return btf__vk_fail(err, r, "vkCreateCommandPool");
    }
    VkFenceCreateInfo fi = {.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    r = vkCreateFence(vk->device, &fi, NULL, &vk->fence);
    if (r != VK_SUCCESS) {
        vk->fence = VK_NULL_HANDLE;
        return btf__vk_fail(err, r, "vkCreateFence");
    }
    return BTF_OK;
}
