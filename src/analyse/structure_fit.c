/*
 * structure_fit.c — the structure layer of an analysis (docs/model.md,
 * "Structure"): what the measured relief and albedo explain of each
 * subspace image is divided out before the CAR fit, so that the fields
 * model only the remainder and the renderer multiplies the measured
 * structure back, registered through one quilting map.
 *
 * The paper keeps the range map and relights it with bump mapping
 * (Haindl & Filip 2007, section III) but fits the CAR models to the whole
 * subspace image, whose variance already holds that relief's shading: the
 * relief was counted twice and registered nowhere. Here each exemplar S_k
 * under light l_k is modelled as
 *     S_k(x) = R_k(x) * A(x) * (a + vis_k(x) max(0, n(x) . l_k)) / (a + l_kz)
 * with A the albedo's luminance pattern from photometric stereo (mean 1),
 * n the range map's normals (btf__normal_map, as the renderer derives
 * them), a the ambient term fitted below, and R_k what the CAR model
 * fits, and vis_k the light's visibility over the range map's horizon
 * (the relief's cast shadows, src/render/btf_horizon.h). The factor is the
 * renderer's bump factor (btf_render_shared.h).
 */
#include "core/core.h"
#include "model/model.h"
#include "model/range_code.h"
#include "render/btf_horizon.h"
#include "render/render.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A shading factor below this is held there when dividing: a texel the
 * relief turns away from the light keeps its own colour, not a blow-up. */
#define SHADE_DIVIDE_MIN 0.1
/* The flat surface's l_z floor (BTF_FLAT_MIN_Z of the renderer). */
#define FLAT_MIN_Z 0.05
/* The parallax's v_z floor (BTF_PARALLAX_MIN_Z of the renderer). */
#define PARALLAX_MIN_Z 0.25

static double luminance(const float *p, int channels)
{
    return channels == 3 ? 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2] : p[0];
}

/* The colour layer (docs/model.md, "Colour layer"): each texel's colour
 * over its luminance, per channel over that ratio's mean, kept when some
 * channel's log2 spread across the sample is at least CHROMA_MIN_SPREAD
 * (BTF_CHROMA_MIN_SPREAD: the colours of a weave's two yarns; a brown
 * leather's pebbles vary mostly in luminance, which the pattern already
 * holds). */
static btf_status colour_layer(const btf_image *albedo, btf_model *m, double *spread_out,
                               btf_error *err)
{
    size_t n = (size_t)m->range_width * m->range_height;
    float *c = btf__alloc(n, 3 * sizeof(float), err);
    if (!c)
        return BTF_E_NOMEM;
    double sum[3] = {0, 0, 0}, spread = 0.0;
    for (size_t i = 0; i < n; i++) {
        const float *p = albedo->data + 3 * i;
        double y = luminance(p, 3);
        for (int k = 0; k < 3; k++) {
            double r = y > 0.0 && isfinite(y) && p[k] > 0.0f && isfinite(p[k]) ? p[k] / y : 1.0;
            c[3 * i + k] = (float)r;
            sum[k] += r;
        }
    }
    for (int k = 0; k < 3; k++) {
        double mean = sum[k] > 0.0 ? sum[k] / (double)n : 1.0, s1 = 0.0, s2 = 0.0;
        for (size_t i = 0; i < n; i++) {
            float v = btf__albedo_value(btf__albedo_code((float)(c[3 * i + k] / mean)));
            c[3 * i + k] = v; /* as the file keeps it */
            double l = log2(v);
            s1 += l, s2 += l * l;
        }
        double var = s2 / (double)n - (s1 / (double)n) * (s1 / (double)n);
        spread = var > spread * spread ? sqrt(var) : spread;
    }
    if (spread_out)
        *spread_out = spread;
    if (spread >= BTF_CHROMA_MIN_SPREAD)
        m->chroma = c;
    else
        free(c);
    return BTF_OK;
}

