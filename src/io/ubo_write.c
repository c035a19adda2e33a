/*
 * ubo_write.c — writing Bonn .btf files (notes
 * /work/shared/formats/ubo2014-btf.md): the common header as btflib's
 * writer emits it (meta block version 4 with channel names R, G, B, §2a;
 * the sampling with every view listing every light, §2b; width, height),
 * then a DFMF body (§3: no rotations, colour model as given, per channel
 * S, U and S x V) or a BDIF body (§6: 4 scan lines per chunk, compression
 * 0, an all-ones mask, no rotations, chunks of halves per texel).
 *
 * The output is a temporary file beside the target, sized in advance and
 * filled through a shared mapping (BDIF's texel-major order takes the
 * images one at a time that way), fsync'd and renamed into place.
 *
 * DFMF from images: per channel, the (view, light) x pixel matrix A's
 * truncated SVD through the Gram matrix of its smaller side: with fewer
 * pixels than images, G = A'A is accumulated image by image (streamed) and
 * its top eigenvectors are V, S x V = V diag(sqrt(lambda)); otherwise the
 * images are held (under max_bytes), G = AA', its eigenvectors are U's
 * directions and S x V = A'U. Either way S x V is then rounded to the
 * stored scalar type and each image's U row is the least-squares fit to it
 * (a K x K Cholesky solve), so the stored factors are the best for each
 * other; the error of the written values is measured on the way.
 */
#include <stdio.h>
#include "core/core.h"
#include "io/ubo2014.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#define DEG2RAD (3.14159265358979323846 / 180.0)

/* A growable byte buffer for the header. */
typedef struct bytes {
    unsigned char *p;
    size_t n, cap;
    int failed;
} bytes;

static void put(bytes *b, const void *data, size_t n)
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
static void put_u32(bytes *b, uint32_t v)
{
    unsigned char x[4] = {(unsigned char)v, (unsigned char)(v >> 8), (unsigned char)(v >> 16),
                          (unsigned char)(v >> 24)};
    put(b, x, 4);
}
static void put_u8(bytes *b, unsigned v)
{
    unsigned char x = (unsigned char)v;
    put(b, &x, 1);
}
static void put_f32(bytes *b, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    put_u32(b, u);
}

/* Signature, meta block (§2a), sampling (§2b), width and height (§2c). */
static void common_header(bytes *b, const char *sig, const btf_dirset *views,
                          const btf_dirset *lights, int width, int height, int cosine_flag)
{
    put(b, sig, strlen(sig));
    size_t meta_start = b->n;
    put_u32(b, 0); /* meta_size, filled in below */
    put_u32(b, 4);
    char text[3][80] = {{"btfcar"}, {"none (synthetic)"}, {"none (synthetic)"}};
    put(b, text, sizeof text);
    put_f32(b, 1.0f);                   /* ppmm */
    for (int c = 0; c < 3; c++)
        put_f32(b, 1.0f);               /* rgb_scale_factor */
    put_u32(b, (uint32_t)cosine_flag);
    put_u32(b, 0);                      /* no XML */
    put_u32(b, 3);
    for (int c = 0; c < 3; c++) {
        put_u32(b, 1);
        put(b, &"RGB"[c], 1);
    }
    if (!b->failed) {
        uint32_t m = (uint32_t)(b->n - meta_start);
        unsigned char *p = b->p + meta_start;
        p[0] = (unsigned char)m, p[1] = (unsigned char)(m >> 8), p[2] = (unsigned char)(m >> 16),
        p[3] = (unsigned char)(m >> 24);
    }
    put_u32(b, (uint32_t)views->count);
    for (int v = 0; v < views->count; v++) {
        put_f32(b, (float)(views->dirs[v].theta * DEG2RAD));
        put_f32(b, (float)(views->dirs[v].phi * DEG2RAD));
        put_u32(b, (uint32_t)lights->count);
        for (int l = 0; l < lights->count; l++) {
            put_f32(b, (float)(lights->dirs[l].theta * DEG2RAD));
            put_f32(b, (float)(lights->dirs[l].phi * DEG2RAD));
        }
    }
    put_u32(b, (uint32_t)width);
    put_u32(b, (uint32_t)height);
}

/* The output: a temporary file of the final size, mapped for writing. */
typedef struct outfile {
    char tmp[4200];
    int fd;
    unsigned char *map;
    size_t size;
} outfile;

