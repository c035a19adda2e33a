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
    kept_margin *margins; /* [(k * 3 + band) * BTF_MAX_LEVELS + level] */
};

static size_t kept_index(int k, int b, int l)
{
    return ((size_t)k * 3 + (size_t)b) * BTF_MAX_LEVELS + (size_t)l;
}

void btf_model_internal_free(struct btf_model_internal *in)
{
    if (!in)
        return;
    free(in->margins);
    free(in);
}

btf_status btf_model_keep_margins(btf_model *m, double budget)
{
    btf_model_internal_free(m->internal);
    m->internal = NULL;
    if (m->n_subspaces <= 0)
        return BTF_OK;
    struct btf_model_internal *in = calloc(1, sizeof *in);
    kept_margin *kept = calloc((size_t)m->n_subspaces * 3 * BTF_MAX_LEVELS, sizeof *kept);
    if (!in || !kept) {
        free(in);
        free(kept);
        return BTF_E_NOMEM;
    }
    in->n_subspaces = m->n_subspaces;
    in->margins = kept;
    for (int k = 0; k < m->n_subspaces; k++)
        for (int b = 0; b < 3; b++)
            for (int l = 0; l < m->subspaces[k].levels && l < BTF_MAX_LEVELS; l++) {
                const btf_car_band *cb = &m->subspaces[k].bands[b][l];
                kept_margin *e = &kept[kept_index(k, b, l)];
                e->n = cb->n;
                memcpy(e->offsets, cb->offsets, sizeof e->offsets);
                memcpy(e->gamma, cb->gamma, sizeof e->gamma);
                if ((e->margin = btf_car_margin_within(cb, budget < 0 ? NULL : &budget)) < 0) {
                    btf_model_internal_free(in);
                    return BTF_E_NOMEM;
                }
            }
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

int btf_model_margin(const btf_model *m, int k, int b, int l)
{
    const btf_car_band *cb = &m->subspaces[k].bands[b][l];
    const struct btf_model_internal *in = m->internal;
    if (in && k < in->n_subspaces && l < BTF_MAX_LEVELS) {
        const kept_margin *e = &in->margins[kept_index(k, b, l)];
        if (kept_for(e, cb))
            return e->margin;
    }
    return btf_car_margin(cb);
}
