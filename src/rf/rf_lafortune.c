/*
 * rf_lafortune.c — the contrast of Meseth, Müller & Klein 2003, Table 1's
 * first column: one Lafortune model per texel over every (view, light)
 * image (Lafortune et al. 1997; per texel as McAllister et al. 2002),
 *   Y(l, v) = rho_d l_z + Σ_{i=1..k} rho_i (cx_i lx vx + cy_i ly vy + cz_i lz vz)^n_i,
 * fitted by Levenberg–Marquardt (rf_lm.c). The lobe's size rho is kept
 * apart from its shape and |cx|, |cy|, |cz| <= 1, so the base is at most 1
 * and no evaluation exceeds rho (no overflow); n in [1/4, 1024], fitted as
 * ln n. Initial lobes: the classic forward-specular (-1, -1, 1), a broader
 * off-specular one, a retro-reflective (1, 1, 1) and a sharp specular one,
 * the first k of them.
 */
#include "rf/rf.h"

#include <math.h>
#include <string.h>

typedef struct laf_data {
    int k, n;
    const double *l, *v;
    const float *y;
} laf_data;

static void laf_residuals(void *user, const double *p, double *cost, double *jtj, double *jtr)
{
    const laf_data *d = user;
    int np = 1 + 5 * d->k;
    double g[RF_LM_MAX], nexp[BTF_RF_MAX_LOBES];
    for (int i = 0; i < d->k; i++)
        nexp[i] = exp(p[1 + 5 * i + 4]);
    double sum = 0.0;
    for (int j = 0; j < d->n; j++) {
        const double *l = d->l + 3 * j, *v = d->v + 3 * j;
        double lz = l[2] > 0.0 ? l[2] : 0.0;
        double f = p[0] * lz;
        g[0] = lz;
        for (int i = 0; i < d->k; i++) {
            const double *q = p + 1 + 5 * i;
            double *gi = g + 1 + 5 * i;
            double a0 = l[0] * v[0], a1 = l[1] * v[1], a2 = l[2] * v[2];
            double s = q[1] * a0 + q[2] * a1 + q[3] * a2;
            if (!(s > 1e-12)) {
                gi[0] = gi[1] = gi[2] = gi[3] = gi[4] = 0.0;
                continue;
            }
            double ls = log(s), sn = exp(nexp[i] * ls);
            f += q[0] * sn;
            if (!jtj)
                continue;
            double common = q[0] * nexp[i] * sn / s;
            gi[0] = sn;
            gi[1] = common * a0, gi[2] = common * a1, gi[3] = common * a2;
            gi[4] = q[0] * sn * ls * nexp[i];
        }
        double r = (double)d->y[j] - f;
        sum += r * r;
        if (!jtj)
            continue;
        rf_lm_accumulate(g, np, r, jtj, jtr);
    }
    *cost = sum;
}

int rf_lafortune_fit(int k, int n, const double *l, const double *v, const float *y,
                     int iterations, float *out)
{
    static const double init[4][4] = {{-1, -1, 1, 8}, {-0.6, -0.6, 0.8, 2},
                                      {1, 1, 1, 4}, {-1, -1, 1, 64}};
    int np = 1 + 5 * k;
    double p[RF_LM_MAX], lo[RF_LM_MAX], hi[RF_LM_MAX];
    double ymax = 0.0, ysum = 0.0, yz = 0.0, zz = 0.0;
    for (int j = 0; j < n; j++) {
        double t = isfinite(y[j]) ? y[j] : 0.0, lz = l[3 * j + 2] > 0.0 ? l[3 * j + 2] : 0.0;
        ymax = t > ymax ? t : ymax;
        ysum += t, yz += t * lz, zz += lz * lz;
    }
    double rho_max = 8.0 * ymax;
    rho_max = rho_max < BTF_RF_MAX_RHO ? rho_max : BTF_RF_MAX_RHO;
    lo[0] = 0.0, hi[0] = rho_max;
    p[0] = zz > 0.0 ? rf_clampd(0.7 * yz / zz, 0.0, rho_max) : 0.0;
    for (int i = 0; i < k; i++) {
        double *q = p + 1 + 5 * i, *ql = lo + 1 + 5 * i, *qh = hi + 1 + 5 * i;
        q[0] = rf_clampd(0.2 * ysum / (n > 0 ? n : 1), 0.0, rho_max);
        q[1] = init[i][0], q[2] = init[i][1], q[3] = init[i][2], q[4] = log(init[i][3]);
        ql[0] = 0.0, qh[0] = rho_max;
        ql[1] = ql[2] = ql[3] = -1.0;
        qh[1] = qh[2] = qh[3] = 1.0;
        ql[4] = RF_LN_NMIN, qh[4] = RF_LN_NMAX;
    }
    laf_data d = {k, n, l, v, y};
    double cost;
    int steps = rho_max > 0.0 ? rf_lm(laf_residuals, &d, np, p, lo, hi, iterations, &cost) : 0;
    out[0] = (float)p[0];
    for (int i = 0; i < k; i++) {
        const double *q = p + 1 + 5 * i;
        float *o = out + 1 + 5 * i;
        o[0] = (float)q[0], o[1] = (float)q[1], o[2] = (float)q[2], o[3] = (float)q[3];
        o[4] = (float)(q[4] / M_LN2);
    }
    return steps;
}
