/*
 * marginal.c — the marginal transfer of synthesis (docs/synthesis.md,
 * "Marginals"; issue 17): the CAR fields of paper section II.C are linear
 * filters of Gaussian noise, so each collapsed band is Gaussian, where the
 * material's decorrelated channels are skewed. Before the decorrelation is
 * undone each band v goes through a monotone piecewise-linear map from the
 * synthesised band's distribution onto the exemplar's quantiles, and the
 * RGB result is brought into the exemplar's RGB box (btf_shared.h,
 * "Gamut"; src/synth/colour.c).
 *
 * Knots: z_j = synth_mean + synth_sd * N_j, N_j the standard normal quantile
 * of p_j = j / 31 for j = 1..30, and of 1/4096 and 1 - 1/4096 for the first
 * and last knot, which carry the exemplar's minimum and maximum. Below z_0
 * and above z_31 the map is flat (the exemplar's range). The table is made
 * once per synthesis on the host, in double rounded to float, for the CPU
 * and the GPU (gpu/synth_gpu.c) alike: both then run btf_transfer of
 * btf_shared.h on the same floats and agree bit for bit.
 */
#include "core/core.h"
#include "synth/synth.h"

#include "btf_shared.h"

#include <float.h>
#include <stdint.h>
#include <string.h>

/* Phi^-1(p_j), made exactly antisymmetric (statistics.NormalDist). */
const double btf_marginal_normal_knots[BTF_MARGIN_KNOTS] = {
    -3.4871041041144313, -1.8485962885014087, -1.5179291595942783, -1.3001534333634233,
    -1.1309776082451579, -0.98916862734063515, -0.86489435868528297, -0.75272879425816974,
    -0.64932391318646587, -0.55244258464677443, -0.460494539103116, -0.37228936046519095,
    -0.28689391692303923, -0.20354423153248624, -0.12158738275048298, -0.04044050856564621,
    0.04044050856564621, 0.12158738275048298, 0.20354423153248624, 0.28689391692303923,
    0.37228936046519095, 0.460494539103116, 0.55244258464677443, 0.64932391318646587,
    0.75272879425816974, 0.86489435868528297, 0.98916862734063515, 1.1309776082451579,
    1.3001534333634233, 1.5179291595942783, 1.8485962885014087, 3.4871041041144313};

void btf_marginal_table_make(const btf_subspace_model *sm, btf_marginal_table *t)
{
    memset(t, 0, sizeof *t);
    const btf_marginal *mg = &sm->marginal;
    if (mg->knots != BTF_MARGIN_KNOTS)
        return; /* no transfer: identity, no clamp (format 1.0, 1.1) */
    t->on = 1;
    for (int b = 0; b < 3; b++) {
        for (int j = 0; j < BTF_MARGIN_KNOTS; j++) {
            t->z[b][j] = (float)((double)mg->synth_mean[b] +
                                 (double)mg->synth_sd[b] * btf_marginal_normal_knots[j]);
            t->q[b][j] = mg->quantile[b][j];
        }
        for (int j = 0; j + 1 < BTF_MARGIN_KNOTS; j++) {
            /* a zero-width segment is never entered (no v has z_j <= v <
             * z_j+1); a slope past the float range is capped, not Inf, so
             * that (v - z) * slope is never 0 * Inf */
            double dz = (double)t->z[b][j + 1] - t->z[b][j];
            double s = dz > 0 ? ((double)t->q[b][j + 1] - t->q[b][j]) / dz : 0.0;
            t->slope[b][j] = s < FLT_MAX ? (float)s : FLT_MAX;
        }
    }
    for (int k = 0; k < 3; k++) {
        t->lo[k] = mg->rgb_lo[k];
        t->hi[k] = mg->rgb_hi[k];
    }
}

static int marginal_row_portable(const btf_marginal_table *t, int band, const float *v,
                                 int width, float *out, int *seg);

static inline uint32_t nonfinite(float v)
{
    uint32_t u;
    memcpy(&u, &v, sizeof u);
    return (uint32_t)((u & 0x7F800000u) == 0x7F800000u);
}

#ifdef SYNTH_HAVE_AVX2
#pragma GCC push_options
#pragma GCC target("avx2")
#include <immintrin.h>

