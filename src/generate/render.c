/*
 * render.c — the images a BTF measurement of a procedural material records
 * (generate/material.c makes the materials): the rectified image of one
 * (view, light) pair, and the per-view and per-light maps that make 6,561
 * of them cheap. This simulates the measured input of the analysis (Haindl
 * & Filip 2007, section II); it is not the rendering of the model on
 * geometry (section III). Axes as in generate/material.c: texture u =
 * column, w = row (row 0 at the top); directions and normals x right, y UP,
 * z towards the camera.
 *
 * Rendering (the rectified image of one (view, light) pair). For every texel
 * (x, y) of the reference plane z = 0 the view ray through (x, y, 0) is
 * marched down through the height field (bilinear, wrapping) from its top to
 * its bottom; the first crossing, refined by one secant step, is the visible
 * point (masking, parallax: raised points appear shifted away from the
 * camera). That point is shaded
 *     ambient*albedo + vis * (kd * albedo * max(0, n.l) + ks * (n.h)^shininess)
 * with vis the light's visibility: a march from the surface point towards the
 * light, soft at the edge (the light is a disc of radius ~2.3 degrees), and, for a
 * coat, ks = specular * F(v.h) / F(1) and kd = 1 - F(v.h) (Schlick), else
 * ks = specular and kd = 1. The lobe needs n.l > 0 and fades in over
 * n.l < 0.1, so light at grazing incidence brings no highlight.
 * The view march depends only on the view and the shadow march only on the
 * light, so both are precomputed maps (generate/material.h) that a generator builds
 * once per direction; btf_procedural_render just builds both and combines them.
 * A view map holds 32 bytes per texel (hit point, normal, albedo), a light
 * map 4.
 */
#include <stdio.h>
#include "core/core.h"
#include "generate/material.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAT_PI 3.14159265358979323846
#define MARCH_STEP 0.5f          /* horizontal march step, texels */
#define MARCH_MAX_THETA 88.0     /* grazing rays are marched as 88 degrees:
                                    at 90 a ray would never reach the surface */
#define LIGHT_HALF_WIDTH 0.04f   /* tan of the light's angular radius: shadow
                                    edges are soft over about 4.6 degrees */

/* ------------------------------------------------------------ checking input */

static btf_status check_material(const btf_procedural *m, btf_error *err)
{
    if (!m || !m->height || !m->normal || !m->albedo)
        return btf__fail(err, BTF_E_ARG, "material: not made (NULL arrays)");
    if (m->size < 1 || m->size > BTF_MATERIAL_MAX_SIZE)
        return btf__fail(err, BTF_E_ARG, "material %s: size %d out of range 1..%d", m->name,
                         m->size, BTF_MATERIAL_MAX_SIZE);
    if (!isfinite(m->specular) || !isfinite(m->shininess) || !isfinite(m->fresnel0) ||
        !isfinite(m->ambient) || m->shininess < 0 || m->fresnel0 < 0 || m->fresnel0 > 1)
        return btf__fail(err, BTF_E_ARG,
                         "material %s: reflectance parameters not finite or out of range "
                         "(shininess >= 0, fresnel0 in [0, 1])",
                         m->name);
    return BTF_OK;
}

static btf_status check_dir(const char *what, btf_dir d, btf_error *err)
{
    if (!(d.theta >= 0.0 && d.theta <= 90.0) || !isfinite(d.phi))
        return btf__fail(err, BTF_E_ARG, "%s direction (theta %g, phi %g): theta must be in "
                         "[0, 90] degrees and phi finite", what, d.theta, d.phi);
    return BTF_OK;
}

static void dir_vec(btf_dir d, float v[3])
{
    double dv[3];
    btf_dir_to_vec(d, dv);
    for (int c = 0; c < 3; c++)
        v[c] = (float)dv[c];
}

/* ------------------------------------------------------------ height marching */

/* The height field with a wrap table, so a march can sample anywhere within
 * `pad` texels outside the tile without a modulo per sample. */
typedef struct field {
    const float *h;
    int n, pad;
    int *wrap;   /* wrap[k] = (k - pad) mod n, for k in [0, n + 2 pad + 2) */
    float lo, hi;
} field;

