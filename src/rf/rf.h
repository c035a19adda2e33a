/*
 * rf.h — what the files of src/rf/ share: the per-view reflectance-field
 * family of Meseth, Müller & Klein 2003 ("Preserving realism in real-time
 * rendering of bidirectional texture functions"), the pixel-wise accuracy
 * end of btfcar's speed/accuracy trade (docs/rf.md).
 *
 * The scalar model functions and the 16-bit dequantisation are static
 * inline here, so that the fit (rf_fit.c, rf_lobes.c, rf_lafortune.c), the
 * error measure (rf_error.c) and the renderer (rf_eval.c, rf_render.c)
 * evaluate the same arithmetic without calling each other's objects.
 * Private to the library (and the tests); not installed.
 */
#ifndef BTF_RF_H
#define BTF_RF_H

#include "btfcar.h"
#include "core/core.h"

#include <math.h>
#include <stdint.h>

/* Parameter bounds (include/btfcar.h): every evaluation stays within rho. */
#define RF_XY_MAX 16.0  /* lobe direction (x, y, 1): within 86.4 degrees of the normal */
#define RF_LN_NMIN (-1.3862943611198906) /* ln 0.25 */
#define RF_LN_NMAX 6.9314718055994531    /* ln 1024 */
#define RF_QMAX 65535.0f

/* Luminance of linear RGB (Rec. 709 / sRGB primaries). */
static inline float rf_luminance(const float *rgb)
{
    return 0.2126f * rgb[0] + 0.7152f * rgb[1] + 0.0722f * rgb[2];
}

/* The PTM basis of paper section 4.2 / Malzbender et al. 2001 at the
 * light's (lu, lv) = (lx, ly). */
static inline void rf_ptm_basis(double lu, double lv, double b[6])
{
    b[0] = lu * lu, b[1] = lv * lv, b[2] = lu * lv, b[3] = lu, b[4] = lv, b[5] = 1.0;
}

static inline double rf_clampd(double v, double lo, double hi)
{
    return v < lo ? lo : v > hi ? hi : v;
}

/* One lobe rho <d, l>^n, d = (x, y, 1) / |(x, y, 1)|, l a unit vector; the
 * parameters are clamped to their box first, so any stored value gives a
 * finite result in [0, rho]. p = (rho, x, y, log2 n). */
static inline double rf_lobe_eval(const float *p, const double l[3])
{
    double rho = rf_clampd(p[0], 0.0, BTF_RF_MAX_RHO);
    double x = rf_clampd(p[1], -RF_XY_MAX, RF_XY_MAX), y = rf_clampd(p[2], -RF_XY_MAX, RF_XY_MAX);
    double n = exp2(rf_clampd(p[3], RF_LN_NMIN / M_LN2, RF_LN_NMAX / M_LN2));
    double c = (x * l[0] + y * l[1] + l[2]) / sqrt(x * x + y * y + 1.0);
    return c > 0.0 ? rho * pow(c, n) : 0.0;
}

/* One Lafortune lobe rho (cx lx vx + cy ly vy + cz lz vz)^n with
 * |c.| <= 1, so the base is at most 1. p = (rho, cx, cy, cz, log2 n). */
static inline double rf_lafortune_lobe(const float *p, const double l[3], const double v[3])
{
    double rho = rf_clampd(p[0], 0.0, BTF_RF_MAX_RHO);
    double s = rf_clampd(p[1], -1, 1) * l[0] * v[0] + rf_clampd(p[2], -1, 1) * l[1] * v[1] +
               rf_clampd(p[3], -1, 1) * l[2] * v[2];
    double n = exp2(rf_clampd(p[4], RF_LN_NMIN / M_LN2, RF_LN_NMAX / M_LN2));
    return s > 0.0 ? rho * pow(s, n) : 0.0;
}

/* The luminance of one texel's field with parameters p (fit's slot order,
 * docs/rf.md): light l, view v (lafortune only). Never negative: a PTM
 * below zero (past the measured lights) gives 0. */
static inline double rf_lum_eval(int fit, int lobes, const float *p, const double l[3],
                                 const double v[3])
{
    double y = 0.0;
    if (fit == BTF_RF_PTM) {
        double b[6];
        rf_ptm_basis(l[0], l[1], b);
        for (int i = 0; i < 6; i++)
            y += (double)p[i] * b[i];
    } else if (fit == BTF_RF_LOBES) {
        for (int i = 0; i < lobes; i++)
            y += rf_lobe_eval(p + 4 * i, l);
    } else {
        y = rf_clampd(p[0], 0.0, BTF_RF_MAX_RHO) * (l[2] > 0.0 ? l[2] : 0.0);
        for (int i = 0; i < lobes; i++)
            y += rf_lafortune_lobe(p + 1 + 5 * i, l, v);
    }
    return isfinite(y) && y > 0.0 ? y : 0.0;
}

/* 16-bit codes with a per-field, per-slot range [lo, hi]. */
static inline uint16_t rf_quantise(float v, float lo, float hi)
{
    if (!(hi > lo))
        return 0;
    float t = (v - lo) * (RF_QMAX / (hi - lo));
    t = t < 0.0f ? 0.0f : t > RF_QMAX ? RF_QMAX : t;
    return (uint16_t)lrintf(t);
}
static inline float rf_dequantise(uint16_t q, float lo, float hi)
{
    return hi > lo ? lo + (float)q * ((hi - lo) / RF_QMAX) : lo;
}

