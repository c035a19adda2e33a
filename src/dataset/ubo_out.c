/*
 * ubo_out.c — what every Bonn .btf writer shares (docs/datasets.md,
 * "UBO2014 .btf files"): the header bytes as btflib's writer
 * emits them (the signature, the meta block of version 4 with channel names
 * R, G, B, §2a; the sampling with every view listing every light, §2b;
 * width and height, §2c), the output file (a temporary beside the target,
 * sized in advance, filled through a shared mapping, fsync'd and renamed
 * into place) and the stored scalars (half, float or double, §0).
 *
 * The writers of the variants (dataset/ubo_write.c: DFMF, FMF, BDIF;
 * dataset/ubo_write_pvf.c: PVF) sit above this file and call nothing else of
 * each other's, so the layering has no cycle.
 */
#include <stdio.h>
#include "core/core.h"
#include "dataset/ubo2014.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#define DEG2RAD (3.14159265358979323846 / 180.0)

void ubo_put(ubo_bytes *b, const void *data, size_t n)
{
    if (b->failed)
        return;
    if (b->n + n > b->cap) {
        size_t cap = b->cap ? b->cap * 2 : 1024;
        while (cap < b->n + n)
            cap *= 2;
        unsigned char *p = realloc(b->p, cap);
        if (!p) {
            b->failed = 1;
            return;
        }
        b->p = p;
        b->cap = cap;
    }
    memcpy(b->p + b->n, data, n);
    b->n += n;
}

void ubo_put_u32(ubo_bytes *b, uint32_t v)
{
    unsigned char x[4];
    ubo_wr32(x, v);
    ubo_put(b, x, 4);
}

void ubo_put_u8(ubo_bytes *b, unsigned v)
{
    unsigned char x = (unsigned char)v;
    ubo_put(b, &x, 1);
}

void ubo_put_f32(ubo_bytes *b, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    ubo_put_u32(b, u);
}

/* §2a: version 4, texts, ppmm 1, rgb_scale_factor 1, the cosine flag, no
 * XML, channels R, G, B; meta_size counts itself. */
static void put_meta(ubo_bytes *b, int cosine_flag)
{
    size_t start = b->n;
    ubo_put_u32(b, 0); /* meta_size, filled in below */
    ubo_put_u32(b, 4);
    char text[3][80] = {{"btfcar"}, {"none (synthetic)"}, {"none (synthetic)"}};
    ubo_put(b, text, sizeof text);
    ubo_put_f32(b, 1.0f);     /* ppmm */
    for (int c = 0; c < 3; c++)
        ubo_put_f32(b, 1.0f); /* rgb_scale_factor */
    ubo_put_u32(b, (uint32_t)cosine_flag);
    ubo_put_u32(b, 0);        /* no XML */
    ubo_put_u32(b, 3);
    for (int c = 0; c < 3; c++) {
        ubo_put_u32(b, 1);
        ubo_put(b, &"RGB"[c], 1);
    }
    if (!b->failed)
        ubo_wr32(b->p + start, (uint32_t)(b->n - start));
}

/* §2b: the views, each with the whole light list, radians. */
void ubo_put_sampling(ubo_bytes *b, const btf_dirset *views, const btf_dirset *lights)
{
    ubo_put_u32(b, (uint32_t)views->count);
    for (int v = 0; v < views->count; v++) {
        ubo_put_f32(b, (float)(views->dirs[v].theta * DEG2RAD));
        ubo_put_f32(b, (float)(views->dirs[v].phi * DEG2RAD));
        ubo_put_u32(b, (uint32_t)lights->count);
        for (int l = 0; l < lights->count; l++) {
            ubo_put_f32(b, (float)(lights->dirs[l].theta * DEG2RAD));
            ubo_put_f32(b, (float)(lights->dirs[l].phi * DEG2RAD));
        }
    }
}

void ubo_common_header(ubo_bytes *b, const char *sig, const btf_dirset *views,
                       const btf_dirset *lights, int width, int height, int cosine_flag)
{
    ubo_put(b, sig, strlen(sig));
    put_meta(b, cosine_flag);
    ubo_put_sampling(b, views, lights);
    ubo_put_u32(b, (uint32_t)width);
    ubo_put_u32(b, (uint32_t)height);
}

btf_status ubo_bytes_check(ubo_bytes *b, const char *path, btf_error *err)
{
    if (!b->failed)
        return BTF_OK;
    free(b->p);
    b->p = NULL;
    return btf__fail(err, BTF_E_NOMEM, "%s: out of memory for the header", path);
}

btf_status ubo_out_open(ubo_outfile *o, const char *path, uint64_t size, btf_error *err)
{
    memset(o, 0, sizeof *o);
    o->fd = -1;
    if (size > (uint64_t)SIZE_MAX / 2)
        return btf__fail(err, BTF_E_ARG, "%s: %llu bytes is too large", path,
                         (unsigned long long)size);
    btf_status rc = btf__tmp_create(path, o->tmp, sizeof o->tmp, &o->fd, err);
    if (rc)
        return rc;
    o->size = (size_t)size;
    /* The temporary is open for writing only; a shared writable mapping
     * needs it open for reading too: the same new file, reopened. */
    int rw = open(o->tmp, O_RDWR | O_NOFOLLOW | O_CLOEXEC);
    if (rw < 0) {
        rc = btf__fail(err, BTF_E_IO, "%s: cannot reopen %s: %s", path, o->tmp, strerror(errno));
    } else {
        close(o->fd);
        o->fd = rw;
    }
    if (rc == BTF_OK && ftruncate(o->fd, (off_t)size) != 0)
        rc = btf__fail(err, BTF_E_IO, "%s: cannot make a file of %llu bytes: %s", path,
                       (unsigned long long)size, strerror(errno));
    if (rc == BTF_OK) {
        o->map = mmap(NULL, o->size, PROT_READ | PROT_WRITE, MAP_SHARED, o->fd, 0);
        if (o->map == MAP_FAILED) {
            o->map = NULL;
            rc = btf__fail(err, BTF_E_IO, "%s: cannot map the output: %s", path, strerror(errno));
        }
    }
    if (rc) {
        close(o->fd);
        btf__abort_file(o->tmp);
        o->fd = -1;
    }
    return rc;
}