static btf_status field_init(field *f, const btf_procedural *m, double reach, btf_error *err)
{
    size_t count = (size_t)m->size * m->size;
    f->h = m->height;
    f->n = m->size;
    f->lo = f->hi = m->height[0];
    for (size_t k = 0; k < count; k++) {
        float v = m->height[k];
        if (!isfinite(v))
            return btf__fail(err, BTF_E_DATA, "material %s: height at texel %zu is not finite",
                             m->name, k);
        f->lo = v < f->lo ? v : f->lo;
        f->hi = v > f->hi ? v : f->hi;
    }
    double span = reach * fmax(fabs((double)f->lo), fabs((double)f->hi)) * 2.0 + 3.0;
    if (span > (double)(1 << 24))
        return btf__fail(err, BTF_E_ARG, "material %s: relief (%g..%g texels) too deep to march",
                         m->name, f->lo, f->hi);
    f->pad = (int)ceil(span);
    int len = f->n + 2 * f->pad + 2;
    f->wrap = btf__alloc((size_t)len, sizeof(int), err);
    if (!f->wrap)
        return BTF_E_NOMEM;
    for (int k = 0; k < len; k++)
        f->wrap[k] = btf_wrap_int((int64_t)k - f->pad, f->n);
    return BTF_OK;
}

/* Bilinear height at (u, w); u, w within pad texels of the tile. */
static inline float field_at(const field *f, float u, float w)
{
    float uu = u + (float)f->pad, ww = w + (float)f->pad;
    int iu = (int)uu, iw = (int)ww;
    float fu = uu - (float)iu, fw = ww - (float)iw;
    const float *r0 = f->h + (size_t)f->wrap[iw] * f->n;
    const float *r1 = f->h + (size_t)f->wrap[iw + 1] * f->n;
    int c0 = f->wrap[iu], c1 = f->wrap[iu + 1];
    float a = r0[c0] + (r0[c1] - r0[c0]) * fu;
    float b = r1[c0] + (r1[c1] - r1[c0]) * fu;
    return a + (b - a) * fw;
}

/* tan(theta), capped where the march would become endless. */
static double march_tan(double theta)
{
    return tan(fmin(theta, MARCH_MAX_THETA) * (MAT_PI / 180.0));
}

/* Bilinear weights and wrapped corner indices of (u, w) in [0, n). */
typedef struct bilerp {
    size_t k00, k01, k10, k11;
    float fu, fw;
} bilerp;

static inline bilerp bilerp_at(int n, float u, float w)
{
    int c0 = (int)u, r0 = (int)w;
    c0 = c0 >= n ? n - 1 : c0;
    r0 = r0 >= n ? n - 1 : r0;
    int c1 = c0 + 1 == n ? 0 : c0 + 1, r1 = r0 + 1 == n ? 0 : r0 + 1;
    bilerp b = {(size_t)r0 * n + c0, (size_t)r0 * n + c1, (size_t)r1 * n + c0,
                (size_t)r1 * n + c1, u - (float)c0, w - (float)r0};
    return b;
}

static inline float bilerp_get(const bilerp *b, const float *a, int stride, int c)
{
    float p = a[b->k00 * stride + c] + (a[b->k01 * stride + c] - a[b->k00 * stride + c]) * b->fu;
    float q = a[b->k10 * stride + c] + (a[b->k11 * stride + c] - a[b->k10 * stride + c]) * b->fu;
    return p + (q - p) * b->fw;
}

/* u mod n in [0, n). Hits are rarely more than a tile away, so one add or
 * subtract usually does, avoiding a division per texel. */
static inline float wrap_coord(float u, int n)
{
    float fn = (float)n;
    if (u < 0.0f || u >= fn) {
        if (u >= -fn && u < 2.0f * fn)
            u = u < 0.0f ? u + fn : u - fn;
        else
            u -= fn * floorf(u / fn);
    }
    return u >= fn || u < 0.0f ? 0.0f : u; /* rounding can land on fn */
}

/* --------------------------------------------------------------- view maps */

/* The height at which the view ray through (x, y, 0) first meets the
 * surface. On the ray, height z is at (x + a z, y + b z). The march goes down
 * from the top of the relief, where the ray is above the surface, to its
 * bottom, where it cannot be, so a crossing always exists. */
static float view_hit_z(const field *f, float x, float y, float a, float b, int steps)
{
    float top = f->hi, dz = (f->hi - f->lo) / (float)steps;
    float zp = top, fp = zp - field_at(f, x + a * zp, y + b * zp);
    if (fp <= 0.0f)
        return zp;
    for (int k = 1; k <= steps; k++) {
        float z = top - dz * (float)k;
        float fz = z - field_at(f, x + a * z, y + b * z);
        if (fz <= 0.0f)
            return zp - fp * (zp - z) / (fp - fz); /* secant: fp > 0 >= fz */
        zp = z;
        fp = fz;
    }
    return f->lo;
}

