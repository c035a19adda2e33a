/*
 * rf.h — what the files of src/rf/ share: the per-view reflectance-field
 * family of Meseth, Müller & Klein 2003 ("Preserving realism in real-time
 * rendering of bidirectional texture functions"), the pixel-wise accuracy
 * end of btfcar's speed/accuracy trade (docs/rf.md).
 *
 * The evaluation of a stored model is src/rf/btf_rf_shared.h (one text
 * for the CPU and the GPU pass, gpu/rf_render.comp), included here with
 * the C accessors; the fit's error measure (rf_fit.c, rf_error.c), the
 * evaluation calls (rf_eval.c) and the renderers (rf_render.c, rf_scene.c)
 * all run it, without calling each other's objects.
 * Private to the library (and the tests); not installed.
 */
#ifndef BTF_RF_H
#define BTF_RF_H

#include "btfcar.h"
#include "scene/gbuffer.h"
#include "rf/rf_error.h"
#include "rf/rf_map.h"
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

/* ------------------------------------------------------------------
 * The evaluation of a stored model: src/rf/btf_rf_shared.h, the one text
 * the CPU renderer and the GPU pass (gpu/rf_render.comp) share. Its C
 * accessors read a model through an rf_ctx.
 */
typedef struct rf_ctx {
    const btf_rf_model *m;
    const btf_light *lights; /* scene render: the scene's lights */
    int n_lights;
    float inv_w, inv_h;      /* 1.0f / the surface's width, height (rf_map.h) */
} rf_ctx;

/* The ring (views of equal theta, within 1e-6 degree) starting at view
 * index `start` of a direction set: its end (exclusive). */
static inline int rf_ring_end(const btf_dirset *s, int start)
{
    int e = start + 1;
    while (e < s->count && fabs(s->dirs[e].theta - s->dirs[start].theta) < 1e-6)
        e++;
    return e;
}

static inline void rf_texel_params(const btf_rf_model *m, int f, size_t t, float *p);
static inline const float *rf_texel_open(const btf_rf_model *m, int f, size_t t, float *p)
{
    rf_texel_params(m, f, t, p);
    return p;
}

#define BTF_RF_CTX const rf_ctx *
#define BTF_RF_FIT(c) ((c)->m->fit)
#define BTF_RF_LOBES(c) ((c)->m->lobes)
#define BTF_RF_NPARAMS(c) ((c)->m->params)
/* the surface's texels: a sampled model's (paper section 6) through its
 * coordinate map (rf_map.h), the model's own otherwise; the GPU pass
 * (gpu/rf_render.comp) looks them up through the same map, uploaded */
#define BTF_RF_WIDTH(c) rf_surface_w((c)->m)
#define BTF_RF_HEIGHT(c) rf_surface_h((c)->m)
#define BTF_RF_INV_WIDTH(c) ((c)->inv_w)
#define BTF_RF_INV_HEIGHT(c) ((c)->inv_h)
#define BTF_RF_TEXEL size_t
#define BTF_RF_TEXEL_AT(c, x, y) rf_surface_texel((c)->m, x, y)
#define BTF_RF_SRC const float *
#define BTF_RF_P(src, s) ((src)[s])
#define BTF_RF_SCRATCH(name) float name[BTF_RF_SLOTS_CAP]
#define BTF_RF_OPEN(c, f, t, scratch) rf_texel_open((c)->m, f, t, scratch)
#define BTF_RF_VIEWSET(c) (&(c)->m->views)
#define BTF_RF_N_LIGHTS(c) ((c)->n_lights)
#define BTF_RF_LIGHT_KIND(c, j) ((int)(c)->lights[j].kind)
#define BTF_RF_LIGHT_VEC(c, j, k)                                                          \
    ((c)->lights[j].kind == BTF_LIGHT_POINT ? (float)(c)->lights[j].position[k]            \
                                            : (float)(c)->lights[j].direction[k])
#define BTF_RF_LIGHT_RGB(c, j, k) ((c)->lights[j].rgb[k])
#define BTF_RFV_SET const btf_dirset *
#define BTF_RFV_COUNT(s) ((s)->count)
#define BTF_RFV_THETA(s, i) ((float)(s)->dirs[i].theta)
#define BTF_RFV_PHI(s, i) ((float)(s)->dirs[i].phi)
#define BTF_RFV_RING_END(s, i) rf_ring_end(s, i)

#include "rf/btf_rf_shared.h"

_Static_assert(BTF_RF_SLOTS_CAP == BTF_RF_MAX_SLOTS, "btf_rf_shared.h's slot count");
_Static_assert(BTF_RF_FIT_PTM == BTF_RF_PTM && BTF_RF_FIT_LOBES == BTF_RF_LOBES &&
               BTF_RF_FIT_LAFORTUNE == BTF_RF_LAFORTUNE, "btf_rf_shared.h's fit numbers");
