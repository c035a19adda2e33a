/*
 * btf_render_shared.h — the per-pixel shading of the renderer (Haindl &
 * Filip 2007, section III and Fig. 1; docs/render.md, "Shading"), as the
 * very same text for the CPU renderer (src/render/shade.c, C11 with
 * -ffp-contract=off) and the GPU render pass (gpu/render.comp, GLSL 4.50),
 * so that the two cannot drift: the constants, the wrapped bilinear taps,
 * the parallax shift, the relief normal, the pair weights, the bump factor
 * and the horizon fade. The direction lookup is btf__hemisphere_lookup.h's;
 * the tangent frame, the lights' directions and falloff, the per-light sum
 * and the radiance clamp are btf_shade_common.h's, which the reflectance
 * field's renders (src/rf/btf_rf_shared.h) share.
 *
 * Data access goes through accessor macros that the includer defines
 * BEFORE including this file (the C side's are below); every function
 * takes a first parameter `ctx` of type BTF_SHADE_CTX:
 *
 *   BTF_SHADE_CTX                   C: const struct btf_shade_ctx *; GLSL: int
 *   BTF_SHADE_VIEWS(ctx)            the views' BTF_HEMI_TABLE
 *   BTF_SHADE_LIGHTS(ctx)           the lights' BTF_HEMI_TABLE
 *   BTF_SHADE_SIZE(ctx)             int: side of the textures
 *   BTF_SHADE_N_LIGHTS_SET(ctx)     int: measured lights (the index table's row)
 *   BTF_SHADE_INDEX(ctx, i)         int: subspace of pair i = view * n + light
 *   BTF_SHADE_HAVE(ctx, k)          int: 1 when subspace k was synthesised
 *   BTF_SHADE_TEX(ctx, k, i)        float: subspace k's float i (pixel * 3 + c)
 *   BTF_SHADE_HEIGHT(ctx, i)        float: range map height of pixel i
 *   BTF_SHADE_NORMAL(ctx, i)        float: normal map float i (pixel * 3 + c)
 *   BTF_SHADE_LIGHT_OUTER_Z(ctx)    float: cos of the largest measured light theta
 *   BTF_SHADE_AMBIENT(ctx)          float: the model's ambient term a >= 0
 *   BTF_SHADE_GAIN(ctx, i, c)       float: pair i's gain of channel c (1 without)
 *   BTF_SHADE_HAS_HORIZON(ctx)      int: 1 when the relief casts shadows and hides
 *                                   what lies behind it (the view is marched)
 *   BTF_SHADE_HMIN(ctx), _HMAX(ctx) float: the height map's extremes
 *   BTF_SHADE_HORIZON(ctx, i)       btf_uint: horizon map word i (texel * 2 + w)
 *   BTF_SHADE_N_LIGHTS(ctx)         int: the scene's lights
 *   BTF_SHADE_LIGHT_KIND(ctx, j)    int: 0 directional, 1 point (btf_light_kind)
 *   BTF_SHADE_LIGHT_VEC(ctx, j, k)  float: unit direction towards it, or position
 *   BTF_SHADE_LIGHT_RGB(ctx, j, k)  float: intensity
 *
 * The arithmetic is float, each result BTF_PRECISE, in one written order;
 * sqrt and division are the only operations whose last bits GPU drivers do
 * not pin down, so the two paths agree to rounding (tests/unit/test_gpu_render.c
 * measures it). Keep this file in the common subset of C and GLSL (the
 * rules of src/synth/btf_noise.h and btf__hemisphere_lookup.h).
 */
#ifndef BTF_RENDER_SHARED_H
#define BTF_RENDER_SHARED_H

#include "btf_hemisphere_lookup.h"
#include "btf_horizon.h"
#include "btf_shade_common.h"

/* Weights below this are rounding (a measured direction's own weight is 1
 * only to ~1e-6): they are dropped and the rest renormalised, so that a
 * pixel at a measured pair selects that pair's subspace alone. */