btf_status btf__structure_albedo_from(const btf_image *albedo, btf_model *m, double *spread,
                                      btf_error *err)
{
    if (spread)
        *spread = 0.0;
    size_t n = (size_t)m->range_width * m->range_height;
    if (albedo->width != m->range_width || albedo->height != m->range_height)
        return btf__fail(err, BTF_E_ARG, "structure layer: albedo %dx%d, range map %dx%d",
                         albedo->width, albedo->height, m->range_width, m->range_height);
    double sum = 0.0;
    size_t count = 0;
    for (size_t i = 0; i < n; i++) {
        double y = luminance(albedo->data + i * albedo->channels, albedo->channels);
        if (y > 0.0 && isfinite(y))
            sum += y, count++;
    }
    m->albedo = btf__alloc(n, sizeof(float), err);
    if (!m->albedo)
        return BTF_E_NOMEM;
    double mean = count && sum > 0.0 ? sum / (double)count : 1.0;
    for (size_t i = 0; i < n; i++) {
        double y = luminance(albedo->data + i * albedo->channels, albedo->channels);
        float a = y > 0.0 && isfinite(y) ? (float)(y / mean) : 1.0f;
        m->albedo[i] = btf__albedo_value(btf__albedo_code(a)); /* as the file keeps it */
    }
    return albedo->channels == 3 ? colour_layer(albedo, m, spread, err) : BTF_OK;
}

float btf__structure_vis(const uint32_t *horizon, size_t i, const double l[3])
{
    if (!horizon)
        return 1.0f;
    /* as btf_shade_shadow does it, with the flat sample's frame */
    float lx = (float)l[0], ly = (float)l[1], lz = (float)l[2];
    float t = btf_horizon_azimuth(lx, ly), fl = floorf(t);
    int d0 = (int)fl;
    d0 = d0 < 0 ? 0 : d0 > 7 ? 7 : d0;
    int d1 = d0 == 7 ? 0 : d0 + 1;
    float f = t - fl;
    uint32_t w0 = horizon[2 * i], w1 = horizon[2 * i + 1];
    float h = btf_horizon_decode(w0, w1, d0) * (1.0f - f) + btf_horizon_decode(w0, w1, d1) * f;
    return btf_horizon_vis(h, lx, ly, lz, 1.0f);
}

/* The shading factor of the lit term lit = vis max(0, n . l) under light l
 * (unit, frame of btf_dir_to_vec) with ambient a. */
static double shade_factor(double lit, const double l[3], double a)
{
    double flat = l[2] > FLAT_MIN_Z ? l[2] : FLAT_MIN_Z;
    return (a + lit) / (a + flat);
}

btf_status btf__structure_normals(const btf_model *m, btf_image *normal, btf_error *err)
{
    btf_image h = {m->range_width, m->range_height, 1, m->range};
    return btf__normal_map(&h, 1.0, normal, err);
}

static double lit_at(const btf_structure_geom *g, size_t t, const double l[3])
{
    const float *nv = g->normal->data + 3 * t;
    double d = nv[0] * l[0] + nv[1] * l[1] + nv[2] * l[2];
    return d > 0.0 ? btf__structure_vis(g->horizon, t, l) * d : 0.0;
}

double btf__structure_lit(const btf_structure_geom *g, size_t i, const double l[3])
{
    if (!g->taps)
        return lit_at(g, i, l);
    const btf_structure_tap *t = &g->taps[i];
    double s = 0.0;
    for (int k = 0; k < 4; k++)
        s += t->w[k] * lit_at(g, (size_t)t->i[k], l);
    return s;
}

double btf__structure_albedo_at(const btf_structure_geom *g, const btf_model *m, size_t i, int c)
{
    const btf_structure_tap *t = g->taps ? &g->taps[i] : NULL;
    double s = 0.0;
    for (int k = 0; k < (t ? 4 : 1); k++) {
        size_t j = t ? (size_t)t->i[k] : i;
        double a = m->albedo[j] * (c >= 0 && m->chroma ? m->chroma[3 * j + c] : 1.0f);
        s += (t ? t->w[k] : 1.0) * a;
    }
    return s;
}

/* The bilinear tap of (u, v) (texel centres at integers) on the w x h
 * sample: round the torus (wrap: the sample on a surface of its own size
 * is quilted as itself, which the renderer wraps) or held inside. */
static void bilinear_tap(double u, double v, int w, int h, int wrap, btf_structure_tap *t)
{
    if (!wrap) {
        u = u < 0.0 ? 0.0 : u > w - 1 ? w - 1 : u;
        v = v < 0.0 ? 0.0 : v > h - 1 ? h - 1 : v;
    }
    double fu = floor(u), fv = floor(v), fx = u - fu, fy = v - fv;
    long x0 = ((long)fu % w + w) % w, y0 = ((long)fv % h + h) % h;
    long x1 = x0 + 1 < w ? x0 + 1 : wrap ? 0 : x0, y1 = y0 + 1 < h ? y0 + 1 : wrap ? 0 : y0;
    t->i[0] = (int)(y0 * w + x0), t->w[0] = (float)((1 - fx) * (1 - fy));
    t->i[1] = (int)(y0 * w + x1), t->w[1] = (float)(fx * (1 - fy));
    t->i[2] = (int)(y1 * w + x0), t->w[2] = (float)((1 - fx) * fy);
    t->i[3] = (int)(y1 * w + x1), t->w[3] = (float)(fx * fy);
}

