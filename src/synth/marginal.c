/*
 * marginal.c — the marginal transfer of synthesis (docs/synthesis.md,
 * "Marginals"): the CAR fields of paper section II.C are linear
 * filters of Gaussian noise, so each collapsed band is Gaussian, where the
 * material's decorrelated channels are skewed. Before the decorrelation is
 * undone each band v goes through a monotone piecewise-linear map from the
 * synthesised band's distribution onto the exemplar's quantiles, and the
 * RGB result is brought into the exemplar's RGB box (btf_shared.h,
 * "Gamut"). btf__marginal_unmix_row does the whole colour step of a row.
 *
 * The model keeps, per band, the exemplar's quantiles at p_j = j / 31 for
 * j = 1..30, and at 1/4096 and 1 - 1/4096 for the first and last; their
 * knots are z_j = synth_mean + synth_sd * N_j, N_j the standard normal
 * quantile of p_j: the map through (z_j, q_j), flat beyond the end knots.
 * Synthesis evaluates that map on a grid made for speed: BTF_MARGIN_SEGS
 * segments of equal width from z_1 to z_30, where it is resampled (linear
 * between the grid's points, which cuts the corners of the model's map at
 * its knots by a small fraction of the range), and the model's own first
 * and last segments beyond (btf_shared.h). The segment of a value is then
 * found by one multiply and a floor, not by comparing it with 30 knots,
 * and its numbers by two in-register permutes of 16-entry tables: the
 * transfer cost as much as the CAR fields with the search, and still a
 * third of them with 32 segments (the lookups dominate).
 * The table is made on the host, in double rounded to float, for the CPU
 * and the GPU (gpu/synth_gpu.c) alike: both then run the formulas of
 * btf_shared.h on the same floats and agree bit for bit.
 */
#include "core/core.h"
#include "synth/synth.h"

#include "btf_shared.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

_Static_assert(BTF_MARGIN_SEGS == 14 && BTF_MARGIN_TABLE == 16 &&
                   sizeof(((btf_marginal_table *)0)->q[0]) == BTF_MARGIN_TABLE * sizeof(float),
               "btf_knot_segment clamps to 14; the table and the AVX2 lookups hold 16");

/* Phi^-1(p_j), made exactly antisymmetric (statistics.NormalDist). */
const double btf__marginal_normal_knots[BTF_MARGIN_KNOTS] = {
    -3.4871041041144313, -1.8485962885014087, -1.5179291595942783, -1.3001534333634233,
    -1.1309776082451579, -0.98916862734063515, -0.86489435868528297, -0.75272879425816974,
    -0.64932391318646587, -0.55244258464677443, -0.460494539103116, -0.37228936046519095,
    -0.28689391692303923, -0.20354423153248624, -0.12158738275048298, -0.04044050856564621,
    0.04044050856564621, 0.12158738275048298, 0.20354423153248624, 0.28689391692303923,
    0.37228936046519095, 0.460494539103116, 0.55244258464677443, 0.64932391318646587,
    0.75272879425816974, 0.86489435868528297, 0.98916862734063515, 1.1309776082451579,
    1.3001534333634233, 1.5179291595942783, 1.8485962885014087, 3.4871041041144313};

/* The model's map of one band at v (double): linear between its knots,
 * flat beyond the ends. */
static double model_map(const double *z, const float *q, double v)
{
    if (!(v > z[0]))
        return q[0];
    if (v >= z[BTF_MARGIN_KNOTS - 1])
        return q[BTF_MARGIN_KNOTS - 1];
    int j = 0;
    while (j + 2 < BTF_MARGIN_KNOTS && z[j + 1] <= v)
        j++;
    double dz = z[j + 1] - z[j];
    double f = dz > 0 ? (v - z[j]) / dz : 1.0;
    return (double)q[j] + f * ((double)q[j + 1] - q[j]);
}

/* The largest rise dq <= want (and >= 0) with q + f * dq <= next for every
 * f <= 1, in float: q + dq itself may round past next. */
static float rise(float q, float want, float next)
{
    float dq = want;
    while (dq > 0.0f && q + dq > next)
        dq = nextafterf(dq, 0.0f);
    return dq > 0.0f ? dq : 0.0f;
}

