/*
 * btf_shade_common.h -- what the two model families do alike when they
 * shade a scene pixel, as ONE text for their shared headers: the CAR
 * model's (src/render/btf_render_shared.h: src/render/shade.c and
 * gpu/render.comp) and the reflectance field's (src/rf/btf_rf_shared.h:
 * src/rf/ and gpu/rf_render.comp). Both take the eye and the lights into
 * the hit point's tangent frame (docs/render.md, "Frames and conventions"),
 * hold the view above the horizon, let a point light fall off as 1/d^2,
 * add each light's intensity times the surface's colour under it and
 * clamp the sum to a radiance (docs/render.md, "Shading", step 5;
 * docs/rf.md, "Rendering"); what differs between them (the texture
 * lookups, the interpolation of the measured directions, the bump factor)
 * stays in each family's header. btf_horizon.h, which the analysis shares
 * with the CAR renderer, takes its vector length from here too.
 *
 * The arithmetic is float, each result BTF_PRECISE ("precise" in GLSL, so
 * no contraction into FMA; the C build uses -ffp-contract=off), in one
 * written order: the order both families wrote before they shared it, so
 * that their CPU and GPU renders keep their bits. sqrt and division are
 * the only operations whose last bits GPU drivers do not pin down (on
 * lavapipe, the CPU's IEEE operations, both paths agree bit for bit;
 * tests/unit/test_gpu_render.c, tests/unit/test_gpu_rf.c).
 *
 * Keep this file in the common subset of C11 and GLSL 4.50 (the rules of
 * src/synth/btf_noise.h, but sqrt through BTF_SQRT and division by "/"):
 * ASCII only, no pointers or arrays, no casts "(T)x" (BTF_F2I, BTF_I2F),
 * float constants with the f suffix. Every function is a pure function of
 * its arguments: neither family's accessor macros are used here.
 */
#ifndef BTF_SHADE_COMMON_H
#define BTF_SHADE_COMMON_H

#include "btf_noise.h" /* BTF_FN, BTF_PRECISE, btf_vec4, BTF_VEC4 */

/* A scene pixel's view is held at least this far above the horizon (an
 * interpolated mesh normal turned slightly away from the eye). */
#define BTF_SHADE_MIN_Z 1e-3f
/* Texture coordinates, squared light distances and radiances beyond this
 * are taken as 0 (and NaN fails the test too). */
#define BTF_SHADE_COORD_MAX 1.0e30f

#if defined(BTF_GLSL) || defined(VULKAN) || defined(GL_core_profile) || defined(GL_ES)
/* ------------------------------------------------------------------ GLSL */
/* A colour, or a direction (r, g, b as x, y, z). */
struct btf_rgb {
    float r, g, b;
};
#define BTF_RGB(a, b, c) btf_rgb(a, b, c)
#define BTF_FLOOR(x) floor(x)
#define BTF_ABS(x) abs(x)
#define BTF_SQRT(x) sqrt(x)
#define BTF_F2I(x) int(x)
#define BTF_I2F(i) float(i)
#else
/* --------------------------------------------------------------------- C */
#include <math.h>
typedef struct btf_rgb {
    float r, g, b;
} btf_rgb;
static inline btf_rgb btf_make_rgb(float a, float b, float c)
{
    btf_rgb t = {a, b, c};
    return t;
}
#define BTF_RGB(a, b, c) btf_make_rgb(a, b, c)
#define BTF_FLOOR(x) floorf(x)
#define BTF_ABS(x) fabsf(x)
#define BTF_SQRT(x) sqrtf(x)
#define BTF_F2I(x) ((int)(x))
#define BTF_I2F(i) ((float)(i))
#endif

/* ============================================== shared part: C and GLSL */

/* a . b, as (a0 b0 + a1 b1) + a2 b2. */
BTF_FN float btf_shade_dot3(float a0, float a1, float a2, float b0, float b1, float b2)
{
    BTF_PRECISE float p = a0 * b0;
    BTF_PRECISE float q = a1 * b1;
    BTF_PRECISE float r = a2 * b2;
    BTF_PRECISE float s = p + q;
    BTF_PRECISE float t = s + r;
    return t;
}

/* |(x, y)|: the length of a vector's part in the tangent plane. */
BTF_FN float btf_shade_len_xy(float x, float y)
{
    BTF_PRECISE float xx = x * x;
    BTF_PRECISE float yy = y * y;
    BTF_PRECISE float s = xx + yy;
    BTF_PRECISE float len = BTF_SQRT(s);
    return len;
}

/* (x, y, z) / |(x, y, z)|; (0, 0, 1), the normal, when the length is not
 * above min_len (a degenerate vector) or not below BTF_SHADE_COORD_MAX. */
BTF_FN btf_rgb btf_shade_unit(float x, float y, float z, float min_len)
{
    float l2 = btf_shade_dot3(x, y, z, x, y, z);
    BTF_PRECISE float len = BTF_SQRT(l2);
    if (!(len > min_len) || !(len < BTF_SHADE_COORD_MAX))
        return BTF_RGB(0.0f, 0.0f, 1.0f);
    BTF_PRECISE float a = x / len;
    BTF_PRECISE float b = y / len;
    BTF_PRECISE float c = z / len;
    return BTF_RGB(a, b, c);
}

