/*
 * car_fit.c — estimation of the 2D causal auto-regressive (CAR) model of one
 * sub-band (paper section II.C, eq. (1)-(2)):
 *
 *     Y_r = gamma X_r + e_r,   e_r ~ N(0, sigma^2) white,
 *
 * X_r the values at the causal neighbourhood offsets I_r of pixel r.
 *
 * Estimates. With the conjugate normal-gamma prior gamma | sigma^2 ~
 * N(0, sigma^2 V0^-1), sigma^-2 ~ Gamma(a0, b0), V0 = v0 I, and the data
 * gathered in V = sum_t [Y_t; X_t][Y_t; X_t]^T, the posterior gives
 *     gamma^T = (V_xx + V0)^-1 V_xy,   lambda = V_yy - V_xy^T (V_xx + V0)^-1 V_xy,
 *     sigma^2 = (2 b0 + lambda) / (2 a0 + t - 2),
 * the paper's estimates with its prior matrix V0 (eq. 2). All sums are double;
 * the solve is a Cholesky factorisation of V_xx + V0, which the prior makes
 * positive definite: no explicit inverse, no failure on a constant band.
 *
 * Neighbourhood choice ("model only what the data requires"). Candidates are
 * a nested family (the first 1, 2, 3, 4, 6, ..., 22, 24 offsets of FAMILY
 * below; before the texture distances measured it, it stopped at 14, and 14 won on every band of
 * every photograph tried: the family, not the data, limited the choice). Each is scored by its log marginal
 * likelihood in closed form
 *     ln p(Y | I) = (eta/2) ln v0 - (1/2) ln |V_xx + V0| + a0 ln b0 - a_t ln b_t
 *                   + ln Gamma(a_t) - ln Gamma(a0) - (t/2) ln 2 pi,
 *     a_t = a0 + t/2,  b_t = b0 + lambda/2,
 * over the same t equations for every candidate (those where the largest
 * neighbourhood fits), so the posterior probabilities compare fairly; the
 * most probable candidate wins. With equal prior odds this is the Bayesian
 * decision rule of Haindl's CAR model selection; the determinant term is the
 * Occam factor that keeps smooth bands small. Data are standardised first
 * (mean 0, variance 1), so v0 = 1, a0 = 1, b0 = 0.01 are weak and scale-free.
 *
 * Stability. Least-squares and Bayesian estimates are not guaranteed stable
 * (a ramp 1.002^x along the rows gives gamma = 1.002 on 0:-1). Every
 * estimate passes the exact test of car/stability.c (the validator's) and
 * the settling rule of car/settle.c (roots near the unit circle correlate
 * beyond the synthesis margins): one that fails is shrunk (gamma <- 0.95
 * gamma, repeatedly) until it passes, sigma is re-estimated for the shrunk
 * gamma, and a warning names the band and what failed.
 */
#include <stdio.h>
#include "core/core.h"
#include "car/car.h"
#include "core/linalg.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PRIOR_V0 1.0
#define PRIOR_A0 1.0
#define PRIOR_B0 0.01

/* The candidate family, nearest first: a ring of offsets at a time, each
 * ring symmetric about the column (so that no direction is favoured). Its
 * 24 offsets are every causal offset within 3 rows up and 3 columns either
 * way (the full half-plane block of 7 x 3 plus the 3 to the left): the
 * whole of BTF_CAR_MAX_NEIGHBOURS, the GPU task record's 24 offsets, and
 * within the AVX2 wavefront's reach (src/synth/wave.c: 3 rows up, 4
 * columns), so that the larger models keep the fast synthesis path. */
static const btf_offset FAMILY[BTF_CAR_MAX_NEIGHBOURS] = {
    {0, -1},  {-1, 0},  {-1, -1}, {-1, 1},  {0, -2},  {-2, 0},  {-1, -2}, {-1, 2},
    {-2, -1}, {-2, 1},  {-2, -2}, {-2, 2},  {0, -3},  {-3, 0},  {-3, -1}, {-3, 1},
    {-1, -3}, {-1, 3},  {-3, -2}, {-3, 2},  {-2, -3}, {-2, 3},  {-3, -3}, {-3, 3}};