/* The dequantised slots of texel t in field f into p (m->slots floats). */
static inline void rf_texel_params(const btf_rf_model *m, int f, size_t t, float *p)
{
    const uint16_t *q = m->codes + ((size_t)f * m->width * m->height + t) * m->slots;
    const float *lo = m->lo + (size_t)f * m->slots, *hi = m->hi + (size_t)f * m->slots;
    for (int s = 0; s < m->slots; s++)
        p[s] = rf_dequantise(q[s], lo[s], hi[s]);
}

/* The fields a render at one view blends (paper section 5.4): the four
 * closest measured views with their weights (btf_rf_view_weights; zero
 * weights dropped) and the view vector each is evaluated with (its own
 * measured direction); a Lafortune model's one field at the view itself
 * (view: its direction, vvec: its unit vector). Shared by the flat render
 * (rf_render.c) and the scene render (rf_scene.c), so that both blend with
 * the same arithmetic. */
typedef struct rf_views {
    int n;
    int field[4];
    double w[4];
    double v[4][3];
} rf_views;

static inline void rf_views_at(const btf_rf_model *m, btf_dir view, const double vvec[3],
                               rf_views *o)
{
    o->n = 0;
    if (m->fit == BTF_RF_LAFORTUNE) {
        o->n = 1, o->field[0] = 0, o->w[0] = 1.0;
        for (int k = 0; k < 3; k++)
            o->v[0][k] = vvec[k];
        return;
    }
    int idx[4];
    double w[4];
    btf_rf_view_weights(&m->views, view, idx, w);
    for (int i = 0; i < 4; i++)
        if (w[i] != 0.0) {
            o->field[o->n] = idx[i], o->w[o->n] = w[i];
            btf_dir_to_vec(m->views.dirs[idx[i]], o->v[o->n]);
            o->n++;
        }
}

/* Linear RGB of texel t under unit light l (tangent frame): the blend of
 * the fields of vs, each field's luminance times its chromaticity. */
static inline void rf_blend(const btf_rf_model *m, const rf_views *vs, size_t t,
                            const double l[3], double sum[3])
{
    float p[BTF_RF_MAX_SLOTS];
    sum[0] = sum[1] = sum[2] = 0.0;
    for (int i = 0; i < vs->n; i++) {
        rf_texel_params(m, vs->field[i], t, p);
        double lum = rf_lum_eval(m->fit, m->lobes, p, l, vs->v[i]);
        for (int k = 0; k < 3; k++)
            sum[k] += vs->w[i] * (float)(lum * p[m->params + k]);
    }
}

/* rf_lm.c: a bounded Levenberg-Marquardt least-squares solver for a few
 * parameters (at most RF_LM_MAX). fn adds up the squared residuals at p
 * into *cost, and, when jtj is not NULL, JᵀJ (upper triangle, row-major
 * np x np) and Jᵀr (r = data - model) into jtj and jtr (zeroed by the
 * caller: rf_lm). Steps are projected onto [lo, hi]; a step whose cost is
 * not finite is rejected like one that does not improve, so the result is
 * always the best finite point visited. Returns the steps taken. */
#define RF_LM_MAX (1 + 5 * BTF_RF_MAX_LOBES)
typedef void (*rf_lm_fn)(void *user, const double *p, double *cost, double *jtj, double *jtr);
int rf_lm(rf_lm_fn fn, void *user, int np, double *p, const double *lo, const double *hi,
          int iterations, double *cost);
/* Solves the symmetric positive definite system a x = b (n <= RF_LM_MAX, a
 * full row-major, only the upper triangle read) by Cholesky; -1 when not
 * positive definite. */
int rf_cholesky_solve(const double *a, const double *b, int n, double *x);

/* rf_ptm.c: the PTM least-squares operator of one light set: pinv (6 x n)
 * with coefficients a = pinv y for luminances y at the n lights. */
btf_status rf_ptm_operator(const btf_dirset *lights, double *pinv, btf_error *err);
/* a[6] = pinv y (n samples). */
void rf_ptm_apply(const double *pinv, int n, const float *y, double a[6]);

/* rf_lobes.c: k lobes fitted to one texel's luminances y at the unit light
 * vectors l[3 n]; ptm: that texel's PTM coefficients (the low pass the
 * initialisation subtracts, paper section 4.2). out: 4k slots in the order
 * (rho, x, y, log2 n). Returns the LM steps taken. */
int rf_lobes_fit(int k, int n, const double *l, const float *y, const double ptm[6],
                 int iterations, float *out);

/* rf_lafortune.c: k Lafortune lobes plus rho_d l_z fitted to one texel's
 * n luminances y at light vectors l[3 n] and view vectors v[3 n]. out:
 * 1 + 5k slots (rho_d, then rho, cx, cy, cz, log2 n per lobe). */
int rf_lafortune_fit(int k, int n, const double *l, const double *v, const float *y,
                     int iterations, float *out);

/* rf_quant.c: codes and ranges of one field from float slots
 * vals[texels * slots]: lo/hi per slot (min and max over the texels),
 * codes[texels * slots]. */
void rf_quantise_field(const float *vals, size_t texels, int slots, float *lo, float *hi,
                       uint16_t *codes);
/* The chromaticity factors (sum of rgb / sum of Y, 1 1 1 for a dark texel),
 * clamped to [0, 64]. */
void rf_chroma(double r, double g, double b, float out[3]);

#endif
