/*
 * rf_sampled.c — btf_rf_fit_sampled, the memory reduction of Meseth,
 * Müller & Klein 2003, section 6 ("Due to the frequent use of 3D texture
 * maps [...] our rendering method turns out to be rather memory
 * consuming"; "The solution for both problems are texture synthesis
 * algorithms"): the reflectance fields are fitted on a small sample of the
 * material only, and the surface is a map of texture coordinates into the
 * sample from a synthesis of it, so that the model's size is the sample's
 * coefficients plus the map, whatever the surface's size.
 *
 * Stages: the representative image (rf_feature.c), the sample's window
 * (rf_sample.c, or the caller's), the fit of that window (btf_rf_fit with
 * a crop), the coordinate map (rf_quilt.c), and the pixel-wise error over
 * the whole dataset through the map (btf__rf_error, one more pass), which
 * shows what the reduction costs: outside the sample's own place no texel
 * of the surface corresponds to the data's.
 */
#include "rf/rf.h"
#include "rf/rf_sample.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The sample's options resolved against the dataset; BTF_E_ARG naming the
 * value when one is out of range. */
static btf_status resolve(const btf_rf_sample_opts *so, const btf_dataset_info *in,
                          btf_rf_sample_opts *r, btf_error *err)
{
    btf_rf_sample_opts d = btf_rf_sample_defaults();
    if (btf__opts_take(r, sizeof *r, so, &d, "btf_rf_fit_sampled", err))
        return BTF_E_ARG;
    if (so->width < 1 || so->height < 1 || so->width > in->width || so->height > in->height)
        return btf__fail(err, BTF_E_ARG, "sample of %dx%d texels (expected 1x1 up to the "
                         "dataset's %dx%d)", so->width, so->height, in->width, in->height);
    if (so->placed && (so->x < 0 || so->y < 0 || so->x > in->width - so->width ||
                       so->y > in->height - so->height))
        return btf__fail(err, BTF_E_ARG, "sample of %dx%d at (%d, %d) (expected a window inside "
                         "the %dx%d images)", so->width, so->height, so->x, so->y, in->width,
                         in->height);
    r->surface_width = so->surface_width ? so->surface_width : in->width;
    r->surface_height = so->surface_height ? so->surface_height : in->height;
    if (r->surface_width < 1 || r->surface_height < 1 ||
        r->surface_width > BTF_RF_MAX_SURFACE_SIDE || r->surface_height > BTF_RF_MAX_SURFACE_SIDE)
        return btf__fail(err, BTF_E_ARG, "surface of %dx%d texels (expected sides 1..%d)",
                         r->surface_width, r->surface_height, BTF_RF_MAX_SURFACE_SIDE);
    int side = so->width < so->height ? so->width : so->height;
    int half = side / 2 < 32 ? side / 2 : 32;
    r->block = so->block ? so->block : half > 1 ? half : 1;
    if (r->block < 1 || r->block > side)
        return btf__fail(err, BTF_E_ARG, "quilting block of %d texels (expected 1..%d, the "
                         "sample's shorter side)", so->block, side);
    r->overlap = so->overlap ? so->overlap : r->block / 4;
    if (r->overlap < 0 || 2 * r->overlap > r->block)
        return btf__fail(err, BTF_E_ARG, "quilting overlap of %d texels (expected 0..%d, half "
                         "the block)", so->overlap, r->block / 2);
    r->tolerance = so->tolerance != 0.0 ? so->tolerance : 0.1;
    if (!(r->tolerance >= 0.0 && r->tolerance <= 1e6))
        return btf__fail(err, BTF_E_ARG, "quilting tolerance %g (expected 0..1e6)",
                         so->tolerance);
    return BTF_OK;
}

