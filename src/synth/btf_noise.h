/*
 * btf_noise.h -- the Gaussian white noise e_r that drives CAR synthesis
 * (Haindl & Filip 2007, section II.C: Y_r = gamma X_r + e_r), ONE text shared
 * by the C library (included by the C11 sources in src/) and the Vulkan
 * compute shaders (included by the .comp files in gpu/, GLSL 4.50 with
 * GL_GOOGLE_include_directive).
 *
 * Why: CPU and GPU synthesis must produce the same image bit for bit, so the
 * noise is a pure function of (seed, stream, row, block) computed with
 * operations whose results IEEE 754 and Vulkan both pin down exactly:
 *  - 32-bit integer arithmetic (Philox-4x32-7, a counter-based generator:
 *    J. K. Salmon, M. A. Moraes, R. O. Dror, D. E. Shaw, "Parallel random
 *    numbers: as easy as 1, 2, 3", SC'11; Random123 known answers in
 *    tests/unit/test_noise.c).  The paper reports Philox-4x32 with 7 rounds
 *    passing all of TestU01's BigCrush; Random123 defaults to 10 for a
 *    safety margin, which texture synthesis, whose noise the CAR model
 *    filters, does not need, while the generator is the largest cost of CPU
 *    synthesis (docs/synthesis.md, "Noise").  A cheaper hash, pcg4d
 *    (Jarzynski and Olano, JCGT 2020), fails dieharder's DNA test
 *    (p < 1e-8) on the words in the order synthesis draws them, where
 *    Philox-4x32-7 passes;
 *  - float additions, subtractions and multiplications (correctly rounded
 *    on both sides), exact int->float conversions of values < 2^24, bit casts
 *    and selects.  No division, no exp/log/sin/cos/sqrt built-ins: their last
 *    bits differ between glibc and GPU drivers.  No value on the Gaussian
 *    path is ever subnormal (GPUs may flush them), infinite or NaN.
 * The Gaussian is Box-Muller (G. E. P. Box, M. E. Muller, Ann. Math. Statist.
 * 29, 1958): z = sqrt(-2 ln u1) (cos, sin)(2 pi u2), with a polynomial log
 * (exponent from the bits, minimax polynomial on the mantissa), a Newton
 * square root seeded by the inverse-sqrt bit trick, and minimax sine and
 * cosine polynomials on an octant taken from the integer bits of u2.
 *
 * Contraction: every float result is stored in a BTF_PRECISE variable
 * ("precise" in GLSL, so SPIR-V marks each operation NoContraction); the C
 * build uses -ffp-contract=off.  Parentheses fix the evaluation order in both.
 *
 * Accuracy (measured by tests/unit/test_noise.c, exhaustive or dense sweeps):
 *  - btf_noise_log: 5.0e-7 absolute on every multiple of 2^-24 in (0, 1)
 *    (a quarter ulp of ln 2^-24), 1.0e-7 relative there and on [2^-100, 2^100];
 *  - btf_noise_sqrt: 2.2e-7 relative (at most 4 ulp); sqrt(0) = 0;
 *  - btf_noise_cossin: 8.7e-8 absolute on all 2^24 angles;
 *  - radius sqrt(-2 ln u1): 7.1e-7 absolute on all 2^23 uniforms; the pair
 *    vs the exact Box-Muller map of the same uniforms: 8.8e-7;
 *  - distribution: the exact tail P(z > t) over the whole sample space
 *    (2^23 radii x 2^24 angles), as a quantile shift (P - Q(t)) / pdf(t):
 *    <= 1.7e-7 up to t = 3, 2.6e-6 at 4, 2.5e-5 at 4.5, 4.4e-4 at 5, 1.1e-2
 *    at 5.5 (u1 on the (k+1)/2^24 grid instead of cell midpoints: 3.8e-3 at 5);
 *  - range: |z| <= sqrt(-2 ln 2^-24) = 5.7681 (normal mass beyond: 8e-9).
 * Bit-exactness: the C build and lavapipe (Mesa llvmpipe 15) agree on every
 * radius, every angle and 840,000 btf_noise4 blocks (checked with a scratch
 * Vulkan host running gpu/noise_check.comp).
 *
 * Keep this file in the common subset of C11 and GLSL 4.50: ASCII only; in
 * the shared part no pointers, arrays, casts "(T)x" (use BTF_U2F), struct
 * literals (use BTF_VEC4...), library calls, division, "__" in names or GLSL
 * reserved words (half, input, output, filter, ...) as names; unsigned
 * constants carry the u suffix, float constants the f suffix and at most 9
 * significant digits (so both compilers round them to the same float).
 * Language differences live in the two blocks just below.
 *
 * Use from GLSL: "#extension GL_GOOGLE_include_directive : require", then
 * #include "btf_noise.h" (glslangValidator -Igpu).  From C: include it
 * (-Igpu); everything is static inline.
 */
