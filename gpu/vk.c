/*
 * vk.c — the context of the internal Vulkan compute layer under GPU
 * synthesis (Haindl & Filip 2007, section II.C, computed as in section III,
 * "Synthesis of the BTF Subspace Images", by compute shaders; see vk.h and
 * docs/gpu.md): btf__vk_create puts together the instance, the device and
 * the memory types, btf__vk_destroy takes them apart, and the accessors. The
 * pieces are in the files gpu/vk_internal.h lists: vk_instance.c,
 * vk_memory.c and vk_job.c.
 */
#include <stdio.h>
#include "vk_internal.h"

#include "core/core.h"

#include <stdlib.h>

#define DEFAULT_TIMEOUT_MS 600000u  /* 10 minutes */

/* ------------------------------------------------------------ context */

btf_status btf__vk_create(const btf_vk_opts *o, btf_vk **out, btf_error *err)
{
    static const btf_vk_opts defaults;
    *out = NULL;
    if (!o)
        o = &defaults;
    btf_vk *vk = btf__calloc(1, sizeof *vk, err);
    if (!vk)
        return BTF_E_NOMEM;
    int rc;
    vk->validation = o->validation;
    vk->timeout_ms = o->timeout_ms ? o->timeout_ms : DEFAULT_TIMEOUT_MS;
    vk->timeout_ns = (uint64_t)vk->timeout_ms * 1000000u;
    rc = btf__vk_make_instance(vk, vk->validation, &vk->instance, err);
    if (!rc && vk->validation)
        rc = btf__vk_make_messenger(vk, err);
    if (!rc)
        rc = btf__vk_choose_device(vk, o, err);
    if (!rc)
        rc = btf__vk_make_device(vk, err);
    if (!rc)
        rc = btf__vk_choose_memory(vk, o->force_staging, err);
    if (rc) {
        btf__vk_destroy(vk);
        return rc;
    }
    *out = vk;
    return BTF_OK;
}

unsigned btf__vk_destroy_checked(btf_vk *vk, char *first_message, size_t n)
{
    if (first_message && n)
        first_message[0] = '\0';
    if (!vk)
        return 0;
    if (vk->device) {
        vkDeviceWaitIdle(vk->device);
        btf__vk_settle(vk);
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
        btf__vk_pin_modules();
        vkDestroyInstance(vk->instance, NULL);
    }
    unsigned count = vk->n_messages;
    if (first_message && n)
        snprintf(first_message, n, "%s", vk->first_message);
    free(vk);
    return count;
}

void btf__vk_destroy(btf_vk *vk)
{
    btf__vk_destroy_checked(vk, NULL, 0);
}

const btf_vk_device_info *btf__vk_info(const btf_vk *vk)
{
    return &vk->info;
}

int btf__vk_validating(const btf_vk *vk)
{
    return vk->validation;
}

unsigned btf__vk_validation_errors(const btf_vk *vk)
{
    return vk->n_messages;
}

const char *btf__vk_first_validation_message(const btf_vk *vk)
{
    return vk->first_message;
}
