/*
 * gpu_handle.c — the btf_gpu handle (include/btfcar/gpu.h; its struct is in
 * gpu/synth_gpu.h, shared with gpu/synth_gpu.c, which runs its pipelines):
 * opening a Vulkan device with the synthesis pipelines and the colour
 * matcher made once (docs/gpu.md, "Synthesis on the GPU"), the accessors
 * the library's other GPU passes and the tests use, and what a device
 * holds — the limits of an image array on it (docs/gpu.md, "Images left on
 * the device"), the memory budget synthesis groups its images by ("Memory
 * budget") and the automatic backend's choice of a device that fits
 * ("Choosing a backend"), one rule for an open btf_gpu and for a listed
 * btf_gpu_device. Of the GPU files it calls only the Vulkan layer and
 * gpu/match_gpu.c; the synthesis (gpu/synth_gpu.c) calls here, never the
 * other way (make check-layering: the two share the struct, not calls
 * both ways).
 */
#include "core/core.h"
#include "synth/synth_testing.h"

#include "synth_gpu.h"
#include "vk.h"

#include "synth_collapse_spv.h"
#include "synth_field_spv.h"
#include "synth_unmix_spv.h"

#include <stdlib.h>

btf_gpu_opts btf_gpu_defaults(void)
{
    btf_gpu_opts o = {
        .struct_size = sizeof o,
        .use_device = 0, /* the best device */
        .device = 0,
        .allow_cpu = 0,
        .validation = 0,
    };
    return o;
}

btf_status btf_gpu_open(const btf_gpu_opts *opts, btf_gpu **out, btf_error *err)
{
    *out = NULL;
    btf_gpu_opts d = btf_gpu_defaults(), o;
    if (btf__opts_take(&o, sizeof o, opts, &d, "btf_gpu_open", err))
        return BTF_E_ARG;
    o.use_device = o.use_device ? o.use_device : d.use_device;
    o.device = o.device ? o.device : d.device;
    o.allow_cpu = o.allow_cpu ? o.allow_cpu : d.allow_cpu;
    o.validation = o.validation ? o.validation : d.validation;
    btf_gpu *g = btf__calloc(1, sizeof *g, err);
    if (!g)
        return BTF_E_NOMEM;
    btf_vk_opts vo = {.use_device = o.use_device, .device = o.device, .allow_cpu = o.allow_cpu,
                      .validation = o.validation};
    btf_status rc = btf__vk_create(&vo, &g->vk, err);
    if (rc == 0)
        rc = btf__vk_pipeline_create(g->vk, synth_field_spv, sizeof synth_field_spv, 2, 20, NULL, 0,
                                     &g->field, err); /* push: seed, s0, s1, task_base */
    if (rc == 0)
        rc = btf__vk_pipeline_create(g->vk, synth_collapse_spv, sizeof synth_collapse_spv, 3, 4,
                                     NULL, 0, &g->collapse, err);
    if (rc == 0)
        rc = btf__vk_pipeline_create(g->vk, synth_unmix_spv, sizeof synth_unmix_spv, 3, 4, NULL, 0,
                                     &g->unmix, err);
    if (rc == 0)
        rc = btf__gpu_matcher_create(g->vk, &g->matcher, err);
    if (rc) {
        btf_gpu_close(g);
        return rc;
    }
    *out = g;
    return BTF_OK;
}

void btf_gpu_close(btf_gpu *g)
{
    if (!g)
        return;
    btf__vk_pipeline_destroy(g->field);
    btf__vk_pipeline_destroy(g->collapse);
    btf__vk_pipeline_destroy(g->unmix);
    btf__gpu_matcher_free(g->matcher);
    btf__vk_destroy(g->vk);
    free(g);
}

const char *btf_gpu_device_name(const btf_gpu *g)
{
    return btf__vk_info(g->vk)->name;
}

int btf__gpu_is_cpu(const btf_gpu *g)
{
    return btf__vk_info(g->vk)->is_cpu;
}

unsigned btf_gpu_validation_errors(const btf_gpu *g)
{
    return btf__vk_validation_errors(g->vk);
}

void btf__gpu_last_tiling(const btf_gpu *g, int *batches, int *jobs)
{
    *batches = g->batches;
    *jobs = g->jobs;
}