/* btf_marginal_row 8 values at a time: the same count of knots, exact
 * gathers of the segment's numbers, btf_transfer's sub, mul, add (no FMA)
 * and its clamps as max(lo, v) and min(hi, a), which are the comparisons
 * `v < lo ? lo : v` and `a > hi ? hi : a` lane by lane, signed zeros
 * included. The last width % 8 values go through the portable loop. */
/* table[i] for 32-entry tables held in four vectors: four in-register
 * permutes and three blends instead of a gather (a gather of 8 costs about
 * as much as the whole transfer did); the same value is fetched, so the
 * bits do not change. */
static inline __m256 lookup32(const __m256 tab[4], __m256i i)
{
    __m256 a = _mm256_permutevar8x32_ps(tab[0], i), b = _mm256_permutevar8x32_ps(tab[1], i);
    __m256 c = _mm256_permutevar8x32_ps(tab[2], i), d = _mm256_permutevar8x32_ps(tab[3], i);
    __m256i hi = _mm256_srli_epi32(i, 3); /* which vector: 0..3 */
    __m256 m0 = _mm256_castsi256_ps(_mm256_slli_epi32(hi, 31));
    __m256 m1 = _mm256_castsi256_ps(_mm256_slli_epi32(hi, 30));
    return _mm256_blendv_ps(_mm256_blendv_ps(a, b, m0), _mm256_blendv_ps(c, d, m0), m1);
}

static void load32(const float *src, __m256 tab[4])
{
    for (int k = 0; k < 4; k++)
        tab[k] = _mm256_loadu_ps(src + 8 * k);
}

static int marginal_row_avx2(const btf_marginal_table *t, int band, const float *v, int width,
                             float *out, int *seg, int *tail)
{
    const float *z = t->z[band], *q = t->q[band], *sl = t->slope[band];
    __m256 z0 = _mm256_set1_ps(z[0]), zn = _mm256_set1_ps(z[BTF_MARGIN_KNOTS - 1]);
    __m256 zj[BTF_MARGIN_KNOTS];
    for (int j = 0; j < BTF_MARGIN_KNOTS; j++)
        zj[j] = _mm256_set1_ps(z[j]);
    /* q shifted by one: q1[i] = q[i + 1] (the segment index is at most 30) */
    float q1s[BTF_MARGIN_KNOTS];
    for (int j = 0; j + 1 < BTF_MARGIN_KNOTS; j++)
        q1s[j] = q[j + 1];
    q1s[BTF_MARGIN_KNOTS - 1] = q[BTF_MARGIN_KNOTS - 1];
    __m256 tz[4], ts[4], tq[4], tq1[4];
    load32(z, tz);
    load32(sl, ts);
    load32(q, tq);
    load32(q1s, tq1);
    const __m256i expo = _mm256_set1_epi32(0x7F800000);
    __m256i bad = _mm256_setzero_si256();
    int x = 0;
    for (; x + 8 <= width; x += 8) {
        __m256 in = _mm256_loadu_ps(v + x);
        __m256i e = _mm256_and_si256(_mm256_castps_si256(in), expo);
        bad = _mm256_or_si256(bad, _mm256_cmpeq_epi32(e, expo));
        __m256 c = _mm256_min_ps(zn, _mm256_max_ps(z0, in));
        /* the count of interior knots at or below c, in two independent
         * halves (a true compare is -1) */
        __m256i i0 = _mm256_setzero_si256(), i1 = _mm256_setzero_si256();
        for (int j = 1; j + 1 < BTF_MARGIN_KNOTS; j += 2) {
            i0 = _mm256_sub_epi32(i0, _mm256_castps_si256(_mm256_cmp_ps(zj[j], c, _CMP_LE_OQ)));
            if (j + 2 < BTF_MARGIN_KNOTS)
                i1 = _mm256_sub_epi32(i1, _mm256_castps_si256(
                                              _mm256_cmp_ps(zj[j + 1], c, _CMP_LE_OQ)));
        }
        __m256i i = _mm256_add_epi32(i0, i1);
        __m256 zi = lookup32(tz, i), si = lookup32(ts, i);
        __m256 qi = lookup32(tq, i), qn = lookup32(tq1, i);
        __m256 r = _mm256_add_ps(qi, _mm256_mul_ps(_mm256_sub_ps(c, zi), si));
        _mm256_storeu_ps(out + x, _mm256_min_ps(qn, _mm256_max_ps(qi, r)));
    }
    *tail = x;
    (void)seg;
    return !_mm256_testz_si256(bad, bad);
}
#pragma GCC pop_options
#endif

