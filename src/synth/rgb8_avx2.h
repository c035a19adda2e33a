/*
 * rgb8_avx2.h — 8 interleaved RGB pixels (24 floats) to three planes of 8
 * and back, with AVX2: per plane a lane permutation and two blends, no
 * scalar stores. Shared by the synthesis' colour steps (colour.c,
 * marginal.c) and colour matching (colour_lab.c). Include it after
 * <immintrin.h> inside a `#pragma GCC target("avx2")` region: the functions
 * are compiled for AVX2 and called only where the CPU has it.
 *
 * Lane i of the three vectors a, b, c (24 floats) holds:
 *   a = r0 g0 b0 r1 g1 b1 r2 g2 | b = b2 r3 g3 b3 r4 g4 b4 r5 | c = g5 b5 r6 g6 b6 r7 g7 b7
 * Moves only: the same bits in and out.
 */
#ifndef BTF_RGB8_AVX2_H
#define BTF_RGB8_AVX2_H

static inline void btf_rgb8_store(const __m256 v[3], float *p)
{
    __m256 a = _mm256_permutevar8x32_ps(v[0], _mm256_setr_epi32(0, 3, 6, 1, 4, 7, 2, 5));
    __m256 b = _mm256_permutevar8x32_ps(v[1], _mm256_setr_epi32(5, 0, 3, 6, 1, 4, 7, 2));
    __m256 c = _mm256_permutevar8x32_ps(v[2], _mm256_setr_epi32(2, 5, 0, 3, 6, 1, 4, 7));
    _mm256_storeu_ps(p, _mm256_blend_ps(_mm256_blend_ps(a, b, 0x92), c, 0x24));
    _mm256_storeu_ps(p + 8, _mm256_blend_ps(_mm256_blend_ps(a, b, 0x24), c, 0x49));
    _mm256_storeu_ps(p + 16, _mm256_blend_ps(_mm256_blend_ps(a, b, 0x49), c, 0x92));
}

static inline void btf_rgb8_load(const float *p, __m256 v[3])
{
    __m256 a = _mm256_loadu_ps(p), b = _mm256_loadu_ps(p + 8), c = _mm256_loadu_ps(p + 16);
    __m256 r = _mm256_blend_ps(_mm256_blend_ps(a, b, 0x92), c, 0x24); /* r0 r3 r6 r1 r4 r7 r2 r5 */
    __m256 g = _mm256_blend_ps(_mm256_blend_ps(a, b, 0x24), c, 0x49); /* g5 g0 g3 g6 g1 g4 g7 g2 */
    __m256 s = _mm256_blend_ps(_mm256_blend_ps(a, b, 0x49), c, 0x92); /* b2 b5 b0 b3 b6 b1 b4 b7 */
    v[0] = _mm256_permutevar8x32_ps(r, _mm256_setr_epi32(0, 3, 6, 1, 4, 7, 2, 5));
    v[1] = _mm256_permutevar8x32_ps(g, _mm256_setr_epi32(1, 4, 7, 2, 5, 0, 3, 6));
    v[2] = _mm256_permutevar8x32_ps(s, _mm256_setr_epi32(2, 5, 0, 3, 6, 1, 4, 7));
}

#endif
