/*
 * stability.c — stability and stationary variance of a CAR band (paper
 * section II.C: the model must be a stable recursion for synthesis to give
 * a stationary field).
 *
 * The recursion synthesis runs (synth/field.c, rows.c) is
 *     X(r, c) = sum_s gamma_s X(r + r_s, c + c_s) + sigma e(r, c),
 * rows top to bottom, each row left to right, the offsets on the
 * non-symmetric half-plane (r_s < 0, or r_s = 0 and c_s < 0). With
 * A(u, v) = 1 - sum_s gamma_s u^{c_s} v^{r_s} (u the column variable, v the
 * row variable) it is the filter 1/A, and the classical NSHP theorem
 * (Ekstrom & Woods 1976, "Two-dimensional spectral factorization with
 * applications in recursive digital filtering", IEEE Trans. ASSP 24(2);
 * DeCarlo, Murray & Saeks 1977 and Strintzis 1977 for the root-map form)
 * says it is stable iff
 *   (b) the row polynomial A(u, infinity) = 1 - sum_{r_s = 0} gamma_s u^{c_s}
 *       has no zero for |u| >= 1: the recursion along one row, given the rows
 *       above, does not grow; and
 *   (a) A(e^{iw}, v) has no zero for |v| >= 1 at every column frequency w:
 *       row after row, every frequency of a row decays. At frequency w the
 *       rows follow X_r B_0(w) = sum_{p >= 1} B_p(w) X_{r-p} + noise, with
 *       B_0(w) = A(e^{iw}, infinity) and B_p(w) = sum_{r_s = -p} gamma_s
 *       e^{i w c_s}: (a) says the roots lambda of lambda^P B_0 - sum_p B_p
 *       lambda^{P-p} (the eigenvalues of that row-to-row companion matrix)
 *       lie inside the unit circle, for every w.
 * The test here demands both with a margin: every root of the row's
 * characteristic polynomial and of every frequency's row-to-row polynomial
 * has modulus below RHO = 1 - BTF_CAR_STABILITY_MARGIN (why that margin:
 * car.h). For (b) that is the Schur-Cohn test of the row polynomial scaled
 * by RHO, exact for its degree of at most 64. For (a) the Schur-Cohn test
 * runs at a set of frequencies, and a bound covers the frequencies between
 * them: see down_rows_within below. A band that the bound cannot cover
 * within its work budget is too close to a root of modulus RHO to prove
 * stable, and counts as unstable.
 *
 * The stationary variance is sigma^2 times the mean of 1/|A|^2 over the
 * frequency torus.
 */
#include "core/core.h"
#include "car/car.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define RHO (1.0 - BTF_CAR_STABILITY_MARGIN)
/* Offsets reach at most 64 rows up and 64 columns either way (the
 * validator's limit, model/model_check.c): the polynomials' degrees. */
#define REACH 64
/* The work budget of the down-the-rows test per band, in nanoseconds of
 * one core as measured (a frequency's test costs 64 + 2 (n + reach) +
 * P (P + 16) of them, P the rows up). Within it a band of the fit's family
 * (3 rows up) is decided to within 5e-7 of the margin (measured on random
 * 24-term bands scaled to the edge); one of 64 rows up and 24 terms when
 * its roots stay below about 0.993. A model file of 6144 bands that all
 * exhaust it costs 25 s of CPU, spread over every core. */
#define WORK_BUDGET 4000000L

typedef struct cx {
    double re, im;
} cx;

static cx cmul(cx a, cx b)
{
    return (cx){a.re * b.re - a.im * b.im, a.re * b.im + a.im * b.re};
}

static double cabs2(cx a)
{
    return a.re * a.re + a.im * a.im;
}

