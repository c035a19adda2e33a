/*
 * subspace_fit.c — the model of one subspace image (paper section II.C):
 * spectral decorrelation into 3 bands (car/decorrelate.c), a
 * Gaussian-Laplacian pyramid per band (car/pyramid.c) and a CAR model per
 * sub-band (car/car_fit.c), the pyramid's depth measured where not given
 * (car/levels.c).
 */
#include <stdio.h>
#include "core/core.h"
#include "car/car.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The CAR models of one band's pyramid, coarsest first: the low-pass
 * G_{L-1} as it is, and every finer level l as the complement of the
 * up-sampled G_{l+1} in G_l (btf_car_fit_complement). Synthesis adds the
 * levels as independent fields, G_l = mean_l + Y_l + up(G_{l+1}); fitting
 * Y_l to the Laplacian L_l = G_l - up(G_{l+1}) alone would drop the
 * cross-covariance of L_l and up(G_{l+1}) (positive where the up-sampling
 * filter's response is between 0 and 1: the octave between two levels), and
 * the synthesis would lose that share of the variance — half of it at mid
 * frequencies on the leather material with 3 levels. */
btf_status btf_fit_band_levels(const double *band, int w, int h, int levels,
                               const btf_car_fit_opts *car, const char *what, btf_car_band *out,
                               btf_error *err)
{
    btf_pyramid p;
    btf_status rc = btf_pyramid_build(band, w, h, levels, &p, err);
    if (rc)
        return rc;
    int l = levels - 1;
    double *g = btf_alloc((size_t)p.width[l] * p.height[l], sizeof(double), err);
    if (!g) {
        btf_pyramid_free(&p);
        return BTF_E_NOMEM;
    }
    memcpy(g, p.level[l], (size_t)p.width[l] * p.height[l] * sizeof(double));
    for (; rc == 0 && l >= 0; l--) {
        char name[160];
        snprintf(name, sizeof name, "%s level %d", what, l);
        btf_car_fit_opts o = *car;
        o.what = name;
        if (l == levels - 1) {
            rc = btf_car_fit(g, p.width[l], p.height[l], &o, &out[l], NULL, err);
            continue;
        }
        double *up;
        size_t n = (size_t)p.width[l] * p.height[l];
        rc = btf_pyr_up(g, p.width[l + 1], p.height[l + 1], p.width[l], p.height[l], &up, err);
        free(g);
        g = NULL;
        if (rc)
            break;
        /* G_l = L_l + up(G_{l+1}): into p.level[l], which is not needed again */
        for (size_t i = 0; i < n; i++)
            p.level[l][i] += up[i];
        rc = btf_car_fit_complement(p.level[l], up, p.width[l], p.height[l], &o, &out[l], NULL,
                                    err);
        free(up);
        if (rc == 0 && l > 0) {
            if (!(g = btf_alloc(n, sizeof(double), err)))
                rc = BTF_E_NOMEM;
            else
                memcpy(g, p.level[l], n * sizeof(double));
        }
    }
    free(g);
    btf_pyramid_free(&p);
    return rc;
}

btf_fit_opts btf_fit_defaults(void)
{
    return (btf_fit_opts){.levels = 0, .car = btf_car_fit_defaults()};
}

btf_status btf_fit_subspace(const btf_image *img, const btf_fit_opts *opts,
                            btf_subspace_model *out, btf_error *err)
{
    /* levels 0 is auto, decided below from the image; btf_car_fit resolves
     * the CAR options' own defaults. */
    btf_fit_opts o = opts ? *opts : btf_fit_defaults();
    memset(out, 0, sizeof *out);
    if (o.levels < 0 || o.levels > BTF_MAX_LEVELS)
        return btf_fail(err, BTF_E_ARG, "levels %d: expected 1..%d or auto", o.levels, BTF_MAX_LEVELS);
    size_t n = (size_t)img->width * img->height;
    for (size_t i = 0; i < n * 3 && img->channels == 3; i++)
        if (!isfinite(img->data[i]))
            return btf_fail(err, BTF_E_ARG, "image pixel %zu is not finite", i / 3);
    out->view = out->light = -1;
    out->width = img->width;
    out->height = img->height;
    btf_status rc = btf_pca3(img, out->mean, out->basis, NULL, err);
    if (rc)
        return rc;
    double *bands[3] = {NULL, NULL, NULL};
    for (int b = 0; b < 3; b++)
        if (!(bands[b] = btf_alloc(n, sizeof(double), err))) {
            for (int k = 0; k < b; k++)
                free(bands[k]);
            return BTF_E_NOMEM;
        }
    btf_decorrelate(img, out->mean, out->basis, bands);
    int levels = o.levels;
    if (!levels && (rc = btf_choose_levels(bands[0], img->width, img->height, &o.car, &levels,
                                           NULL, err))) {
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
        rc = btf_fit_band_levels(bands[b], img->width, img->height, levels, &o.car, what,
                                 out->bands[b], err);
    }
    for (int b = 0; b < 3; b++)
        free(bands[b]);
    return rc;
}
