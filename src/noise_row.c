/*
 * noise_row.c — a row of synthesis noise: the Gaussians of consecutive
 * blocks of gpu/btf_noise.h, bit for bit what btf_noise4 gives block by block.
 *
 * Why a file of its own: the generator is the largest cost of CPU synthesis
 * (issue 5's workload draws 25 million Gaussians). The portable loop is left
 * to the compiler's vectoriser, which on x86-64 does two things badly: it
 * turns Philox's 32 x 32 -> 64-bit products by constants into chains of
 * 64-bit shifts and adds, and it evaluates the long Box-Muller dependency
 * chains (log polynomial, Newton square root) one vector at a time, so the
 * core waits on latency. The AVX2 path below multiplies with vpmuludq and
 * runs four independent vectors in lock step (source-level interleaving);
 * it is 2.3x faster on a Zen 3 core. It performs the very same IEEE
 * operations in the same order (additions, multiplications, exact int ->
 * float conversions, bit operations; no FMA: the build forbids contraction
 * and nothing here asks for it), so the bits do not change: tests/test_noise.c
 * compares the two paths over many rows, and the GPU parity tests hold.
 */
#include "internal.h"

#include "btf_noise.h"

#include <stdatomic.h>
#include <stdlib.h>
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
#include <immintrin.h>

typedef uint32_t v8u __attribute__((vector_size(32)));
typedef int32_t v8i __attribute__((vector_size(32)));
typedef float v8f __attribute__((vector_size(32)));

#define AVX_FN static inline __attribute__((always_inline))
/* Box-Muller vectors evaluated in lock step: four 8-lane chains hide the
 * latency of one (two in the tail of a row). */
#define NV 4
#define EACH for (int j = 0; j < nv; j++)

/* hi:lo = m * c per lane (BTF_MULHILO), with two vpmuludq. */
AVX_FN void mulhilo8(uint32_t m, v8u c, v8u *hi, v8u *lo)
{
    __m256i mm = _mm256_set1_epi32((int)m), cc = (__m256i)c;
    __m256i even = _mm256_mul_epu32(cc, mm);                         /* lanes 0, 2, 4, 6 */
    __m256i odd = _mm256_mul_epu32(_mm256_srli_epi64(cc, 32), mm);  /* lanes 1, 3, 5, 7 */
    *hi = (v8u)_mm256_blend_epi32(_mm256_srli_epi64(even, 32), odd, 0xAA);
    *lo = (v8u)_mm256_blend_epi32(even, _mm256_slli_epi64(odd, 32), 0xAA);
}

/* a where the mask is set, else b (the ?: of btf_noise.h). */
AVX_FN v8f select8(v8i mask, v8f a, v8f b)
{
    return (v8f)(((v8u)mask & (v8u)a) | (~(v8u)mask & (v8u)b));
}

AVX_FN v8f u2f8(v8u u) /* exact: u < 2^24 wherever it is used */
{
    return __builtin_convertvector((v8i)u, v8f);
}

/* btf_noise_gauss2 on nv x 8 word pairs (nv <= NV, a constant where it is
 * inlined): same operations, same order. */