static const int FAMILY_SIZES[] = {1, 2, 3, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24};
#define N_FAMILY_SIZES 14

int btf__car_candidate_offsets(btf_offset offsets[BTF_CAR_MAX_NEIGHBOURS])
{
    memcpy(offsets, FAMILY, sizeof FAMILY);
    return BTF_CAR_MAX_NEIGHBOURS;
}

/* ----------------------------------------------------------- accumulation */

typedef struct reach {
    int up, left, right;
} reach;

static reach reach_of(const btf_offset *o, int n)
{
    reach r = {0, 0, 0};
    for (int i = 0; i < n; i++) {
        if (-o[i].row > r.up)
            r.up = -o[i].row;
        if (-o[i].col > r.left)
            r.left = -o[i].col;
        if (o[i].col > r.right)
            r.right = o[i].col;
    }
    return r;
}

/* V = sum over the pixels where all n offsets fit of [y; x][y; x]^T,
 * (n+1) x (n+1), row-major; returns t, the number of pixels. */
static long accumulate_one(const double *z, int w, int h, const btf_offset *o, int n, double *v)
{
    reach r = reach_of(o, n);
    int m = n + 1;
    memset(v, 0, (size_t)m * m * sizeof(double));
    long t = 0;
    double u[BTF_CAR_MAX_NEIGHBOURS + 1];
    for (int y = r.up; y < h; y++)
        for (int x = r.left; x < w - r.right; x++) {
            u[0] = z[(size_t)y * w + x];
            for (int i = 0; i < n; i++)
                u[i + 1] = z[(size_t)(y + o[i].row) * w + x + o[i].col];
            for (int i = 0; i < m; i++)
                for (int j = 0; j <= i; j++)
                    v[i * m + j] += u[i] * u[j];
            t++;
        }
    for (int i = 0; i < m; i++)
        for (int j = i + 1; j < m; j++)
            v[i * m + j] = v[j * m + i];
    return t;
}

/* The moments V of z, less those of `sub` when it is not NULL (the
 * complement fit of btf__car_fit_complement: the moments of a field whose
 * autocovariance is z's minus sub's). */
static long accumulate(const double *z, const double *sub, int w, int h, const btf_offset *o,
                       int n, double *v)
{
    long t = accumulate_one(z, w, h, o, n, v);
    if (sub) {
        double vs[(BTF_CAR_MAX_NEIGHBOURS + 1) * (BTF_CAR_MAX_NEIGHBOURS + 1)];
        accumulate_one(sub, w, h, o, n, vs);
        for (int i = 0; i < (n + 1) * (n + 1); i++)
            v[i] -= vs[i];
    }
    return t;
}

/* Estimates and log evidence of the sub-model using the first eta offsets
 * (the leading block of V). Returns 0, or -1 when the fit is impossible. */
static int fit_prefix(const double *v, int m, int eta, long t, double *gamma, double *lambda,
                      double *log_ev)
{
    double a[(BTF_CAR_MAX_NEIGHBOURS) * (BTF_CAR_MAX_NEIGHBOURS)];
    double l[(BTF_CAR_MAX_NEIGHBOURS) * (BTF_CAR_MAX_NEIGHBOURS)];
    double vxy[BTF_CAR_MAX_NEIGHBOURS];
    for (int i = 0; i < eta; i++) {
        for (int j = 0; j < eta; j++)
            a[i * eta + j] = v[(i + 1) * m + (j + 1)] + (i == j ? PRIOR_V0 : 0.0);
        vxy[i] = v[(i + 1) * m];
    }
    if (btf__linalg_cholesky(a, eta, 0, eta, l) != 0)
        return -1;
    memcpy(gamma, vxy, (size_t)eta * sizeof *gamma);
    btf__linalg_cholesky_solve(l, eta, gamma);
    double fit = 0.0, logdet = 0.0;
    for (int i = 0; i < eta; i++) {
        fit += vxy[i] * gamma[i];
        logdet += 2.0 * log(l[i * eta + i]);
    }
    double lam = v[0] - fit;
    if (lam < 0.0)
        lam = 0.0; /* rounding on a perfectly predictable band */
    double at = PRIOR_A0 + 0.5 * (double)t, bt = PRIOR_B0 + 0.5 * lam;
    *lambda = lam;
    *log_ev = 0.5 * eta * log(PRIOR_V0) - 0.5 * logdet + PRIOR_A0 * log(PRIOR_B0) - at * log(bt) +
              lgamma(at) - lgamma(PRIOR_A0) - 0.5 * (double)t * log(2.0 * 3.14159265358979323846);
    for (int i = 0; i < eta; i++)
        if (!isfinite(gamma[i]))
            return -1;
    return isfinite(*log_ev) ? 0 : -1;
}

