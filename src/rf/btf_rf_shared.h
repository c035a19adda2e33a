/*
 * btf_rf_shared.h — the evaluation of a reflectance-field model (Meseth,
 * Müller & Klein 2003; docs/rf.md) as ONE text for the CPU renderer
 * (src/rf/, C11 compiled with -ffp-contract=off) and the GPU render pass
 * (gpu/rf_render.comp, GLSL 4.50), so that the two cannot drift: the 16-bit
 * dequantisation, the parameter clamps, the PTM, lobe and Lafortune
 * luminance of a texel (sections 4.1, 4.2), the four closest measured views
 * and their bilinear weights in theta and phi (section 5.4), the local view
 * and light directions of a scene pixel, and the blend (equation (3) with
 * one light per term). The steps of a scene pixel that the CAR model's
 * renders take alike (the tangent frame, the lights' directions and
 * falloff, the per-light sum, the radiance clamp, the texel wrap) are
 * src/render/btf_shade_common.h, one text for both families.
 *
 * The arithmetic is float, each result BTF_PRECISE ("precise" in GLSL, so no
 * contraction into FMA), in one written order. pow, exp2, log2 and atan2
 * are computed here from adds and multiplies (btf_noise.h's log, a
 * polynomial exp2, Cephes' atanf), never by a library or a driver, whose
 * last bits differ between glibc and GPU drivers. Only sqrt and division
 * remain, as in src/render/btf_render_shared.h: on lavapipe (the CPU's IEEE
 * operations) both paths give the same bits; a real GPU may round those two
 * differently (tests/unit/test_gpu_rf.c states the tolerance).
 *
 * Accuracy against the double-precision functions of libm: exp2 within
 * 1.2e-7 relative on [-125, 126]; log2 from btf_noise_log (1e-7 relative);
 * pow(c, n) = exp2(n log2 c) within 1.5e-7 (2 + |n log2 c|) relative;
 * atan2 within 3e-7 rad (tests/unit/test_rf.c, shared_math_matches_libm). Values below FLT_MIN are taken as 0, so no
 * subnormal (which GPUs may flush) is ever an operand.
 *
 * Data access goes through macros that the includer defines BEFORE
 * including this file (the C side's are in src/rf/rf.h, the shader's in
 * gpu/rf_render.comp):
 *
 *   BTF_RF_CTX                  C: const rf_ctx *; GLSL: int
 *   BTF_RF_FIT(ctx)             int: 0 ptm, 1 lobes, 2 lafortune
 *   BTF_RF_LOBES(ctx)           int: k
 *   BTF_RF_NPARAMS(ctx)         int: luminance parameters (the chromaticity follows)
 *   BTF_RF_WIDTH(ctx), BTF_RF_HEIGHT(ctx)          int: texels
 *   BTF_RF_INV_WIDTH(ctx), BTF_RF_INV_HEIGHT(ctx)  float: 1.0f / width, height
 *   BTF_RF_TEXEL                the type of a texel index (C size_t, GLSL uint)
 *   BTF_RF_TEXEL_AT(ctx, x, y)  texel index of (x, y)
 *   BTF_RF_SRC                  the type of a texel's parameters in one field
 *                               (C: const float *, its dequantised slots;
 *                               GLSL: where they start, read on demand)
 *   BTF_RF_P(src, s)            float: slot s of src
 *   BTF_RF_SCRATCH(name)        declares the room BTF_RF_OPEN may fill (C:
 *                               float name[BTF_RF_SLOTS_CAP])
 *   BTF_RF_OPEN(ctx, f, t, scratch)  the BTF_RF_SRC of texel t of field f
 *   BTF_RF_VIEWSET(ctx)         the measured views' BTF_RFV_SET
 *   BTF_RF_N_LIGHTS(ctx)        int: the scene's lights
 *   BTF_RF_LIGHT_KIND(ctx, j)   int: 0 directional, 1 point (btf_light_kind)
 *   BTF_RF_LIGHT_VEC(ctx, j, k) float: direction towards it, or position
 *   BTF_RF_LIGHT_RGB(ctx, j, k) float: intensity
 *   BTF_RFV_SET                 C: const btf_dirset *; GLSL: int
 *   BTF_RFV_COUNT(s)            int: measured views
 *   BTF_RFV_THETA(s, i), BTF_RFV_PHI(s, i)  float: view i in degrees
 *   BTF_RFV_RING_END(s, i)      int: one past the last view of the ring
 *                               (equal theta) that starts at view i
 *
 * Keep this file in the common subset of C11 and GLSL 4.50 (the rules of
 * src/synth/btf_noise.h, but sqrt and division through BTF_SQRT and "/"):
 * ASCII only, no pointers and no arrays (the one scratch array of the C
 * side is BTF_RF_SCRATCH's), no casts "(T)x" (BTF_F2I, BTF_I2F of
 * btf_shade_common.h, BTF_RF_I2U below), float constants with the f suffix
 * and at most 9 significant digits, no GLSL reserved words as names.
 */
