/*
 * colour.c — the last step of synthesis (Haindl & Filip 2007, section
 * II.C, after the pyramid collapse): the spectral decorrelation of the
 * analysis undone, rgb_k = mean_k + sum_b basis[b][k] band_b, row by row,
 * with the test that no Inf or NaN leaves the library. The formula is
 * btf_unmix of src/synth/btf_shared.h, as in the GPU shader
 * gpu/synth_unmix.comp; the AVX2 loop performs its operations in the same
 * order, so every path gives the same bits. With a marginal transfer
 * the whole colour step is src/synth/marginal.c's (btf__marginal_unmix_row).
 */
#include "core/core.h"
#include "synth/synth.h"

#include "btf_shared.h"

#include <stdint.h>
#include <string.h>

#if defined(__GNUC__) && !defined(__clang__)
typedef float v4f __attribute__((vector_size(16)));
typedef int32_t v4i __attribute__((vector_size(16)));
#endif

/* Interleaves three planes into RGB triples. With GCC: four pixels at a
 * time with shuffles (a scalar loop costs a store per value). */
static void interleave3(const float *p0, const float *p1, const float *p2, int width, float *row)
{
    int x = 0;
#if defined(__GNUC__) && !defined(__clang__)
    for (; x + 4 <= width; x += 4) {
        v4f a, b, c;
        memcpy(&a, p0 + x, sizeof a);
        memcpy(&b, p1 + x, sizeof b);
        memcpy(&c, p2 + x, sizeof c);
        v4f ab_lo = __builtin_shuffle(a, b, (v4i){0, 4, 1, 5}); /* a0 b0 a1 b1 */
        v4f ab_hi = __builtin_shuffle(a, b, (v4i){2, 6, 3, 7}); /* a2 b2 a3 b3 */
        v4f o0 = __builtin_shuffle(ab_lo, c, (v4i){0, 1, 4, 2}); /* a0 b0 c0 a1 */
        v4f t = __builtin_shuffle(ab_lo, c, (v4i){3, 5, 3, 5});  /* b1 c1 . . */
        v4f o1 = __builtin_shuffle(t, ab_hi, (v4i){0, 1, 4, 5}); /* b1 c1 a2 b2 */
        v4f o2 = __builtin_shuffle(c, ab_hi, (v4i){2, 6, 7, 3}); /* c2 a3 b3 c3 */
        memcpy(row + 3 * x, &o0, sizeof o0);
        memcpy(row + 3 * x + 4, &o1, sizeof o1);
        memcpy(row + 3 * x + 8, &o2, sizeof o2);
    }
#endif
    for (; x < width; x++) {
        row[3 * x] = p0[x];
        row[3 * x + 1] = p1[x];
        row[3 * x + 2] = p2[x];
    }
}

/* Inverse decorrelation of one row (btf_unmix per channel): channel by
 * channel into planes, with the finite test folded in (loops the compiler
 * vectorises), then interleaved. Returns nonzero when a value is Inf or NaN
 * (all exponent bits set). */
SYNTH_AVX2_CLONES
static int unmix_planar(const btf_subspace_model *sm, const float *b0, const float *b1,
                        const float *b2, int width, float *plane, float *row)
{
    uint32_t bad = 0;
    for (int k = 0; k < 3; k++) {
        float *p = plane + (size_t)k * width;
        float mean = sm->mean[k], c0 = sm->basis[k], c1 = sm->basis[3 + k];
        float c2 = sm->basis[6 + k];
        for (int x = 0; x < width; x++) {
            float v = btf_unmix(mean, c0, c1, c2, b0[x], b1[x], b2[x]);
            bad |= btf_nonfinite_bits(v);
            p[x] = v;
        }
    }
    interleave3(plane, plane + width, plane + 2 * (size_t)width, width, row);
    return bad != 0;
}

#ifdef SYNTH_HAVE_AVX2
#pragma GCC push_options
#pragma GCC target("avx2")
#include <immintrin.h>

#include "rgb8_avx2.h"

