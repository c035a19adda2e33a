/*
 * torus.c — one CAR field on a W x H torus, solved exactly in the Fourier
 * domain: the generator of tileable synthesis (docs/synthesis.md,
 * "Tileable synthesis").
 *
 * The causal recursion of Haindl & Filip 2007, section II.C,
 *
 *     Y(r, c) = sum_s gamma_s Y(r + dr_s, c + dc_s) + sigma e(r, c),
 *
 * taken with periodic boundaries (indices mod H and mod W) is one linear
 * system A Y = sigma e whose matrix A is circulant (block circulant with
 * circulant blocks), so the 2D DFT diagonalises it. With the forward DFT
 * F(k1, k2) = sum_{r,c} f(r, c) exp(-2 pi i (k1 c / W + k2 r / H)) (OpenCV's),
 * a shifted field f(r + dr, c + dc) transforms to
 * exp(+2 pi i (k1 dc / W + k2 dr / H)) F, hence
 *
 *     A(k1, k2) = 1 - sum_s gamma_s exp(+2 pi i (k1 dc_s / W + k2 dr_s / H))
 *     Y = IDFT( DFT(sigma e) / A ).
 *
 * The field is then exactly stationary on the torus: its covariance is the
 * stationary one's periodic sum, and its variance sigma^2 mean(1/|A|^2) over
 * the grid, which for a torus larger than the correlation length is the
 * model's stationary variance (btf__car_stationary_variance: the same mean
 * over the continuous frequency torus). A stable model (the validator's
 * check, car/stability.c) has A != 0 on the whole frequency torus; a grid
 * frequency with |A|^2 below SYNTH_TORUS_MIN_A2 is refused all the same.
 *
 * The noise is the streaming synthesis' own: pixel (r, c) takes the
 * Gaussian of row r and column c of the field's stream (btf_noise.h, with
 * BTF_NOISE_ORIGIN added), so the same seed gives the same noise.
 */
#include "core/core.h"
#include "io/io.h"
#include "synth/synth.h"
#include "synth/synth_testing.h"

#include "btf_shared.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* |A|^2 below this at a grid frequency is a singular system: the field
 * would be amplified 10^10 times there (a stable model stays far above). */
#define SYNTH_TORUS_MIN_A2 1e-10

/* e^(2 pi i k / n) for k = 0 .. n - 1 into cs[2k], cs[2k + 1]. The angle is
 * formed from k / n, exact for the grid, so every offset's phase is a table
 * entry (index k dc mod n) and no angle grows with the frequency. */
static void unit_roots(int n, double *cs)
{
    const double two_pi = 6.283185307179586476925286766559;
    for (int k = 0; k < n; k++) {
        double a = two_pi * ((double)k / (double)n);
        cs[2 * k] = cos(a);
        cs[2 * k + 1] = sin(a);
    }
}

/* (a mod n) in 0 .. n - 1 for any sign of a. */
static int wrap(long a, int n)
{
    long m = a % n;
    return (int)(m < 0 ? m + n : m);
}

/* sigma e over the torus into re (row-major, h rows of w), im zeroed. */
static btf_status noise_field(const btf_car_band *b, uint32_t stream, int w, int h,
                              uint64_t seed, int vector_noise, double *re, double *im,
                              btf_error *err)
{
    uint32_t blocks = (uint32_t)(w + 3) / 4;
    float *e = btf__alloc((size_t)blocks * 4, sizeof(float), err);
    if (!e)
        return BTF_E_NOMEM;
    const uint32_t b0 = (uint32_t)BTF_NOISE_ORIGIN / 4u; /* column 0: ORIGIN is a multiple of 4 */
    for (int r = 0; r < h; r++) {
        btf__noise_blocks((uint32_t)seed, (uint32_t)(seed >> 32), stream,
                          (uint32_t)(r + BTF_NOISE_ORIGIN), b0, blocks, vector_noise, e);
        double *row = re + (size_t)r * w;
        for (int c = 0; c < w; c++)
            row[c] = (double)b->sigma * (double)e[c];
    }
    memset(im, 0, (size_t)w * h * sizeof(double));
    free(e);
    return BTF_OK;
}

/* Divides the spectrum (re, im) by A(k1, k2) at every grid frequency;
 * BTF_E_NUMERIC when |A|^2 falls below the floor somewhere. The offsets
 * are grouped by row: A = 1 - sum_j exp(i 2 pi k2 dr_j / H) Q_j(k1) with
 * Q_j(k1) = sum over the offsets s of row dr_j of gamma_s
 * exp(i 2 pi k1 dc_s / W), tabulated once, so a frequency costs one complex
 * multiply-add per distinct row (3 or 4) instead of one per offset. */
