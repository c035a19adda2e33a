/*
 * btf_shared.h — constants and formulas of CAR synthesis (Haindl & Filip
 * 2007, section II.C: the causal recursion, the pyramid collapse, the
 * inverse decorrelation) shared, as the very same text, by the CPU code
 * (src/synth/, C11 with -ffp-contract=off) and the Vulkan compute shaders
 * (gpu/synth_*.comp, GLSL 4.50). Every float function performs its
 * operations in one written order, each result `precise` in GLSL, so the
 * two paths agree bit for bit. Keep it in the common subset of C and GLSL
 * (see src/synth/btf_noise.h).
 */
#ifndef BTF_SHARED_H
#define BTF_SHARED_H

#include "btf_noise.h"

/* The rows a level's CAR field starts above its window, and the columns it
 * extends on either side, are the band's margin (src/car/margin.c), computed
 * on the host for both paths. Field coordinates are signed (burn-in rows
 * and margins are negative); the noise counter takes them plus this origin,
 * as unsigned. */
#define BTF_NOISE_ORIGIN 268435456 /* 2^28 */
/* The largest output side: coordinates plus margins stay far from 2^28. */
#define BTF_SYNTH_MAX_SIDE 16777216 /* 2^24 */

/* The sum of one field pixel, Y = sum_s gamma_s Y_s + sigma e, runs in this
 * order on both sides: from 0, the offsets of earlier rows in stored order
 * (btf_car_accumulate), then the noise (btf_car_output), then the same-row
 * offsets from the farthest column to the nearest (btf_car_accumulate). The
 * nearest neighbour comes last so that on the CPU one pixel waits on the
 * previous one for a single multiply and add. */

/* GPU work per invocation is bounded: lavapipe silently ends an invocation
 * after some 13,000 iterations of an inner loop. Pixel loops cover at most
 * BTF_GPU_CHUNK pixels per workgroup of 64 (2,048 iterations); the wavefront
 * runs at most BTF_GPU_LOOP_BUDGET pixel iterations per dispatch. */
#define BTF_GPU_CHUNK 131072
#define BTF_GPU_LOOP_BUDGET 4096

/* floor(a / 2) for any sign: the coarse column or row of a fine one (level
 * windows, src/synth/geometry.h; the up-sampling of the collapse). */
BTF_FN int btf_floordiv2(int a)
{
    return a >= 0 ? a / 2 : -((-a + 1) / 2);
}

/* Tileable synthesis (docs/synthesis.md, "Tileable synthesis"): a field
 * pixel at signed coordinate a takes the noise of a mod n (floor-mod, n >
 * 0), burn-in rows and margin columns included, so that the streaming
 * recursion converges to the field on the torus. Written without % on a
 * negative operand (undefined in GLSL). */
BTF_FN int btf_period_coord(int a, int n)
{
    return a >= 0 ? a % n : (n - 1) - ((-a - 1) % n);
}

/* One step of the neighbourhood sum: acc + gamma * y. */
BTF_FN float btf_car_accumulate(float acc, float gamma, float y)
{
    BTF_PRECISE float p = gamma * y;
    BTF_PRECISE float s = acc + p;
    return s;
}

/* The new field value: the prediction plus the scaled noise. */
BTF_FN float btf_car_output(float acc, float sigma, float e)
{
    BTF_PRECISE float p = sigma * e;
    BTF_PRECISE float s = acc + p;
    return s;
}

BTF_FN float btf_add_mean(float mean, float field)
{
    BTF_PRECISE float s = mean + field;
    return s;
}

BTF_FN float btf_add_level(float a, float b)
{
    BTF_PRECISE float s = a + b;
    return s;
}

/* pyrUp in one dimension: an even fine sample from coarse a, b, c with
 * weights 1, 6, 1 over 8; an odd one halfway between b and c. */
BTF_FN float btf_up_even(float a, float b, float c)
{
    BTF_PRECISE float ac = a + c;
    BTF_PRECISE float b6 = b * 6.0f;
    BTF_PRECISE float s = ac + b6;
    BTF_PRECISE float r = s * 0.125f;
    return r;
}

BTF_FN float btf_up_odd(float b, float c)
{
    BTF_PRECISE float s = b + c;
    BTF_PRECISE float r = s * 0.5f;
    return r;
}

/* Inverse decorrelation of one colour channel k: mean_k + sum_b basis[b][k] v_b. */
BTF_FN float btf_unmix(float mean, float b0, float b1, float b2, float v0, float v1, float v2)
{
    BTF_PRECISE float p0 = b0 * v0;
    BTF_PRECISE float s0 = mean + p0;
    BTF_PRECISE float p1 = b1 * v1;
    BTF_PRECISE float s1 = s0 + p1;
    BTF_PRECISE float p2 = b2 * v2;
    BTF_PRECISE float s2 = s1 + p2;
    return s2;
}