/* unmix_planar in one pass with AVX2, 8 pixels at a time: btf_unmix's
 * multiplies and adds in its order (no FMA: the build forbids contraction
 * and no intrinsic here asks for it), the finite test, and the RGB
 * interleave (btf_rgb8_store, rgb8_avx2.h) straight into the row; the
 * last width % 8 pixels go through unmix_planar. Same bits. */
static int unmix_avx2(const btf_subspace_model *sm, const float *b0, const float *b1,
                      const float *b2, int width, float *plane, float *row)
{
    __m256 mean[3], c0[3], c1[3], c2[3];
    for (int k = 0; k < 3; k++) {
        mean[k] = _mm256_set1_ps(sm->mean[k]);
        c0[k] = _mm256_set1_ps(sm->basis[k]);
        c1[k] = _mm256_set1_ps(sm->basis[3 + k]);
        c2[k] = _mm256_set1_ps(sm->basis[6 + k]);
    }
    const __m256i expo = _mm256_set1_epi32(0x7F800000);
    /* lane i of out k takes its channel from the permuted a, b or c */
    __m256i bad = _mm256_setzero_si256();
    int x = 0;
    for (; x + 8 <= width; x += 8) {
        __m256 v0 = _mm256_loadu_ps(b0 + x), v1 = _mm256_loadu_ps(b1 + x);
        __m256 v2 = _mm256_loadu_ps(b2 + x), ch[3];
        for (int k = 0; k < 3; k++) {
            __m256 s = _mm256_add_ps(mean[k], _mm256_mul_ps(c0[k], v0));
            s = _mm256_add_ps(s, _mm256_mul_ps(c1[k], v1));
            ch[k] = _mm256_add_ps(s, _mm256_mul_ps(c2[k], v2));
            __m256i e = _mm256_and_si256(_mm256_castps_si256(ch[k]), expo);
            bad = _mm256_or_si256(bad, _mm256_cmpeq_epi32(e, expo));
        }
        btf_rgb8_store(ch, row + 3 * x);
    }
    int tail = x < width ? unmix_planar(sm, b0 + x, b1 + x, b2 + x, width - x, plane,
                                        row + 3 * x) : 0;
    return !_mm256_testz_si256(bad, bad) || tail;
}
#pragma GCC pop_options
#endif

static int unmix_plain(const btf_subspace_model *sm, const float *b0, const float *b1,
                       const float *b2, int width, float *plane, float *row)
{
#ifdef SYNTH_HAVE_AVX2
    if (__builtin_cpu_supports("avx2")) /* a load and a test */
        return unmix_avx2(sm, b0, b1, b2, width, plane, row);
#endif
    return unmix_planar(sm, b0, b1, b2, width, plane, row);
}

int btf__unmix_row(const btf_subspace_model *sm, const btf_marginal_table *t, const float *b0,
                   const float *b1, const float *b2, int width, float *scratch, float *row)
{
    if (!t || !t->on)
        return unmix_plain(sm, b0, b1, b2, width, scratch, row);
    if (!btf__marginal_unmix_row(sm, t, b0, b1, b2, width, row))
        return 0;
    /* A band is Inf or NaN: the row without the transfer, which carries it
     * into the colours, so that the caller's finite test refuses the image
     * (the GPU skips the transfer of such a pixel, gpu/synth_unmix.comp). */
    return unmix_plain(sm, b0, b1, b2, width, scratch, row);
}

int btf__any_nonfinite(const float *v, size_t n)
{
    uint32_t bad = 0;
    for (size_t i = 0; i < n; i++)
        bad |= btf_nonfinite_bits(v[i]);
    return bad != 0;
}

btf_status btf__check_finite_row(const float *v, size_t n, int subspace, int y, btf_error *err)
{
    if (btf__any_nonfinite(v, n))
        return btf__fail(err, BTF_E_NUMERIC,
                         "synthesis of subspace %d overflowed the float range at row %d "
                         "(the model's values are too large for float images)", subspace, y);
    return BTF_OK;
}
