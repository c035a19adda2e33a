/*
 * photostereo.c — normals and albedo per pixel from images of one view under
 * N >= 3 known lights: robust Lambertian photometric stereo (Woodham 1980,
 * "Photometric method for determining surface orientation from multiple
 * images"), the range-map stage of Haindl & Filip 2007, section II.B.
 *
 * Model. A Lambertian pixel lit by the unit light l_i shows I_i = rho n.l_i =
 * g.l_i with g = rho n, so three or more lights determine g by least squares,
 * g = (sum l l^T)^-1 sum I_i l_i, and then rho = |g|, n = g / |g|. The fit is
 * made on one grey value per sample (the mean of its channels, each divided
 * by that image's light intensity), in double precision; the albedo of every
 * channel is then the least-squares rho_c with the normal fixed,
 * rho_c = sum I_ic n.l_i / sum (n.l_i)^2 over the samples the fit kept.
 *
 * Real samples break the model: cast and attached shadows are too dark,
 * specular highlights too bright, clipped values wrong. The robust rule,
 * per pixel (docs/photostereo.md, where the choices are measured):
 *  1. saturated samples (any raw channel >= saturation) and samples <= 0 are
 *     excluded;
 *  2. shadows: the reference level is the pixel's brightest value after
 *     the top 5 % (a few highlights); samples below dark x reference are
 *     shadowed, and so are those below a jump of 3x between consecutive
 *     sorted values (the shadow gap: shadows lit by ambient light form a
 *     cluster that can outnumber the lit samples of a pixel in a crevice);
 *     both exclusions are for good;
 *  3. a first fit uses the remaining samples between their trim_low and
 *     (1 - trim_high) quantiles (a trimmed least squares: highlights are
 *     among the brightest);
 *  4. reweighting, at most `iterations` times, until the set stops changing:
 *     with the robust scale s = 1.4826 median |r| over the current set
 *     (r: deleted residuals, which a single high-leverage outlier cannot
 *     hide; s at least 2 % of the albedo, so that perfect data does not make
 *     every sample an outlier), a sample is kept when the fit predicts it lit
 *     (g.l > 0), it is at most outlier x s below the fit (shadows only
 *     darken: partial shadows go), at most 2 outlier x s above it, and it is
 *     not a highlight: brighter than the fit by more than s with its half
 *     vector (of the light and the view (0, 0, 1)) within specular_cone of
 *     the normal. Samples may come back.
 * Every fit needs at least 3 samples whose sum l l^T has a condition number
 * <= max_condition (the lights are not nearly coplanar); a reweighting step
 * that would break this is not taken.
 *
 * Fallback. A pixel whose first fit has fewer than 3 good samples, or whose
 * good lights are nearly coplanar, gets the normal (0, 0, 1) (facing the
 * camera: zero slope, so the integrated height just bridges it) and the
 * albedo that normal explains best from its unsaturated positive samples
 * (from its saturated ones, a lower bound, if it has nothing else); it is
 * marked invalid (valid = 0, lights_used = 0). All-dark pixels thus get
 * albedo 0. The whole light set must be well conditioned, else the call
 * fails with a message naming the direction the lights cannot resolve.
 *
 * Memory and streaming. The grey values of all samples (N floats per pixel)
 * are kept; images are read one at a time (files are decoded twice: once
 * for the grey values, once more for the colour albedo), so a dataset never
 * has all its images in memory. Rows are solved by a pool of threads; each
 * pixel is independent, so the result does not depend on the thread count.
 */
#include <stdio.h>
#include "io/io.h"
#include "core/core.h"

#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define PS_PI 3.14159265358979323846
#define DEF_DARK 0.1
#define DEF_TRIM_HIGH 0.1
#define DEF_OUTLIER 2.0
#define DEF_SATURATION 0.99
#define DEF_MAX_CONDITION 1e4
#define DEF_ITERATIONS 5
#define DEF_SPECULAR_CONE 20.0 /* degrees between the half vector and the normal */
#define REF_QUANTILE 0.95     /* the reference level: the brightest after the top 5 % */
#define SCALE_FLOOR 0.02      /* robust scale floor, fraction of the albedo */
#define SHADOW_GAP 3.0        /* a jump between sorted values that splits off shadows */
#define MAD_TO_SIGMA 1.4826   /* median |r| -> standard deviation for Gaussian r */
#define MAX_THREADS 64
#define ROWS_PER_TASK 8

/* ---------------------------------------------------------------- options */

typedef struct ps_params {
    double dark, trim_low, trim_high, outlier, saturation, max_cond;
    double cone_cos;          /* cos of the specular cone; > 1: no cone rule */
    int iterations, plain;
} ps_params;

static int resolve_opts(const btf_photostereo_opts *o, ps_params *p, btf_error *err)
{
    if (!isfinite(o->dark) || o->dark >= 1.0 || !isfinite(o->trim_low) || o->trim_low < 0.0 ||
        !isfinite(o->trim_high) || o->trim_high >= 1.0)
        return btf_fail(err, BTF_E_ARG,
                        "photostereo: dark %g, trim_low %g, trim_high %g: expected dark < 1, "
                        "trim_low in [0, 1), trim_high < 1",
                        o->dark, o->trim_low, o->trim_high);
    p->dark = o->dark == 0.0 ? DEF_DARK : o->dark < 0.0 ? 0.0 : o->dark;
    p->trim_low = o->trim_low;
    p->trim_high = o->trim_high == 0.0 ? DEF_TRIM_HIGH : o->trim_high < 0.0 ? 0.0 : o->trim_high;
    if (p->trim_low + p->trim_high >= 1.0)
        return btf_fail(err, BTF_E_ARG, "photostereo: trim_low %g + trim_high %g leave no samples",
                        p->trim_low, p->trim_high);
    if (!(o->outlier >= 0.0) || !isfinite(o->outlier))
        return btf_fail(err, BTF_E_ARG, "photostereo: outlier %g: expected a finite value >= 0",
                        o->outlier);
    p->outlier = o->outlier == 0.0 ? DEF_OUTLIER : o->outlier;
    if (isnan(o->saturation))
        return btf_fail(err, BTF_E_ARG, "photostereo: saturation is NaN");
    p->saturation = o->saturation == 0.0 ? DEF_SATURATION
                    : o->saturation < 0.0 ? INFINITY : o->saturation;
    if (!(o->max_condition == 0.0 || (o->max_condition >= 1.0 && isfinite(o->max_condition))))
        return btf_fail(err, BTF_E_ARG, "photostereo: max_condition %g: expected 0 or >= 1",
                        o->max_condition);
    p->max_cond = o->max_condition == 0.0 ? DEF_MAX_CONDITION : o->max_condition;
    if (!isfinite(o->specular_cone) || o->specular_cone >= 90.0)
        return btf_fail(err, BTF_E_ARG, "photostereo: specular_cone %g: expected < 90 degrees",
                        o->specular_cone);
    p->cone_cos = o->specular_cone < 0.0 ? 2.0
                  : cos((o->specular_cone == 0.0 ? DEF_SPECULAR_CONE : o->specular_cone) *
                        (PS_PI / 180.0));
    p->iterations = o->iterations == 0 ? DEF_ITERATIONS : o->iterations < 0 ? 0 : o->iterations;
    p->plain = o->plain != 0;
    if (o->threads < 0)
        return btf_fail(err, BTF_E_ARG, "photostereo: threads %d: expected >= 0", o->threads);
    return BTF_OK;
}