static btf_status out_open(outfile *o, const char *path, uint64_t size, btf_error *err)
{
    memset(o, 0, sizeof *o);
    o->fd = -1;
    if (size > (uint64_t)SIZE_MAX / 2)
        return btf_fail(err, BTF_E_ARG, "%s: %llu bytes is too large", path,
                        (unsigned long long)size);
    btf_status rc = btf_tmp_create(path, o->tmp, sizeof o->tmp, &o->fd, err);
    if (rc)
        return rc;
    o->size = (size_t)size;
    /* The temporary is open for writing only; a shared writable mapping
     * needs it open for reading too: the same new file, reopened. */
    int rw = open(o->tmp, O_RDWR | O_NOFOLLOW | O_CLOEXEC);
    if (rw < 0) {
        rc = btf_fail(err, BTF_E_IO, "%s: cannot reopen %s: %s", path, o->tmp, strerror(errno));
    } else {
        close(o->fd);
        o->fd = rw;
    }
    if (rc == BTF_OK && ftruncate(o->fd, (off_t)size) != 0)
        rc = btf_fail(err, BTF_E_IO, "%s: cannot make a file of %llu bytes: %s", path,
                      (unsigned long long)size, strerror(errno));
    if (rc == BTF_OK) {
        o->map = mmap(NULL, o->size, PROT_READ | PROT_WRITE, MAP_SHARED, o->fd, 0);
        if (o->map == MAP_FAILED) {
            o->map = NULL;
            rc = btf_fail(err, BTF_E_IO, "%s: cannot map the output: %s", path, strerror(errno));
        }
    }
    if (rc) {
        close(o->fd);
        btf_abort_file(o->tmp);
        o->fd = -1;
    }
    return rc;
}

/* Finishes (rc 0: sync, close, rename) or abandons the output. */
static btf_status out_close(outfile *o, const char *path, btf_status rc, btf_error *err)
{
    if (o->map) {
        if (rc == BTF_OK && msync(o->map, o->size, MS_SYNC) != 0)
            rc = btf_fail(err, BTF_E_IO, "%s: cannot write: %s", path, strerror(errno));
        munmap(o->map, o->size);
        o->map = NULL;
    }
    if (o->fd >= 0) {
        if (rc == BTF_OK && fsync(o->fd) != 0)
            rc = btf_fail(err, BTF_E_IO, "%s: cannot write: %s", path, strerror(errno));
        if (close(o->fd) != 0 && rc == BTF_OK)
            rc = btf_fail(err, BTF_E_IO, "%s: cannot write: %s", path, strerror(errno));
        o->fd = -1;
        if (rc == BTF_OK)
            rc = btf_commit_file(o->tmp, path, err);
        else
            btf_abort_file(o->tmp);
    }
    return rc;
}

static void store_scalar(unsigned char *p, float v, int size)
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

/* The value a float becomes when stored with `size` bytes. */
static float stored_value(float v, int size)
{
    return size == 2 ? ubo_half_to_float(ubo_float_to_half(v)) : v;
}

static btf_status check_sets(const char *path, const btf_dirset *views, const btf_dirset *lights,
                             int width, int height, btf_error *err)
{
    if (!views || !lights || views->count < 1 || lights->count < 1)
        return btf_fail(err, BTF_E_ARG, "%s: the view and light sets must not be empty", path);
    if (width < 1 || height < 1 || width > BTF_MAX_SIDE || height > BTF_MAX_SIDE)
        return btf_fail(err, BTF_E_ARG, "%s: image size %dx%d out of range 1..%d", path, width,
                        height, BTF_MAX_SIDE);
    return BTF_OK;
}