#ifndef BTF_NOISE_H
#define BTF_NOISE_H

#if defined(BTF_GLSL) || defined(VULKAN) || defined(GL_core_profile) || defined(GL_ES)
/* ------------------------------------------------------------------ GLSL */
#define BTF_FN
#define BTF_PRECISE precise
#define btf_uint uint
#define btf_uvec2 uvec2
#define btf_uvec4 uvec4
#define btf_vec2 vec2
#define btf_vec4 vec4
#define BTF_UVEC2(a, b) uvec2(a, b)
#define BTF_UVEC4(a, b, c, d) uvec4(a, b, c, d)
#define BTF_VEC2(a, b) vec2(a, b)
#define BTF_VEC4(a, b, c, d) vec4(a, b, c, d)
#define BTF_U2F(u) float(u)
#define btf_float_bits(f) floatBitsToUint(f)
#define btf_bits_float(u) uintBitsToFloat(u)
/* hi:lo = a * b, the full 64-bit product of two uints (statement). */
#define BTF_MULHILO(a, b, hi, lo) umulExtended(a, b, hi, lo)

#elif defined(__STDC_VERSION__) || defined(__cplusplus)
/* --------------------------------------------------------------------- C */
#include <stdint.h>
#include <string.h>

/* always_inline: synthesis loops over blocks must inline the generator so
 * the compiler can vectorise it (3-4x faster on a row of noise). */
#if defined(__GNUC__)
#define BTF_FN static inline __attribute__((always_inline))
#else
#define BTF_FN static inline
#endif
#define BTF_PRECISE
typedef uint32_t btf_uint;
typedef struct btf_uvec2 { btf_uint x, y; } btf_uvec2;
typedef struct btf_uvec4 { btf_uint x, y, z, w; } btf_uvec4;
typedef struct btf_vec2 { float x, y; } btf_vec2;
typedef struct btf_vec4 { float x, y, z, w; } btf_vec4;

static inline btf_uvec2 btf_make_uvec2(btf_uint a, btf_uint b)
{
    btf_uvec2 v = {a, b};
    return v;
}
static inline btf_uvec4 btf_make_uvec4(btf_uint a, btf_uint b, btf_uint c, btf_uint d)
{
    btf_uvec4 v = {a, b, c, d};
    return v;
}
static inline btf_vec2 btf_make_vec2(float a, float b)
{
    btf_vec2 v = {a, b};
    return v;
}
static inline btf_vec4 btf_make_vec4(float a, float b, float c, float d)
{
    btf_vec4 v = {a, b, c, d};
    return v;
}
static inline btf_uint btf_float_bits(float f)
{
    btf_uint u;
    memcpy(&u, &f, sizeof u);
    return u;
}
static inline float btf_bits_float(btf_uint u)
{
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}
#define BTF_UVEC2(a, b) btf_make_uvec2(a, b)
#define BTF_UVEC4(a, b, c, d) btf_make_uvec4(a, b, c, d)
#define BTF_VEC2(a, b) btf_make_vec2(a, b)
#define BTF_VEC4(a, b, c, d) btf_make_vec4(a, b, c, d)
#define BTF_U2F(u) ((float)(u))
#define BTF_MULHILO(a, b, hi, lo)                                             \
    do {                                                                      \
        uint64_t btf_p_ = (uint64_t)(a) * (uint64_t)(b);                      \
        (hi) = (btf_uint)(btf_p_ >> 32);                                      \
        (lo) = (btf_uint)btf_p_;                                              \
    } while (0)

