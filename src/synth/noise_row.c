/*
 * noise_row.c — a row of synthesis noise (Haindl & Filip 2007, section
 * II.C: the white Gaussian noise e_r that drives each CAR field): the
 * Gaussians of consecutive blocks of src/synth/btf_noise.h, bit for bit
 * what btf_noise4 gives block by block.
 *
 * Why a file of its own: the generator is the largest cost of CPU
 * synthesis (the paper's workload, 15 images of 512 x 512 with 3 bands and
 * 3 levels, draws some 17.5 million Gaussians). The portable loop is left
 * to the compiler's vectoriser, which on x86-64 does two things badly: it
 * turns Philox's 32 x 32 -> 64-bit products by constants into chains of
 * 64-bit shifts and adds, and it evaluates the long Box-Muller dependency
 * chains (log polynomial, Newton square root) one vector at a time, so the
 * core waits on latency.
 * The AVX2 path below multiplies with vpmuludq and runs four independent
 * vectors in lock step (source-level interleaving); it is 2.3x faster on a
 * Zen 3 core. It performs the very same IEEE operations in the same order
 * (additions, multiplications, exact int -> float conversions, bit
 * operations; no FMA: the build forbids contraction and nothing here asks
 * for it), so the bits do not change: tests/unit/test_noise.c compares the two
 * paths over many rows, and the GPU parity tests hold.
 */
#include "core/core.h"
#include "synth/synth.h"

#include "btf_noise.h"

#include <string.h>

/* The portable path: btf_noise4 block by block. */
static void noise_blocks_portable(uint32_t seed_lo, uint32_t seed_hi, uint32_t stream,
                                  uint32_t row, uint32_t b0, uint32_t n, float *out)
{
    for (uint32_t i = 0; i < n; i++) {
        btf_vec4 v = btf_noise4(seed_lo, seed_hi, stream, row, b0 + i);
        out[4 * i] = v.x;
        out[4 * i + 1] = v.y;
        out[4 * i + 2] = v.z;
        out[4 * i + 3] = v.w;
    }
}

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define BTF_HAVE_AVX2_PATH 1
#pragma GCC push_options
#pragma GCC target("avx2")
#include "noise_avx2.h"

/* Writes lanes of (z0, z1, z2, z3) as 8 consecutive blocks: column 4 i + k
 * of the output is lane i of zk. */
AVX_FN void store_blocks8(float *p, v8f z0, v8f z1, v8f z2, v8f z3)
{
    __m256 ab0 = _mm256_unpacklo_ps((__m256)z0, (__m256)z1);
    __m256 ab1 = _mm256_unpackhi_ps((__m256)z0, (__m256)z1);
    __m256 cd0 = _mm256_unpacklo_ps((__m256)z2, (__m256)z3);
    __m256 cd1 = _mm256_unpackhi_ps((__m256)z2, (__m256)z3);
    /* rk holds blocks k and k + 4 */
    __m256 r0 = (__m256)_mm256_unpacklo_pd((__m256d)ab0, (__m256d)cd0);
    __m256 r1 = (__m256)_mm256_unpackhi_pd((__m256d)ab0, (__m256d)cd0);
    __m256 r2 = (__m256)_mm256_unpacklo_pd((__m256d)ab1, (__m256d)cd1);
    __m256 r3 = (__m256)_mm256_unpackhi_pd((__m256d)ab1, (__m256d)cd1);
    _mm256_storeu_ps(p, _mm256_permute2f128_ps(r0, r1, 0x20));
    _mm256_storeu_ps(p + 8, _mm256_permute2f128_ps(r2, r3, 0x20));
    _mm256_storeu_ps(p + 16, _mm256_permute2f128_ps(r0, r1, 0x31));
    _mm256_storeu_ps(p + 24, _mm256_permute2f128_ps(r2, r3, 0x31));
}

/* Blocks b .. b + 8 G - 1 (32 G Gaussians) into out: Philox-4x32-7 on G
 * 8-lane groups (G = 1 or 2, a constant where it is inlined), then
 * Box-Muller on their 2 G word pairs. */
AVX_FN void noise_groups(const int G, const philox8_plan *plan, uint32_t row, uint32_t b,
                         float *out)
{
    v8u blocks[2], cx[2], cy[2], cz[2], cw[2];
    for (int g = 0; g < G; g++) {
        uint32_t c = b + 8u * (uint32_t)g;
        blocks[g] = (v8u){c, c + 1, c + 2, c + 3, c + 4, c + 5, c + 6, c + 7};
    }
    philox8_noise(G, blocks, blocks[0] * 0u + row, plan, cx, cy, cz, cw);
    /* btf_noise4: (x, y) give components 0 and 1, (z, w) components 2 and 3 */
    v8u a[NV], w[NV];
    for (int g = 0; g < G; g++) {
        a[g] = cx[g], a[G + g] = cz[g];
        w[g] = cy[g], w[G + g] = cw[g];
    }
    v8f z0[NV], z1[NV];
    gauss2_lockstep(2 * G, a, w, z0, z1);
    for (int g = 0; g < G; g++)
        store_blocks8(out + 32 * g, z0[g], z1[g], z0[G + g], z1[G + g]);
}

static void noise_blocks_avx2(uint32_t seed_lo, uint32_t seed_hi, uint32_t stream, uint32_t row,
                              uint32_t b0, uint32_t n, float *out)
{
    philox8_plan plan;
    philox8_plan_make(&plan, stream, seed_lo, seed_hi);
    uint32_t i = 0;
    for (; i + 16 <= n; i += 16)
        noise_groups(2, &plan, row, b0 + i, out + 4 * i);
    if (i + 8 <= n) {
        noise_groups(1, &plan, row, b0 + i, out + 4 * i);
        i += 8;
    }
    if (i < n) {
        /* The last 1..7 blocks: one more group into a scratch buffer,
         * cheaper than even a few blocks of the scalar generator (8x slower
         * per Gaussian). */
        float tail[32];
        noise_groups(1, &plan, row, b0 + i, tail);
        memcpy(out + 4 * i, tail, (size_t)(n - i) * 4 * sizeof(float));
    }
}
#pragma GCC pop_options
#endif

int btf__noise_avx2_available(void)
{
#ifdef BTF_HAVE_AVX2_PATH
    return __builtin_cpu_supports("avx2") != 0;
#else
    return 0;
#endif
}

void btf__noise_blocks(uint32_t seed_lo, uint32_t seed_hi, uint32_t stream, uint32_t row,
                       uint32_t b0, uint32_t n, int vector_path, float *out)
{
#ifdef BTF_HAVE_AVX2_PATH
    if (vector_path && __builtin_cpu_supports("avx2")) { /* a load and a test */
        noise_blocks_avx2(seed_lo, seed_hi, stream, row, b0, n, out);
        return;
    }
#endif
    (void)vector_path;
    noise_blocks_portable(seed_lo, seed_hi, stream, row, b0, n, out);
}