#define BTF_RENDER_MIN_WEIGHT 1e-5f
/* A view below the horizon is held at this height (btf_shade_local_view). */
#define BTF_RENDER_MIN_Z BTF_SHADE_MIN_Z
/* Parallax shifts grow as 1 / v_z towards grazing views; past 75.5 degrees
 * they are held at 4 h (offset limiting), which keeps them bounded. */
#define BTF_PARALLAX_MIN_Z 0.25f
/* The flat surface's n . l below which the normalisation is held: lights
 * within 3 degrees of the horizon fade out instead of dividing by ~0. */
#define BTF_FLAT_MIN_Z 0.05f
/* At most this many lights per scene (the GPU pass's uniform block). */
#define BTF_RENDER_MAX_LIGHTS 16

#if defined(BTF_GLSL) || defined(VULKAN) || defined(GL_core_profile) || defined(GL_ES)
/* ------------------------------------------------------------------ GLSL */
struct btf_tap1 {
    int i0, i1;
    float f;
};
struct btf_pixel {
    float r, g, b;
    int missing;
};
#define BTF_TAP1(a, b, c) btf_tap1(a, b, c)
#define BTF_PIXEL(a, b, c, m) btf_pixel(a, b, c, m)
#else
/* --------------------------------------------------------------------- C */
typedef struct btf_tap1 {
    int i0, i1;
    float f;
} btf_tap1;
/* A shaded pixel: its colour, and beside it (never in it: any float may be
 * a real colour of an unclamped model) whether a pair it selects has a
 * subspace that was not synthesised. */
typedef struct btf_pixel {
    float r, g, b;
    int missing;
} btf_pixel;
static inline btf_tap1 btf_make_tap1(int a, int b, float c)
{
    btf_tap1 t = {a, b, c};
    return t;
}
static inline btf_pixel btf_make_pixel(float a, float b, float c, int m)
{
    btf_pixel t = {a, b, c, m};
    return t;
}
#define BTF_TAP1(a, b, c) btf_make_tap1(a, b, c)
#define BTF_PIXEL(a, b, c, m) btf_make_pixel(a, b, c, m)
#endif

/* ============================================== shared part: C and GLSL */

/* The two taps and the fraction of a wrapped linear lookup at texture
 * coordinate x (texel centres at i + 1/2) on a side of s texels. The
 * coordinate is first brought near [0, s) in float (a wrong period there
 * moves by whole periods, which the integer wrap undoes), then wrapped as
 * an integer. */
BTF_FN btf_tap1 btf_shade_tap1(float x, int s)
{
    BTF_PRECISE float x0 = x - 0.5f;
    float t = btf_shade_coord(x0);
    float sf = BTF_I2F(s);
    BTF_PRECISE float q = t / sf;
    float k = BTF_FLOOR(q);
    BTF_PRECISE float sk = sf * k;
    BTF_PRECISE float r = t - sk;
    float fl = BTF_FLOOR(r);
    BTF_PRECISE float f = r - fl;
    int i = btf_shade_wrap(BTF_F2I(fl), s);
    int i1 = i + 1 == s ? 0 : i + 1;
    return BTF_TAP1(i, i1, f);
}

/* Linear interpolation a (1 - f) + b f. */
BTF_FN float btf_shade_lerp(float a, float b, float f)
{
    BTF_PRECISE float g = 1.0f - f;
    BTF_PRECISE float p = a * g;
    BTF_PRECISE float q = b * f;
    BTF_PRECISE float s = p + q;
    return s;
}

/* Subspace k's channel c, bilinear at taps (tx, ty). */
BTF_FN float btf_shade_tex(BTF_SHADE_CTX ctx, int k, btf_tap1 tx, btf_tap1 ty, int c)
{
    int s = BTF_SHADE_SIZE(ctx);
    float a = BTF_SHADE_TEX(ctx, k, 3 * (ty.i0 * s + tx.i0) + c);
    float b = BTF_SHADE_TEX(ctx, k, 3 * (ty.i0 * s + tx.i1) + c);
    float d = BTF_SHADE_TEX(ctx, k, 3 * (ty.i1 * s + tx.i0) + c);
    float e = BTF_SHADE_TEX(ctx, k, 3 * (ty.i1 * s + tx.i1) + c);
    return btf_shade_lerp(btf_shade_lerp(a, b, tx.f), btf_shade_lerp(d, e, tx.f), ty.f);
}