#ifndef BTF_RF_SHARED_H
#define BTF_RF_SHARED_H

#include "btf_noise.h" /* BTF_FN, BTF_PRECISE, btf_uint, bit casts, btf_noise_log */
/* btf_rgb, BTF_FLOOR, BTF_ABS, BTF_SQRT, BTF_F2I, BTF_I2F and the shading
 * steps both families take; the path is relative to this file, which both
 * the C compiler and glslangValidator search first. */
#include "../render/btf_shade_common.h"

/* The fits (btf_rf_fit_kind) and the most slots of a texel in one field
 * (BTF_RF_MAX_SLOTS of include/btfcar.h: 1 + 5 * 4 lobes + 3 colours). */
#define BTF_RF_FIT_PTM 0
#define BTF_RF_FIT_LOBES 1
#define BTF_RF_FIT_LAFORTUNE 2
#define BTF_RF_SLOTS_CAP 24

/* The parameter box (docs/rf.md, "The fits"; include/btfcar.h): lobe size
 * rho in [0, 1e4] (BTF_RF_MAX_RHO), lobe direction (x, y, 1) with |x|, |y|
 * <= 16, Lafortune coefficients |c| <= 1, log2 of the exponent in [-2, 10]
 * (n in [1/4, 1024]). Clamped at every evaluation, so any stored value -- a
 * damaged file's too -- evaluates finitely and no lobe exceeds its rho. */
#define BTF_RF_RHO_MAX 10000.0f
#define BTF_RF_XY_MAX 16.0f
#define BTF_RF_LOG2N_MIN -2.0f
#define BTF_RF_LOG2N_MAX 10.0f
/* Chromaticity factors in [0, 64], as the fit stores them (rf_chroma). */
#define BTF_RF_CHROMA_MAX 64.0f
/* 16-bit codes: v = lo + code * (hi - lo) / 65535 (docs/rf.md, "Quantisation"). */
#define BTF_RF_QSTEPS 65535.0f
#define BTF_RF_FLT_MIN 1.17549435e-38f
#define BTF_RF_FLT_MAX 3.40282347e38f
#define BTF_RF_INV_LN2 1.44269504f
#define BTF_RF_DEG 57.2957795f
#define BTF_RF_PI 3.14159265f
#define BTF_RF_PI_2 1.57079633f
#define BTF_RF_PI_4 0.785398163f
#define BTF_RF_TAN_PI_8 0.414213562f
/* 2^f = sum (f ln 2)^k / k! on [-1/2, 1/2], k <= 7 (truncation 5e-9). */
#define BTF_RF_EXP2_C1 0.693147181f
#define BTF_RF_EXP2_C2 0.240226507f
#define BTF_RF_EXP2_C3 0.0555041087f
#define BTF_RF_EXP2_C4 0.00961812911f
#define BTF_RF_EXP2_C5 0.00133335581f
#define BTF_RF_EXP2_C6 0.000154035304f
#define BTF_RF_EXP2_C7 1.52527338e-05f
/* atan on [-tan(pi/8), tan(pi/8)]: Cephes atanf.c (S. L. Moshier),
 * atan(z) = z + z^3 P(z^2). */
