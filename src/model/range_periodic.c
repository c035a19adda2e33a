/*
 * range_periodic.c — the range tile made periodic (paper section III: the
 * range map "further enlarged by image-tiling": a seamless range map at
 * any size), by a variance-preserving cross-fade with its own copy
 * shifted by half a period, along x and then along y.
 *
 * Why this one (docs/render.md, "Range and normal map"): the photometric-
 * stereo height map of paper section II.B is not periodic; its periodic
 * extension jumps at the tile's edges. Along x, texel x of the result is
 *
 *     p(x) = sin(pi (x + 1/2) / w) u(x) + |cos(pi (x + 1/2) / w)| u(x + w/2 mod w)
 *
 * (u less its mean, which is added back): in the middle of the tile it is u
 * itself, near both edges the shifted copy, whose texels there are u's
 * neighbours around w/2 — so p continues across the wrap with the steps of
 * real texture, not a flattened seam — and the shifted copy's own jump (at
 * x = w/2) falls where its weight is 0. The weights are normalised so that
 * the blend keeps the surface's variance given the measured correlation of
 * the two copies (independent stretches: a^2 + b^2 = 1; a surface that is
 * already periodic with half the tile: a + b = 1, i.e. itself), so the
 * slopes keep their contrast (Moisan's periodic component, tried first,
 * shrinks the steps across the wrap to 0.4-0.5 of the inside ones, which a
 * grazing light showed as a bright line once per period). The y pass does
 * the same to the x pass's rows, which are already periodic along x.
 *
 * First the tile's mean slope is removed (a plane through its centre, so
 * the mean stays): a periodic surface has none (its steps around a period
 * sum to zero), a flat material sample has none either (a tilt is the
 * sample's mounting or integration bias), and any blend of a ramp with its
 * shifted copy keeps a fold.
 */
#include "core/core.h"
#include "model/range_code.h"

#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#define RP_PI 3.14159265358979323846

/* Removes the tile's mean slope: the mean of its steps along each axis,
 * times the distance from the centre (a plane of zero mean). */
static void remove_mean_slope(double *u, int w, int h)
{
    double gx = 0.0, gy = 0.0;
    for (int y = 0; y < h && w > 1; y++)
        gx += (u[(size_t)y * w + w - 1] - u[(size_t)y * w]) / (w - 1);
    for (int x = 0; x < w && h > 1; x++)
        gy += (u[(size_t)(h - 1) * w + x] - u[x]) / (h - 1);
    gx /= h, gy /= w;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            u[(size_t)y * w + x] -= gx * (x - 0.5 * (w - 1)) + gy * (y - 0.5 * (h - 1));
}

/* The correlation of the pass's texels with their partners half a period
 * along, clamped to [-0.5, 1]. */
static double half_shift_correlation(const double *u, int len, int lines, ptrdiff_t step,
                                     ptrdiff_t stride)
{
    double sab = 0.0, saa = 0.0;
    for (int l = 0; l < lines; l++) {
        const double *line = u + (ptrdiff_t)l * stride;
        for (int k = 0; k < len; k++) {
            double a = line[k * step], b = line[((k + len / 2) % len) * step];
            sab += a * b;
            saa += a * a;
        }
    }
    double rho = saa > 0.0 ? sab / saa : 0.0;
    return rho < -0.5 ? -0.5 : rho > 1.0 ? 1.0 : rho;
}

/* One pass: `lines` lines of `len` texels each, texel k of a line at
 * k * step, lines `stride` apart; each line becomes its cross-fade with
 * itself shifted by len / 2 (see above), the weights divided by
 * sqrt(a^2 + b^2 + 2 a b rho) so that the variance is kept whatever the
 * correlation rho of the two copies (a tile that is already periodic with
 * half its period, rho = 1, stays itself). A line of 1 texel stays. */
static void cross_fade(double *u, double *tmp, int len, int lines, ptrdiff_t step,
                       ptrdiff_t stride)
{
    if (len < 2)
        return;
    int half = len / 2;
    double rho = half_shift_correlation(u, len, lines, step, stride);
    for (int l = 0; l < lines; l++) {
        double *line = u + (ptrdiff_t)l * stride;
        for (int k = 0; k < len; k++)
            tmp[k] = line[k * step];
        for (int k = 0; k < len; k++) {
            double t = RP_PI * (k + 0.5) / len, a = sin(t), b = fabs(cos(t));
            double norm = sqrt(a * a + b * b + 2.0 * a * b * rho);
            line[k * step] = (a * tmp[k] + b * tmp[(k + half) % len]) / norm;
        }
    }
}

/* The float nearest v within the finite range: heights near FLT_MAX may
 * move past it by the decomposition's rounding. */
static float finite_float(double v)
{
    return v > FLT_MAX ? FLT_MAX : v < -FLT_MAX ? -FLT_MAX : (float)v;
}

btf_status btf_range_make_periodic(float *heights, int width, int height, btf_error *err)
{
    if (!heights || width < 1 || height < 1)
        return btf__fail(err, BTF_E_ARG, "range tile: %d x %d heights%s (expected at least 1 x 1)",
                         width, height, heights ? "" : " at NULL");
    size_t n = (size_t)width * height;
    for (size_t i = 0; i < n; i++)
        if (!isfinite(heights[i]))
            return btf__fail(err, BTF_E_DATA, "range tile: height %g at (%zu, %zu) (expected finite "
                             "heights)", heights[i], i % (size_t)width, i / (size_t)width);
    if (n == 1)
        return BTF_OK; /* a single sample is periodic */
    double *u = btf__alloc(n * 2, sizeof(double), err);
    if (!u)
        return BTF_E_NOMEM;
    double *tmp = u + n, mean = 0.0;
    for (size_t i = 0; i < n; i++)
        mean += heights[i];
    mean /= (double)n;
    for (size_t i = 0; i < n; i++)
        u[i] = heights[i] - mean;
    remove_mean_slope(u, width, height);
    cross_fade(u, tmp, width, height, 1, width);   /* along x: rows of width texels */
    cross_fade(u, tmp, height, width, width, 1);   /* along y: columns of height texels */
    /* The blend's weights do not sum to 1 (their squares do): re-centre, so
     * that the tile keeps its mean exactly. */
    double drift = 0.0;
    for (size_t i = 0; i < n; i++)
        drift += u[i];
    mean -= drift / (double)n;
    for (size_t i = 0; i < n; i++)
        heights[i] = finite_float(u[i] + mean);
    /* On the model file's 16-bit grid, so that writing the tile loses
     * nothing and a converted 1.0 file re-reads to the same model. */
    btf__range_snap(heights, n);
    free(u);
    return BTF_OK;
}