/* ---------------------------------------------------------- 3x3 algebra */

/* A symmetric 3x3 matrix as a00, a11, a22, a01, a02, a12. */
typedef struct sym3 {
    double a00, a11, a22, a01, a02, a12;
} sym3;

/* Eigenvalues, descending (closed form for symmetric 3x3 matrices, Smith
 * 1961): cheap enough to check every pixel's conditioning. */
static void sym3_eig(const sym3 *m, double ev[3])
{
    double p1 = m->a01 * m->a01 + m->a02 * m->a02 + m->a12 * m->a12;
    double q = (m->a00 + m->a11 + m->a22) / 3.0;
    double d0 = m->a00 - q, d1 = m->a11 - q, d2 = m->a22 - q;
    double p2 = d0 * d0 + d1 * d1 + d2 * d2 + 2.0 * p1;
    if (!(p2 > 0.0)) {
        ev[0] = ev[1] = ev[2] = q;
        return;
    }
    double p = sqrt(p2 / 6.0);
    /* det((A - qI) / p) / 2 */
    double b00 = d0 / p, b11 = d1 / p, b22 = d2 / p;
    double b01 = m->a01 / p, b02 = m->a02 / p, b12 = m->a12 / p;
    double det = b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02) +
                 b02 * (b01 * b12 - b11 * b02);
    double r = det / 2.0;
    r = r < -1.0 ? -1.0 : r > 1.0 ? 1.0 : r;
    double phi = acos(r) / 3.0;
    ev[0] = q + 2.0 * p * cos(phi);
    ev[2] = q + 2.0 * p * cos(phi + 2.0 * PS_PI / 3.0);
    ev[1] = 3.0 * q - ev[0] - ev[2];
}

/* Condition number lambda_max / lambda_min; infinity when singular. */
static double sym3_condition(const sym3 *m)
{
    double ev[3];
    sym3_eig(m, ev);
    if (!(ev[2] > 0.0) || !isfinite(ev[0]))
        return INFINITY;
    return ev[0] / ev[2];
}

/* The unit eigenvector of the smallest eigenvalue (the direction the lights
 * resolve worst): the cross product of two rows of A - lambda I. */
static void sym3_weak_axis(const sym3 *m, double v[3])
{
    double ev[3];
    sym3_eig(m, ev);
    double l = ev[2];
    double r[3][3] = {{m->a00 - l, m->a01, m->a02},
                      {m->a01, m->a11 - l, m->a12},
                      {m->a02, m->a12, m->a22 - l}};
    double best = -1.0;
    v[0] = 0.0, v[1] = 0.0, v[2] = 1.0;
    for (int i = 0; i < 3; i++) {
        const double *a = r[i], *b = r[(i + 1) % 3];
        double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                       a[0] * b[1] - a[1] * b[0]};
        double n = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        if (n > best && n > 0.0) {
            best = n;
            v[0] = c[0] / n, v[1] = c[1] / n, v[2] = c[2] / n;
        }
    }
}

/* Solves A g = b after checking A's conditioning; 0 when rejected. inv
 * (may be NULL) receives A^-1. */
static int sym3_solve(const sym3 *m, const double b[3], double max_cond, double g[3], sym3 *inv)
{
    double c00 = m->a11 * m->a22 - m->a12 * m->a12;
    double c01 = m->a02 * m->a12 - m->a01 * m->a22;
    double c02 = m->a01 * m->a12 - m->a02 * m->a11;
    double c11 = m->a00 * m->a22 - m->a02 * m->a02;
    double c12 = m->a01 * m->a02 - m->a00 * m->a12;
    double c22 = m->a00 * m->a11 - m->a01 * m->a01;
    double det = m->a00 * c00 + m->a01 * c01 + m->a02 * c02;
    if (!(det > 0.0) || !isfinite(det))
        return 0;
    /* For a positive definite A, lambda_min >= det / lambda_max^2, so the
     * condition number is at most trace^3 / det: when that bound passes,
     * the eigenvalues need not be computed (most pixels). */
    double tr = m->a00 + m->a11 + m->a22;
    if (!(tr * tr * tr <= max_cond * det) && !(sym3_condition(m) <= max_cond))
        return 0;
    g[0] = (c00 * b[0] + c01 * b[1] + c02 * b[2]) / det;
    g[1] = (c01 * b[0] + c11 * b[1] + c12 * b[2]) / det;
    g[2] = (c02 * b[0] + c12 * b[1] + c22 * b[2]) / det;
    if (inv) {
        inv->a00 = c00 / det, inv->a11 = c11 / det, inv->a22 = c22 / det;
        inv->a01 = c01 / det, inv->a02 = c02 / det, inv->a12 = c12 / det;
    }
    return isfinite(g[0]) && isfinite(g[1]) && isfinite(g[2]);
}

static void sym3_add(sym3 *m, const double *l)
{
    m->a00 += l[0] * l[0];
    m->a11 += l[1] * l[1];
    m->a22 += l[2] * l[2];
    m->a01 += l[0] * l[1];
    m->a02 += l[0] * l[2];
    m->a12 += l[1] * l[2];
}

/* ------------------------------------------------------------- selection */

/* The k-th smallest of a[0..n-1] (0-based); reorders a. Quickselect: the
 * per-pixel quantiles cost O(N), not a sort. */
static double select_kth(double *a, int n, int k)
{
    int lo = 0, hi = n - 1;
    while (lo < hi) {
        double pivot = a[lo + (hi - lo) / 2];
        int i = lo, j = hi;
        while (i <= j) {
            while (a[i] < pivot)
                i++;
            while (a[j] > pivot)
                j--;
            if (i <= j) {
                double t = a[i];
                a[i] = a[j];
                a[j] = t;
                i++;
                j--;
            }
        }
        if (k <= j)
            hi = j;
        else if (k >= i)
            lo = i;
        else
            break;
    }
    return a[k];
}

/* Sorts a[0..n-1] ascending (Shell's gaps: n is small, no allocation). */
static void sort_values(double *a, int n)
{
    static const int gaps[] = {57, 23, 10, 4, 1};
    for (int g = 0; g < 5; g++) {
        int h = gaps[g];
        for (int i = h; i < n; i++) {
            double t = a[i];
            int j = i;
            for (; j >= h && a[j - h] > t; j -= h)
                a[j] = a[j - h];
            a[j] = t;
        }
    }
}

/* The shadow gap. In a pixel that most lights reach only through cast
 * shadow, the shadowed samples (lit by ambient or interreflected light) form
 * a dark cluster that can outnumber the lit samples and sit above dark x ref.
 * Such a cluster is separated from the lit values by a jump: in the sorted
 * values a, the largest ratio a[i+1] / a[i] with a[i+1] between dark_cut and
 * ref and at least 3 values from a[i+1] up. When it reaches SHADOW_GAP, the
 * values up to a[i] are shadows: returns a[i+1], else 0. Lit samples of a
 * Lambertian pixel vary smoothly with the light, so they show no such jump. */
