/*
 * devices.c — the Vulkan devices GPU synthesis (Haindl & Filip 2007,
 * section II.C, as compute shaders: docs/gpu.md) can run on, for the public
 * API: the internal layer's device records (gpu/vk.h) cut down to what a
 * caller chooses a device by. The automatic choice among them
 * (btf_gpu_auto_device) is in gpu/gpu_handle.c, beside the memory budget
 * it applies.
 */
#include "core/core.h"
#include "synth_gpu.h"
#include "vk.h"

#include <stdio.h>
#include <stdlib.h>

_Static_assert((int)BTF_GPU_DISCRETE == BTF_VK_TYPE_DISCRETE_GPU &&
                   (int)BTF_GPU_INTEGRATED == BTF_VK_TYPE_INTEGRATED_GPU &&
                   (int)BTF_GPU_VIRTUAL == BTF_VK_TYPE_VIRTUAL_GPU &&
                   (int)BTF_GPU_CPU == BTF_VK_TYPE_CPU,
               "btf_gpu_device_type mirrors VkPhysicalDeviceType");

btf_status btf_gpu_list_devices(btf_gpu_device **list, int *count, btf_error *err)
{
    *list = NULL;
    *count = 0;
    btf_vk_device_info *in;
    int n;
    btf_status rc = btf__vk_list_devices(&in, &n, err);
    if (rc)
        return rc;
    btf_gpu_device *out = btf__calloc(n > 0 ? (size_t)n : 1, sizeof *out, err);
    if (!out) {
        free(in);
        return BTF_E_NOMEM;
    }
    for (int i = 0; i < n; i++) {
        btf_gpu_device *d = &out[i];
        d->index = in[i].index;
        snprintf(d->name, sizeof d->name, "%s", in[i].name);
        d->type = in[i].type >= (int)BTF_GPU_OTHER && in[i].type <= (int)BTF_GPU_CPU
                      ? (btf_gpu_device_type)in[i].type
                      : BTF_GPU_OTHER;
        d->type_name = btf__vk_type_name(in[i].type);
        btf__vk_version_text(in[i].api_version, d->vulkan_version, sizeof d->vulkan_version);
        d->usable = in[i].usable;
        d->max_buffer_bytes = in[i].max_storage_buffer_range;
        d->device_local_bytes = in[i].device_local_bytes;
        d->storage_16bit = in[i].storage_16bit;
    }
    free(in);
    *list = out;
    *count = n;
    return BTF_OK;
}