/* The taps of every pixel of the sample (the caller's to fill), and the
 * texture step of one unit of height seen from view: (v_x, -v_y) / v_z,
 * v_z held at the renderer's BTF_PARALLAX_MIN_Z. */
static btf_structure_tap *view_taps(const btf_model *m, btf_dir view, double *dx, double *dy,
                                    btf_error *err)
{
    double v[3];
    btf_dir_to_vec(view, v);
    double z = v[2] > PARALLAX_MIN_Z ? v[2] : PARALLAX_MIN_Z;
    *dx = v[0] / z, *dy = -v[1] / z;
    return btf__alloc((size_t)m->range_width * m->range_height, sizeof(btf_structure_tap), err);
}

static double height_wrapped(const btf_model *m, double u, double v)
{
    btf_structure_tap t;
    bilinear_tap(u, v, m->range_width, m->range_height, 1, &t);
    double s = 0.0;
    for (int k = 0; k < 4; k++)
        s += t.w[k] * m->range[t.i[k]];
    return s;
}

btf_status btf__structure_march_taps(const btf_model *m, btf_dir view, btf_structure_tap **taps,
                                     btf_error *err)
{
    int w = m->range_width, h = m->range_height;
    double dx, dy, lo = 0.0, hi = 0.0;
    btf_structure_tap *o = view_taps(m, view, &dx, &dy, err);
    if (!o)
        return BTF_E_NOMEM;
    for (size_t i = 0; i < (size_t)w * h; i++) {
        lo = i == 0 || m->range[i] < lo ? m->range[i] : lo;
        hi = i == 0 || m->range[i] > hi ? m->range[i] : hi;
    }
    /* btf_shade_march's rule at relief 1 */
    double span = (hi - lo) * sqrt(dx * dx + dy * dy) / BTF_MARCH_STEP;
    int steps = (int)floor(span < BTF_MARCH_MAX ? span : BTF_MARCH_MAX) + 1;
    double dh = (hi - lo) / steps;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double hit = lo, prev_h = hi, prev_d = 0.0;
            for (int i = 0; i <= steps; i++) {
                double hr = hi - i * dh, d = hr - height_wrapped(m, x + hr * dx, y + hr * dy);
                if (d <= 0.0) {
                    hit = i == 0 ? hr : prev_h - prev_d / (prev_d - d) * dh;
                    break;
                }
                prev_h = hr, prev_d = d;
            }
            bilinear_tap(x + hit * dx, y + hit * dy, w, h, 1, &o[(size_t)y * w + x]);
        }
    *taps = o;
    return BTF_OK;
}

btf_status btf__structure_warp(const btf_model *m, btf_dir view, btf_structure_tap **taps,
                               btf_error *err)
{
    int w = m->range_width, h = m->range_height;
    double dx, dy;
    btf_structure_tap *o = view_taps(m, view, &dx, &dy, err);
    if (!o)
        return BTF_E_NOMEM;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            /* the one-step parallax shift (u, v) += h (v_x, -v_y) / v_z of
             * the texel's own height h, texel centres at integers, held
             * inside. The renderer marches the view ray for a relief that
             * casts shadows (btf_shade_march); registering the exemplars
             * with that march was measured worse (the generated fabric's
             * report distance 10.4 against 8.3: photometric stereo's
             * heights of deep gaps are too shallow for a march to find
             * what hides them), so the analysis keeps the one step. */
            double hh = m->range[(size_t)y * w + x];
            bilinear_tap(x + hh * dx, y + hh * dy, w, h, 0, &o[(size_t)y * w + x]);
        }
    *taps = o;
    return BTF_OK;
}

/* The ambient term: the a that makes the remainder most uniform, i.e.
 * that minimises the summed variance over the exemplars of
 *     log(luminance / A) - log(a + vis max(0, n . l))
 * (the CAR fields then carry the least of the relief's shading). A
 * least-squares line of luminance / A against the lit term was tried
 * first; with the exemplars registered (btf__structure_warp) its errors in
 * the lit term drove a towards 0 and shadows far too dark. Searched on a
 * log grid over [AMBIENT_MIN, BTF_STRUCTURE_AMBIENT_MAX], then refined by
 * golden section. */
