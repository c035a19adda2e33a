/*
 * pca_views.c — the pixel-wise contrast of the report's compression
 * accounting (docs/report-compression.md): per view, a principal component analysis of its
 * n_lights images, each image one vector of width x height x 3 values in
 * 8-bit sRGB levels (report/srgb_levels.c). The eigen-images come from the
 * n_lights x n_lights Gram matrix of the centred images (the "snapshot"
 * trick: its eigenvectors u_k give the eigen-images X^T u_k / sqrt(lambda_k),
 * and the same eigenvalues), so a view costs n_lights^2 / 2 dot products of
 * image length and one small eigenproblem (core/linalg.c). The squared
 * error of keeping c components is the sum of the discarded eigenvalues, so
 * c and its error need no second pass over the pixels. Stored per view: the
 * mean image, c eigen-images and n_lights x c weights, each value in `bits`
 * bits. This is the kind of per-view representation the pixel-wise BTF
 * methods use (Meseth, Mueller & Klein 2003 fit per view; PCA per view is
 * the textbook form). docs/report-compression.md.
 *
 * Memory: one view's images (float and int16) per worker thread (views run in parallel over
 * core/pool.c); each view's result depends on that view alone, so the
 * results do not depend on the thread count.
 */
#include "report/report.h"
#include "core/linalg.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#ifdef __SSE2__
#include <emmintrin.h>
#endif

#define DEFAULT_MAX_RMS 2.0
#define DEFAULT_BITS 16
#define GRAM_BLOCK 512 /* pixels' values per pass: n_lights rows of it stay in cache */

btf_pca_opts btf_pca_defaults(void)
{
    btf_pca_opts o = {.struct_size = sizeof o};
    o.max_rms = DEFAULT_MAX_RMS;
    o.bits = DEFAULT_BITS;
    return o;
}

static btf_status resolve(const btf_pca_opts *opts, btf_pca_opts *o, btf_error *err)
{
    btf_pca_opts d = btf_pca_defaults();
    if (btf__opts_take(o, sizeof *o, opts, &d, "btf_pca_contrast", err))
        return BTF_E_ARG;
    if (o->max_rms == 0)
        o->max_rms = DEFAULT_MAX_RMS;
    if (o->bits == 0)
        o->bits = DEFAULT_BITS;
    return BTF_OK;
}

void btf__pca_result_free(btf_pca_result *r)
{
    if (!r)
        return;
    free(r->components);
    free(r->view_rms);
    memset(r, 0, sizeof *r);
}

typedef struct job_ctx {
    const btf_dataset *ds;
    const btf_dataset_info *info;
    const btf_srgb_levels_table *levels;
    int cap;                 /* the most components a view may keep */
    double max_rms;
    int *components;         /* [views] */
    double *residual;        /* [views]: the discarded eigenvalues' sum */
} job_ctx;

/* Sum of a[i] b[i] in double, over 8 lanes (products of floats are exact
 * in double; float products would leave about 10^-3 of a level in the
 * discarded eigenvalues of data of known rank). The path of values that
 * are not all whole levels (EXR, 16-bit files). */
static double dot(const float *a, const float *b, size_t n)
{
    double acc[8] = {0};
    size_t i = 0;
    for (; i + 8 <= n; i += 8)
        for (int k = 0; k < 8; k++)
            acc[k] += (double)a[i + k] * (double)b[i + k];
    double s = 0;
    for (; i < n; i++)
        s += (double)a[i] * b[i];
    for (int k = 0; k < 8; k++)
        s += acc[k];
    return s;
}

/* The same for whole levels 0..255 held as int16, exactly: the path of
 * 8-bit files. n <= GRAM_BLOCK keeps each 32-bit lane below 2^31
 * (GRAM_BLOCK / 8 steps of two products of at most 255^2). */
static int64_t dot16(const int16_t *a, const int16_t *b, size_t n)
{
    size_t i = 0;
    int64_t s = 0;
#ifdef __SSE2__
    __m128i acc = _mm_setzero_si128();
    for (; i + 8 <= n; i += 8)
        acc = _mm_add_epi32(acc, _mm_madd_epi16(_mm_loadu_si128((const __m128i *)(a + i)),
                                                _mm_loadu_si128((const __m128i *)(b + i))));
    int32_t lane[4];
    _mm_storeu_si128((__m128i *)lane, acc);
    s = (int64_t)lane[0] + lane[1] + lane[2] + lane[3];
#endif
    for (; i < n; i++)
        s += (int32_t)a[i] * b[i];
    return s;
}

/* The Gram matrix of the centred images (lower triangle and diagonal
 * filled, n x n). Whole levels: the uncentred Gram matrix exactly in
 * integers, centred afterwards (H G H, H = I - 1 1^T / n); else the images
 * are centred in place and their products summed in double. */