static btf_status divide_by_a(const btf_car_band *b, int w, int h, double *re, double *im,
                              const char *what, btf_error *err)
{
    int rows[BTF_CAR_MAX_NEIGHBOURS], nr = 0;
    for (int s = 0; s < b->n; s++) {
        int j = 0;
        while (j < nr && rows[j] != b->offsets[s].row)
            j++;
        if (j == nr)
            rows[nr++] = b->offsets[s].row;
    }
    /* unit roots of both sides, then Q_j's real and imaginary rows */
    double *cw = btf__alloc((size_t)(w + h) * 2 + (size_t)nr * w * 2, sizeof(double), err);
    if (!cw)
        return BTF_E_NOMEM;
    double *ch = cw + (size_t)w * 2, *q = ch + (size_t)h * 2;
    unit_roots(w, cw);
    unit_roots(h, ch);
    for (int j = 0; j < nr; j++) {
        double *qr = q + (size_t)j * 2 * w, *qi = qr + w;
        for (int k1 = 0; k1 < w; k1++) {
            double sr = 0.0, si = 0.0;
            for (int s = 0; s < b->n; s++)
                if (b->offsets[s].row == rows[j]) {
                    const double *pc = cw + 2 * wrap((long)k1 * b->offsets[s].col, w);
                    sr += (double)b->gamma[s] * pc[0];
                    si += (double)b->gamma[s] * pc[1];
                }
            qr[k1] = sr, qi[k1] = si;
        }
    }
    double min_a2 = INFINITY;
    int min_k1 = 0, min_k2 = 0;
    for (int k2 = 0; k2 < h; k2++) {
        double rr[BTF_CAR_MAX_NEIGHBOURS], ri[BTF_CAR_MAX_NEIGHBOURS];
        for (int j = 0; j < nr; j++) {
            const double *pr = ch + 2 * wrap((long)k2 * rows[j], h);
            rr[j] = pr[0], ri[j] = pr[1];
        }
        double *xr = re + (size_t)k2 * w, *xi = im + (size_t)k2 * w;
        for (int k1 = 0; k1 < w; k1++) {
            double ar = 1.0, ai = 0.0;
            for (int j = 0; j < nr; j++) {
                double qr = q[(size_t)j * 2 * w + k1], qi = q[(size_t)j * 2 * w + w + k1];
                ar -= rr[j] * qr - ri[j] * qi;
                ai -= rr[j] * qi + ri[j] * qr;
            }
            double a2 = ar * ar + ai * ai;
            if (!(a2 >= SYNTH_TORUS_MIN_A2)) { /* refused below, once the minimum is known */
                if (!(a2 >= min_a2))
                    min_a2 = a2, min_k1 = k1, min_k2 = k2;
                continue;
            }
            double vr = xr[k1], vi = xi[k1];
            xr[k1] = (vr * ar + vi * ai) / a2; /* X conj(A) / |A|^2 */
            xi[k1] = (vi * ar - vr * ai) / a2;
        }
    }
    free(cw);
    if (min_a2 < SYNTH_TORUS_MIN_A2 || isnan(min_a2))
        return btf__fail(err, BTF_E_NUMERIC, "%s: the CAR model is singular on the %dx%d torus "
                         "(|A|^2 = %.3g < %.0e at frequency (%d, %d)): its recursion is unstable",
                         what, w, h, min_a2, SYNTH_TORUS_MIN_A2, min_k1, min_k2);
    return BTF_OK;
}

btf_status synth_torus_field(const btf_car_band *b, uint32_t stream, int w, int h,
                             uint64_t seed, int vector_noise, const char *what, float *out,
                             btf_error *err)
{
    size_t n = (size_t)w * h;
    if (!(b->sigma > 0.0f)) { /* no noise: the zero field solves A Y = 0 */
        memset(out, 0, n * sizeof(float));
        return BTF_OK;
    }
    double *re = btf__alloc(n * 2, sizeof(double), err);
    if (!re)
        return BTF_E_NOMEM;
    double *im = re + n;
    btf_status rc = noise_field(b, stream, w, h, seed, vector_noise, re, im, err);
    char msg[256];
    if (rc == BTF_OK && b->n > 0) { /* white noise (no neighbours) is its own field */
        if (btfcv_dft2(re, im, w, h, 0, msg, sizeof msg) != 0)
            rc = btf__fail(err, BTF_E_NUMERIC, "%s: DFT of %dx%d failed: %s", what, w, h, msg);
        if (rc == BTF_OK)
            rc = divide_by_a(b, w, h, re, im, what, err);
        if (rc == BTF_OK && btfcv_dft2(re, im, w, h, 1, msg, sizeof msg) != 0)
            rc = btf__fail(err, BTF_E_NUMERIC, "%s: inverse DFT of %dx%d failed: %s", what, w, h,
                           msg);
    }
    if (rc == BTF_OK)
        for (size_t i = 0; i < n; i++)
            out[i] = (float)re[i]; /* the imaginary part is rounding noise: e is real */
    free(re);
    return rc;
}

btf_status btf__car_torus_field(const btf_car_band *band, uint32_t stream, int w, int h,
                                uint64_t seed, float *out, btf_error *err)
{
    if (w < 1 || h < 1 || (uint64_t)w * (uint64_t)h > BTF_SYNTH_TILE_MAX_PIXELS)
        return btf__fail(err, BTF_E_ARG, "torus field of %dx%d: sides 1.. and at most %llu pixels",
                         w, h, (unsigned long long)BTF_SYNTH_TILE_MAX_PIXELS);
    btf_status rc = btf__synth_check_band(band, 0, err);
    return rc ? rc : synth_torus_field(band, stream, w, h, seed, 1, "torus field", out, err);
}