#else
#error "btf_noise.h: neither C nor GLSL"
#endif

/* ============================================== shared part: C and GLSL */

/* Philox-4x32 constants (Salmon et al. 2011; Random123 philox.h). */
#define BTF_PHILOX_M0 0xD2511F53u
#define BTF_PHILOX_M1 0xCD9E8D57u
#define BTF_PHILOX_W0 0x9E3779B9u /* golden ratio */
#define BTF_PHILOX_W1 0xBB67AE85u /* sqrt(3) - 1 */
#define BTF_PHILOX_ROUNDS 7

/* The 4th counter word of the synthesis noise; other uses of Philox with the
 * same seed must use another value ("CARN"). */
#define BTF_NOISE_TAG 0x4341524Eu

/* Stream packing: subspace 16 bits, band 8 bits, pyramid level 8 bits. */
#define BTF_NOISE_MAX_SUBSPACES 65536u
#define BTF_NOISE_MAX_BANDS 256u
#define BTF_NOISE_MAX_LEVELS 256u

/* Largest |z|: sqrt(-2 ln 2^-24), the radius of the smallest u1. */
#define BTF_NOISE_MAX_ABS 5.76810741f

#define BTF_2POW_M24 5.9604644775390625e-8f /* 2^-24, exact */

/* ln 2 split so that e * BTF_LN2_HI is exact for |e| < 256. */
#define BTF_LN2_HI 0.693145751953125f
#define BTF_LN2_LO 1.42860677e-6f
/* Mantissa bits of sqrt(2) as a float: mantissas from here on are halved. */
#define BTF_SQRT2_MANT 0x003504F3u
/* ln(1 + f) = f + f^2 Q(f) on [sqrt(1/2) - 1, sqrt(2) - 1]: minimax for the
 * relative error of the sum (Remez, 3.0e-8 before rounding to float). */
#define BTF_LOG_Q0 -0.499999911f
#define BTF_LOG_Q1 0.333339512f
#define BTF_LOG_Q2 -0.250017554f
#define BTF_LOG_Q3 0.199620724f
#define BTF_LOG_Q4 -0.165705085f
#define BTF_LOG_Q5 0.149179727f
#define BTF_LOG_Q6 -0.143075228f
#define BTF_LOG_Q7 0.0873484462f
/* sin(2 pi t) = t S(t^2), cos(2 pi t) = C(t^2) for |t| <= 1/8 turn: minimax
 * in relative error (3.2e-9 and 5.6e-11 before rounding to float). */
#define BTF_SIN_S0 6.28318548f
#define BTF_SIN_S1 -41.3416634f
#define BTF_SIN_S2 81.5923538f
#define BTF_SIN_S3 -75.3935623f
#define BTF_COS_C0 1.0f
#define BTF_COS_C1 -19.7392082f
#define BTF_COS_C2 64.9393082f
#define BTF_COS_C3 -85.4422989f
#define BTF_COS_C4 59.2027969f

/* One Philox-4x32 round. */
BTF_FN btf_uvec4 btf_philox_round(btf_uvec4 c, btf_uvec2 k)
{
    btf_uint hi0, lo0, hi1, lo1;
    BTF_MULHILO(BTF_PHILOX_M0, c.x, hi0, lo0);
    BTF_MULHILO(BTF_PHILOX_M1, c.z, hi1, lo1);
    return BTF_UVEC4(hi1 ^ c.y ^ k.x, lo1, hi0 ^ c.w ^ k.y, lo0);
}

