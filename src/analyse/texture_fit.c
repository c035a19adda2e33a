/*
 * texture_fit.c — the model of one ordinary colour texture (Haindl & Filip
 * 2007, section II.C without II.A and II.B): a model of one subspace, fitted
 * by analyse/subspace_fit.c, with no direction sets, no index table and no
 * range map, and the margins synthesis will use kept with it, and the
 * marginal transfer that keeps the texture's histogram.
 */
#include "analyse/analyse.h"
#include "car/car.h"
#include "core/core.h"
#include "model/model.h"

#include <stdio.h>
#include <string.h>

btf_status btf_texture_fit(const btf_image *img, const btf_fit_opts *opts, btf_model *out,
                           btf_error *err)
{
    memset(out, 0, sizeof *out);
    if (!img || !img->data || img->channels != 3)
        return btf__fail(err, BTF_E_ARG, "texture fit needs an RGB image");
    out->subspaces = btf__calloc(1, sizeof(btf_subspace_model), err);
    if (!out->subspaces)
        return BTF_E_NOMEM;
    out->n_subspaces = 1;
    snprintf(out->views.name, sizeof out->views.name, "none");
    snprintf(out->lights.name, sizeof out->lights.name, "none");
    btf_status rc = btf__fit_subspace(img, opts, &out->subspaces[0], err);
    if (rc == 0 && btf__model_keep_margins(out, -1.0) != BTF_OK) /* for synthesis */
        rc = btf__fail(err, BTF_E_NOMEM, "out of memory");
    if (rc == 0) /* the histogram to keep (src/analyse/marginal_fit.c) */
        rc = btf__fit_marginals(img, out, 0, err);
    if (rc)
        btf_model_free(out);
    return rc;
}
