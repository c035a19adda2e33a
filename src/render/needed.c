/*
 * needed.c — model only what the scene requires (docs/render.md): walk
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
    btf_shade_ctx *ctx;   /* tables, index and lights (no images) */
    uint8_t *rows_needed; /* [row][n_subspaces]: each row's own marks */
} needed_walk;

/* The subspaces of the pairs of lookups hv x hl whose two weights count
 * (the rule of btf_shade_blend). */
static void mark_pairs(const btf_shade_ctx *ctx, btf_hemi_weights hv, btf_hemi_weights hl,
                       uint8_t *mark)
{
    if (!(btf_shade_kept(hv.w0, hv.w1, hv.w2) > 0.0f) ||
        !(btf_shade_kept(hl.w0, hl.w1, hl.w2) > 0.0f))
        return;
    for (int i = 0; i < 3; i++) {
        if (!(btf_shade_w(hv, i) >= BTF_RENDER_MIN_WEIGHT))
            continue;
        for (int j = 0; j < 3; j++)
            if (btf_shade_w(hl, j) >= BTF_RENDER_MIN_WEIGHT)
                mark[BTF_SHADE_INDEX(ctx, btf_shade_i(hv, i) * ctx->n_lights_set +
                                              btf_shade_i(hl, j))] = 1;
    }
}

/* The directions of pixel p as btf_shade_pixel takes them. */
static void mark_pixel(const needed_walk *w, size_t p, uint8_t *mark)
{
    const btf_shade_ctx *ctx = w->ctx;
    const float *f = w->g->frame + 9 * p, *pos = w->g->position + 3 * p, *e = w->g->view + 3 * p;
    float vz = btf_shade_dot3(f[6], f[7], f[8], e[0], e[1], e[2]);
    vz = vz > BTF_RENDER_MIN_Z ? vz : BTF_RENDER_MIN_Z;
    btf_hemi_weights hv = btf_hemi_lookup(&ctx->views, btf_shade_dot3(f[0], f[1], f[2], e[0], e[1], e[2]),
                                          btf_shade_dot3(f[3], f[4], f[5], e[0], e[1], e[2]), vz);
    for (int j = 0; j < ctx->n_lights; j++) {
        btf_rgb d = btf_shade_light_dir(ctx, j, pos[0], pos[1], pos[2]);
        float lz = btf_shade_dot3(f[6], f[7], f[8], d.r, d.g, d.b);
        if (!(lz > 0.0f))
            continue; /* below the surface's horizon: no light (docs/render.md) */
        btf_hemi_weights hl =
            btf_hemi_lookup(&ctx->lights, btf_shade_dot3(f[0], f[1], f[2], d.r, d.g, d.b),
                            btf_shade_dot3(f[3], f[4], f[5], d.r, d.g, d.b), lz);
        mark_pairs(ctx, hv, hl, mark);
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

btf_status btf__render_check_model(const btf_model *m, btf_error *err)
{
    if (!m || m->n_subspaces < 1 || !m->subspaces)
        return btf__fail(err, BTF_E_ARG, "no model to render");
    if (!m->index || m->views.count < 1 || m->lights.count < 1)
        return btf__fail(err, BTF_E_ARG, "the model is a single texture: it has no view and "
                         "light directions to render with (analyse a BTF dataset)");
    return BTF_OK;
}

btf_status btf__render_needed(const btf_model *m, const btf_gbuffer *g, const btf_light *lights,
                              int n_lights, uint8_t *needed, int *count, btf_error *err)
{
    btf_status rc = btf__render_check_model(m, err);
    if (rc)
        return rc;
    if (!g || !needed || (n_lights > 0 && !lights) || n_lights < 0)
        return btf__fail(err, BTF_E_ARG, "needed subspaces: missing G-buffer or lights");
    needed_walk w = {m, g, NULL, NULL};
    btf_hemisphere *views = NULL, *lts = NULL;
    uint8_t *pair_index = NULL;
    w.ctx = btf__alloc(1, sizeof *w.ctx, err);
    if (!w.ctx)
        return BTF_E_NOMEM;
    memset(w.ctx, 0, sizeof *w.ctx);
    btf_render_sets sets;
    if ((rc = btf__render_sets_make(m, &sets, err)))
        goto done;
    if ((rc = btf__render_ctx_lights(w.ctx, lights, n_lights, err)) ||
        (rc = btf_hemisphere_build(&sets.views, &views, err)) ||
        (rc = btf_hemisphere_build(&sets.lights, &lts, err)) ||
        !(pair_index = btf__render_pair_index(m, &sets, err))) {
        btf__render_sets_free(&sets);
        rc = rc ? rc : BTF_E_NOMEM;
        goto done;
    }
    w.ctx->n_lights_set = sets.lights.count;
    btf__render_sets_free(&sets);
    btf__hemisphere_get_table(views, &w.ctx->views);
    btf__hemisphere_get_table(lts, &w.ctx->lights);
    w.ctx->index = pair_index;
    w.rows_needed = btf__alloc((size_t)(g->height > 0 ? g->height : 1),
                               (size_t)m->n_subspaces, err);
    if (!w.rows_needed) {
        rc = BTF_E_NOMEM;
        goto done;
    }
    memset(w.rows_needed, 0, (size_t)(g->height > 0 ? g->height : 1) * (size_t)m->n_subspaces);
    if ((rc = btf__pool_run(g->height, 0, walk_row, &w, NULL, err)))
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
    BTF_FREE_ALL(pair_index, w.rows_needed, w.ctx);
    btf_hemisphere_free(views);
    btf_hemisphere_free(lts);
    return rc;
}
