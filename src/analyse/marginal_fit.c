/*
 * marginal_fit.c — the marginal transfer of a subspace (docs/synthesis.md,
 * "Marginals"). The CAR model of paper section II.C reproduces a
 * band's second-order statistics, and its fields, linear filters of
 * Gaussian noise, have Gaussian marginals; the material's decorrelated
 * channels are skewed. This stage keeps what synthesis needs to give each
 * band the exemplar's histogram (src/synth/marginal.c applies it):
 *
 *   - the exemplar's quantiles of each decorrelated channel at the knots'
 *     probabilities (the minimum, j / 31 for j = 1..30, the maximum),
 *   - the mean and standard deviation of the same band of a synthesis of
 *     the model itself (512 x 512, seed MEASURE_SEED, no transfer): the
 *     Gaussian the knots are placed on; measured, not derived from the
 *     bands' variances, so that whatever the pyramid and the CAR fits make
 *     of the variance is what the map starts from,
 *   - the exemplar's linear RGB range, its low end at least 0: the box the
 *     RGB result is clamped to,
 *   - the exemplar's CIE L*, a*, b* quantiles at the same probabilities,
 *     for colour matching (synth/colour_match.c, format 1.3).
 */
#include "analyse/analyse.h"
#include "car/car.h"
#include "core/core.h"
#include "synth/synth.h"
#include "model/model.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MEASURE_SIDE 512
#define MEASURE_SEED 0x6d617267u /* "marg" */

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The exemplar's quantiles of one band (sorted in place): linear between
 * order statistics at h = (n - 1) p, p = j / (knots - 1); the ends are the
 * minimum and the maximum. Rounded to float, then made nondecreasing (the
 * rounding is monotone already; this only guards it). */
static void band_quantiles(double *v, size_t n, float *q)
{
    qsort(v, n, sizeof *v, cmp_double);
    for (int j = 0; j < BTF_MARGIN_KNOTS; j++) {
        double h = (double)(n - 1) * j / (BTF_MARGIN_KNOTS - 1);
        size_t i = (size_t)h;
        double f = h - (double)i;
        double x = i + 1 < n ? v[i] + f * (v[i + 1] - v[i]) : v[n - 1];
        q[j] = (float)x;
        if (j > 0 && q[j] < q[j - 1])
            q[j] = q[j - 1];
    }
}

/* Mean and standard deviation of each band of a synthesis without the
 * transfer, its RGB decorrelated again with the subspace's basis. */
static btf_status measure_synthesis(const btf_model *m, int subspace, float mean[3],
                                    float sd[3], btf_error *err)
{
    btf_model tmp = *m; /* the same model with this subspace's transfer off */
    btf_subspace_model sm = m->subspaces[subspace];
    sm.marginal.knots = 0;
    tmp.subspaces = &sm;
    tmp.n_subspaces = 1;
    tmp.index = NULL;
    tmp.views.count = tmp.lights.count = 0;
    tmp.internal = NULL; /* kept margins are indexed by subspace: computed afresh */
    tmp.albedo = NULL;   /* the fields' own bands, before the structure layer */
    btf_synth_opts so = btf_synth_defaults();
    so.width = so.height = MEASURE_SIDE;
    so.seed = MEASURE_SEED;
    so.match_colours = -1; /* the field's own distribution, before any map */
    btf_image out = {0};
    btf_status rc = btf_synthesise_image(&tmp, 0, &so, &out, err);
    if (rc)
        return rc;
    size_t n = (size_t)out.width * out.height;
    double *bands[3] = {NULL, NULL, NULL};
    for (int b = 0; b < 3 && rc == BTF_OK; b++)
        if (!(bands[b] = btf__alloc(n, sizeof(double), err)))
            rc = BTF_E_NOMEM;
    if (rc == BTF_OK) {
        btf__decorrelate(&out, sm.mean, sm.basis, bands);
        for (int b = 0; b < 3; b++) {
            double s = 0.0, ss = 0.0;
            for (size_t i = 0; i < n; i++)
                s += bands[b][i];
            double mu = s / (double)n;
            for (size_t i = 0; i < n; i++)
                ss += (bands[b][i] - mu) * (bands[b][i] - mu);
            mean[b] = (float)mu;
            sd[b] = (float)sqrt(ss / (double)n);
        }
    }
    for (int b = 0; b < 3; b++)
        free(bands[b]);
    btf_image_free(&out);
    return rc;
}

/* Every number within the model file's limit for transfers (1e37,
 * docs/model-format.md): differences of knots and slopes stay finite. */