btf_status btf__view_map_make(const btf_procedural *m, btf_dir view, btf_view_map **out,
                              btf_error *err)
{
    if (!out)
        return btf__fail(err, BTF_E_ARG, "view map: no output given");
    *out = NULL;
    btf_status rc = check_material(m, err);
    if (rc || (rc = check_dir("view", view, err)))
        return rc;
    double t = march_tan(view.theta);
    field f;
    if ((rc = field_init(&f, m, t, err)))
        return rc;
    int n = m->size;
    size_t count = (size_t)n * n;
    btf_view_map *vm = btf__alloc(1, sizeof *vm, err);
    float *block = vm ? btf__alloc(count * 8, sizeof(float), err) : NULL;
    if (!block) {
        free(vm);
        free(f.wrap);
        return BTF_E_NOMEM;
    }
    vm->size = n;
    vm->hit = block;
    vm->normal = block + 2 * count;
    vm->albedo = block + 5 * count;

    /* Ray offset per unit height, in texture coordinates (rows grow to -y). */
    double phi = view.phi * (MAT_PI / 180.0);
    float a = (float)(t * cos(phi)), b = (float)(-t * sin(phi));
    int steps = (int)ceil((double)(f.hi - f.lo) * t / MARCH_STEP);
    int flat = steps < 1 || t < 1e-9;
    for (int y = 0; y < n; y++) {
        for (int x = 0; x < n; x++) {
            size_t k = (size_t)y * n + x;
            float u = (float)x, w = (float)y;
            if (!flat) {
                float z = view_hit_z(&f, (float)x, (float)y, a, b, steps);
                u = wrap_coord((float)x + a * z, n);
                w = wrap_coord((float)y + b * z, n);
            }
            vm->hit[2 * k] = u;
            vm->hit[2 * k + 1] = w;
            bilerp bl = bilerp_at(n, u, w);
            float nv[3];
            for (int c = 0; c < 3; c++) {
                nv[c] = bilerp_get(&bl, m->normal, 3, c);
                vm->albedo[3 * k + c] = bilerp_get(&bl, m->albedo, 3, c);
            }
            float len = sqrtf(nv[0] * nv[0] + nv[1] * nv[1] + nv[2] * nv[2]);
            if (!(len > 1e-6f) || !isfinite(len)) {
                nv[0] = nv[1] = 0.0f;
                nv[2] = len = 1.0f;
            }
            float inv = 1.0f / len;
            for (int c = 0; c < 3; c++)
                vm->normal[3 * k + c] = nv[c] * inv;
        }
    }
    free(f.wrap);
    *out = vm;
    return BTF_OK;
}

void btf__view_map_free(btf_view_map *vm)
{
    if (!vm)
        return;
    free(vm->hit);
    free(vm);
}

/* -------------------------------------------------------------- light maps */

/* Visibility of the light from (x, y, h0): march towards it, horizontally
 * along (cu, cw), rising 1/t per texel, until above the relief. The smallest
 * clearance angle (height over the ray / distance) decides: the light is a
 * disc of angular radius ~LIGHT_HALF_WIDTH, half hidden at clearance 0. */
static float light_vis(const field *f, float x, float y, float h0, float cu, float cw,
                       float inv_t, float reach)
{
    float worst = 1e30f;
    for (int k = 1;; k++) {
        float d = MARCH_STEP * (float)k;
        if (d > reach)
            break;
        float c = (h0 + d * inv_t - field_at(f, x + cu * d, y + cw * d)) / d;
        worst = c < worst ? c : worst;
        if (worst <= -LIGHT_HALF_WIDTH)
            return 0.0f;
    }
    float v = 0.5f + worst * (0.5f / LIGHT_HALF_WIDTH);
    return v > 1.0f ? 1.0f : v < 0.0f ? 0.0f : v;
}

btf_status btf__light_map_make(const btf_procedural *m, btf_dir light, btf_light_map **out,
                               btf_error *err)
{
    if (!out)
        return btf__fail(err, BTF_E_ARG, "light map: no output given");
    *out = NULL;
    btf_status rc = check_material(m, err);
    if (rc || (rc = check_dir("light", light, err)))
        return rc;
    double t = march_tan(light.theta);
    field f;
    if ((rc = field_init(&f, m, t, err)))
        return rc;
    int n = m->size;
    size_t count = (size_t)n * n;
    btf_light_map *lm = btf__alloc(1, sizeof *lm, err);
    float *vis = lm ? btf__alloc(count, sizeof(float), err) : NULL;
    if (!vis) {
        free(lm);
        free(f.wrap);
        return BTF_E_NOMEM;
    }
    lm->size = n;
    lm->vis = vis;
    double phi = light.phi * (MAT_PI / 180.0);
    float cu = (float)cos(phi), cw = (float)-sin(phi);
    float inv_t = t > 1e-9 ? (float)(1.0 / t) : 0.0f;
    for (int y = 0; y < n; y++) {
        for (int x = 0; x < n; x++) {
            size_t k = (size_t)y * n + x;
            float h0 = m->height[k];
            float reach = (float)((double)(f.hi - h0) * t);
            vis[k] = t > 1e-9 && reach >= MARCH_STEP
                         ? light_vis(&f, (float)x, (float)y, h0, cu, cw, inv_t, reach)
                         : 1.0f;
        }
    }
    free(f.wrap);
    *out = lm;
    return BTF_OK;
}

