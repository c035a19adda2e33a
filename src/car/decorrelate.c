/*
 * decorrelate.c — spectral decorrelation of a colour image (paper section
 * II.C): the mean colour is subtracted and the pixels are projected on the
 * eigenvectors of their 3 x 3 colour covariance (Karhunen-Loeve transform),
 * giving three mono-spectral bands that are modelled independently. The
 * basis is orthonormal, so the inverse is its transpose and restores the
 * colour correlations exactly. Nothing is divided by an eigenvalue, so a band
 * of zero variance (a grey or constant image) is harmless: it is constant.
 */
#include "core/core.h"
#include "car/car.h"
#include "core/linalg.h"

#include <math.h>
#include <string.h>

/* The eigenvectors of the colour covariance by cyclic Jacobi rotations
 * (core/linalg.c): plain, robust and deterministic. This rule measures the
 * off-diagonal part by absolute values, stops at 1e-17 of the diagonal and
 * takes a rotation whose tangent overflowed as negligible (tangent 0); the
 * models analysed so far were made with it, and another rule could change
 * their bits. */
static const btf_linalg_jacobi_rule COLOUR_RULE = {
    .max_sweeps = 64, .abs_sums = 1, .tiny = 1e-300, .relative = 1e-17, .finite_tangent = 1};

btf_status btf__pca3(const btf_image *img, float mean[3], float basis[9], double variance[3],
                     btf_error *err)
{
    if (!img || !img->data || img->channels != 3)
        return btf__fail(err, BTF_E_ARG, "spectral decorrelation needs an RGB image");
    size_t n = (size_t)img->width * img->height;
    double m[3] = {0, 0, 0};
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            m[k] += img->data[3 * i + k];
    for (int k = 0; k < 3; k++)
        m[k] /= (double)n;
    double c[3][3] = {{0}};
    for (size_t i = 0; i < n; i++) {
        double d[3];
        for (int k = 0; k < 3; k++)
            d[k] = img->data[3 * i + k] - m[k];
        for (int a = 0; a < 3; a++)
            for (int b = a; b < 3; b++)
                c[a][b] += d[a] * d[b];
    }
    for (int a = 0; a < 3; a++)
        for (int b = a; b < 3; b++)
            c[b][a] = c[a][b] = c[a][b] / (double)n;
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++)
            if (!isfinite(c[a][b]))
                return btf__fail(err, BTF_E_NUMERIC, "colour covariance is not finite "
                                 "(pixel values too large)");
    double v[3][3], ev[3];
    btf__linalg_jacobi(&c[0][0], 3, &COLOUR_RULE, ev, &v[0][0]);
    /* Order bands by decreasing variance; fix each vector's sign so that its
     * largest component is positive (one basis per image, run to run). */
    int order[3] = {0, 1, 2};
    for (int i = 0; i < 3; i++)
        for (int j = i + 1; j < 3; j++)
            if (ev[order[j]] > ev[order[i]]) {
                int t = order[i];
                order[i] = order[j];
                order[j] = t;
            }
    for (int r = 0; r < 3; r++) {
        int col = order[r], big = 0;
        for (int k = 1; k < 3; k++)
            if (fabs(v[k][col]) > fabs(v[big][col]))
                big = k;
        double sign = v[big][col] < 0 ? -1.0 : 1.0;
        for (int k = 0; k < 3; k++)
            basis[3 * r + k] = (float)(sign * v[k][col]);
        if (variance)
            variance[r] = ev[col] > 0.0 ? ev[col] : 0.0;
    }
    for (int k = 0; k < 3; k++)
        mean[k] = (float)m[k];
    return BTF_OK;
}

void btf__decorrelate(const btf_image *img, const float mean[3], const float basis[9],
                      double *bands[3])
{
    size_t n = (size_t)img->width * img->height;
    for (size_t i = 0; i < n; i++) {
        double d[3];
        for (int k = 0; k < 3; k++)
            d[k] = (double)img->data[3 * i + k] - mean[k];
        for (int b = 0; b < 3; b++)
            bands[b][i] = basis[3 * b] * d[0] + basis[3 * b + 1] * d[1] + basis[3 * b + 2] * d[2];
    }
}