#define BTF_RF_ATAN_P0 0.0805374449538f
#define BTF_RF_ATAN_P1 -0.138776856032f
#define BTF_RF_ATAN_P2 0.199777106478f
#define BTF_RF_ATAN_P3 -0.333329491539f

#if defined(BTF_GLSL) || defined(VULKAN) || defined(GL_core_profile) || defined(GL_ES)
/* ------------------------------------------------------------------ GLSL */
/* The four closest measured views (field indices) and their weights. */
struct btf_rf_views {
    int i0, i1, i2, i3;
    float w0, w1, w2, w3;
};
struct btf_rf_pair {
    int i0, i1;
    float t;
};
#define BTF_RF_VIEWS(a, b, c, d, e, f, g, h) btf_rf_views(a, b, c, d, e, f, g, h)
#define BTF_RF_PAIR(a, b, c) btf_rf_pair(a, b, c)
#define BTF_RF_I2U(i) uint(i)
/* The shader defines BTF_RF_OPEN(ctx, f, t, scratch) as btf_rf_open(f, t)
 * and BTF_RF_P(src, s) as btf_rf_param(src, s): the slot
 * read and dequantised where it is used, so that no private array is
 * indexed (which lavapipe runs through scratch memory, an order of
 * magnitude slower). */
uvec4 btf_rf_open(int f, uint t);
float btf_rf_param(uvec4 src, int s);
#else
/* --------------------------------------------------------------------- C */
typedef struct btf_rf_views {
    int i0, i1, i2, i3;
    float w0, w1, w2, w3;
} btf_rf_views;
typedef struct btf_rf_pair {
    int i0, i1;
    float t;
} btf_rf_pair;
static inline btf_rf_views btf_rf_make_views(int a, int b, int c, int d, float e, float f,
                                             float g, float h)
{
    btf_rf_views v = {a, b, c, d, e, f, g, h};
    return v;
}
static inline btf_rf_pair btf_rf_make_pair(int a, int b, float c)
{
    btf_rf_pair v = {a, b, c};
    return v;
}
#define BTF_RF_VIEWS(a, b, c, d, e, f, g, h) btf_rf_make_views(a, b, c, d, e, f, g, h)
#define BTF_RF_PAIR(a, b, c) btf_rf_make_pair(a, b, c)
#define BTF_RF_I2U(i) ((btf_uint)(i))
#endif
/* A texel's colour is btf_shade_common.h's btf_rgb; the family's sources
 * and its shader know it by this name. */
#define btf_rf_rgb btf_rgb

/* ============================================== shared part: C and GLSL */

/* ------------------------------------------------ codes and parameters */

/* The step of a slot's codes: (hi - lo) / 65535, 0 for an empty range.
 * Computed once per field and slot by the host (C) for both paths. */
BTF_FN float btf_rf_scale(float lo, float hi)
{
    BTF_PRECISE float d = hi - lo;
    BTF_PRECISE float s = d / BTF_RF_QSTEPS;
    return hi > lo ? s : 0.0f;
}

/* A 16-bit code's value: lo + code * scale. */
BTF_FN float btf_rf_dequant(btf_uint q, float lo, float scale)
{
    BTF_PRECISE float s = BTF_U2F(q) * scale;
    BTF_PRECISE float v = lo + s;
    return v;
}

/* x within [lo, hi]; NaN gives lo. */
BTF_FN float btf_rf_clamp(float x, float lo, float hi)
{
    return !(x >= lo) ? lo : x > hi ? hi : x;
}

/* ------------------------------------------------ exp2, log2, pow, atan2 */

/* 2^t: t = k + f with k an integer and |f| <= 1/2, 2^f by its Taylor
 * polynomial, 2^k put into the exponent bits. 0 below 2^-125 (so that no
 * result is subnormal); t is held at 126. */