void btf__marginal_table_make(const btf_subspace_model *sm, btf_marginal_table *t)
{
    enum { S = BTF_MARGIN_SEGS, LOWER = BTF_MARGIN_TABLE - 1, LAST = BTF_MARGIN_KNOTS - 1 };
    memset(t, 0, sizeof *t);
    const btf_marginal *mg = &sm->marginal;
    if (mg->knots != BTF_MARGIN_KNOTS)
        return; /* no transfer: identity, no clamp (format 1.0, 1.1) */
    t->on = 1;
    for (int b = 0; b < 3; b++) {
        const float *q = mg->quantile[b];
        double z[BTF_MARGIN_KNOTS];
        for (int j = 0; j < BTF_MARGIN_KNOTS; j++)
            z[j] = (double)mg->synth_mean[b] + (double)mg->synth_sd[b] * btf__marginal_normal_knots[j];
        t->qmin[b] = q[0], t->qmax[b] = q[LAST];
        double ih = (double)S / (z[LAST - 1] - z[1]);
        if (!(ih > 0 && ih <= 1e30)) {
            /* sd 0 (or below 1e-30 of the range): every v on one point, the
             * exemplar's median; t is 0 whatever v is */
            for (int k = 0; k < BTF_MARGIN_TABLE; k++)
                t->q[b][k] = (float)(0.5 * ((double)q[15] + q[16]));
            continue;
        }
        float o = (float)z[1], h = (float)ih;
        t->origin[b] = o, t->inv_h[b] = h;
        /* where the end knots fall, by the very float operations of
         * btf_knot_pos */
        float z0 = (float)z[0], zn = (float)z[LAST];
        float tlo = (z0 - o) * h, thi = (zn - o) * h;
        tlo = tlo < -1.0f ? tlo : -1.0f, thi = thi > (float)S ? thi : (float)S;
        t->tlo[b] = tlo, t->thi[b] = thi;
        /* grid point k (t = k) at the model's map; the tails continue the
         * model's first and last segments */
        float val[S + 1];
        for (int k = 0; k <= S; k++)
            val[k] = (float)model_map(z, q, (double)o + k / (double)h);
        for (int k = 0; k < S; k++) {
            t->q[b][k] = val[k];
            t->dq[b][k] = rise(val[k], val[k + 1] - val[k], val[k + 1]);
        }
        /* upper tail: from val[S] at t = S to q_last at thi */
        t->q[b][S] = val[S];
        t->dq[b][S] = thi > (float)S ? (float)(((double)q[LAST] - val[S]) / ((double)thi - S))
                                     : 0.0f;
        if (!(t->dq[b][S] >= 0.0f))
            t->dq[b][S] = 0.0f;
        /* lower tail: f = t + 1 in [tlo + 1, 1), from q_0 at tlo up to
         * val[0] at t = 0 */
        double sl = tlo < -1.0f ? ((double)val[0] - q[0]) / (-(double)tlo) : 0.0;
        float sf = sl > 0 && sl < FLT_MAX ? (float)sl : 0.0f;
        float ql = (float)((double)val[0] - sf);
        t->q[b][LOWER] = ql;
        t->dq[b][LOWER] = rise(ql, sf, val[0]);
    }
    for (int k = 0; k < 3; k++) {
        t->mean[k] = sm->mean[k];
        t->lo[k] = mg->rgb_lo[k];
        t->hi[k] = mg->rgb_hi[k];
        t->nlo[k] = (float)((double)sm->mean[k] - mg->rgb_lo[k]);
        t->nhi[k] = (float)((double)mg->rgb_hi[k] - sm->mean[k]);
    }
}

/* The transfer of band b at v (finite or not: the caller tests), written
 * without branches so that the compiler can keep a row's loop free of
 * mispredictions (a branchy version took 8 ns per value): floor(x) from a
 * conversion to int (floorf is a call into libm on plain x86-64), exact as
 * x is clamped to [tlo, thi], small; NaN taken as tlo for the conversion
 * (the result is NaN all the same); the entry fl & 15 (the lower tail's
 * -1 is 15). */