static double shadow_gap(const double *a, int n, double ref, double dark_cut)
{
    double best = 0.0, cut = 0.0;
    for (int i = 0; i + 3 < n; i++) {
        if (a[i + 1] > ref || a[i + 1] < dark_cut || !(a[i] > 0.0))
            continue;
        double r = a[i + 1] / a[i];
        if (r > best) {
            best = r;
            cut = a[i + 1];
        }
    }
    return best >= SHADOW_GAP ? cut : 0.0;
}

/* ------------------------------------------------------- the pixel fit */

typedef struct ps_scratch {
    double *sel;              /* n */
    double *res;              /* n residuals */
    unsigned char *ok, *use, *next; /* n flags each */
    double *row;              /* width * n grey values of one row */
} ps_scratch;

/* Least squares over the flagged samples; 0 if < 3 or ill-conditioned.
 * inv receives (sum l l^T)^-1 for the leverages. */
static int fit_set(const double *L, int n, const double *v, const unsigned char *use,
                   double max_cond, double g[3], sym3 *inv)
{
    sym3 m = {0};
    double b[3] = {0, 0, 0};
    int count = 0;
    for (int i = 0; i < n; i++) {
        if (!use[i])
            continue;
        const double *l = L + 3 * i;
        sym3_add(&m, l);
        b[0] += v[i] * l[0];
        b[1] += v[i] * l[1];
        b[2] += v[i] * l[2];
        count++;
    }
    return count >= 3 && sym3_solve(&m, b, max_cond, g, inv);
}

static double quad_form(const sym3 *m, const double *l)
{
    return m->a00 * l[0] * l[0] + m->a11 * l[1] * l[1] + m->a22 * l[2] * l[2] +
           2.0 * (m->a01 * l[0] * l[1] + m->a02 * l[0] * l[2] + m->a12 * l[1] * l[2]);
}

/* Residuals of every sample against g into s->res; for the samples of the
 * fit, the deleted residual r / (1 - h), h = l^T A^-1 l the sample's
 * leverage: what the fit without that sample would predict. A single bad
 * sample of high leverage (a partly shadowed one amid the lights) pulls an
 * ordinary fit towards itself and hides its own residual; its deleted
 * residual does not. Returns the robust scale 1.4826 median |r| of the fit's
 * samples, at least SCALE_FLOOR x albedo. */
static double residuals(const double *L, int n, const double *v, const double g[3],
                        const sym3 *inv, ps_scratch *s)
{
    int m = 0;
    for (int i = 0; i < n; i++) {
        const double *l = L + 3 * i;
        double res = v[i] - (g[0] * l[0] + g[1] * l[1] + g[2] * l[2]);
        if (s->use[i]) {
            double h = quad_form(inv, l);
            if (h < 1.0 - 1e-6)
                res /= 1.0 - h;
            s->sel[m++] = fabs(res);
        }
        s->res[i] = res;
    }
    double rho = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    double sigma = m > 0 ? MAD_TO_SIGMA * select_kth(s->sel, m, m / 2) : 0.0;
    return sigma > SCALE_FLOOR * rho ? sigma : SCALE_FLOOR * rho;
}

/* One reweighting step: the samples consistent with g, into s->next (see
 * the header). Shadows only darken and highlights only brighten, so the
 * window is asymmetric: a sample more than outlier x s below the fit is
 * (partly) shadowed; one above it is a highlight when its half vector with
 * the view lies within the specular cone of the normal (and it exceeds the
 * fit by more than s), and an outlier anyway beyond 2 x outlier x s. A
 * sample the fit predicts unlit (g.l <= 0) carries no information. Returns
 * the number kept; *changed tells whether the set differs. */
static int reweight(const ps_params *P, const double *L, const double *H, int n,
                    const double *v, const double g[3], const sym3 *inv, ps_scratch *s,
                    int *changed)
{
    double sigma = residuals(L, n, v, g, inv, s);
    double rho = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    double below = P->outlier * sigma, above = 2.0 * P->outlier * sigma;
    double cone = P->cone_cos * rho;
    int kept = 0;
    *changed = 0;
    for (int i = 0; i < n; i++) {
        const double *l = L + 3 * i, *hv = H + 3 * i;
        double pred = g[0] * l[0] + g[1] * l[1] + g[2] * l[2], res = s->res[i];
        int highlight = res > sigma && g[0] * hv[0] + g[1] * hv[1] + g[2] * hv[2] > cone;
        unsigned char k = s->ok[i] && pred > 0.0 && res >= -below && res <= above && !highlight;
        s->next[i] = k;
        kept += k;
        *changed |= k != s->use[i];
    }
    return kept;
}

/* The first set: the candidates (unsaturated, > 0) that are not shadowed
 * (dark rule and shadow gap), less the trim fractions of the darkest and
 * brightest. s->sel holds the nc candidate values. Returns the number of
 * samples not shadowed (s->ok). */
static int first_set(const ps_params *P, int n, const double *v, int nc, ps_scratch *s)
{
    sort_values(s->sel, nc);
    double ref = s->sel[(int)floor(REF_QUANTILE * (nc - 1))];
    double dark_cut = P->dark * ref, gap = shadow_gap(s->sel, nc, ref, dark_cut);
    if (gap > dark_cut)
        dark_cut = gap;
    int first = 0;
    while (first < nc && s->sel[first] < dark_cut)
        first++;
    int nok = nc - first;
    if (nok < 3)
        return nok;
    /* The samples not shadowed are sel[first..nc-1], sorted. */
    double hi = s->sel[first + (int)floor((1.0 - P->trim_high) * (nok - 1))];
    double lo = s->sel[first + (int)ceil(P->trim_low * (nok - 1))];
    for (int i = 0; i < n; i++) {
        s->ok[i] = (unsigned char)(s->use[i] && v[i] >= dark_cut);
        s->use[i] = (unsigned char)(s->ok[i] && v[i] >= lo && v[i] <= hi);
    }
    return nok;
}

/* The robust fit of one pixel's samples v (negative: saturated). On return
 * s->use flags the samples of the final fit. 1: fitted; 0: fallback. */
static int fit_pixel(const ps_params *P, const double *L, const double *H, int n,
                     const double *v, ps_scratch *s, double g[3])
{
    sym3 inv;
    int nc = 0;
    for (int i = 0; i < n; i++) {
        int cand = P->plain ? v[i] >= 0.0 : v[i] > 0.0;
        s->use[i] = (unsigned char)cand;
        if (cand)
            s->sel[nc++] = v[i];
    }
    if (P->plain) /* a black pixel gives g = 0: the fallback, not a 0/0 normal */
        return fit_set(L, n, v, s->use, P->max_cond, g, &inv) &&
               g[0] * g[0] + g[1] * g[1] + g[2] * g[2] > 0.0;
    if (nc < 3 || first_set(P, n, v, nc, s) < 3)
        return 0;
    if (!fit_set(L, n, v, s->use, P->max_cond, g, &inv)) {
        /* Too few in the trimmed middle: every non-shadowed sample. */
        memcpy(s->use, s->ok, (size_t)n);
        if (!fit_set(L, n, v, s->use, P->max_cond, g, &inv))
            return 0;
    }
    for (int it = 0; it < P->iterations; it++) {
        int changed;
        int kept = reweight(P, L, H, n, v, g, &inv, s, &changed);
        double g2[3];
        sym3 inv2;
        if (!changed || kept < 3 || !fit_set(L, n, v, s->next, P->max_cond, g2, &inv2))
            break;
        memcpy(s->use, s->next, (size_t)n);
        memcpy(g, g2, sizeof g2);
        inv = inv2;
    }
    return g[0] * g[0] + g[1] * g[1] + g[2] * g[2] > 0.0;
}

