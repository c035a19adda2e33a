/*
 * range_code.c — the coding of the range-map tile (Haindl & Filip 2007,
 * section II.B: the range map of the material's surface) in the model file's
 * RANG section (docs/model-format.md, "RANG: the range-map tile"): the
 * canonical quantisation grid of the heights and the prediction coding of
 * the quantised samples (a plane predictor from three neighbours, residuals
 * zigzag-mapped). model/model_maps.c writes and reads the section with
 * these; declarations in model/range_code.h.
 */
#include "model/range_code.h"

#include <math.h>
#include <stddef.h>

/* The canonical grid of heights in [lo, hi]: the smallest e at which every
 * height floors to k + q with q <= 65535 and k + q + 1 within 24 bits. The
 * condition only coarsens as e grows, and heights decoded from a grid pick
 * the same grid again (docs/model-format.md), so decode(encode(m)) is a
 * fixed point. -1 when no e fits (a span near FLT_MAX). */
int btf__range_grid_choose(double lo, double hi, int *e, int32_t *k)
{
    for (int x = BTF_RANGE_GRID_E_MIN; x <= BTF_RANGE_GRID_E_MAX; x++) {
        double a = floor(ldexp(lo, -x)), b = floor(ldexp(hi, -x));
        if (a >= -BTF_RANGE_GRID_K_LIMIT && b - a <= BTF_RANGE_GRID_Q_MAX &&
            b + 1.0 <= BTF_RANGE_GRID_K_LIMIT) {
            *e = x;
            *k = (int32_t)a;
            return 0;
        }
    }
    return -1;
}

void btf__range_extremes(const float *h, size_t n, float *lo, float *hi)
{
    *lo = *hi = h[0];
    for (size_t i = 1; i < n; i++) {
        *lo = h[i] < *lo ? h[i] : *lo;
        *hi = h[i] > *hi ? h[i] : *hi;
    }
}

int btf__range_snap(float *h, size_t n)
{
    if (n == 0)
        return 0;
    float lo, hi;
    btf__range_extremes(h, n, &lo, &hi);
    int e;
    int32_t k;
    if (btf__range_grid_choose(lo, hi, &e, &k) != 0)
        return -1;
    for (size_t i = 0; i < n; i++)
        h[i] = btf__range_grid_value(e, k, (unsigned)(floor(ldexp(h[i], -e)) - k));
    return 0;
}

float btf__range_grid_value(int e, int32_t k, unsigned q)
{
    return (float)ldexp((double)k + (double)q + 0.5, e);
}

/* The predictor of sample (x, y) from its quantised left, upper and
 * upper-left neighbours (a plane through them, clamped): smooth surfaces
 * leave small residuals, which deflate well. */
unsigned btf__range_predict(const uint16_t *q, int w, int x, int y)
{
    if (y == 0)
        return x == 0 ? 0 : q[x - 1];
    const uint16_t *row = q + (size_t)y * w, *up = row - w;
    if (x == 0)
        return up[0];
    long p = (long)row[x - 1] + up[x] - up[x - 1];
    return p < 0 ? 0 : p > 65535 ? 65535 : (unsigned)p;
}

/* Residual modulo 2^16 as a signed value, zigzag-mapped so that small
 * magnitudes of either sign give small codes: 0, -1, 1, -2 -> 0, 1, 2, 3. */
unsigned btf__range_zigzag(unsigned q, unsigned pred)
{
    unsigned d = (q - pred) & 0xFFFFu;
    return d < 0x8000u ? 2 * d : 2 * (0x10000u - d) - 1;
}

unsigned btf__range_unzigzag(unsigned z, unsigned pred)
{
    unsigned mag = z >> 1;
    unsigned d = (z & 1) ? 0x10000u - mag - 1 : mag;
    return (pred + d) & 0xFFFFu;
}
