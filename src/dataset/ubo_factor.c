/*
 * ubo_factor.c — the truncated SVD that the DFMF and FMF writers store
 * (docs/datasets.md, "UBO2014 .btf files", §3 and §4), computed from the
 * images of a callback:
 *
 *   DFMF  three matrices, one per channel c: row i = image i's channel c
 *         (i = view x n_lights + light), a column per pixel (§3);
 *   FMF   one matrix for the three channels: row 3 i + c = image i's
 *         channel c (§4: U[(v nL + l) nC + c]), a column per pixel; with
 *         log_values its entries are ln(value + 1e-5), the dynamic-range
 *         reduction the reader undoes (§4).
 *
 * Each matrix A (R rows x P pixels) goes through the Gram matrix of its
 * smaller side: with P <= R, G = A'A is accumulated image by image
 * (streamed; for FMF the three channels' Grams add up) and its top
 * eigenvectors are V, S x V = V diag(sqrt(lambda)); otherwise the images
 * are held (under max_bytes), G = AA', its eigenvectors are U's directions
 * and S x V = A'U. Either way S x V is then rounded to the stored scalar
 * type and each row of U is the least-squares fit to it (a K x K Cholesky
 * solve), so the stored factors are the best for each other; the error of
 * the values the reader will decode is measured on the way.
 */
#include <stdio.h>
#include "core/core.h"
#include "core/linalg.h"
#include "dataset/ubo2014.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define UBO_EPS 1e-5 /* §4: the dynamic-range reduction's epsilon, hard-coded by every reader */

typedef struct fact {
    const ubo_source *src;
    int fmf, log_values;
    uint64_t n, px, rows; /* images, pixels, rows per matrix (n, or 3 n for FMF) */
    int nm;               /* matrices: 3 (DFMF) or 1 (FMF) */
    int k, s;
} fact;

/* Per matrix after the eigen step: S x V (px x kc, rounded), its Cholesky. */
typedef struct chan {
    int kc;
    float *sxv, *u;
    double *chol;
} chan;

/* Image i, checked; with log_values its values become ln(value + eps).
 * total[c] gets the sum of squares of channel c's values. */
static btf_status get_image(const fact *f, uint64_t i, btf_image *img, double total[3],
                            btf_error *err)
{
    btf_status rc = ubo_get_image(f->src, i, img, err);
    for (uint64_t j = 0; rc == BTF_OK && j < 3 * f->px; j++) {
        double x = img->data[j];
        total[j % 3] += x * x;
        if (!f->log_values)
            continue;
        if (!(x > -UBO_EPS)) {
            int v = (int)(i / (uint64_t)f->src->lights->count);
            rc = btf__fail(err, BTF_E_ARG, "%s: image (view %d, light %d) has the value %g: the "
                           "logarithm of the dynamic-range reduction needs values above -1e-5",
                           f->src->path, v, (int)(i % (uint64_t)f->src->lights->count), x);
        }
        img->data[j] = (float)log(x + UBO_EPS);
    }
    if (rc)
        btf_image_free(img);
    return rc;
}

/* Matrix m's row r in images held as n x px x 3 floats (stride 3). */
static const float *held_row(const fact *f, const float *a, int m, uint64_t r)
{
    if (f->fmf)
        return a + (r / 3) * f->px * 3 + r % 3;
    return a + r * f->px * 3 + (uint64_t)m;
}

static btf_status finish_channel(chan *ch, int s, uint64_t px, btf_error *err)
{
    int kc = ch->kc;
    for (uint64_t i = 0; i < px * (uint64_t)kc; i++)
        ch->sxv[i] = ubo_stored(ch->sxv[i], s);
    ch->chol = btf__calloc((size_t)kc * kc, sizeof *ch->chol, err);
    if (!ch->chol)
        return BTF_E_NOMEM;
    for (uint64_t r = 0; r < px; r++)
        for (int i = 0; i < kc; i++)
            for (int j = 0; j <= i; j++)
                ch->chol[i * kc + j] += (double)ch->sxv[r * kc + i] * ch->sxv[r * kc + j];
    if (btf__linalg_cholesky(ch->chol, kc, 0, kc, ch->chol) != 0)
        return btf__fail(err, BTF_E_NUMERIC, "the rounded S x V's columns are dependent; use fewer "
                         "components");
    return BTF_OK;
}