BTF_FN float btf_rf_exp2(float t)
{
    if (!(t > -125.0f))
        return 0.0f;
    float tt = t < 126.0f ? t : 126.0f;
    float k = BTF_FLOOR(tt + 0.5f);
    BTF_PRECISE float f = tt - k;
    BTF_PRECISE float p = 1.0f + f * (BTF_RF_EXP2_C1 + f * (BTF_RF_EXP2_C2 + f * (BTF_RF_EXP2_C3 +
                          f * (BTF_RF_EXP2_C4 + f * (BTF_RF_EXP2_C5 + f * (BTF_RF_EXP2_C6 +
                          f * BTF_RF_EXP2_C7))))));
    int e = BTF_F2I(k) + 127;
    BTF_PRECISE float r = p * btf_bits_float(BTF_RF_I2U(e) << 23u);
    return r;
}

/* c^n for c >= 0, n in [1/4, 1024]: exp2(n log2 c), log2 from
 * btf_noise_log; 0 for c below FLT_MIN (and for NaN). */
BTF_FN float btf_rf_pow(float c, float n)
{
    if (!(c >= BTF_RF_FLT_MIN))
        return 0.0f;
    float cc = c < BTF_RF_FLT_MAX ? c : BTF_RF_FLT_MAX;
    BTF_PRECISE float l = btf_noise_log(cc);
    BTF_PRECISE float l2 = l * BTF_RF_INV_LN2;
    BTF_PRECISE float t = n * l2;
    return btf_rf_exp2(t);
}

/* atan2(y, x) in radians, in (-pi, pi]; (0, 0) gives 0. Octant
 * reduction to a = min/max in [0, 1], then Cephes' range reduction at
 * tan(pi/8) and its polynomial. */
BTF_FN float btf_rf_atan2(float y, float x)
{
    float ax = BTF_ABS(x), ay = BTF_ABS(y);
    float mx = ax > ay ? ax : ay, mn = ax > ay ? ay : ax;
    if (!(mx > 0.0f) || !(mx <= BTF_RF_FLT_MAX))
        return 0.0f;
    BTF_PRECISE float a = mn / mx;
    BTF_PRECISE float z = a;
    float base = 0.0f;
    if (a > BTF_RF_TAN_PI_8) {
        BTF_PRECISE float num = a - 1.0f;
        BTF_PRECISE float den = a + 1.0f;
        z = num / den;
        base = BTF_RF_PI_4;
    }
    BTF_PRECISE float z2 = z * z;
    BTF_PRECISE float q = ((BTF_RF_ATAN_P0 * z2 + BTF_RF_ATAN_P1) * z2 + BTF_RF_ATAN_P2) * z2 +
                          BTF_RF_ATAN_P3;
    BTF_PRECISE float zq = z2 * z;
    BTF_PRECISE float r = base + (zq * q + z);
    if (ay > ax)
        r = BTF_RF_PI_2 - r;
    if (x < 0.0f)
        r = BTF_RF_PI - r;
    if (y < 0.0f)
        r = -r;
    return r;
}

/* ------------------------------------------------------- the fits */

/* One lobe rho <d, l>^n, d = (x, y, 1) / |(x, y, 1)|, parameters (rho, x,
 * y, log2 n) clamped to the box first: a finite result in [0, rho]
 * (paper section 4.2, equation (1), in the form of docs/rf.md). */
BTF_FN float btf_rf_lobe(float rho0, float x0, float y0, float e0, float lx, float ly, float lz)
{
    float rho = btf_rf_clamp(rho0, 0.0f, BTF_RF_RHO_MAX);
    float x = btf_rf_clamp(x0, -BTF_RF_XY_MAX, BTF_RF_XY_MAX);
    float y = btf_rf_clamp(y0, -BTF_RF_XY_MAX, BTF_RF_XY_MAX);
    float n = btf_rf_exp2(btf_rf_clamp(e0, BTF_RF_LOG2N_MIN, BTF_RF_LOG2N_MAX));
    BTF_PRECISE float xx = x * x;
    BTF_PRECISE float yy = y * y;
    BTF_PRECISE float s1 = xx + yy;
    BTF_PRECISE float s2 = s1 + 1.0f;
    BTF_PRECISE float len = BTF_SQRT(s2);
    BTF_PRECISE float a = x * lx;
    BTF_PRECISE float b = y * ly;
    BTF_PRECISE float ab = a + b;
    BTF_PRECISE float d = ab + lz;
    BTF_PRECISE float c = d / len;
    if (!(c > 0.0f))
        return 0.0f;
    BTF_PRECISE float r = rho * btf_rf_pow(c, n);
    return r;
}

