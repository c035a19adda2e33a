/*
 * ps_fit.c — the robust Lambertian fit of one pixel (Woodham 1980,
 * "Photometric method for determining surface orientation from multiple
 * images"; the range-map stage of Haindl & Filip 2007, section II.B).
 *
 * A Lambertian pixel lit by the unit light l_i shows I_i = rho n.l_i =
 * g.l_i with g = rho n (the scaled normal), so three or more lights
 * determine g by least squares, g = (sum l l^T)^-1 sum I_i l_i, and then
 * rho = |g|, n = g / |g|. The samples are one grey value per light (the
 * mean of the channels, each divided by the light's intensity).
 *
 * Real samples break the model: cast and attached shadows are too dark,
 * specular highlights too bright, clipped values wrong. The robust rule
 * (docs/photostereo.md, where the choices are measured):
 *  1. saturated samples (stored negated) and samples <= 0 are excluded;
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
 *     vector (of the light and the view (0, 0, 1)) within the specular cone
 *     of the normal. Samples may come back.
 * Every fit needs at least 3 samples whose Gram matrix sum l l^T has a
 * condition number <= max_condition (the lights are not nearly coplanar); a
 * reweighting step that would break this is not taken. A pixel whose first
 * fit fails takes the fallback normal (0, 0, 1), chosen by the caller.
 */
#include "range/range.h"
#include "core/core.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define REF_QUANTILE 0.95     /* the reference level: the brightest after the top 5 % */
#define SCALE_FLOOR 0.02      /* robust scale floor, fraction of the albedo */
#define SHADOW_GAP 3.0        /* a jump between sorted values that splits off shadows */
#define MAD_TO_SIGMA 1.4826   /* median |r| -> standard deviation for Gaussian r */

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
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
        double ratio = a[i + 1] / a[i];
        if (ratio > best) {
            best = ratio;
            cut = a[i + 1];
        }
    }
    return best >= SHADOW_GAP ? cut : 0.0;
}

/* Least squares over the flagged samples; 0 if < 3 or ill-conditioned.
 * gram_inverse receives (sum l l^T)^-1 for the leverages. */
static int fit_set(const double *lights, int count, const double *samples,
                   const unsigned char *in_fit, double max_condition, double scaled_normal[3],
                   btf_sym3 *gram_inverse)
{
    btf_sym3 gram = {0};
    double rhs[3] = {0, 0, 0};
    int used = 0;
    for (int i = 0; i < count; i++) {
        if (!in_fit[i])
            continue;
        const double *l = lights + 3 * i;
        btf_sym3_add_outer(&gram, l);
        rhs[0] += samples[i] * l[0];
        rhs[1] += samples[i] * l[1];
        rhs[2] += samples[i] * l[2];
        used++;
    }
    return used >= 3 &&
           btf__sym3_solve(&gram, rhs, max_condition, scaled_normal, gram_inverse);
}

/* Residuals of every sample against the fit into s->residuals; for the
 * samples of the fit, the deleted residual r / (1 - h), with h = l^T
 * (sum l l^T)^-1 l (gram_inverse) the sample's leverage: what the fit
 * without that sample would predict. A single bad sample of high leverage
 * (a partly shadowed one amid the lights) pulls an ordinary fit towards
 * itself and hides its own residual; its deleted residual does not.
 * Returns the robust scale 1.4826 median |r| of the fit's samples, at
 * least SCALE_FLOOR x albedo. */
static double residuals(const double *lights, int count, const double *samples,
                        const double scaled_normal[3], const btf_sym3 *gram_inverse,
                        btf_ps_scratch *s)
{
    int in = 0;
    for (int i = 0; i < count; i++) {
        const double *l = lights + 3 * i;
        double res = samples[i] - dot3(scaled_normal, l);
        if (s->in_fit[i]) {
            double leverage = btf_sym3_quadratic(gram_inverse, l);
            if (leverage < 1.0 - 1e-6)
                res /= 1.0 - leverage;
            s->values[in++] = fabs(res);
        }
        s->residuals[i] = res;
    }
    double albedo = sqrt(dot3(scaled_normal, scaled_normal));
    double scale = in > 0 ? MAD_TO_SIGMA * btf__select_kth(s->values, in, in / 2) : 0.0;
    return scale > SCALE_FLOOR * albedo ? scale : SCALE_FLOOR * albedo;
}

/* One reweighting step: the samples consistent with the fit, into
 * s->next_fit. Shadows only darken and highlights only brighten, so the
 * window is asymmetric: a sample more than outlier x s below the fit is
 * (partly) shadowed; one above it is a highlight when its half vector with
 * the view lies within the specular cone of the normal (and it exceeds the
 * fit by more than s), and an outlier anyway beyond 2 x outlier x s. A
 * sample the fit predicts unlit (g.l <= 0) carries no information. Returns
 * the number kept; *changed tells whether the set differs. */
static int reweight(const btf_ps_params *params, const double *lights, const double *halfway,
                    int count, const double *samples, const double scaled_normal[3],
                    const btf_sym3 *gram_inverse, btf_ps_scratch *s, int *changed)
{
    double scale = residuals(lights, count, samples, scaled_normal, gram_inverse, s);
    double albedo = sqrt(dot3(scaled_normal, scaled_normal));
    double below = params->outlier * scale, above = 2.0 * params->outlier * scale;
    /* g.h > cos(cone) |g|: the half vector lies within the cone of the normal. */
    double cone = params->specular_cos * albedo;
    int kept = 0;
    *changed = 0;
    for (int i = 0; i < count; i++) {
        const double *l = lights + 3 * i, *half = halfway + 3 * i;
        double predicted = dot3(scaled_normal, l), res = s->residuals[i];
        int highlight = res > scale && dot3(scaled_normal, half) > cone;
        unsigned char keep = s->unshadowed[i] && predicted > 0.0 && res >= -below &&
                             res <= above && !highlight;
        s->next_fit[i] = keep;
        kept += keep;
        *changed |= keep != s->in_fit[i];
    }
    return kept;
}

