/*
 * btfcar/gpu.h — the Vulkan compute path: devices, synthesis and the
 * renders of both model families on a GPU (docs/gpu.md).
 * Part of the public C API of btfcar; include/btfcar.h includes every
 * topical header, and its conventions (docs/api.md) hold here too.
 */
#ifndef BTFCAR_GPU_H
#define BTFCAR_GPU_H

#include "base.h"
#include "image.h"
#include "model.h"
#include "synth.h"
#include "render.h"

#include <stdint.h>

/* What this header declares is part of the ABI of libbtfcar.so: the library
 * is compiled with -fvisibility=hidden, and the declarations of the public
 * headers alone are exported (docs/install.md, "Shared library and soname"). */
#pragma GCC visibility push(default)

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------ synthesis (GPU) */

/* The Vulkan compute path (gpu/synth_gpu.c, docs/gpu.md): the same fields,
 * collapse and colour as btf_synthesise, bit for bit, computed by compute
 * shaders (a wavefront over each causal field). */
typedef struct btf_gpu btf_gpu;

typedef enum btf_gpu_device_type { /* VkPhysicalDeviceType's values */
    BTF_GPU_OTHER = 0,
    BTF_GPU_INTEGRATED = 1,
    BTF_GPU_DISCRETE = 2,
    BTF_GPU_VIRTUAL = 3,
    BTF_GPU_CPU = 4 /* a CPU driver such as lavapipe */
} btf_gpu_device_type;

typedef struct btf_gpu_device {
    int index;                 /* for btf_gpu_opts.device */
    char name[256];
    btf_gpu_device_type type;
    const char *type_name;     /* "discrete GPU", "integrated GPU", "virtual GPU",
                                  "CPU", "other" */
    char vulkan_version[32];   /* "1.3.230" */
    int usable;                /* Vulkan >= 1.1 and a compute queue */
    uint64_t max_buffer_bytes; /* largest storage buffer (maxStorageBufferRange) */
    uint64_t device_local_bytes; /* size of the largest device-local memory heap */
    int storage_16bit;         /* 1: 16-bit values in storage buffers
                                  (storageBuffer16BitAccess, Vulkan 1.1) */
} btf_gpu_device;

/* Every Vulkan device, in the driver's order (the indices of
 * btf_gpu_opts.device). *list is malloc'd: free() it; *count may be 0. No
 * Vulkan driver: BTF_E_UNSUPPORTED. */
btf_status btf_gpu_list_devices(btf_gpu_device **list, int *count, btf_error *err);

/* Options of btf_gpu_open; zero-initialised means the defaults. */
typedef struct btf_gpu_opts {
    size_t struct_size; /* sizeof the struct (set by the defaults); 0: this header's */
    int use_device;   /* 1: take `device` (an index of btf_gpu_list_devices);
                         0: the best device, discrete > integrated > virtual
                         GPU > CPU */
    int device;
    int allow_cpu;    /* 1: a CPU device (lavapipe) may be the best device */
    int validation;   /* 1: the Khronos validation layer, its messages counted */
} btf_gpu_opts;

/* The defaults that a zero field of btf_gpu_opts stands for. */
btf_gpu_opts btf_gpu_defaults(void);

btf_status btf_gpu_open(const btf_gpu_opts *opts, btf_gpu **out, btf_error *err);
void btf_gpu_close(btf_gpu *g);
const char *btf_gpu_device_name(const btf_gpu *g);
unsigned btf_gpu_validation_errors(const btf_gpu *g);
const char *btf_gpu_first_validation_message(const btf_gpu *g);

/* Synthesises n subspace images into outs[0 .. n-1] (allocated here, linear
 * RGB), as btf_synthesise with the same opts would (the CPU switches do not
 * apply). Images are grouped in batches and cut into strips of rows so that
 * every GPU buffer fits the device's limit; the causal fields carry their
 * last rows from strip to strip, so the result is the same whatever the
 * tiling. The structure layer and colour matching run on the device
 * (docs/gpu.md, "Colour matching on the device"), the CPU's bits. */
btf_status btf_gpu_synthesise(btf_gpu *g, const btf_model *m, const int *subspaces, int n,
                              const btf_synth_opts *opts, btf_image *outs, btf_error *err);
/* The bytes of images btf_gpu_synthesise_each keeps on the device at once:
 * a quarter of the device's largest device-local heap (the rest for the
 * synthesis' own buffers and other programs), at most the 4 storage
 * buffers of the device's limit that one group of images may span. */
uint64_t btf_gpu_memory_budget(const btf_gpu *g);
/* Whether the CLI's synthesis runs a work whose largest image takes
 * image_bytes on g (docs/gpu.md, "Choosing a backend": auto opens only a
 * real GPU, btf_gpu_opts.allow_cpu 0, or the device named): the image fits
 * g's memory budget; else auto takes the CPU, which streams, and --backend
 * gpu is refused. */
int btf_gpu_auto_fits(const btf_gpu *g, uint64_t image_bytes);
/* The rule of --backend auto over a device list (btf_gpu_list_devices;
 * docs/gpu.md, "Choosing a backend"): the index (btf_gpu_device.index) of
 * the device a work whose largest image takes image_bytes (0: any) runs
 * on — the best usable real GPU (discrete, then integrated, then virtual;
 * never a CPU device such as lavapipe) whose memory budget holds the
 * image — or -1 for the CPU. */
int btf_gpu_auto_device(const btf_gpu_device *list, int n, uint64_t image_bytes);
/* The same images handed to fn in order (btf_image_fn: fn may keep each),
 * synthesised in groups that fit btf_gpu_memory_budget, each group
 * finished on the device and read back one image at a time: at most one
 * image on the host besides what fn keeps, whatever n. An image larger
 * than the budget alone is synthesised in strips straight to the host and
 * finished there by the CPU's code (the same bits). */
btf_status btf_gpu_synthesise_each(btf_gpu *g, const btf_model *m, const int *subspaces, int n,
                                   const btf_synth_opts *opts, btf_image_fn fn, void *user,
                                   btf_error *err);

/* -------------------------------------------------------- render (GPU) */

/* The GPU render pass (gpu/render_gpu.c, docs/render.md, "On the GPU"):
 * the same plan as btf_render_scene / btf_render_flat (G-buffer traced on
 * the CPU, the needed subspaces), then two compute passes on g's device:
 * the needed subspaces synthesised tileable into one device buffer, left
 * there, and a render shader running the CPU renderer's shading text
 * (src/render/btf_render_shared.h). A frame beyond the device's buffer
 * limits is rendered in bands of rows. info's synth_s and shade_s are the
 * two passes. */
btf_status btf_gpu_render_scene(btf_gpu *g, const btf_model *m, const btf_scene *s,
                                const btf_render_opts *opts, btf_image *out,
                                btf_render_info *info, btf_error *err);
btf_status btf_gpu_render_flat(btf_gpu *g, const btf_model *m, btf_dir view, btf_dir light,
                               const btf_render_opts *opts, btf_image *out,
                               btf_render_info *info, btf_error *err);

#ifdef __cplusplus
}
#endif

#pragma GCC visibility pop
#endif /* BTFCAR_GPU_H */
