/*
 * rf_lobes.c — the non-linear reflectance field of Meseth, Müller & Klein
 * 2003, section 4.2, equation (1): RF_v(x, l) ≈ Σ_{i=1..k} <(a,b,c)_i, l>^n_i,
 * fitted to one texel's luminances over the light directions by
 * Levenberg–Marquardt (rf_lm.c).
 *
 * Parametrisation. The lobe <(a,b,c), l>^n is kept as rho <d, l>^n with
 * d = (x, y, 1) / |(x, y, 1)| (so (a,b,c) = rho^(1/n) d): the same function
 * for lobes above the horizon, but its size rho is separate from its shape,
 * so rho, x, y, n can be boxed (rho <= BTF_RF_MAX_RHO, |x|, |y| <= 16,
 * n in [1/4, 1024], fitted as ln n) and no evaluation can overflow, which
 * the paper reports its GPU did with the raw form ("rather high exponents
 * for spatially restricted lobes", section 7).
 *
 * Initialisation, as the paper describes it ("detecting principal
 * directions with a high-pass filter and using the recovered directions as
 * an initialization"): the texel's biquadratic PTM is its low pass over the
 * light hemisphere. Lobe 1 is a broad lobe (n = 1) at the low pass's
 * principal direction, the light where the PTM is largest; lobes 2..k are
 * narrow lobes (n = 16) at the largest peaks of the high pass, data minus
 * PTM, at least 25 degrees apart, sized to the peak.
 */
#include "rf/rf.h"

#include <float.h>
#include <math.h>
#include <string.h>

typedef struct lobe_data {
    int k, n;
    const double *l;
    const float *y;
} lobe_data;

static void lobes_residuals(void *user, const double *p, double *cost, double *jtj,
                            double *jtr)
{
    const lobe_data *d = user;
    int np = 4 * d->k;
    double g[4 * BTF_RF_MAX_LOBES];
    double nexp[BTF_RF_MAX_LOBES], inv_s[BTF_RF_MAX_LOBES];
    for (int i = 0; i < d->k; i++) {
        nexp[i] = exp(p[4 * i + 3]);
        inv_s[i] = 1.0 / sqrt(p[4 * i + 1] * p[4 * i + 1] + p[4 * i + 2] * p[4 * i + 2] + 1.0);
    }
    double sum = 0.0;
    for (int j = 0; j < d->n; j++) {
        const double *l = d->l + 3 * j;
        double f = 0.0;
        for (int i = 0; i < d->k; i++) {
            const double *q = p + 4 * i;
            double c = (q[1] * l[0] + q[2] * l[1] + l[2]) * inv_s[i];
            double *gi = g + 4 * i;
            if (!(c > 1e-12)) {
                gi[0] = gi[1] = gi[2] = gi[3] = 0.0;
                continue;
            }
            double lc = log(c), cn = exp(nexp[i] * lc);
            f += q[0] * cn;
            if (!jtj)
                continue;
            double common = q[0] * nexp[i] * cn / c;
            gi[0] = cn;
            gi[1] = common * (l[0] - c * q[1] * inv_s[i]) * inv_s[i];
            gi[2] = common * (l[1] - c * q[2] * inv_s[i]) * inv_s[i];
            gi[3] = q[0] * cn * lc * nexp[i];
        }
        double r = (double)d->y[j] - f;
        sum += r * r;
        if (!jtj)
            continue;
        rf_lm_accumulate(g, np, r, jtj, jtr);
    }
    *cost = sum;
}

/* The tangent-plane coordinates (x, y) of a direction: d ∝ (x, y, 1). */
static void dir_xy(const double *l, double *x, double *y)
{
    double z = l[2] > 1.0 / RF_XY_MAX ? l[2] : 1.0 / RF_XY_MAX;
    *x = rf_clampd(l[0] / z, -RF_XY_MAX, RF_XY_MAX);
    *y = rf_clampd(l[1] / z, -RF_XY_MAX, RF_XY_MAX);
}