_Static_assert((int)BTF_RF_RHO_MAX == (int)BTF_RF_MAX_RHO, "btf_rf_shared.h's rho bound");

/* An evaluation context of m (no lights). */
static inline rf_ctx rf_ctx_of(const btf_rf_model *m)
{
    rf_ctx c = {m, NULL, 0, 1.0f / (float)rf_surface_w(m), 1.0f / (float)rf_surface_h(m)};
    return c;
}

/* One lobe with parameters p = (rho, x, y, log2 n) at the unit light l. */
static inline double rf_lobe_eval(const float *p, const double l[3])
{
    return btf_rf_lobe(p[0], p[1], p[2], p[3], (float)l[0], (float)l[1], (float)l[2]);
}

/* The luminance of one texel's field with parameters p (fit's slot order,
 * docs/rf.md): light l, view v (lafortune only; may be NULL otherwise),
 * btf_rf_lum in float. */
static inline double rf_lum_eval(int fit, int lobes, const float *p, const double l[3],
                                 const double v[3])
{
    float vx = v ? (float)v[0] : 0.0f, vy = v ? (float)v[1] : 0.0f, vz = v ? (float)v[2] : 1.0f;
    return btf_rf_lum(p, fit, lobes, (float)l[0], (float)l[1], (float)l[2], vx, vy, vz);
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
    return btf_rf_dequant(q, lo, btf_rf_scale(lo, hi));
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
 * closest measured views with their weights (btf_rf_four_views of the
 * shared header), or a Lafortune model's one field; and the unit view
 * vector (Lafortune's lobes take it). Shared by the flat render
 * (rf_render.c) and the GPU pass's host code, so that both blend the same
 * fields with the same weights. */
typedef struct rf_look {
    btf_rf_views vs;
    float v[3];
} rf_look;

static inline rf_look rf_look_at(const btf_rf_model *m, btf_dir view)
{
    rf_look o;
    double vv[3];
    btf_dir_to_vec(view, vv);
    for (int k = 0; k < 3; k++)
        o.v[k] = (float)vv[k];
    if (m->fit == BTF_RF_LAFORTUNE)
        o.vs = btf_rf_make_views(0, 0, 0, 0, 1.0f, 0.0f, 0.0f, 0.0f);
    else
        o.vs = btf_rf_four_views(&m->views, (float)view.theta, (float)view.phi);
    return o;
}

/* rf_render.c: rows [0, height) of out (any size) from the tile of the
 * first min(width, tw) x min(height, th) texels (tw x th the model's),
 * which holds tile_w floats x 3 per row: pixel (x, y) is texel (x mod tw,
 * y mod th). */
void rf_tile_expand(const float *tile, int tile_w, int tw, int th, btf_image *out);
/* rf_render.c: the checks of a flat render (one-line BTF_E_ARG). */
btf_status rf_flat_check(const btf_rf_model *m, btf_dir view, btf_dir light, int width,
                         int height, int threads, btf_error *err);

/* rf_scene.c: the checks of a scene render with m and the G-buffer traced
 * (width, height 0: 512, set here); g is zeroed first, to free in any case
 * (btf__gbuffer_free). Shared by the CPU and the GPU scene renders. */
btf_status rf_scene_trace(const btf_rf_model *m, const btf_scene *s, int *width, int *height,
                          int threads, btf_gbuffer *g, btf_error *err);

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
/* Adds one residual r with gradient g (np entries) to the normal equations
 * of a Gauss-Newton step: jtr += g r and the upper triangle of jtj += g g^T.
 * Zero entries of g (parameters of lobes the sample does not see) are
 * skipped. Both fits' cost functions end each sample with it. */
void rf_lm_accumulate(const double *g, int np, double r, double *jtj, double *jtr);
/* Solves the symmetric positive definite system a x = b (n <= RF_LM_MAX, a
 * full row-major, only the upper triangle read) by Cholesky (core/linalg.c);
 * -1 when not positive definite, or when the factor or x is not finite. */
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

/* Luminance parameters per texel and field of a fit with k lobes. */
int btf__rf_param_count(int fit, int lobes);
/* BTF_E_DATA with the message when ds is a sparse set (the family fits
 * every light at each view); BTF_OK for a full grid. */
btf_status btf__rf_refuse_sparse(const btf_dataset *ds, btf_error *err);
/* Linear RGB of texel (x, y) (wrapped into the surface, btf_rf_surface_size;
 * a sampled model's through its coordinate map) of field `field` (a view
 * index; 0 for lafortune) lit from `light` (view: the view direction, used
 * by lafortune only); btf__rf_eval weights four of them. */
void btf__rf_eval_field(const btf_rf_model *m, int field, btf_dir view, btf_dir light, int x,
                        int y, float rgb[3]);

#include "rf/rf_render.h"

#endif
