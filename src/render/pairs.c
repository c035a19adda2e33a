/*
 * pairs.c — the C side's context of the shared shading
 * (btf_render_shared.h): the material's tables and images, the lights.
 */
#include "render/shade.h"
#include "core/core.h"
#include "model/model.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

btf_status btf__render_ctx_lights(btf_shade_ctx *ctx, const btf_light *lights, int n_lights,
                                  btf_error *err)
{
    if (n_lights < 0 || n_lights > BTF_RENDER_MAX_LIGHTS)
        return btf__fail(err, BTF_E_ARG, "%d lights: the renderer takes at most %d", n_lights,
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

void btf__render_ctx_material(btf_shade_ctx *ctx, const struct btf_render_material *rm)
{
    btf__hemisphere_get_table(rm->views, &ctx->views);
    btf__hemisphere_get_table(rm->lights, &ctx->lights);
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

float btf__render_ambient(const btf_model *m)
{
    return m->albedo ? (isfinite(m->ambient) && m->ambient > 0.0f ? m->ambient : 0.0f) : -1.0f;
}

/* The direction nearest to d among set's (ties: the lowest index). */
static int nearest_dir(const btf_dirset *set, btf_dir d)
{
    int best = 0;
    for (int i = 1; i < set->count; i++)
        if (btf_dir_angle(set->dirs[i], d) < btf_dir_angle(set->dirs[best], d))
            best = i;
    return best;
}

/* Ghost directions that make a set of 1 or 2 directions a triangle: for one
 * direction two at theta 80 degrees, 120 degrees of azimuth either side of
 * it; for two, the one of eight at theta 80 whose triangle with them is
 * widest (on the disk of sin theta (cos phi, sin phi)). */
static int ghosts(const btf_dirset *set, btf_dir *g)
{
    if (set->count == 1) {
        g[0] = (btf_dir){80.0, fmod(set->dirs[0].phi + 120.0, 360.0)};
        g[1] = (btf_dir){80.0, fmod(set->dirs[0].phi + 240.0, 360.0)};
        return 2;
    }
    double a[3], b[3], best = -1.0;
    btf_dir_to_vec(set->dirs[0], a);
    btf_dir_to_vec(set->dirs[1], b);
    for (int k = 0; k < 8; k++) {
        btf_dir c = {80.0, 45.0 * k};
        double v[3];
        btf_dir_to_vec(c, v);
        double area = fabs((b[0] - a[0]) * (v[1] - a[1]) - (b[1] - a[1]) * (v[0] - a[0]));
        if (area > best) {
            best = area;
            g[0] = c;
        }
    }
    return 1;
}

/* One set the renderer triangulates and, per direction, the model's. */
static btf_status render_set(const btf_dirset *set, btf_dirset *out, int **of, btf_error *err)
{
    btf_dir list[2 + 2];
    btf_status rc;
    if (set->count >= 3 || set->count < 1) {
        rc = btf__dirset_copy(out, set, err);
    } else {
        for (int i = 0; i < set->count; i++)
            list[i] = set->dirs[i];
        int n = set->count + ghosts(set, list + set->count);
        rc = btf_dirset_from_list(out, list, n, err);
        if (rc == BTF_OK)
            snprintf(out->name, sizeof out->name, "%s", set->name);
    }
    if (rc)
        return rc;
    *of = btf__alloc((size_t)(out->count > 0 ? out->count : 1), sizeof(int), err);
    if (!*of) {
        btf_dirset_free(out);
        return BTF_E_NOMEM;
    }
    for (int i = 0; i < out->count; i++)
        (*of)[i] = set->count >= 3 ? i : nearest_dir(set, out->dirs[i]);
    return BTF_OK;
}

btf_status btf__render_sets_make(const btf_model *m, btf_render_sets *s, btf_error *err)
{
    memset(s, 0, sizeof *s);
    btf_status rc = render_set(&m->views, &s->views, &s->view_of, err);
    if (rc == BTF_OK)
        rc = render_set(&m->lights, &s->lights, &s->light_of, err);
    if (rc)
        btf__render_sets_free(s);
    return rc;
}

void btf__render_sets_free(btf_render_sets *s)
{
    btf_dirset_free(&s->views);
    btf_dirset_free(&s->lights);
    free(s->view_of);
    free(s->light_of);
    memset(s, 0, sizeof *s);
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

/* For every pair of the model's grid the pair whose image and gain stand
 * for it: itself when measured; in a sparse set (docs/render.md, "Sparse
 * pair sets") the nearest measured pair. */
static btf_status pair_sources(const btf_model *m, size_t **out, btf_error *err)
{
    size_t n = (size_t)m->views.count * (size_t)m->lights.count;
    size_t *src = btf__alloc(n ? n : 1, sizeof *src, err);
    double *vv = btf__alloc((size_t)m->views.count + m->lights.count + 1, 3 * sizeof(double), err);
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

/* The model's pair standing for pair p of the renderer's grid. */
static size_t model_pair(const btf_model *m, const btf_render_sets *s, const size_t *src,
                         size_t p)
{
    size_t L = (size_t)s->lights.count;
    return src[(size_t)s->view_of[p / L] * (size_t)m->lights.count + (size_t)s->light_of[p % L]];
}

uint8_t *btf__render_pair_index(const btf_model *m, const btf_render_sets *s, btf_error *err)
{
    size_t n = (size_t)s->views.count * (size_t)s->lights.count, *src = NULL;
    uint8_t *idx = btf__alloc(n ? n : 1, 1, err);
    if (!idx || pair_sources(m, &src, err)) {
        free(idx);
        return NULL;
    }
    for (size_t p = 0; p < n; p++)
        idx[p] = m->index ? m->index[model_pair(m, s, src, p)] : 0;
    free(src);
    return idx;
}

float *btf__render_gains(const btf_model *m, const btf_render_sets *s, btf_error *err)
{
    size_t n = (size_t)s->views.count * (size_t)s->lights.count, *src = NULL;
    float *g = btf__alloc(n ? 3 * n : 1, sizeof(float), err);
    if (!g || pair_sources(m, &src, err)) {
        free(g);
        return NULL;
    }
    for (size_t p = 0; p < n; p++) {
        size_t q = model_pair(m, s, src, p);
        for (int c = 0; c < 3; c++)
            g[3 * p + c] = m->gain ? m->gain[3 * q + c] : 1.0f;
    }
    free(src);
    return g;
}

float btf__render_reflectance(const btf_model *m, int k)
{
    float a = btf__render_ambient(m);
    if (a < 0.0f || k < 0 || k >= m->n_subspaces || m->subspaces[k].light < 0 ||
        m->subspaces[k].light >= m->lights.count)
        return 1.0f;
    double l[3];
    btf_dir_to_vec(m->lights.dirs[m->subspaces[k].light], l);
    double z = l[2] > BTF_FLAT_MIN_Z ? l[2] : BTF_FLAT_MIN_Z; /* the shading's flat floor */
    return (float)(1.0 / (a + z));
}

void btf__render_scale_texture(float *data, size_t floats, float g)
{
    for (size_t i = 0; i < floats; i++)
        data[i] = data[i] * g;
}

float btf__render_light_outer_z(const btf_model *m)
{
    double outer = 0.0;
    for (int i = 0; i < m->lights.count; i++)
        outer = m->lights.dirs[i].theta > outer ? m->lights.dirs[i].theta : outer;
    return (float)cos(outer * (3.14159265358979323846 / 180.0));
}

btf_status btf__render_relief(const btf_model *m, const btf_image *height, int threads,
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
    return btf__horizon_map(h, height->width, height->height, 1, threads, horizon, err);
}