/* Schur-Cohn step-down (the Levinson recursion run backwards) of the monic
 * complex polynomial p(z) = z^n + p[n-1] z^(n-1) + ... + p[0], destroyed on
 * the way. 1 when every root lies in the open unit disc, 0 otherwise
 * (Schur 1917, Cohn 1922; e.g. Marden, "Geometry of polynomials", ch. X).
 * One step with the reflection coefficient k = p[0]: |k| >= 1 means the
 * roots' product has modulus >= 1, so one lies outside or on the circle.
 * Else q = p - k p*, p*(z) = z^n conj(p(1 / conj z)), has q(0) = 0, and on
 * |z| = 1, where |p*| = |p| and |k p*| < |p|, it has (Rouche) as many roots
 * inside as p; p <- q / ((1 - |k|^2) z) is monic of degree n - 1. As
 * |q| <= (1 + |k|) |p| on the circle, |p_old| >= (1 - |k|) |p_new| there:
 * *floor gets prod (1 - |k|), a lower bound of |p| on the unit circle. */
static int schur_cohn(cx *p, int n, double *floor)
{
    double f = 1.0;
    cx t[REACH];
    for (int m = n; m > 0; m--) {
        cx k = p[0];
        double kk = cabs2(k);
        /* Within rounding of the circle counts as on it: unstable. */
        if (!(kk < 1.0 - 1e-12))
            return 0;
        double d = 1.0 - kk;
        for (int j = 1; j < m; j++) {
            cx c = {p[m - j].re, -p[m - j].im}, kc = cmul(k, c);
            t[j - 1] = (cx){(p[j].re - kc.re) / d, (p[j].im - kc.im) / d};
        }
        memcpy(p, t, (size_t)(m - 1) * sizeof *p);
        f *= 1.0 - sqrt(kk);
    }
    *floor = f;
    return 1;
}

/* (b) with the margin: the roots of the recursion along a row,
 * z^Q - sum_{r_s = 0} gamma_s z^(Q + c_s), all of modulus below RHO. That is
 * the Schur-Cohn test of the polynomial at RHO z, divided by RHO^Q: the
 * coefficient of z^(Q + c_s) becomes -gamma_s RHO^(c_s). */
static int along_row_within(const btf_car_band *b)
{
    cx p[REACH + 1] = {{0.0, 0.0}};
    int q = 0;
    for (int s = 0; s < b->n; s++)
        if (b->offsets[s].row == 0 && -b->offsets[s].col > q)
            q = -b->offsets[s].col;
    if (q == 0)
        return 1;
    for (int s = 0; s < b->n; s++)
        if (b->offsets[s].row == 0)
            p[q + b->offsets[s].col].re -= b->gamma[s] * pow(RHO, b->offsets[s].col);
    double floor;
    return schur_cohn(p, q, &floor);
}

/* A band's terms for the test down the rows: A_RHO(w, t) = 1 - sum_s g_s
 * e^{i (w c_s + t r_s)}, g_s = gamma_s RHO^(r_s), is A on |u| = 1,
 * |v| = RHO (a zero of it there is a root lambda of modulus RHO). With
 * c~_s = c_s + kappa r_s (the shear of choose_shear below), d1[p] and
 * d2[p] are sum |g_s| |c~_s| and sum |g_s| c~_s^2 over the terms p rows
 * up (p = 0: the row's own terms): they bound the derivatives in w of the
 * coefficients. lip = sum_p d1[p]. */
typedef struct terms {
    int n, rows, reach; /* rows: P, the most rows up; reach: max |c_s| */
    int row[BTF_CAR_MAX_NEIGHBOURS], col[BTF_CAR_MAX_NEIGHBOURS];
    double g[BTF_CAR_MAX_NEIGHBOURS];
    double kappa, lip, d1[REACH + 1], d2[REACH + 1];
} terms;

/* For every kappa, min_t |A_RHO(w, t)| = min_t |A_RHO(w, t + kappa w)| (a
 * shift of the period in t), and |d/dw A_RHO(w, t + kappa w)| <= sum_s
 * |g_s| |c_s + kappa r_s|: the kappa that makes that bound least, one of
 * the 0 = c_s + kappa r_s (a convex piecewise linear function's corners)
 * or 0. A band whose rows repeat diagonally (one neighbour -1:-1) so has a
 * bound of 0 along the diagonal. */