#define AMBIENT_MIN 1e-3
#define AMBIENT_GRID 48
#define AMBIENT_REFINE 24

typedef struct ambient_data {
    size_t n;     /* texels over all exemplars */
    float *y;     /* log(luminance / A) */
    float *lit;   /* vis max(0, n . l) */
    int *which;   /* exemplar of each texel */
    int count;
} ambient_data;

static double ambient_cost(const ambient_data *d, double a)
{
    double cost = 0.0;
    size_t i = 0;
    for (int k = 0; k < d->count; k++) {
        double s1 = 0.0, s2 = 0.0;
        size_t n = 0;
        for (; i < d->n && d->which[i] == k; i++, n++) {
            double r = d->y[i] - log(a + d->lit[i]);
            s1 += r, s2 += r * r;
        }
        if (n)
            cost += s2 / (double)n - (s1 / (double)n) * (s1 / (double)n);
    }
    return cost;
}

static double ambient_search(const ambient_data *d)
{
    double lo = log(AMBIENT_MIN), hi = log(BTF_STRUCTURE_AMBIENT_MAX), step = (hi - lo) / AMBIENT_GRID;
    int best = 0;
    double best_cost = ambient_cost(d, exp(lo));
    for (int j = 1; j <= AMBIENT_GRID; j++) {
        double c = ambient_cost(d, exp(lo + j * step));
        if (c < best_cost)
            best_cost = c, best = j;
    }
    double x0 = lo + (best > 0 ? best - 1 : 0) * step, x1 = lo + (best < AMBIENT_GRID ? best + 1 : best) * step;
    const double g = 0.6180339887498949;
    for (int it = 0; it < AMBIENT_REFINE; it++) {
        double u = x1 - g * (x1 - x0), v = x0 + g * (x1 - x0);
        if (ambient_cost(d, exp(u)) < ambient_cost(d, exp(v)))
            x1 = v;
        else
            x0 = u;
    }
    double a = exp(0.5 * (x0 + x1));
    return a < AMBIENT_MIN ? 0.0 : a > BTF_STRUCTURE_AMBIENT_MAX ? BTF_STRUCTURE_AMBIENT_MAX : a;
}

double btf__structure_fit_ambient(const btf_image *imgs, const btf_dir *lights,
                                  const btf_structure_geom *geoms, int n, const btf_model *m)
{
    size_t total = 0;
    for (int k = 0; k < n; k++)
        total += (size_t)imgs[k].width * imgs[k].height;
    ambient_data d = {0, malloc((total ? total : 1) * sizeof(float)),
                      malloc((total ? total : 1) * sizeof(float)),
                      malloc((total ? total : 1) * sizeof(int)), 0};
    double a = 0.0;
    if (d.y && d.lit && d.which) {
        for (int k = 0; k < n; k++) {
            double l[3];
            btf_dir_to_vec(lights[k], l);
            if (l[2] <= 0.0)
                continue;
            size_t px = (size_t)imgs[k].width * imgs[k].height;
            for (size_t i = 0; i < px; i++) {
                double y = luminance(imgs[k].data + 3 * i, 3) /
                           btf__structure_albedo_at(&geoms[k], m, i, -1);
                if (!(y > 0.0) || !isfinite(y))
                    continue; /* black: says nothing about the ratio */
                d.y[d.n] = (float)log(y);
                d.lit[d.n] = (float)btf__structure_lit(&geoms[k], i, l);
                d.which[d.n++] = d.count;
            }
            d.count++;
        }
        if (d.n)
            a = ambient_search(&d);
    }
    BTF_FREE_ALL(d.y, d.lit, d.which);
    return a;
}

void btf__structure_divide(btf_image *img, const btf_model *m, const btf_structure_geom *g,
                           btf_dir light, int albedo, double *mean_shade)
{
    double l[3];
    btf_dir_to_vec(light, l);
    size_t n = (size_t)img->width * img->height;
    double s = 0.0;
    for (size_t i = 0; i < n; i++) {
        double f = l[2] > 0.0 ? shade_factor(btf__structure_lit(g, i, l), l, m->ambient) : 1.0;
        s += f;
        double e = f > SHADE_DIVIDE_MIN ? f : SHADE_DIVIDE_MIN;
        for (int c = 0; c < 3; c++)
            img->data[3 * i + c] = (float)(img->data[3 * i + c] /
                                           (albedo ? e * btf__structure_albedo_at(g, m, i, c) : e));
    }
    if (mean_shade)
        *mean_shade = n ? s / (double)n : 1.0;
}
