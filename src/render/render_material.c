/*
 * render_material.c — the material ready to shade with: the triangulated
 * direction sets (render/hemisphere.c), the range and normal map of the
 * texture's size (btf__range_map), and the tileable subspace images the
 * scene needs (btf_synthesise with tileable set), synthesised once, in
 * parallel, kept in memory for the frame and never written to disk.
 */
#include "render/shade.h"
#include "core/core.h"
#include "model/model.h"
#include "synth/synth.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* 2^(levels - 1) of the deepest pyramid: a tileable synthesis needs each
 * side divisible by it (docs/synthesis.md, "Tileable synthesis"). */
static int texture_step(const btf_model *m)
{
    int levels = 1;
    for (int k = 0; k < m->n_subspaces; k++)
        if (m->subspaces[k].levels > levels)
            levels = m->subspaces[k].levels;
    return 1 << (levels - 1);
}

int btf__render_texture_side(const btf_model *m, int side)
{
    int step = texture_step(m);
    if (side < 8)
        side = 8;
    if (side > BTF_RENDER_MAX_SIDE)
        side = BTF_RENDER_MAX_SIDE;
    return (side + step - 1) / step * step;
}

typedef struct synth_jobs {
    const btf_model *m;
    const int *which;
    btf_render_material *rm;
    uint64_t seed;
    const btf_image *albedo; /* the structure layer's, placed with the range map */
} synth_jobs;

static btf_status synth_job(void *user, int j, int worker, btf_error *err)
{
    (void)worker;
    synth_jobs *s = user;
    int k = s->which[j];
    btf_synth_opts o = btf_synth_defaults();
    o.width = o.height = s->rm->size;
    o.seed = s->seed;
    o.tileable = 1;
    btf_status rc = btf__synthesise_image_albedo(s->m, k, &o, s->albedo, &s->rm->tex[k], err);
    btf_image *t = &s->rm->tex[k];
    if (rc == BTF_OK && s->m->albedo)
        btf__render_scale_texture(t->data, (size_t)t->width * t->height * 3,
                                  btf__render_reflectance(s->m, k));
    return rc;
}

void btf__render_material_free(btf_render_material *rm)
{
    if (!rm)
        return;
    btf_hemisphere_free(rm->views);
    btf_hemisphere_free(rm->lights);
    btf_image_free(&rm->height);
    btf_image_free(&rm->normal);
    if (rm->tex)
        for (int k = 0; k < rm->n_subspaces; k++)
            btf_image_free(&rm->tex[k]);
    BTF_FREE_ALL(rm->tex, rm->index, rm->gain, rm->horizon, rm);
}

static btf_status build_tables(const btf_model *m, btf_render_material *rm, btf_error *err)
{
    btf_render_sets sets;
    btf_status rc = btf__render_sets_make(m, &sets, err);
    if (rc)
        return rc;
    size_t pairs = (size_t)sets.views.count * (size_t)sets.lights.count;
    rm->n_views = sets.views.count;
    rm->n_lights = sets.lights.count;
    rm->n_subspaces = m->n_subspaces;
    rm->index = btf__render_pair_index(m, &sets, err);
    rm->tex = btf__alloc((size_t)m->n_subspaces, sizeof *rm->tex, err);
    rm->gain = btf__render_gains(m, &sets, err);
    if (!rm->index || !rm->tex || !rm->gain) {
        btf__render_sets_free(&sets);
        return BTF_E_NOMEM;
    }
    memset(rm->tex, 0, (size_t)m->n_subspaces * sizeof *rm->tex);
    for (size_t i = 0; i < pairs; i++)
        if (rm->index[i] >= m->n_subspaces) {
            btf__render_sets_free(&sets);
            return btf__fail(err, BTF_E_FORMAT, "index table entry %zu names subspace %d of %d",
                             i, rm->index[i], m->n_subspaces);
        }
    rm->light_outer_z = btf__render_light_outer_z(m);
    rm->ambient = btf__render_ambient(m);
    rc = btf_hemisphere_build(&sets.views, &rm->views, err);
    if (rc == BTF_OK)
        rc = btf_hemisphere_build(&sets.lights, &rm->lights, err);
    btf__render_sets_free(&sets);
    return rc;
}

btf_status btf__render_material_build(const btf_model *m, const uint8_t *needed,
                                      int texture_size, uint64_t seed, int threads,
                                      btf_render_material **out, btf_error *err)
{
    if (!out)
        return btf__fail(err, BTF_E_ARG, "render material: no output given");
    *out = NULL;
    btf_status rc = btf__render_check_model(m, err);
    if (rc)
        return rc;
    int side = btf__render_texture_side(m, texture_size);
    if (side != texture_size)
        return btf__fail(err, BTF_E_ARG, "texture size %d: expected a multiple of %d (the "
                         "model's pyramid) from 8 to %d, e.g. %d", texture_size, texture_step(m),
                         BTF_RENDER_MAX_SIDE, side);
    btf_render_material *rm = btf__alloc(1, sizeof *rm, err);
    if (!rm)
        return BTF_E_NOMEM;
    memset(rm, 0, sizeof *rm);
    rm->size = side;
    int *which = NULL;
    btf_image albedo = {0}; /* quilted once with the range map, for every texture */
    if ((rc = build_tables(m, rm, err)) ||
        (rc = btf__structure_maps(m, side, side, seed, &rm->height, &rm->normal,
                                  m->albedo ? &albedo : NULL, 1, err)))
        goto fail;
    float bounds[2];
    if ((rc = btf__render_relief(m, &rm->height, threads, &rm->horizon, bounds, err)))
        goto fail;
    rm->hmin = bounds[0], rm->hmax = bounds[1];
    which = btf__alloc((size_t)m->n_subspaces, sizeof *which, err);
    if (!which) {
        rc = BTF_E_NOMEM;
        goto fail;
    }
    int n = 0;
    for (int k = 0; k < m->n_subspaces; k++)
        if (!needed || needed[k])
            which[n++] = k;
    synth_jobs sj = {m, which, rm, seed, albedo.data ? &albedo : NULL};
    if ((rc = btf__pool_run(n, threads, synth_job, &sj, NULL, err)))
        goto fail;
    free(which);
    btf_image_free(&albedo);
    *out = rm;
    return BTF_OK;
fail:
    free(which);
    btf_image_free(&albedo);
    btf__render_material_free(rm);
    return rc;
}