/* The reader's sum (dataset/ubo_decode.c): 8 lanes, added in one fixed order. */
static float dot8(const float *a, const float *b, int k)
{
    float acc[8] = {0};
    for (int j = 0; j < k; j++)
        acc[j & 7] += a[j] * b[j];
    return ((acc[0] + acc[4]) + (acc[2] + acc[6])) + ((acc[1] + acc[5]) + (acc[3] + acc[7]));
}

/* U's row of one matrix row x (px values, stride 3): the least-squares fit
 * to the rounded S x V, rounded; the error of the decoded values (after
 * exp for log_values) into sum2, maxe. */
static void fit_row(const fact *f, const chan *ch, const float *x, float *urow, double *sum2,
                    double *maxe, double *work)
{
    int kc = ch->kc;
    for (int j = 0; j < kc; j++)
        work[j] = 0;
    for (uint64_t r = 0; r < f->px; r++) {
        double xv = x[3 * r];
        const float *sr = ch->sxv + r * (uint64_t)kc;
        for (int j = 0; j < kc; j++)
            work[j] += xv * sr[j];
    }
    btf__linalg_cholesky_solve(ch->chol, kc, work);
    for (int j = 0; j < kc; j++)
        urow[j] = ubo_stored((float)work[j], f->s);
    for (uint64_t r = 0; r < f->px; r++) {
        double v = dot8(urow, ch->sxv + r * (uint64_t)kc, kc), want = x[3 * r];
        double e = f->log_values ? exp(v) - exp(want) : v - want;
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

/* Streams the images into the three channels' pixel Grams (upper triangles). */
static btf_status accumulate_grams(const fact *f, gram_job *gj, double total[3], btf_error *err)
{
    uint64_t px = f->px;
    int nb = 32;
    float *xb = btf__alloc((size_t)nb * px * 3, sizeof *xb, err);
    if (!xb)
        return BTF_E_NOMEM;
    gj->xb = xb;
    int jobs = (int)((px + 15) / 16);
    btf_status rc = BTF_OK;
    for (uint64_t i0 = 0; i0 < f->n && rc == BTF_OK; i0 += (uint64_t)nb) {
        gj->nb = (int)(f->n - i0 < (uint64_t)nb ? f->n - i0 : (uint64_t)nb);
        for (int b = 0; b < gj->nb && rc == BTF_OK; b++) {
            btf_image img = {0};
            rc = get_image(f, i0 + (uint64_t)b, &img, total, err);
            if (rc == BTF_OK)
                memcpy(xb + (uint64_t)b * px * 3, img.data, px * 3 * sizeof(float));
            btf_image_free(&img);
        }
        if (rc == BTF_OK)
            rc = btf__pool_run(jobs, 0, gram_rows, gj, NULL, err);
        ubo_report(f->src, 0.45 * (double)(i0 + (uint64_t)gj->nb) / (double)f->n, "Gram matrices");
    }
    free(xb);
    return rc;
}

/* Fewer pixels than rows: S x V from the eigenvectors of A'A. */
static btf_status factor_by_pixels(const fact *f, chan ch[3], double total[3], btf_error *err)
{
    uint64_t px = f->px;
    gram_job gj = {.px = px, .rows_per_job = 16};
    btf_status rc = BTF_OK;
    for (int c = 0; c < 3 && rc == BTF_OK; c++) {
        gj.g[c] = btf__calloc(px * px, sizeof(double), err);
        rc = gj.g[c] ? BTF_OK : BTF_E_NOMEM;
    }
    if (rc == BTF_OK)
        rc = accumulate_grams(f, &gj, total, err);
    double *val = rc == BTF_OK ? btf__alloc((size_t)f->k, sizeof *val, err) : NULL;
    double *vec = rc == BTF_OK ? btf__alloc(px * (uint64_t)f->k, sizeof *vec, err) : NULL;
    if (rc == BTF_OK && (!val || !vec))
        rc = BTF_E_NOMEM;
    if (rc == BTF_OK && f->fmf) /* §4: one matrix; its Gram is the channels' sum */
        for (uint64_t i = 0; i < px * px; i++)
            gj.g[0][i] += gj.g[1][i] + gj.g[2][i];
    for (int m = 0; m < f->nm && rc == BTF_OK; m++) {
        double *g = gj.g[m];
        for (uint64_t r = 0; r < px; r++) /* mirror the upper triangle */
            for (uint64_t t = r + 1; t < px; t++)
                g[t * px + r] = g[r * px + t];
        rc = ubo_top_eigen(g, (int)px, f->k, val, vec, err);
        if (rc)
            break;
        ch[m].kc = ubo_keep_components(val, f->k);
        ch[m].sxv = btf__alloc(px * (uint64_t)ch[m].kc, sizeof(float), err);
        if (!ch[m].sxv) {
            rc = BTF_E_NOMEM;
            break;
        }
        for (uint64_t r = 0; r < px; r++)
            for (int j = 0; j < ch[m].kc; j++)
                ch[m].sxv[r * (uint64_t)ch[m].kc + j] =
                    (float)(vec[r * (uint64_t)f->k + j] * sqrt(val[j]));
        ubo_report(f->src, 0.45 + 0.1 * (m + 1) / f->nm, "eigenvectors");
    }
    for (int c = 0; c < 3; c++)
        free(gj.g[c]);
    free(val);
    free(vec);
    return rc;
}

/* Matrix m's row Gram AA' (rows x rows) from the held images. */
static void row_gram(const fact *f, const float *a, int m, double *g)
{
    uint64_t R = f->rows;
    for (uint64_t i = 0; i < R; i++)
        for (uint64_t j = i; j < R; j++) {
            const float *x = held_row(f, a, m, i), *y = held_row(f, a, m, j);
            double d = 0;
            for (uint64_t r = 0; r < f->px; r++)
                d += (double)x[3 * r] * y[3 * r];
            g[i * R + j] = g[j * R + i] = d;
        }
}

/* S x V = A'U for matrix m: px x kc. */
static void project_rows(const fact *f, const float *a, int m, const double *vec, float *sxv,
                         int kc)
{
    for (uint64_t r = 0; r < f->px; r++)
        for (int j = 0; j < kc; j++) {
            double d = 0;
            for (uint64_t i = 0; i < f->rows; i++)
                d += vec[i * (uint64_t)f->k + j] * held_row(f, a, m, i)[3 * r];
            sxv[r * (uint64_t)kc + j] = (float)d;
        }
}

/* Fewer rows than pixels: hold the images, AA', S x V = A'U. Returns the
 * images (n x px x 3) in *held for the U pass. */
static btf_status factor_by_rows(const fact *f, chan ch[3], double total[3], float **held,
                                 btf_error *err)
{
    uint64_t n = f->n, px = f->px, R = f->rows;
    float *a = btf__alloc(n * px * 3, sizeof *a, err);
    double *g = btf__alloc(R * R, sizeof *g, err);
    double *val = btf__alloc((size_t)f->k, sizeof *val, err);
    double *vec = btf__alloc(R * (uint64_t)f->k, sizeof *vec, err);
    btf_status rc = a && g && val && vec ? BTF_OK : BTF_E_NOMEM;
    for (uint64_t i = 0; i < n && rc == BTF_OK; i++) {
        btf_image img = {0};
        rc = get_image(f, i, &img, total, err);
        if (rc == BTF_OK)
            memcpy(a + i * px * 3, img.data, px * 3 * sizeof(float));
        btf_image_free(&img);
        ubo_report(f->src, 0.3 * (double)(i + 1) / (double)n, "reading images");
    }
    for (int m = 0; m < f->nm && rc == BTF_OK; m++) {
        row_gram(f, a, m, g);
        rc = ubo_top_eigen(g, (int)R, f->k, val, vec, err);
        if (rc)
            break;
        int kc = ch[m].kc = ubo_keep_components(val, f->k);
        ch[m].sxv = btf__alloc(px * (uint64_t)kc, sizeof(float), err);
        if (!ch[m].sxv) {
            rc = BTF_E_NOMEM;
            break;
        }
        project_rows(f, a, m, vec, ch[m].sxv, kc);
        ubo_report(f->src, 0.3 + 0.25 * (m + 1) / f->nm, "eigenvectors");
    }
    BTF_FREE_ALL(g, val, vec);
    if (rc) {
        free(a);
        return rc;
    }
    *held = a;
    return BTF_OK;
}

/* The U pass: every image's rows fitted to the rounded S x V. */
static btf_status fit_all(const fact *f, chan ch[3], const float *held, double sum2[3],
                          double maxe[3], btf_error *err)
{
    double work[UBO_MAX_COMPONENTS + 8], unused[3] = {0};
    btf_status rc = BTF_OK;
    for (uint64_t i = 0; i < f->n && rc == BTF_OK; i++) {
        btf_image img = {0};
        const float *x = held ? held + i * f->px * 3 : NULL;
        if (!x) {
            rc = get_image(f, i, &img, unused, err);
            x = img.data;
        }
        for (int c = 0; c < 3 && rc == BTF_OK; c++) {
            int m = f->fmf ? 0 : c;
            uint64_t r = f->fmf ? 3 * i + (uint64_t)c : i;
            fit_row(f, &ch[m], x + c, ch[m].u + r * (uint64_t)ch[m].kc, &sum2[c], &maxe[c], work);
        }
        btf_image_free(&img);
        ubo_report(f->src, 0.55 + 0.4 * (double)(i + 1) / (double)f->n, "fitting U");
    }
    return rc;
}

/* The working memory of the factorisation, to compare with the cap. */
static uint64_t working_bytes(const fact *f)
{
    if (f->px <= f->rows)
        return 3 * f->px * f->px * 8 + f->px * 32 * 12;
    return f->n * f->px * 12 + f->rows * f->rows * 8;
}

btf_status ubo_factorise(const ubo_source *src, int fmf, int log_values, int components,
                         int scalar, uint64_t max_bytes, ubo_factors *out,
                         btf_ubo2014_write_stats *st, btf_error *err)
{
    memset(out, 0, sizeof *out);
    fact f = {.src = src, .fmf = fmf, .log_values = log_values, .s = scalar};
    f.n = (uint64_t)src->views->count * src->lights->count;
    f.px = (uint64_t)src->width * src->height;
    f.rows = fmf ? 3 * f.n : f.n;
    f.nm = fmf ? 1 : 3;
    uint64_t small = f.rows < f.px ? f.rows : f.px;
    f.k = (int)((uint64_t)components < small ? (uint64_t)components : small);
    if (f.k > UBO_MAX_COMPONENTS)
        return btf__fail(err, BTF_E_ARG, "%s: %d components: at most %d", src->path, f.k,
                         UBO_MAX_COMPONENTS);
    uint64_t need = working_bytes(&f);
    if (small > 46340 || need > max_bytes)
        return btf__fail(err, BTF_E_UNSUPPORTED,
                         "%s: the factorisation of %llu rows of %llu pixels needs %llu bytes of "
                         "working memory, over the cap of %llu (btf_ubo2014_write_opts.max_bytes)",
                         src->path, (unsigned long long)f.rows, (unsigned long long)f.px,
                         (unsigned long long)need, (unsigned long long)max_bytes);
    chan ch[3] = {{0}};
    double total[3] = {0}, sum2[3] = {0}, maxe[3] = {0};
    float *held = NULL;
    btf_status rc = f.px <= f.rows ? factor_by_pixels(&f, ch, total, err)
                                   : factor_by_rows(&f, ch, total, &held, err);
    for (int m = 0; m < f.nm && rc == BTF_OK; m++) {
        rc = finish_channel(&ch[m], f.s, f.px, err);
        if (rc == BTF_OK) {
            ch[m].u = btf__alloc(f.rows * (uint64_t)ch[m].kc, sizeof(float), err);
            rc = ch[m].u ? BTF_OK : BTF_E_NOMEM;
        }
    }
    if (rc == BTF_OK)
        rc = fit_all(&f, ch, held, sum2, maxe, err);
    free(held);
    out->fmf = fmf;
    for (int m = 0; m < 3; m++) {
        free(ch[m].chol);
        out->kc[m] = ch[m].kc;
        out->u[m] = ch[m].u;
        out->sxv[m] = ch[m].sxv;
    }
    if (rc) {
        ubo_factors_free(out);
        return rc;
    }
    for (int c = 0; st && c < 3; c++) {
        st->components[c] = ch[fmf ? 0 : c].kc;
        st->rms_error[c] = sqrt(sum2[c] / (double)(f.n * f.px));
        st->max_error[c] = maxe[c];
        st->energy[c] = total[c] > 0 ? 1.0 - sum2[c] / total[c] : 1.0;
    }
    return BTF_OK;
}

void ubo_factors_free(ubo_factors *f)
{
    for (int m = 0; m < 3; m++) {
        free(f->u[m]);
        free(f->sxv[m]);
        f->u[m] = f->sxv[m] = NULL;
    }
}
