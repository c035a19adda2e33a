/*
 * upsample.c — pyrUp on streamed rows, the step of the pyramid collapse
 * (Haindl & Filip 2007, section II.C: the synthesised sub-band levels are
 * recombined, G_l = mean_l + Y_l + up(G_{l+1})): a coarse row up-sampled
 * horizontally to the finer level's window (btf__up_row), and the vertical
 * pass that adds the coarse rows to a field row (btf__level_sum_row). The
 * weights are those of btf_up_even and btf_up_odd (src/synth/btf_shared.h),
 * which the GPU shader gpu/synth_collapse.comp uses too: the same bits.
 */
#include "synth/synth.h"

#include "btf_shared.h"

#ifdef SYNTH_HAVE_AVX2
#pragma GCC push_options
#pragma GCC target("avx2")
#include <immintrin.h>

/* btf__up_row's column pairs with AVX2: fine columns 2j and 2j + 1 from coarse
 * cc[j - 1 .. j + 1], 8 pairs at a time, btf_up_even and btf_up_odd in
 * their order (no FMA), interleaved by unpacks and lane permutes into whole
 * vector stores (a loop per parity stores one lane at a time). Returns the
 * pairs done. */
static int up_pairs_avx2(const float *cc, int m, float *out)
{
    const __m256 six = _mm256_set1_ps(6.0f), eighth = _mm256_set1_ps(0.125f);
    const __m256 half = _mm256_set1_ps(0.5f);
    int j = 0;
    for (; j + 8 <= m; j += 8) {
        __m256 a = _mm256_loadu_ps(cc + j - 1), b = _mm256_loadu_ps(cc + j);
        __m256 c = _mm256_loadu_ps(cc + j + 1);
        __m256 even = _mm256_mul_ps(_mm256_add_ps(_mm256_add_ps(a, c), _mm256_mul_ps(b, six)),
                                    eighth);
        __m256 odd = _mm256_mul_ps(_mm256_add_ps(b, c), half);
        __m256 lo = _mm256_unpacklo_ps(even, odd), hi = _mm256_unpackhi_ps(even, odd);
        _mm256_storeu_ps(out + 2 * j, _mm256_permute2f128_ps(lo, hi, 0x20));
        _mm256_storeu_ps(out + 2 * j + 8, _mm256_permute2f128_ps(lo, hi, 0x31));
    }
    return j;
}
#pragma GCC pop_options
#endif

/* Fine column x reads coarse floor(x / 2); an even x is btf_up_even of
 * three coarse values, an odd x btf_up_odd of two. After an odd first
 * column, the rest goes in (even, odd) pairs. */
void btf__up_row(const float *c, int cx0, int fx0, int n, float *o)
{
    int x = 0;
    if ((fx0 & 1) && n > 0) {
        const float *cc = c + (btf_floordiv2(fx0) - cx0);
        o[0] = btf_up_odd(cc[0], cc[1]);
        x = 1;
    }
    const float *cc = c + (btf_floordiv2(fx0 + x) - cx0); /* coarse of fine column x */
    int m = (n - x) / 2, j = 0;
#ifdef SYNTH_HAVE_AVX2
    if (__builtin_cpu_supports("avx2"))
        j = up_pairs_avx2(cc, m, o + x);
#endif
    for (; j < m; j++) {
        o[x + 2 * j] = btf_up_even(cc[j - 1], cc[j], cc[j + 1]);
        o[x + 2 * j + 1] = btf_up_odd(cc[j], cc[j + 1]);
    }
    if ((n - x) & 1) /* a last even column */
        o[n - 1] = btf_up_even(cc[m - 1], cc[m], cc[m + 1]);
}

/* Three loops, one per case, so that each is a plain loop the compiler
 * vectorises (clones for AVX2). */
SYNTH_AVX2_CLONES
void btf__level_sum_row(int w, float mean, const float *f, const float *a, const float *b,
                        const float *c, float *out)
{
    if (!b) {
        for (int k = 0; k < w; k++)
            out[k] = btf_add_mean(mean, f[k]);
    } else if (!a) {
        for (int k = 0; k < w; k++)
            out[k] = btf_add_level(btf_add_mean(mean, f[k]), btf_up_odd(b[k], c[k]));
    } else {
        for (int k = 0; k < w; k++)
            out[k] = btf_add_level(btf_add_mean(mean, f[k]), btf_up_even(a[k], b[k], c[k]));
    }
}