static int within_limits(const btf_marginal *mg)
{
    const float lim = 1e37f;
    for (int b = 0; b < 3; b++) {
        if (!(fabsf(mg->synth_mean[b]) <= lim && mg->synth_sd[b] <= lim))
            return 0;
        for (int j = 0; j < BTF_MARGIN_KNOTS; j++)
            if (!(fabsf(mg->quantile[b][j]) <= lim))
                return 0;
    }
    for (int k = 0; k < 3; k++)
        if (!(mg->rgb_hi[k] <= lim))
            return 0;
    return 1;
}

btf_status btf__fit_marginals(const btf_image *img, btf_model *m, int subspace, btf_error *err)
{
    return btf__fit_marginals_lab(img, img, m, subspace, err);
}

btf_status btf__fit_marginals_lab(const btf_image *img, const btf_image *lab_img, btf_model *m,
                                  int subspace, btf_error *err)
{
    if (!img || !img->data || img->channels != 3 || img->width < 1 || img->height < 1)
        return btf__fail(err, BTF_E_ARG, "marginal transfer needs an RGB image");
    if (!m || subspace < 0 || subspace >= m->n_subspaces || !m->subspaces)
        return btf__fail(err, BTF_E_ARG, "marginal transfer: subspace %d (expected 0..%d)",
                         subspace, m ? m->n_subspaces - 1 : -1);
    btf_subspace_model *sm = &m->subspaces[subspace];
    btf_marginal mg = {0};
    size_t n = (size_t)img->width * img->height;
    for (int k = 0; k < 3; k++) {
        float lo = img->data[k], hi = img->data[k];
        for (size_t i = 0; i < n; i++) {
            float v = img->data[3 * i + k];
            if (!isfinite(v))
                return btf__fail(err, BTF_E_ARG, "image pixel %zu is not finite", i);
            lo = v < lo ? v : lo;
            hi = v > hi ? v : hi;
        }
        /* with a structure layer, colour matching clamps the image with its
         * albedo pattern (lab_img) to this box too: it spans both */
        for (size_t i = 0; lab_img != img && i < n; i++) {
            float v = lab_img->data[3 * i + k];
            if (!isfinite(v))
                return btf__fail(err, BTF_E_ARG, "image pixel %zu is not finite", i);
            lo = v < lo ? v : lo;
            hi = v > hi ? v : hi;
        }
        mg.rgb_lo[k] = lo > 0.0f ? lo : 0.0f; /* no negative radiance, whatever the input */
        mg.rgb_hi[k] = hi > mg.rgb_lo[k] ? hi : mg.rgb_lo[k];
    }
    double *bands[3] = {NULL, NULL, NULL};
    btf_status rc = BTF_OK;
    for (int b = 0; b < 3 && rc == BTF_OK; b++)
        if (!(bands[b] = btf__alloc(n, sizeof(double), err)))
            rc = BTF_E_NOMEM;
    if (rc == BTF_OK) {
        btf__decorrelate(img, sm->mean, sm->basis, bands);
        for (int b = 0; b < 3; b++)
            band_quantiles(bands[b], n, mg.quantile[b]);
        btf_error me = {0};
        rc = measure_synthesis(m, subspace, mg.synth_mean, mg.synth_sd, &me);
        if (rc == BTF_E_NUMERIC) {
            /* the model's synthesis overflows float (values near the float
             * limit): no transfer, so that synthesis refuses it as before
             * instead of clamping Inf away */
            for (int b = 0; b < 3; b++)
                free(bands[b]);
            sm->marginal.knots = 0;
            return BTF_OK;
        }
        if (rc)
            btf__fail(err, rc, "%s", me.msg);
    }
    for (int b = 0; b < 3; b++)
        free(bands[b]);
    if (rc)
        return rc;
    if (!within_limits(&mg)) {
        sm->marginal.knots = 0; /* values the file cannot hold safely: none */
        return BTF_OK;
    }
    /* the exemplar's Lab histogram, for colour matching (synth/colour_match.c) */
    if ((rc = btf__lab_quantiles(lab_img, btf__lab_scale(&mg), BTF_LAB_SAMPLE, mg.lab_quantile, err)))
        return rc;
    for (int c = 0; c < 3; c++) /* what the model file keeps (monotone: still nondecreasing) */
        for (int j = 0; j < BTF_MARGIN_KNOTS; j++)
            mg.lab_quantile[c][j] = btf__lab_decode(c, btf__lab_code(c, mg.lab_quantile[c][j]));
    mg.lab_knots = BTF_MARGIN_KNOTS;
    mg.knots = BTF_MARGIN_KNOTS;
    sm->marginal = mg;
    return BTF_OK;
}