static inline float transfer1(const btf_marginal_table *t, int b, float v)
{
    float x = btf_knot_pos(v, t->origin[b], t->inv_h[b], t->tlo[b], t->thi[b]);
    float xs = x > t->tlo[b] ? x : t->tlo[b]; /* x, or tlo for NaN (a maxss) */
    float tr = (float)(int)xs;
    float fl = btf_knot_segment(tr - (float)(tr > xs)); /* no branch to mispredict */
    unsigned i = (unsigned)(int)fl & 15u;
    return btf_transfer(x, fl, t->q[b][i], t->dq[b][i], t->qmin[b], t->qmax[b]);
}

int btf__marginal_row(const btf_marginal_table *t, int band, const float *v, int width, float *out)
{
    uint32_t bad = 0;
    for (int x = 0; x < width; x++) {
        bad |= btf_nonfinite_bits(v[x]);
        out[x] = transfer1(t, band, v[x]);
    }
    return bad != 0;
}

/* One colour into the box (btf_shared.h, "Gamut"): as gpu/synth_unmix.comp. */
void btf__marginal_gamut(const btf_marginal_table *t, float c[3])
{
    if (btf_in_box(c[0], t->lo[0], t->hi[0]) && btf_in_box(c[1], t->lo[1], t->hi[1]) &&
        btf_in_box(c[2], t->lo[2], t->hi[2]))
        return;
    float s = 1.0f;
    for (int k = 0; k < 3; k++) {
        float sk = btf_gamut_share(c[k], t->mean[k], t->lo[k], t->hi[k], t->nlo[k], t->nhi[k]);
        s = sk < s ? sk : s;
    }
    s = s < 0.0f ? 0.0f : s;
    for (int k = 0; k < 3; k++) {
        float d = c[k] - t->mean[k]; /* one rounding (no contraction), as the shader's precise */
        c[k] = btf_clampf(btf_gamut_point(t->mean[k], s, d), t->lo[k], t->hi[k]);
    }
}

/* The colour step of pixels [x0, width), 64 at a time: the bands' transfers
 * in loops over the pixels, then per pixel the unmix, the gamut (a test
 * that rarely fails, then btf__marginal_gamut) and the interleave. */
static int unmix_row_portable(const btf_subspace_model *sm, const btf_marginal_table *t,
                              const float *const *band, int x0, int width, float *row)
{
    uint32_t bad = 0;
    float v[3][64];
    for (int c0 = x0; c0 < width; c0 += 64) {
        int n = width - c0 < 64 ? width - c0 : 64;
        for (int b = 0; b < 3; b++)
            for (int i = 0; i < n; i++) {
                bad |= btf_nonfinite_bits(band[b][c0 + i]);
                v[b][i] = transfer1(t, b, band[b][c0 + i]);
            }
        for (int i = 0; i < n; i++) {
            float c[3];
            for (int k = 0; k < 3; k++)
                c[k] = btf_unmix(sm->mean[k], sm->basis[k], sm->basis[3 + k], sm->basis[6 + k],
                                 v[0][i], v[1][i], v[2][i]);
            btf__marginal_gamut(t, c);
            for (int k = 0; k < 3; k++)
                row[3 * (c0 + i) + k] = c[k];
        }
    }
    return bad != 0;
}

#ifdef SYNTH_HAVE_AVX2
#pragma GCC push_options
#pragma GCC target("avx2")
#include <immintrin.h>

#include "rgb8_avx2.h"

/* table[i & 15] for 16-entry tables held in two vectors: two in-register
 * permutes (by the low 3 bits) and a blend (by bit 3, as sign bit m)
 * instead of a gather (a pair of gathers cost as much as two 32-entry
 * lookups, and those as much as the rest of the colour step); the same
 * value is fetched, so the bits do not change. */
static inline __m256 lookup16(const __m256 tab[2], __m256i i, __m256 m)
{
    return _mm256_blendv_ps(_mm256_permutevar8x32_ps(tab[0], i),
                            _mm256_permutevar8x32_ps(tab[1], i), m);
}

typedef struct band_avx2 {
    __m256 origin, ih, tlo, thi, qmin, qmax, q[2], dq[2];
} band_avx2;