/* The fallback's sample set for the albedo with the normal (0, 0, 1). */
static void fallback_set(const double *L, int n, const double *v, unsigned char *use)
{
    int any = 0;
    for (int i = 0; i < n; i++) {
        use[i] = (unsigned char)(v[i] > 0.0 && L[3 * i + 2] > 0.0);
        any |= use[i];
    }
    if (!any)
        for (int i = 0; i < n; i++)
            use[i] = (unsigned char)(v[i] < 0.0 && L[3 * i + 2] > 0.0);
}

/* ------------------------------------------------------------ the job */

typedef struct ps_job {
    int w, h, n, words;
    const double *L;          /* n x 3, unit */
    const double *H;          /* n x 3, unit half vectors of l and the view (0, 0, 1) */
    const float *grey;        /* n x (w h), image-major; < 0: saturated */
    const unsigned char *inside;
    ps_params prm;
    float *normal, *used, *valid;
    uint64_t *bits;           /* (w h) x words: samples of each pixel's fit */
    atomic_int next_task, rows_done, fitted, fallback;
} ps_job;

static void solve_row(ps_job *j, ps_scratch *s, int y)
{
    int w = j->w, n = j->n;
    size_t wh = (size_t)w * j->h, base = (size_t)y * w;
    /* Gather the row pixel-major: each image's row is contiguous. */
    for (int i = 0; i < n; i++) {
        const float *src = j->grey + (size_t)i * wh + base;
        for (int x = 0; x < w; x++)
            s->row[(size_t)x * n + i] = src[x];
    }
    int fitted = 0, fallback = 0;
    for (int x = 0; x < w; x++) {
        size_t k = base + (size_t)x;
        if (!j->inside[k])
            continue;
        const double *v = s->row + (size_t)x * n;
        double g[3] = {0, 0, 0};
        int ok = fit_pixel(&j->prm, j->L, j->H, n, v, s, g);
        float *nv = j->normal + 3 * k;
        if (ok) {
            double rho = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
            nv[0] = (float)(g[0] / rho);
            nv[1] = (float)(g[1] / rho);
            nv[2] = (float)(g[2] / rho);
            int cnt = 0;
            for (int i = 0; i < n; i++)
                cnt += s->use[i];
            j->used[k] = (float)cnt;
            j->valid[k] = 1.0f;
            fitted++;
        } else {
            fallback_set(j->L, n, v, s->use);
            nv[0] = nv[1] = 0.0f;
            nv[2] = 1.0f;
            fallback++;
        }
        uint64_t *b = j->bits + k * (size_t)j->words;
        for (int i = 0; i < n; i++)
            if (s->use[i])
                b[i >> 6] |= (uint64_t)1 << (i & 63);
    }
    atomic_fetch_add(&j->fitted, fitted);
    atomic_fetch_add(&j->fallback, fallback);
}

typedef struct ps_worker {
    ps_job *job;
    ps_scratch s;
    pthread_t thread;
} ps_worker;

/* Runs row tasks until none is left. Only the calling thread is given a
 * progress callback (the library's callbacks need not be thread-safe). */
static void run_tasks(ps_job *j, ps_scratch *s, btf_progress_fn progress, void *user,
                      double f0, double f1)
{
    int tasks = (j->h + ROWS_PER_TASK - 1) / ROWS_PER_TASK;
    for (;;) {
        int t = atomic_fetch_add(&j->next_task, 1);
        if (t >= tasks)
            break;
        int y0 = t * ROWS_PER_TASK, y1 = y0 + ROWS_PER_TASK < j->h ? y0 + ROWS_PER_TASK : j->h;
        for (int y = y0; y < y1; y++)
            solve_row(j, s, y);
        int done = atomic_fetch_add(&j->rows_done, y1 - y0) + (y1 - y0);
        if (progress)
            progress(user, f0 + (f1 - f0) * done / j->h, "fitting normals");
    }
}

static void *worker_main(void *p)
{
    ps_worker *wk = p;
    run_tasks(wk->job, &wk->s, NULL, NULL, 0.0, 0.0);
    return NULL;
}

static void scratch_free(ps_scratch *s)
{
    free(s->sel);
    free(s->res);
    free(s->ok);
    free(s->row);
    memset(s, 0, sizeof *s);
}

static int scratch_alloc(ps_scratch *s, int n, int w, btf_error *err)
{
    memset(s, 0, sizeof *s);
    s->sel = btf_alloc((size_t)n, sizeof(double), err);
    s->res = btf_alloc((size_t)n, sizeof(double), err);
    s->ok = btf_alloc((size_t)n, 3, err);
    s->row = btf_alloc((size_t)n * (size_t)w, sizeof(double), err);
    if (!s->sel || !s->res || !s->ok || !s->row) {
        scratch_free(s);
        return BTF_E_NOMEM;
    }
    s->use = s->ok + n;
    s->next = s->ok + 2 * n;
    return BTF_OK;
}

/* Solves every pixel with a pool of threads (the calling thread is one of
 * them and reports progress between its tasks). */
static int solve_all(ps_job *j, int threads, btf_progress_fn progress, void *user,
                     double f0, double f1, btf_error *err)
{
    if (threads <= 0)
        threads = btf_cpu_count();
    if (threads > MAX_THREADS)
        threads = MAX_THREADS;
    int tasks = (j->h + ROWS_PER_TASK - 1) / ROWS_PER_TASK;
    if (threads > tasks)
        threads = tasks;
    ps_worker *wk = btf_calloc((size_t)threads, sizeof *wk, err);
    if (!wk)
        return BTF_E_NOMEM;
    int rc = BTF_OK, made = 0;
    for (int t = 0; t < threads && rc == BTF_OK; t++) {
        wk[t].job = j;
        rc = scratch_alloc(&wk[t].s, j->n, j->w, err);
        made += rc == BTF_OK;
    }
    int started = 0;
    for (int t = 1; t < made && rc == BTF_OK; t++) {
        if (pthread_create(&wk[t].thread, NULL, worker_main, &wk[t]) != 0)
            break; /* fewer threads: the tasks still all get done */
        started = t;
    }
    if (rc == BTF_OK)
        run_tasks(j, &wk[0].s, progress, user, f0, f1);
    for (int t = 1; t <= started; t++)
        pthread_join(wk[t].thread, NULL);
    for (int t = 0; t < made; t++)
        scratch_free(&wk[t].s);
    free(wk);
    return rc;
}

/* ------------------------------------------------------------- sources */

/* Where the images come from: memory, or files decoded on demand. */
typedef struct ps_source {
    const char *name;          /* for messages: "photostereo", a manifest, a dataset */
    int count;
    const btf_image *images;   /* in memory, or NULL */
    const char *const *paths;  /* files otherwise */
    btf_read_opts read;
    int width, height, channels;
} ps_source;