AVX_FN void gauss2_lockstep(const int nv, const v8u *a, const v8u *b, v8f *z0, v8f *z1)
{
    v8f e[NV], f[NV], q[NV], x[NV], h[NV], y[NV];
    EACH {
        /* btf_noise_uniform_open, then the exponent and mantissa of btf_noise_log */
        v8f u = u2f8((a[j] >> 8) | 1u) * BTF_2POW_M24;
        v8u ix = (v8u)u;
        v8u mant = ix & 0x007FFFFFu;
        v8u hm = (v8u)(mant >= BTF_SQRT2_MANT) & 1u;
        v8f m = (v8f)(mant | (0x3F800000u - (hm << 23)));
        e[j] = u2f8((ix >> 23) + hm) - 127.0f;
        f[j] = m - 1.0f;
    }
    EACH q[j] = BTF_LOG_Q6 + f[j] * BTF_LOG_Q7;
    EACH q[j] = BTF_LOG_Q5 + f[j] * q[j];
    EACH q[j] = BTF_LOG_Q4 + f[j] * q[j];
    EACH q[j] = BTF_LOG_Q3 + f[j] * q[j];
    EACH q[j] = BTF_LOG_Q2 + f[j] * q[j];
    EACH q[j] = BTF_LOG_Q1 + f[j] * q[j];
    EACH q[j] = BTF_LOG_Q0 + f[j] * q[j];
    EACH {
        v8f lnm = f[j] + (f[j] * f[j]) * q[j];
        v8f r = e[j] * BTF_LN2_HI + (e[j] * BTF_LN2_LO + lnm);
        x[j] = -2.0f * r;
    }
    /* btf_noise_sqrt */
    EACH {
        h[j] = 0.5f * x[j];
        y[j] = (v8f)(0x5F3759DFu - ((v8u)x[j] >> 1));
    }
    EACH y[j] = y[j] * (1.5f - (h[j] * y[j]) * y[j]);
    EACH y[j] = y[j] * (1.5f - (h[j] * y[j]) * y[j]);
    EACH y[j] = y[j] * (1.5f - (h[j] * y[j]) * y[j]);
    EACH {
        v8f r = x[j] * y[j];
        /* btf_noise_cossin(b >> 8); -v is v with its sign bit flipped */
        v8u kk = (b[j] >> 8) + 0x00200000u;
        v8u quad = (kk >> 22) & 3u;
        v8f t = u2f8(kk & 0x003FFFFFu) * BTF_2POW_M24 - 0.125f;
        v8f s = t * t;
        v8f sn = t * (BTF_SIN_S0 + s * (BTF_SIN_S1 + s * (BTF_SIN_S2 + s * BTF_SIN_S3)));
        v8f cs = BTF_COS_C0 + s * (BTF_COS_C1 + s * (BTF_COS_C2 + s * (BTF_COS_C3 +
                 s * BTF_COS_C4)));
        v8i odd = (v8i)((quad & 1u) != 0u);
        v8f ca = select8(odd, sn, cs), cb = select8(odd, cs, sn);
        v8u flip_a = ((quad + 1u) & 2u) << 30, flip_b = (quad & 2u) << 30;
        z0[j] = r * (v8f)((v8u)ca ^ flip_a);
        z1[j] = r * (v8f)((v8u)cb ^ flip_b);
    }
}

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
AVX_FN void noise_groups(const int G, uint32_t seed_lo, uint32_t seed_hi, uint32_t stream,
                         uint32_t row, uint32_t b, float *out)
{
    v8u cx[2], cy[2], cz[2], cw[2];
    for (int g = 0; g < G; g++) {
        uint32_t c = b + 8u * (uint32_t)g;
        v8u blocks = {c, c + 1, c + 2, c + 3, c + 4, c + 5, c + 6, c + 7};
        cx[g] = blocks;
        cy[g] = blocks * 0u + row;
        cz[g] = blocks * 0u + stream;
        cw[g] = blocks * 0u + BTF_NOISE_TAG;
    }
    uint32_t k0 = seed_lo, k1 = seed_hi;
    for (int i = 0; i < BTF_PHILOX_ROUNDS; i++) {
        for (int g = 0; g < G; g++) { /* btf_philox_round */
            v8u hi0, lo0, hi1, lo1;
            mulhilo8(BTF_PHILOX_M0, cx[g], &hi0, &lo0);
            mulhilo8(BTF_PHILOX_M1, cz[g], &hi1, &lo1);
            cx[g] = hi1 ^ cy[g] ^ k0;
            cy[g] = lo1;
            cz[g] = hi0 ^ cw[g] ^ k1;
            cw[g] = lo0;
        }
        k0 += BTF_PHILOX_W0;
        k1 += BTF_PHILOX_W1;
    }
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
    uint32_t i = 0;
    for (; i + 16 <= n; i += 16)
        noise_groups(2, seed_lo, seed_hi, stream, row, b0 + i, out + 4 * i);
    if (i + 8 <= n) {
        noise_groups(1, seed_lo, seed_hi, stream, row, b0 + i, out + 4 * i);
        i += 8;
    }
    if (i < n) {
        /* The last 1..7 blocks: one more group into a scratch buffer,
         * cheaper than even a few blocks of the scalar generator (8x slower
         * per Gaussian). */
        float tail[32];
        noise_groups(1, seed_lo, seed_hi, stream, row, b0 + i, tail);
        memcpy(out + 4 * i, tail, (size_t)(n - i) * 4 * sizeof(float));
    }
}
#pragma GCC pop_options
#endif

/* BTF_NOISE_PORTABLE=1 in the environment forces the portable path (tests
 * compare the two; a user can rule out the vector path when in doubt). */
int btf_noise_path_avx2(void)
{
#ifdef BTF_HAVE_AVX2_PATH
    static atomic_int path = -1; /* decided once; a race only repeats the decision */
    int p = atomic_load(&path);
    if (p < 0) {
        const char *env = getenv("BTF_NOISE_PORTABLE");
        p = (env && *env && strcmp(env, "0")) ? 0 : __builtin_cpu_supports("avx2") != 0;
        atomic_store(&path, p);
    }
    return p;
#else
    return 0;
#endif
}

void btf_noise_blocks(uint32_t seed_lo, uint32_t seed_hi, uint32_t stream, uint32_t row,
                      uint32_t b0, uint32_t n, int vector_path, float *out)
{
#ifdef BTF_HAVE_AVX2_PATH
    if (vector_path && btf_noise_path_avx2()) {
        noise_blocks_avx2(seed_lo, seed_hi, stream, row, b0, n, out);
        return;
    }
#endif
    (void)vector_path;
    noise_blocks_portable(seed_lo, seed_hi, stream, row, b0, n, out);
}