BTF_FN float btf_shade_height(BTF_SHADE_CTX ctx, btf_tap1 tx, btf_tap1 ty)
{
    int s = BTF_SHADE_SIZE(ctx);
    float a = BTF_SHADE_HEIGHT(ctx, ty.i0 * s + tx.i0);
    float b = BTF_SHADE_HEIGHT(ctx, ty.i0 * s + tx.i1);
    float d = BTF_SHADE_HEIGHT(ctx, ty.i1 * s + tx.i0);
    float e = BTF_SHADE_HEIGHT(ctx, ty.i1 * s + tx.i1);
    return btf_shade_lerp(btf_shade_lerp(a, b, tx.f), btf_shade_lerp(d, e, tx.f), ty.f);
}

BTF_FN float btf_shade_normal(BTF_SHADE_CTX ctx, btf_tap1 tx, btf_tap1 ty, int c)
{
    int s = BTF_SHADE_SIZE(ctx);
    float a = BTF_SHADE_NORMAL(ctx, 3 * (ty.i0 * s + tx.i0) + c);
    float b = BTF_SHADE_NORMAL(ctx, 3 * (ty.i0 * s + tx.i1) + c);
    float d = BTF_SHADE_NORMAL(ctx, 3 * (ty.i1 * s + tx.i0) + c);
    float e = BTF_SHADE_NORMAL(ctx, 3 * (ty.i1 * s + tx.i1) + c);
    return btf_shade_lerp(btf_shade_lerp(a, b, tx.f), btf_shade_lerp(d, e, tx.f), ty.f);
}

/* The sum of the weights that count (>= BTF_RENDER_MIN_WEIGHT). */
BTF_FN float btf_shade_kept(float a, float b, float c)
{
    BTF_PRECISE float s = 0.0f;
    if (a >= BTF_RENDER_MIN_WEIGHT)
        s = s + a;
    if (b >= BTF_RENDER_MIN_WEIGHT)
        s = s + b;
    if (c >= BTF_RENDER_MIN_WEIGHT)
        s = s + c;
    return s;
}

/* Weight j (0..2) of a lookup and its index. */
BTF_FN float btf_shade_w(btf_hemi_weights h, int j)
{
    return j == 0 ? h.w0 : j == 1 ? h.w1 : h.w2;
}
BTF_FN int btf_shade_i(btf_hemi_weights h, int j)
{
    return j == 0 ? h.i0 : j == 1 ? h.i1 : h.i2;
}

/* 1 when every pair btf_shade_blend counts (both weights kept) selects a
 * subspace that was synthesised: the flag is looked up by subspace index
 * (BTF_SHADE_HAVE), so no colour value can be mistaken for a missing
 * subspace (unclamped Gaussian colours of format 1.0/1.1 models
 * reach any negative value). */
BTF_FN int btf_shade_pairs_have(BTF_SHADE_CTX ctx, btf_hemi_weights hv, btf_hemi_weights hl)
{
    if (!(btf_shade_kept(hv.w0, hv.w1, hv.w2) > 0.0f) ||
        !(btf_shade_kept(hl.w0, hl.w1, hl.w2) > 0.0f))
        return 1; /* the blend is 0 and reads no image */
    int n = BTF_SHADE_N_LIGHTS_SET(ctx);
    for (int i = 0; i < 3; i++) {
        if (!(btf_shade_w(hv, i) >= BTF_RENDER_MIN_WEIGHT))
            continue;
        for (int j = 0; j < 3; j++) {
            if (!(btf_shade_w(hl, j) >= BTF_RENDER_MIN_WEIGHT))
                continue;
            int k = BTF_SHADE_INDEX(ctx, btf_shade_i(hv, i) * n + btf_shade_i(hl, j));
            if (BTF_SHADE_HAVE(ctx, k) == 0)
                return 0;
        }
    }
    return 1;
}

