/*
 * pairs.c — the C side's context of the shared shading
 * (btf_render_shared.h): the material's tables and images, the lights.
 */
#include "render/shade.h"
#include "core/core.h"
#include "model/model.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

btf_status btf_render_ctx_lights(btf_shade_ctx *ctx, const btf_light *lights, int n_lights,
                                 btf_error *err)
{
    if (n_lights < 0 || n_lights > BTF_RENDER_MAX_LIGHTS)
        return btf_fail(err, BTF_E_ARG, "%d lights: the renderer takes at most %d", n_lights,
                        BTF_RENDER_MAX_LIGHTS);
    ctx->n_lights = n_lights;
    for (int j = 0; j < n_lights; j++) {
        const btf_light *l = &lights[j];
        ctx->kind[j] = l->kind == BTF_LIGHT_POINT ? 1 : 0;
        double n2 = 0.0;
        for (int k = 0; k < 3; k++)
            n2 += l->direction[k] * l->direction[k];
        double inv = n2 > 0.0 && isfinite(n2) ? 1.0 / sqrt(n2) : 0.0;
        for (int k = 0; k < 3; k++) {
            ctx->vec[j][k] = ctx->kind[j] ? (float)l->position[k] : (float)(l->direction[k] * inv);
            ctx->rgb[j][k] = l->rgb[k];
        }
    }
    return BTF_OK;
}

void btf_render_ctx_material(btf_shade_ctx *ctx, const struct btf_render_material *rm)
{
    btf_hemisphere_get_table(rm->views, &ctx->views);
    btf_hemisphere_get_table(rm->lights, &ctx->lights);
    ctx->size = rm->size;
    ctx->n_lights_set = rm->n_lights;
    ctx->index = rm->index;
    for (int k = 0; k < rm->n_subspaces && k < BTF_SHADE_CTX_MAX_SUBSPACES; k++)
        ctx->tex[k] = rm->tex[k].data;
    ctx->height = rm->height.data;
    ctx->normal = rm->normal.data;
    ctx->gain = rm->gain;
    ctx->horizon = rm->horizon;
    ctx->hmin = rm->hmin;
    ctx->hmax = rm->hmax;
    ctx->light_outer_z = rm->light_outer_z;
    ctx->ambient = rm->ambient;
}

float btf_render_ambient(const btf_model *m)
{
    return m->albedo ? (isfinite(m->ambient) && m->ambient > 0.0f ? m->ambient : 0.0f) : -1.0f;
}

/* The measured pair nearest to pair p in the space of pairs (Haindl &
 * Filip 2007, section III: the Euclidean distance of the unit direction
 * vectors, here of views and lights together); ties: the lowest pair. */
static size_t nearest_measured(const btf_model *m, const double *vv, const double *lv, size_t p)
{
    size_t L = (size_t)m->lights.count, n = (size_t)m->views.count * L, best = p;
    double best_d = INFINITY;
    const double *a = vv + 3 * (p / L), *b = lv + 3 * (p % L);
    for (size_t q = 0; q < n; q++) {
        if (m->index[q] == BTF_PAIR_NONE)
            continue;
        const double *c = vv + 3 * (q / L), *e = lv + 3 * (q % L);
        double d = 0.0;
        for (int k = 0; k < 3; k++)
            d += (a[k] - c[k]) * (a[k] - c[k]) + (b[k] - e[k]) * (b[k] - e[k]);
        if (d < best_d) {
            best_d = d;
            best = q;
        }
    }
    return best;
}

/* For every pair of the grid the pair whose image and gain stand for it:
 * itself when measured; in a sparse set (docs/render.md, "Sparse pair
 * sets") the nearest measured pair. */
static btf_status pair_sources(const btf_model *m, size_t **out, btf_error *err)
{
    size_t n = (size_t)m->views.count * (size_t)m->lights.count;
    size_t *src = btf_alloc(n ? n : 1, sizeof *src, err);
    double *vv = btf_alloc((size_t)m->views.count + m->lights.count + 1, 3 * sizeof(double), err);
    if (!src || !vv) {
        free(src);
        free(vv);
        return BTF_E_NOMEM;
    }
    double *lv = vv + 3 * (size_t)m->views.count;
    for (int i = 0; i < m->views.count; i++)
        btf_dir_to_vec(m->views.dirs[i], vv + 3 * i);
    for (int i = 0; i < m->lights.count; i++)
        btf_dir_to_vec(m->lights.dirs[i], lv + 3 * i);
    for (size_t p = 0; p < n; p++)
        src[p] = m->index && m->index[p] == BTF_PAIR_NONE ? nearest_measured(m, vv, lv, p) : p;
    free(vv);
    *out = src;
    return BTF_OK;
}

uint8_t *btf_render_pair_index(const btf_model *m, btf_error *err)
{
    size_t n = (size_t)m->views.count * (size_t)m->lights.count, *src = NULL;
    uint8_t *idx = btf_alloc(n ? n : 1, 1, err);
    if (!idx || pair_sources(m, &src, err)) {
        free(idx);
        return NULL;
    }
    for (size_t p = 0; p < n; p++)
        idx[p] = m->index ? m->index[src[p]] : 0;
    free(src);
    return idx;
}

float *btf_render_gains(const btf_model *m, btf_error *err)
{
    size_t n = (size_t)m->views.count * (size_t)m->lights.count, *src = NULL;
    float *g = btf_alloc(n ? 3 * n : 1, sizeof(float), err);
    if (!g || pair_sources(m, &src, err)) {
        free(g);
        return NULL;
    }
    for (size_t p = 0; p < n; p++)
        for (int c = 0; c < 3; c++)
            g[3 * p + c] = m->gain ? m->gain[3 * src[p] + c] : 1.0f;
    free(src);
    return g;
}

float btf_render_reflectance(const btf_model *m, int k)
{
    float a = btf_render_ambient(m);
    if (a < 0.0f || k < 0 || k >= m->n_subspaces || m->subspaces[k].light < 0 ||
        m->subspaces[k].light >= m->lights.count)
        return 1.0f;
    double l[3];
    btf_dir_to_vec(m->lights.dirs[m->subspaces[k].light], l);
    double z = l[2] > BTF_FLAT_MIN_Z ? l[2] : BTF_FLAT_MIN_Z; /* the shading's flat floor */
    return (float)(1.0 / (a + z));
}

void btf_render_scale_texture(float *data, size_t floats, float g)
{
    for (size_t i = 0; i < floats; i++)
        data[i] = data[i] * g;
}

float btf_render_light_outer_z(const btf_model *m)
{
    double outer = 0.0;
    for (int i = 0; i < m->lights.count; i++)
        outer = m->lights.dirs[i].theta > outer ? m->lights.dirs[i].theta : outer;
    return (float)cos(outer * (3.14159265358979323846 / 180.0));
}

btf_status btf_render_relief(const btf_model *m, const btf_image *height, int threads,
                             uint32_t **horizon, float bounds[2], btf_error *err)
{
    size_t n = (size_t)height->width * height->height;
    const float *h = height->data;
    float a = n ? h[0] : 0.0f, b = a;
    for (size_t i = 1; i < n; i++) {
        a = h[i] < a ? h[i] : a;
        b = h[i] > b ? h[i] : b;
    }
    bounds[0] = a, bounds[1] = b;
    *horizon = NULL;
    if (!(m->shadows && m->albedo))
        return BTF_OK;
    return btf_horizon_map(h, height->width, height->height, 1, threads, horizon, err);
}
