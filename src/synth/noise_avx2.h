/*
 * noise_avx2.h — the AVX2 building blocks of the synthesis noise (the white
 * noise of the CAR fields, Haindl & Filip 2007, section II.C): Philox
 * products with vpmuludq and Box-Muller on several 8-lane vectors in lock
 * step (src/synth/noise_row.c explains why). Shared by src/synth/noise_row.c
 * (rows of noise) and src/synth/wave.c (noise drawn lane by lane for the
 * wavefront), so both give btf_noise4's bits. Include only inside a region
 * compiled for AVX2 (#pragma GCC target("avx2")), after
 * src/synth/btf_noise.h, GCC on x86-64.
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
        /* hm: all ones (-1) where btf_noise_log's hm is 1, so the
         * exponent adds 1 as "- hm", and "+ (hm << 23)" takes 1 from the
         * mantissa's exponent field (mod 2^32), as "- (1 << 23)" there */
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

/* The words of btf_noise4's counters (block, row, stream, BTF_NOISE_TAG)
 * that do not change along a row, with the seed's round keys, as 8-lane
 * vectors in memory: the rounds read them as operands instead of
 * broadcasting scalars again on every call (GCC rebuilds such constants
 * through general registers, two instructions each, once the vector
 * registers run out). Made once per (seed, stream). */
typedef struct philox8_plan {
    uint32_t key[BTF_PHILOX_ROUNDS][2][8]; /* round i's (k0, k1); rounds 0 and 1
                                            * read theirs folded into x0, z0, x1 */
    uint32_t x0[8]; /* round 0: hi(M1 stream) ^ k0, the part of x shared by all lanes */
    uint32_t z0[8]; /* round 0: BTF_NOISE_TAG ^ k1 */
    uint32_t x1[8]; /* round 1: lo(M1 stream) ^ k0, y after round 0 being lo(M1 stream) */
} philox8_plan;

static inline void philox8_plan_make(philox8_plan *p, uint32_t stream, uint32_t k0, uint32_t k1)
{
    uint32_t s_hi, s_lo; /* stream * M1: round 0's second product, the same everywhere */
    BTF_MULHILO(BTF_PHILOX_M1, stream, s_hi, s_lo);
    for (int i = 0; i < BTF_PHILOX_ROUNDS; i++) {
        for (int l = 0; l < 8; l++) {
            p->key[i][0][l] = k0;
            p->key[i][1][l] = k1;
        }
        if (i == 0)
            for (int l = 0; l < 8; l++)
                p->x0[l] = s_hi ^ k0, p->z0[l] = BTF_NOISE_TAG ^ k1;
        if (i == 1)
            for (int l = 0; l < 8; l++)
                p->x1[l] = s_lo ^ k0;
        k0 += BTF_PHILOX_W0;
        k1 += BTF_PHILOX_W1;
    }
}

#define PLAN8(v) ((v8u)_mm256_loadu_si256((const __m256i *)(v)))

/* The Philox-4x32-7 words (btf_philox) of the counters (block[g], row,
 * stream, BTF_NOISE_TAG) of G groups (G <= 2) into (cx, cy, cz, cw), with
 * the plan of (seed, stream). The same values with less work: the groups
 * share row, stream and the tag, so round 0 leaves x equal in all groups
 * and round 1 multiplies that x once. (Exclusive or is associative:
 * regrouping its operands changes no bit.) */
AVX_FN void philox8_noise(const int G, const v8u *block, v8u row, const philox8_plan *p,
                          v8u *cx, v8u *cy, v8u *cz, v8u *cw)
{
    v8u x1 = row ^ PLAN8(p->x0), z1[2], w1[2], hi, lo;
    for (int g = 0; g < G; g++) { /* round 0 */
        mulhilo8(BTF_PHILOX_M0, block[g], &hi, &lo);
        z1[g] = hi ^ PLAN8(p->z0);
        w1[g] = lo;
    }
    v8u x_hi, x_lo; /* round 1 */
    mulhilo8(BTF_PHILOX_M0, x1, &x_hi, &x_lo);
    for (int g = 0; g < G; g++) {
        mulhilo8(BTF_PHILOX_M1, z1[g], &hi, &lo);
        cx[g] = hi ^ PLAN8(p->x1);
        cy[g] = lo;
        cz[g] = x_hi ^ w1[g] ^ PLAN8(p->key[1][1]);
        cw[g] = x_lo;
    }
    for (int i = 2; i < BTF_PHILOX_ROUNDS; i++) {
        for (int g = 0; g < G; g++) { /* btf_philox_round */
            v8u hi0, lo0, hi1, lo1;
            mulhilo8(BTF_PHILOX_M0, cx[g], &hi0, &lo0);
            mulhilo8(BTF_PHILOX_M1, cz[g], &hi1, &lo1);
            cx[g] = hi1 ^ cy[g] ^ PLAN8(p->key[i][0]);
            cy[g] = lo1;
            cz[g] = hi0 ^ cw[g] ^ PLAN8(p->key[i][1]);
            cw[g] = lo0;
        }
    }
}

#endif
