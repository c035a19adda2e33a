/*
 * colour_match.c — colour matching after synthesis (docs/synthesis.md,
 * "Colour matching"; issue 17, "keep the material's marginals"). The
 * marginal transfer (marginal.c) gives each decorrelated band the
 * exemplar's histogram, yet the fidelity bench measured the CIE Lab
 * histograms of small syntheses 1.5-19 times further from the exemplar's
 * than the exemplar's own quadrants are from each other: the chroma
 * channels, because paper section II.C synthesises the three bands as
 * independent fields where the material's chroma follows its lightness
 * (even exact per-channel RGB histogram matching left fabric at 6-19), and
 * the luminance, because a small image's histogram strays from the model's
 * with its realisation (its largest structures are few). A fixed map per
 * Lab channel, measured once on a large synthesis, brought the worst case
 * to 3; measuring the output's own quantiles brought every exemplar of the
 * bench below 0.9 (docs/fidelity.md). So this pass reads the whole image:
 *   1. its L*, a*, b* quantiles at the model's probabilities (colour_lab.c),
 *   2. per pixel: Lab, each channel through the piecewise-linear map from
 *      those quantiles onto the exemplar's (flat beyond the ends), back to
 *      linear RGB, clamped into the exemplar's RGB box (no negative light).
 * Rows in parallel; each pixel's result depends on the quantiles and the
 * pixel alone, so any thread count gives the same bytes.
 */
#include "btfcar.h"
#include "core/core.h"
#include "synth/synth.h"

#include <math.h>
#include <string.h>

#define ROWS_PER_JOB 16

typedef struct match_job {
    btf_image *img;
    const btf_marginal *mg;
    float scale;
    float src[3][BTF_MARGIN_KNOTS]; /* the image's own quantiles */
    double slope[3][BTF_MARGIN_KNOTS]; /* of the map from segment j to j + 1 */
} match_job;

/* The first knot of src (nondecreasing) not below v, or K when all are. */
static int first_not_below(const float *src, float v)
{
    int lo = 0, hi = BTF_MARGIN_KNOTS; /* the answer is in [lo, hi] */
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (src[mid] < v)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* The map of one channel: linear between (src[j], dst[j]), flat beyond the
 * ends. A value equal to a run of knots j0..j1 (a channel constant over
 * those probabilities: a constant or tiny image) maps to the target at the
 * run's middle probability, so that a constant image takes the exemplar's
 * median, not its minimum; monotone and finite either way. */
static float map_channel(const float *src, const float *dst, const double *slope, float v)
{
    if (!(v >= src[0]))
        return dst[0];
    if (v > src[BTF_MARGIN_KNOTS - 1])
        return dst[BTF_MARGIN_KNOTS - 1];
    int a = first_not_below(src, v);
    if (src[a] == v) { /* v on knots a..b */
        int b = a;
        while (b + 1 < BTF_MARGIN_KNOTS && src[b + 1] == v)
            b++;
        return (float)(0.5 * ((double)dst[(a + b) / 2] + dst[(a + b + 1) / 2]));
    }
    return (float)(dst[a - 1] + ((double)v - src[a - 1]) * slope[a - 1]);
}

static btf_status match_rows(void *user, int job, int worker, btf_error *err)
{
    (void)worker, (void)err;
    match_job *mj = user;
    const btf_marginal *mg = mj->mg;
    int y0 = job * ROWS_PER_JOB, y1 = y0 + ROWS_PER_JOB;
    y1 = y1 < mj->img->height ? y1 : mj->img->height;
    for (int y = y0; y < y1; y++) {
        float *p = mj->img->data + (size_t)y * mj->img->width * 3;
        for (int x = 0; x < mj->img->width; x++, p += 3) {
            float lab[3], rgb[3];
            btf_lab_from_rgb(p, mj->scale, lab);
            for (int c = 0; c < 3; c++)
                lab[c] = map_channel(mj->src[c], mg->lab_quantile[c], mj->slope[c], lab[c]);
            btf_rgb_from_lab(lab, mj->scale, rgb);
            for (int k = 0; k < 3; k++) /* the box also catches what float rounding left */
                p[k] = rgb[k] >= mg->rgb_lo[k] ? (rgb[k] <= mg->rgb_hi[k] ? rgb[k] : mg->rgb_hi[k])
                                               : mg->rgb_lo[k];
        }
    }
    return BTF_OK;
}

btf_status btf_colour_match_check(const btf_model *m, int subspace, btf_error *err)
{
    if (!m || !m->subspaces || subspace < 0 || subspace >= m->n_subspaces)
        return btf_fail(err, BTF_E_ARG, "colour matching: subspace %d (expected 0..%d)",
                        subspace, m ? m->n_subspaces - 1 : -1);
    const btf_marginal *mg = &m->subspaces[subspace].marginal;
    if (!mg->knots || !mg->lab_knots)
        return btf_fail(err, BTF_E_ARG,
                        "colour matching: subspace %d holds no Lab histogram (a model file of "
                        "format 1.2 or older: analyse the material again)", subspace);
    return BTF_OK;
}

btf_status btf_colour_match(const btf_model *m, int subspace, btf_image *img, btf_error *err)
{
    btf_status rc = btf_colour_match_check(m, subspace, err);
    if (rc)
        return rc;
    const btf_marginal *mg = &m->subspaces[subspace].marginal;
    if (!img || !img->data || img->channels != 3 || img->width < 1 || img->height < 1)
        return btf_fail(err, BTF_E_ARG, "colour matching needs an RGB image");
    size_t n = (size_t)img->width * img->height * 3;
    for (size_t i = 0; i < n; i++)
        if (!isfinite(img->data[i]))
            return btf_fail(err, BTF_E_ARG, "colour matching: pixel (%zu, %zu) is not finite",
                            i / 3 % (size_t)img->width, i / 3 / (size_t)img->width);
    match_job mj = {img, mg, btf_lab_scale(mg), {{0}}, {{0}}};
    int jobs = (img->height + ROWS_PER_JOB - 1) / ROWS_PER_JOB;
    rc = btf_lab_quantiles(img, mj.scale, mj.src, err);
    if (rc)
        return rc;
    for (int c = 0; c < 3; c++) /* a segment a value falls inside has src[j] < src[j + 1] */
        for (int j = 0; j + 1 < BTF_MARGIN_KNOTS; j++) {
            double run = (double)mj.src[c][j + 1] - mj.src[c][j];
            mj.slope[c][j] = run > 0.0 ? ((double)mg->lab_quantile[c][j + 1] -
                                          mg->lab_quantile[c][j]) / run : 0.0;
        }
    return btf_pool_run(jobs, 0, match_rows, &mj, NULL, err);
}
