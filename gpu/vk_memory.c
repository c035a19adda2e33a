/*
 * vk_memory.c — memory of the Vulkan compute layer (gpu/vk.h; the files:
 * gpu/vk_internal.h): the choice of memory types when a context is made,
 * storage buffers (mapped where host-visible memory is fast, else
 * device-local), and upload and download, by memcpy into mapped buffers or
 * through a staging buffer, one copy job per chunk.
 */
#include "vk_internal.h"

#include "core/core.h"

#include <stdlib.h>
#include <string.h>

#define STAGING_CHUNK ((VkDeviceSize)16 << 20)

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
        return btf__vk_fail(err, r, "vkCreateBuffer");
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
int btf__vk_choose_memory(btf_vk *vk, int force_staging, btf_error *err)
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
        return btf__fail(err, BTF_E_UNSUPPORTED,
                         "Vulkan device %s offers no memory type for %s buffers", vk->info.name,
                         t < 0 ? "storage" : "host-visible staging");
    vk->storage_type = (uint32_t)t;
    if (!vk->info.mapped_buffers) {
        vk->upload_type = (uint32_t)up;
        vk->download_type = (uint32_t)(down >= 0 ? down : up);
    }
    return BTF_OK;
}

/* ------------------------------------------------------------ buffers */

/* Allocates and binds memory of type for b (and maps it when map). */
static int bind_memory(btf_vk *vk, btf_vk_buffer *b, uint32_t type, int map, btf_error *err)
{
    VkMemoryRequirements mr;
    vkGetBufferMemoryRequirements(vk->device, b->buffer, &mr);
    if (!(mr.memoryTypeBits & (1u << type)))
        return btf__fail(err, BTF_E_UNSUPPORTED,
                         "vkGetBufferMemoryRequirements: memory type %u not allowed for a "
                         "buffer of %llu bytes",
                         type, (unsigned long long)b->size);
    uint32_t heap = vk->mem.memoryTypes[type].heapIndex;
    VkDeviceSize heap_size = vk->mem.memoryHeaps[heap].size;
    if (mr.size > heap_size)
        return btf__fail(err, BTF_E_NOMEM,
                         "a Vulkan buffer of %llu bytes does not fit in memory heap %u of %s "
                         "(%llu bytes)",
                         (unsigned long long)mr.size, heap, vk->info.name,
                         (unsigned long long)heap_size);
    if (vk->info.max_allocation_bytes && mr.size > vk->info.max_allocation_bytes)
        return btf__fail(err, BTF_E_NOMEM,
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
        return btf__fail(err, BTF_E_NOMEM,
                         "vkAllocateMemory of %llu bytes failed: %s (heap %u: %llu bytes, "
                         "%llu of them already allocated by btfcar)",
                         (unsigned long long)mr.size, btf__vk_result_name(r), heap,
                         (unsigned long long)heap_size,
                         (unsigned long long)vk->heap_used[heap]);
    }
    b->alloc_size = mr.size;
    b->heap = heap;
    vk->heap_used[heap] += mr.size;
    if ((r = vkBindBufferMemory(vk->device, b->buffer, b->memory, 0)) != VK_SUCCESS)
        return btf__vk_fail(err, r, "vkBindBufferMemory");
    if (map && (r = vkMapMemory(vk->device, b->memory, 0, VK_WHOLE_SIZE, 0, &b->mapped)) !=
                   VK_SUCCESS) {
        b->mapped = NULL;
        return btf__vk_fail(err, r, "vkMapMemory");
    }
    return BTF_OK;
}

static void buffer_free(btf_vk_buffer *b)
{
    if (!b)
        return;
    btf_vk *vk = b->vk;
    btf__vk_settle(vk);
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
    btf_vk_buffer *b = btf__calloc(1, sizeof *b, err);
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
        rc = btf__vk_fail(err, r, "vkCreateBuffer");
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

btf_status btf__vk_buffer_create(btf_vk *vk, uint64_t bytes, btf_vk_buffer **out, btf_error *err)
{
    *out = NULL;
    int rc = btf__vk_check_usable(vk, err);
    if (rc)
        return rc;
    if (bytes == 0 || bytes > vk->info.max_storage_buffer_range)
        return btf__fail(err, BTF_E_ARG,
                         "a Vulkan storage buffer of %llu bytes: %s holds 1 to %llu bytes "
                         "(maxStorageBufferRange; larger data must be split)",
                         (unsigned long long)bytes, vk->info.name,
                         (unsigned long long)vk->info.max_storage_buffer_range);
    return buffer_make(vk, bytes,
                       VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
                           VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                       vk->storage_type, vk->info.mapped_buffers, out, err);
}

void btf__vk_buffer_destroy(btf_vk_buffer *buf)
{
    buffer_free(buf);
}

uint64_t btf__vk_buffer_size(const btf_vk_buffer *buf)
{
    return buf->size;
}

void *btf__vk_buffer_mapped(btf_vk_buffer *buf)
{
    return buf->mapped;
}

/* One staging copy of bytes (<= the staging size): to the buffer (up) or
 * from it. */
static int staged_copy(btf_vk *vk, btf_vk_buffer *stage, VkBuffer buf, uint64_t offset,
                       uint64_t bytes, int up, btf_error *err)
{
    btf_vk_job *job;
    int rc = btf__vk_job_begin(vk, &job, err);
    if (rc)
        return rc;
    if (up)
        btf__vk_record_copy(job, stage->buffer, 0, buf, offset, bytes);
    else
        btf__vk_record_copy(job, buf, offset, stage->buffer, 0, bytes);
    return btf__vk_job_submit_wait(job, err);
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

btf_status btf__vk_buffer_upload(btf_vk *vk, btf_vk_buffer *buf, uint64_t offset, const void *data,
                         uint64_t bytes, btf_error *err)
{
    int rc = btf__vk_check_usable(vk, err);
    if (!rc)
        rc = btf__vk_check_range(buf, offset, bytes, "btf_vk_buffer_upload", err);
    if (rc || bytes == 0)
        return rc;
    if (buf->mapped) {
        memcpy((unsigned char *)buf->mapped + offset, data, bytes);
        return BTF_OK;
    }
    return staged(vk, buf->buffer, offset, (unsigned char *)(uintptr_t)data, bytes, 1, err);
}

btf_status btf__vk_buffer_download(btf_vk *vk, const btf_vk_buffer *buf, uint64_t offset, void *data,
                           uint64_t bytes, btf_error *err)
{
    int rc = btf__vk_check_usable(vk, err);
    if (!rc)
        rc = btf__vk_check_range(buf, offset, bytes, "btf_vk_buffer_download", err);
    if (rc || bytes == 0)
        return rc;
    if (buf->mapped) {
        memcpy(data, (const unsigned char *)buf->mapped + offset, bytes);
        return BTF_OK;
    }
    return staged(vk, buf->buffer, offset, data, bytes, 0, err);
}