/* The marginal transfer (docs/synthesis.md, "Marginals"), per band: a
 * monotone piecewise-linear map on BTF_MARGIN_SEGS segments of equal width
 * between the band's second and last-but-one knot, and one segment beyond
 * each (the model's first and last segments), so that the segment of v is
 * found by a subtraction, a multiplication and a floor instead of a search
 * (the colour step runs beside the CAR fields and must keep up). v's place
 * on the grid, t = (v - origin) * inv_h clamped to [tlo, thi] (where the
 * end knots fall); its segment fl = floor(t) clamped to [-1, SEGS]: -1 and
 * SEGS are the tails, whose f runs past [0, 1]; entry fl & 15 of the
 * band's 16-entry table (the lower tail is entry 15), so that the CPU
 * fetches it with two in-register permutes; f = t - fl; the value
 * q + f * dq clamped to the exemplar's range [qmin, qmax]. The table
 * (src/synth/marginal.c) is made on the host so that q + dq does not pass
 * the next segment's q: every step is monotone under round-to-nearest and
 * a segment ends at or below where the next starts, so the map is
 * monotone. The clamps are comparisons (not min/max, whose signed zeros
 * differ between C, AVX2 and GLSL). Only sub, mul, add, floor and
 * compares: exact in Vulkan as in C. */
#define BTF_MARGIN_SEGS 14
#define BTF_MARGIN_TABLE 16

BTF_FN float btf_clampf(float v, float lo, float hi)
{
    float a = v < lo ? lo : v;
    return a > hi ? hi : a;
}

BTF_FN float btf_knot_pos(float v, float origin, float inv_h, float tlo, float thi)
{
    BTF_PRECISE float d = v - origin;
    BTF_PRECISE float t = d * inv_h;
    return btf_clampf(t, tlo, thi);
}

/* fl: floor(t) (floorf / floor / _mm256_floor_ps: exact everywhere),
 * clamped by btf_knot_segment. */
BTF_FN float btf_knot_segment(float fl)
{
    return btf_clampf(fl, -1.0f, 14.0f); /* BTF_MARGIN_SEGS */
}

BTF_FN float btf_transfer(float t, float fl, float q, float dq, float qmin, float qmax)
{
    BTF_PRECISE float f = t - fl;
    BTF_PRECISE float p = f * dq;
    BTF_PRECISE float s = q + p;
    return btf_clampf(s, qmin, qmax);
}

/* Gamut (docs/synthesis.md, "Marginals"): a colour outside the exemplar's
 * RGB box is moved towards the subspace's mean colour, c(t) = mean + t d
 * with d = rgb - mean, to the largest t in [0, 1] that keeps all three
 * channels in the box, t = min over the channels outside of
 * (bound - mean) / |d| (bound: the side it crossed); then each channel is
 * clamped to the box (which absorbs the rounding of t and matters only
 * when the mean itself is outside it). Moving along d keeps the colour on
 * the exemplar's colour line or plane, where a per-channel clamp alone
 * would leave it (new colours in a weak band). A closed form where 12
 * halvings were (a tenth of the work, and branch-free, so the CPU runs it
 * on 8 pixels at a time). The quotient comes from btf_recip, not a
 * division: Vulkan's division is not correctly rounded, so the CPU and
 * the GPU would differ. */
BTF_FN float btf_gamut_point(float mean, float t, float d)
{
    BTF_PRECISE float p = t * d;
    BTF_PRECISE float c = mean + p;
    return c;
}

BTF_FN int btf_in_box(float c, float lo, float hi)
{
    return (c >= lo && c <= hi) ? 1 : 0;
}

/* 1 / x for x in [2^-40, 2^40] (the caller clamps), without a division:
 * a first guess from the bits (within 12.5 %), then three Newton steps
 * r (2 - x r), each squaring the relative error (to about 1e-7). Integer
 * and float ops only, so the same bits in C, AVX2 and GLSL; no subnormal
 * on the way (flushed on some GPUs). */
#define BTF_RECIP_MIN 9.094947017729282e-13f /* 2^-40 */
#define BTF_RECIP_MAX 1099511627776.0f        /* 2^40 */

BTF_FN float btf_recip_step(float x, float r)
{
    BTF_PRECISE float e = x * r;
    BTF_PRECISE float n = 2.0f - e;
    BTF_PRECISE float s = r * n;
    return s;
}

BTF_FN float btf_recip(float x)
{
    float r = btf_bits_float(0x7EF311C7u - btf_float_bits(x));
    r = btf_recip_step(x, r);
    r = btf_recip_step(x, r);
    return btf_recip_step(x, r);
}

/* The largest share of d = c - mean that channel c allows: 1 inside
 * [lo, hi]; above hi, nhi / |d| (nhi = hi - mean); below lo, nlo / |d|
 * (nlo = mean - lo). nhi and nlo come from the host's table. */
BTF_FN float btf_gamut_share(float c, float mean, float lo, float hi, float nlo, float nhi)
{
    BTF_PRECISE float d = c - mean;
    BTF_PRECISE float nd = 0.0f - d;
    float ad = d < 0.0f ? nd : d;
    float r = btf_recip(btf_clampf(ad, BTF_RECIP_MIN, BTF_RECIP_MAX));
    float num = c > hi ? nhi : nlo;
    BTF_PRECISE float s = num * r;
    return (c > hi || c < lo) ? s : 1.0f;
}

#if !defined(BTF_GLSL) && !defined(VULKAN) && !defined(GL_core_profile) && !defined(GL_ES)
/* C only: the four Gaussians of one noise block into an array. */
static inline void btf_noise_block(btf_uint seed_lo, btf_uint seed_hi, btf_uint stream,
                                   btf_uint row, btf_uint block, float e[4])
{
    btf_vec4 v = btf_noise4(seed_lo, seed_hi, stream, row, block);
    e[0] = v.x;
    e[1] = v.y;
    e[2] = v.z;
    e[3] = v.w;
}
#endif

#endif /* BTF_SHARED_H */
