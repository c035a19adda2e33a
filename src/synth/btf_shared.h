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

/* The marginal transfer (docs/synthesis.md, "Marginals"), per band: v
 * clamped to the first and last knot [z0, zn], then on the segment i whose
 * knot z <= v (found by counting knots, src/synth/marginal.c and
 * gpu/synth_unmix.comp alike), q + (v - z) * slope, clamped to [q, q_next].
 * Every step is monotone in v and segment i ends at q_next where segment
 * i + 1 starts, so the map is monotone; the clamps are written as
 * comparisons (not min/max, whose signed zeros differ between C, AVX2 and
 * GLSL). Only sub, mul, add and compares: exact in Vulkan as in C. */
BTF_FN float btf_clampf(float v, float lo, float hi)
{
    float a = v < lo ? lo : v;
    return a > hi ? hi : a;
}

BTF_FN float btf_transfer(float v, float z, float slope, float q, float q_next)
{
    BTF_PRECISE float d = v - z;
    BTF_PRECISE float p = d * slope;
    BTF_PRECISE float s = q + p;
    return btf_clampf(s, q, q_next);
}

/* Gamut (docs/synthesis.md, "Marginals"): a colour outside the exemplar's
 * RGB box is moved towards the subspace's mean colour, c(t) = mean + t d
 * with d = rgb - mean, to the largest t in [0, 1] found by
 * BTF_GAMUT_STEPS halvings (division-free, so exact on every GPU) that
 * keeps all three channels in the box; then each channel is clamped to the
 * box (which only matters when the mean itself is outside it). Moving along
 * d keeps the colour on the exemplar's colour line or plane, where a
 * per-channel clamp alone would leave it (new colours in a weak band). */
#define BTF_GAMUT_STEPS 12

BTF_FN float btf_gamut_point(float mean, float t, float d)
{
    BTF_PRECISE float p = t * d;
    BTF_PRECISE float c = mean + p;
    return c;
}

BTF_FN float btf_midpoint(float a, float b)
{
    BTF_PRECISE float s = a + b;
    BTF_PRECISE float m = s * 0.5f;
    return m;
}

BTF_FN int btf_in_box(float c, float lo, float hi)
{
    return (c >= lo && c <= hi) ? 1 : 0;
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