/* The nine pairs' blend of the subspace images at taps (tx, ty): pairs whose
 * two weights count, renormalised. Pairs of the same subspace are summed
 * into one weight and sampled once. Every subspace it reads must have been
 * synthesised (btf_shade_pairs_have, which the caller asks first); the
 * result is any real colour, negative ones included. */
BTF_FN btf_rgb btf_shade_blend(BTF_SHADE_CTX ctx, btf_hemi_weights hv, btf_hemi_weights hl,
                               btf_tap1 tx, btf_tap1 ty)
{
    float sv = btf_shade_kept(hv.w0, hv.w1, hv.w2);
    float sl = btf_shade_kept(hl.w0, hl.w1, hl.w2);
    BTF_PRECISE float r = 0.0f;
    BTF_PRECISE float g = 0.0f;
    BTF_PRECISE float b = 0.0f;
    /* The pair gains (docs/model.md, "Pair gains"), interpolated with the
     * pairs' own weights: exactly the measured pair's at a measured pair. */
    BTF_PRECISE float gr = 0.0f;
    BTF_PRECISE float gg = 0.0f;
    BTF_PRECISE float gb = 0.0f;
    if (!(sv > 0.0f) || !(sl > 0.0f))
        return BTF_RGB(0.0f, 0.0f, 0.0f);
    int n = BTF_SHADE_N_LIGHTS_SET(ctx);
    /* The distinct subspaces in first-seen order with summed weights. */
    int k0 = -1, k1 = -1, k2 = -1, k3 = -1, k4 = -1, k5 = -1, k6 = -1, k7 = -1, k8 = -1;
    float w0 = 0.0f, w1 = 0.0f, w2 = 0.0f, w3 = 0.0f, w4 = 0.0f, w5 = 0.0f, w6 = 0.0f,
          w7 = 0.0f, w8 = 0.0f;
    for (int i = 0; i < 3; i++) {
        float wv = btf_shade_w(hv, i);
        if (!(wv >= BTF_RENDER_MIN_WEIGHT))
            continue;
        for (int j = 0; j < 3; j++) {
            float wl = btf_shade_w(hl, j);
            if (!(wl >= BTF_RENDER_MIN_WEIGHT))
                continue;
            int pair = btf_shade_i(hv, i) * n + btf_shade_i(hl, j);
            BTF_PRECISE float a = wv / sv;
            BTF_PRECISE float c = wl / sl;
            BTF_PRECISE float w = a * c;
            BTF_PRECISE float hr = w * BTF_SHADE_GAIN(ctx, pair, 0);
            BTF_PRECISE float hg = w * BTF_SHADE_GAIN(ctx, pair, 1);
            BTF_PRECISE float hb = w * BTF_SHADE_GAIN(ctx, pair, 2);
            int k = BTF_SHADE_INDEX(ctx, pair);
            gr = gr + hr;
            gg = gg + hg;
            gb = gb + hb;
            if (k0 < 0 || k0 == k) { k0 = k; w0 = w0 + w; }
            else if (k1 < 0 || k1 == k) { k1 = k; w1 = w1 + w; }
            else if (k2 < 0 || k2 == k) { k2 = k; w2 = w2 + w; }
            else if (k3 < 0 || k3 == k) { k3 = k; w3 = w3 + w; }
            else if (k4 < 0 || k4 == k) { k4 = k; w4 = w4 + w; }
            else if (k5 < 0 || k5 == k) { k5 = k; w5 = w5 + w; }
            else if (k6 < 0 || k6 == k) { k6 = k; w6 = w6 + w; }
            else if (k7 < 0 || k7 == k) { k7 = k; w7 = w7 + w; }
            else { k8 = k; w8 = w8 + w; }
        }
    }
    for (int d = 0; d < 9; d++) {
        int k = d == 0 ? k0 : d == 1 ? k1 : d == 2 ? k2 : d == 3 ? k3 : d == 4 ? k4
              : d == 5 ? k5 : d == 6 ? k6 : d == 7 ? k7 : k8;
        float w = d == 0 ? w0 : d == 1 ? w1 : d == 2 ? w2 : d == 3 ? w3 : d == 4 ? w4
                : d == 5 ? w5 : d == 6 ? w6 : d == 7 ? w7 : w8;
        if (k < 0)
            break;
        BTF_PRECISE float tr = w * btf_shade_tex(ctx, k, tx, ty, 0);
        BTF_PRECISE float tg = w * btf_shade_tex(ctx, k, tx, ty, 1);
        BTF_PRECISE float tb = w * btf_shade_tex(ctx, k, tx, ty, 2);
        r = r + tr;
        g = g + tg;
        b = b + tb;
    }
    BTF_PRECISE float pr = r * gr;
    BTF_PRECISE float pg = g * gg;
    BTF_PRECISE float pb = b * gb;
    return BTF_RGB(pr, pg, pb);
}