/* btf_knot_pos, btf_knot_segment, the entry, btf_transfer: the same operations
 * (no FMA), the clamps as max(lo, v) and min(hi, a), which are the
 * comparisons `v < lo ? lo : v` and `a > hi ? hi : a` lane by lane, signed
 * zeros included; the lower tail's -1 is entry 15 by its low bits. */
static inline __m256 transfer8(const band_avx2 *bt, __m256 v)
{
    const __m256 minus1 = _mm256_set1_ps(-1.0f), segs = _mm256_set1_ps((float)BTF_MARGIN_SEGS);
    __m256 x = _mm256_mul_ps(_mm256_sub_ps(v, bt->origin), bt->ih);
    x = _mm256_min_ps(bt->thi, _mm256_max_ps(bt->tlo, x));
    __m256 fl = _mm256_min_ps(segs, _mm256_max_ps(minus1, _mm256_floor_ps(x)));
    __m256i i = _mm256_cvttps_epi32(fl);
    __m256 m = _mm256_castsi256_ps(_mm256_slli_epi32(i, 28));
    __m256 q = lookup16(bt->q, i, m), dq = lookup16(bt->dq, i, m);
    __m256 r = _mm256_add_ps(q, _mm256_mul_ps(_mm256_sub_ps(x, fl), dq));
    return _mm256_min_ps(bt->qmax, _mm256_max_ps(bt->qmin, r));
}

/* btf__marginal_gamut on 8 colours, applied where `out` is set: each
 * btf_gamut_share and btf_recip step as a vector op in the shared order;
 * `d < 0 ? -d : d` as a blend, the min and max as in transfer8. */
static inline void gamut8(const btf_marginal_table *t, __m256 c[3], __m256 out)
{
    const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
    const __m256 two = _mm256_set1_ps(2.0f);
    const __m256 rmin = _mm256_set1_ps(BTF_RECIP_MIN), rmax = _mm256_set1_ps(BTF_RECIP_MAX);
    const __m256i magic = _mm256_set1_epi32(0x7EF311C7);
    __m256 s = one, d[3];
    for (int k = 0; k < 3; k++) {
        __m256 mean = _mm256_set1_ps(t->mean[k]);
        __m256 lo = _mm256_set1_ps(t->lo[k]), hi = _mm256_set1_ps(t->hi[k]);
        d[k] = _mm256_sub_ps(c[k], mean);
        __m256 ad = _mm256_blendv_ps(d[k], _mm256_sub_ps(zero, d[k]),
                                     _mm256_cmp_ps(d[k], zero, _CMP_LT_OQ));
        __m256 x = _mm256_min_ps(rmax, _mm256_max_ps(rmin, ad));
        __m256 r = _mm256_castsi256_ps(_mm256_sub_epi32(magic, _mm256_castps_si256(x)));
        for (int n = 0; n < 3; n++)
            r = _mm256_mul_ps(r, _mm256_sub_ps(two, _mm256_mul_ps(x, r)));
        __m256 above = _mm256_cmp_ps(c[k], hi, _CMP_GT_OQ);
        __m256 below = _mm256_cmp_ps(c[k], lo, _CMP_LT_OQ);
        __m256 num = _mm256_blendv_ps(_mm256_set1_ps(t->nlo[k]), _mm256_set1_ps(t->nhi[k]),
                                      above);
        __m256 sk = _mm256_blendv_ps(one, _mm256_mul_ps(num, r), _mm256_or_ps(above, below));
        s = _mm256_min_ps(sk, s); /* sk < s ? sk : s */
    }
    s = _mm256_max_ps(zero, s); /* s < 0 ? 0 : s */
    for (int k = 0; k < 3; k++) {
        __m256 lo = _mm256_set1_ps(t->lo[k]), hi = _mm256_set1_ps(t->hi[k]);
        __m256 p = _mm256_add_ps(_mm256_set1_ps(t->mean[k]), _mm256_mul_ps(s, d[k]));
        p = _mm256_min_ps(hi, _mm256_max_ps(lo, p));
        c[k] = _mm256_blendv_ps(c[k], p, out);
    }
}