/* Philox-4x32-7: 128 random bits for a 128-bit counter and a 64-bit key. */
BTF_FN btf_uvec4 btf_philox(btf_uvec4 ctr, btf_uvec2 key)
{
    for (int i = 0; i < BTF_PHILOX_ROUNDS - 1; i++) {
        ctr = btf_philox_round(ctr, key);
        key.x += BTF_PHILOX_W0;
        key.y += BTF_PHILOX_W1;
    }
    return btf_philox_round(ctr, key);
}

/* Natural log of a positive normal float x (not 0, subnormal, Inf or NaN).
 * x = 2^e m with m in [sqrt(1/2), sqrt(2)); ln x = e ln 2 + ln(1 + f),
 * f = m - 1 exact (Sterbenz). */
BTF_FN float btf_noise_log(float x)
{
    btf_uint ix = btf_float_bits(x);
    btf_uint mant = ix & 0x007FFFFFu;
    btf_uint hm = (mant >= BTF_SQRT2_MANT) ? 1u : 0u; /* halve m */
    BTF_PRECISE float m = btf_bits_float(mant | (0x3F800000u - (hm << 23)));
    BTF_PRECISE float e = BTF_U2F((ix >> 23) + hm) - 127.0f;
    BTF_PRECISE float f = m - 1.0f;
    BTF_PRECISE float q = BTF_LOG_Q0 + f * (BTF_LOG_Q1 + f * (BTF_LOG_Q2 + f * (BTF_LOG_Q3 +
                          f * (BTF_LOG_Q4 + f * (BTF_LOG_Q5 + f * (BTF_LOG_Q6 +
                          f * BTF_LOG_Q7))))));
    BTF_PRECISE float lnm = f + (f * f) * q;
    BTF_PRECISE float r = e * BTF_LN2_HI + (e * BTF_LN2_LO + lnm);
    return r;
}

/* Square root of x >= 0 (normal or zero): three Newton steps for 1/sqrt(x)
 * from the bit-trick start (Lomont's constant family), then x * (1/sqrt x). */
BTF_FN float btf_noise_sqrt(float x)
{
    BTF_PRECISE float h = 0.5f * x;
    BTF_PRECISE float y = btf_bits_float(0x5F3759DFu - (btf_float_bits(x) >> 1));
    y = y * (1.5f - (h * y) * y);
    y = y * (1.5f - (h * y) * y);
    y = y * (1.5f - (h * y) * y);
    BTF_PRECISE float r = x * y;
    return r;
}

/* (cos, sin) of 2 pi k / 2^24 for the low 24 bits of k.  The integer bits
 * pick the quadrant nearest the angle; the rest, t in [-1/8, 1/8) turn, is
 * exact in float and feeds the polynomials. */
BTF_FN btf_vec2 btf_noise_cossin(btf_uint k)
{
    btf_uint kk = k + 0x00200000u;
    btf_uint quad = (kk >> 22) & 3u;
    BTF_PRECISE float t = BTF_U2F(kk & 0x003FFFFFu) * BTF_2POW_M24 - 0.125f;
    BTF_PRECISE float s = t * t;
    BTF_PRECISE float sn = t * (BTF_SIN_S0 + s * (BTF_SIN_S1 + s * (BTF_SIN_S2 +
                           s * BTF_SIN_S3)));
    BTF_PRECISE float cs = BTF_COS_C0 + s * (BTF_COS_C1 + s * (BTF_COS_C2 +
                           s * (BTF_COS_C3 + s * BTF_COS_C4)));
    /* quadrant 0: (c, s), 1: (-s, c), 2: (-c, -s), 3: (s, -c) */
    BTF_PRECISE float a = ((quad & 1u) != 0u) ? sn : cs;
    BTF_PRECISE float b = ((quad & 1u) != 0u) ? cs : sn;
    BTF_PRECISE float c = (((quad + 1u) & 2u) != 0u) ? -a : a;
    BTF_PRECISE float d = ((quad & 2u) != 0u) ? -b : b;
    return BTF_VEC2(c, d);
}