/* The bump factor of docs/render.md: (a + vis max(0, n . l)) / (a + max(l_z,
 * BTF_FLAT_MIN_Z)) with n the relief-scaled normal (nx, ny, nz) and a the
 * model's ambient term (0 without a structure layer: the plain ratio),
 * times the horizon fade l_z / cos(theta_outer) beyond the outermost light
 * ring; 0 for l_z <= 0. A model with a structure layer (a >= 0; -1
 * without) has textures divided by (a + l_z) of their subspace's light
 * (btf__render_reflectance), so the factor is a + max(0, n . l) itself and a
 * pair's brightness follows its own light, not its subspace's; the
 * analysis divides each exemplar by the relit shading under its own light
 * (docs/model.md, "Structure"). */
BTF_FN float btf_shade_bump(BTF_SHADE_CTX ctx, float nx, float ny, float nz, float lx,
                            float ly, float lz, float vis)
{
    if (!(lz > 0.0f))
        return 0.0f;
    float ndotl = btf_shade_dot3(nx, ny, nz, lx, ly, lz);
    float flatz = lz > BTF_FLAT_MIN_Z ? lz : BTF_FLAT_MIN_Z;
    float given = BTF_SHADE_AMBIENT(ctx);
    float amb = given > 0.0f ? given : 0.0f;
    float lit0 = ndotl > 0.0f ? ndotl : 0.0f;
    BTF_PRECISE float lit = lit0 * vis;
    BTF_PRECISE float num = amb + lit;
    BTF_PRECISE float den = amb + flatz;
    BTF_PRECISE float factor = num / den;
    if (given >= 0.0f)
        factor = num; /* structure layer: textures hold reflectance, see above */
    float outer = BTF_SHADE_LIGHT_OUTER_Z(ctx);
    if (lz < outer) {
        BTF_PRECISE float fade = lz / outer;
        factor = factor * fade;
    }
    return factor;
}

/* The horizon tangent of map direction d, bilinear at taps (tx, ty). */
BTF_FN float btf_shade_horizon_dir(BTF_SHADE_CTX ctx, btf_tap1 tx, btf_tap1 ty, int d)
{
    int s = BTF_SHADE_SIZE(ctx);
    int i00 = 2 * (ty.i0 * s + tx.i0);
    int i01 = 2 * (ty.i0 * s + tx.i1);
    int i10 = 2 * (ty.i1 * s + tx.i0);
    int i11 = 2 * (ty.i1 * s + tx.i1);
    float a = btf_horizon_decode(BTF_SHADE_HORIZON(ctx, i00), BTF_SHADE_HORIZON(ctx, i00 + 1), d);
    float b = btf_horizon_decode(BTF_SHADE_HORIZON(ctx, i01), BTF_SHADE_HORIZON(ctx, i01 + 1), d);
    float c = btf_horizon_decode(BTF_SHADE_HORIZON(ctx, i10), BTF_SHADE_HORIZON(ctx, i10 + 1), d);
    float e = btf_horizon_decode(BTF_SHADE_HORIZON(ctx, i11), BTF_SHADE_HORIZON(ctx, i11 + 1), d);
    return btf_shade_lerp(btf_shade_lerp(a, b, tx.f), btf_shade_lerp(c, e, tx.f), ty.f);
}