static double choose_shear(const terms *t)
{
    double best = INFINITY, kappa = 0.0;
    for (int j = -1; j < t->n; j++) {
        if (j >= 0 && t->row[j] == 0)
            continue;
        double k = j < 0 ? 0.0 : -(double)t->col[j] / t->row[j], l = 0.0;
        for (int s = 0; s < t->n; s++)
            l += fabs(t->g[s]) * fabs(t->col[s] + k * t->row[s]);
        if (l < best)
            best = l, kappa = k;
    }
    return kappa;
}

static void band_terms(const btf_car_band *b, terms *t)
{
    memset(t, 0, sizeof *t);
    t->n = b->n;
    for (int s = 0; s < b->n; s++) {
        t->row[s] = b->offsets[s].row;
        t->col[s] = b->offsets[s].col;
        t->g[s] = b->gamma[s] * pow(RHO, b->offsets[s].row);
        if (-t->row[s] > t->rows)
            t->rows = -t->row[s];
        if (abs(t->col[s]) > t->reach)
            t->reach = abs(t->col[s]);
    }
    t->kappa = choose_shear(t);
    for (int s = 0; s < t->n; s++) {
        double c = fabs(t->col[s] + t->kappa * t->row[s]), g = fabs(t->g[s]);
        t->d1[-t->row[s]] += g * c;
        t->d2[-t->row[s]] += g * c * c;
        t->lip += g * c;
    }
}

/* One frequency w: |C_0|, and for every p >= 1 |C_p| and |N_p|, N_p =
 * C~_p' C_0 - C~_p C_0' (C~_p = C_p e^{-i kappa w p}, the sheared
 * coefficient; ' is d/dw), and the Schur-Cohn floor of the monic
 * polynomial. */
typedef struct frequency {
    double c0, floor, cp[REACH + 1], np[REACH + 1];
} frequency;

/* At column frequency w: the row-to-row polynomial of roots zeta = lambda /
 * RHO, U(zeta) = C_0 zeta^P - sum_{p >= 1} C_p zeta^(P - p), C_0 = B_0(w),
 * C_p = RHO^-p B_p(w), made monic by C_0 (not 0 once (b) holds). On
 * |zeta| = 1, |U(e^{it})| = |A_RHO(w, t)|. 1 when every root has |zeta| <
 * 1, with f filled in: f->floor <= |U / C_0| on the circle. */
static int frequency_within(const terms *t, double w, frequency *f)
{
    cx e[REACH + 1], c[REACH + 1], d[REACH + 1], p[REACH];
    e[0] = (cx){1.0, 0.0};
    if (t->reach > 0)
        e[1] = (cx){cos(w), sin(w)};
    for (int k = 2; k <= t->reach; k++)
        e[k] = cmul(e[k - 1], e[1]);
    for (int k = 0; k <= t->rows; k++)
        c[k] = d[k] = (cx){0.0, 0.0};
    c[0].re = 1.0;
    for (int s = 0; s < t->n; s++) {
        int col = t->col[s], up = -t->row[s];
        cx ph = col >= 0 ? e[col] : (cx){e[-col].re, -e[-col].im};
        /* C_0 = 1 - sum, C_p = +sum; the derivative brings i c~_s */
        double g = up == 0 ? -t->g[s] : t->g[s], ct = col + t->kappa * t->row[s];
        c[up].re += g * ph.re, c[up].im += g * ph.im;
        d[up].re -= g * ct * ph.im, d[up].im += g * ct * ph.re;
    }
    double c0 = cabs2(c[0]);
    if (!(c0 > 0.0))
        return 0;
    f->c0 = sqrt(c0);
    cx inv = {c[0].re / c0, -c[0].im / c0};
    for (int k = 1; k <= t->rows; k++) { /* coefficient of zeta^(P - k) */
        cx v = cmul(c[k], inv), a = cmul(d[k], c[0]), b = cmul(c[k], d[0]);
        p[t->rows - k] = (cx){-v.re, -v.im};
        f->cp[k] = sqrt(cabs2(c[k]));
        f->np[k] = sqrt(cabs2((cx){a.re - b.re, a.im - b.im}));
    }
    return schur_cohn(p, t->rows, &f->floor);
}

