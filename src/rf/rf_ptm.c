/*
 * rf_ptm.c — the biquadratic polynomial texture map of one reflectance
 * field (Meseth, Müller & Klein 2003, section 4.2, after Malzbender et al.
 * 2001): L(lu, lv) = a0 lu^2 + a1 lv^2 + a2 lu lv + a3 lu + a4 lv + a5 over
 * the light's projection (lu, lv) = (lx, ly), by linear least squares.
 *
 * Every texel of a view shares the light set, so the least-squares
 * operator (AᵀA)⁻¹Aᵀ is computed once per light set and a texel's fit is a
 * 6 x n matrix-vector product. A light set that cannot pin six
 * coefficients (fewer than six distinct lights) gets a tiny ridge instead
 * of an error, so the fit is still defined.
 */
#include "rf/rf.h"

#include <string.h>

btf_status rf_ptm_operator(const btf_dirset *lights, double *pinv, btf_error *err)
{
    int n = lights->count;
    double ata[36] = {0};
    for (int j = 0; j < n; j++) {
        double l[3], b[6];
        btf_dir_to_vec(lights->dirs[j], l);
        rf_ptm_basis(l[0], l[1], b);
        for (int r = 0; r < 6; r++)
            for (int c = r; c < 6; c++)
                ata[r * 6 + c] += b[r] * b[c];
    }
    double trace = 0.0;
    for (int r = 0; r < 6; r++)
        trace += ata[r * 6 + r];
    for (int r = 0; r < 6; r++)
        ata[r * 6 + r] += 1e-10 * trace / 6.0 + 1e-300;
    /* pinv column j = (AᵀA)⁻¹ b_j */
    for (int j = 0; j < n; j++) {
        double l[3], b[6], x[6];
        btf_dir_to_vec(lights->dirs[j], l);
        rf_ptm_basis(l[0], l[1], b);
        if (rf_cholesky_solve(ata, b, 6, x) != 0)
            return btf__fail(err, BTF_E_NUMERIC, "PTM fit: the %d light directions do not "
                             "determine a biquadratic (expected at least 6 distinct)", n);
        for (int r = 0; r < 6; r++)
            pinv[r * n + j] = x[r];
    }
    return BTF_OK;
}

void rf_ptm_apply(const double *pinv, int n, const float *y, double a[6])
{
    for (int r = 0; r < 6; r++) {
        const double *row = pinv + (size_t)r * n;
        double s = 0.0;
        for (int j = 0; j < n; j++)
            s += row[j] * y[j];
        a[r] = s;
    }
}
