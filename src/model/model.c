/*
 * model.c — the model struct's lifetime (paper section II: direction sets,
 * index table, per-subspace CAR models, range tile), and the provenance a
 * synthesis of one of its subspaces carries into an EXR.
 */
#include "core/core.h"
#include "model/model.h"

#include <stdlib.h>
#include <string.h>

void btf_model_free(btf_model *m)
{
    if (!m)
        return;
    btf_dirset_free(&m->views);
    btf_dirset_free(&m->lights);
    BTF_FREE_ALL(m->index, m->subspaces, m->range, m->albedo, m->chroma, m->gain);
    btf__model_internal_free(m->internal);
    memset(m, 0, sizeof *m);
}

btf_exr_meta btf_model_exr_meta(const btf_model *m, const char *model_path, int subspace,
                                uint64_t seed)
{
    btf_exr_meta meta = {.model = model_path, .seed = seed, .subspace = subspace};
    if (!m || subspace < 0 || subspace >= m->n_subspaces || !m->subspaces)
        return meta;
    const btf_subspace_model *sm = &m->subspaces[subspace];
    if (sm->view >= 0 && sm->view < m->views.count && sm->light >= 0 &&
        sm->light < m->lights.count) {
        meta.has_dirs = 1;
        meta.view = m->views.dirs[sm->view];
        meta.light = m->lights.dirs[sm->light];
    }
    return meta;
}