/* Image i: a pointer into memory, or decoded into tmp (free it after). */
static int source_get(const ps_source *s, int i, btf_image *tmp, const btf_image **img,
                      btf_error *err)
{
    if (s->images) {
        *img = &s->images[i];
        return BTF_OK;
    }
    btf_read_opts ro = s->read;
    ro.channels = 3;
    int rc = btf_image_read(s->paths[i], &ro, tmp, err);
    if (rc)
        return rc;
    if (tmp->width != s->width || tmp->height != s->height) {
        rc = btf_fail(err, BTF_E_DATA, "%s: size %dx%d differs from the first image's %dx%d",
                      s->paths[i], tmp->width, tmp->height, s->width, s->height);
        btf_image_free(tmp);
        return rc;
    }
    *img = tmp;
    return BTF_OK;
}

static double channel_intensity(const double *E, int i, int c, int channels)
{
    if (!E)
        return 1.0;
    if (channels == 1)
        return (E[3 * i] + E[3 * i + 1] + E[3 * i + 2]) / 3.0;
    return E[3 * i + c];
}

/* A raw value as the model sees it: negatives (noise below black) and
 * non-finite values (only memory images can hold them) count as 0. */
static double clean(float v)
{
    return isfinite(v) && v > 0.0f ? (double)v : 0.0;
}

/* The grey sample of image i at every pixel: mean over channels of
 * value / intensity; saturated samples stored negated. */
static void grey_of(const btf_image *img, int i, const double *E, double sat,
                    const unsigned char *inside, float *out)
{
    size_t count = (size_t)img->width * img->height;
    int C = img->channels;
    double inv[3];
    for (int c = 0; c < C; c++)
        inv[c] = 1.0 / channel_intensity(E, i, c, C) / C;
    for (size_t k = 0; k < count; k++) {
        if (!inside[k]) {
            out[k] = 0.0f;
            continue;
        }
        const float *p = img->data + k * (size_t)C;
        double g = 0.0;
        int saturated = 0;
        for (int c = 0; c < C; c++) {
            saturated |= p[c] >= sat; /* NaN compares false */
            g += clean(p[c]) * inv[c];
        }
        float f = (float)g;
        if (!isfinite(f))
            f = FLT_MAX;
        if (saturated)
            f = -(f > FLT_MIN ? f : FLT_MIN);
        out[k] = f;
    }
}

/* Albedo accumulation of image i: for each pixel whose fit used sample i,
 * num_c += I_c n.l and den += (n.l)^2. */
static void albedo_add(const btf_image *img, int i, const double *E, const double *L,
                       const ps_job *j, double *num, double *den)
{
    size_t count = (size_t)img->width * img->height;
    int C = img->channels;
    double inv[3];
    for (int c = 0; c < C; c++)
        inv[c] = 1.0 / channel_intensity(E, i, c, C);
    const double *l = L + 3 * i;
    uint64_t bit = (uint64_t)1 << (i & 63);
    for (size_t k = 0; k < count; k++) {
        if (!(j->bits[k * (size_t)j->words + (size_t)(i >> 6)] & bit))
            continue;
        const float *nv = j->normal + 3 * k;
        double nl = nv[0] * l[0] + nv[1] * l[1] + nv[2] * l[2];
        if (!(nl > 0.0))
            continue;
        const float *p = img->data + k * (size_t)C;
        for (int c = 0; c < C; c++)
            num[k * (size_t)C + c] += clean(p[c]) * inv[c] * nl;
        den[k] += nl * nl;
    }
}

/* ---------------------------------------------------------- the driver */

static int check_lights(const char *name, const double *lights, const double *E, int n,
                        const ps_params *P, double *L, double *condition, btf_error *err)
{
    sym3 m = {0};
    for (int i = 0; i < n; i++) {
        const double *l = lights + 3 * i;
        double len = sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]);
        if (!isfinite(len) || !(len > 1e-12))
            return btf_fail(err, BTF_E_ARG, "%s: light %d (%g, %g, %g) is not a finite "
                            "non-zero vector", name, i, l[0], l[1], l[2]);
        for (int c = 0; c < 3; c++)
            L[3 * i + c] = l[c] / len;
        sym3_add(&m, L + 3 * i);
        if (E)
            for (int c = 0; c < 3; c++)
                if (!(E[3 * i + c] > 0.0) || !isfinite(E[3 * i + c]))
                    return btf_fail(err, BTF_E_ARG, "%s: light %d intensity (%g, %g, %g) "
                                    "must be finite and positive", name, i, E[3 * i], E[3 * i + 1],
                                    E[3 * i + 2]);
    }
    *condition = sym3_condition(&m);
    if (!(*condition <= P->max_cond)) {
        double ax[3];
        sym3_weak_axis(&m, ax);
        return btf_fail(err, BTF_E_DATA, "%s: the %d light directions are (nearly) "
                        "coplanar: condition number %.3g exceeds %g, so the normal is not "
                        "determined along (%.3f, %.3f, %.3f); use lights spread over more than "
                        "one plane", name, n, *condition, P->max_cond, ax[0], ax[1], ax[2]);
    }
    return BTF_OK;
}

/* The half vector of each light with the view, which is the camera axis
 * (0, 0, 1) in this frame; 0 for a light straight behind the surface. */
static void half_vectors(const double *L, int n, double *H)
{
    for (int i = 0; i < n; i++) {
        double h[3] = {L[3 * i], L[3 * i + 1], L[3 * i + 2] + 1.0};
        double len = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
        for (int c = 0; c < 3; c++)
            H[3 * i + c] = len > 1e-9 ? h[c] / len : 0.0;
    }
}

static void report(const btf_photostereo_opts *o, double f, const char *what)
{
    if (o->progress)
        o->progress(o->progress_user, f, what);
}

/* Pass 1: the grey values of every image. Files take the first two fifths
 * of the progress bar, memory none to speak of. */
static int pass_grey(const ps_source *src, const double *E, const ps_params *P,
                     const unsigned char *inside, float *grey, const btf_photostereo_opts *o,
                     btf_error *err)
{
    size_t wh = (size_t)src->width * src->height;
    for (int i = 0; i < src->count; i++) {
        btf_image tmp = {0};
        const btf_image *img;
        int rc = source_get(src, i, &tmp, &img, err);
        if (rc)
            return rc;
        grey_of(img, i, E, P->saturation, inside, grey + (size_t)i * wh);
        btf_image_free(&tmp);
        if (!src->images)
            report(o, 0.4 * (i + 1) / src->count, "reading images");
    }
    return BTF_OK;
}

/* Pass 2: the colour albedo with the normals fixed. */
static int pass_albedo(const ps_source *src, const double *E, const ps_job *j,
                       const unsigned char *inside, btf_image *albedo,
                       const btf_photostereo_opts *o, btf_error *err)
{
    size_t wh = (size_t)src->width * src->height;
    int C = src->channels;
    double *num = btf_calloc(wh * (size_t)(C + 1), sizeof(double), err);
    if (!num)
        return BTF_E_NOMEM;
    double *den = num + wh * (size_t)C;
    int rc = BTF_OK;
    for (int i = 0; i < src->count && rc == BTF_OK; i++) {
        btf_image tmp = {0};
        const btf_image *img;
        if ((rc = source_get(src, i, &tmp, &img, err)))
            break;
        albedo_add(img, i, E, j->L, j, num, den);
        btf_image_free(&tmp);
        if (!src->images)
            report(o, 0.5 + 0.4 * (i + 1) / src->count, "reading images (albedo)");
    }
    for (size_t k = 0; rc == BTF_OK && k < wh; k++) {
        for (int c = 0; c < C; c++) {
            double a = inside[k] && den[k] > 0.0 ? num[k * C + c] / den[k] : 0.0;
            float f = (float)a;
            albedo->data[k * C + c] = isfinite(f) ? f : FLT_MAX;
        }
    }
    free(num);
    return rc;
}

