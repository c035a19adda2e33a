/*
 * model_margins.c — the synthesis margins of a model's bands, kept with the
 * model (Haindl & Filip 2007, section II.C: each sub-band's CAR field is
 * started far enough outside its window that the window is stationary).
 * car/margin.c computes a band's margin; this file keeps one per
 * (subspace, band, level) in the model's private part, so that synthesis
 * need not compute them at every call, and answers for a band whose
 * coefficients changed since by computing its margin afresh.
 */
#include "model/model.h"
#include "car/car.h"
#include "core/core.h"

#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

/* A kept margin and what it was computed from. */
typedef struct kept_margin {
    int n;
    btf_offset offsets[BTF_CAR_MAX_NEIGHBOURS];
    float gamma[BTF_CAR_MAX_NEIGHBOURS];
    int margin;
} kept_margin;

struct btf_model_internal {
    int n_subspaces;
    kept_margin *margins; /* [(k * 3 + band) * BTF_MAX_LEVELS + level]; NULL: none kept */
    /* the remainders' periodic cells (model/structure_cells.c): model data
     * kept here, not in btf_model, whose layout the library's ABI fixes */
    btf_cells *cells;
};

static size_t kept_index(int k, int b, int l)
{
    return ((size_t)k * 3 + (size_t)b) * BTF_MAX_LEVELS + (size_t)l;
}

void btf__model_internal_free(struct btf_model_internal *in)
{
    if (!in)
        return;
    btf__cells_free(in->cells);
    free(in->margins);
    free(in);
}

const btf_cells *btf__model_cells(const btf_model *m)
{
    return m && m->internal ? m->internal->cells : NULL;
}

btf_status btf__model_set_cells(btf_model *m, btf_cells *cells, btf_error *err)
{
    if (!m->internal && !(m->internal = btf__calloc(1, sizeof *m->internal, err))) {
        btf__cells_free(cells);
        return BTF_E_NOMEM;
    }
    btf__cells_free(m->internal->cells);
    m->internal->cells = cells;
    return BTF_OK;
}

/* The bands in the order the budget is spent: subspace, band, level. */
typedef struct margin_jobs {
    const btf_model *m;
    kept_margin *kept;
    int *band;      /* job -> kept index */
    double *work;   /* job -> the work its margin took; -1: not computed */
    double budget;  /* < 0: none */
    _Atomic long long spent; /* work of the jobs done: past the budget, no more */
} margin_jobs;

/* Work units a band may take at most, by far (the largest margin test of
 * car/margin.c is about 1e7): counting from here stays exact in double. */
#define UNLIMITED 1e15

static btf_status margin_job(void *user, int j, int worker, btf_error *err)
{
    (void)worker, (void)err;
    margin_jobs *mj = user;
    int i = mj->band[j], l = i % BTF_MAX_LEVELS, b = i / BTF_MAX_LEVELS % 3;
    int k = i / BTF_MAX_LEVELS / 3;
    mj->work[j] = -1.0;
    if (mj->budget >= 0 && (double)atomic_load(&mj->spent) > mj->budget)
        return BTF_OK; /* the walk in turn takes it from here */
    double left = UNLIMITED;
    kept_margin *e = &mj->kept[i];
    e->margin = btf__car_margin_within(&mj->m->subspaces[k].bands[b][l], &left);
    mj->work[j] = UNLIMITED - left;
    atomic_fetch_add(&mj->spent, (long long)mj->work[j]);
    return e->margin < 0 ? BTF_E_NOMEM : BTF_OK;
}

/* The bands' margins on every CPU, each as if alone (and none started once
 * the work done passes the budget); then the budget spent in order, as one
 * thread computing them in turn would: while it lasts for a band, that
 * band's margin is the one computed; from the first band it does not cover
 * (or that was not computed), the rest are computed in turn with what is
 * left. So the margins are those of the single-threaded walk, bit for bit,
 * and the work at most the budget plus one band per CPU. */
