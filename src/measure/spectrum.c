/*
 * spectrum.c — component (a) of the texture distance (docs/measure.md,
 * "Spectrum"): the radially averaged power spectrum of luminance, on a log
 * scale, compared bin by bin. Luminance is linear Y (Rec. 709 weights), not
 * L*: a spectrum is a second-order statistic of a linear quantity, the one
 * a Gaussian model (and the phase-randomisation baseline) reproduces; the
 * perceptual non-linearity of L* would mix the histogram into it. Without pixel correspondence the power
 * spectrum is what a stationary Gaussian texture is (the CAR model of the
 * paper, section II.C, is one), and its radial profile says at which scales
 * the texture has its contrast.
 *
 * The view is windowed by a separable symmetric Hann window
 * w(n) = 0.5 - 0.5 cos(2 pi (n + 0.5) / N), which tapers the borders so
 * that the jump between opposite edges (the DFT treats the view as
 * periodic) does not leak a cross of false power into every bin; the
 * window-weighted mean is removed first, so that no DC leaks either. The
 * power is |F|^2 / sum(w^2), a density: white noise of variance v has
 * expected power v in every bin, whatever the view's size, so views of
 * different sizes compare. Bins are rings of width 1/s cycles per pixel
 * (s: the smallest side among the views compared), ring k holding the
 * frequencies of radius in [(k - 0.5)/s, (k + 0.5)/s), k = 1 .. s/2: every
 * view has at least one DFT sample in every ring.
 */
#include "core/core.h"
#include "io/io.h"
#include "measure/measure.h"

#include <math.h>
#include <stdlib.h>

/* Power below this (Y^2 per unit bandwidth, -120 dB; Y is about 1 at
 * white) is taken as this: a constant view has a finite log spectrum. */
#define POWER_FLOOR 1e-12

static void hann(double *w, int n)
{
    for (int i = 0; i < n; i++)
        w[i] = 0.5 - 0.5 * cos(2.0 * M_PI * (i + 0.5) / n);
}

/* The signed frequency index of DFT sample i of n (i > n/2 are negative). */
static int signed_index(int i, int n)
{
    return i > n / 2 ? i - n : i;
}

btf_status ms_spectrum(const ms_view *v, int s, double *out, btf_error *err)
{
    int w = v->w, h = v->h, nbins = s / 2;
    size_t n = (size_t)w * h;
    double *re = btf__alloc(2 * n + w + h + 2 * (size_t)nbins, sizeof(double), err);
    if (!re)
        return BTF_E_NOMEM;
    double *im = re + n, *wx = im + n, *wy = wx + w, *count = wy + h, *sum = count + nbins;
    hann(wx, w);
    hann(wy, h);
    double wsum = 0.0, mean = 0.0, w2x = 0.0, w2y = 0.0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double l = v->lab[MS_CH * ((size_t)(v->y0 + y) * v->stride + v->x0 + x) + MS_Y];
            wsum += wx[x] * wy[y];
            mean += wx[x] * wy[y] * l;
        }
    mean /= wsum;
    for (int x = 0; x < w; x++)
        w2x += wx[x] * wx[x];
    for (int y = 0; y < h; y++)
        w2y += wy[y] * wy[y];
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double l = v->lab[MS_CH * ((size_t)(v->y0 + y) * v->stride + v->x0 + x) + MS_Y];
            re[(size_t)y * w + x] = (l - mean) * wx[x] * wy[y];
            im[(size_t)y * w + x] = 0.0;
        }
    char why[256];
    if (btfcv_dft2(re, im, w, h, 0, why, sizeof why) != 0) {
        free(re);
        return btf__fail(err, BTF_E_UNSUPPORTED, "power spectrum: DFT failed: %s", why);
    }
    for (int k = 0; k < nbins; k++)
        count[k] = sum[k] = 0.0;
    for (int y = 0; y < h; y++) {
        double fy = (double)signed_index(y, h) / h;
        for (int x = 0; x < w; x++) {
            double fx = (double)signed_index(x, w) / w;
            int k = (int)floor(sqrt(fx * fx + fy * fy) * s + 0.5);
            if (k < 1 || k > nbins)
                continue;
            size_t i = (size_t)y * w + x;
            sum[k - 1] += re[i] * re[i] + im[i] * im[i];
            count[k - 1] += 1.0;
        }
    }
    for (int k = 0; k < nbins; k++) {
        double p = count[k] > 0.0 ? sum[k] / count[k] / (w2x * w2y) : 0.0;
        out[k] = 10.0 * log10(p + POWER_FLOOR);
    }
    free(re);
    return BTF_OK;
}

/* Root mean square of the difference in dB, ring k weighted by 1/k: each
 * octave of frequency weighs the same (a ring's weight is proportional to
 * d(log f)), so the few coarse rings, where a texture's structure often is,
 * count as much as the many fine ones. */
double ms_spectrum_distance(const double *a, const double *b, int nbins)
{
    double num = 0.0, den = 0.0;
    for (int k = 1; k <= nbins; k++) {
        double d = a[k - 1] - b[k - 1];
        num += d * d / k;
        den += 1.0 / k;
    }
    return den > 0.0 ? sqrt(num / den) : 0.0;
}