/* The representative image, the window and the map; *map malloc'd. */
static btf_status synthesise(const btf_dataset *ds, const btf_rf_sample_opts *r, int threads,
                             int *sx, int *sy, uint16_t **map, btf_rf_fit_info *info,
                             btf_error *err)
{
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    double t0 = btf__now();
    float *feat = NULL;
    int view;
    btf_status rc = rf_feature_image(ds, threads, &feat, &view, err);
    *sx = r->x, *sy = r->y;
    if (rc == BTF_OK && !r->placed)
        rc = rf_sample_choose(feat, in->width, in->height, r->width, r->height, sx, sy, err);
    double t1 = btf__now();
    *map = NULL;
    if (rc == BTF_OK) {
        *map = btf__alloc((size_t)r->surface_width * r->surface_height, 2 * sizeof(uint16_t),
                          err);
        rc = *map ? BTF_OK : BTF_E_NOMEM;
    }
    if (rc == BTF_OK) {
        rf_quilt_args q = {feat, in->width, *sx, *sy, r->width, r->height, r->surface_width,
                           r->surface_height, r->block, r->overlap, r->tolerance, r->seed,
                           threads, 0, {0, 0, 0, 0}};
        rc = rf_quilt(&q, *map, err);
    }
    free(feat);
    if (rc) {
        free(*map);
        *map = NULL;
    }
    info->sample_s = t1 - t0;
    info->quilt_s = btf__now() - t1;
    return rc;
}

btf_status btf_rf_fit_sampled(const btf_dataset *ds, const btf_rf_opts *opts,
                              const btf_rf_sample_opts *so, btf_rf_model *out,
                              btf_error *err)
{
    if (!out)
        return btf__fail(err, BTF_E_ARG, "btf_rf_fit_sampled: no output model");
    memset(out, 0, sizeof *out);
    if (!ds || !so)
        return btf__fail(err, BTF_E_ARG, "btf_rf_fit_sampled: no dataset or no sample options");
    if (btf__rf_refuse_sparse(ds, err))
        return BTF_E_DATA;
    double t0 = btf__now();
    btf_rf_opts d = btf_rf_defaults(), o;
    if (btf__opts_take(&o, sizeof o, opts, &d, "btf_rf_fit_sampled", err))
        return BTF_E_ARG;
    if (o.threads < 0)
        return btf__fail(err, BTF_E_ARG, "threads %d (expected >= 0)", o.threads);
    btf_rf_sample_opts r;
    btf_status rc = resolve(so, btf_dataset_get_info(ds), &r, err);
    if (rc)
        return rc;
    btf_rf_fit_info fi, si;
    memset(&si, 0, sizeof si);
    uint16_t *map = NULL;
    int sx, sy;
    rc = synthesise(ds, &r, o.threads, &sx, &sy, &map, &si, err);
    if (rc)
        return rc;
    btf_rf_fit_info *user = o.info;
    o.info = &fi;
    o.crop_x = sx, o.crop_y = sy, o.crop_width = r.width, o.crop_height = r.height;
    rc = btf_rf_fit(ds, &o, out, err);
    if (rc) {
        free(map);
        return rc;
    }
    out->map = map;
    out->surface_width = r.surface_width, out->surface_height = r.surface_height;
    out->sample_x = sx, out->sample_y = sy;
    double t1 = btf__now(), e = 0.0, s = 0.0;
    rc = btf__rf_error(ds, out, o.threads, &e, &s, err);
    if (rc) {
        btf_rf_model_free(out);
        return rc;
    }
    if (user) {
        *user = fi;
        user->sample_mean_abs_error = out->fit == BTF_RF_LAFORTUNE ? 0.0 : fi.mean_abs_error;
        user->mean_abs_error = e, user->mean_luminance = s;
        user->sample_s = si.sample_s, user->quilt_s = si.quilt_s;
        user->error_s = btf__now() - t1;
        user->quilt_block = r.block, user->quilt_overlap = r.overlap;
        user->seconds = btf__now() - t0;
    }
    return BTF_OK;
}
