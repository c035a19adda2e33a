/*
 * btf_horizon.h — the relief's cast shadows by horizon mapping (Max 1988,
 * "Horizon mapping: shadows for bump-mapped surfaces"; docs/render.md,
 * "Shadows"), as one text for the CPU renderer, the GPU render pass and
 * the analysis' structure layer (analyse/structure_fit.c), so that what the
 * analysis divides out is what the renderer multiplies back.
 *
 * For every texel and each of BTF_HORIZON_DIRS azimuths (world x right,
 * y up, as the normals; direction d at d * 45 degrees) the map holds the
 * tangent of the highest elevation at which the relief hides the sky,
 * marched up to BTF_HORIZON_REACH texels (render/horizon.c). A light of
 * tangent-frame direction (lx, ly, lz) is seen where the tangent of its
 * elevation, lz / |l_xy|, clears r times that horizon (r the relief scale,
 * which scales every height); the edge is soft over BTF_SHADOW_SOFT in
 * tangent, as a light of ~2.3 degrees' radius casts it. The horizon
 * between two mapped azimuths is interpolated linearly in the "diamond
 * angle" (a monotone function of the azimuth that needs one division, no
 * arctangent, so the two paths agree to rounding).
 *
 * Packing: one byte per direction, the tangent times BTF_HORIZON_PER_UNIT
 * rounded (0..255), four directions per 32-bit word: word 0 holds
 * directions 0..3 (direction d in bits 8d..8d+7), word 1 directions 4..7.
 * The common subset of C and GLSL (rules of btf__hemisphere_lookup.h).
 */
#ifndef BTF_HORIZON_H
#define BTF_HORIZON_H

#include "btf_shade_common.h" /* btf_noise.h's BTF_FN, BTF_PRECISE, BTF_U2F; btf_shade_len_xy */

#define BTF_HORIZON_DIRS 8
#define BTF_HORIZON_PER_UNIT 64.0f /* codes per unit of tangent: 255 is 3.98 (76 degrees) */
#define BTF_HORIZON_REACH 24       /* texels marched from each texel */
#define BTF_SHADOW_SOFT 0.04f      /* half-width of a shadow's edge, in tangent */
/* The view march of a relief that casts shadows (btf_shade_march in
 * btf_render_shared.h, btf__structure_warp in the analysis): steps of at
 * most this many texels, at most this many steps. */
#define BTF_MARCH_STEP 0.5f
#define BTF_MARCH_MAX 96

/* The horizon tangent of direction d (0..7) from a texel's two words. */
BTF_FN float btf_horizon_decode(btf_uint w0, btf_uint w1, int d)
{
    btf_uint w = d < 4 ? w0 : w1;
    btf_uint q = (w >> (8 * (d & 3))) & 255u;
    BTF_PRECISE float t = BTF_U2F(q) / BTF_HORIZON_PER_UNIT;
    return t;
}

/* The diamond angle of (lx, ly) times 2: 0 along +x, 2 along +y, 4 along
 * -x, 6 along -y, in [0, 8); direction d of the map sits at exactly d. */
BTF_FN float btf_horizon_azimuth(float lx, float ly)
{
    float ax = lx < 0.0f ? -lx : lx;
    float ay = ly < 0.0f ? -ly : ly;
    BTF_PRECISE float l1 = ax + ay;
    if (!(l1 > 1e-30f))
        return 0.0f;
    BTF_PRECISE float qx = ax / l1;
    BTF_PRECISE float qy = ay / l1;
    BTF_PRECISE float p = qy;
    if (lx < 0.0f && ly >= 0.0f)
        p = 1.0f + qx;
    else if (lx < 0.0f)
        p = 2.0f + qy;
    else if (ly < 0.0f)
        p = 3.0f + qx;
    BTF_PRECISE float t = 2.0f * p;
    return t < 8.0f ? t : 0.0f;
}

/* The light's visibility, 0..1, at a texel of horizon tangent h (in the
 * light's azimuth, unscaled heights) under relief scale r. r <= 0 (a
 * flat or inverted relief, which the map does not describe) and a light
 * at the pole see everything. */
BTF_FN float btf_horizon_vis(float h, float lx, float ly, float lz, float r)
{
    if (!(r > 0.0f))
        return 1.0f;
    BTF_PRECISE float lxy = btf_shade_len_xy(lx, ly);
    if (!(lxy > 1e-6f))
        return 1.0f;
    BTF_PRECISE float rh = r * h;
    BTF_PRECISE float occ = rh * lxy;
    BTF_PRECISE float num = lz - occ;
    BTF_PRECISE float den = 2.0f * BTF_SHADOW_SOFT;
    BTF_PRECISE float den2 = den * lxy;
    BTF_PRECISE float q = num / den2;
    BTF_PRECISE float v = 0.5f + q;
    return v > 1.0f ? 1.0f : v > 0.0f ? v : 0.0f;
}

#endif /* BTF_HORIZON_H */
