/*
 * margin.c — how far outside its window a CAR field must start so that the
 * window is stationary from its first pixel (paper section II.C: the model
 * is stationary; synthesis must not show the zero boundary).
 *
 * A synthesised field starts from zeros BTF margin rows above its window and
 * runs that many extra columns on either side. The boundary's effect on a
 * window pixel is what the field's impulse response carries over that
 * distance: with h the response of the recursion Y_r = sum_s gamma_s Y_{r+s}
 * + e_r to a unit impulse, the stationary variance is sigma^2 sum h^2 and a
 * pixel m rows or columns from the boundary misses about the part of that
 * sum beyond m. The margin is the smallest m (a multiple of
 * BTF_SYNTH_MARGIN_MIN, at least twice the neighbourhood's reach) whose
 * missing part is below BTF_SYNTH_MARGIN_EPS of the whole, capped at
 * BTF_SYNTH_MARGIN_MAX: found by doubling, then by bisection between the
 * last two powers of two (a band that needs 130 rows costs 136, not 256:
 * margins are a large part of the pixels synthesised when the bands are
 * strongly correlated). A weakly correlated band (most of them) needs 8 or
 * 16 pixels, a strongly correlated one more, up to 256: a margin per band
 * costs each band only what its own correlation needs, where one fixed
 * margin would be too much for most and too little for some. A band that
 * needs more than the cap (a nearly unstable one) is synthesised with 256
 * and its first rows fall short of the stationary variance: fitting warns
 * of it (btf__car_margin_shortfall).
 *
 * The response is computed in double on a grid of 2m + 1 rows and 4m + 1
 * columns with the synthesis' own zero boundary, so the estimate includes
 * what the boundary does. The result depends on the band alone, never on
 * the output size, tiling or backend: CPU and GPU (gpu/synth_gpu.c) call
 * this same function and stay bit-identical. A model keeps the margins of
 * its bands (src/model/model_margins.c) so that synthesis computes them
 * once.
 */
#include "core/core.h"
#include "car/car.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

/* The larger of the neighbourhood's row and column reach. */
static int band_reach(const btf_car_band *b)
{
    int r = 0;
    for (int s = 0; s < b->n; s++) {
        int dr = abs(b->offsets[s].row), dc = abs(b->offsets[s].col);
        r = dr > r ? dr : r;
        r = dc > r ? dc : r;
    }
    return r;
}

/* The share of the impulse response's energy lying outside rows [0, m],
 * columns [-m, m], the response computed on rows [0, 2m] and columns
 * [-2m, 2m] (zeros beyond, as in synthesis): 1 for a growing response, -1
 * when the grid cannot be allocated. The grid carries `reach` zero rows
 * above and columns on either side, so the sum needs no bounds checks. */
static double outside_share(const btf_car_band *b, int m, int reach)
{
    int rows = 2 * m + 1, cols = 4 * m + 1, c0 = 2 * m;
    size_t stride = (size_t)cols + 2 * reach;
    double *h = calloc((size_t)(rows + reach) * stride, sizeof *h);
    if (!h)
        return -1.0;
    ptrdiff_t off[BTF_CAR_MAX_NEIGHBOURS];
    double gam[BTF_CAR_MAX_NEIGHBOURS];
    for (int s = 0; s < b->n; s++) {
        off[s] = (ptrdiff_t)b->offsets[s].row * (ptrdiff_t)stride + b->offsets[s].col;
        gam[s] = b->gamma[s];
    }
    double total = 0.0, inside = 0.0;
    for (int r = 0; r < rows && total < 1e300; r++) { /* a blow-up ends it early */
        double *row = h + (size_t)(r + reach) * stride + reach;
        for (int c = 0; c < cols; c++) {
            double v = (r == 0 && c == c0) ? 1.0 : 0.0;
            for (int s = 0; s < b->n; s++)
                v += gam[s] * row[c + off[s]];
            row[c] = v;
            double e = v * v;
            total += e;
            if (r <= m && abs(c - c0) <= m)
                inside += e;
        }
    }
    free(h);
    if (!(total < 1e300))
        return 1.0; /* a growing response (or NaN coefficients): all of it is outside */
    return (total - inside) / total;
}

/* The work of testing margin m: grid cells times neighbours. */
static double test_work(const btf_car_band *b, int m)
{
    return (2.0 * m + 1.0) * (4.0 * m + 1.0) * (b->n + 1);
}

/* Whether margin m leaves at most BTF_SYNTH_MARGIN_EPS outside: 1 yes, 0
 * no, -1 out of memory, -2 out of budget (budget NULL: none). */
static int margin_enough(const btf_car_band *b, int m, int reach, double *budget)
{
    if (budget) {
        if (*budget < test_work(b, m))
            return -2;
        *budget -= test_work(b, m);
    }
    double share = outside_share(b, m, reach);
    if (share < 0.0)
        return -1;
    return share <= BTF_SYNTH_MARGIN_EPS;
}

int btf__car_margin_within(const btf_car_band *b, double *budget)
{
    if (b->n == 0)
        return 0; /* white noise: no memory, no transient */
    int m = BTF_SYNTH_MARGIN_MIN, reach = band_reach(b);
    while (m < 2 * reach && m < BTF_SYNTH_MARGIN_MAX)
        m *= 2;
    int first = m, ok = 0;
    for (;; m *= 2) {
        ok = margin_enough(b, m, reach, budget);
        if (ok == -2)
            return BTF_SYNTH_MARGIN_MAX; /* out of budget: the safe answer */
        if (ok < 0)
            return -1;
        if (ok || m >= BTF_SYNTH_MARGIN_MAX)
            break;
    }
    if (!ok || m == first)
        return m; /* the cap (not enough: fitting warns), or the least allowed */
    /* m is enough and m / 2 is not: bisect in steps of the minimum. */
    int lo = m / 2, hi = m;
    while (hi - lo > BTF_SYNTH_MARGIN_MIN) {
        int mid = (lo + hi) / 2 / BTF_SYNTH_MARGIN_MIN * BTF_SYNTH_MARGIN_MIN;
        int r = margin_enough(b, mid, reach, budget);
        if (r == -2)
            return hi; /* enough, if not the least */
        if (r < 0)
            return -1;
        if (r)
            hi = mid;
        else
            lo = mid;
    }
    return hi;
}

int btf__car_margin(const btf_car_band *b)
{
    return btf__car_margin_within(b, NULL);
}

double btf__car_margin_shortfall(const btf_car_band *b, int m)
{
    if (b->n == 0)
        return 0.0;
    return outside_share(b, m, band_reach(b));
}
