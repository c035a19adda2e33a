/*
 * ubo_write_pvf.c — the PVF variant of the Bonn .btf files (per-view
 * factorisation; notes /work/shared/formats/ubo2014-btf.md §5, which has it
 * from btflib alone): after the header (the common one of §2 with the
 * rotations field for "!PVF06FCR", without for "!PVF06FC"; or the legacy
 * one: the magic 301074, K, width, height, the slot count and the sampling)
 * come num_components and num_view_slots, then per view slot: the scalar
 * size, K, num_weights, dim, the K eigenvalues, Mean[dim], C[dim x K] and
 * W[num_weights x K].
 *
 * From images, each view's slot is the PCA of its pixels in the 3 nL
 * dimensions of (light, channel) (btflib's "light fields stacked
 * column-wise": value = W[y W + x] . C[3 l + c] + Mean[3 l + c]): the mean
 * and the covariance over the pixels, its top eigenvectors as C; C and the
 * mean are rounded to the stored scalar and each pixel's W row is then the
 * least-squares fit to them, so the stored factors are the best for each
 * other; the error of the values the reader decodes is measured on the way.
 */
#include <stdio.h>
#include "core/core.h"
#include "io/ubo2014.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PVF_LEGACY_MAGIC 301074u /* §5: the legacy header's first field */

static uint64_t slot_bytes(int s, uint32_t k, uint32_t num_weights, uint32_t dim)
{
    return 13 + (uint64_t)s * ((uint64_t)k + dim + (uint64_t)dim * k + (uint64_t)num_weights * k);
}

/* The header up to the slots; rotations: 1 for "!PVF06FCR". */
static void put_pvf_header(ubo_bytes *h, const char *sig, int legacy, uint32_t k,
                           const btf_dirset *views, const btf_dirset *lights, int width,
                           int height)
{
    if (legacy) {
        ubo_put(h, sig, strlen(sig));
        ubo_put_u32(h, PVF_LEGACY_MAGIC);
        ubo_put_u32(h, k);
        ubo_put_u32(h, (uint32_t)width);
        ubo_put_u32(h, (uint32_t)height);
        ubo_put_u32(h, (uint32_t)views->count);
        ubo_put_sampling(h, views, lights);
        return;
    }
    ubo_common_header(h, sig, views, lights, width, height, 0);
    if (!strcmp(sig, "!PVF06FCR"))
        ubo_put_u32(h, 0); /* num_rotations */
    ubo_put_u32(h, k);
    ubo_put_u32(h, (uint32_t)views->count);
}

static int pvf_signature_ok(const char *sig)
{
    return sig && (!strcmp(sig, "!PVF06FCR") || !strcmp(sig, "!PVF06FC"));
}

/* One slot at *p (advanced). */
static btf_status put_slot(unsigned char **p, int s, const ubo_pvf_view *sl, const char *path,
                           btf_error *err)
{
    unsigned char *q = *p;
    *q++ = (unsigned char)s;
    ubo_wr32(q, sl->k);
    ubo_wr32(q + 4, sl->num_weights);
    ubo_wr32(q + 8, sl->dim);
    q += 12;
    btf_status rc = BTF_OK;
    for (uint32_t j = 0; j < sl->k; j++, q += s)
        ubo_store(q, sl->ev ? sl->ev[j] : 0.0f, s);
    rc = ubo_store_all(&q, sl->mean, sl->dim, s, path, "a PVF mean", err);
    if (rc == BTF_OK)
        rc = ubo_store_all(&q, sl->c, (uint64_t)sl->dim * sl->k, s, path, "a PVF C", err);
    if (rc == BTF_OK)
        rc = ubo_store_all(&q, sl->w, (uint64_t)sl->num_weights * sl->k, s, path, "a PVF W",
                           err);
    *p = q;
    return rc;
}

btf_status ubo_write_pvf(const char *path, const btf_dirset *views, const btf_dirset *lights,
                         int width, int height, const ubo_pvf *pv, btf_error *err)
{
    btf_status rc = ubo_check_sets(path, views, lights, width, height, err);
    if (rc == BTF_OK && !pvf_signature_ok(pv->signature))
        rc = btf_fail(err, BTF_E_ARG, "%s: PVF signature \"%s\": expected !PVF06FCR or !PVF06FC",
                      path, pv->signature ? pv->signature : "(none)");
    int s = pv->scalar_size;
    if (rc == BTF_OK && s != 2 && s != 4 && s != 8)
        rc = btf_fail(err, BTF_E_ARG, "%s: scalar size %d: expected 2, 4 or 8", path, s);
    if (rc)
        return rc;
    uint64_t body = 0;
    for (int v = 0; v < views->count; v++) {
        const ubo_pvf_view *sl = &pv->views[v];
        if (!sl->mean || !sl->c || !sl->w)
            return btf_fail(err, BTF_E_ARG, "%s: PVF view %d has no matrices", path, v);
        body += slot_bytes(s, sl->k, sl->num_weights, sl->dim);
    }
    ubo_bytes h = {0};
    put_pvf_header(&h, pv->signature, pv->legacy, pv->num_components, views, lights, width,
                   height);
    ubo_outfile o;
    unsigned char *p;
    rc = ubo_out_header(&o, path, &h, body, &p, err);
    for (int v = 0; rc == BTF_OK && v < views->count; v++)
        rc = put_slot(&p, s, &pv->views[v], path, err);
    return ubo_out_close(&o, path, rc, err);
}