btf_status btf_ubo2014_write_factors(const char *path, const btf_dirset *views,
                                     const btf_dirset *lights, int width, int height,
                                     const btf_ubo2014_factors *f, btf_error *err)
{
    btf_status rc = check_sets(path, views, lights, width, height, err);
    if (rc)
        return rc;
    int s = f->scalar_size ? f->scalar_size : 2;
    if (s != 2 && s != 4 && s != 8)
        return btf_fail(err, BTF_E_ARG, "%s: scalar size %d: expected 2, 4 or 8", path, s);
    int kmax = 0;
    for (int c = 0; c < 3; c++) {
        if (f->components[c] < 1 || !f->u[c] || !f->sxv[c])
            return btf_fail(err, BTF_E_ARG, "%s: channel %d has %d components or no matrices",
                            path, c, f->components[c]);
        kmax = f->components[c] > kmax ? f->components[c] : kmax;
    }
    uint64_t rows = (uint64_t)views->count * lights->count, cols = (uint64_t)width * height;
    if (rows > UINT32_MAX)
        return btf_fail(err, BTF_E_ARG, "%s: %llu (view, light) pairs do not fit the format",
                        path, (unsigned long long)rows);
    bytes h = {0};
    common_header(&h, "!DFMF08FCR", views, lights, width, height, f->cosine_flag);
    put_u32(&h, 0); /* num_rotations */
    put_u32(&h, (uint32_t)kmax);
    put_u32(&h, (uint32_t)f->colour_model);
    for (int i = 0; i < 3; i++)
        put_f32(&h, 0.0f);
    for (int i = 0; i < 9; i++)
        put_f32(&h, i % 4 == 0 ? 1.0f : 0.0f);
    if (h.failed) {
        free(h.p);
        return btf_fail(err, BTF_E_NOMEM, "%s: out of memory for the header", path);
    }
    uint64_t size = h.n;
    for (int c = 0; c < 3; c++)
        size += 13 + (uint64_t)s * f->components[c] * (1 + rows + cols);
    outfile o;
    rc = out_open(&o, path, size, err);
    if (rc) {
        free(h.p);
        return rc;
    }
    memcpy(o.map, h.p, h.n);
    unsigned char *p = o.map + h.n;
    free(h.p);
    for (int c = 0; c < 3 && rc == BTF_OK; c++) {
        uint32_t k = (uint32_t)f->components[c];
        *p++ = (unsigned char)s;
        uint32_t fields[3] = {k, (uint32_t)rows, (uint32_t)cols};
        for (int i = 0; i < 3; i++, p += 4)
            p[0] = (unsigned char)fields[i], p[1] = (unsigned char)(fields[i] >> 8),
            p[2] = (unsigned char)(fields[i] >> 16), p[3] = (unsigned char)(fields[i] >> 24);
        for (uint32_t j = 0; j < k; j++, p += s) { /* S: the norms of S x V's columns */
            double n2 = 0;
            for (uint64_t r = 0; r < cols; r++)
                n2 += (double)f->sxv[c][r * k + j] * f->sxv[c][r * k + j];
            store_scalar(p, (float)sqrt(n2), s);
        }
        for (uint64_t i = 0; i < rows * k; i++, p += s) {
            if (!isfinite(f->u[c][i]))
                rc = btf_fail(err, BTF_E_ARG, "%s: U of channel %d has a non-finite value", path, c);
            store_scalar(p, f->u[c][i], s);
        }
        for (uint64_t i = 0; i < cols * k; i++, p += s) {
            if (!isfinite(f->sxv[c][i]))
                rc = btf_fail(err, BTF_E_ARG, "%s: SxV of channel %d has a non-finite value", path,
                              c);
            store_scalar(p, f->sxv[c][i], s);
        }
    }
    return out_close(&o, path, rc, err);
}

/* ------------------------------------------------------------------ BDIF */