void btf__gpu_set_max_buffer_bytes(btf_gpu *g, uint64_t bytes)
{
    g->max_buffer_bytes = bytes;
}

const char *btf_gpu_first_validation_message(const btf_gpu *g)
{
    return btf__vk_first_validation_message(g->vk);
}

uint64_t btf__gpu_max_buffer_bytes(const btf_gpu *g)
{
    uint64_t dev = btf__vk_info(g->vk)->max_storage_buffer_range;
    return g->max_buffer_bytes && g->max_buffer_bytes < dev ? g->max_buffer_bytes : dev;
}

const btf_gpu_matcher *btf__gpu_match_pipes(const btf_gpu *g)
{
    return g->matcher;
}

btf_vk *btf__gpu_vk(btf_gpu *g)
{
    return g->vk;
}

/* ---------------------------------------------- image arrays on the device */

/* The floats per buffer of an array on a device whose largest storage
 * buffer is max_buffer_bytes: all of it, at most 2^27 (eight of them: 2^30
 * floats, int32 indices), at least 1. */
static uint64_t floats_per_buffer(uint64_t max_buffer_bytes)
{
    uint64_t cap = max_buffer_bytes / 4;
    if (cap > (1ull << 27))
        cap = 1ull << 27;
    return cap > 0 ? cap : 1;
}

uint64_t btf__gpu_images_cap(const btf_gpu *g)
{
    return floats_per_buffer(btf__gpu_max_buffer_bytes(g));
}

/* Bindings of the render pass besides its two arrays, the images and the
 * range and normal maps (gpu/render.comp). */
#define RENDER_OTHER_BINDINGS 6

int btf__gpu_images_buffers(const btf_gpu *g)
{
    int64_t n = ((int64_t)btf__vk_info(g->vk)->max_storage_buffers - RENDER_OTHER_BINDINGS) / 2;
    return n >= BTF_GPU_DEVICE_BUFFERS ? BTF_GPU_DEVICE_BUFFERS : n >= 1 ? (int)n : 1;
}

/* ---------------------------------------- memory budget, backend choice */

/* btf_gpu_memory_budget of a device whose largest storage buffer and
 * device-local heap are these (0: not reported), binding all
 * BTF_GPU_DEVICE_BUFFERS: a quarter of the heap, at most what the buffers
 * hold. */
static uint64_t budget_bytes(uint64_t max_buffer_bytes, uint64_t heap_bytes)
{
    uint64_t cap = floats_per_buffer(max_buffer_bytes);
    uint64_t most = 4ull * BTF_GPU_DEVICE_BUFFERS * cap, heap = heap_bytes / 4;
    return heap > 0 && heap < most ? heap : most;
}

uint64_t btf_gpu_memory_budget(const btf_gpu *g)
{
    uint64_t b = budget_bytes(btf__gpu_max_buffer_bytes(g),
                              btf__vk_info(g->vk)->device_local_bytes);
    uint64_t spans = 4ull * btf__gpu_images_buffers(g) * btf__gpu_images_cap(g);
    return b < spans ? b : spans;
}

int btf_gpu_auto_fits(const btf_gpu *g, uint64_t image_bytes)
{
    return g && image_bytes <= btf_gpu_memory_budget(g);
}

/* The automatic choice's order (as btf__vk_create's best device):
 * discrete, integrated, virtual, other; a CPU device never. */
static int auto_rank(btf_gpu_device_type t)
{
    switch (t) {
    case BTF_GPU_DISCRETE: return 4;
    case BTF_GPU_INTEGRATED: return 3;
    case BTF_GPU_VIRTUAL: return 2;
    case BTF_GPU_CPU: return 0;
    default: return 1;
    }
}

int btf_gpu_auto_device(const btf_gpu_device *list, int n, uint64_t image_bytes)
{
    int best = -1;
    for (int i = 0; list && i < n; i++) {
        const btf_gpu_device *d = &list[i];
        if (!d->usable || auto_rank(d->type) == 0 ||
            image_bytes > budget_bytes(d->max_buffer_bytes, d->device_local_bytes))
            continue;
        if (best < 0 || auto_rank(d->type) > auto_rank(list[best].type))
            best = i;
    }
    return best < 0 ? -1 : list[best].index;
}
