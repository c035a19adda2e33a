/*
 * synth_gpu.h — private GPU synthesis calls for other GPU passes of the
 * library (the render pass of issue 16), not part of the public API
 * (include/btfcar.h): subspace images synthesised into one device buffer
 * that stays on the device, and the Vulkan layer of a btf_gpu so that
 * another file can create pipelines and dispatch on the same device
 * (gpu/vk.h). Defined in gpu/synth_gpu.c.
 */
#ifndef BTF_SYNTH_GPU_H
#define BTF_SYNTH_GPU_H

#include "btfcar.h"
#include "vk.h"

#include <stdint.h>

/* The Vulkan device, queue and allocator of g (owned by g: valid until
 * btf_gpu_close; never destroy it). */
btf_vk *btf_gpu_vk(btf_gpu *g);
/* The largest storage buffer this btf_gpu uses: the device's limit, or
 * less where btf_gpu_set_max_buffer_bytes lowered it (tests). */
uint64_t btf_gpu_max_buffer_bytes(const btf_gpu *g);

/* The most device buffers btf_gpu_synthesise_device spreads its images
 * over (the render pass binds as many: gpu/render.comp). */
#define BTF_GPU_DEVICE_BUFFERS 4

/* Synthesises subspace images subspaces[0 .. n - 1] (1 <= n) with opts as
 * btf_gpu_synthesise does (the same bits, tileable included) into device
 * buffers it creates, out[0 .. BTF_GPU_DEVICE_BUFFERS - 1] (NULL where
 * unused; the caller destroys them with btf_vk_buffer_destroy): image i,
 * linear RGB floats interleaved, row-major, width x height x 3 (opts'
 * size, 0: the analysed one), lies in out[buffer[i]] from float index
 * offsets[i] (n entries each, filled here). Images fill a buffer in order
 * up to the device's largest storage buffer (maxStorageBufferRange, or the
 * testing limit of btf_gpu_set_max_buffer_bytes), then the next: no
 * device limit turns into a refusal while the images fit
 * BTF_GPU_DEVICE_BUFFERS buffers. Nothing passes through the host but
 * colour matching; the images are not checked for Inf or NaN here (the
 * formulas are btf_gpu_synthesise's, which checks them on download).
 * BTF_E_UNSUPPORTED when one image alone exceeds a buffer or all need more
 * than BTF_GPU_DEVICE_BUFFERS, the message naming the sizes; BTF_E_ARG for
 * bad requests as btf_gpu_synthesise. On error every out[] is NULL. */
btf_status btf_gpu_synthesise_device(btf_gpu *g, const btf_model *m, const int *subspaces, int n,
                                     const btf_synth_opts *opts, btf_vk_buffer **out,
                                     int *buffer, uint64_t *offsets, btf_error *err);

#endif