/* ------------------------------------------------------- from the images */

/* One view's images as X (px x dim, dim = 3 nL; X[p][3 l + c]), and the
 * sums of squares per channel into total. */
static btf_status read_view(const ubo_source *src, int v, float *x, double total[3],
                            btf_error *err)
{
    int nl = src->lights->count;
    uint64_t px = (uint64_t)src->width * src->height, dim = 3 * (uint64_t)nl;
    btf_status rc = BTF_OK;
    for (int l = 0; l < nl && rc == BTF_OK; l++) {
        btf_image img = {0};
        rc = ubo_get_image(src, (uint64_t)v * nl + l, &img, err);
        for (uint64_t p = 0; rc == BTF_OK && p < px; p++)
            for (int c = 0; c < 3; c++) {
                float val = img.data[3 * p + (uint64_t)c];
                x[p * dim + 3 * (uint64_t)l + (uint64_t)c] = val;
                total[c] += (double)val * val;
            }
        btf_image_free(&img);
    }
    return rc;
}

/* The column means (rounded to the stored scalar) and the covariance
 * (dim x dim, full) of X about the exact means. */
static void mean_cov(const float *x, uint64_t px, uint64_t dim, int s, float *mean,
                     double *cov, double *mu)
{
    for (uint64_t d = 0; d < dim; d++)
        mu[d] = 0;
    for (uint64_t p = 0; p < px; p++)
        for (uint64_t d = 0; d < dim; d++)
            mu[d] += x[p * dim + d];
    for (uint64_t d = 0; d < dim; d++) {
        mu[d] /= (double)px;
        mean[d] = ubo_stored((float)mu[d], s);
    }
    memset(cov, 0, dim * dim * sizeof *cov);
    for (uint64_t p = 0; p < px; p++) {
        const float *row = x + p * dim;
        for (uint64_t d = 0; d < dim; d++) {
            double a = row[d] - mu[d];
            for (uint64_t e = d; e < dim; e++)
                cov[d * dim + e] += a * (row[e] - mu[e]);
        }
    }
    for (uint64_t d = 0; d < dim; d++)
        for (uint64_t e = d + 1; e < dim; e++)
            cov[e * dim + d] = cov[d * dim + e];
}

/* The reader's sum (io/ubo_decode.c): 8 lanes, added in one fixed order. */
static float dot8(const float *a, const float *b, uint32_t k)
{
    float acc[8] = {0};
    for (uint32_t j = 0; j < k; j++)
        acc[j & 7] += a[j] * b[j];
    return ((acc[0] + acc[4]) + (acc[2] + acc[6])) + ((acc[1] + acc[5]) + (acc[3] + acc[7]));
}

/* W (px x k): each pixel's fit to the rounded C and mean; the errors. */
static btf_status fit_weights(const float *x, uint64_t px, uint64_t dim, uint32_t k, int s,
                              const float *mean, const float *c, float *w, double sum2[3],
                              double maxe[3], btf_error *err)
{
    double *l = btf_calloc((size_t)k * k, sizeof *l, err), b[UBO_MAX_COMPONENTS];
    if (!l)
        return BTF_E_NOMEM;
    for (uint64_t d = 0; d < dim; d++)
        for (uint32_t i = 0; i < k; i++)
            for (uint32_t j = 0; j <= i; j++)
                l[i * k + j] += (double)c[d * k + i] * c[d * k + j];
    if (!ubo_cholesky(l, (int)k)) {
        free(l);
        return btf_fail(err, BTF_E_NUMERIC, "a PVF view's rounded components are dependent; use "
                        "fewer components");
    }
    for (uint64_t p = 0; p < px; p++) {
        const float *row = x + p * dim;
        float *wr = w + p * k;
        for (uint32_t j = 0; j < k; j++)
            b[j] = 0;
        for (uint64_t d = 0; d < dim; d++)
            for (uint32_t j = 0; j < k; j++)
                b[j] += ((double)row[d] - mean[d]) * c[d * k + j];
        ubo_chol_solve(l, (int)k, b);
        for (uint32_t j = 0; j < k; j++)
            wr[j] = ubo_stored((float)b[j], s);
        for (uint64_t d = 0; d < dim; d++) {
            double e = (double)(dot8(c + d * k, wr, k) + mean[d]) - row[d];
            sum2[d % 3] += e * e;
            maxe[d % 3] = fmax(maxe[d % 3], fabs(e));
        }
    }
    free(l);
    return BTF_OK;
}

/* Working memory of one view and the results of all. */
typedef struct pvf_work {
    float *x, *mean, *c, *w, *ev;
    double *cov, *mu, *val, *vec;
} pvf_work;