/* The radius uniform: the midpoint of one of 2^23 equal cells of (0, 1),
 * (2k + 1) / 2^24 from the top 23 bits of a: exact in float, never 0 or 1.
 * Midpoints, not (k + 1) / 2^24, keep the tails unbiased. */
BTF_FN float btf_noise_uniform_open(btf_uint a)
{
    BTF_PRECISE float u = BTF_U2F((a >> 8) | 1u) * BTF_2POW_M24;
    return u;
}

/* Two independent standard Gaussians (Box-Muller) from two random words:
 * a gives the radius, the top 24 bits of b the angle. */
BTF_FN btf_vec2 btf_noise_gauss2(btf_uint a, btf_uint b)
{
    BTF_PRECISE float r2 = -2.0f * btf_noise_log(btf_noise_uniform_open(a));
    BTF_PRECISE float r = btf_noise_sqrt(r2);
    btf_vec2 cs = btf_noise_cossin(b >> 8);
    BTF_PRECISE float z0 = r * cs.x;
    BTF_PRECISE float z1 = r * cs.y;
    return BTF_VEC2(z0, z1);
}

/* The noise stream of (subspace, band, pyramid level); each must be below
 * BTF_NOISE_MAX_SUBSPACES, _BANDS, _LEVELS (callers check: larger values
 * are masked and would share streams). */
BTF_FN btf_uint btf_noise_stream(btf_uint subspace, btf_uint band, btf_uint level)
{
    return ((subspace & 0xFFFFu) << 16) | ((band & 0xFFu) << 8) | (level & 0xFFu);
}

/* The four Gaussians of pixels 4 block .. 4 block + 3 of a row: the pixel at
 * column c uses component c & 3 of block c >> 2.  The seed is the 64-bit
 * Philox key; the counter is (block, row, stream, BTF_NOISE_TAG).  Rows and
 * columns are uint: callers map negative (burn-in) indices by adding a fixed
 * offset (uint(int) conversion also works: it wraps in both languages). */
BTF_FN btf_vec4 btf_noise4(btf_uint seed_lo, btf_uint seed_hi, btf_uint stream,
                           btf_uint row, btf_uint block)
{
    btf_uvec4 w = btf_philox(BTF_UVEC4(block, row, stream, BTF_NOISE_TAG),
                             BTF_UVEC2(seed_lo, seed_hi));
    btf_vec2 g0 = btf_noise_gauss2(w.x, w.y);
    btf_vec2 g1 = btf_noise_gauss2(w.z, w.w);
    return BTF_VEC4(g0.x, g0.y, g1.x, g1.y);
}

/* Component i & 3 of v (C structs have no v[i]). */
BTF_FN float btf_vec4_at(btf_vec4 v, btf_uint i)
{
    btf_uint j = i & 3u;
    return (j == 0u) ? v.x : ((j == 1u) ? v.y : ((j == 2u) ? v.z : v.w));
}

/* The Gaussian of the pixel at column col alone: bit for bit component
 * col & 3 of btf_noise4(..., col >> 2), at half the Box-Muller work. */
BTF_FN float btf_noise1(btf_uint seed_lo, btf_uint seed_hi, btf_uint stream, btf_uint row,
                        btf_uint col)
{
    btf_uvec4 w = btf_philox(BTF_UVEC4(col >> 2u, row, stream, BTF_NOISE_TAG),
                             BTF_UVEC2(seed_lo, seed_hi));
    btf_uint j = col & 3u;
    btf_vec2 g = btf_noise_gauss2((j < 2u) ? w.x : w.z, (j < 2u) ? w.y : w.w);
    return ((j & 1u) != 0u) ? g.y : g.x;
}

#endif /* BTF_NOISE_H */
