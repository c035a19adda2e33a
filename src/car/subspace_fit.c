/*
 * subspace_fit.c — the model of one subspace image (paper section II.C):
 * spectral decorrelation into 3 bands (car/decorrelate.c), a
 * Gaussian-Laplacian pyramid per band (car/pyramid.c) and a CAR model per
 * sub-band (car/car_fit.c).
 *
 * Pyramid depth (--levels auto). The correlation length ell of the dominant
 * band is the smallest lag (1..64) at which its normalised autocorrelation,
 * averaged over the horizontal and vertical directions, falls below 1/e.
 * Each pyramid level halves distances, so a small neighbourhood at level l
 * reaches 2^l pixels: L = 1 + floor(log2(ell / 2)), at most 3 (the paper's
 * bound), and at most as many as keep the coarsest level 16 pixels wide.
 */
#include <stdio.h>
#include "core/core.h"
#include "car/car.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Normalised autocorrelation of a band at lag k (horizontal + vertical). */
static double autocorr(const double *z, int w, int h, int k, double var)
{
    double s = 0.0;
    long n = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x + k < w; x++, n++)
            s += z[(size_t)y * w + x] * z[(size_t)y * w + x + k];
    for (int y = 0; y + k < h; y++)
        for (int x = 0; x < w; x++, n++)
            s += z[(size_t)y * w + x] * z[(size_t)(y + k) * w + x];
    return n ? s / ((double)n * var) : 0.0;
}

int btf_auto_levels(const double *band, int w, int h)
{
    int side = w < h ? w : h, cap = 1;
    while (cap < 3 && (side >> cap) >= 16)
        cap++;
    if (cap == 1)
        return 1;
    size_t n = (size_t)w * h;
    double mean = 0.0, var = 0.0;
    for (size_t i = 0; i < n; i++)
        mean += band[i];
    mean /= (double)n;
    double *z = malloc(n * sizeof(double));
    if (!z)
        return 1;
    for (size_t i = 0; i < n; i++) {
        z[i] = band[i] - mean;
        var += z[i] * z[i];
    }
    var /= (double)n;
    int ell = 64;
    if (var > 0.0) {
        for (int k = 1; k <= 64 && k < side; k++)
            if (autocorr(z, w, h, k, var) < exp(-1.0)) {
                ell = k;
                break;
            }
    } else {
        ell = 1;
    }
    free(z);
    int levels = 1;
    while (levels < cap && (ell >> (levels + 1)) >= 1)
        levels++;
    return levels;
}

static btf_status fit_band(const double *band, int w, int h, int levels,
                           const btf_car_fit_opts *car, const char *what, btf_car_band *out,
                           btf_error *err)
{
    btf_pyramid p;
    btf_status rc = btf_pyramid_build(band, w, h, levels, &p, err);
    if (rc)
        return rc;
    for (int l = 0; rc == 0 && l < levels; l++) {
        char name[160];
        snprintf(name, sizeof name, "%s level %d", what, l);
        btf_car_fit_opts o = *car;
        o.what = name;
        rc = btf_car_fit(p.level[l], p.width[l], p.height[l], &o, &out[l], NULL, err);
    }
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
    int levels = o.levels ? o.levels : btf_auto_levels(bands[0], img->width, img->height);
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
        rc = fit_band(bands[b], img->width, img->height, levels, &o.car, what, out->bands[b], err);
    }
    for (int b = 0; b < 3; b++)
        free(bands[b]);
    return rc;
}
