/*
 * noise_avx2.h — the AVX2 building blocks of the synthesis noise: Philox
 * products with vpmuludq and Box-Muller on several 8-lane vectors in lock
 * step (src/noise_row.c explains why). Shared by src/noise_row.c (rows of
 * noise) and src/wave.c (noise drawn lane by lane for the wavefront), so
 * both give btf_noise4's bits. Include only inside a region compiled for
 * AVX2 (#pragma GCC target("avx2")), after gpu/btf_noise.h, GCC on x86-64.
 */
#ifndef BTF_NOISE_AVX2_H
#define BTF_NOISE_AVX2_H

#include <immintrin.h>

typedef uint32_t v8u __attribute__((vector_size(32)));
typedef int32_t v8i __attribute__((vector_size(32)));
typedef float v8f __attribute__((vector_size(32)));

#define AVX_FN static inline __attribute__((always_inline))
/* Box-Muller vectors evaluated in lock step: four 8-lane chains hide the
 * latency of one (two in the tail of a row). */
#define NV 4
#define EACH for (int j = 0; j < nv; j++)

/* hi:lo = m * c per lane (BTF_MULHILO): the high words from two vpmuludq,
 * the low words from one vpmulld (one instruction instead of a shift and a
 * blend of the products: about 5 % off the generator on Zen 3). */
AVX_FN void mulhilo8(uint32_t m, v8u c, v8u *hi, v8u *lo)
{
    __m256i mm = _mm256_set1_epi32((int)m), cc = (__m256i)c;
    __m256i even = _mm256_mul_epu32(cc, mm);                         /* lanes 0, 2, 4, 6 */
    __m256i odd = _mm256_mul_epu32(_mm256_srli_epi64(cc, 32), mm);  /* lanes 1, 3, 5, 7 */
    *hi = (v8u)_mm256_blend_epi32(_mm256_srli_epi64(even, 32), odd, 0xAA);
    *lo = (v8u)_mm256_mullo_epi32(cc, mm);
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
        /* hm: all ones where btf_noise_log's hm is 1 (the exponent gains
         * 1 - hm wraps to + 1, the mantissa's exponent field loses one) */
        v8u hm = (v8u)((v8i)mant > (int32_t)(BTF_SQRT2_MANT - 1u));
        v8f m = (v8f)(mant | (0x3F800000u + (hm << 23)));
        e[j] = u2f8((ix >> 23) - hm) - 127.0f;
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
        v8f t = u2f8(kk & 0x003FFFFFu) * BTF_2POW_M24 - 0.125f;
        v8f s = t * t;
        v8f sn = t * (BTF_SIN_S0 + s * (BTF_SIN_S1 + s * (BTF_SIN_S2 + s * BTF_SIN_S3)));
        v8f cs = BTF_COS_C0 + s * (BTF_COS_C1 + s * (BTF_COS_C2 + s * (BTF_COS_C3 +
                 s * BTF_COS_C4)));
        /* quad = bits 22 and 23 of kk, moved to the sign bit: q0 is quad
         * & 1 (blendv reads the sign), q1 quad & 2; (quad + 1) & 2 is their
         * exclusive or. Fewer instructions than quad's compares and
         * and/or selects; the same values. */
        v8u q0 = kk << 9, q1 = kk << 8;
        v8f ca = (v8f)_mm256_blendv_ps((__m256)cs, (__m256)sn, (__m256)q0);
        v8f cb = (v8f)_mm256_blendv_ps((__m256)sn, (__m256)cs, (__m256)q0);
        v8u flip_a = (q0 ^ q1) & 0x80000000u, flip_b = q1 & 0x80000000u;
        z0[j] = r * (v8f)((v8u)ca ^ flip_a);
        z1[j] = r * (v8f)((v8u)cb ^ flip_b);
    }
}

/* Philox-4x32-7 (btf_philox) rounds first .. BTF_PHILOX_ROUNDS - 1 on G
 * groups of 8 counters (x, y, z, w), in place; (k0, k1) is round first's
 * key. */
AVX_FN void philox8_rounds(const int first, const int G, v8u *cx, v8u *cy, v8u *cz, v8u *cw,
                           uint32_t k0, uint32_t k1)
{
    for (int i = first; i < BTF_PHILOX_ROUNDS; i++) {
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
}

/* The Philox words of btf_noise4 for the counters (block[g], row, stream,
 * BTF_NOISE_TAG) of G groups (G <= 2) into (cx, cy, cz, cw): the same
 * values as btf_philox, with less work. The groups share row, stream and
 * the tag, so round 0 multiplies the constant z word once, in scalar, and
 * leaves x equal in all groups; round 1 multiplies that shared x once.
 * (Exclusive or is associative: regrouping its operands changes no bit.) */
AVX_FN void philox8_noise(const int G, const v8u *block, v8u row, uint32_t stream,
                          uint32_t k0, uint32_t k1, v8u *cx, v8u *cy, v8u *cz, v8u *cw)
{
    uint32_t s_hi, s_lo; /* stream * M1, round 0's second product */
    BTF_MULHILO(BTF_PHILOX_M1, stream, s_hi, s_lo);
    v8u x1 = row ^ (s_hi ^ k0), z1[2], w1[2], hi, lo;
    for (int g = 0; g < G; g++) {
        mulhilo8(BTF_PHILOX_M0, block[g], &hi, &lo);
        z1[g] = hi ^ (BTF_NOISE_TAG ^ k1);
        w1[g] = lo; /* y after round 0 is s_lo in every lane */
    }
    k0 += BTF_PHILOX_W0;
    k1 += BTF_PHILOX_W1;
    v8u x_hi, x_lo;
    mulhilo8(BTF_PHILOX_M0, x1, &x_hi, &x_lo);
    for (int g = 0; g < G; g++) {
        mulhilo8(BTF_PHILOX_M1, z1[g], &hi, &lo);
        cx[g] = hi ^ (s_lo ^ k0);
        cy[g] = lo;
        cz[g] = x_hi ^ w1[g] ^ k1;
        cw[g] = x_lo;
    }
    k0 += BTF_PHILOX_W0;
    k1 += BTF_PHILOX_W1;
    philox8_rounds(2, G, cx, cy, cz, cw, k0, k1);
}

#endif