/* Residual sum of squares of a given gamma from V: V_yy - 2 g.V_xy + g V_xx g. */
static double residual(const double *v, int m, const double *g, int eta)
{
    double s = v[0];
    for (int i = 0; i < eta; i++) {
        s -= 2.0 * g[i] * v[(i + 1) * m];
        for (int j = 0; j < eta; j++)
            s += g[i] * g[j] * v[(i + 1) * m + (j + 1)];
    }
    return s > 0.0 ? s : 0.0;
}

/* ------------------------------------------------------------------ fitting */

static void warn(const btf_car_fit_opts *o, const char *text)
{
    if (!o->warn)
        return;
    char msg[512];
    snprintf(msg, sizeof msg, "%s%s%s", o->what ? o->what : "", o->what ? ": " : "", text);
    o->warn(o->warn_user, msg);
}

/* float of a double, clamped to the finite float range. */
static float to_float(double v)
{
    if (v > FLT_MAX)
        return FLT_MAX;
    if (v < -FLT_MAX)
        return -FLT_MAX;
    return (float)v;
}

/* Mean and standard deviation in double, in two passes over the band
 * scaled by its largest magnitude, so that values near the double limits
 * (1e300) do not overflow when squared. */
static void moments(const double *band, size_t n, double *mean, double *sd)
{
    double big = 0.0;
    for (size_t i = 0; i < n; i++)
        if (fabs(band[i]) > big)
            big = fabs(band[i]);
    if (!(big > 0.0)) {
        *mean = 0.0;
        *sd = 0.0;
        return;
    }
    double m = 0.0;
    for (size_t i = 0; i < n; i++)
        m += band[i] / big;
    m /= (double)n;
    double v = 0.0;
    for (size_t i = 0; i < n; i++) {
        double d = band[i] / big - m;
        v += d * d;
    }
    *mean = m * big;
    *sd = sqrt(v / (double)n) * big;
}

/* Whether the fit keeps b: stable by the exact test of car/stability.c (the
 * validator's), and settling (car/settle.c). 1 or 0, with why (why_n
 * bytes) saying what failed; -1 when out of memory. */
static int keeps(const btf_car_band *b, char *why, size_t why_n)
{
    char reason[200];
    if (!btf__car_stability_why(b, reason, sizeof reason)) {
        snprintf(why, why_n, "unstable estimate (%s)", reason);
        return 0;
    }
    int settles = btf__car_fit_settles(b);
    if (settles == 0)
        snprintf(why, why_n, "estimate too near the unit circle to settle (a field of it from "
                 "zeros still grows over 160 rows: its correlation outreaches the synthesis "
                 "margins)");
    return settles;
}

/* Shrinks gamma (gamma <- 0.95^k gamma, the least k) until the fit keeps
 * it; *factor gets 0.95^k, why the estimate's failure (why_n bytes). A
 * whole step of 5 % rather than the largest factor kept: a band pushed
 * onto the margin would correlate over 1e6 pixels, far beyond any
 * synthesis margin (car/margin.c). Small enough a factor always passes
 * (both tests' sufficient sum f sum |gamma| < 0.99 holds from k = 60 on
 * for sum |gamma| <= 20); past 200 steps (sum |gamma| above 28000, which
 * the prior keeps estimates from) the band is dropped to white noise. -1
 * when out of memory (shrinking anyway would make the result depend on
 * free memory). */