void btf_ps_result_free(btf_ps_result *r)
{
    if (!r)
        return;
    btf_image_free(&r->normal);
    btf_image_free(&r->albedo);
    btf_image_free(&r->height);
    btf_image_free(&r->lights_used);
    btf_image_free(&r->valid);
    memset(r, 0, sizeof *r);
    r->view = -1;
}

static int alloc_result(btf_ps_result *r, int w, int h, int C, btf_error *err)
{
    int rc;
    if ((rc = btf_image_alloc(&r->normal, w, h, 3, err)) ||
        (rc = btf_image_alloc(&r->albedo, w, h, C, err)) ||
        (rc = btf_image_alloc(&r->lights_used, w, h, 1, err)) ||
        (rc = btf_image_alloc(&r->valid, w, h, 1, err)))
        return rc;
    return BTF_OK;
}

static int mask_inside(const char *name, const btf_image *mask, int w, int h,
                       unsigned char *inside, int *pixels, btf_error *err)
{
    size_t wh = (size_t)w * h;
    if (mask && (!mask->data || mask->width != w || mask->height != h ||
                 (mask->channels != 1 && mask->channels != 3)))
        return btf_fail(err, BTF_E_ARG, "%s: the mask (%dx%d, %d channels) does not fit the "
                        "images (%dx%d; 1 or 3 channels)", name, mask->width, mask->height,
                        mask->channels, w, h);
    int n = 0;
    for (size_t k = 0; k < wh; k++) {
        int in = 1;
        if (mask) {
            in = 0;
            for (int c = 0; c < mask->channels; c++) {
                float v = mask->data[k * (size_t)mask->channels + c];
                in |= v != 0.0f && isfinite(v);
            }
        }
        inside[k] = (unsigned char)in;
        n += in;
    }
    *pixels = n;
    return BTF_OK;
}

/* The size of a file source from its first image's header. */
static int probe_size(ps_source *src, btf_error *err)
{
    btf_image_header hdr;
    int rc = btf_image_probe(src->paths[0], &hdr, err);
    if (rc)
        return rc;
    src->width = hdr.width;
    src->height = hdr.height;
    src->channels = 3;
    return BTF_OK;
}

/* The whole stage; a file source's size comes from its first image. */
static int ps_run(ps_source *src, const double *lights, const double *E,
                  const btf_image *mask, const btf_photostereo_opts *o, btf_ps_result *out,
                  btf_error *err)
{
    ps_params P;
    int rc = resolve_opts(o, &P, err);
    if (rc)
        return rc;
    int n = src->count;
    if (n < 3)
        return btf_fail(err, BTF_E_ARG, "%s: %d images; at least 3 lights are needed", src->name,
                        n);
    double *L = btf_alloc((size_t)n * 6, sizeof(double), err); /* lights, half vectors */
    if (!L)
        return BTF_E_NOMEM;
    /* The lights first: a coplanar set fails before any file is touched. */
    if ((rc = check_lights(src->name, lights, E, n, &P, L, &out->condition, err)) ||
        (src->width == 0 && (rc = probe_size(src, err)))) {
        free(L);
        return rc;
    }
    int w = src->width, h = src->height;
    size_t wh = (size_t)w * h;
    unsigned char *inside = btf_alloc(wh, 1, err);
    if (!inside) {
        free(L);
        return BTF_E_NOMEM;
    }
    float *grey = NULL;
    ps_job *j = NULL;
    if ((rc = mask_inside(src->name, mask, w, h, inside, &out->pixels, err)) ||
        (rc = alloc_result(out, w, h, src->channels, err)))
        goto done;
    half_vectors(L, n, L + 3 * (size_t)n);
    grey = btf_alloc(wh * (size_t)n, sizeof(float), err);
    j = btf_calloc(1, sizeof *j, err);
    if (!grey || !j) {
        rc = BTF_E_NOMEM;
        goto done;
    }
    j->w = w, j->h = h, j->n = n, j->words = (n + 63) / 64;
    j->L = L, j->H = L + 3 * (size_t)n, j->grey = grey, j->inside = inside, j->prm = P;
    j->normal = out->normal.data, j->used = out->lights_used.data, j->valid = out->valid.data;
    j->bits = btf_calloc(wh * (size_t)j->words, sizeof(uint64_t), err);
    if (!j->bits) {
        rc = BTF_E_NOMEM;
        goto done;
    }
    if ((rc = pass_grey(src, E, &P, inside, grey, o, err)))
        goto done;
    if ((rc = solve_all(j, o->threads, o->progress, o->progress_user, 0.4, 0.5, err)))
        goto done;
    free(grey);
    grey = NULL;
    out->fitted = atomic_load(&j->fitted);
    out->fallback = atomic_load(&j->fallback);
    if ((rc = pass_albedo(src, E, j, inside, &out->albedo, o, err)))
        goto done;
    report(o, 0.9, "integrating");
    rc = btf_integrate(&out->normal, mask, &o->integrate, &out->height, err);
    if (rc == BTF_OK)
        report(o, 1.0, "done");
done:
    if (j)
        free(j->bits);
    free(j);
    free(grey);
    free(inside);
    free(L);
    return rc;
}

static int start_result(btf_ps_result *out, btf_error *err)
{
    if (!out)
        return btf_fail(err, BTF_E_ARG, "photostereo: no result given");
    memset(out, 0, sizeof *out);
    out->view = -1;
    return BTF_OK;
}

int btf_photostereo(const btf_image *images, int count, const double *lights,
                    const double *intensity, const btf_image *mask,
                    const btf_photostereo_opts *opts, btf_ps_result *out, btf_error *err)
{
    int rc = start_result(out, err);
    if (rc)
        return rc;
    btf_photostereo_opts o = {0};
    if (opts)
        o = *opts;
    if (!images || !lights || count < 3)
        return btf_fail(err, BTF_E_ARG, "photostereo: %d images given; at least 3 lights are "
                        "needed", images && lights ? count : 0);
    const btf_image *a = &images[0];
    for (int i = 0; i < count; i++) {
        const btf_image *b = &images[i];
        if (!b->data || b->width < 1 || b->height < 1 || (b->channels != 1 && b->channels != 3))
            return btf_fail(err, BTF_E_ARG, "photostereo: image %d is empty or has %d channels "
                            "(expected 1 or 3)", i, b->channels);
        if (b->width != a->width || b->height != a->height || b->channels != a->channels)
            return btf_fail(err, BTF_E_ARG, "photostereo: image %d is %dx%dx%d, image 0 is "
                            "%dx%dx%d", i, b->width, b->height, b->channels, a->width,
                            a->height, a->channels);
    }
    ps_source src = {"photostereo", count, images, NULL, {0}, a->width, a->height, a->channels};
    rc = ps_run(&src, lights, intensity, mask, &o, out, err);
    if (rc)
        btf_ps_result_free(out);
    return rc;
}

