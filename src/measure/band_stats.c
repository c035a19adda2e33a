/*
 * band_stats.c — component (c) of the texture distance (docs/measure.md,
 * "Structure"): the shape of the texture at each scale, as the statistics
 * Portilla & Simoncelli (2000) and STSIM (Zujovic et al. 2013) compare
 * instead of pixels. Lightness L* is split into band-pass bands by a
 * Laplacian pyramid (Burt & Adelson 1983; the paper's Gaussian-Laplacian
 * pyramid, section II.C): band l = G_l - g * G_l, with g the 5-tap binomial
 * [1 4 6 4 1] / 16 (separable, mirrored at the borders) and
 * G_{l+1} = g * G_l taken at every second pixel. (The band is the
 * difference to the blurred image at the same size, not to the expanded
 * next level: the same band-pass, without an interpolation step.) Per band:
 * the log variance (contrast at that scale), skewness and log kurtosis (the
 * shape of the band's marginal: edges and spots are heavy-tailed, Gaussian
 * textures are not), and the correlation with the neighbour at (0, 1),
 * (1, 0), (1, 1), (1, -1) (orientation and regularity at that scale).
 */
#include "core/core.h"
#include "measure/measure.h"

#include <math.h>
#include <stdlib.h>

/* A band whose variance is below this (L*^2) is constant: its shape
 * statistics are those of a Gaussian (skewness 0, kurtosis 3), its
 * correlations 0, so two constant bands agree. */
#define VARIANCE_ZERO 1e-10

static const int OFFSETS[MS_OFFSETS][2] = {{0, 1}, {1, 0}, {1, 1}, {1, -1}};

static int mirror(int i, int n)
{
    if (n == 1)
        return 0;
    if (i < 0)
        i = -i;
    if (i >= n)
        i = 2 * n - 2 - i;
    return i < 0 ? 0 : i >= n ? n - 1 : i;
}

/* out = g * in (w x h), through tmp (w x h). */
static void binomial_blur(const double *in, double *tmp, double *out, int w, int h)
{
    static const double g[5] = {1.0 / 16, 4.0 / 16, 6.0 / 16, 4.0 / 16, 1.0 / 16};
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double s = 0.0;
            for (int k = -2; k <= 2; k++)
                s += g[k + 2] * in[(size_t)y * w + mirror(x + k, w)];
            tmp[(size_t)y * w + x] = s;
        }
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double s = 0.0;
            for (int k = -2; k <= 2; k++)
                s += g[k + 2] * tmp[(size_t)mirror(y + k, h) * w + x];
            out[(size_t)y * w + x] = s;
        }
}

static void statistics(const double *b, int w, int h, ms_band *out)
{
    size_t n = (size_t)w * h;
    double mu = 0.0;
    for (size_t i = 0; i < n; i++)
        mu += b[i];
    mu /= (double)n;
    double m2 = 0.0, m3 = 0.0, m4 = 0.0;
    for (size_t i = 0; i < n; i++) {
        double d = b[i] - mu, d2 = d * d;
        m2 += d2;
        m3 += d2 * d;
        m4 += d2 * d2;
    }
    m2 /= (double)n;
    m3 /= (double)n;
    m4 /= (double)n;
    out->log_variance = log(m2 + MS_VARIANCE_FLOOR);
    if (m2 <= VARIANCE_ZERO) {
        out->skewness = 0.0;
        out->log_kurtosis = log(3.0);
        for (int o = 0; o < MS_OFFSETS; o++)
            out->rho[o] = 0.0;
        return;
    }
    out->skewness = m3 / (m2 * sqrt(m2));
    out->log_kurtosis = log(m4 / (m2 * m2));
    for (int o = 0; o < MS_OFFSETS; o++) {
        int dy = OFFSETS[o][0], dx = OFFSETS[o][1];
        double s = 0.0;
        size_t pairs = 0;
        for (int y = 0; y + dy < h; y++)
            for (int x = dx < 0 ? -dx : 0; x < w && x + dx < w; x++) {
                s += (b[(size_t)y * w + x] - mu) * (b[(size_t)(y + dy) * w + x + dx] - mu);
                pairs++;
            }
        out->rho[o] = pairs ? s / (double)pairs / m2 : 0.0;
    }
}

btf_status ms_band_stats(const ms_view *v, int levels, ms_band *out, btf_error *err)
{
    int w = v->w, h = v->h;
    size_t n = (size_t)w * h;
    double *g = btf__alloc(3 * n, sizeof(double), err);
    if (!g)
        return BTF_E_NOMEM;
    double *blur = g + n, *tmp = blur + n;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            g[(size_t)y * w + x] = v->lab[MS_CH * ((size_t)(v->y0 + y) * v->stride + v->x0 + x)];
    for (int l = 0; l < levels; l++) {
        binomial_blur(g, tmp, blur, w, h);
        for (size_t i = 0; i < (size_t)w * h; i++)
            tmp[i] = g[i] - blur[i];
        statistics(tmp, w, h, &out[l]);
        int nw = (w + 1) / 2, nh = (h + 1) / 2;
        for (int y = 0; y < nh; y++)
            for (int x = 0; x < nw; x++)
                g[(size_t)y * nw + x] = blur[(size_t)(2 * y) * w + 2 * x];
        w = nw;
        h = nh;
    }
    free(g);
    return BTF_OK;
}

/* Mean over bands of the mean absolute difference of the band's
 * statistics: log variance (a ratio of contrasts), skewness, log kurtosis
 * and the correlations. */
double ms_structure_distance(const ms_band *a, const ms_band *b, int levels)
{
    double sum = 0.0;
    for (int l = 0; l < levels; l++) {
        double d = fabs(a[l].log_variance - b[l].log_variance) +
                   fabs(a[l].skewness - b[l].skewness) +
                   fabs(a[l].log_kurtosis - b[l].log_kurtosis);
        for (int o = 0; o < MS_OFFSETS; o++)
            d += fabs(a[l].rho[o] - b[l].rho[o]);
        sum += d / (3 + MS_OFFSETS);
    }
    return levels > 0 ? sum / levels : 0.0;
}