/* The colour step, 8 pixels at a time, all in registers: the three
 * transfers, btf_unmix's multiplies and adds in its order, the box test
 * (gamut8 only for the vectors with a colour outside, a few percent of
 * them), and the RGB interleave (btf_rgb8_store, rgb8_avx2.h) straight
 * into the row. Returns the pixels done (a multiple of 8). */
static int unmix_row_avx2(const btf_subspace_model *sm, const btf_marginal_table *t,
                          const float *const *band, int width, float *row, int *bad_out)
{
    band_avx2 bt[3];
    __m256 mean[3], c0[3], c1[3], c2[3], lo[3], hi[3];
    for (int b = 0; b < 3; b++) {
        bt[b].origin = _mm256_set1_ps(t->origin[b]);
        bt[b].ih = _mm256_set1_ps(t->inv_h[b]);
        bt[b].tlo = _mm256_set1_ps(t->tlo[b]);
        bt[b].thi = _mm256_set1_ps(t->thi[b]);
        bt[b].qmin = _mm256_set1_ps(t->qmin[b]);
        bt[b].qmax = _mm256_set1_ps(t->qmax[b]);
        for (int k = 0; k < 2; k++) {
            bt[b].q[k] = _mm256_loadu_ps(t->q[b] + 8 * k);
            bt[b].dq[k] = _mm256_loadu_ps(t->dq[b] + 8 * k);
        }
    }
    for (int k = 0; k < 3; k++) {
        mean[k] = _mm256_set1_ps(sm->mean[k]);
        c0[k] = _mm256_set1_ps(sm->basis[k]);
        c1[k] = _mm256_set1_ps(sm->basis[3 + k]);
        c2[k] = _mm256_set1_ps(sm->basis[6 + k]);
        lo[k] = _mm256_set1_ps(t->lo[k]);
        hi[k] = _mm256_set1_ps(t->hi[k]);
    }
    /* the finite test as the largest magnitude's bits (and, unsigned max):
     * Inf or NaN when they reach the exponent's all-ones */
    const __m256i magn = _mm256_set1_epi32(0x7FFFFFFF);
    __m256i bad = _mm256_setzero_si256();
    int x = 0;
    for (; x + 8 <= width; x += 8) {
        __m256 v[3], ch[3];
        for (int b = 0; b < 3; b++) {
            __m256 in = _mm256_loadu_ps(band[b] + x);
            bad = _mm256_max_epu32(bad, _mm256_and_si256(_mm256_castps_si256(in), magn));
            v[b] = transfer8(&bt[b], in);
        }
        __m256 inside = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
        for (int k = 0; k < 3; k++) {
            __m256 s = _mm256_add_ps(mean[k], _mm256_mul_ps(c0[k], v[0]));
            s = _mm256_add_ps(s, _mm256_mul_ps(c1[k], v[1]));
            ch[k] = _mm256_add_ps(s, _mm256_mul_ps(c2[k], v[2]));
            inside = _mm256_and_ps(inside, _mm256_and_ps(_mm256_cmp_ps(ch[k], lo[k], _CMP_GE_OQ),
                                                         _mm256_cmp_ps(ch[k], hi[k], _CMP_LE_OQ)));
        }
        if (_mm256_movemask_ps(inside) != 0xFF)
            gamut8(t, ch, _mm256_xor_ps(inside, _mm256_castsi256_ps(_mm256_set1_epi32(-1))));
        btf_rgb8_store(ch, row + 3 * x);
    }
    bad = _mm256_cmpgt_epi32(bad, _mm256_set1_epi32(0x7F7FFFFF));
    *bad_out = !_mm256_testz_si256(bad, bad);
    return x;
}
#pragma GCC pop_options
#endif

int btf__marginal_unmix_row(const btf_subspace_model *sm, const btf_marginal_table *t,
                            const float *b0, const float *b1, const float *b2, int width,
                            float *row)
{
    const float *band[3] = {b0, b1, b2};
    int x = 0, bad = 0;
#ifdef SYNTH_HAVE_AVX2
    if (__builtin_cpu_supports("avx2") && !t->portable)
        x = unmix_row_avx2(sm, t, band, width, row, &bad);
#endif
    return unmix_row_portable(sm, t, band, x, width, row) | bad;
}
