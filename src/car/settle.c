/*
 * settle.c — the fit's settling rule (car/car_fit.c, docs/model.md
 * "Stability"): beyond stability (car/stability.c, the exact test), a
 * fitted band is kept only if a field of its recursion, started from zeros
 * as synthesis starts one, stops growing within a 160 x 192 test field, or
 * its coefficients sum below 1 in magnitude. A stable band that fails it has
 * roots close to the unit circle (from about 0.98): its correlation
 * outreaches the synthesis margins (car/margin.c), so that synthesis misses
 * part of its variance, and the measured choice of the pyramid depth
 * (analyse/levels.c) judges the depths by syntheses. This was the fit's
 * stability criterion until the numerics review of 2026-12, which found that it misses slow
 * growth (a root of 1.002 grows by 1.5 over 192 columns); as a rule of
 * quality on top of the exact test it keeps fits as they were, but where
 * it let an unstable estimate through.
 */
#include "core/core.h"
#include "car/car.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The least |A(w1, w2)|^2 on an n x n grid (n <= 64), by table: the offsets
 * are integers, so every phase is 2 pi k / n for k = (i r + j c) mod n, and
 * n sines and cosines serve the whole grid (the fit asks at every step of
 * its shrinking). A spectral gain 1 / |A|^2 above 1e6 marks a band too
 * near the unit circle for synthesis to settle. */
static double spectrum_min(const btf_car_band *b, int n)
{
    double ct[64], st[64];
    for (int k = 0; k < n; k++) {
        ct[k] = cos(2.0 * 3.14159265358979323846 * k / n);
        st[k] = sin(2.0 * 3.14159265358979323846 * k / n);
    }
    int rr[BTF_CAR_MAX_NEIGHBOURS], cc[BTF_CAR_MAX_NEIGHBOURS];
    for (int s = 0; s < b->n; s++) {
        rr[s] = ((b->offsets[s].row % n) + n) % n;
        cc[s] = ((b->offsets[s].col % n) + n) % n;
    }
    double mn = INFINITY;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            double re = 1.0, im = 0.0;
            for (int s = 0; s < b->n; s++) {
                int k = (i * rr[s] + j * cc[s]) % n;
                re -= b->gamma[s] * ct[k];
                im += b->gamma[s] * st[k];
            }
            double a2 = re * re + im * im;
            if (a2 < mn)
                mn = a2;
        }
    return mn;
}

/* Two doubles at once (SSE2 on x86-64, NEON on arm64; GCC and clang). */
typedef double pair __attribute__((vector_size(16)));

/* dst[x] += g src[x] for x < RECURSION_COLS, two at a time: the compiler
 * does not vectorise this loop by itself at -O2. src ends at least 64
 * cells before dst starts (offsets reach at most 64 columns), so the two
 * never overlap. */
#define RECURSION_COLS 192
static void add_scaled(double *dst, const double *src, double g)
{
    pair gg = {g, g};
    for (int x = 0; x < RECURSION_COLS; x += 2) {
        pair a, b;
        memcpy(&a, dst + x, sizeof a);
        memcpy(&b, src + x, sizeof b);
        a += gg * b;
        memcpy(dst + x, &a, sizeof a);
    }
}

/* Runs the recursion on a rows x cols field of unit noise (zero boundary).
 * A stable model does not grow: neither down the rows (the last quarter of
 * rows against the quarter before) nor along them (the last quarter of
 * columns against the quarter before; the zero boundary only ever lowers
 * the variance near an edge). 1: grows, 0: does not, -1: out of memory. */
static int recursion_grows(const btf_car_band *b)
{
    enum { R = 160, C = RECURSION_COLS, P = 64 /* offsets reach at most 64 (model/model_check.c) */ };
    /* The field within a zero frame of P cells above, left and right, so
     * that the neighbours need no bounds tests (a zero neighbour adds 0). */
    enum { W = C + 2 * P };
    for (int k = 0; k < b->n; k++)
        if (b->offsets[k].row < -P || b->offsets[k].col < -P || b->offsets[k].col > P)
            return 1; /* beyond any model's reach: not a recursion we run */
    double *pad = calloc((size_t)(R + P) * W, sizeof(double));
    double *f = malloc((size_t)R * C * sizeof(double));
    if (!pad || !f) {
        free(pad);
        free(f);
        return -1;
    }
    /* Neighbours on rows above are known for the whole row: their sum is
     * one vector pass per neighbour; only the same-row ones (left of the
     * pixel) make the pass sequential. The split changes the order of the
     * additions, not the verdict (its thresholds are factors of 1.5). */
    long up[BTF_CAR_MAX_NEIGHBOURS], left[BTF_CAR_MAX_NEIGHBOURS];
    double gu[BTF_CAR_MAX_NEIGHBOURS], gl[BTF_CAR_MAX_NEIGHBOURS];
    int n_up = 0, n_left = 0;
    for (int k = 0; k < b->n; k++) {
        if (b->offsets[k].row < 0) {
            up[n_up] = (long)b->offsets[k].row * W + b->offsets[k].col;
            gu[n_up++] = b->gamma[k];
        } else {
            left[n_left] = b->offsets[k].col;
            gl[n_left++] = b->gamma[k];
        }
    }
    btf_rng rng;
    btf__rng_seed(&rng, 12345);
    for (int y = 0; y < R; y++) {
        double *row = pad + (size_t)(y + P) * W + P;
        /* Uniform noise of unit variance is enough to excite growth. */
        for (int x = 0; x < C; x++)
            row[x] = (btf__rng_uniform(&rng) - 0.5) * 3.4641016151377544;
        for (int k = 0; k < n_up; k++)
            add_scaled(row, row + up[k], gu[k]);
        for (int x = 0; x < C; x++) {
            double s = row[x];
            for (int k = 0; k < n_left; k++)
                s += gl[k] * row[x + left[k]];
            row[x] = s;
        }
        memcpy(f + (size_t)y * C, row, C * sizeof(double));
    }
    free(pad);
    double rows1 = 0.0, rows2 = 0.0, cols1 = 0.0, cols2 = 0.0;
    for (int y = R / 2; y < R; y++)
        for (int x = C / 4; x < C; x++) {
            double q = f[y * C + x] * f[y * C + x];
            if (x < 3 * C / 4) {
                if (y < 3 * R / 4)
                    rows1 += q;
                else
                    rows2 += q;
            }
            if (y >= 3 * R / 4) {
                if (x < C / 2)
                    continue;
                if (x < 3 * C / 4)
                    cols1 += q;
                else
                    cols2 += q;
            }
        }
    free(f);
    if (!isfinite(rows1) || !isfinite(rows2) || !isfinite(cols1) || !isfinite(cols2))
        return 1;
    return rows2 > 1.5 * rows1 + 1e-12 || cols2 > 1.5 * cols1 + 1e-12;
}

/* 1 when the band settles, 0 when not, -1 when out of memory (so that a
 * fit under memory pressure fails instead of shrinking for no reason). */
int btf__car_fit_settles(const btf_car_band *b)
{
    double sum = 0.0;
    for (int i = 0; i < b->n; i++)
        sum += fabs(b->gamma[i]);
    if (sum < 1.0)
        return 1;
    if (!(spectrum_min(b, 64) > 1e-6))
        return 0;
    int grows = recursion_grows(b);
    return grows < 0 ? -1 : !grows;
}