btf_status ubo_out_close(ubo_outfile *o, const char *path, btf_status rc, btf_error *err)
{
    if (o->map) {
        if (rc == BTF_OK && msync(o->map, o->size, MS_SYNC) != 0)
            rc = btf__fail(err, BTF_E_IO, "%s: cannot write: %s", path, strerror(errno));
        munmap(o->map, o->size);
        o->map = NULL;
    }
    if (o->fd >= 0) {
        if (rc == BTF_OK && fsync(o->fd) != 0)
            rc = btf__fail(err, BTF_E_IO, "%s: cannot write: %s", path, strerror(errno));
        if (close(o->fd) != 0 && rc == BTF_OK)
            rc = btf__fail(err, BTF_E_IO, "%s: cannot write: %s", path, strerror(errno));
        o->fd = -1;
        if (rc == BTF_OK)
            rc = btf__commit_file(o->tmp, path, err);
        else
            btf__abort_file(o->tmp);
    }
    return rc;
}

btf_status ubo_out_header(ubo_outfile *o, const char *path, ubo_bytes *h, uint64_t body,
                          unsigned char **p, btf_error *err)
{
    memset(o, 0, sizeof *o);
    o->fd = -1; /* closing it is a no-op until it is open */
    btf_status rc = ubo_bytes_check(h, path, err);
    if (rc == BTF_OK)
        rc = ubo_out_open(o, path, h->n + body, err);
    if (rc == BTF_OK) {
        memcpy(o->map, h->p, h->n);
        *p = o->map + h->n;
    }
    free(h->p);
    h->p = NULL;
    return rc;
}

void ubo_store(unsigned char *p, float v, int size)
{
    if (size == 2) {
        uint16_t h = ubo_float_to_half(v);
        p[0] = (unsigned char)h, p[1] = (unsigned char)(h >> 8);
    } else if (size == 4) {
        memcpy(p, &v, 4); /* little-endian hosts only, as every reader (§0) */
    } else {
        double d = v;
        memcpy(p, &d, 8);
    }
}

float ubo_stored(float v, int size)
{
    return size == 2 ? ubo_half_to_float(ubo_float_to_half(v)) : v;
}

btf_status ubo_store_all(unsigned char **p, const float *v, uint64_t n, int size, const char *path,
                         const char *what, btf_error *err)
{
    for (uint64_t i = 0; i < n; i++) {
        if (!isfinite(v[i]))
            return btf__fail(err, BTF_E_ARG, "%s: %s has a non-finite value at %llu", path, what,
                             (unsigned long long)i);
        ubo_store(*p, v[i], size);
        *p += size;
    }
    return BTF_OK;
}

btf_status ubo_check_sets(const char *path, const btf_dirset *views, const btf_dirset *lights,
                          int width, int height, btf_error *err)
{
    if (!views || !lights || views->count < 1 || lights->count < 1)
        return btf__fail(err, BTF_E_ARG, "%s: the view and light sets must not be empty", path);
    if (width < 1 || height < 1 || width > BTF_MAX_SIDE || height > BTF_MAX_SIDE)
        return btf__fail(err, BTF_E_ARG, "%s: image size %dx%d out of range 1..%d", path, width,
                         height, BTF_MAX_SIDE);
    if ((uint64_t)views->count * lights->count > UINT32_MAX / 3)
        return btf__fail(err, BTF_E_ARG, "%s: %d x %d (view, light) pairs do not fit the format",
                         path, views->count, lights->count);
    return BTF_OK;
}

btf_status ubo_get_image(const ubo_source *s, uint64_t i, btf_image *img, btf_error *err)
{
    int v = (int)(i / (uint64_t)s->lights->count), l = (int)(i % (uint64_t)s->lights->count);
    btf_status rc = s->image(s->user, v, l, img, err);
    if (rc == BTF_OK && (img->width != s->width || img->height != s->height || img->channels != 3))
        rc = btf__fail(err, BTF_E_ARG, "%s: image (view %d, light %d) is %dx%dx%d, expected %dx%dx3",
                       s->path, v, l, img->width, img->height, img->channels, s->width, s->height);
    uint64_t n = 3 * (uint64_t)s->width * s->height;
    for (uint64_t j = 0; rc == BTF_OK && j < n; j++)
        if (!isfinite(img->data[j]))
            rc = btf__fail(err, BTF_E_ARG, "%s: image (view %d, light %d) has a non-finite value",
                           s->path, v, l);
    if (rc)
        btf_image_free(img);
    return rc;
}

void ubo_report(const ubo_source *s, double frac, const char *what)
{
    if (s->progress)
        s->progress(s->progress_user, frac, what);
}