/* The light's visibility at taps (tx, ty) (btf_horizon.h): the horizon in
 * its azimuth, between the two nearest mapped directions, against its
 * elevation; 1 without a horizon map or relief. */
BTF_FN float btf_shade_shadow(BTF_SHADE_CTX ctx, btf_tap1 tx, btf_tap1 ty, float lx, float ly,
                              float lz, float r)
{
    if (!(r > 0.0f) || BTF_SHADE_HAS_HORIZON(ctx) == 0)
        return 1.0f;
    float t = btf_horizon_azimuth(lx, ly);
    float fl = BTF_FLOOR(t);
    int d0 = BTF_F2I(fl);
    d0 = d0 < 0 ? 0 : d0 > 7 ? 7 : d0;
    int d1 = d0 == 7 ? 0 : d0 + 1;
    BTF_PRECISE float f = t - fl;
    float h = btf_shade_lerp(btf_shade_horizon_dir(ctx, tx, ty, d0),
                             btf_shade_horizon_dir(ctx, tx, ty, d1), f);
    return btf_horizon_vis(h, lx, ly, lz, r);
}

/* The relief-scaled unit normal at taps (tx, ty): the map's normal is
 * (-h_x, -h_y, 1) normalised, so scaling the heights by r scales its x and
 * y by r against z. r = 0 (or a degenerate normal): (0, 0, 1). */
BTF_FN btf_rgb btf_shade_relief_normal(BTF_SHADE_CTX ctx, btf_tap1 tx, btf_tap1 ty, float r)
{
    if (r == 0.0f)
        return BTF_RGB(0.0f, 0.0f, 1.0f);
    BTF_PRECISE float x = r * btf_shade_normal(ctx, tx, ty, 0);
    BTF_PRECISE float y = r * btf_shade_normal(ctx, tx, ty, 1);
    float z = btf_shade_normal(ctx, tx, ty, 2);
    return btf_shade_unit(x, y, z, 1e-20f);
}

/* Parallax occlusion (docs/render.md, "Masking"): the view ray through
 * the reference plane's point (u, v) is at (u, v) + H (v_x, -v_y) / v_z at
 * height H; it is marched down from the relief's top in steps of at most
 * BTF_MARCH_STEP texels until it meets the relief-scaled height field,
 * and the crossing refined linearly between the last two steps. So a
 * groove behind a ridge is hidden at grazing views, as in a measured
 * image, where the one-step shift below lets it through. */
/* (BTF_MARCH_STEP and BTF_MARCH_MAX: btf_horizon.h, which the analysis
 * shares.) */