/* One Lafortune lobe rho (cx lx vx + cy ly vy + cz lz vz)^n, |c.| <= 1 so
 * the base is at most 1; parameters (rho, cx, cy, cz, log2 n). */
BTF_FN float btf_rf_lafortune_lobe(float rho0, float cx0, float cy0, float cz0, float e0,
                                   float lx, float ly, float lz, float vx, float vy, float vz)
{
    float rho = btf_rf_clamp(rho0, 0.0f, BTF_RF_RHO_MAX);
    float cx = btf_rf_clamp(cx0, -1.0f, 1.0f);
    float cy = btf_rf_clamp(cy0, -1.0f, 1.0f);
    float cz = btf_rf_clamp(cz0, -1.0f, 1.0f);
    float n = btf_rf_exp2(btf_rf_clamp(e0, BTF_RF_LOG2N_MIN, BTF_RF_LOG2N_MAX));
    BTF_PRECISE float a0 = cx * lx;
    BTF_PRECISE float a = a0 * vx;
    BTF_PRECISE float b0 = cy * ly;
    BTF_PRECISE float b = b0 * vy;
    BTF_PRECISE float c0 = cz * lz;
    BTF_PRECISE float c = c0 * vz;
    BTF_PRECISE float ab = a + b;
    BTF_PRECISE float s = ab + c;
    if (!(s > 0.0f))
        return 0.0f;
    BTF_PRECISE float r = rho * btf_rf_pow(s, n);
    return r;
}

/* The luminance of one texel's field with parameters p (the fit's slot
 * order, docs/rf.md "File"): light (lx, ly, lz), view (vx, vy, vz)
 * (Lafortune only), unit vectors in the tangent frame. Never negative and
 * never non-finite: a PTM below zero (past the measured lights) gives 0. */
BTF_FN float btf_rf_lum(BTF_RF_SRC p, int fit, int lobes, float lx, float ly, float lz, float vx,
                        float vy, float vz)
{
    BTF_PRECISE float y = 0.0f;
    if (fit == BTF_RF_FIT_PTM) {
        /* paper section 4.1 / Malzbender et al. 2001: a0 lu^2 + a1 lv^2 +
         * a2 lu lv + a3 lu + a4 lv + a5, (lu, lv) = (lx, ly) */
        BTF_PRECISE float uu = lx * lx;
        BTF_PRECISE float vv = ly * ly;
        BTF_PRECISE float uv = lx * ly;
        BTF_PRECISE float t0 = BTF_RF_P(p, 0) * uu;
        BTF_PRECISE float t1 = BTF_RF_P(p, 1) * vv;
        BTF_PRECISE float t2 = BTF_RF_P(p, 2) * uv;
        BTF_PRECISE float t3 = BTF_RF_P(p, 3) * lx;
        BTF_PRECISE float t4 = BTF_RF_P(p, 4) * ly;
        y = ((((t0 + t1) + t2) + t3) + t4) + BTF_RF_P(p, 5);
    } else if (fit == BTF_RF_FIT_LOBES) {
        for (int i = 0; i < lobes; i++)
            y = y + btf_rf_lobe(BTF_RF_P(p, 4 * i), BTF_RF_P(p, 4 * i + 1),
                                BTF_RF_P(p, 4 * i + 2), BTF_RF_P(p, 4 * i + 3), lx, ly, lz);
    } else {
        float rd = btf_rf_clamp(BTF_RF_P(p, 0), 0.0f, BTF_RF_RHO_MAX);
        float lzp = lz > 0.0f ? lz : 0.0f;
        y = rd * lzp;
        for (int i = 0; i < lobes; i++)
            y = y + btf_rf_lafortune_lobe(BTF_RF_P(p, 1 + 5 * i), BTF_RF_P(p, 2 + 5 * i),
                                          BTF_RF_P(p, 3 + 5 * i), BTF_RF_P(p, 4 + 5 * i),
                                          BTF_RF_P(p, 5 + 5 * i), lx, ly, lz, vx, vy, vz);
    }
    return y > 0.0f && y <= BTF_RF_FLT_MAX ? y : 0.0f;
}