btf_status btf__model_keep_margins(btf_model *m, double budget)
{
    /* the model's own data (its cells) moves to the new internal part only
     * when that is whole: on failure the old one stays as it was (its
     * margins are checked against the bands before use) */
    if (m->n_subspaces <= 0) {
        btf__model_internal_free(m->internal);
        m->internal = NULL;
        return BTF_OK;
    }
    struct btf_model_internal *in = calloc(1, sizeof *in);
    size_t nkept = (size_t)m->n_subspaces * 3 * BTF_MAX_LEVELS;
    kept_margin *kept = calloc(nkept, sizeof *kept);
    margin_jobs mj = {m, kept, calloc(nkept, sizeof(int)), calloc(nkept, sizeof(double)), budget,
                      0};
    if (!in || !kept || !mj.band || !mj.work) {
        BTF_FREE_ALL(in, kept, mj.band, mj.work);
        return BTF_E_NOMEM;
    }
    in->n_subspaces = m->n_subspaces;
    in->margins = kept;
    int jobs = 0;
    for (int k = 0; k < m->n_subspaces; k++)
        for (int b = 0; b < 3; b++)
            for (int l = 0; l < m->subspaces[k].levels && l < BTF_MAX_LEVELS; l++) {
                const btf_car_band *cb = &m->subspaces[k].bands[b][l];
                kept_margin *e = &kept[kept_index(k, b, l)];
                e->n = cb->n;
                memcpy(e->offsets, cb->offsets, sizeof e->offsets);
                memcpy(e->gamma, cb->gamma, sizeof e->gamma);
                mj.band[jobs++] = (int)kept_index(k, b, l);
            }
    btf_error perr = {0};
    btf_status rc = btf__pool_run(jobs, 0, margin_job, &mj, NULL, &perr);
    for (int j = 0; rc == BTF_OK && budget >= 0 && j < jobs; j++) {
        if (mj.work[j] >= 0 && budget >= mj.work[j]) {
            budget -= mj.work[j];
            continue;
        }
        for (; j < jobs; j++) { /* the budget runs out in band j: in turn from here */
            int i = mj.band[j], l = i % BTF_MAX_LEVELS, b = i / BTF_MAX_LEVELS % 3;
            int k = i / BTF_MAX_LEVELS / 3;
            if ((kept[i].margin = btf__car_margin_within(&m->subspaces[k].bands[b][l],
                                                         &budget)) < 0)
                rc = BTF_E_NOMEM;
        }
    }
    free(mj.band);
    free(mj.work);
    if (rc != BTF_OK) {
        btf__model_internal_free(in);
        return BTF_E_NOMEM;
    }
    if (m->internal) { /* the cells go on; the old margins are replaced */
        in->cells = m->internal->cells;
        m->internal->cells = NULL;
    }
    btf__model_internal_free(m->internal);
    m->internal = in;
    return BTF_OK;
}

/* Whether a kept margin was computed for this band: the same neighbours
 * and the same coefficient bits (the margin depends on nothing else). */
static int kept_for(const kept_margin *e, const btf_car_band *b)
{
    return e->n == b->n && b->n >= 0 && b->n <= BTF_CAR_MAX_NEIGHBOURS &&
           !memcmp(e->offsets, b->offsets, (size_t)b->n * sizeof b->offsets[0]) &&
           !memcmp(e->gamma, b->gamma, (size_t)b->n * sizeof b->gamma[0]);
}

int btf__model_margin(const btf_model *m, int k, int b, int l)
{
    const btf_car_band *cb = &m->subspaces[k].bands[b][l];
    const struct btf_model_internal *in = m->internal;
    if (in && in->margins && k < in->n_subspaces && l < BTF_MAX_LEVELS) {
        const kept_margin *e = &in->margins[kept_index(k, b, l)];
        if (kept_for(e, cb))
            return e->margin;
    }
    return btf__car_margin(cb);
}
