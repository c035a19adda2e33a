/*
 * vk_job.c — work of the Vulkan compute layer (gpu/vk.h; the files:
 * gpu/vk_internal.h): compute pipelines from SPIR-V with their layouts and
 * specialisation constants, and jobs: one command buffer of dispatches,
 * fills and copies with a memory barrier after each command, descriptor
 * sets from pools that grow with the job, submitted and waited for on the
 * context's fence. A job that does not finish leaves the context unusable;
 * the checks every call of the layer starts with are here.
 */
#include <stdio.h>
#include "vk_internal.h"

#include "core/core.h"

#include <stdlib.h>

/* ---------------------------------------------------------- checks */

/* BTF_OK, or the reason this context can no longer be used. */
int btf__vk_check_usable(const btf_vk *vk, btf_error *err)
{
    if (vk->broken[0])
        return btf__fail(err, BTF_E_UNSUPPORTED, "%s", vk->broken);
    return BTF_OK;
}

/* [offset, offset + bytes) lies inside the buffer (overflow-safe). */
int btf__vk_check_range(const btf_vk_buffer *b, uint64_t offset, uint64_t bytes,
                        const char *what, btf_error *err)
{
    if (offset > b->size || bytes > b->size - offset)
        return btf__fail(err, BTF_E_ARG,
                         "%s: bytes %llu..%llu are outside the Vulkan buffer of %llu bytes",
                         what, (unsigned long long)offset,
                         (unsigned long long)offset + (unsigned long long)bytes,
                         (unsigned long long)b->size);
    return BTF_OK;
}

/* ---------------------------------------------------------- pipelines */

static int check_pipeline_args(const btf_vk *vk, const uint32_t *spirv, size_t spirv_bytes,
                               int n_buffers, uint32_t push_bytes, const uint32_t *spec,
                               int n_spec, btf_error *err)
{
    if (!spirv || spirv_bytes < 20 || spirv_bytes % 4 || spirv[0] != 0x07230203u)
        return btf__fail(err, BTF_E_ARG,
                         "btf_vk_pipeline_create: not a SPIR-V module (%zu bytes)", spirv_bytes);
    int max_buffers = (int)(vk->info.max_storage_buffers < BTF_VK_MAX_BUFFERS
                                ? vk->info.max_storage_buffers
                                : BTF_VK_MAX_BUFFERS);
    if (n_buffers < 0 || n_buffers > max_buffers)
        return btf__fail(err, BTF_E_ARG,
                         "btf_vk_pipeline_create: %d storage buffers (0..%d allowed on %s)",
                         n_buffers, max_buffers, vk->info.name);
    if (push_bytes % 4 || push_bytes > vk->info.max_push_constants_bytes)
        return btf__fail(err, BTF_E_ARG,
                         "btf_vk_pipeline_create: %u push constant bytes (a multiple of 4, at "
                         "most maxPushConstantsSize = %u)",
                         push_bytes, vk->info.max_push_constants_bytes);
    if (n_spec < 0 || n_spec > BTF_VK_MAX_SPEC || (n_spec > 0 && !spec))
        return btf__fail(err, BTF_E_ARG,
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
        return btf__vk_fail(err, r, "vkCreateDescriptorSetLayout");
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
        return btf__vk_fail(err, r, "vkCreatePipelineLayout");
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
        return btf__vk_fail(err, r, "vkCreateShaderModule");
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
        return btf__vk_fail(err, r, "vkCreateComputePipelines");
    }
    return BTF_OK;
}

btf_status btf__vk_pipeline_create(btf_vk *vk, const uint32_t *spirv, size_t spirv_bytes,
                           int n_buffers, uint32_t push_constant_bytes,
                           const uint32_t *spec_values, int n_spec, btf_vk_pipeline **out,
                           btf_error *err)
{
    *out = NULL;
    int rc = btf__vk_check_usable(vk, err);
    if (!rc)
        rc = check_pipeline_args(vk, spirv, spirv_bytes, n_buffers, push_constant_bytes,
                                 spec_values, n_spec, err);
    if (rc)
        return rc;
    btf_vk_pipeline *p = btf__calloc(1, sizeof *p, err);
    if (!p)
        return BTF_E_NOMEM;
    p->vk = vk;
    p->n_buffers = n_buffers;
    p->push_bytes = push_constant_bytes;
    rc = make_layouts(p, push_constant_bytes, err);
    if (!rc)
        rc = make_pipeline(p, spirv, spirv_bytes, spec_values, n_spec, err);
    if (rc) {
        btf__vk_pipeline_destroy(p);
        return rc;
    }
    *out = p;
    return BTF_OK;
}