static void gram_matrix(float *x, int16_t *xi, int n, size_t d, double *gram)
{
    if (xi) {
        int64_t *g = (int64_t *)calloc((size_t)n * n, sizeof *g);
        /* (no memory: fall through to the float path) */
        if (g) {
            for (size_t p0 = 0; p0 < d; p0 += GRAM_BLOCK) {
                size_t len = d - p0 < GRAM_BLOCK ? d - p0 : GRAM_BLOCK;
                for (int i = 0; i < n; i++)
                    for (int j = 0; j <= i; j++)
                        g[i * n + j] += dot16(xi + (size_t)i * d + p0, xi + (size_t)j * d + p0, len);
            }
            for (int i = 0; i < n; i++)
                for (int j = 0; j < i; j++)
                    g[j * n + i] = g[i * n + j];
            double total = 0;
            double *row = (double *)calloc((size_t)n, sizeof *row);
            if (row) {
                for (int i = 0; i < n; i++) {
                    int64_t r = 0;
                    for (int j = 0; j < n; j++)
                        r += g[i * n + j];
                    row[i] = (double)r;
                    total += (double)r;
                }
                for (int i = 0; i < n; i++)
                    for (int j = 0; j <= i; j++)
                        gram[i * n + j] = ((double)g[i * n + j] - row[i] / n) - row[j] / n +
                                          total / ((double)n * n);
                free(row);
                free(g);
                return;
            }
            free(g);
        }
    }
    for (size_t p = 0; p < d; p++) {
        double mean = 0;
        for (int l = 0; l < n; l++)
            mean += x[(size_t)l * d + p];
        float mu = (float)(mean / n);
        for (int l = 0; l < n; l++)
            x[(size_t)l * d + p] -= mu;
    }
    for (size_t p0 = 0; p0 < d; p0 += GRAM_BLOCK) {
        size_t len = d - p0 < GRAM_BLOCK ? d - p0 : GRAM_BLOCK;
        for (int i = 0; i < n; i++)
            for (int j = 0; j <= i; j++)
                gram[i * n + j] += dot(x + (size_t)i * d + p0, x + (size_t)j * d + p0, len);
    }
}

static btf_status view_job(void *user, int view, int worker, btf_error *err)
{
    (void)worker;
    job_ctx *c = user;
    const btf_dataset_info *info = c->info;
    int n = info->n_lights;
    size_t d = (size_t)info->width * info->height * 3;
    float *x = btf__alloc((size_t)n * d, sizeof *x, NULL);
    int16_t *xi = btf__alloc((size_t)n * d, sizeof *xi, NULL);
    double *gram = btf__calloc((size_t)n * n, sizeof *gram, NULL);
    double *val = btf__alloc((size_t)n, sizeof *val, NULL);
    double *vec = btf__alloc((size_t)n * n, sizeof *vec, NULL);
    btf_image img = {0};
    btf_status rc = BTF_OK;
    if (!x || !xi || !gram || !val || !vec) {
        rc = btf__fail(err, BTF_E_NOMEM, "%s: out of memory for the images of view %d (%zu x %zu values)",
                       info->root, view, (size_t)n, d);
        goto done;
    }
    int whole = 1; /* every value a whole level (8-bit files) */
    for (int l = 0; l < n; l++) {
        if ((rc = btf_dataset_read(c->ds, view, l, &img, err)))
            goto done;
        if (img.width != info->width || img.height != info->height || img.channels != 3) {
            rc = btf__fail(err, BTF_E_DATA, "%s: %dx%d image of %d channels (expected %dx%d RGB)",
                           btf_dataset_path(c->ds, view, l), img.width, img.height,
                           img.channels, info->width, info->height);
            goto done;
        }
        float *row = x + (size_t)l * d;
        int16_t *irow = xi + (size_t)l * d;
        btf__srgb_levels(c->levels, img.data, d, row);
        for (size_t p = 0; p < d && whole; p++) {
            irow[p] = (int16_t)row[p];
            whole = (float)irow[p] == row[p];
        }
        btf_image_free(&img);
    }
    gram_matrix(x, whole ? xi : NULL, n, d, gram);
    for (int i = 0; i < n; i++)
        for (int j = 0; j < i; j++)
            gram[j * n + i] = gram[i * n + j];
    /* Until the off-diagonal part vanishes (at most 100 sweeps): the
     * rule the report's numbers have been made with. */
    static const btf_linalg_jacobi_rule rule = {.max_sweeps = 100, .relative = 1e-30};
    if (btf__linalg_sym_eigen(gram, n, &rule, val, vec) != 0) {
        rc = btf__fail(err, BTF_E_NOMEM, "%s: out of memory for view %d's eigenproblem",
                       info->root, view);
        goto done;
    }
    /* residual[c] = sum of the eigenvalues from c on (negative ones are
     * rounding: 0). The smallest c within the cap whose RMS error meets
     * the target; the cap itself when none does. */
    double allowed = c->max_rms * c->max_rms * (double)n * (double)d;
    double tail = 0;
    for (int k = n - 1; k >= c->cap; k--)
        tail += val[k] > 0 ? val[k] : 0;
    int keep = c->cap;
    double kept_tail = tail;
    for (int k = c->cap - 1; k >= 0; k--) {
        double t = tail + (val[k] > 0 ? val[k] : 0);
        if (t > allowed)
            break;
        tail = t;
        keep = k;
        kept_tail = t;
    }
    if (!isfinite(kept_tail)) {
        rc = btf__fail(err, BTF_E_NUMERIC, "%s: view %d: the PCA's error is not finite",
                       info->root, view);
        goto done;
    }
    c->components[view] = keep;
    c->residual[view] = kept_tail;
done:
    btf_image_free(&img);
    BTF_FREE_ALL(x, xi, gram, val, vec);
    return rc;
}

