/*
 * rf_lm.c — the Levenberg–Marquardt solver of the non-linear reflectance
 * field fits (Meseth, Müller & Klein 2003, section 4.2: "A Levenberg-
 * Marquardt algorithm is used for the fitting", after Lafortune et al.
 * 1997 and McAllister et al. 2002): damped Gauss–Newton steps on a few
 * parameters, with Marquardt's diagonal scaling, projected onto a box.
 *
 * Why it never returns NaN: it starts from a finite point, accepts a step
 * only when the new cost is finite and smaller, and a matrix that is not
 * positive definite (a dead lobe has zero derivatives) only raises the
 * damping. A dark, saturated or constant texel therefore ends at a finite
 * point, at worst the initial one.
 */
#include "rf/rf.h"
#include "core/linalg.h"

#include <math.h>
#include <string.h>

/* The fits' contract on top of core/linalg.c: a factor with an infinite
 * pivot, or a solution that is not finite, is refused (-1), so that the
 * callers never step to or store a non-finite value. Checking the pivots
 * after the factorisation refuses exactly the matrices a check at each
 * pivot would: the factor's entries up to the first infinite pivot are the
 * same, and that pivot stays on l's diagonal. */
void rf_lm_accumulate(const double *g, int np, double r, double *jtj, double *jtr)
{
    for (int a = 0; a < np; a++) {
        if (g[a] == 0.0)
            continue;
        jtr[a] += g[a] * r;
        for (int b = a; b < np; b++)
            jtj[a * np + b] += g[a] * g[b];
    }
}

int rf_cholesky_solve(const double *a, const double *b, int n, double *x)
{
    double l[RF_LM_MAX * RF_LM_MAX];
    if (btf__linalg_cholesky(a, n, 1, n, l) != 0)
        return -1;
    for (int i = 0; i < n; i++)
        if (!isfinite(l[i * n + i]))
            return -1;
    for (int i = 0; i < n; i++)
        x[i] = b[i];
    btf__linalg_cholesky_solve(l, n, x);
    for (int i = 0; i < n; i++)
        if (!isfinite(x[i]))
            return -1;
    return 0;
}

static void evaluate(rf_lm_fn fn, void *user, int np, const double *p, double *cost,
                     double *jtj, double *jtr)
{
    *cost = 0.0;
    if (jtj) {
        memset(jtj, 0, sizeof(double) * np * np);
        memset(jtr, 0, sizeof(double) * np);
    }
    fn(user, p, cost, jtj, jtr);
}

int rf_lm(rf_lm_fn fn, void *user, int np, double *p, const double *lo, const double *hi,
          int iterations, double *cost_out)
{
    double jtj[RF_LM_MAX * RF_LM_MAX], jtr[RF_LM_MAX];
    double njtj[RF_LM_MAX * RF_LM_MAX], njtr[RF_LM_MAX];
    double a[RF_LM_MAX * RF_LM_MAX], step[RF_LM_MAX], trial[RF_LM_MAX];
    for (int i = 0; i < np; i++)
        p[i] = rf_clampd(isfinite(p[i]) ? p[i] : 0.5 * (lo[i] + hi[i]), lo[i], hi[i]);
    double cost;
    evaluate(fn, user, np, p, &cost, jtj, jtr);
    if (!isfinite(cost)) { /* cannot happen with the clamped models; stay put */
        *cost_out = INFINITY;
        return 0;
    }
    double lambda = 1e-3;
    int it = 0;
    while (it < iterations && cost > 0.0) {
        it++;
        int accepted = 0;
        while (!accepted) {
            double trace = 0.0;
            for (int i = 0; i < np; i++)
                trace += jtj[i * np + i];
            double tiny = 1e-12 * (trace > 0.0 ? trace / np : 1.0) + 1e-30;
            memcpy(a, jtj, sizeof(double) * np * np);
            for (int i = 0; i < np; i++)
                a[i * np + i] += lambda * (jtj[i * np + i] + tiny) + tiny;
            if (rf_cholesky_solve(a, jtr, np, step) == 0) {
                int moved = 0;
                for (int i = 0; i < np; i++) {
                    trial[i] = rf_clampd(p[i] + step[i], lo[i], hi[i]);
                    moved |= trial[i] != p[i];
                }
                if (!moved) /* the step is lost in rounding or the box: done */
                    goto done;
                double c;
                evaluate(fn, user, np, trial, &c, njtj, njtr);
                if (isfinite(c) && c < cost) {
                    double gain = cost - c;
                    memcpy(p, trial, sizeof(double) * np);
                    memcpy(jtj, njtj, sizeof(double) * np * np);
                    memcpy(jtr, njtr, sizeof(double) * np);
                    cost = c;
                    lambda = lambda / 3.0 < 1e-9 ? 1e-9 : lambda / 3.0;
                    accepted = 1;
                    if (gain <= 1e-10 * cost + 1e-20) /* converged */
                        goto done;
                    continue;
                }
            }
            lambda *= 4.0;
            if (lambda > 1e10)
                goto done;
        }
    }
done:
    *cost_out = cost;
    return it;
}
