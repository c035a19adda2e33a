/*
 * vk.h — the library's small internal Vulkan compute layer, on which GPU
 * synthesis (Haindl & Filip 2007, section II.C, computed as in section III,
 * "Synthesis of the BTF Subspace Images", by compute shaders) is built: one
 * device, one compute queue, storage buffers, compute pipelines built from
 * SPIR-V, and jobs (one command buffer of dispatches, fills and copies,
 * submitted and waited for). btf_gpu_list_devices lists devices with it.
 * Not installed: no Vulkan type appears here, so includers need no Vulkan
 * headers.
 *
 * Why a layer of our own: the Vulkan boilerplate (instance, device choice,
 * memory types, descriptor sets, barriers, fences) is the same for every
 * shader, and the rules that make it correct — barriers after every command,
 * limits checked before Vulkan sees a call, validation errors counted —
 * are kept once, here, rather than by each shader's host code. docs/gpu.md
 * describes the choices.
 *
 * The layer is four files behind this one interface, sharing the private
 * gpu/vk_internal.h: gpu/vk.c (the context: create, destroy, accessors),
 * gpu/vk_instance.c (loader, instance, validation messenger, device list
 * and choice), gpu/vk_memory.c (memory types, buffers, upload and download
 * with staging) and gpu/vk_job.c (pipelines, descriptor pools, jobs,
 * barriers, fences). Each calls only the ones after it in that list.
 *
 * Conventions are the library's: btf_status returns, one-line btf_error
 * messages naming the Vulkan call and its VkResult, zero-initialised option
 * structs, no globals, no environment reads, no printing. Every Vulkan call
 * of the layer is checked; with no Vulkan driver installed everything fails
 * with BTF_E_UNSUPPORTED.
 *
 * Threads: a btf_vk and everything made from it must be used by one thread at
 * a time (one queue, one command pool). Separate btf_vk handles are
 * independent.
 */
#ifndef BTF_VK_H
#define BTF_VK_H

#include <stddef.h>
#include <stdint.h>

#include "btfcar.h"

/* ---------------------------------------------------------------- devices */

/* VkPhysicalDeviceType values, so that includers need no Vulkan header. */
enum {
    BTF_VK_TYPE_OTHER = 0,
    BTF_VK_TYPE_INTEGRATED_GPU = 1,
    BTF_VK_TYPE_DISCRETE_GPU = 2,
    BTF_VK_TYPE_VIRTUAL_GPU = 3,
    BTF_VK_TYPE_CPU = 4
};

typedef struct btf_vk_device_info {
    int index;                      /* in btf__vk_list_devices (btf_vk_opts.device) */
    char name[256];
    int type;                       /* BTF_VK_TYPE_... (VkPhysicalDeviceType) */
    int is_cpu;                     /* type == BTF_VK_TYPE_CPU (lavapipe) */
    uint32_t vendor_id, device_id;
    uint32_t api_version;           /* VK_MAKE_API_VERSION; see btf__vk_version_text */
    int usable;                     /* Vulkan >= 1.1 and a compute queue */
    uint64_t max_storage_buffer_range;  /* bytes one storage buffer may hold */
    uint64_t max_allocation_bytes;  /* maxMemoryAllocationSize (0: not reported) */
    uint64_t device_local_bytes;    /* size of the largest device-local heap */
    uint32_t max_workgroup_count[3];
    uint32_t max_workgroup_size[3];
    uint32_t max_workgroup_invocations;
    uint32_t max_push_constants_bytes;
    uint32_t max_storage_buffers;   /* per shader stage (maxPerStageDescriptorStorageBuffers) */
    uint32_t subgroup_size;         /* 0 if the device does not say */
    int storage_16bit;              /* storageBuffer16BitAccess (Vulkan 1.1 16-bit storage):
                                       16-bit values in storage buffers */
    /* Filled by btf__vk_create only (0 in btf__vk_list_devices): */
    int mapped_buffers;             /* 1: buffers are host-visible and coherent, upload and
                                       download are memcpy; 0: staging copies */
} btf_vk_device_info;

/* Every Vulkan device, in the driver's enumeration order (the index of
 * btf_vk_opts.device). *list is malloc'd (free() it);
 * *count may be 0. No driver: BTF_E_UNSUPPORTED. */
btf_status btf__vk_list_devices(btf_vk_device_info **list, int *count, btf_error *err);

/* "discrete GPU", "integrated GPU", "virtual GPU", "CPU", "other". */
const char *btf__vk_type_name(int type);
/* "1.3.230" into buf. */
void btf__vk_version_text(uint32_t api_version, char *buf, size_t n);

/* ---------------------------------------------------------------- context */

typedef struct btf_vk btf_vk;

typedef struct btf_vk_opts {
    int use_device;  /* 1: take `device` (an index of btf__vk_list_devices);
                        0: the best device: discrete > integrated > virtual
                        GPU > CPU */
    int device;
    int allow_cpu;   /* automatic choice only: 1 lets a CPU device (lavapipe) be
                        chosen; 0 refuses it with BTF_E_UNSUPPORTED. A device
                        named by use_device is always taken. */
    int validation;  /* 1: VK_LAYER_KHRONOS_validation (with synchronisation
                        validation) and a messenger counting its errors and
                        warnings; BTF_E_UNSUPPORTED if the layer is missing. */
    int force_staging; /* 1: never map storage buffers, use staging copies
                          (tests the path discrete GPUs take) */
    uint32_t timeout_ms; /* wait limit of one job (0: 10 minutes) */
} btf_vk_opts;