static int stabilise(btf_car_band *b, double *factor, char *why, size_t why_n)
{
    double f = 1.0;
    float g0[BTF_CAR_MAX_NEIGHBOURS];
    memcpy(g0, b->gamma, sizeof g0);
    int kept = keeps(b, why, why_n);
    for (int k = 0; k < 200 && kept == 0; k++) {
        f *= 0.95;
        for (int i = 0; i < b->n; i++)
            b->gamma[i] = (float)(g0[i] * f);
        char later[8]; /* the first failure is the one reported */
        kept = keeps(b, later, sizeof later);
    }
    if (kept < 0)
        return -1;
    if (!kept) {
        b->n = 0;
        f = 0.0;
    }
    *factor = f;
    return 0;
}

btf_car_fit_opts btf_car_fit_defaults(void)
{
    return (btf_car_fit_opts){.struct_size = sizeof(btf_car_fit_opts),
                              .n_fixed = 0, .max_neighbours = BTF_CAR_MAX_NEIGHBOURS};
}

/* The options with every zero (or negative) count replaced by its default. */
static btf_status resolve_opts(const btf_car_fit_opts *opts, btf_car_fit_opts *o, btf_error *err)
{
    btf_car_fit_opts d = btf_car_fit_defaults();
    if (btf__opts_take(o, sizeof *o, opts, &d, "btf_car_fit", err))
        return BTF_E_ARG;
    if (o->max_neighbours <= 0)
        o->max_neighbours = d.max_neighbours;
    return BTF_OK;
}

/* The fit of `band`, or with `sub` (not NULL) the complement fit: the
 * moments are band's less sub's, the mean band's less sub's. Returns 1 (and
 * fits nothing) when the complement has no variance or no candidate fits it,
 * so that the caller can fall back to the difference band. */