/* ------------------------------------------ the four closest views */

/* phi brought into [0, 360). */
BTF_FN float btf_rf_wrap360(float phi)
{
    BTF_PRECISE float q = phi / 360.0f;
    float k = BTF_FLOOR(q);
    BTF_PRECISE float k360 = 360.0f * k;
    BTF_PRECISE float r = phi - k360;
    if (r >= 360.0f)
        r = r - 360.0f;
    if (r < 0.0f)
        r = r + 360.0f;
    return r >= 0.0f && r < 360.0f ? r : 0.0f;
}

/* Within the ring of views [a, b): the two measured azimuths around phi
 * and the weight t of the second (a ring of one view: that view, t = 0). */
BTF_FN btf_rf_pair btf_rf_ring_pair(BTF_RFV_SET s, int a, int b, float phi)
{
    if (b - a <= 1)
        return BTF_RF_PAIR(a, a, 0.0f);
    float ph = btf_rf_wrap360(phi);
    /* the last view whose phi <= ph, circularly (before the first: the
     * last); a ring's azimuths ascend (btf_dirset's order), so the scan
     * stops at the first one past ph */
    int j = b - 1;
    for (int k = a; k < b; k++) {
        if (!(BTF_RFV_PHI(s, k) <= ph))
            break;
        j = k;
    }
    int j1 = j + 1 < b ? j + 1 : a;
    BTF_PRECISE float gap = BTF_RFV_PHI(s, j1) - BTF_RFV_PHI(s, j);
    if (!(gap > 0.0f))
        gap = gap + 360.0f;
    if (!(gap > 0.0f)) /* two views on one azimuth: not in a dirset */
        gap = 360.0f;
    BTF_PRECISE float off = ph - BTF_RFV_PHI(s, j);
    if (off < 0.0f)
        off = off + 360.0f;
    BTF_PRECISE float t = off / gap;
    return BTF_RF_PAIR(j, j1, btf_rf_clamp(t, 0.0f, 1.0f));
}

/* The four closest measured views of (theta, phi) in degrees and their
 * weights (paper section 5.4: "we choose the closest theta values from the
 * existing measurement data. Next, for each such theta, we determine the
 * closest phi values [...] The according weights are computed via
 * bilinear interpolation"): the rings around theta (the nearest alone
 * below the first or past the last ring), on each the two azimuths around
 * phi, weights (1 - wt)(1 - t0), (1 - wt) t0, wt (1 - t1), wt t1, which sum
 * to 1 (to float rounding) and vary continuously. At a measured view the
 * weight is exactly 1 on it. */
BTF_FN btf_rf_views btf_rf_four_views(BTF_RFV_SET s, float theta, float phi)
{
    int n = BTF_RFV_COUNT(s);
    int r0 = 0, r1 = -1;
    int a = 0;
    while (a < n) {
        if (BTF_RFV_THETA(s, a) <= theta) {
            r0 = a;
            a = BTF_RFV_RING_END(s, a);
        } else {
            r1 = a;
            break;
        }
    }
    BTF_PRECISE float wt = 0.0f;
    if (BTF_RFV_THETA(s, r0) > theta) {
        r1 = -1; /* below the first ring */
    } else if (r1 >= 0) {
        BTF_PRECISE float num = theta - BTF_RFV_THETA(s, r0);
        BTF_PRECISE float den = BTF_RFV_THETA(s, r1) - BTF_RFV_THETA(s, r0);
        wt = num / den;
    }
    btf_rf_pair p0 = btf_rf_ring_pair(s, r0, BTF_RFV_RING_END(s, r0), phi);
    btf_rf_pair p1 = BTF_RF_PAIR(p0.i0, p0.i1, 0.0f);
    if (r1 >= 0)
        p1 = btf_rf_ring_pair(s, r1, BTF_RFV_RING_END(s, r1), phi);
    BTF_PRECISE float u = 1.0f - wt;
    BTF_PRECISE float a0 = 1.0f - p0.t;
    BTF_PRECISE float a1 = 1.0f - p1.t;
    BTF_PRECISE float w0 = u * a0;
    BTF_PRECISE float w1 = u * p0.t;
    BTF_PRECISE float w2 = wt * a1;
    BTF_PRECISE float w3 = wt * p1.t;
    return BTF_RF_VIEWS(p0.i0, p0.i1, p1.i0, p1.i1, w0, w1, w2, w3);
}

