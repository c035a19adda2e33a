/*
 * synth_gpu.h — private GPU synthesis calls for other GPU passes of the
 * library (the render pass, render_gpu.c), not part of the public API
 * (include/btfcar.h): subspace images synthesised into one device buffer
 * that stays on the device, and the Vulkan layer of a btf_gpu so that
 * another file can create pipelines and dispatch on the same device
 * (gpu/vk.h). Defined in three files, each calling only those after it
 * (make check-layering):
 *   gpu/synth_gpu.c   the synthesis (btf__gpu_synthesise_device);
 *   gpu/gpu_handle.c  the btf_gpu handle, its accessors, the limits of an
 *                     image array on its device, the memory budget;
 *   gpu/gpu_images.c  image arrays: create, free, copy, download, upload.
 * Colour matching on the device is gpu/match_gpu.c's, the reflectance-field
 * renders gpu/rf_render_gpu.c's.
 */
#ifndef BTF_SYNTH_GPU_H
#define BTF_SYNTH_GPU_H

#include "btfcar.h"
#include "vk.h"

#include <stdint.h>

typedef struct btf_gpu_matcher btf_gpu_matcher;

/* The handle's fields, for the two files that make it up: gpu/gpu_handle.c
 * (open, close, the accessors) and gpu/synth_gpu.c (which runs the
 * synthesis pipelines and counts its jobs). Every other file goes through
 * the accessors. */
struct btf_gpu {
    btf_vk *vk;
    uint64_t max_buffer_bytes; /* 0: the device's limit */
    int jobs, batches;         /* of the last btf_gpu_synthesise */
    btf_vk_pipeline *field, *collapse, *unmix;
    btf_gpu_matcher *matcher; /* colour matching on the device */
};

/* The Vulkan device, queue and allocator of g (owned by g: valid until
 * btf_gpu_close; never destroy it). */
btf_vk *btf__gpu_vk(btf_gpu *g);
/* The largest storage buffer this btf_gpu uses: the device's limit, or
 * less where btf__gpu_set_max_buffer_bytes lowered it (tests). */
uint64_t btf__gpu_max_buffer_bytes(const btf_gpu *g);

/* The most device buffers an image array spreads over: the shaders that
 * read one (gpu/render.comp, gpu/match_*.comp) declare as many bindings;
 * how many a device takes comes from its limits (btf__gpu_images_buffers). */
#define BTF_GPU_DEVICE_BUFFERS 8

/* Images on the device: one array of floats laid over up to
 * BTF_GPU_DEVICE_BUFFERS storage buffers of `cap` floats each (the last
 * may be shorter): float index f lies in buf[f / cap] at f % cap. So no
 * device limit on one storage buffer bounds an image, only all of them
 * together (docs/gpu.md, "Images left on the device"). */
typedef struct btf_gpu_images {
    btf_vk_buffer *buf[BTF_GPU_DEVICE_BUFFERS]; /* NULL where unused */
    uint64_t cap;                               /* floats per buffer */
} btf_gpu_images;
/* Copies bytes between the host and the array at float offset off. */
btf_status btf__gpu_images_download(btf_vk *vk, const btf_gpu_images *im, uint64_t off,
                                    float *data, uint64_t floats, btf_error *err);
btf_status btf__gpu_images_upload(btf_vk *vk, const btf_gpu_images *im, uint64_t off,
                                  const float *data, uint64_t floats, btf_error *err);
void btf__gpu_images_free(btf_gpu_images *im);
/* Records into job a device-side copy of `floats` floats from src at byte
 * src_bytes into the array at float offset off, split where it crosses a
 * buffer (the synthesis' strips put in place). */
btf_status btf__gpu_images_copy_in(btf_vk_job *job, const btf_vk_buffer *src, uint64_t src_bytes,
                                   const btf_gpu_images *im, uint64_t off, uint64_t floats,
                                   btf_error *err);
/* The floats per buffer of g's arrays: its largest storage buffer, at most
 * 2^27 (so that eight of them index with 32-bit ints). */
uint64_t btf__gpu_images_cap(const btf_gpu *g);
/* The buffers one array of g's may span: BTF_GPU_DEVICE_BUFFERS, fewer
 * where the device binds fewer storage buffers per shader stage than the
 * render pass needs for two such arrays and its 6 other buffers
 * (maxPerStageDescriptorStorageBuffers). */