/* World vector (x, y, z) in the tangent frame of rows T (f0..f2), B
 * (f3..f5), N (f6..f8) (docs/render.md, "Frames and conventions"). */
BTF_FN btf_rgb btf_shade_local(float f0, float f1, float f2, float f3, float f4, float f5,
                               float f6, float f7, float f8, float x, float y, float z)
{
    float a = btf_shade_dot3(f0, f1, f2, x, y, z);
    float b = btf_shade_dot3(f3, f4, f5, x, y, z);
    float c = btf_shade_dot3(f6, f7, f8, x, y, z);
    return BTF_RGB(a, b, c);
}

/* The local view of world unit vector (ex, ey, ez) to the eye, its z held
 * at least BTF_SHADE_MIN_Z above the horizon. */
BTF_FN btf_rgb btf_shade_local_view(float f0, float f1, float f2, float f3, float f4, float f5,
                                    float f6, float f7, float f8, float ex, float ey, float ez)
{
    btf_rgb v = btf_shade_local(f0, f1, f2, f3, f4, f5, f6, f7, f8, ex, ey, ez);
    float z = v.b > BTF_SHADE_MIN_Z ? v.b : BTF_SHADE_MIN_Z;
    return BTF_RGB(v.r, v.g, z);
}

/* A texture coordinate, or 0 where it is beyond BTF_SHADE_COORD_MAX or
 * NaN (which would wrap to no texel). */
BTF_FN float btf_shade_coord(float c)
{
    return BTF_ABS(c) < BTF_SHADE_COORD_MAX ? c : 0.0f;
}

/* Texel i wrapped into [0, n) for any sign (the textures repeat across the
 * surface), without % on a negative operand (undefined in GLSL). */
BTF_FN int btf_shade_wrap(int i, int n)
{
    return i < 0 ? n - 1 - ((-i - 1) % n) : i % n;
}

/* Towards a light from the world point (px, py, pz): a point light
 * (point == 1, btf_light_kind) at position (lx, ly, lz), else a
 * directional light towards (lx, ly, lz), of any length (docs/scene.md,
 * "The file"). x, y, z: the unit world direction towards it; w: its
 * intensity scale, 1, or 1/d^2 at distance d from a point light. (0, 0, 0,
 * 0) when it gives no light: a point light at the point itself, or a
 * vector that is zero or not finite. */
BTF_FN btf_vec4 btf_shade_light(int point, float lx, float ly, float lz, float px, float py,
                                float pz)
{
    BTF_PRECISE float qx = lx;
    BTF_PRECISE float qy = ly;
    BTF_PRECISE float qz = lz;
    if (point == 1) {
        qx = qx - px;
        qy = qy - py;
        qz = qz - pz;
    }
    float d2 = btf_shade_dot3(qx, qy, qz, qx, qy, qz);
    if (!(d2 > 1e-24f) || !(d2 < BTF_SHADE_COORD_MAX))
        return BTF_VEC4(0.0f, 0.0f, 0.0f, 0.0f);
    BTF_PRECISE float inv = 1.0f / d2;
    float scale = point == 1 ? inv : 1.0f;
    BTF_PRECISE float d = BTF_SQRT(d2);
    BTF_PRECISE float dx = qx / d;
    BTF_PRECISE float dy = qy / d;
    BTF_PRECISE float dz = qz / d;
    return BTF_VEC4(dx, dy, dz, scale);
}

/* One light's term added to the pixel's sum: acc + (I scale) c per channel,
 * I = (ir, ig, ib) the light's intensity, scale its falloff
 * (btf_shade_light) and c the surface's colour under it (docs/render.md,
 * "Shading", step 5: intensities multiply the measured values). */
BTF_FN btf_rgb btf_shade_add_light(btf_rgb acc, float ir, float ig, float ib, float scale,
                                   btf_rgb c)
{
    BTF_PRECISE float sr = ir * scale;
    BTF_PRECISE float sg = ig * scale;
    BTF_PRECISE float sb = ib * scale;
    BTF_PRECISE float tr = sr * c.r;
    BTF_PRECISE float tg = sg * c.g;
    BTF_PRECISE float tb = sb * c.b;
    BTF_PRECISE float r = acc.r + tr;
    BTF_PRECISE float g = acc.g + tg;
    BTF_PRECISE float b = acc.b + tb;
    return BTF_RGB(r, g, b);
}

/* The pixel's radiance from the sum of its lights: no negative radiance
 * (the CAR model's Gaussian tails; a PTM past its measured lights is
 * already held at 0) and nothing non-finite, each such channel 0. */
BTF_FN btf_rgb btf_shade_radiance(btf_rgb c)
{
    float r = c.r > 0.0f && c.r < BTF_SHADE_COORD_MAX ? c.r : 0.0f;
    float g = c.g > 0.0f && c.g < BTF_SHADE_COORD_MAX ? c.g : 0.0f;
    float b = c.b > 0.0f && c.b < BTF_SHADE_COORD_MAX ? c.b : 0.0f;
    return BTF_RGB(r, g, b);
}

#endif /* BTF_SHADE_COMMON_H */