static btf_status write_bdif(const char *path, const btf_dirset *views, const btf_dirset *lights,
                             int width, int height, btf_pair_image_fn image, void *user,
                             const btf_ubo2014_write_opts *o, btf_ubo2014_write_stats *st,
                             btf_error *err)
{
    const uint32_t lines = 4;
    uint64_t n = (uint64_t)views->count * lights->count, px = (uint64_t)width * height;
    uint64_t per_texel = n * 3 * 2, a = (uint64_t)width * lines;
    uint64_t chunks = (px + a - 1) / a;
    if (a * per_texel > UINT32_MAX)
        return btf_fail(err, BTF_E_ARG, "%s: a chunk of %llu texels of %llu bytes exceeds the "
                        "format's 4 GiB chunk size", path, (unsigned long long)a,
                        (unsigned long long)per_texel);
    bytes h = {0};
    common_header(&h, "!BDIF06R2!", views, lights, width, height, 0);
    put_u32(&h, lines);
    put_u8(&h, 0);
    for (uint64_t i = 0; i < px; i++)
        put_u8(&h, 1);
    put_u32(&h, 0); /* num_rotations */
    if (h.failed) {
        free(h.p);
        return btf_fail(err, BTF_E_NOMEM, "%s: out of memory for the header", path);
    }
    uint64_t size = h.n + chunks * 4 + px * per_texel;
    outfile of;
    btf_status rc = out_open(&of, path, size, err);
    if (rc) {
        free(h.p);
        return rc;
    }
    memcpy(of.map, h.p, h.n);
    unsigned char *base = of.map + h.n;
    free(h.p);
    for (uint64_t i = 0; i < chunks; i++) {
        uint64_t t = i + 1 < chunks ? a : px - i * a;
        uint32_t b = (uint32_t)(t * per_texel);
        unsigned char *p = base + i * (4 + a * per_texel);
        p[0] = (unsigned char)b, p[1] = (unsigned char)(b >> 8), p[2] = (unsigned char)(b >> 16),
        p[3] = (unsigned char)(b >> 24);
    }
    double sum2[3] = {0}, maxe[3] = {0};
    for (int v = 0; v < views->count && rc == BTF_OK; v++)
        for (int l = 0; l < lights->count && rc == BTF_OK; l++) {
            btf_image img = {0};
            rc = image(user, v, l, &img, err);
            if (rc == BTF_OK && (img.width != width || img.height != height || img.channels != 3))
                rc = btf_fail(err, BTF_E_ARG, "%s: image (view %d, light %d) is %dx%dx%d, expected "
                              "%dx%dx3", path, v, l, img.width, img.height, img.channels, width,
                              height);
            uint64_t off = ((uint64_t)v * lights->count + l) * 6;
            for (uint64_t i = 0; rc == BTF_OK && i < px; i++) {
                unsigned char *p = base + (i / a) * (4 + a * per_texel) + 4 + (i % a) * per_texel + off;
                for (int c = 0; c < 3; c++) {
                    float x = img.data[3 * i + (uint64_t)c];
                    if (!isfinite(x)) {
                        rc = btf_fail(err, BTF_E_ARG, "%s: image (view %d, light %d) has a "
                                      "non-finite value", path, v, l);
                        break;
                    }
                    store_scalar(p + 2 * c, x, 2);
                    double e = (double)stored_value(x, 2) - x;
                    sum2[c] += e * e;
                    maxe[c] = fmax(maxe[c], fabs(e));
                }
            }
            btf_image_free(&img);
            if (o->progress)
                o->progress(o->progress_user, (double)(v * lights->count + l + 1) / (double)n,
                            "writing images");
        }
    rc = out_close(&of, path, rc, err);
    if (rc == BTF_OK && st) {
        for (int c = 0; c < 3; c++) {
            st->rms_error[c] = sqrt(sum2[c] / (double)(n * px));
            st->max_error[c] = maxe[c];
            st->energy[c] = 1.0;
        }
        st->bytes = size;
    }
    return rc;
}

/* ------------------------------------------------------------------ DFMF */

typedef struct fact {
    const char *path;
    const btf_dirset *views, *lights;
    int width, height;
    btf_pair_image_fn image;
    void *user;
    const btf_ubo2014_write_opts *o;
    uint64_t n, px;
    int k, s;
} fact;

static btf_status get_image(const fact *f, uint64_t i, btf_image *img, btf_error *err)
{
    int v = (int)(i / (uint64_t)f->lights->count), l = (int)(i % (uint64_t)f->lights->count);
    btf_status rc = f->image(f->user, v, l, img, err);
    if (rc == BTF_OK && (img->width != f->width || img->height != f->height || img->channels != 3))
        rc = btf_fail(err, BTF_E_ARG, "%s: image (view %d, light %d) is %dx%dx%d, expected %dx%dx3",
                      f->path, v, l, img->width, img->height, img->channels, f->width, f->height);
    for (uint64_t j = 0; rc == BTF_OK && j < 3 * f->px; j++)
        if (!isfinite(img->data[j]))
            rc = btf_fail(err, BTF_E_ARG, "%s: image (view %d, light %d) has a non-finite value",
                          f->path, v, l);
    if (rc)
        btf_image_free(img);
    return rc;
}

static void report(const fact *f, double frac, const char *what)
{
    if (f->o->progress)
        f->o->progress(f->o->progress_user, frac, what);
}