/* The views a texel seen from the local direction (vx, vy, vz) (any
 * length, vz > 0) blends: the four closest measured views, at theta =
 * atan2(|(vx, vy)|, vz) and phi = atan2(vy, vx); a Lafortune model's one
 * field, which is evaluated at the view itself. */
BTF_FN btf_rf_views btf_rf_views_at(BTF_RF_CTX ctx, float vx, float vy, float vz)
{
    if (BTF_RF_FIT(ctx) == BTF_RF_FIT_LAFORTUNE)
        return BTF_RF_VIEWS(0, 0, 0, 0, 1.0f, 0.0f, 0.0f, 0.0f);
    BTF_PRECISE float rho = btf_shade_len_xy(vx, vy);
    BTF_PRECISE float theta = btf_rf_atan2(rho, vz) * BTF_RF_DEG;
    BTF_PRECISE float phi = btf_rf_atan2(vy, vx) * BTF_RF_DEG;
    return btf_rf_four_views(BTF_RF_VIEWSET(ctx), theta, phi);
}

/* --------------------------------------------------------- the blend */

/* Linear RGB of texel t under the unit light (lx, ly, lz): each field of vs
 * with a non-zero weight, its luminance times its chromaticity (the three
 * slots after the luminance parameters, held in [0, 64] as the fit
 * stores them), weighted and summed in the order
 * of vs (paper equation (3) for one light: "multiply the resulting
 * luminances by the average colors for the reflectance field and the
 * weights w_v, and add them"). (vx, vy, vz): the unit view, for Lafortune. */
BTF_FN btf_rgb btf_rf_blend(BTF_RF_CTX ctx, btf_rf_views vs, BTF_RF_TEXEL t, float lx,
                            float ly, float lz, float vx, float vy, float vz)
{
    int fit = BTF_RF_FIT(ctx), lobes = BTF_RF_LOBES(ctx), np = BTF_RF_NPARAMS(ctx);
    BTF_RF_SCRATCH(scratch);
    BTF_PRECISE float r = 0.0f;
    BTF_PRECISE float g = 0.0f;
    BTF_PRECISE float b = 0.0f;
    for (int i = 0; i < 4; i++) {
        float w = i == 0 ? vs.w0 : i == 1 ? vs.w1 : i == 2 ? vs.w2 : vs.w3;
        int f = i == 0 ? vs.i0 : i == 1 ? vs.i1 : i == 2 ? vs.i2 : vs.i3;
        if (w == 0.0f)
            continue;
        BTF_RF_SRC p = BTF_RF_OPEN(ctx, f, t, scratch);
        float lum = btf_rf_lum(p, fit, lobes, lx, ly, lz, vx, vy, vz);
        BTF_PRECISE float cr = lum * btf_rf_clamp(BTF_RF_P(p, np), 0.0f, BTF_RF_CHROMA_MAX);
        BTF_PRECISE float cg = lum * btf_rf_clamp(BTF_RF_P(p, np + 1), 0.0f, BTF_RF_CHROMA_MAX);
        BTF_PRECISE float cb = lum * btf_rf_clamp(BTF_RF_P(p, np + 2), 0.0f, BTF_RF_CHROMA_MAX);
        BTF_PRECISE float tr = w * cr;
        BTF_PRECISE float tg = w * cg;
        BTF_PRECISE float tb = w * cb;
        r = r + tr;
        g = g + tg;
        b = b + tb;
    }
    return BTF_RGB(r, g, b);
}

/* ------------------------------------------------------- scene pixels */

/* The texel of texture coordinate c along a side of n texels: floor(c)
 * wrapped into [0, n) (inv_n = 1.0f / n), exactly for |c| < 2^24; beyond
 * 10^30 (or NaN) the coordinate is taken as 0. */