/* Whether [w - h, w + h] keeps every root inside by the monic polynomial's
 * bound: there |C_0| lies within c0 -+ h d1[0], the monic coefficients R_p =
 * C~_p / C_0 have |R_p'| = |N_p| / |C_0|^2 with |N_p'| = |C~_p'' C_0 - C~_p
 * C_0''| <= d2[p] |C_0| + |C~_p| d2[0], so sum_p |R_p(w') - R_p(w)| <= h
 * sum_p sup |R_p'|; below floor, no root reaches the circle (Rouche). */
static int monic_holds(const terms *t, const frequency *f, double h, double slack)
{
    double lo = f->c0 - h * t->d1[0], hi = f->c0 + h * t->d1[0], sum = 0.0;
    if (!(lo > 0.0))
        return 0;
    for (int p = 1; p <= t->rows; p++)
        sum += f->np[p] + h * (t->d2[p] * hi + (f->cp[p] + h * t->d1[p]) * t->d2[0]);
    return h * sum / (lo * lo) + slack / f->c0 < f->floor;
}

/* The half-width of the interval around w that f proves, the larger of
 * two bounds: |A_RHO| itself, at least c0 floor at w and changing by at
 * most lip per radian (its sheared form), and the monic polynomial's
 * (monic_holds), which is far longer where C_0 and the C_p share a small
 * factor: a band nearly unstable along its rows as well as down them, as
 * smooth bands are, whose |A_RHO| is small near w = 0 although its roots
 * are not near the margin. guess: where to start looking (the last
 * interval's half-width); the bound found is within 1/16 of the best. */
static double proven_half_width(const terms *t, const frequency *f, double slack, double guess)
{
    double direct = t->lip > 0.0 ? (f->c0 * f->floor - slack) / t->lip : INFINITY;
    double cap = t->d1[0] > 0.0 ? f->c0 / t->d1[0] : 2.0 * M_PI;
    double h = guess > 0.0 && 4.0 * guess < cap ? 4.0 * guess : cap;
    while (h > 1e-15 && !monic_holds(t, f, h, slack))
        h *= 0.5;
    if (!(h > 1e-15))
        h = 0.0;
    for (double step = 0.5 * h; step > h / 16.0 && h > 0.0; step *= 0.5)
        if (h + step < cap && monic_holds(t, f, h + step, slack))
            h += step;
    return direct > h ? direct : h;
}

/* Where to test a piece [a, z] next to a proven interval of half-width g
 * (on its left when side > 0, on its right when side < 0; side 0: none):
 * 0.9 g into it, where the next interval likely reaches back to the proven
 * one (min_t |A_RHO| changes slowly), but at least a quarter and at most
 * half of the piece, so that pieces shrink geometrically. */
static double test_point(double a, double z, double g, int side)
{
    double width = z - a, step = 0.9 * g;
    if (side == 0)
        return 0.5 * (a + z);
    step = step < 0.25 * width ? 0.25 * width : step > 0.5 * width ? 0.5 * width : step;
    return side > 0 ? a + step : z - step;
}

/* (a) with the margin, once (b) holds, so that C_0(w) != 0 and the roots
 * move continuously with w: every root of every frequency's row-to-row
 * polynomial inside |zeta| < 1. A frequency w where the Schur-Cohn test
 * holds proves an interval [w - h, w + h] (proven_half_width): no root
 * reaches |zeta| = 1 within it, so the roots stay inside (the argument of
 * DeCarlo, Murray & Saeks 1977: a root that leaves must cross the circle).
 * The circle [0, 2 pi] is covered piece by piece: a piece not yet proven
 * is tested (test_point), and what is left of it on either side becomes
 * two pieces. Every test lies at least a quarter into its piece, so a
 * frequency with a root outside is reached within a few dozen tests of its
 * neighbourhood. 1: proven; 0: a frequency has a root outside (*w_bad gets
 * it); -1: not proven within the work budget, or at a frequency whose
 * bound is not positive (the band is within rounding of a root on the
 * margin). */
