/*
 * pair_gain.c — the pair gains (docs/model.md, "Pair gains"): every
 * measured (view, light) pair keeps its own mean colour.
 *
 * The paper renders a pair from the image of its subspace (Haindl & Filip
 * 2007, sections II.A and III): all pairs of one cluster share that
 * image's colour histogram, and the relit shading only moves their
 * brightness as the relief's cosine does. The first-order statistics are
 * what an observer notices first (docs/measure.md: a 1 % brightness shift
 * is several times the material's distance to itself), and they cost one
 * colour per pair: the ratio of the measured image's mean colour to the
 * mean colour the renderer gives that pair, which the renderer multiplies
 * back (interpolated with the images' own weights, btf_render_shared.h).
 */
#include "core/core.h"
#include "model/model.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The flat surface's l_z floor (BTF_FLAT_MIN_Z of the renderer). */
#define FLAT_MIN_Z 0.05

btf_status btf__pair_gains(btf_model *m, const float *means, const double *pred, btf_error *err)
{
    int V = m->views.count, L = m->lights.count;
    size_t pairs = (size_t)V * L;
    float *g = btf__alloc(pairs * 3, sizeof(float), err);
    if (!g)
        return BTF_E_NOMEM;
    for (size_t i = 0; i < pairs; i++) {
        for (int c = 0; c < 3; c++) {
            double p = pred[3 * i + c], meas = means[3 * i + c];
            /* a black channel (or a prediction of nothing) keeps gain 1 */
            double r = p > 1e-12 && meas > 1e-12 && isfinite(p) && isfinite(meas) ? meas / p : 1.0;
            g[3 * i + c] = btf__gain_value(btf__gain_code((float)r)); /* as the file keeps it */
        }
    }
    free(m->gain);
    m->gain = g;
    return BTF_OK;
}

/* One view's pass: W_c(t), the albedo pattern of channel c (over its mean)
 * summed over the pixels whose taps read texel t, with their weights. */
static void view_weights(const btf_structure_tap *taps, size_t n, const float *alb, double *w)
{
    memset(w, 0, 3 * n * sizeof *w);
    for (size_t p = 0; p < n; p++)
        for (int k = 0; k < 4; k++) {
            size_t t = (size_t)taps[p].i[k];
            for (int c = 0; c < 3; c++)
                w[3 * t + c] += taps[p].w[k] * alb[3 * t + c];
        }
}

btf_status btf__pair_predict_views(const btf_model *m, const double *tex_mean,
                                   const btf_image *normal, const uint32_t *horizon,
                                   double *pred, btf_error *err)
{
    int V = m->views.count, L = m->lights.count;
    size_t n = (size_t)m->range_width * m->range_height;
    float *lit = btf__alloc((size_t)L * n, sizeof(float), err);
    float *alb = btf__alloc(n, 3 * sizeof(float), err);
    double *w = btf__alloc(n, 3 * sizeof(double), err);
    btf_status rc = lit && alb && w ? BTF_OK : BTF_E_NOMEM;
    btf_structure_geom g = {normal, horizon, NULL};
    for (int l = 0; rc == BTF_OK && l < L; l++) { /* vis max(0, n.l) per texel */
        double v[3];
        btf_dir_to_vec(m->lights.dirs[l], v);
        for (size_t t = 0; t < n; t++)
            lit[(size_t)l * n + t] = (float)btf__structure_lit(&g, t, v);
    }
    double mean[3] = {0, 0, 0};
    for (size_t t = 0; rc == BTF_OK && t < n; t++)
        for (int c = 0; c < 3; c++) {
            alb[3 * t + c] = m->albedo[t] * (m->chroma ? m->chroma[3 * t + c] : 1.0f);
            mean[c] += alb[3 * t + c];
        }
    for (size_t t = 0; rc == BTF_OK && t < n; t++)
        for (int c = 0; c < 3; c++)
            alb[3 * t + c] = (float)(alb[3 * t + c] / (mean[c] > 0.0 ? mean[c] / (double)n : 1.0));
    double a = m->ambient > 0.0f ? m->ambient : 0.0;
    for (int v = 0; rc == BTF_OK && v < V; v++) {
        btf_structure_tap *taps = NULL;
        rc = m->shadows ? btf__structure_march_taps(m, m->views.dirs[v], &taps, err)
                        : btf__structure_warp(m, m->views.dirs[v], &taps, err);
        if (rc)
            break;
        view_weights(taps, n, alb, w);
        free(taps);
        double total[3] = {0, 0, 0};
        for (size_t t = 0; t < n; t++)
            for (int c = 0; c < 3; c++)
                total[c] += w[3 * t + c];
        for (int l = 0; l < L; l++) {
            size_t pair = (size_t)v * L + l;
            if (m->index[pair] == BTF_PAIR_NONE) { /* not measured: gain 1 */
                for (int c = 0; c < 3; c++)
                    pred[3 * pair + c] = 0.0;
                continue;
            }
            int k = m->index[pair], own = m->subspaces[k].light;
            double lk[3] = {0, 0, 1}, dot[3] = {0, 0, 0};
            if (own >= 0 && own < L)
                btf_dir_to_vec(m->lights.dirs[own], lk);
            /* btf__render_reflectance: 1 / (a + max(l_kz, floor)) */
            double refl = 1.0 / (a + (lk[2] > FLAT_MIN_Z ? lk[2] : FLAT_MIN_Z));
            const float *li = lit + (size_t)l * n;
            for (size_t t = 0; t < n; t++)
                for (int c = 0; c < 3; c++)
                    dot[c] += w[3 * t + c] * li[t];
            for (int c = 0; c < 3; c++)
                pred[3 * pair + c] = tex_mean[3 * k + c] * refl * (a * total[c] + dot[c]) / (double)n;
        }
    }
    BTF_FREE_ALL(lit, alb, w);
    return rc;
}
