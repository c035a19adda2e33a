/*
 * ubo_write_pvf.c — the PVF variant of the Bonn .btf files (per-view
 * factorisation; docs/datasets.md, "UBO2014 .btf files", §5, known from
 * btflib alone): after the header (the common one of §2 with the
 * rotations field for "!PVF06FCR", without for "!PVF06FC"; or the legacy
 * one: the magic 301074, K, width, height, the slot count and the sampling)
 * come num_components and num_view_slots, then per view slot: the scalar
 * size, K, num_weights, dim, the K eigenvalues, Mean[dim], C[dim x K] and
 * W[num_weights x K].
 *
 * From images, each view's slot is the PCA of its pixels in the 3 nL
 * dimensions of (light, channel) (btflib's "light fields stacked
 * column-wise": value = W[y W + x] . C[3 l + c] + Mean[3 l + c]): the mean
 * over the pixels, then the top eigenvectors of the centred data's Gram
 * matrix on its smaller side (the covariance, or the pixels' Gram when
 * there are fewer pixels than dimensions) give C with unit columns; C and
 * the mean are rounded to the stored scalar and each pixel's W row is then
 * the least-squares fit to them, so the stored factors are the best for
 * each other; the error of the values the reader decodes is measured on
 * the way. The slots are held until the file is written (a view's K is
 * known only after its PCA: components with a zero eigenvalue are dropped).
 */
#include <stdio.h>
#include "core/core.h"
#include "core/linalg.h"
#include "dataset/ubo2014.h"

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
        rc = btf__fail(err, BTF_E_ARG, "%s: PVF signature \"%s\": expected !PVF06FCR or !PVF06FC",
                       path, pv->signature ? pv->signature : "(none)");
    int s = pv->scalar_size;
    if (rc == BTF_OK && s != 2 && s != 4 && s != 8)
        rc = btf__fail(err, BTF_E_ARG, "%s: scalar size %d: expected 2, 4 or 8", path, s);
    if (rc)
        return rc;
    uint64_t body = 0;
    for (int v = 0; v < views->count; v++) {
        const ubo_pvf_view *sl = &pv->views[v];
        if (!sl->mean || !sl->c || !sl->w)
            return btf__fail(err, BTF_E_ARG, "%s: PVF view %d has no matrices", path, v);
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

/* The column means of X: exact into mu, rounded to the stored scalar into
 * mean; X is then centred on the exact means in place. */
static void centre(float *x, uint64_t px, uint64_t dim, int s, float *mean, double *mu)
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
    for (uint64_t p = 0; p < px; p++)
        for (uint64_t d = 0; d < dim; d++)
            x[p * dim + d] = (float)(x[p * dim + d] - mu[d]);
}

/* The Gram matrix of the smaller side of the centred X (n x n, full):
 * X X' (pixels) when px <= dim, else X'X (the covariance, dim x dim). */
static void gram(const float *x, uint64_t px, uint64_t dim, double *g)
{
    int by_pixels = px <= dim;
    uint64_t n = by_pixels ? px : dim, len = by_pixels ? dim : px;
    for (uint64_t i = 0; i < n; i++)
        for (uint64_t j = i; j < n; j++) {
            double d = 0;
            for (uint64_t t = 0; t < len; t++)
                d += by_pixels ? (double)x[i * dim + t] * x[j * dim + t]
                               : (double)x[t * dim + i] * x[t * dim + j];
            g[i * n + j] = g[j * n + i] = d;
        }
}

/* C (dim x kc, unit columns): the eigenvectors themselves (covariance
 * side) or X' e_j / sqrt(lambda_j) (pixel side); rounded. */
static void components(const float *x, uint64_t px, uint64_t dim, const double *val,
                       const double *vec, uint32_t k, uint32_t kc, int s, float *c)
{
    for (uint64_t d = 0; d < dim; d++)
        for (uint32_t j = 0; j < kc; j++) {
            double v = 0; /* vec is px x k on the pixel side, dim x k otherwise */
            if (px <= dim) {
                for (uint64_t p = 0; p < px; p++)
                    v += vec[p * k + j] * x[p * dim + d];
                v = val[j] > 0 ? v / sqrt(val[j]) : 0;
            } else {
                v = vec[d * k + j];
            }
            c[d * kc + j] = ubo_stored((float)v, s);
        }
}

