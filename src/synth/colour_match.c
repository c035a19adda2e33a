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
#include <stdlib.h>

#define ROWS_PER_JOB 16

/* Each channel's map is resampled on BTF_LAB_MAP_SEGS segments of equal
 * width from its first source knot to its last: a value's segment is then
 * a multiply and a floor, not a search among 32 knots (the search was half
 * the cost of the pass). Resampling cuts the corners of the map at its
 * knots by at most a segment's width (1/256 of the image's range); the
 * map stays monotone, and flat beyond the ends. */
typedef struct match_job {
    btf_image *img;
    const btf_marginal *mg;
    float scale;
    btf_lab_map map[3];
} match_job;

/* The map from the image's quantiles src (nondecreasing) onto the
 * exemplar's dst at v: linear between (src[j], dst[j]), flat beyond the
 * ends. A value equal to a run of knots j0..j1 (a channel constant over
 * those probabilities: a constant or tiny image) maps to the target at the
 * run's middle probability, so that a constant image takes the exemplar's
 * median, not its minimum; monotone and finite either way. */
static double exact_map(const float *src, const float *dst, double v)
{
    const int last = BTF_MARGIN_KNOTS - 1;
    if (!(v >= src[0]))
        return dst[0];
    if (v > src[last])
        return dst[last];
    int a = 0;
    while (src[a] < v) /* ends by src[last] >= v */
        a++;
    if (src[a] == v) { /* v on knots a..b */
        int b = a;
        while (b < last && src[b + 1] == v)
            b++;
        return 0.5 * ((double)dst[(a + b) / 2] + dst[(a + b + 1) / 2]);
    }
    return dst[a - 1] + (v - src[a - 1]) * ((double)dst[a] - dst[a - 1]) /
                            ((double)src[a] - src[a - 1]);
}

static void lab_map_make(const float *src, const float *dst, btf_lab_map *m)
{
    double lo = src[0], h = ((double)src[BTF_MARGIN_KNOTS - 1] - lo) / BTF_LAB_MAP_SEGS;
    double inv = h > 0.0 ? 1.0 / h : 0.0;
    m->origin = (float)lo;
    m->inv_h = (float)(inv < 1e30 ? inv : 1e30); /* finite: a tiny range is all but a step */
    for (int i = 0; i <= BTF_LAB_MAP_SEGS; i++) {
        float q = (float)exact_map(src, dst, lo + i * h);
        m->q[i] = i > 0 && q < m->q[i - 1] ? m->q[i - 1] : q; /* monotone after rounding */
    }
    for (int i = 0; i < BTF_LAB_MAP_SEGS; i++)
        m->dq[i] = m->q[i + 1] - m->q[i];
}

static btf_status match_rows(void *user, int job, int worker, btf_error *err)
{
    (void)worker, (void)err;
    match_job *mj = user;
    const btf_marginal *mg = mj->mg;
    int w = mj->img->width, y0 = job * ROWS_PER_JOB, y1 = y0 + ROWS_PER_JOB;
    y1 = y1 < mj->img->height ? y1 : mj->img->height;
    for (int y = y0; y < y1; y++)
        btf_lab_match_row(mj->map, mj->scale, mg->rgb_lo, mg->rgb_hi,
                          mj->img->data + (size_t)y * w * 3, w);
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

btf_status btf_colour_match_wanted(const btf_model *m, int subspace, int opt, int *on,
                                  btf_error *err)
{
    *on = 0;
    if (opt < 0)
        return BTF_OK;
    btf_error quiet; /* the default: a subspace that cannot be matched is not, no error */
    btf_status rc = btf_colour_match_check(m, subspace, opt > 0 ? err : &quiet);
    *on = rc == BTF_OK;
    return opt > 0 ? rc : BTF_OK;
}

void btf_colour_match_maps(const btf_model *m, int subspace, const float src[3][BTF_MARGIN_KNOTS],
                           btf_lab_map map[3])
{
    for (int c = 0; c < 3; c++)
        lab_map_make(src[c], m->subspaces[subspace].marginal.lab_quantile[c], &map[c]);
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
    int bad = btf_any_nonfinite(img->data, n); /* then the first such pixel, for the message */
    for (size_t i = 0; bad && i < n; i++)
        if (!isfinite(img->data[i]))
            return btf_fail(err, BTF_E_ARG, "colour matching: pixel (%zu, %zu) is not finite",
                            i / 3 % (size_t)img->width, i / 3 / (size_t)img->width);
    match_job *mj = btf_alloc(1, sizeof *mj, err); /* 6 KB of maps: not on the stack */
    if (!mj)
        return BTF_E_NOMEM;
    mj->img = img, mj->mg = mg, mj->scale = btf_lab_scale(mg);
    float src[3][BTF_MARGIN_KNOTS]; /* the image's own quantiles */
    rc = btf_lab_quantiles(img, mj->scale, BTF_LAB_MATCH_SAMPLE, src, err);
    if (rc == BTF_OK)
        btf_colour_match_maps(m, subspace, src, mj->map);
    int jobs = (img->height + ROWS_PER_JOB - 1) / ROWS_PER_JOB;
    if (rc == BTF_OK)
        rc = btf_pool_run(jobs, 0, match_rows, mj, NULL, err);
    free(mj);
    return rc;
}
