/*
 * vk_internal.h — what the files of the Vulkan compute layer share and its
 * users do not see (gpu/vk.h is the interface): the handles' structs and the
 * functions one file of the layer calls in another. Includes the Vulkan
 * header; only gpu/vk*.c include this file.
 *
 * The files, each calling only those after it (make check-layering):
 *   vk.c           the context: btf__vk_create, btf__vk_destroy, accessors;
 *   vk_memory.c    memory types, storage buffers, upload and download
 *                  (staging copies are jobs);
 *   vk_job.c       pipelines, jobs, descriptor pools, barriers, the fence
 *                  wait, and the checks every call starts with;
 *   vk_instance.c  loader, instance, validation messenger, device list and
 *                  choice, VkResult messages.
 */
#ifndef BTF_VK_INTERNAL_H
#define BTF_VK_INTERNAL_H

#include "vk.h"

#include <vulkan/vulkan.h>

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

/* ------------------------------------------------- vk_instance.c */

/* "VK_ERROR_DEVICE_LOST" and so on ("unknown VkResult" otherwise). */
const char *btf__vk_result_name(VkResult r);
/* "vkCreateDevice failed: VK_ERROR_..." (out-of-memory results: BTF_E_NOMEM). */
int btf__vk_fail(btf_error *err, VkResult r, const char *call);
/* Sanitizer builds: keeps the driver and layer libraries loaded before the
 * last instance goes (see vk_instance.c); otherwise nothing. */
void btf__vk_pin_modules(void);
/* A Vulkan 1.1 instance; with vk != NULL and validation, the layer and a
 * messenger creation chain reporting to vk (also during create/destroy). */
int btf__vk_make_instance(btf_vk *vk, int validation, VkInstance *out, btf_error *err);
/* The messenger counting the validation layer's errors and warnings. */
int btf__vk_make_messenger(btf_vk *vk, btf_error *err);
/* vk->phys, info and queue_family: the device o names, or the best one. */
int btf__vk_choose_device(btf_vk *vk, const btf_vk_opts *o, btf_error *err);
/* The logical device, its compute queue, the command pool and the fence. */
int btf__vk_make_device(btf_vk *vk, btf_error *err);

/* ------------------------------------------------------ vk_job.c */

/* BTF_OK, or the reason this context can no longer be used. */
int btf__vk_check_usable(const btf_vk *vk, btf_error *err);
/* [offset, offset + bytes) lies inside the buffer (overflow-safe); what
 * starts the message. */
int btf__vk_check_range(const btf_vk_buffer *b, uint64_t offset, uint64_t bytes,
                        const char *what, btf_error *err);
/* After a timeout: wait for the job that did not finish and free it, so
 * that what it uses can be destroyed (the context stays unusable). */
void btf__vk_settle(btf_vk *vk);
/* Records a copy of bytes and the barrier after it (no checks). */
void btf__vk_record_copy(btf_vk_job *job, VkBuffer src, uint64_t src_off, VkBuffer dst,
                         uint64_t dst_off, uint64_t bytes);

/* --------------------------------------------------- vk_memory.c */

/* The memory types of storage and staging buffers, and whether storage
 * buffers are mapped (vk->info.mapped_buffers). */
int btf__vk_choose_memory(btf_vk *vk, int force_staging, btf_error *err);

#endif