/* The reader's sum (dataset/ubo_decode.c): 8 lanes, added in one fixed order. */
static float dot8(const float *a, const float *b, uint32_t k)
{
    float acc[8] = {0};
    for (uint32_t j = 0; j < k; j++)
        acc[j & 7] += a[j] * b[j];
    return ((acc[0] + acc[4]) + (acc[2] + acc[6])) + ((acc[1] + acc[5]) + (acc[3] + acc[7]));
}

/* W (px x k): each pixel's fit to the rounded C and mean (x centred on the
 * exact means mu); the errors of the decoded values. */
static btf_status fit_weights(const float *x, const double *mu, uint64_t px, uint64_t dim,
                              uint32_t k, int s, const float *mean, const float *c, float *w,
                              double sum2[3], double maxe[3], btf_error *err)
{
    double *l = btf__calloc((size_t)k * k, sizeof *l, err), b[UBO_MAX_COMPONENTS];
    if (!l)
        return BTF_E_NOMEM;
    for (uint64_t d = 0; d < dim; d++)
        for (uint32_t i = 0; i < k; i++)
            for (uint32_t j = 0; j <= i; j++)
                l[i * k + j] += (double)c[d * k + i] * c[d * k + j];
    if (btf__linalg_cholesky(l, (int)k, 0, (int)k, l) != 0) {
        free(l);
        return btf__fail(err, BTF_E_NUMERIC, "a PVF view's rounded components are dependent; use "
                         "fewer components");
    }
    for (uint64_t p = 0; p < px; p++) {
        const float *row = x + p * dim;
        float *wr = w + p * k;
        for (uint32_t j = 0; j < k; j++)
            b[j] = 0;
        for (uint64_t d = 0; d < dim; d++)
            for (uint32_t j = 0; j < k; j++)
                b[j] += ((double)row[d] + mu[d] - mean[d]) * c[d * k + j];
        btf__linalg_cholesky_solve(l, (int)k, b);
        for (uint32_t j = 0; j < k; j++)
            wr[j] = ubo_stored((float)b[j], s);
        for (uint64_t d = 0; d < dim; d++) {
            double e = (double)(dot8(c + d * k, wr, k) + mean[d]) - ((double)row[d] + mu[d]);
            sum2[d % 3] += e * e;
            maxe[d % 3] = fmax(maxe[d % 3], fabs(e));
        }
    }
    free(l);
    return BTF_OK;
}

/* The working memory of one view. */
typedef struct pvf_work {
    float *x;
    double *g, *mu, *val, *vec;
} pvf_work;

static void work_free(pvf_work *w)
{
    BTF_FREE_ALL(w->x, w->g, w->mu, w->val, w->vec);
}

static btf_status work_alloc(pvf_work *w, uint64_t px, uint64_t dim, uint32_t k, btf_error *err)
{
    uint64_t n = px <= dim ? px : dim;
    w->x = btf__alloc(px * dim, sizeof *w->x, err);
    w->g = btf__alloc(n * n, sizeof *w->g, err);
    w->mu = btf__alloc(dim, sizeof *w->mu, err);
    w->val = btf__alloc(k, sizeof *w->val, err);
    w->vec = btf__alloc(n * k, sizeof *w->vec, err);
    return w->x && w->g && w->mu && w->val && w->vec ? BTF_OK : BTF_E_NOMEM;
}

/* The slots of all views, in memory until the file is written. */
typedef struct pvf_slots {
    ubo_pvf_view *v;
    int n;
} pvf_slots;

static void slots_free(pvf_slots *sl)
{
    for (int i = 0; sl->v && i < sl->n; i++) {
        BTF_FREE_ALL((void *)sl->v[i].ev, (void *)sl->v[i].mean, (void *)sl->v[i].c,
                     (void *)sl->v[i].w);
    }
    free(sl->v);
}

