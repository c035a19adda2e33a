/*
 * analyse.c — the whole analysis of a BTF dataset into one model (paper
 * section II): stage 1 segments the (view, light) space into K subspace
 * images (src/segment.c); stage 2 recovers the range map by photometric
 * stereo on the view closest to the normal (src/photostereo.c) and keeps it
 * as a small tile; stage 3 models each subspace image with the multi-scale
 * colour CAR model (src/fit.c).
 */
#include "internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Area-averages the height map into a T x T tile: each tile texel is the
 * mean of the source pixels whose centres fall in its cell. */
static int range_tile(const btf_image *h, int t, btf_model *m, btf_error *err)
{
    m->range = btf_calloc((size_t)t * t, sizeof(float), err);
    double *acc = btf_calloc((size_t)t * t, sizeof(double), err);
    int *cnt = btf_calloc((size_t)t * t, sizeof(int), err);
    if (!m->range || !acc || !cnt) {
        free(acc);
        free(cnt);
        free(m->range);
        m->range = NULL;
        return BTF_E_NOMEM;
    }
    for (int y = 0; y < h->height; y++)
        for (int x = 0; x < h->width; x++) {
            int ty = (int)((long)y * t / h->height), tx = (int)((long)x * t / h->width);
            acc[(size_t)ty * t + tx] += h->data[(size_t)y * h->width + x];
            cnt[(size_t)ty * t + tx]++;
        }
    for (size_t i = 0; i < (size_t)t * t; i++)
        m->range[i] = cnt[i] ? (float)(acc[i] / cnt[i]) : 0.0f;
    m->range_width = m->range_height = t;
    m->range_texel = (float)h->width / (float)t;
    free(acc);
    free(cnt);
    return BTF_OK;
}

static int stage_range(const btf_dataset *ds, const btf_analyse_opts *o, btf_model *m,
                       btf_error *err)
{
    btf_ps_result ps;
    int rc = btf_photostereo_dataset(ds, NULL, &o->photostereo, &ps, err);
    if (rc)
        return rc;
    int side = ps.height.width < ps.height.height ? ps.height.width : ps.height.height;
    int t = o->range_size > 0 ? o->range_size : 64;
    if (t > side)
        t = side;
    rc = range_tile(&ps.height, t, m, err);
    btf_ps_result_free(&ps);
    return rc;
}

static int stage_fit(const btf_dataset *ds, const btf_segmentation *seg, const btf_analyse_opts *o,
                     btf_model *m, btf_error *err)
{
    m->subspaces = btf_calloc((size_t)seg->k, sizeof(btf_subspace_model), err);
    if (!m->subspaces)
        return BTF_E_NOMEM;
    m->n_subspaces = seg->k;
    for (int k = 0; k < seg->k; k++) {
        btf_image img;
        int rc = btf_dataset_read(ds, seg->rep_view[k], seg->rep_light[k], &img, err);
        if (rc)
            return rc;
        char what[64];
        snprintf(what, sizeof what, "subspace %d", k);
        btf_fit_opts fo = o->fit;
        fo.car.what = what;
        rc = btf_fit_subspace(&img, &fo, &m->subspaces[k], err);
        btf_image_free(&img);
        if (rc)
            return rc;
        m->subspaces[k].view = seg->rep_view[k];
        m->subspaces[k].light = seg->rep_light[k];
        if (o->progress)
            o->progress(o->progress_user, (double)(k + 1) / seg->k, "fitting CAR models");
    }
    return BTF_OK;
}

int btf_analyse(const btf_dataset *ds, const btf_analyse_opts *opts, btf_model *out,
                btf_error *err)
{
    btf_analyse_opts o = {0};
    if (opts)
        o = *opts;
    memset(out, 0, sizeof *out);
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    if (o.segment.features.progress == NULL) {
        o.segment.features.progress = o.progress;
        o.segment.features.progress_user = o.progress_user;
    }
    btf_segmentation seg;
    int rc = btf_segment(ds, &o.segment, &seg, err);
    if (rc)
        return rc;
    rc = btf_dirset_copy(&out->views, in->views, err);
    if (rc == 0)
        rc = btf_dirset_copy(&out->lights, in->lights, err);
    if (rc == 0) {
        size_t n = (size_t)in->n_views * in->n_lights;
        out->index = btf_alloc(n, 1, err);
        if (out->index)
            memcpy(out->index, seg.index, n);
        else
            rc = BTF_E_NOMEM;
    }
    if (rc == 0 && !o.no_range)
        rc = stage_range(ds, &o, out, err);
    if (rc == 0)
        rc = stage_fit(ds, &seg, &o, out, err);
    btf_segmentation_free(&seg);
    if (rc)
        btf_model_free(out);
    return rc;
}