BTF_FN int btf_rf_wrap(float c, int n, float inv_n)
{
    float fl = BTF_FLOOR(btf_shade_coord(c));
    BTF_PRECISE float q = fl * inv_n;
    float k = BTF_FLOOR(q);
    BTF_PRECISE float nk = BTF_I2F(n) * k;
    BTF_PRECISE float r = fl - nk;
    if (!(BTF_ABS(r) < 16777216.0f)) /* past 2^24 floats skip texels */
        r = 0.0f;
    return btf_shade_wrap(BTF_F2I(r), n);
}

/* Light j seen from the world point (px, py, pz): btf_shade_light's unit
 * direction (x, y, z) and intensity scale (w). A directional light's
 * vector is normalised here, in float: the hosts (src/rf/rf.h,
 * gpu/rf_render_gpu.c) pass the scene's as it is. */
BTF_FN btf_vec4 btf_rf_light(BTF_RF_CTX ctx, int j, float px, float py, float pz)
{
    return btf_shade_light(BTF_RF_LIGHT_KIND(ctx, j) == 1 ? 1 : 0, BTF_RF_LIGHT_VEC(ctx, j, 0),
                           BTF_RF_LIGHT_VEC(ctx, j, 1), BTF_RF_LIGHT_VEC(ctx, j, 2), px, py, pz);
}

/* One pixel of a scene (docs/rf.md, "Rendering"): frame rows T (f0..f2),
 * B (f3..f5), N (f6..f8), world hit (px, py, pz), world unit vector to the
 * eye (ex, ey, ez), texture coordinate (u, v). The local view is held at
 * least BTF_SHADE_MIN_Z above the horizon; the texel is floor(u), floor(v)
 * wrapped into the model; per light above the surface's horizon the four
 * closest views' fields at the exact light direction, times the light's
 * intensity (and 1/d^2). Linear RGB, >= 0 and finite. No parallax and no
 * bump mapping: a field holds the surface's relief itself. */
BTF_FN btf_rgb btf_rf_shade_pixel(BTF_RF_CTX ctx, float f0, float f1, float f2, float f3,
                                  float f4, float f5, float f6, float f7, float f8, float px,
                                  float py, float pz, float ex, float ey, float ez, float u,
                                  float v)
{
    btf_rgb w = btf_shade_local_view(f0, f1, f2, f3, f4, f5, f6, f7, f8, ex, ey, ez);
    float vx = w.r, vy = w.g, vz = w.b;
    btf_rf_views vs = btf_rf_views_at(ctx, vx, vy, vz);
    /* the unit view, which a Lafortune lobe is evaluated at */
    btf_rgb n = btf_shade_unit(vx, vy, vz, 0.0f);
    int tx = btf_rf_wrap(u, BTF_RF_WIDTH(ctx), BTF_RF_INV_WIDTH(ctx));
    int ty = btf_rf_wrap(v, BTF_RF_HEIGHT(ctx), BTF_RF_INV_HEIGHT(ctx));
    BTF_RF_TEXEL t = BTF_RF_TEXEL_AT(ctx, tx, ty);
    btf_rgb sum = BTF_RGB(0.0f, 0.0f, 0.0f);
    for (int j = 0; j < BTF_RF_N_LIGHTS(ctx); j++) {
        btf_vec4 d = btf_rf_light(ctx, j, px, py, pz);
        if (d.w == 0.0f)
            continue;
        btf_rgb l = btf_shade_local(f0, f1, f2, f3, f4, f5, f6, f7, f8, d.x, d.y, d.z);
        if (!(l.b > 0.0f))
            continue; /* below the surface's horizon: no light */
        btf_rgb c = btf_rf_blend(ctx, vs, t, l.r, l.g, l.b, n.r, n.g, n.b);
        sum = btf_shade_add_light(sum, BTF_RF_LIGHT_RGB(ctx, j, 0), BTF_RF_LIGHT_RGB(ctx, j, 1),
                                  BTF_RF_LIGHT_RGB(ctx, j, 2), d.w, c);
    }
    return btf_shade_radiance(sum);
}

#endif /* BTF_RF_SHARED_H */