void btf__vk_pipeline_destroy(btf_vk_pipeline *p)
{
    if (!p)
        return;
    btf__vk_settle(p->vk);
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

/* After a timeout: wait for the job that did not finish and free it, so
 * that what it uses can be destroyed (the context stays unusable). */
void btf__vk_settle(btf_vk *vk)
{
    if (vk->stuck) {
        vkDeviceWaitIdle(vk->device);
        job_free(vk->stuck);
        vk->stuck = NULL;
    }
}

btf_status btf__vk_job_begin(btf_vk *vk, btf_vk_job **out, btf_error *err)
{
    *out = NULL;
    int rc = btf__vk_check_usable(vk, err);
    if (rc)
        return rc;
    btf_vk_job *job = btf__calloc(1, sizeof *job, err);
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
        return btf__vk_fail(err, r, "vkAllocateCommandBuffers");
    }
    VkCommandBufferBeginInfo bi = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO,
                                   .flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT};
    if ((r = vkBeginCommandBuffer(job->cmd, &bi)) != VK_SUCCESS) {
        job_free(job);
        return btf__vk_fail(err, r, "vkBeginCommandBuffer");
    }
    *out = job;
    return BTF_OK;
}

void btf__vk_job_abort(btf_vk_job *job)
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
            return btf__fail(err, BTF_E_NOMEM, "out of memory for Vulkan descriptor pools");
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
        return btf__vk_fail(err, r, "vkCreateDescriptorPool");
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
        return btf__vk_fail(err, r, "vkAllocateDescriptorSets");
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
        return btf__fail(err, BTF_E_ARG, "btf_vk_job_dispatch: pipeline of another context");
    if (nbufs != pipe->n_buffers || (nbufs > 0 && !bufs))
        return btf__fail(err, BTF_E_ARG,
                         "btf_vk_job_dispatch: %d buffers given, the pipeline binds %d", nbufs,
                         pipe->n_buffers);
    for (int i = 0; i < nbufs; i++)
        if (!bufs[i] || bufs[i]->vk != job->vk)
            return btf__fail(err, BTF_E_ARG, "btf_vk_job_dispatch: buffer %d is %s", i,
                             bufs[i] ? "of another context" : "NULL");
    if (push_bytes != pipe->push_bytes || (push_bytes && !push))
        return btf__fail(err, BTF_E_ARG,
                         "btf_vk_job_dispatch: %u push constant bytes given, the pipeline "
                         "declares %u",
                         push_bytes, pipe->push_bytes);
    for (int i = 0; i < 3; i++)
        if (g[i] > in->max_workgroup_count[i])
            return btf__fail(err, BTF_E_ARG,
                             "btf_vk_job_dispatch: %u x %u x %u workgroups exceed "
                             "maxComputeWorkGroupCount %u x %u x %u of %s",
                             g[0], g[1], g[2], in->max_workgroup_count[0],
                             in->max_workgroup_count[1], in->max_workgroup_count[2], in->name);
    return BTF_OK;
}