static int down_rows_within(const btf_car_band *b, double *w_bad)
{
    terms t;
    band_terms(b, &t);
    if (t.rows == 0)
        return 1; /* no rows above: A_RHO(w, t) = C_0(w) != 0 by (b) */
    double mag = 1.0;
    for (int s = 0; s < t.n; s++)
        mag += fabs(t.g[s]);
    /* Rounding of C_p and of the step-down: far below 1e-12 of the terms. */
    double slack = 1e-12 * mag;
    long cost = 64 + 2 * (t.n + t.reach) + (long)t.rows * (t.rows + 16), work = 0;
    /* Depth first, a piece at most 3/4 of its parent: 128 levels reach 1e-15. */
    enum { STACK = 160 };
    double lo[STACK], hi[STACK], guess[STACK];
    signed char side[STACK];
    int top = 0;
    lo[0] = 0.0, hi[0] = 2.0 * M_PI, guess[0] = 0.0, side[0] = 0, top = 1;
    while (top > 0) {
        top--;
        double a = lo[top], z = hi[top], g = guess[top], w = test_point(a, z, g, side[top]);
        frequency f;
        if ((work += cost) > WORK_BUDGET || z - a < 1e-12 || top + 2 > STACK)
            return -1;
        if (!frequency_within(&t, w, &f)) {
            *w_bad = w;
            return 0;
        }
        double h = proven_half_width(&t, &f, slack, g);
        if (!(h > 0.0))
            return -1;
        if (w - h > a)
            lo[top] = a, hi[top] = w - h, guess[top] = h, side[top++] = -1;
        if (w + h < z)
            lo[top] = w + h, hi[top] = z, guess[top] = h, side[top++] = 1;
    }
    return 1;
}

/* sum_s |gamma_s| RHO^-d_s < 1, d_s the rows up (or, on the row, the
 * columns left) of offset s, is enough: for a root lambda of (a) or (b)
 * with |lambda| >= RHO, 1 = |sum_s gamma_s ... lambda^-d_s| would be below
 * 1. Most fitted bands pass here. */
static int sum_within(const btf_car_band *b)
{
    double sum = 0.0;
    for (int s = 0; s < b->n; s++) {
        int d = b->offsets[s].row < 0 ? -b->offsets[s].row : -b->offsets[s].col;
        sum += fabs(b->gamma[s]) * pow(RHO, -d);
    }
    return sum < 1.0;
}

/* A recursion at all: at most BTF_CAR_MAX_NEIGHBOURS causal offsets within
 * REACH pixels, finite coefficients (the validator says which rule a file
 * breaks before it asks for stability; btf__car_is_stable, which the tests
 * call directly, may get anything). */
static int band_valid(const btf_car_band *b, char *why, size_t n)
{
    if (b->n < 0 || b->n > BTF_CAR_MAX_NEIGHBOURS) {
        snprintf(why, n, "%d neighbours (expected 0..%d)", b->n, BTF_CAR_MAX_NEIGHBOURS);
        return 0;
    }
    for (int s = 0; s < b->n; s++) {
        btf_offset o = b->offsets[s];
        if (!btf__offset_is_causal(o) || o.row < -REACH || o.col < -REACH || o.col > REACH) {
            snprintf(why, n, "offset %d:%d is not a causal offset within %d pixels", o.row, o.col,
                     REACH);
            return 0;
        }
        if (!isfinite(b->gamma[s])) {
            snprintf(why, n, "gamma[%d] is %g", s, b->gamma[s]);
            return 0;
        }
    }
    return 1;
}

