/*
 * rf_sample.c — which window of the material the memory reduction of
 * Meseth, Müller & Klein 2003, section 6, fits. The paper fits "small
 * samples" (64^2 of Proposte and corduroy, 96^2 of knitted wool) without
 * saying how they were cut; here the rule is documented and deterministic:
 * of every sw x sh window of the representative image (rf_feature.c), the
 * one whose channels' means and standard deviations are closest (sum of
 * squared differences) to the whole image's, the first in row-major order
 * on ties. A window like the whole in level and contrast of albedo and
 * slope is one without a stain or a seam that the synthesis would then
 * repeat over the surface. Means and spreads of all windows come from
 * summed-area tables, so every window is tried in O(width height).
 */
#include "rf/rf_sample.h"

#include <math.h>
#include <stdlib.h>

btf_status rf_sample_choose(const float *feat, int width, int height, int sw, int sh, int *x,
                            int *y, btf_error *err)
{
    *x = *y = 0;
    if (sw < 1 || sh < 1 || sw > width || sh > height)
        return btf__fail(err, BTF_E_ARG, "sample of %dx%d texels (expected 1x1 up to the "
                         "images' %dx%d)", sw, sh, width, height);
    size_t W = (size_t)width + 1;
    /* per channel: sum and sum of squares, (width + 1) x (height + 1) */
    double *sat = btf__calloc(W * ((size_t)height + 1), 2 * RF_FEATURES * sizeof(double), err);
    if (!sat)
        return BTF_E_NOMEM;
    const int K = 2 * RF_FEATURES;
    for (int r = 0; r < height; r++)
        for (int c = 0; c < width; c++) {
            const float *f = feat + ((size_t)r * width + c) * RF_FEATURES;
            double *o = sat + (((size_t)r + 1) * W + c + 1) * K;
            const double *up = sat + ((size_t)r * W + c + 1) * K;
            const double *left = sat + (((size_t)r + 1) * W + c) * K;
            const double *diag = sat + ((size_t)r * W + c) * K;
            for (int k = 0; k < RF_FEATURES; k++) {
                double v = f[k];
                o[2 * k] = v + up[2 * k] + left[2 * k] - diag[2 * k];
                o[2 * k + 1] = v * v + up[2 * k + 1] + left[2 * k + 1] - diag[2 * k + 1];
            }
        }
    double whole_mean[RF_FEATURES], whole_sd[RF_FEATURES];
    const double *all = sat + ((size_t)height * W + width) * K;
    double n_all = (double)width * height, n = (double)sw * sh;
    for (int k = 0; k < RF_FEATURES; k++) {
        whole_mean[k] = all[2 * k] / n_all;
        double var = all[2 * k + 1] / n_all - whole_mean[k] * whole_mean[k];
        whole_sd[k] = var > 0.0 ? sqrt(var) : 0.0;
    }
    double best = INFINITY;
    for (int r = 0; r + sh <= height; r++)
        for (int c = 0; c + sw <= width; c++) {
            const double *a = sat + ((size_t)r * W + c) * K;
            const double *b = sat + ((size_t)r * W + c + sw) * K;
            const double *d = sat + (((size_t)r + sh) * W + c) * K;
            const double *e = sat + (((size_t)r + sh) * W + c + sw) * K;
            double dist = 0.0;
            for (int k = 0; k < RF_FEATURES; k++) {
                double m = (e[2 * k] - b[2 * k] - d[2 * k] + a[2 * k]) / n;
                double var = (e[2 * k + 1] - b[2 * k + 1] - d[2 * k + 1] + a[2 * k + 1]) / n -
                             m * m;
                double sd = var > 0.0 ? sqrt(var) : 0.0;
                dist += (m - whole_mean[k]) * (m - whole_mean[k]) +
                        (sd - whole_sd[k]) * (sd - whole_sd[k]);
            }
            if (dist < best)
                best = dist, *x = c, *y = r;
        }
    free(sat);
    return BTF_OK;
}