btf_status btf__vk_job_dispatch(btf_vk_job *job, const btf_vk_pipeline *pipe,
                        btf_vk_buffer *const *bufs, int nbufs, const void *push,
                        uint32_t push_bytes, uint32_t gx, uint32_t gy, uint32_t gz,
                        btf_error *err)
{
    const uint32_t g[3] = {gx, gy, gz};
    int rc = btf__vk_check_usable(job->vk, err);
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

btf_status btf__vk_job_fill(btf_vk_job *job, btf_vk_buffer *buf, uint64_t offset, uint64_t bytes,
                    uint32_t value, btf_error *err)
{
    int rc = btf__vk_check_usable(job->vk, err);
    if (!rc && buf->vk != job->vk)
        rc = btf__fail(err, BTF_E_ARG, "btf_vk_job_fill: buffer of another context");
    if (!rc)
        rc = btf__vk_check_range(buf, offset, bytes, "btf_vk_job_fill", err);
    if (!rc && (offset % 4 || bytes % 4))
        rc = btf__fail(err, BTF_E_ARG,
                       "btf_vk_job_fill: offset %llu and size %llu must be multiples of 4",
                       (unsigned long long)offset, (unsigned long long)bytes);
    if (rc || bytes == 0)
        return rc;
    vkCmdFillBuffer(job->cmd, buf->buffer, offset, bytes, value);
    barrier_after(job->cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT);
    return BTF_OK;
}

void btf__vk_record_copy(btf_vk_job *job, VkBuffer src, uint64_t src_off, VkBuffer dst,
                         uint64_t dst_off, uint64_t bytes)
{
    VkBufferCopy region = {.srcOffset = src_off, .dstOffset = dst_off, .size = bytes};
    vkCmdCopyBuffer(job->cmd, src, dst, 1, &region);
    barrier_after(job->cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT);
}

btf_status btf__vk_job_copy(btf_vk_job *job, const btf_vk_buffer *src, uint64_t src_offset,
                    btf_vk_buffer *dst, uint64_t dst_offset, uint64_t bytes, btf_error *err)
{
    int rc = btf__vk_check_usable(job->vk, err);
    if (!rc && (src->vk != job->vk || dst->vk != job->vk))
        rc = btf__fail(err, BTF_E_ARG, "btf_vk_job_copy: buffer of another context");
    if (!rc)
        rc = btf__vk_check_range(src, src_offset, bytes, "btf_vk_job_copy (source)", err);
    if (!rc)
        rc = btf__vk_check_range(dst, dst_offset, bytes, "btf_vk_job_copy (destination)", err);
    if (!rc && src == dst && src_offset < dst_offset + bytes && dst_offset < src_offset + bytes)
        rc = btf__fail(err, BTF_E_ARG, "btf_vk_job_copy: source and destination overlap");
    if (rc || bytes == 0)
        return rc;
    btf__vk_record_copy(job, src->buffer, src_offset, dst->buffer, dst_offset, bytes);
    return BTF_OK;
}

/* A timeout or a lost device: the job may still run, so it is kept for
 * btf__vk_destroy and the context refuses further work. */
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
                 btf__vk_result_name(r), (int)r, vk->info.name);
    return btf__fail(err, BTF_E_UNSUPPORTED, "%s", vk->broken);
}

btf_status btf__vk_job_submit_wait(btf_vk_job *job, btf_error *err)
{
    btf_vk *vk = job->vk;
    int rc = btf__vk_check_usable(vk, err);
    if (rc) {
        job_free(job);
        return rc;
    }
    VkResult r = vkEndCommandBuffer(job->cmd);
    if (r != VK_SUCCESS) {
        job_free(job);
        return btf__vk_fail(err, r, "vkEndCommandBuffer");
    }
    if ((r = vkResetFences(vk->device, 1, &vk->fence)) != VK_SUCCESS) {
        job_free(job);
        return btf__vk_fail(err, r, "vkResetFences");
    }
    VkSubmitInfo si = {.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO,
                       .commandBufferCount = 1,
                       .pCommandBuffers = &job->cmd};
    r = vkQueueSubmit(vk->queue, 1, &si, vk->fence);
    if (r == VK_ERROR_DEVICE_LOST)
        return job_stuck(job, r, err);
    if (r != VK_SUCCESS) {
        job_free(job);
        return btf__vk_fail(err, r, "vkQueueSubmit");
    }
    r = vkWaitForFences(vk->device, 1, &vk->fence, VK_TRUE, vk->timeout_ns);
    if (r != VK_SUCCESS)
        return job_stuck(job, r, err);
    job_free(job);
    return BTF_OK;
}
