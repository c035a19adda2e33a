/*
 * colour_match.c — colour matching after synthesis (docs/synthesis.md,
 * "Colour matching": keep the material's marginals). The
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

/* A job's pixels: about this many per job, so that a job of the relay's
 * background (core/pool.c) takes some 20 microseconds and a batch of the
 * pipeline posted meanwhile hardly waits. */
#define PIXELS_PER_JOB 2048

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

btf_status btf__colour_match_check(const btf_model *m, int subspace, btf_error *err)
{
    if (!m || !m->subspaces || subspace < 0 || subspace >= m->n_subspaces)
        return btf__fail(err, BTF_E_ARG, "colour matching: subspace %d (expected 0..%d)",
                         subspace, m ? m->n_subspaces - 1 : -1);
    const btf_marginal *mg = &m->subspaces[subspace].marginal;
    if (!mg->knots || !mg->lab_knots)
        return btf__fail(err, BTF_E_ARG,
                         "colour matching: subspace %d holds no Lab histogram (a model file of "
                         "format 1.2 or older: analyse the material again)", subspace);
    return BTF_OK;
}

btf_status btf__colour_match_wanted(const btf_model *m, int subspace, int opt, int *on,
                                  btf_error *err)
{
    *on = 0;
    if (opt < 0)
        return BTF_OK;
    btf_error quiet; /* the default: a subspace that cannot be matched is not, no error */
    btf_status rc = btf__colour_match_check(m, subspace, opt > 0 ? err : &quiet);
    *on = rc == BTF_OK;
    return opt > 0 ? rc : BTF_OK;
}

void btf__colour_match_maps(const btf_marginal *mg, const float src[3][BTF_MARGIN_KNOTS],
                            btf_lab_map map[3])
{
    for (int c = 0; c < 3; c++)
        lab_map_make(src[c], mg->lab_quantile[c], &map[c]);
}

/* The pass as jobs run in order (btf_match_task in synth.h): the sample's
 * rows, the quantiles and maps, then the image's rows. Each job's output
 * depends on its index alone, whoever runs it. */
static int sample_jobs(const btf_match_task *t)
{
    return (t->sample.rows + t->sample_rows_per_job - 1) / t->sample_rows_per_job;
}

static btf_status task_job(void *user, int j, int worker, btf_error *err)
{
    btf_match_task *t = user;
    const btf_marginal *mg = t->mg;
    int w = t->img->width, s = sample_jobs(t);
    if (j < s) { /* sample rows r0 .. r1 - 1 */
        int r0 = j * t->sample_rows_per_job, r1 = r0 + t->sample_rows_per_job;
        r1 = r1 < t->sample.rows ? r1 : t->sample.rows;
        for (int r = r0; r < r1; r++) {
            int y = r * t->sample.sy;
            btf__lab_sample_row(&t->sample, y, t->img->data + (size_t)y * w * 3,
                                t->scratch + (size_t)worker * t->sample.cols * 3);
        }
        return BTF_OK;
    }
    if (j == s) { /* the image's own quantiles, the maps onto the exemplar's */
        float src[3][BTF_MARGIN_KNOTS];
        btf_status rc = btf__lab_sample_quantiles(&t->sample, src, err);
        if (rc == BTF_OK)
            btf__colour_match_maps(mg, src, t->map);
        return rc;
    }
    int y0 = (j - s - 1) * t->rows_per_job, y1 = y0 + t->rows_per_job;
    y1 = y1 < t->img->height ? y1 : t->img->height;
    for (int y = y0; y < y1; y++)
        btf__lab_match_row(t->map, t->scale, mg->rgb_lo, mg->rgb_hi,
                           t->img->data + (size_t)y * w * 3, w);
    return BTF_OK;
}

btf_status btf__match_task_begin(btf_match_task **out, const btf_model *m, int subspace,
                                 btf_image *img, btf_error *err)
{
    *out = NULL;
    btf_status rc = btf__colour_match_check(m, subspace, err);
    if (rc)
        return rc;
    btf_match_task *t = btf__calloc(1, sizeof *t, err); /* 6 KB of maps: not on the stack */
    if (!t)
        return BTF_E_NOMEM;
    t->img = img, t->mg = &m->subspaces[subspace].marginal, t->scale = btf__lab_scale(t->mg);
    rc = btf__lab_sample_begin(&t->sample, img->width, img->height, BTF_LAB_MATCH_SAMPLE,
                               t->scale, err);
    t->scratch = rc ? NULL : btf__alloc((size_t)t->sample.cols * 3 * 2, sizeof(float), err);
    if (!t->scratch) {
        btf__match_task_free(t);
        return rc ? rc : BTF_E_NOMEM;
    }
    t->sample_rows_per_job = PIXELS_PER_JOB / t->sample.cols;
    t->sample_rows_per_job += t->sample_rows_per_job < 1;
    t->rows_per_job = PIXELS_PER_JOB / img->width;
    t->rows_per_job += t->rows_per_job < 1;
    int s = sample_jobs(t), rows = (img->height + t->rows_per_job - 1) / t->rows_per_job;
    t->bg = (btf_background){.fn = task_job, .user = t, .count = s + 1 + rows};
    *out = t;
    return BTF_OK;
}

typedef struct task_rest {
    btf_match_task *t;
    int first;
} task_rest;

static btf_status rest_job(void *user, int j, int worker, btf_error *err)
{
    task_rest *r = user;
    return task_job(r->t, r->first + j, worker, err);
}

btf_status btf__match_task_finish(btf_match_task *t, btf_error *err)
{
    btf_background *bg = &t->bg;
    if (bg->status) {
        if (err)
            *err = bg->error;
        return bg->status;
    }
    int s = sample_jobs(t);
    btf_status rc = BTF_OK;
    for (; rc == BTF_OK && bg->done <= s; bg->done++) /* in order: the maps need the sample */
        rc = task_job(t, bg->done, 0, err);
    task_rest rest = {t, bg->done};
    if (rc == BTF_OK)
        rc = btf__pool_run(bg->count - bg->done, 0, rest_job, &rest, NULL, err);
    if (rc == BTF_OK)
        bg->done = bg->count;
    return rc;
}

void btf__match_task_free(btf_match_task *t)
{
    if (!t)
        return;
    btf__lab_sample_free(&t->sample);
    free(t->scratch);
    free(t);
}

btf_status btf__colour_match(const btf_model *m, int subspace, btf_image *img, btf_error *err)
{
    btf_status rc = btf__colour_match_check(m, subspace, err);
    if (rc)
        return rc;
    if (!img || !img->data || img->channels != 3 || img->width < 1 || img->height < 1)
        return btf__fail(err, BTF_E_ARG, "colour matching needs an RGB image");
    size_t n = (size_t)img->width * img->height * 3;
    int bad = btf__any_nonfinite(img->data, n); /* then the first such pixel, for the message */
    for (size_t i = 0; bad && i < n; i++)
        if (!isfinite(img->data[i]))
            return btf__fail(err, BTF_E_ARG, "colour matching: pixel (%zu, %zu) is not finite",
                             i / 3 % (size_t)img->width, i / 3 / (size_t)img->width);
    return btf__match_synthesised(m, subspace, img, err);
}

btf_status btf__match_synthesised(const btf_model *m, int subspace, btf_image *img,
                                  btf_error *err)
{
    btf_match_task *t;
    btf_status rc = btf__match_task_begin(&t, m, subspace, img, err);
    if (rc == BTF_OK)
        rc = btf__match_task_finish(t, err);
    btf__match_task_free(t);
    return rc;
}