/* One view's slot: mean, C, W and the eigenvalues, allocated. */
static btf_status view_slot(const ubo_source *src, int v, uint32_t k, int s, pvf_work *w,
                            ubo_pvf_view *out, double total[3], double sum2[3], double maxe[3],
                            btf_error *err)
{
    uint64_t px = (uint64_t)src->width * src->height, dim = 3 * (uint64_t)src->lights->count;
    uint64_t n = px <= dim ? px : dim;
    uint32_t kn = (uint64_t)k < n ? k : (uint32_t)n;
    btf_status rc = read_view(src, v, w->x, total, err);
    if (rc)
        return rc;
    float *mean = btf__alloc(dim, sizeof *mean, err);
    if (!mean)
        return BTF_E_NOMEM;
    out->mean = mean;
    centre(w->x, px, dim, s, mean, w->mu);
    gram(w->x, px, dim, w->g);
    rc = ubo_top_eigen(w->g, (int)n, (int)kn, w->val, w->vec, err);
    if (rc)
        return rc;
    uint32_t kc = (uint32_t)ubo_keep_components(w->val, (int)kn);
    float *c = btf__alloc(dim * kc, sizeof *c, err), *wt = btf__alloc(px * kc, sizeof *wt, err);
    float *ev = btf__alloc(kc, sizeof *ev, err);
    out->c = c, out->w = wt, out->ev = ev;
    if (!c || !wt || !ev)
        return BTF_E_NOMEM;
    *out = (ubo_pvf_view){kc, (uint32_t)px, (uint32_t)dim, ev, mean, c, wt};
    for (uint32_t j = 0; j < kc; j++)
        ev[j] = (float)(w->val[j] / (double)px); /* the covariance's eigenvalues */
    components(w->x, px, dim, w->val, w->vec, kn, kc, s, c);
    return fit_weights(w->x, w->mu, px, dim, kc, s, mean, c, wt, sum2, maxe, err);
}

btf_status ubo_write_pvf_images(const ubo_source *src, const char *signature, int components,
                                int scalar, uint64_t max_bytes, btf_ubo2014_write_stats *st,
                                btf_error *err)
{
    const char *path = src->path;
    int nv = src->views->count;
    uint64_t px = (uint64_t)src->width * src->height, dim = 3 * (uint64_t)src->lights->count;
    uint64_t n = px <= dim ? px : dim;
    uint32_t k = (uint32_t)((uint64_t)components < n ? (uint64_t)components : n);
    if (k > UBO_MAX_COMPONENTS)
        return btf__fail(err, BTF_E_ARG, "%s: %u components: at most %d", path, k,
                         UBO_MAX_COMPONENTS);
    uint64_t need = px * dim * 4 + n * n * 8 + (uint64_t)nv * (dim + px) * k * 4;
    if (n > 46340 || need > max_bytes)
        return btf__fail(err, BTF_E_UNSUPPORTED, "%s: the PCA of %d views of %llu pixels in "
                         "%llu dimensions needs %llu bytes of working memory, over the cap of "
                         "%llu (btf_ubo2014_write_opts.max_bytes)", path, nv,
                         (unsigned long long)px, (unsigned long long)dim,
                         (unsigned long long)need, (unsigned long long)max_bytes);
    pvf_work w = {0};
    pvf_slots sl = {btf__calloc((size_t)nv, sizeof *sl.v, err), nv};
    btf_status rc = sl.v ? work_alloc(&w, px, dim, k, err) : BTF_E_NOMEM;
    double total[3] = {0}, sum2[3] = {0}, maxe[3] = {0};
    uint32_t kmax = 0;
    for (int v = 0; v < nv && rc == BTF_OK; v++) {
        rc = view_slot(src, v, k, scalar, &w, &sl.v[v], total, sum2, maxe, err);
        kmax = sl.v[v].k > kmax ? sl.v[v].k : kmax;
        ubo_report(src, 0.95 * (v + 1) / nv, "a PCA per view");
    }
    work_free(&w);
    ubo_pvf pv = {signature, 0, scalar, kmax, sl.v};
    if (rc == BTF_OK)
        rc = ubo_write_pvf(path, src->views, src->lights, src->width, src->height, &pv, err);
    slots_free(&sl);
    uint64_t pairs = (uint64_t)nv * src->lights->count;
    for (int c = 0; rc == BTF_OK && st && c < 3; c++) {
        st->components[c] = (int)kmax;
        st->rms_error[c] = sqrt(sum2[c] / (double)(pairs * px));
        st->max_error[c] = maxe[c];
        st->energy[c] = total[c] > 0 ? 1.0 - sum2[c] / total[c] : 1.0;
    }
    return rc;
}
