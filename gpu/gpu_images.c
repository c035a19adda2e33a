/*
 * gpu_images.c — images on the device as one array of floats laid over up
 * to BTF_GPU_DEVICE_BUFFERS storage buffers (btf_gpu_images, gpu/synth_gpu.h;
 * docs/gpu.md, "Images left on the device"): creating and freeing an array,
 * and every transfer to or from one — a device-side copy into it (each
 * synthesis strip put in place, gpu/synth_gpu.c), download and upload (an
 * image finished on the host, the render's maps in gpu/render_gpu.c, the
 * tests). An array spreads over several buffers so that no one buffer's
 * limit (maxStorageBufferRange) bounds an image; one walker, each_piece,
 * cuts every transfer where it crosses a buffer, so the host writes the
 * index arithmetic (float f in buffer f / cap at f % cap, the shaders'
 * too) once. How large an array of a btf_gpu may be (btf__gpu_images_cap,
 * btf__gpu_images_buffers) is a matter of the device's limits:
 * gpu/gpu_handle.c. Of the GPU files it calls only the Vulkan layer
 * (gpu/vk.h).
 */
#include "core/core.h"

#include "synth_gpu.h"
#include "vk.h"

#include <string.h>

/* The pieces of `floats` floats of an array from float offset off, one
 * per buffer they touch: fn(user, buffer, its byte offset, floats before
 * this piece, the piece's floats) in order, stopping at the first error.
 * Every transfer to or from an array walks it so. */
typedef btf_status (*piece_fn)(void *user, btf_vk_buffer *buf, uint64_t at_bytes,
                               uint64_t done, uint64_t n, btf_error *err);

static btf_status each_piece(const btf_gpu_images *im, uint64_t off, uint64_t floats,
                             piece_fn fn, void *user, btf_error *err)
{
    for (uint64_t done = 0; done < floats;) {
        uint64_t b = (off + done) / im->cap, at = (off + done) % im->cap;
        uint64_t n = im->cap - at < floats - done ? im->cap - at : floats - done;
        btf_status rc = fn(user, im->buf[b], 4 * at, done, n, err);
        if (rc)
            return rc;
        done += n;
    }
    return BTF_OK;
}

typedef struct piece_copy {
    btf_vk_job *job;
    const btf_vk_buffer *src;
    uint64_t src_bytes;
} piece_copy;

static btf_status copy_piece(void *user, btf_vk_buffer *buf, uint64_t at_bytes, uint64_t done,
                             uint64_t n, btf_error *err)
{
    piece_copy *c = user;
    return btf__vk_job_copy(c->job, c->src, c->src_bytes + 4 * done, buf, at_bytes, 4 * n, err);
}

btf_status btf__gpu_images_copy_in(btf_vk_job *job, const btf_vk_buffer *src, uint64_t src_bytes,
                                   const btf_gpu_images *im, uint64_t off, uint64_t floats,
                                   btf_error *err)
{
    piece_copy c = {job, src, src_bytes};
    return each_piece(im, off, floats, copy_piece, &c, err);
}

typedef struct piece_host {
    btf_vk *vk;
    float *down;      /* download into, or */
    const float *up;  /* upload from */
} piece_host;

static btf_status host_piece(void *user, btf_vk_buffer *buf, uint64_t at_bytes, uint64_t done,
                             uint64_t n, btf_error *err)
{
    piece_host *h = user;
    return h->down ? btf__vk_buffer_download(h->vk, buf, at_bytes, h->down + done, 4 * n, err)
                   : btf__vk_buffer_upload(h->vk, buf, at_bytes, h->up + done, 4 * n, err);
}

btf_status btf__gpu_images_download(btf_vk *vk, const btf_gpu_images *im, uint64_t off,
                                    float *data, uint64_t floats, btf_error *err)
{
    piece_host h = {vk, data, NULL};
    return each_piece(im, off, floats, host_piece, &h, err);
}

btf_status btf__gpu_images_upload(btf_vk *vk, const btf_gpu_images *im, uint64_t off,
                                  const float *data, uint64_t floats, btf_error *err)
{
    piece_host h = {vk, NULL, data};
    return each_piece(im, off, floats, host_piece, &h, err);
}

btf_status btf__gpu_images_create(btf_vk *vk, uint64_t floats, uint64_t cap, int most,
                                  const char *what, btf_gpu_images *out, btf_error *err)
{
    memset(out, 0, sizeof *out);
    out->cap = cap > 0 ? cap : 1;
    most = most < 1 ? 1 : most > BTF_GPU_DEVICE_BUFFERS ? BTF_GPU_DEVICE_BUFFERS : most;
    if (floats > (uint64_t)most * out->cap)
        return btf__fail(err, BTF_E_UNSUPPORTED, "%s need %.1f MiB, more than %d storage buffers "
                         "of %.1f MiB (the device's limits) hold; use the CPU backend", what,
                         4 * floats / 1048576.0, most, 4 * out->cap / 1048576.0);
    btf_status rc = BTF_OK;
    for (uint64_t b = 0; rc == BTF_OK && b * out->cap < floats; b++) {
        uint64_t part = floats - b * out->cap < out->cap ? floats - b * out->cap : out->cap;
        rc = btf__vk_buffer_create(vk, 4 * part, &out->buf[b], err);
    }
    if (rc)
        btf__gpu_images_free(out);
    return rc;
}

void btf__gpu_images_free(btf_gpu_images *im)
{
    for (int b = 0; im && b < BTF_GPU_DEVICE_BUFFERS; b++) {
        btf__vk_buffer_destroy(im->buf[b]);
        im->buf[b] = NULL;
    }
}