/* Cholesky of the k x k h (lower, in place); 0 if not positive definite. */
static int cholesky(double *h, int k)
{
    for (int j = 0; j < k; j++) {
        double d = h[j * k + j];
        for (int i = 0; i < j; i++)
            d -= h[j * k + i] * h[j * k + i];
        if (!(d > 0))
            return 0;
        d = sqrt(d);
        h[j * k + j] = d;
        for (int r = j + 1; r < k; r++) {
            double x = h[r * k + j];
            for (int i = 0; i < j; i++)
                x -= h[r * k + i] * h[j * k + i];
            h[r * k + j] = x / d;
        }
    }
    return 1;
}

static void chol_solve(const double *l, int k, double *b)
{
    for (int i = 0; i < k; i++) {
        double x = b[i];
        for (int j = 0; j < i; j++)
            x -= l[i * k + j] * b[j];
        b[i] = x / l[i * k + i];
    }
    for (int i = k - 1; i >= 0; i--) {
        double x = b[i];
        for (int j = i + 1; j < k; j++)
            x -= l[j * k + i] * b[j];
        b[i] = x / l[i * k + i];
    }
}

/* Per channel after the eigen step: S x V (px x kc, rounded), its Cholesky. */
typedef struct chan {
    int kc;
    float *sxv, *u;
    double *chol;
    double total; /* sum of squares of the channel */
} chan;

/* The number of components worth keeping: sqrt(lambda) above 1e-7 of the first. */
static int keep(const double *val, int k)
{
    int kc = 0;
    double top = val[0] > 0 ? sqrt(val[0]) : 0;
    while (kc < k && val[kc] > 0 && sqrt(val[kc]) > 1e-7 * top)
        kc++;
    return kc ? kc : 1;
}

static btf_status finish_channel(chan *ch, int s, uint64_t px, btf_error *err)
{
    int kc = ch->kc;
    for (uint64_t i = 0; i < px * (uint64_t)kc; i++)
        ch->sxv[i] = stored_value(ch->sxv[i], s);
    ch->chol = btf_calloc((size_t)kc * kc, sizeof *ch->chol, err);
    if (!ch->chol)
        return BTF_E_NOMEM;
    for (uint64_t r = 0; r < px; r++)
        for (int i = 0; i < kc; i++)
            for (int j = 0; j <= i; j++)
                ch->chol[i * kc + j] += (double)ch->sxv[r * kc + i] * ch->sxv[r * kc + j];
    if (!cholesky(ch->chol, kc))
        return btf_fail(err, BTF_E_NUMERIC, "the rounded S x V's columns are dependent; use fewer "
                        "components");
    return BTF_OK;
}

/* U's row of an image channel x (px values): the least-squares fit to the
 * rounded S x V, rounded; the error of the reconstruction into sum2, maxe. */
static void fit_row(const chan *ch, int s, uint64_t px, const float *x, int stride, float *urow,
                    double *sum2, double *maxe, double *work)
{
    int kc = ch->kc;
    for (int j = 0; j < kc; j++)
        work[j] = 0;
    for (uint64_t r = 0; r < px; r++) {
        double xv = x[r * (uint64_t)stride];
        const float *sr = ch->sxv + r * (uint64_t)kc;
        for (int j = 0; j < kc; j++)
            work[j] += xv * sr[j];
    }
    chol_solve(ch->chol, kc, work);
    for (int j = 0; j < kc; j++)
        urow[j] = stored_value((float)work[j], s);
    float a[8] = {0};
    (void)a;
    for (uint64_t r = 0; r < px; r++) {
        const float *sr = ch->sxv + r * (uint64_t)kc;
        float acc[8] = {0};
        for (int j = 0; j < kc; j++)
            acc[j & 7] += urow[j] * sr[j]; /* as the reader sums (io/ubo_decode.c) */
        float v = ((acc[0] + acc[4]) + (acc[2] + acc[6])) + ((acc[1] + acc[5]) + (acc[3] + acc[7]));
        double e = (double)v - x[r * (uint64_t)stride];
        *sum2 += e * e;
        if (fabs(e) > *maxe)
            *maxe = fabs(e);
    }
}

typedef struct gram_job {
    double *g[3];
    const float *xb; /* batch: nb images x px x 3 */
    int nb;
    uint64_t px;
    int rows_per_job;
} gram_job;