int btf_photostereo_dataset(const btf_dataset *ds, const btf_image *mask,
                            const btf_photostereo_opts *opts, btf_ps_result *out, btf_error *err)
{
    int rc = start_result(out, err);
    if (rc)
        return rc;
    if (!ds)
        return btf_fail(err, BTF_E_ARG, "photostereo: no dataset given");
    btf_photostereo_opts o = {0};
    if (opts)
        o = *opts;
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    /* The view closest to the normal: the images are then (nearly)
     * orthographic and unshifted by parallax. */
    int view = 0;
    for (int v = 1; v < in->n_views; v++)
        if (in->views->dirs[v].theta < in->views->dirs[view].theta)
            view = v;
    int n = in->n_lights;
    double *L = btf_alloc((size_t)n * 3, sizeof(double), err);
    const char **paths = btf_alloc((size_t)n, sizeof(char *), err);
    if (!L || !paths) {
        free(L);
        free(paths);
        return BTF_E_NOMEM;
    }
    for (int i = 0; i < n; i++) {
        btf_dir_to_vec(in->lights->dirs[i], L + 3 * i);
        paths[i] = btf_dataset_path(ds, view, i);
    }
    ps_source src = {in->root, n, NULL, paths, o.read, in->width, in->height, 3};
    rc = ps_run(&src, L, NULL, mask, &o, out, err);
    out->view = view;
    out->view_dir = in->views->dirs[view];
    free(L);
    free(paths);
    if (rc)
        btf_ps_result_free(out);
    return rc;
}

/* ---------------------------------------------------------- manifests */

typedef struct manifest_cols {
    int path, theta, phi, lx, ly, lz, r, g, b;
} manifest_cols;

static int manifest_columns(const btf_tsv *t, const char *path, manifest_cols *c, btf_error *err)
{
    c->path = btf_tsv_column(t, "path");
    c->theta = btf_tsv_column(t, "theta_l");
    c->phi = btf_tsv_column(t, "phi_l");
    c->lx = btf_tsv_column(t, "lx");
    c->ly = btf_tsv_column(t, "ly");
    c->lz = btf_tsv_column(t, "lz");
    c->r = btf_tsv_column(t, "r");
    c->g = btf_tsv_column(t, "g");
    c->b = btf_tsv_column(t, "b");
    if (c->path < 0)
        return btf_fail(err, BTF_E_FORMAT, "%s: no 'path' column in the header line", path);
    int angles = (c->theta >= 0) + (c->phi >= 0), vec = (c->lx >= 0) + (c->ly >= 0) + (c->lz >= 0);
    int rgb = (c->r >= 0) + (c->g >= 0) + (c->b >= 0);
    if (angles == 1 || (vec != 0 && vec != 3) || (rgb != 0 && rgb != 3))
        return btf_fail(err, BTF_E_FORMAT, "%s: incomplete columns: give theta_l and phi_l, or "
                        "lx, ly and lz, and r, g, b together or not at all", path);
    if (angles == 2 && vec == 3)
        return btf_fail(err, BTF_E_FORMAT, "%s: both theta_l/phi_l and lx/ly/lz columns: give "
                        "the light one way only", path);
    if (angles == 0 && vec == 0)
        return btf_fail(err, BTF_E_FORMAT, "%s: no light columns (theta_l, phi_l or lx, ly, lz)",
                        path);
    return BTF_OK;
}

static int manifest_row(const btf_tsv *t, const char *path, int row, const manifest_cols *c,
                        double *L, double *E, btf_error *err)
{
    int rc;
    if (c->theta >= 0) {
        btf_dir d;
        if ((rc = btf_tsv_number(t, path, row, c->theta, &d.theta, err)) ||
            (rc = btf_tsv_number(t, path, row, c->phi, &d.phi, err)))
            return rc;
        if (d.theta < 0.0 || d.theta > 90.0)
            return btf_fail(err, BTF_E_FORMAT, "%s:%d: theta_l %g out of range 0..90 degrees",
                            path, t->line_no[row], d.theta);
        btf_dir_to_vec(d, L);
    } else {
        int cols[3] = {c->lx, c->ly, c->lz};
        for (int k = 0; k < 3; k++)
            if ((rc = btf_tsv_number(t, path, row, cols[k], &L[k], err)))
                return rc;
        double len = sqrt(L[0] * L[0] + L[1] * L[1] + L[2] * L[2]);
        if (!(len > 1e-12) || !isfinite(len))
            return btf_fail(err, BTF_E_FORMAT, "%s:%d: light (%g, %g, %g) is not a non-zero "
                            "finite vector", path, t->line_no[row], L[0], L[1], L[2]);
    }
    if (E) {
        int cols[3] = {c->r, c->g, c->b};
        for (int k = 0; k < 3; k++) {
            if ((rc = btf_tsv_number(t, path, row, cols[k], &E[k], err)))
                return rc;
            if (!(E[k] > 0.0))
                return btf_fail(err, BTF_E_FORMAT, "%s:%d: intensity %s = %g must be positive",
                                path, t->line_no[row], t->names[cols[k]], E[k]);
        }
    }
    return BTF_OK;
}

/* A manifest's relative path, from the manifest's folder. */
static int resolve_path(const char *manifest, const char *rel, char **out, btf_error *err)
{
    if (!*rel)
        return btf_fail(err, BTF_E_FORMAT, "%s: empty path", manifest);
    const char *slash = strrchr(manifest, '/');
    size_t dl = rel[0] == '/' || !slash ? 0 : (size_t)(slash - manifest) + 1;
    size_t rl = strlen(rel);
    char *p = btf_alloc(dl + rl + 1, 1, err);
    if (!p)
        return BTF_E_NOMEM;
    memcpy(p, manifest, dl);
    memcpy(p + dl, rel, rl + 1);
    *out = p;
    return BTF_OK;
}

int btf_photostereo_manifest(const char *path, const btf_image *mask,
                             const btf_photostereo_opts *opts, btf_ps_result *out, btf_error *err)
{
    int rc = start_result(out, err);
    if (rc)
        return rc;
    if (!path)
        return btf_fail(err, BTF_E_ARG, "photostereo: no manifest given");
    btf_photostereo_opts o = {0};
    if (opts)
        o = *opts;
    btf_tsv t;
    if ((rc = btf_tsv_read(path, &t, err)))
        return rc;
    manifest_cols c;
    if ((rc = manifest_columns(&t, path, &c, err))) {
        btf_tsv_free(&t);
        return rc;
    }
    int n = t.nrows;
    if (n < 3) {
        btf_tsv_free(&t);
        return btf_fail(err, BTF_E_FORMAT, "%s: %d images; photometric stereo needs at least 3",
                        path, n);
    }
    double *L = btf_alloc((size_t)n * 3, sizeof(double), err);
    double *E = c.r >= 0 ? btf_alloc((size_t)n * 3, sizeof(double), err) : NULL;
    char **paths = btf_calloc((size_t)n, sizeof(char *), err);
    if (!L || !paths || (c.r >= 0 && !E))
        rc = BTF_E_NOMEM;
    for (int i = 0; i < n && rc == BTF_OK; i++) {
        rc = manifest_row(&t, path, i, &c, L + 3 * i, E ? E + 3 * i : NULL, err);
        if (rc == BTF_OK)
            rc = resolve_path(path, btf_tsv_cell(&t, i, c.path), &paths[i], err);
    }
    ps_source src = {path, n, NULL, (const char *const *)paths, o.read, 0, 0, 3};
    if (rc == BTF_OK)
        rc = ps_run(&src, L, E, mask, &o, out, err);
    for (int i = 0; paths && i < n; i++)
        free(paths[i]);
    free(paths);
    free(L);
    free(E);
    btf_tsv_free(&t);
    if (rc)
        btf_ps_result_free(out);
    return rc;
}