btf_status btf__pca_contrast(const btf_dataset *ds, const btf_pca_opts *opts,
                             btf_pca_result *out, btf_error *err)
{
    if (!out)
        return btf__fail(err, BTF_E_ARG, "dataset: no PCA result to fill");
    memset(out, 0, sizeof *out);
    if (!ds)
        return btf__fail(err, BTF_E_ARG, "dataset: no dataset for the PCA contrast");
    double t0 = btf__now();
    const btf_dataset_info *info = btf_dataset_get_info(ds);
    btf_pca_opts o;
    if (resolve(opts, &o, err))
        return BTF_E_ARG;
    if (!(o.max_rms > 0) || !isfinite(o.max_rms))
        return btf__fail(err, BTF_E_ARG, "%s: PCA error target %g (expected a finite value > 0, "
                         "in 8-bit levels)", info->root, o.max_rms);
    if (o.bits < 1 || o.bits > 32)
        return btf__fail(err, BTF_E_ARG, "%s: %d bits per stored value (expected 1..32)",
                         info->root, o.bits);
    if (o.max_components < 0 || o.max_components > info->n_lights)
        return btf__fail(err, BTF_E_ARG, "%s: at most %d components (expected 0..%d, the lights)",
                         info->root, o.max_components, info->n_lights);
    if (o.threads < 0)
        return btf__fail(err, BTF_E_ARG, "%s: %d threads (expected 0 for all CPUs, or more)",
                         info->root, o.threads);
    btf_srgb_levels_table table;
    btf__srgb_levels_init(&table);
    job_ctx c = {ds, info, &table, o.max_components ? o.max_components : info->n_lights,
                 o.max_rms, NULL, NULL};
    c.components = btf__calloc((size_t)info->n_views, sizeof *c.components, NULL);
    c.residual = btf__calloc((size_t)info->n_views, sizeof *c.residual, NULL);
    out->view_rms = btf__calloc((size_t)info->n_views, sizeof *out->view_rms, NULL);
    if (!c.components || !c.residual || !out->view_rms) {
        BTF_FREE_ALL(c.components, c.residual, out->view_rms);
        out->view_rms = NULL;
        return btf__fail(err, BTF_E_NOMEM, "%s: out of memory", info->root);
    }
    btf_pool_progress pr = {o.progress, o.progress_user, "PCA per view", 0, 1, 1};
    btf_status rc = btf__pool_run(info->n_views, o.threads, view_job, &c, &pr, err);
    if (rc) {
        free(c.components);
        free(c.residual);
        btf__pca_result_free(out);
        return rc;
    }
    btf__raw_bytes_of(info, &out->raw);
    out->views = info->n_views;
    out->lights = info->n_lights;
    out->width = info->width;
    out->height = info->height;
    out->components = c.components;
    size_t d = (size_t)info->width * info->height * 3;
    double values = (double)info->n_lights * (double)d, residual = 0, comps = 0;
    out->min_components = info->n_lights;
    for (int v = 0; v < info->n_views; v++) {
        int k = c.components[v];
        out->view_rms[v] = sqrt(c.residual[v] / values);
        residual += c.residual[v];
        comps += k;
        out->min_components = k < out->min_components ? k : out->min_components;
        out->max_components = k > out->max_components ? k : out->max_components;
        uint64_t stored = (uint64_t)d * (uint64_t)(1 + k) + (uint64_t)info->n_lights * k;
        out->bytes += (stored * (uint64_t)o.bits + 7) / 8;
    }
    free(c.residual);
    out->mean_components = comps / info->n_views;
    out->rms = sqrt(residual / (values * info->n_views));
    out->ratio = (double)out->raw.raw / (double)out->bytes;
    out->seconds = btf__now() - t0;
    return BTF_OK;
}
