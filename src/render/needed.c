/*
 * needed.c — model only what the scene requires (issue 15, point 7): walk
 * the G-buffer's pixels, find each one's three views and, per light, three
 * lights (Haindl & Filip 2007, section III), and collect the subspaces the
 * pairs with non-zero weight select. Only those are synthesised; a scene
 * seen near the normal needs far fewer than one seen at grazing angles.
 */
#include "render/shade.h"
#include "core/core.h"

#include <stdlib.h>
#include <string.h>

typedef struct needed_walk {
    const btf_model *m;
    const btf_gbuffer *g;
    const btf_light *lights;
    int n_lights;
    btf_hemisphere *views, *lts;
    uint8_t *rows_needed; /* [row][n_subspaces]: each row's own marks */
} needed_walk;

static void mark_pixel(const needed_walk *w, size_t p, uint8_t *mark)
{
    const float *frame = w->g->frame + 9 * p;
    float vl[3], ll[3], dir[3], rgb[3];
    btf_render_local_view(frame, w->g->view + 3 * p, vl);
    int iv[3], il[3];
    float wv[3], wl[3];
    btf_hemisphere_lookup(w->views, vl, iv, wv);
    for (int k = 0; k < w->n_lights; k++) {
        if (!btf_render_light_at(&w->lights[k], w->g->position + 3 * p, dir, rgb))
            continue;
        btf_render_to_local(frame, dir, ll);
        if (!(ll[2] > 0.0f))
            continue; /* below the surface's horizon: no light (docs/render.md) */
        btf_hemisphere_lookup(w->lts, ll, il, wl);
        btf_render_pairs pairs;
        btf_render_pairs_of(w->m->index, w->m->lights.count, iv, wv, il, wl, &pairs);
        for (int d = 0; d < pairs.n; d++)
            mark[pairs.sub[d]] = 1;
    }
}

static btf_status walk_row(void *user, int y, int worker, btf_error *err)
{
    (void)worker, (void)err;
    needed_walk *w = user;
    uint8_t *mark = w->rows_needed + (size_t)y * (size_t)w->m->n_subspaces;
    for (int x = 0; x < w->g->width; x++) {
        size_t p = (size_t)y * (size_t)w->g->width + (size_t)x;
        if (w->g->object[p] >= 0)
            mark_pixel(w, p, mark);
    }
    return BTF_OK;
}

btf_status btf_render_check_model(const btf_model *m, btf_error *err)
{
    if (!m || m->n_subspaces < 1 || !m->subspaces)
        return btf_fail(err, BTF_E_ARG, "no model to render");
    if (!m->index || m->views.count < 1 || m->lights.count < 1)
        return btf_fail(err, BTF_E_ARG, "the model is a single texture: it has no view and "
                        "light directions to render with (analyse a BTF dataset)");
    return BTF_OK;
}

btf_status btf_render_needed(const btf_model *m, const btf_gbuffer *g, const btf_light *lights,
                             int n_lights, uint8_t *needed, int *count, btf_error *err)
{
    btf_status rc = btf_render_check_model(m, err);
    if (rc)
        return rc;
    if (!g || !needed || (n_lights > 0 && !lights) || n_lights < 0)
        return btf_fail(err, BTF_E_ARG, "needed subspaces: missing G-buffer or lights");
    needed_walk w = {m, g, lights, n_lights, NULL, NULL, NULL};
    if ((rc = btf_hemisphere_build(&m->views, &w.views, err)) ||
        (rc = btf_hemisphere_build(&m->lights, &w.lts, err)))
        goto done;
    w.rows_needed = btf_alloc((size_t)(g->height > 0 ? g->height : 1),
                              (size_t)m->n_subspaces, err);
    if (!w.rows_needed) {
        rc = BTF_E_NOMEM;
        goto done;
    }
    memset(w.rows_needed, 0, (size_t)(g->height > 0 ? g->height : 1) * (size_t)m->n_subspaces);
    if ((rc = btf_pool_run(g->height, 0, walk_row, &w, NULL, err)))
        goto done;
    memset(needed, 0, (size_t)m->n_subspaces);
    int n = 0;
    for (int k = 0; k < m->n_subspaces; k++) {
        for (int y = 0; y < g->height && !needed[k]; y++)
            needed[k] = w.rows_needed[(size_t)y * (size_t)m->n_subspaces + (size_t)k];
        n += needed[k];
    }
    if (count)
        *count = n;
done:
    free(w.rows_needed);
    btf_hemisphere_free(w.views);
    btf_hemisphere_free(w.lts);
    return rc;
}
