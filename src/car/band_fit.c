/*
 * band_fit.c — the CAR models of one spectral band's Gaussian-Laplacian
 * pyramid (paper section II.C: every sub-band has its own CAR model), fitted
 * so that the levels synthesised as independent fields add up to the band
 * (docs/model.md, "Levels that add up").
 */
#include <stdio.h>
#include "core/core.h"
#include "car/car.h"

#include <stdlib.h>
#include <string.h>

/* The CAR models of one band's pyramid, coarsest first: the low-pass
 * G_{L-1} as it is, and every finer level l as the complement of the
 * up-sampled G_{l+1} in G_l (btf__car_fit_complement). Synthesis adds the
 * levels as independent fields, G_l = mean_l + Y_l + up(G_{l+1}); fitting
 * Y_l to the Laplacian L_l = G_l - up(G_{l+1}) alone would drop the
 * cross-covariance of L_l and up(G_{l+1}) (positive where the up-sampling
 * filter's response is between 0 and 1: the octave between two levels), and
 * the synthesis would lose that share of the variance — half of it at mid
 * frequencies on the leather material with 3 levels. */
btf_status btf__fit_band_levels(const double *band, int w, int h, int levels,
                                const btf_car_fit_opts *car, const char *what, btf_car_band *out,
                                btf_error *err)
{
    btf_pyramid p;
    btf_status rc = btf__pyramid_build(band, w, h, levels, &p, err);
    if (rc)
        return rc;
    int l = levels - 1;
    double *g = btf__alloc((size_t)p.width[l] * p.height[l], sizeof(double), err);
    if (!g) {
        btf__pyramid_free(&p);
        return BTF_E_NOMEM;
    }
    memcpy(g, p.level[l], (size_t)p.width[l] * p.height[l] * sizeof(double));
    for (; rc == 0 && l >= 0; l--) {
        char name[160];
        snprintf(name, sizeof name, "%s level %d", what, l);
        btf_car_fit_opts o = *car;
        o.what = name;
        if (l == levels - 1) {
            rc = btf__car_fit(g, p.width[l], p.height[l], &o, &out[l], NULL, err);
            continue;
        }
        double *up;
        size_t n = (size_t)p.width[l] * p.height[l];
        rc = btf__pyr_up(g, p.width[l + 1], p.height[l + 1], p.width[l], p.height[l], &up, err);
        free(g);
        g = NULL;
        if (rc)
            break;
        /* G_l = L_l + up(G_{l+1}): into p.level[l], which is not needed again */
        for (size_t i = 0; i < n; i++)
            p.level[l][i] += up[i];
        rc = btf__car_fit_complement(p.level[l], up, p.width[l], p.height[l], &o, &out[l], NULL,
                                     err);
        free(up);
        if (rc == 0 && l > 0) {
            if (!(g = btf__alloc(n, sizeof(double), err)))
                rc = BTF_E_NOMEM;
            else
                memcpy(g, p.level[l], n * sizeof(double));
        }
    }
    free(g);
    btf__pyramid_free(&p);
    return rc;
}