static btf_status fit(const double *band, const double *sub, int w, int h,
                      const btf_car_fit_opts *opts, btf_car_band *out, btf_car_fit_info *info,
                      btf_error *err)
{
    btf_car_fit_opts o;
    if (resolve_opts(opts, &o, err))
        return BTF_E_ARG;
    btf_car_fit_info inf = {.chosen = -1, .shrink = 1.0};
    memset(out, 0, sizeof *out);
    if (!band || w < 1 || h < 1)
        return btf__fail(err, BTF_E_ARG, "CAR fit of a %d x %d band", w, h);
    if (o.n_fixed < 0 || o.n_fixed > BTF_CAR_MAX_NEIGHBOURS)
        return btf__fail(err, BTF_E_ARG, "neighbourhood of %d offsets", o.n_fixed);
    if (!(o.coefficient_bits >= 0.0 && o.coefficient_bits <= 1e6))
        return btf__fail(err, BTF_E_ARG, "CAR fit: %g bits per coefficient (expected 0..1e6)",
                         o.coefficient_bits);
    for (int i = 0; i < o.n_fixed; i++)
        if (!btf__offset_is_causal(o.fixed[i]))
            return btf__fail(err, BTF_E_ARG, "offset %d:%d is not causal", o.fixed[i].row,
                             o.fixed[i].col);
    size_t n = (size_t)w * h;
    for (size_t i = 0; i < n; i++)
        if (!isfinite(band[i]) || (sub && !isfinite(sub[i])))
            return btf__fail(err, BTF_E_ARG, "CAR fit: sample %zu of the band is not finite", i);
    double mean, sd, sub_mean = 0.0, sub_sd = 0.0;
    moments(band, n, &mean, &sd);
    if (sub)
        moments(sub, n, &sub_mean, &sub_sd);
    if (!isfinite(mean) || !isfinite(sd) || !isfinite(sub_mean) || !isfinite(sub_sd))
        return btf__fail(err, BTF_E_NUMERIC, "CAR fit: band mean or variance overflows");
    double band_mean = mean;
    if (sub) {
        /* the complement's variance: what the band holds beyond sub */
        double var = (sd - sub_sd) * (sd + sub_sd);
        if (!(var > 1e-6 * sd * sd))
            return 1;
        mean -= sub_mean;
        sd = sqrt(var);
    }
    out->mean = to_float(mean);
    /* A constant band: nothing to model beyond its mean. The floor is
     * relative to the band's own values (its largest magnitude), so a band
     * of any scale (an image scaled by 1e-30 as well as by 1e30) is modelled
     * alike; below it the variation is rounding noise of its values. */
    double big = 0.0;
    for (size_t i = 0; i < n; i++)
        if (fabs(band[i]) > big)
            big = fabs(band[i]);
    if (sub && !(sd > 1e-12 * big))
        return 1;
    if (!(sd > 1e-12 * big)) {
        if (sd > 0.0) {
            char text[200];
            snprintf(text, sizeof text, "treated as constant: its standard deviation %.3g is "
                     "below 1e-12 of its largest magnitude %.3g", sd, big);
            warn(&o, text);
        }
        if (info)
            *info = inf;
        return BTF_OK;
    }
    double *z = btf__alloc(sub ? 2 * n : n, sizeof(double), err), *zs = sub ? z + n : NULL;
    if (!z)
        return BTF_E_NOMEM;
    for (size_t i = 0; i < n; i++)
        z[i] = (band[i] - band_mean) / sd;
    for (size_t i = 0; sub && i < n; i++)
        zs[i] = (sub[i] - sub_mean) / sd;

    const btf_offset *offs = o.n_fixed ? o.fixed : FAMILY;
    int maxn = o.max_neighbours;
    int sizes[N_FAMILY_SIZES], nsizes = 0;
    if (o.n_fixed) {
        sizes[nsizes++] = o.n_fixed;
    } else {
        for (int i = 0; i < N_FAMILY_SIZES; i++)
            if (FAMILY_SIZES[i] <= maxn)
                sizes[nsizes++] = FAMILY_SIZES[i];
        if (nsizes == 0)
            sizes[nsizes++] = 1;
    }
    /* Shrink the family until its largest member has equations to spare:
     * tiny images get small models instead of none. */
    double v[(BTF_CAR_MAX_NEIGHBOURS + 1) * (BTF_CAR_MAX_NEIGHBOURS + 1)];
    long t = 0;
    while (nsizes > 0) {
        t = accumulate(z, zs, w, h, offs, sizes[nsizes - 1], v);
        if (t >= 2L * sizes[nsizes - 1] + 4)
            break;
        nsizes--;
    }
    inf.pixels = t;
    int m = nsizes ? sizes[nsizes - 1] + 1 : 0;
    double best = -INFINITY, best_lambda = 0.0, g[BTF_CAR_MAX_NEIGHBOURS];
    int best_eta = 0;
    for (int c = 0; c < nsizes; c++) {
        double gc[BTF_CAR_MAX_NEIGHBOURS], lam, ev;
        if (fit_prefix(v, m, sizes[c], t, gc, &lam, &ev) != 0)
            continue;
        inf.size[inf.candidates] = sizes[c];
        inf.log_evidence[inf.candidates] = ev;
        /* The prior odds of a candidate: 2^-bits per coefficient it stores
         * (o.coefficient_bits; 0: equal odds, the paper's rule). */
        double score = ev - o.coefficient_bits * M_LN2 * sizes[c];
        if (score > best) {
            best = score;
            best_eta = sizes[c];
            best_lambda = lam;
            inf.chosen = inf.candidates;
            memcpy(g, gc, (size_t)sizes[c] * sizeof(double));
        }
        inf.candidates++;
    }
    if (inf.chosen < 0 && sub) {
        free(z);
        return 1; /* the complement's moments are not positive definite */
    }
    if (inf.chosen < 0) {
        /* No neighbourhood fits (1 x 1, 1 x N images): white noise. */
        out->sigma = to_float(sd);
        char text[160];
        snprintf(text, sizeof text, "too small for a CAR model (%ld equations); white noise", t);
        warn(&o, text);
        free(z);
        if (info)
            *info = inf;
        return BTF_OK;
    }
    out->n = best_eta;
    memcpy(out->offsets, offs, (size_t)best_eta * sizeof(btf_offset));
    for (int i = 0; i < best_eta; i++)
        out->gamma[i] = (float)g[i];
    double s2 = (2.0 * PRIOR_B0 + best_lambda) / (2.0 * PRIOR_A0 + (double)t - 2.0);
    char why[300];
    if (stabilise(out, &inf.shrink, why, sizeof why) < 0) {
        free(z);
        return btf__fail(err, BTF_E_NOMEM, "out of memory checking the model's stability");
    }
    if (inf.shrink < 1.0) {
        double gs[BTF_CAR_MAX_NEIGHBOURS];
        for (int i = 0; i < out->n; i++)
            gs[i] = out->gamma[i];
        s2 = (2.0 * PRIOR_B0 + residual(v, m, gs, out->n)) / (2.0 * PRIOR_A0 + (double)t - 2.0);
        char text[400];
        snprintf(text, sizeof text, "%s: coefficients scaled by %.3f", why, inf.shrink);
        warn(&o, text);
    }
    out->sigma = to_float(sqrt(s2) * sd);
    free(z);
    int margin = btf__car_margin(out);
    if (margin < 0)
        return btf__fail(err, BTF_E_NOMEM, "out of memory");
    if (margin == BTF_SYNTH_MARGIN_MAX) {
        /* Nearly unstable: its correlation outreaches the largest margin. */
        double short_by = btf__car_margin_shortfall(out, BTF_SYNTH_MARGIN_MAX);
        /* What synthesis really gives against the band's own variance: a
         * pure periodic pattern comes out (nearly) flat. */
        double got = btf__car_synth_variance(out, BTF_SYNTH_MARGIN_MAX);
        double missed = got < 0.0 ? -1.0 : 1.0 - got / (sd * sd);
        if (missed >= BTF_CAR_MISSED_LOUD) {
            char text[300];
            snprintf(text, sizeof text, BTF_CAR_MISSED_TEXT " %.0f%% of the band's variance: "
                     "synthesis gives %.3g of its %.3g (a periodic pattern, such as a 1-pixel "
                     "checkerboard, is beyond a CAR model: its recursion does not settle within "
                     "the %d-pixel synthesis margin)", 100.0 * (missed > 1.0 ? 1.0 : missed),
                     got, sd * sd, BTF_SYNTH_MARGIN_MAX);
            warn(&o, text);
        } else if (short_by > BTF_SYNTH_MARGIN_EPS) {
            char text[200];
            snprintf(text, sizeof text, "correlation reaches beyond the %d-pixel synthesis "
                     "margin: the first rows and columns of a synthesis miss at least %.2g%% of "
                     "the stationary variance", BTF_SYNTH_MARGIN_MAX, 100.0 * short_by);
            warn(&o, text);
        }
    }
    if (info)
        *info = inf;
    return BTF_OK;
}

btf_status btf__car_fit(const double *band, int w, int h, const btf_car_fit_opts *opts,
                        btf_car_band *out, btf_car_fit_info *info, btf_error *err)
{
    return fit(band, NULL, w, h, opts, out, info, err);
}

btf_status btf__car_fit_complement(const double *band, const double *sub, int w, int h,
                                   const btf_car_fit_opts *opts, btf_car_band *out,
                                   btf_car_fit_info *info, btf_error *err)
{
    btf_status rc = fit(band, sub, w, h, opts, out, info, err);
    if ((int)rc != 1)
        return rc;
    /* No complement to fit: the difference band itself. */
    size_t n = (size_t)w * h;
    double *d = btf__alloc(n, sizeof(double), err);
    if (!d)
        return BTF_E_NOMEM;
    for (size_t i = 0; i < n; i++)
        d[i] = band[i] - sub[i];
    rc = fit(d, NULL, w, h, opts, out, info, err);
    free(d);
    return rc;
}