BTF_FN btf_rgb btf_shade_march(BTF_SHADE_CTX ctx, float u, float v, float dx, float dy,
                               float relief)
{
    int s = BTF_SHADE_SIZE(ctx);
    BTF_PRECISE float top = relief * BTF_SHADE_HMAX(ctx);
    BTF_PRECISE float bot = relief * BTF_SHADE_HMIN(ctx);
    BTF_PRECISE float depth = top - bot;
    BTF_PRECISE float reach = btf_shade_len_xy(dx, dy);
    BTF_PRECISE float span = depth * reach;
    BTF_PRECISE float q = span / BTF_MARCH_STEP;
    float qc = q < BTF_I2F(BTF_MARCH_MAX) ? q : BTF_I2F(BTF_MARCH_MAX);
    float cq = BTF_FLOOR(qc);
    int steps = BTF_F2I(cq) + 1;
    BTF_PRECISE float dh = depth / BTF_I2F(steps);
    BTF_PRECISE float prev_h = top;
    BTF_PRECISE float prev_d = 0.0f;
    for (int i = 0; i <= steps; i++) {
        BTF_PRECISE float ih = BTF_I2F(i) * dh;
        BTF_PRECISE float h = top - ih;
        BTF_PRECISE float ox = h * dx;
        BTF_PRECISE float oy = h * dy;
        BTF_PRECISE float pu = u + ox;
        BTF_PRECISE float pv = v + oy;
        btf_tap1 tx = btf_shade_tap1(pu, s);
        btf_tap1 ty = btf_shade_tap1(pv, s);
        BTF_PRECISE float hs = relief * btf_shade_height(ctx, tx, ty);
        BTF_PRECISE float d = h - hs;
        if (d <= 0.0f) {
            if (i == 0)
                return BTF_RGB(pu, pv, 0.0f);
            BTF_PRECISE float den = prev_d - d;
            BTF_PRECISE float t = prev_d / den;
            BTF_PRECISE float tdh = t * dh;
            BTF_PRECISE float hh = prev_h - tdh;
            BTF_PRECISE float hx = hh * dx;
            BTF_PRECISE float hy = hh * dy;
            BTF_PRECISE float ru = u + hx;
            BTF_PRECISE float rv = v + hy;
            return BTF_RGB(ru, rv, 0.0f);
        }
        prev_h = h;
        prev_d = d;
    }
    BTF_PRECISE float bx = bot * dx;
    BTF_PRECISE float by = bot * dy;
    BTF_PRECISE float bu = u + bx;
    BTF_PRECISE float bv = v + by;
    return BTF_RGB(bu, bv, 0.0f);
}

/* The parallax-shifted texture coordinate (u, v): (u, v) += h (v_x, -v_y) /
 * max(v_z, BTF_PARALLAX_MIN_Z), h the relief-scaled height at (u, v), or,
 * for a relief that casts shadows (BTF_SHADE_HAS_HORIZON), where the
 * marched view ray meets it (btf_shade_march). The result's r and g are
 * u' and v'. */
BTF_FN btf_rgb btf_shade_parallax(BTF_SHADE_CTX ctx, float u, float v, float vx, float vy,
                                  float vz, float relief)
{
    if (relief == 0.0f)
        return BTF_RGB(u, v, 0.0f);
    int s = BTF_SHADE_SIZE(ctx);
    if (relief > 0.0f && BTF_SHADE_HAS_HORIZON(ctx) != 0) {
        float zm = vz > BTF_PARALLAX_MIN_Z ? vz : BTF_PARALLAX_MIN_Z;
        BTF_PRECISE float mx = vx / zm;
        BTF_PRECISE float my = vy / zm;
        return btf_shade_march(ctx, u, v, mx, -my, relief);
    }
    btf_tap1 tx = btf_shade_tap1(u, s);
    btf_tap1 ty = btf_shade_tap1(v, s);
    BTF_PRECISE float h = relief * btf_shade_height(ctx, tx, ty);
    float z = vz > BTF_PARALLAX_MIN_Z ? vz : BTF_PARALLAX_MIN_Z;
    BTF_PRECISE float dx = h * vx;
    BTF_PRECISE float dy = h * vy;
    BTF_PRECISE float sx = dx / z;
    BTF_PRECISE float sy = dy / z;
    BTF_PRECISE float u2 = u + sx;
    BTF_PRECISE float v2 = v - sy;
    return BTF_RGB(u2, v2, 0.0f);
}

/* Light j seen from the world point (px, py, pz): the unit world direction
 * towards it (x, y, z) and its intensity scale (w), btf_shade_light's. A
 * directional light's vector is the host's as it is: unit already (the
 * host normalises it in double, btf__render_ctx_lights in
 * src/render/pairs.c), scale 1. */
BTF_FN btf_vec4 btf_shade_light_at(BTF_SHADE_CTX ctx, int j, float px, float py, float pz)
{
    float dx = BTF_SHADE_LIGHT_VEC(ctx, j, 0);
    float dy = BTF_SHADE_LIGHT_VEC(ctx, j, 1);
    float dz = BTF_SHADE_LIGHT_VEC(ctx, j, 2);
    if (BTF_SHADE_LIGHT_KIND(ctx, j) != 1)
        return BTF_VEC4(dx, dy, dz, 1.0f);
    return btf_shade_light(1, dx, dy, dz, px, py, pz);
}