void btf__light_map_free(btf_light_map *lm)
{
    if (!lm)
        return;
    free(lm->vis);
    free(lm);
}

/* ------------------------------------------------------------------ shading */

/* What is the same for every texel of one (view, light) pair. */
typedef struct shade_consts {
    float l[3], h[3];
    float kd, ks, shininess, ambient;
    float cut; /* n.h below which the lobe is negligible (< 1e-7) */
} shade_consts;

static shade_consts shade_setup(const btf_procedural *m, btf_dir view, btf_dir light)
{
    shade_consts s;
    float v[3];
    dir_vec(view, v);
    dir_vec(light, s.l);
    float hv[3] = {v[0] + s.l[0], v[1] + s.l[1], v[2] + s.l[2]};
    float len = sqrtf(hv[0] * hv[0] + hv[1] * hv[1] + hv[2] * hv[2]);
    if (!(len > 1e-6f)) { /* opposite grazing directions: no half vector */
        hv[0] = hv[1] = 0.0f;
        hv[2] = len = 1.0f;
    }
    for (int c = 0; c < 3; c++)
        s.h[c] = hv[c] / len;
    float vh = v[0] * s.h[0] + v[1] * s.h[1] + v[2] * s.h[2];
    vh = vh < 0.0f ? 0.0f : vh > 1.0f ? 1.0f : vh;
    s.kd = 1.0f;
    s.ks = m->specular;
    if (m->fresnel0 > 0.0f) {
        /* Schlick; the coat reflects F and passes 1 - F to the base. */
        float q = 1.0f - vh, q5 = q * q * q * q * q;
        float fr = m->fresnel0 + (1.0f - m->fresnel0) * q5;
        s.kd = 1.0f - fr;
        s.ks = m->specular * fr / m->fresnel0;
    }
    s.shininess = m->shininess;
    s.ambient = m->ambient;
    s.cut = s.shininess > 0.0f ? expf(logf(1e-7f) / s.shininess) : 0.0f;
    return s;
}

btf_status btf__material_render_maps(const btf_procedural *m, const btf_view_map *vm,
                                     const btf_light_map *lm, btf_dir view, btf_dir light,
                                     btf_image *out, btf_error *err)
{
    if (!out)
        return btf__fail(err, BTF_E_ARG, "render: no output image given");
    btf_status rc = check_material(m, err);
    if (rc || (rc = check_dir("view", view, err)) || (rc = check_dir("light", light, err)))
        return rc;
    if (!vm || !lm || vm->size != m->size || lm->size != m->size)
        return btf__fail(err, BTF_E_ARG, "render: maps missing or not of material %s (size %d)",
                         m->name, m->size);
    int n = m->size;
    if ((rc = btf_image_alloc(out, n, n, 3, err)))
        return rc;
    shade_consts s = shade_setup(m, view, light);
    size_t count = (size_t)n * n;
    float *o = out->data;
    for (size_t k = 0; k < count; k++) {
        const float *nv = vm->normal + 3 * k, *al = vm->albedo + 3 * k;
        bilerp bl = bilerp_at(n, vm->hit[2 * k], vm->hit[2 * k + 1]);
        float vis = bilerp_get(&bl, lm->vis, 1, 0);
        float ndl = nv[0] * s.l[0] + nv[1] * s.l[1] + nv[2] * s.l[2];
        float diff = 0.0f, spec = 0.0f;
        if (ndl > 0.0f && vis > 0.0f) {
            diff = vis * s.kd * ndl;
            float ndh = nv[0] * s.h[0] + nv[1] * s.h[1] + nv[2] * s.h[2];
            /* The lobe fades out over the last ~6 degrees before the
             * terminator: light at grazing incidence brings no energy. */
            float fade = ndl < 0.1f ? 10.0f * ndl : 1.0f;
            if (ndh > s.cut)
                spec = vis * fade * s.ks * powf(ndh, s.shininess);
        }
        for (int c = 0; c < 3; c++)
            o[3 * k + c] = al[c] * (s.ambient + diff) + spec;
    }
    return BTF_OK;
}

btf_status btf_procedural_render(const btf_procedural *m, btf_dir view, btf_dir light, btf_image *out,
                               btf_error *err)
{
    btf_view_map *vm = NULL;
    btf_light_map *lm = NULL;
    btf_status rc = btf__view_map_make(m, view, &vm, err);
    if (!rc)
        rc = btf__light_map_make(m, light, &lm, err);
    if (!rc)
        rc = btf__material_render_maps(m, vm, lm, view, light, out, err);
    btf__view_map_free(vm);
    btf__light_map_free(lm);
    return rc;
}
