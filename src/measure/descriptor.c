/*
 * descriptor.c — everything one view contributes to the three distance
 * components (docs/measure.md): its log spectrum, its sorted Lab values and
 * its band statistics, computed once per view and compared pairwise by
 * texture_distance.c.
 */
#include "core/core.h"
#include "measure/measure.h"

#include <stdlib.h>
#include <string.h>

void ms_desc_free(ms_desc *d)
{
    if (!d)
        return;
    free(d->spectrum);
    free(d->sorted[0]); /* one block for the three channels */
    memset(d, 0, sizeof *d);
}

btf_status ms_describe(const ms_view *v, int s, int levels, ms_desc *d, btf_error *err)
{
    int nbins = s / 2;
    memset(d, 0, sizeof *d);
    d->n = (size_t)v->w * v->h;
    d->nbins = nbins;
    d->levels = levels;
    d->spectrum = btf__alloc((size_t)nbins, sizeof(double), err);
    d->sorted[0] = d->spectrum ? btf__alloc(3 * d->n, sizeof(float), err) : NULL;
    if (!d->sorted[0]) {
        ms_desc_free(d);
        return BTF_E_NOMEM;
    }
    d->sorted[1] = d->sorted[0] + d->n;
    d->sorted[2] = d->sorted[1] + d->n;
    btf_status rc = ms_spectrum(v, s, d->spectrum, err);
    if (rc == BTF_OK)
        rc = ms_band_stats(v, levels, d->bands, err);
    if (rc != BTF_OK) {
        ms_desc_free(d);
        return rc;
    }
    ms_sort_channels(v, d->sorted);
    return BTF_OK;
}