/* Instance, device, compute queue, command pool. o may be NULL (defaults). */
btf_status btf__vk_create(const btf_vk_opts *o, btf_vk **out, btf_error *err);
/* Waits for the device to be idle, then frees everything; NULL is fine.
 * Buffers and pipelines must be destroyed first. */
void btf__vk_destroy(btf_vk *vk);
/* The same, and returns btf__vk_validation_errors counted over the whole life
 * including the teardown (where the layer reports objects never destroyed);
 * the first message goes to first_message (n bytes; may be NULL). */
unsigned btf__vk_destroy_checked(btf_vk *vk, char *first_message, size_t n);

const btf_vk_device_info *btf__vk_info(const btf_vk *vk);
/* 1 if the validation layer is on. */
int btf__vk_validating(const btf_vk *vk);
/* Errors and warnings the validation layer reported so far (0 without it),
 * and the text of the first one ("" if none). */
unsigned btf__vk_validation_errors(const btf_vk *vk);
const char *btf__vk_first_validation_message(const btf_vk *vk);

/* ---------------------------------------------------------------- buffers */

typedef struct btf_vk_buffer btf_vk_buffer;

/* A storage buffer of `bytes` (1 .. max_storage_buffer_range; content
 * undefined). Larger data must be split by the caller. Errors: BTF_E_ARG for
 * a size beyond the device's limits, BTF_E_NOMEM when the memory heap cannot
 * hold it. */
btf_status btf__vk_buffer_create(btf_vk *vk, uint64_t bytes, btf_vk_buffer **out, btf_error *err);
void btf__vk_buffer_destroy(btf_vk_buffer *buf); /* NULL is fine */
uint64_t btf__vk_buffer_size(const btf_vk_buffer *buf);
/* The mapped memory when info.mapped_buffers (read and write it directly
 * between jobs), else NULL. */
void *btf__vk_buffer_mapped(btf_vk_buffer *buf);

/* Copies bytes between host memory and [offset, offset + bytes) of the
 * buffer. Synchronous; never while a submitted job uses the buffer (jobs
 * are synchronous too, so only threads could break this). */
btf_status btf__vk_buffer_upload(btf_vk *vk, btf_vk_buffer *buf, uint64_t offset, const void *data,
                         uint64_t bytes, btf_error *err);
btf_status btf__vk_buffer_download(btf_vk *vk, const btf_vk_buffer *buf, uint64_t offset, void *data,
                           uint64_t bytes, btf_error *err);

/* -------------------------------------------------------------- pipelines */

typedef struct btf_vk_pipeline btf_vk_pipeline;

#define BTF_VK_MAX_BUFFERS 32 /* storage buffers of one pipeline */
#define BTF_VK_MAX_SPEC 64    /* specialisation constants of one pipeline */

/* A compute pipeline: entry point "main"; storage buffers at set 0, bindings
 * 0 .. n_buffers - 1; push_constant_bytes (a multiple of 4, may be 0) of push
 * constants at offset 0; specialisation constants constant_id 0 .. n_spec - 1,
 * 4 bytes each (uint, int or float bits). The shader must declare exactly
 * this interface (the validation layer checks). */
btf_status btf__vk_pipeline_create(btf_vk *vk, const uint32_t *spirv, size_t spirv_bytes,
                           int n_buffers, uint32_t push_constant_bytes,
                           const uint32_t *spec_values, int n_spec,
                           btf_vk_pipeline **out, btf_error *err);
void btf__vk_pipeline_destroy(btf_vk_pipeline *pipe); /* NULL is fine */

/* ------------------------------------------------------------------- jobs */

typedef struct btf_vk_job btf_vk_job;

/* A job records commands into one command buffer; nothing runs before
 * btf__vk_job_submit_wait. Every command is followed by a memory barrier, so
 * each one sees the results of all before it (and the host sees everything
 * once the job is done). A failed record call leaves the job as it was. */
btf_status btf__vk_job_begin(btf_vk *vk, btf_vk_job **out, btf_error *err);

/* Dispatches gx * gy * gz workgroups of pipe with bufs[0 .. nbufs-1] bound at
 * bindings 0 .. nbufs-1 (nbufs must equal the pipeline's n_buffers) and
 * push_bytes (equal to its push_constant_bytes) of push constants. Counts
 * beyond maxComputeWorkGroupCount are refused (BTF_E_ARG); a zero count
 * records nothing. */
btf_status btf__vk_job_dispatch(btf_vk_job *job, const btf_vk_pipeline *pipe,
                        btf_vk_buffer *const *bufs, int nbufs, const void *push,
                        uint32_t push_bytes, uint32_t gx, uint32_t gy, uint32_t gz,
                        btf_error *err);
/* Fills [offset, offset + bytes) with the 32-bit value; offset and bytes are
 * multiples of 4. */
btf_status btf__vk_job_fill(btf_vk_job *job, btf_vk_buffer *buf, uint64_t offset, uint64_t bytes,
                    uint32_t value, btf_error *err);
/* Copies bytes from src at src_offset to dst at dst_offset (regions of one
 * buffer must not overlap). */
btf_status btf__vk_job_copy(btf_vk_job *job, const btf_vk_buffer *src, uint64_t src_offset,
                    btf_vk_buffer *dst, uint64_t dst_offset, uint64_t bytes, btf_error *err);

/* Submits, waits (at most opts.timeout_ms) and frees the job, whatever the
 * outcome. A timeout or a lost device is BTF_E_UNSUPPORTED and leaves the
 * btf_vk unusable (only btf__vk_destroy then, which waits for the device). */
btf_status btf__vk_job_submit_wait(btf_vk_job *job, btf_error *err);
/* Frees a job without running it; NULL is fine. */
void btf__vk_job_abort(btf_vk_job *job);

#endif