/* The first set: the candidates (s->in_fit: unsaturated, > 0) that are not
 * shadowed (dark rule and shadow gap) into s->unshadowed, and of those the
 * ones inside the trim quantiles into s->in_fit. s->values holds the
 * n_candidates candidate values. Returns the number not shadowed. */
static int first_set(const btf_ps_params *params, int count, const double *samples,
                     int n_candidates, btf_ps_scratch *s)
{
    btf__sort_small(s->values, n_candidates);
    double ref = s->values[(int)floor(REF_QUANTILE * (n_candidates - 1))];
    double dark_cut = params->dark * ref;
    double gap = shadow_gap(s->values, n_candidates, ref, dark_cut);
    if (gap > dark_cut)
        dark_cut = gap;
    int first = 0;
    while (first < n_candidates && s->values[first] < dark_cut)
        first++;
    int n_lit = n_candidates - first;
    if (n_lit < 3)
        return n_lit;
    /* The samples not shadowed are values[first..n_candidates-1], sorted. */
    double hi = s->values[first + (int)floor((1.0 - params->trim_high) * (n_lit - 1))];
    double lo = s->values[first + (int)ceil(params->trim_low * (n_lit - 1))];
    for (int i = 0; i < count; i++) {
        s->unshadowed[i] = (unsigned char)(s->in_fit[i] && samples[i] >= dark_cut);
        s->in_fit[i] = (unsigned char)(s->unshadowed[i] && samples[i] >= lo && samples[i] <= hi);
    }
    return n_lit;
}

int btf__ps_fit_pixel(const btf_ps_params *params, const double *lights, const double *halfway,
                      int count, const double *samples, btf_ps_scratch *s,
                      double scaled_normal[3])
{
    btf_sym3 gram_inverse;
    int n_candidates = 0;
    for (int i = 0; i < count; i++) {
        int candidate = params->plain ? samples[i] >= 0.0 : samples[i] > 0.0;
        s->in_fit[i] = (unsigned char)candidate;
        if (candidate)
            s->values[n_candidates++] = samples[i];
    }
    if (params->plain) /* a black pixel gives g = 0: the fallback, not a 0/0 normal */
        return fit_set(lights, count, samples, s->in_fit, params->max_condition, scaled_normal,
                       &gram_inverse) &&
               dot3(scaled_normal, scaled_normal) > 0.0;
    if (n_candidates < 3 || first_set(params, count, samples, n_candidates, s) < 3)
        return 0;
    if (!fit_set(lights, count, samples, s->in_fit, params->max_condition, scaled_normal,
                 &gram_inverse)) {
        /* Too few in the trimmed middle: every non-shadowed sample. */
        memcpy(s->in_fit, s->unshadowed, (size_t)count);
        if (!fit_set(lights, count, samples, s->in_fit, params->max_condition, scaled_normal,
                     &gram_inverse))
            return 0;
    }
    for (int it = 0; it < params->iterations; it++) {
        int changed;
        int kept = reweight(params, lights, halfway, count, samples, scaled_normal,
                            &gram_inverse, s, &changed);
        double next_normal[3];
        btf_sym3 next_inverse;
        if (!changed || kept < 3 ||
            !fit_set(lights, count, samples, s->next_fit, params->max_condition, next_normal,
                     &next_inverse))
            break;
        memcpy(s->in_fit, s->next_fit, (size_t)count);
        memcpy(scaled_normal, next_normal, sizeof next_normal);
        gram_inverse = next_inverse;
    }
    return dot3(scaled_normal, scaled_normal) > 0.0;
}

/* The normal (0, 0, 1) explains best the samples of lights above the
 * horizon; the unsaturated positive ones, else the saturated ones (a lower
 * bound on the albedo, better than none). */
void btf__ps_fallback_set(const double *lights, int count, const double *samples,
                          unsigned char *in_fit)
{
    int any = 0;
    for (int i = 0; i < count; i++) {
        in_fit[i] = (unsigned char)(samples[i] > 0.0 && lights[3 * i + 2] > 0.0);
        any |= in_fit[i];
    }
    if (!any)
        for (int i = 0; i < count; i++)
            in_fit[i] = (unsigned char)(samples[i] < 0.0 && lights[3 * i + 2] > 0.0);
}

void btf__ps_scratch_free(btf_ps_scratch *s)
{
    BTF_FREE_ALL(s->values, s->residuals, s->unshadowed, s->row_samples);
    memset(s, 0, sizeof *s);
}

btf_status btf__ps_scratch_alloc(btf_ps_scratch *s, int count, int width, btf_error *err)
{
    memset(s, 0, sizeof *s);
    s->values = btf__alloc((size_t)count, sizeof(double), err);
    s->residuals = btf__alloc((size_t)count, sizeof(double), err);
    s->unshadowed = btf__alloc((size_t)count, 3, err); /* the three flag arrays in one block */
    s->row_samples = btf__alloc((size_t)count * (size_t)width, sizeof(double), err);
    if (!s->values || !s->residuals || !s->unshadowed || !s->row_samples) {
        btf__ps_scratch_free(s);
        return BTF_E_NOMEM;
    }
    s->in_fit = s->unshadowed + count;
    s->next_fit = s->unshadowed + 2 * count;
    return BTF_OK;
}