int btf__car_stability_why(const btf_car_band *b, char *why, size_t n)
{
    char dummy[1];
    if (!why)
        why = dummy, n = sizeof dummy;
    if (!band_valid(b, why, n))
        return 0;
    if (sum_within(b))
        return 1;
    if (!along_row_within(b)) {
        snprintf(why, n, "its recursion along a row has a root of modulus 1 - %g or more",
                 BTF_CAR_STABILITY_MARGIN);
        return 0;
    }
    double w = 0.0;
    int down = down_rows_within(b, &w);
    if (w > M_PI)
        w -= 2.0 * M_PI; /* reported in (-pi, pi] */
    if (down == 0)
        snprintf(why, n, "its rows do not decay: at column frequency %.3g pi the row-to-row "
                 "recursion has a root of modulus 1 - %g or more", w / M_PI,
                 BTF_CAR_STABILITY_MARGIN);
    else if (down < 0)
        snprintf(why, n, "its recursion down the rows is too near a root of modulus 1 - %g to "
                 "prove stable", BTF_CAR_STABILITY_MARGIN);
    return down == 1;
}

int btf__car_is_stable(const btf_car_band *b)
{
    return btf__car_stability_why(b, NULL, 0);
}

/* |A(w1, w2)|^2 on an n x n grid of the frequency torus: the mean of its
 * inverse (the stationary variance for unit noise). */
static double spectrum_mean_inverse(const btf_car_band *b, int n)
{
    double acc = 0.0;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            double w1 = 2.0 * M_PI * i / n;
            double w2 = 2.0 * M_PI * j / n;
            double re = 1.0, im = 0.0;
            for (int s = 0; s < b->n; s++) {
                double ph = w1 * b->offsets[s].row + w2 * b->offsets[s].col;
                re -= b->gamma[s] * cos(ph);
                im += b->gamma[s] * sin(ph);
            }
            double a2 = re * re + im * im;
            acc += a2 > 1e-300 ? 1.0 / a2 : 1e300;
        }
    return acc / ((double)n * n);
}

double btf__car_stationary_variance(const btf_car_band *b)
{
    return (double)b->sigma * b->sigma * spectrum_mean_inverse(b, 256);
}

double btf__car_synth_variance(const btf_car_band *b, int margin)
{
    /* The field synthesis runs (synth/field.c): zeros outside, the window
     * starting `margin` rows below the top and `margin` columns in from
     * either side; the window is its first WIN x WIN pixels. */
    enum { WIN = 64, P = 64 };
    if (margin < 0)
        margin = 0;
    for (int k = 0; k < b->n; k++)
        if (b->offsets[k].row < -P || b->offsets[k].col < -P || b->offsets[k].col > P)
            return -1.0;
    int rows = margin + WIN, cols = 2 * margin + WIN, w = cols + 2 * P;
    double *pad = calloc((size_t)(rows + P) * (size_t)w, sizeof(double));
    if (!pad)
        return -1.0;
    long rel[BTF_CAR_MAX_NEIGHBOURS];
    for (int k = 0; k < b->n; k++)
        rel[k] = (long)b->offsets[k].row * w + b->offsets[k].col;
    btf_rng rng;
    btf__rng_seed(&rng, 271828);
    double sum = 0.0, sq = 0.0, sigma = b->sigma;
    for (int y = 0; y < rows; y++) {
        double *row = pad + (size_t)(y + P) * w + P;
        for (int x = 0; x < cols; x++) {
            double s = 0.0;
            for (int k = 0; k < b->n; k++)
                s += b->gamma[k] * row[x + rel[k]];
            row[x] = s + sigma * (btf__rng_uniform(&rng) - 0.5) * 3.4641016151377544;
            if (y >= margin && x >= margin && x < margin + WIN) {
                sum += row[x];
                sq += row[x] * row[x];
            }
        }
    }
    free(pad);
    double n = (double)WIN * WIN, mean = sum / n, v = sq / n - mean * mean;
    return isfinite(v) && v > 0.0 ? v : 0.0;
}