/* Rows [j*R, (j+1)*R) of the upper triangles: G_c[r][t] += sum_b x_b[r] x_b[t]. */
static btf_status gram_rows(void *user, int job, int worker, btf_error *err)
{
    (void)worker;
    (void)err;
    gram_job *g = user;
    uint64_t r0 = (uint64_t)job * g->rows_per_job, r1 = r0 + g->rows_per_job;
    if (r1 > g->px)
        r1 = g->px;
    for (int c = 0; c < 3; c++)
        for (uint64_t r = r0; r < r1; r++) {
            double *row = g->g[c] + r * g->px;
            for (int b = 0; b < g->nb; b++) {
                const float *x = g->xb + (uint64_t)b * g->px * 3;
                double a = x[3 * r + (uint64_t)c];
                if (a == 0)
                    continue;
                for (uint64_t t = r; t < g->px; t++)
                    row[t] += a * x[3 * t + (uint64_t)c];
            }
        }
    return BTF_OK;
}

/* Fewer pixels than images: stream the images into A'A. */
static btf_status factor_by_pixels(const fact *f, chan ch[3], double total[3], btf_error *err)
{
    uint64_t px = f->px;
    int nb = 32;
    gram_job gj = {.px = px, .rows_per_job = 16};
    float *xb = btf_alloc((size_t)nb * px * 3, sizeof *xb, err);
    btf_status rc = xb ? BTF_OK : BTF_E_NOMEM;
    for (int c = 0; c < 3 && rc == BTF_OK; c++) {
        gj.g[c] = btf_calloc(px * px, sizeof(double), err);
        rc = gj.g[c] ? BTF_OK : BTF_E_NOMEM;
    }
    gj.xb = xb;
    int jobs = (int)((px + 15) / 16);
    for (uint64_t i0 = 0; i0 < f->n && rc == BTF_OK; i0 += (uint64_t)nb) {
        gj.nb = (int)(f->n - i0 < (uint64_t)nb ? f->n - i0 : (uint64_t)nb);
        for (int b = 0; b < gj.nb && rc == BTF_OK; b++) {
            btf_image img = {0};
            rc = get_image(f, i0 + (uint64_t)b, &img, err);
            if (rc == BTF_OK) {
                memcpy(xb + (uint64_t)b * px * 3, img.data, px * 3 * sizeof(float));
                for (uint64_t j = 0; j < 3 * px; j++)
                    total[j % 3] += (double)img.data[j] * img.data[j];
            }
            btf_image_free(&img);
        }
        if (rc == BTF_OK)
            rc = btf_pool_run(jobs, 0, gram_rows, &gj, NULL, err);
        report(f, 0.45 * (double)(i0 + (uint64_t)gj.nb) / (double)f->n, "Gram matrices");
    }
    free(xb);
    double *val = rc == BTF_OK ? btf_alloc((size_t)f->k, sizeof *val, err) : NULL;
    double *vec = rc == BTF_OK ? btf_alloc(px * (uint64_t)f->k, sizeof *vec, err) : NULL;
    if (rc == BTF_OK && (!val || !vec))
        rc = BTF_E_NOMEM;
    for (int c = 0; c < 3 && rc == BTF_OK; c++) {
        double *g = gj.g[c];
        for (uint64_t r = 0; r < px; r++) /* mirror the upper triangle */
            for (uint64_t t = r + 1; t < px; t++)
                g[t * px + r] = g[r * px + t];
        rc = ubo_top_eigen(g, (int)px, f->k, val, vec, err);
        if (rc)
            break;
        ch[c].kc = keep(val, f->k);
        ch[c].sxv = btf_alloc(px * (uint64_t)ch[c].kc, sizeof(float), err);
        if (!ch[c].sxv) {
            rc = BTF_E_NOMEM;
            break;
        }
        for (uint64_t r = 0; r < px; r++)
            for (int j = 0; j < ch[c].kc; j++)
                ch[c].sxv[r * (uint64_t)ch[c].kc + j] =
                    (float)(vec[r * (uint64_t)f->k + j] * sqrt(val[j]));
        free(gj.g[c]);
        gj.g[c] = NULL;
        report(f, 0.45 + 0.1 * (c + 1) / 3.0, "eigenvectors");
    }
    for (int c = 0; c < 3; c++)
        free(gj.g[c]);
    free(val);
    free(vec);
    return rc;
}

/* Fewer images than pixels: hold them, AA', S x V = A'U. Returns the
 * images (n x px x 3) in *held for the U pass. */