/* The unit world direction from (px, py, pz) towards light j; (0, 0, 0)
 * for a point light at the point itself (the needed set's rule,
 * src/render/needed.c). */
BTF_FN btf_rgb btf_shade_light_dir(BTF_SHADE_CTX ctx, int j, float px, float py, float pz)
{
    btf_vec4 d = btf_shade_light_at(ctx, j, px, py, pz);
    return BTF_RGB(d.x, d.y, d.z);
}

/* One pixel (docs/render.md, "Shading"): frame rows T (f0..f2), B (f3..f5),
 * N (f6..f8), world hit (px, py, pz), world unit vector to the eye (ex, ey,
 * ez), texture coordinate (u, v). Returns the linear RGB, >= 0 and finite,
 * with missing 0; missing 1 (and black) when a pair selects a subspace
 * that was not synthesised. */
BTF_FN btf_pixel btf_shade_pixel(BTF_SHADE_CTX ctx, float f0, float f1, float f2, float f3,
                                 float f4, float f5, float f6, float f7, float f8, float px,
                                 float py, float pz, float ex, float ey, float ez, float u,
                                 float v, float relief)
{
    btf_rgb w = btf_shade_local_view(f0, f1, f2, f3, f4, f5, f6, f7, f8, ex, ey, ez);
    float vx = w.r, vy = w.g, vz = w.b;
    btf_hemi_weights hv = btf_hemi_lookup(BTF_SHADE_VIEWS(ctx), vx, vy, vz);
    btf_rgb uv2 = btf_shade_parallax(ctx, u, v, vx, vy, vz, relief);
    int s = BTF_SHADE_SIZE(ctx);
    btf_tap1 tx = btf_shade_tap1(uv2.r, s);
    btf_tap1 ty = btf_shade_tap1(uv2.g, s);
    btf_rgb n = btf_shade_relief_normal(ctx, tx, ty, relief);
    btf_rgb sum = BTF_RGB(0.0f, 0.0f, 0.0f);
    for (int j = 0; j < BTF_SHADE_N_LIGHTS(ctx); j++) {
        btf_vec4 d = btf_shade_light_at(ctx, j, px, py, pz);
        btf_rgb l = btf_shade_local(f0, f1, f2, f3, f4, f5, f6, f7, f8, d.x, d.y, d.z);
        float lx = l.r, ly = l.g, lz = l.b;
        if (!(lz > 0.0f))
            continue; /* below the surface's horizon: no light */
        btf_hemi_weights hl = btf_hemi_lookup(BTF_SHADE_LIGHTS(ctx), lx, ly, lz);
        if (btf_shade_pairs_have(ctx, hv, hl) == 0)
            return BTF_PIXEL(0.0f, 0.0f, 0.0f, 1);
        btf_rgb c = btf_shade_blend(ctx, hv, hl, tx, ty);
        float vis = btf_shade_shadow(ctx, tx, ty, lx, ly, lz, relief);
        float factor = btf_shade_bump(ctx, n.r, n.g, n.b, lx, ly, lz, vis);
        BTF_PRECISE float cr = c.r * factor;
        BTF_PRECISE float cg = c.g * factor;
        BTF_PRECISE float cb = c.b * factor;
        sum = btf_shade_add_light(sum, BTF_SHADE_LIGHT_RGB(ctx, j, 0),
                                  BTF_SHADE_LIGHT_RGB(ctx, j, 1), BTF_SHADE_LIGHT_RGB(ctx, j, 2),
                                  d.w, BTF_RGB(cr, cg, cb));
    }
    btf_rgb rad = btf_shade_radiance(sum);
    return BTF_PIXEL(rad.r, rad.g, rad.b, 0);
}

#endif /* BTF_RENDER_SHARED_H */