static void work_free(pvf_work *w)
{
    free(w->x);
    free(w->mean);
    free(w->c);
    free(w->w);
    free(w->ev);
    free(w->cov);
    free(w->mu);
    free(w->val);
    free(w->vec);
}

static btf_status work_alloc(pvf_work *w, uint64_t px, uint64_t dim, uint32_t k, btf_error *err)
{
    memset(w, 0, sizeof *w);
    w->x = btf_alloc(px * dim, sizeof *w->x, err);
    w->mean = btf_alloc(dim, sizeof *w->mean, err);
    w->c = btf_alloc(dim * k, sizeof *w->c, err);
    w->w = btf_alloc(px * k, sizeof *w->w, err);
    w->ev = btf_alloc(k, sizeof *w->ev, err);
    w->cov = btf_alloc(dim * dim, sizeof *w->cov, err);
    w->mu = btf_alloc(dim, sizeof *w->mu, err);
    w->val = btf_alloc(k, sizeof *w->val, err);
    w->vec = btf_alloc(dim * k, sizeof *w->vec, err);
    if (w->x && w->mean && w->c && w->w && w->ev && w->cov && w->mu && w->val && w->vec)
        return BTF_OK;
    work_free(w);
    return BTF_E_NOMEM;
}

/* One view's slot into w (C, mean, W, eigenvalues). */
static btf_status view_slot(const ubo_source *src, int v, uint32_t k, int s, pvf_work *w,
                            double total[3], double sum2[3], double maxe[3], btf_error *err)
{
    uint64_t px = (uint64_t)src->width * src->height, dim = 3 * (uint64_t)src->lights->count;
    btf_status rc = read_view(src, v, w->x, total, err);
    if (rc)
        return rc;
    mean_cov(w->x, px, dim, s, w->mean, w->cov, w->mu);
    rc = ubo_top_eigen(w->cov, (int)dim, (int)k, w->val, w->vec, err);
    if (rc)
        return rc;
    for (uint64_t i = 0; i < dim * k; i++)
        w->c[i] = ubo_stored((float)w->vec[i], s);
    for (uint32_t j = 0; j < k; j++)
        w->ev[j] = (float)w->val[j];
    return fit_weights(w->x, px, dim, k, s, w->mean, w->c, w->w, sum2, maxe, err);
}

btf_status ubo_write_pvf_images(const ubo_source *src, const char *signature, int components,
                                int scalar, uint64_t max_bytes, btf_ubo2014_write_stats *st,
                                btf_error *err)
{
    const char *path = src->path;
    int nv = src->views->count;
    uint64_t px = (uint64_t)src->width * src->height, dim = 3 * (uint64_t)src->lights->count;
    uint32_t k = (uint32_t)((uint64_t)components < dim ? (uint64_t)components : dim);
    if (k > UBO_MAX_COMPONENTS)
        return btf_fail(err, BTF_E_ARG, "%s: %u components: at most %d", path, k,
                        UBO_MAX_COMPONENTS);
    uint64_t need = px * dim * 4 + dim * dim * 8 + px * k * 4;
    if (dim > 46340 || need > max_bytes)
        return btf_fail(err, BTF_E_UNSUPPORTED, "%s: the PCA of a view's %llu pixels in %llu "
                        "dimensions needs %llu bytes of working memory, over the cap of %llu "
                        "(btf_ubo2014_write_opts.max_bytes)", path, (unsigned long long)px,
                        (unsigned long long)dim, (unsigned long long)need,
                        (unsigned long long)max_bytes);
    pvf_work w;
    btf_status rc = work_alloc(&w, px, dim, k, err);
    if (rc)
        return rc;
    ubo_bytes h = {0};
    put_pvf_header(&h, signature, 0, k, src->views, src->lights, src->width, src->height);
    ubo_outfile o;
    unsigned char *p;
    rc = ubo_out_header(&o, path, &h, (uint64_t)nv * slot_bytes(scalar, k, (uint32_t)px,
                                                                 (uint32_t)dim), &p, err);
    double total[3] = {0}, sum2[3] = {0}, maxe[3] = {0};
    for (int v = 0; v < nv && rc == BTF_OK; v++) {
        rc = view_slot(src, v, k, scalar, &w, total, sum2, maxe, err);
        ubo_pvf_view sl = {k, (uint32_t)px, (uint32_t)dim, w.ev, w.mean, w.c, w.w};
        if (rc == BTF_OK)
            rc = put_slot(&p, scalar, &sl, path, err);
        ubo_report(src, (double)(v + 1) / nv, "a PCA per view");
    }
    work_free(&w);
    rc = ubo_out_close(&o, path, rc, err);
    uint64_t n = (uint64_t)nv * src->lights->count;
    for (int c = 0; rc == BTF_OK && st && c < 3; c++) {
        st->components[c] = (int)k;
        st->rms_error[c] = sqrt(sum2[c] / (double)(n * px));
        st->max_error[c] = maxe[c];
        st->energy[c] = total[c] > 0 ? 1.0 - sum2[c] / total[c] : 1.0;
    }
    return rc;
}