int rf_lobes_fit(int k, int n, const double *l, const float *y, const double ptm[6],
                 int iterations, float *out)
{
    double p[4 * BTF_RF_MAX_LOBES], lo[4 * BTF_RF_MAX_LOBES], hi[4 * BTF_RF_MAX_LOBES];
    double ymax = 0.0, ysum = 0.0;
    for (int j = 0; j < n; j++) {
        double v = isfinite(y[j]) ? y[j] : 0.0;
        ymax = v > ymax ? v : ymax;
        ysum += v;
    }
    double rho_max = 8.0 * ymax;
    rho_max = rho_max < BTF_RF_MAX_RHO ? rho_max : BTF_RF_MAX_RHO;
    for (int i = 0; i < k; i++) {
        lo[4 * i] = 0.0, hi[4 * i] = rho_max;
        lo[4 * i + 1] = lo[4 * i + 2] = -RF_XY_MAX;
        hi[4 * i + 1] = hi[4 * i + 2] = RF_XY_MAX;
        lo[4 * i + 3] = RF_LN_NMIN, hi[4 * i + 3] = RF_LN_NMAX;
    }
    /* The low pass (the PTM) and its principal direction. */
    double high[4096]; /* a direction set holds at most 4096 */
    n = n < 4096 ? n : 4096;
    int best_low = 0;
    double low_max = -DBL_MAX;
    for (int j = 0; j < n; j++) {
        double b[6], s = 0.0;
        rf_ptm_basis(l[3 * j], l[3 * j + 1], b);
        for (int r = 0; r < 6; r++)
            s += ptm[r] * b[r];
        if (s > low_max)
            low_max = s, best_low = j;
        high[j] = (isfinite(y[j]) ? y[j] : 0.0) - s;
    }
    /* Lobe 1: broad, at the low pass's principal direction, sized so that
     * its mean is the data's. */
    dir_xy(l + 3 * best_low, &p[1], &p[2]);
    p[3] = 0.0; /* n = 1 */
    double csum = 0.0, s0 = 1.0 / sqrt(p[1] * p[1] + p[2] * p[2] + 1.0);
    for (int j = 0; j < n; j++) {
        double c = (p[1] * l[3 * j] + p[2] * l[3 * j + 1] + l[3 * j + 2]) * s0;
        csum += c > 0.0 ? c : 0.0;
    }
    p[0] = csum > 0.0 ? rf_clampd(ysum / csum, 0.0, rho_max) : 0.0;
    /* Lobes 2..k: the high pass's peaks, 25 degrees apart. */
    int chosen[BTF_RF_MAX_LOBES];
    double cos_apart = cos(25.0 * M_PI / 180.0);
    for (int i = 1; i < k; i++) {
        int best = -1;
        double hmax = -DBL_MAX;
        for (int j = 0; j < n; j++) {
            int near = 0;
            for (int c = 1; c < i; c++) {
                const double *a = l + 3 * chosen[c], *b = l + 3 * j;
                near |= a[0] * b[0] + a[1] * b[1] + a[2] * b[2] > cos_apart;
            }
            if (!near && high[j] > hmax)
                hmax = high[j], best = j;
        }
        double *q = p + 4 * i;
        if (best < 0) { /* no peak left: a small lobe at the normal */
            q[0] = 0.0, q[1] = q[2] = 0.0;
        } else {
            chosen[i] = best;
            dir_xy(l + 3 * best, &q[1], &q[2]);
            q[0] = rf_clampd(hmax, 0.0, rho_max);
        }
        q[3] = log(16.0);
    }
    lobe_data d = {k, n, l, y};
    double cost;
    int steps = rho_max > 0.0 ? rf_lm(lobes_residuals, &d, 4 * k, p, lo, hi, iterations, &cost)
                              : 0;
    for (int i = 0; i < k; i++) {
        out[4 * i] = (float)rf_clampd(p[4 * i], 0.0, BTF_RF_MAX_RHO);
        out[4 * i + 1] = (float)p[4 * i + 1];
        out[4 * i + 2] = (float)p[4 * i + 2];
        out[4 * i + 3] = (float)(p[4 * i + 3] / M_LN2);
    }
    return steps;
}
