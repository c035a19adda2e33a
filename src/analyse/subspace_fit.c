/*
 * subspace_fit.c — the model of one subspace image (paper section II.C):
 * spectral decorrelation into 3 bands (car/decorrelate.c), a
 * Gaussian-Laplacian pyramid per band (car/pyramid.c) and a CAR model per
 * sub-band (car/car_fit.c), the pyramid's depth measured where not given
 * (analyse/levels.c).
 */
#include <stdio.h>
#include "core/core.h"
#include "car/car.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

btf_fit_opts btf_fit_defaults(void)
{
    return (btf_fit_opts){.struct_size = sizeof(btf_fit_opts),
                          .levels = 0, .car = btf_car_fit_defaults()};
}

btf_status btf__fit_subspace(const btf_image *img, const btf_fit_opts *opts,
                             btf_subspace_model *out, btf_error *err)
{
    /* levels 0 is auto, decided below from the image; btf__car_fit resolves
     * the CAR options' own defaults. */
    memset(out, 0, sizeof *out);
    btf_fit_opts d = btf_fit_defaults(), o;
    if (btf__opts_take(&o, sizeof o, opts, &d, "btf_fit_subspace", err))
        return BTF_E_ARG;
    if (o.levels < 0 || o.levels > BTF_MAX_LEVELS)
        return btf__fail(err, BTF_E_ARG, "levels %d: expected 1..%d or auto", o.levels, BTF_MAX_LEVELS);
    if (o.max_auto_levels < 0 || o.max_auto_levels > BTF_MAX_LEVELS)
        return btf__fail(err, BTF_E_ARG, "auto levels cap %d: expected 1..%d or 0 (the default)",
                         o.max_auto_levels, BTF_MAX_LEVELS);
    size_t n = (size_t)img->width * img->height;
    for (size_t i = 0; i < n * 3 && img->channels == 3; i++)
        if (!isfinite(img->data[i]))
            return btf__fail(err, BTF_E_ARG, "image pixel %zu is not finite", i / 3);
    out->view = out->light = -1;
    out->width = img->width;
    out->height = img->height;
    btf_status rc = btf__pca3(img, out->mean, out->basis, NULL, err);
    if (rc)
        return rc;
    double *bands[3] = {NULL, NULL, NULL};
    for (int b = 0; b < 3; b++)
        if (!(bands[b] = btf__alloc(n, sizeof(double), err))) {
            for (int k = 0; k < b; k++)
                free(bands[k]);
            return BTF_E_NOMEM;
        }
    btf__decorrelate(img, out->mean, out->basis, bands);
    int levels = o.levels;
    /* band 0's image level: the mean colour along its basis vector */
    btf_levels_mask mask = {o.masking, fabs((double)out->basis[0] * out->mean[0] +
                                            (double)out->basis[1] * out->mean[1] +
                                            (double)out->basis[2] * out->mean[2])};
    if (!levels && (rc = btf__choose_levels(bands[0], img->width, img->height, &o.car,
                                            o.max_auto_levels, o.masking ? &mask : NULL,
                                            &levels, NULL, err))) {
        for (int b = 0; b < 3; b++)
            free(bands[b]);
        return rc;
    }
    /* A level must keep at least one pixel per side. */
    while (levels > 1 && ((img->width >> (levels - 1)) < 1 || (img->height >> (levels - 1)) < 1))
        levels--;
    out->levels = levels;
    const char *base = o.car.what ? o.car.what : "subspace";
    if (o.levels && levels < o.levels && o.car.warn) {
        char msg[256];
        snprintf(msg, sizeof msg, "%s: %d pyramid levels asked for, %d used (the most a %dx%d "
                 "image allows: every level keeps at least one pixel per side)", base, o.levels,
                 levels, img->width, img->height);
        o.car.warn(o.car.warn_user, msg);
    }
    for (int b = 0; rc == 0 && b < 3; b++) {
        char what[128];
        snprintf(what, sizeof what, "%s band %d", base, b);
        rc = btf__fit_band_levels(bands[b], img->width, img->height, levels, &o.car, what,
                                  out->bands[b], err);
    }
    for (int b = 0; b < 3; b++)
        free(bands[b]);
    return rc;
}