static btf_status factor_by_images(const fact *f, chan ch[3], double total[3], float **held,
                                   btf_error *err)
{
    uint64_t n = f->n, px = f->px;
    float *a = btf_alloc(n * px * 3, sizeof *a, err);
    double *g = btf_alloc(n * n, sizeof *g, err);
    double *val = btf_alloc((size_t)f->k, sizeof *val, err);
    double *vec = btf_alloc(n * (uint64_t)f->k, sizeof *vec, err);
    btf_status rc = a && g && val && vec ? BTF_OK : BTF_E_NOMEM;
    for (uint64_t i = 0; i < n && rc == BTF_OK; i++) {
        btf_image img = {0};
        rc = get_image(f, i, &img, err);
        if (rc == BTF_OK) {
            memcpy(a + i * px * 3, img.data, px * 3 * sizeof(float));
            for (uint64_t j = 0; j < 3 * px; j++)
                total[j % 3] += (double)img.data[j] * img.data[j];
        }
        btf_image_free(&img);
        report(f, 0.3 * (double)(i + 1) / (double)n, "reading images");
    }
    for (int c = 0; c < 3 && rc == BTF_OK; c++) {
        for (uint64_t i = 0; i < n; i++)
            for (uint64_t j = i; j < n; j++) {
                double d = 0;
                const float *x = a + i * px * 3 + c, *y = a + j * px * 3 + c;
                for (uint64_t r = 0; r < px; r++)
                    d += (double)x[3 * r] * y[3 * r];
                g[i * n + j] = g[j * n + i] = d;
            }
        rc = ubo_top_eigen(g, (int)n, f->k, val, vec, err);
        if (rc)
            break;
        int kc = ch[c].kc = keep(val, f->k);
        ch[c].sxv = btf_calloc(px * (uint64_t)kc, sizeof(float), err);
        if (!ch[c].sxv) {
            rc = BTF_E_NOMEM;
            break;
        }
        for (uint64_t r = 0; r < px; r++)
            for (int j = 0; j < kc; j++) {
                double d = 0;
                for (uint64_t i = 0; i < n; i++)
                    d += vec[i * (uint64_t)f->k + j] * a[i * px * 3 + 3 * r + (uint64_t)c];
                ch[c].sxv[r * (uint64_t)kc + j] = (float)d;
            }
        report(f, 0.3 + 0.25 * (c + 1) / 3.0, "eigenvectors");
    }
    free(g);
    free(val);
    free(vec);
    if (rc) {
        free(a);
        return rc;
    }
    *held = a;
    return BTF_OK;
}