int btf__gpu_images_buffers(const btf_gpu *g);
/* An array of `floats` floats over at most `most` (<= BTF_GPU_DEVICE_BUFFERS)
 * buffers of cap floats; BTF_E_UNSUPPORTED (naming `what` and the sizes)
 * when they do not hold it. */
btf_status btf__gpu_images_create(btf_vk *vk, uint64_t floats, uint64_t cap, int most,
                                  const char *what, btf_gpu_images *out, btf_error *err);

/* Synthesises subspace images subspaces[0 .. n - 1] (1 <= n) with opts as
 * btf_gpu_synthesise does (the same bits, tileable included) into the
 * device array *out it creates (the caller frees it with
 * btf__gpu_images_free): image i, linear RGB floats interleaved,
 * row-major, width x height x 3 (opts' size, 0: the analysed one), starts
 * at float offsets[i] (n entries, filled here); the images follow one
 * another, and the buffers are as large as the device's largest storage
 * buffer allows (maxStorageBufferRange, or the testing limit of
 * btf__gpu_set_max_buffer_bytes). Nothing passes through the host but
 * colour matching; the images are not checked for Inf or NaN here (the
 * formulas are btf_gpu_synthesise's, which checks them on download).
 * BTF_E_UNSUPPORTED when all n images need more than
 * BTF_GPU_DEVICE_BUFFERS buffers, the message naming the sizes; BTF_E_ARG
 * for bad requests as btf_gpu_synthesise. On error *out holds nothing. */
btf_status btf__gpu_synthesise_device(btf_gpu *g, const btf_model *m, const int *subspaces, int n,
                                      const btf_synth_opts *opts, btf_gpu_images *out,
                                      uint64_t *offsets, btf_error *err);

/* Colour matching on the device (gpu/match_gpu.c, docs/gpu.md "Colour
 * matching on the device"): the pipelines, made once per btf_gpu. */
btf_status btf__gpu_matcher_create(btf_vk *vk, btf_gpu_matcher **out, btf_error *err);
void btf__gpu_matcher_free(btf_gpu_matcher *mt); /* NULL is fine */
/* The image of `subspace` at float offset off of *im (w x h RGB) in place:
 * times the structure layer's pattern (NULL or empty: none; from
 * btf__structure_pattern, at most the device's largest buffer), then, when
 * match, colour matched: the bits btf__structure_apply and btf__colour_match
 * give on the host. The image is not read back. */
btf_status btf__gpu_match_images(btf_vk *vk, const btf_gpu_matcher *mt, const btf_model *m,
                                 int subspace, int match, const btf_gpu_images *im,
                                 uint64_t off, int w, int h, const btf_image *pattern,
                                 btf_error *err);
/* g's matcher (made by btf_gpu_open). */
const btf_gpu_matcher *btf__gpu_match_pipes(const btf_gpu *g);

/* 1 when g is a CPU device (lavapipe). */
int btf__gpu_is_cpu(const btf_gpu *g);

/* Reached through the material interface (btfcar/material.h) by users;
 * declared here for the library and its tests. */
/* ------------------------------------- reflectance-field renders (GPU) */

/* btf__rf_render_flat and btf__rf_render_scene on g's Vulkan device
 * (gpu/rf_render_gpu.c,
 * gpu/rf_render.comp; docs/rf.md, "Rendering on the GPU"), with the
 * formulas of the CPU renders (one text, src/rf/btf_rf_shared.h): on
 * lavapipe the pixels are the CPU's bit for bit, on other devices within
 * the rounding of sqrt and division. The flat render uploads only the (at
 * most four) fields of the view and shades each distinct texel once; the
 * scene render traces on the host (threads: 0 all CPUs) and uploads every
 * field. A model whose codes exceed 4 of the device's largest storage
 * buffers is BTF_E_UNSUPPORTED. info (NULL: not wanted): trace_s (scene),
 * synth_s the upload of the model's fields and parameters, shade_s the
 * render pass with its download. */
btf_status btf__gpu_rf_render_flat(btf_gpu *g, const btf_rf_model *m, btf_dir view,
                                   btf_dir light, int width, int height, btf_image *out,
                                   btf_render_info *info, btf_error *err);
btf_status btf__gpu_rf_render_scene(btf_gpu *g, const btf_rf_model *m, const btf_scene *s,
                                    int width, int height, int threads, btf_image *out,
                                    btf_render_info *info, btf_error *err);

#endif