/* ------------------------------------------------------------ previews */

int btf_normals_preview(const btf_image *normals, btf_image *out, btf_error *err)
{
    if (!out)
        return btf_fail(err, BTF_E_ARG, "normals preview: no output given");
    memset(out, 0, sizeof *out);
    if (!normals || !normals->data || normals->channels != 3)
        return btf_fail(err, BTF_E_ARG, "normals preview: a 3-channel normal map is needed");
    int rc = btf_image_alloc(out, normals->width, normals->height, 3, err);
    if (rc)
        return rc;
    size_t count = (size_t)normals->width * normals->height;
    for (size_t k = 0; k < count; k++) {
        const float *n = normals->data + 3 * k;
        if (!(n[0] != 0.0f || n[1] != 0.0f || n[2] != 0.0f))
            continue; /* outside the mask: black */
        for (int c = 0; c < 3; c++) {
            float v = isfinite(n[c]) ? 0.5f * (n[c] + 1.0f) : 0.5f;
            /* The PNG writer encodes to sRGB; pre-linearise so the file holds
             * (n + 1) / 2 as the usual normal-map convention wants. */
            out->data[3 * k + c] = btf_srgb_to_linear(v);
        }
    }
    return BTF_OK;
}

/* Slope of h along columns / rows at (x, y) by central differences inside
 * the valid set, one-sided at its edge, 0 where isolated. */
static double slope_at(const btf_image *h, const unsigned char *in, int x, int y, int dx, int dy)
{
    int w = h->width, H = h->height;
    int x0 = x - dx, y0 = y - dy, x1 = x + dx, y1 = y + dy;
    int has0 = x0 >= 0 && y0 >= 0 && in[(size_t)y0 * w + x0];
    int has1 = x1 < w && y1 < H && in[(size_t)y1 * w + x1];
    double c = h->data[(size_t)y * w + x];
    if (has0 && has1)
        return 0.5 * (h->data[(size_t)y1 * w + x1] - h->data[(size_t)y0 * w + x0]);
    if (has1)
        return h->data[(size_t)y1 * w + x1] - c;
    if (has0)
        return c - h->data[(size_t)y0 * w + x0];
    return 0.0;
}

int btf_height_relief(const btf_image *height, const btf_image *mask, btf_image *out,
                      btf_error *err)
{
    if (!out)
        return btf_fail(err, BTF_E_ARG, "relief: no output given");
    memset(out, 0, sizeof *out);
    if (!height || !height->data || height->channels != 1)
        return btf_fail(err, BTF_E_ARG, "relief: a 1-channel height map is needed");
    int w = height->width, h = height->height, pixels;
    size_t count = (size_t)w * h;
    unsigned char *in = btf_alloc(count, 1, err);
    if (!in)
        return BTF_E_NOMEM;
    int rc = mask_inside("relief", mask, w, h, in, &pixels, err);
    if (rc == BTF_OK)
        rc = btf_image_alloc(out, w, h, 3, err);
    if (rc) {
        free(in);
        return rc;
    }
    /* Exaggeration: the mean slope becomes 0.5 whatever the relief's depth,
     * so a nearly flat surface still shows its shape. Tint: height from dark
     * blue-grey (low) to warm white (high) between its extremes. */
    double sum = 0.0, lo = INFINITY, hi = -INFINITY;
    int n = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            size_t k = (size_t)y * w + x;
            if (!in[k] || !isfinite(height->data[k]))
                continue;
            double gx = slope_at(height, in, x, y, 1, 0), gy = slope_at(height, in, x, y, 0, 1);
            sum += sqrt(gx * gx + gy * gy);
            lo = fmin(lo, height->data[k]);
            hi = fmax(hi, height->data[k]);
            n++;
        }
    double mean = n > 0 ? sum / n : 0.0;
    double ex = mean > 1e-12 ? 0.5 / mean : 1.0;
    double span = hi > lo ? hi - lo : 1.0;
    /* Light from the top left, 45 degrees up: (-1, 1, sqrt 2) / 2. */
    const double l[3] = {-0.5, 0.5, 0.70710678118654752};
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            size_t k = (size_t)y * w + x;
            if (!in[k] || !isfinite(height->data[k]))
                continue;
            double gx = ex * slope_at(height, in, x, y, 1, 0);
            double gy = -ex * slope_at(height, in, x, y, 0, 1); /* y up */
            double len = sqrt(gx * gx + gy * gy + 1.0);
            double shade = (-gx * l[0] - gy * l[1] + l[2]) / len;
            shade = 0.15 + 0.85 * (shade > 0.0 ? shade : 0.0);
            double t = (height->data[k] - lo) / span;
            const double low[3] = {0.55, 0.62, 0.75}, high[3] = {1.0, 0.97, 0.88};
            for (int c = 0; c < 3; c++) {
                double v = shade * (low[c] + (high[c] - low[c]) * t);
                out->data[3 * k + c] = btf_srgb_to_linear((float)(v > 1.0 ? 1.0 : v));
            }
        }
    free(in);
    return BTF_OK;
}

static int write_pair(const char *outdir, const char *name, const btf_image *exr,
                      const btf_image *png, btf_error *err)
{
    char path[4096], file[64];
    int rc;
    snprintf(file, sizeof file, "%s.exr", name);
    if ((rc = btf_path_join(path, sizeof path, outdir, file, err)) ||
        (rc = btf_image_write_exr(path, exr, 0, err)))
        return rc;
    snprintf(file, sizeof file, "%s.png", name);
    if ((rc = btf_path_join(path, sizeof path, outdir, file, err)) ||
        (rc = btf_image_write_png(path, png, err)))
        return rc;
    return BTF_OK;
}

int btf_ps_write(const btf_ps_result *r, const btf_image *mask, const char *outdir,
                 btf_error *err)
{
    if (!r || !outdir || !r->normal.data || !r->albedo.data || !r->height.data)
        return btf_fail(err, BTF_E_ARG, "photostereo: nothing to write (empty result or no folder)");
    int rc = btf_mkdirs(outdir, err);
    if (rc)
        return rc;
    btf_image prev = {0};
    if ((rc = btf_normals_preview(&r->normal, &prev, err)) == BTF_OK)
        rc = write_pair(outdir, "normals", &r->normal, &prev, err);
    btf_image_free(&prev);
    if (rc == BTF_OK)
        rc = write_pair(outdir, "albedo", &r->albedo, &r->albedo, err);
    if (rc == BTF_OK && (rc = btf_height_relief(&r->height, mask, &prev, err)) == BTF_OK)
        rc = write_pair(outdir, "height", &r->height, &prev, err);
    btf_image_free(&prev);
    return rc;
}