static btf_status write_dfmf(const char *path, const btf_dirset *views, const btf_dirset *lights,
                             int width, int height, btf_pair_image_fn image, void *user,
                             const btf_ubo2014_write_opts *o, btf_ubo2014_write_stats *st,
                             btf_error *err)
{
    fact f = {path, views, lights, width, height, image, user, o, 0, 0, 0, 0};
    f.n = (uint64_t)views->count * lights->count;
    f.px = (uint64_t)width * height;
    f.s = o->scalar_size;
    uint64_t small = f.n < f.px ? f.n : f.px;
    f.k = (int)((uint64_t)o->components < small ? (uint64_t)o->components : small);
    if (f.s != 2 && f.s != 4)
        return btf_fail(err, BTF_E_ARG, "%s: scalar size %d: expected 2 (half) or 4 (float)", path,
                        f.s);
    uint64_t need = f.px <= f.n ? 3 * f.px * f.px * 8 + f.px * 32 * 12
                                : f.n * f.px * 12 + f.n * f.n * 8;
    if (small > 46340 || need > o->max_bytes)
        return btf_fail(err, BTF_E_UNSUPPORTED,
                        "%s: the factorisation of %llu images of %llu pixels needs %llu bytes of "
                        "working memory, over the cap of %llu (btf_ubo2014_write_opts.max_bytes)",
                        path, (unsigned long long)f.n, (unsigned long long)f.px,
                        (unsigned long long)need, (unsigned long long)o->max_bytes);
    chan ch[3] = {{0}};
    double total[3] = {0}, sum2[3] = {0}, maxe[3] = {0};
    float *held = NULL;
    btf_status rc = f.px <= f.n ? factor_by_pixels(&f, ch, total, err)
                                : factor_by_images(&f, ch, total, &held, err);
    for (int c = 0; c < 3 && rc == BTF_OK; c++) {
        rc = finish_channel(&ch[c], f.s, f.px, err);
        if (rc == BTF_OK) {
            ch[c].u = btf_alloc(f.n * (uint64_t)ch[c].kc, sizeof(float), err);
            rc = ch[c].u ? BTF_OK : BTF_E_NOMEM;
        }
    }
    double work[4096 + 8];
    if (rc == BTF_OK && f.k > 4096)
        rc = btf_fail(err, BTF_E_ARG, "%s: %d components: at most 4096", path, f.k);
    for (uint64_t i = 0; i < f.n && rc == BTF_OK; i++) {
        btf_image img = {0};
        const float *x = held ? held + i * f.px * 3 : NULL;
        if (!x) {
            rc = get_image(&f, i, &img, err);
            x = img.data;
        }
        for (int c = 0; c < 3 && rc == BTF_OK; c++)
            fit_row(&ch[c], f.s, f.px, x + c, 3, ch[c].u + i * (uint64_t)ch[c].kc, &sum2[c],
                    &maxe[c], work);
        btf_image_free(&img);
        report(&f, 0.55 + 0.4 * (double)(i + 1) / (double)f.n, "fitting U");
    }
    free(held);
    if (rc == BTF_OK) {
        btf_ubo2014_factors fa = {.colour_model = 0, .scalar_size = f.s};
        for (int c = 0; c < 3; c++) {
            fa.components[c] = ch[c].kc;
            fa.u[c] = ch[c].u;
            fa.sxv[c] = ch[c].sxv;
        }
        rc = btf_ubo2014_write_factors(path, views, lights, width, height, &fa, err);
    }
    if (rc == BTF_OK && st) {
        for (int c = 0; c < 3; c++) {
            st->components[c] = ch[c].kc;
            st->rms_error[c] = sqrt(sum2[c] / (double)(f.n * f.px));
            st->max_error[c] = maxe[c];
            st->energy[c] = total[c] > 0 ? 1.0 - sum2[c] / total[c] : 1.0;
        }
    }
    for (int c = 0; c < 3; c++) {
        free(ch[c].sxv);
        free(ch[c].u);
        free(ch[c].chol);
    }
    report(&f, 1.0, "written");
    return rc;
}

btf_ubo2014_write_opts btf_ubo2014_write_defaults(void)
{
    return (btf_ubo2014_write_opts){.variant = BTF_UBO2014_DFMF, .components = 16,
                                    .scalar_size = 2, .max_bytes = (uint64_t)1 << 31};
}

btf_status btf_ubo2014_write(const char *path, const btf_dirset *views, const btf_dirset *lights,
                             int width, int height, btf_pair_image_fn image, void *user,
                             const btf_ubo2014_write_opts *opts, btf_ubo2014_write_stats *stats,
                             btf_error *err)
{
    btf_ubo2014_write_opts d = btf_ubo2014_write_defaults(), o = opts ? *opts : d;
    if (o.components == 0)
        o.components = d.components;
    if (o.scalar_size == 0)
        o.scalar_size = d.scalar_size;
    if (o.max_bytes == 0)
        o.max_bytes = d.max_bytes;
    if (stats)
        memset(stats, 0, sizeof *stats);
    btf_status rc = check_sets(path, views, lights, width, height, err);
    if (rc)
        return rc;
    if (!image)
        return btf_fail(err, BTF_E_ARG, "%s: no image callback", path);
    if (o.components < 1)
        return btf_fail(err, BTF_E_ARG, "%s: %d components: expected at least 1", path,
                        o.components);
    if ((uint64_t)views->count * lights->count > UINT32_MAX)
        return btf_fail(err, BTF_E_ARG, "%s: too many (view, light) pairs", path);
    if (o.variant == BTF_UBO2014_BDIF)
        rc = write_bdif(path, views, lights, width, height, image, user, &o, stats, err);
    else if (o.variant == BTF_UBO2014_DFMF)
        rc = write_dfmf(path, views, lights, width, height, image, user, &o, stats, err);
    else
        rc = btf_fail(err, BTF_E_ARG, "%s: variant %d: expected DFMF (0) or BDIF (1)", path,
                      o.variant);
    if (rc == BTF_OK && stats && o.variant == BTF_UBO2014_DFMF) {
        FILE *fp = fopen(path, "rb");
        if (fp) {
            fseek(fp, 0, SEEK_END);
            stats->bytes = (uint64_t)ftell(fp);
            fclose(fp);
        }
    }
    return rc;
}