/* The segment index is a count of interior knots at or below v: the same
 * index a search would give, in loops over the row the compiler
 * vectorises (by hand with AVX2). */
int btf_marginal_row(const btf_marginal_table *t, int band, const float *v, int width,
                     float *out, int *seg)
{
#ifdef SYNTH_HAVE_AVX2
    if (__builtin_cpu_supports("avx2")) {
        int done = 0, bad = marginal_row_avx2(t, band, v, width, out, seg, &done);
        if (done == width)
            return bad;
        return marginal_row_portable(t, band, v + done, width - done, out + done, seg) | bad;
    }
#endif
    return marginal_row_portable(t, band, v, width, out, seg);
}

static int marginal_row_portable(const btf_marginal_table *t, int band, const float *v,
                                 int width, float *out, int *seg)
{
    const float *z = t->z[band], *q = t->q[band], *sl = t->slope[band];
    float z0 = z[0], zn = z[BTF_MARGIN_KNOTS - 1];
    uint32_t bad = 0;
    for (int x = 0; x < width; x++) {
        bad |= nonfinite(v[x]);
        out[x] = btf_clampf(v[x], z0, zn);
        seg[x] = 0;
    }
    for (int j = 1; j + 1 < BTF_MARGIN_KNOTS; j++) {
        float zj = z[j];
        for (int x = 0; x < width; x++)
            seg[x] += zj <= out[x];
    }
    for (int x = 0; x < width; x++) {
        int i = seg[x];
        out[x] = btf_transfer(out[x], z[i], sl[i], q[i], q[i + 1]);
    }
    return bad != 0;
}

/* One colour into the box (btf_shared.h, "Gamut"): as gpu/synth_unmix.comp. */
static void gamut_pixel(const btf_marginal_table *t, const float mean[3], float *c)
{
    if (btf_in_box(c[0], t->lo[0], t->hi[0]) && btf_in_box(c[1], t->lo[1], t->hi[1]) &&
        btf_in_box(c[2], t->lo[2], t->hi[2]))
        return;
    float d[3];
    for (int k = 0; k < 3; k++)
        d[k] = c[k] - mean[k]; /* one rounding (no contraction), as the shader's precise */
    float a = 0.0f, b = 1.0f;
    for (int s = 0; s < BTF_GAMUT_STEPS; s++) {
        float m = btf_midpoint(a, b);
        int in = 1;
        for (int k = 0; k < 3; k++)
            in &= btf_in_box(btf_gamut_point(mean[k], m, d[k]), t->lo[k], t->hi[k]);
        if (in)
            a = m;
        else
            b = m;
    }
    for (int k = 0; k < 3; k++)
        c[k] = btf_clampf(btf_gamut_point(mean[k], a, d[k]), t->lo[k], t->hi[k]);
}

/* Planar: a vectorised test of the box, the rare colours outside it one by
 * one (gamut_pixel). */
SYNTH_AVX2_CLONES
void btf_marginal_gamut_planes(const btf_marginal_table *t, const float mean[3], float *p0,
                               float *p1, float *p2, int width)
{
    float l0 = t->lo[0], l1 = t->lo[1], l2 = t->lo[2];
    float h0 = t->hi[0], h1 = t->hi[1], h2 = t->hi[2];
    for (int x0 = 0; x0 < width; x0 += 64) {
        int x1 = x0 + 64 < width ? x0 + 64 : width, out = 0;
        for (int x = x0; x < x1; x++)
            out |= !(btf_in_box(p0[x], l0, h0) & btf_in_box(p1[x], l1, h1) &
                     btf_in_box(p2[x], l2, h2));
        if (!out)
            continue;
        for (int x = x0; x < x1; x++) {
            float c[3] = {p0[x], p1[x], p2[x]};
            gamut_pixel(t, mean, c);
            p0[x] = c[0], p1[x] = c[1], p2[x] = c[2];
        }
    }
}
