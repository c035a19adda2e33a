/*
 * shade.c — the per-pixel rendering of Haindl & Filip 2007, section III and
 * Fig. 1, on a G-buffer (docs/render.md, "Shading"):
 *
 *  1. the local view direction v (tangent frame) selects three measured
 *     views with barycentric weights wv, each light's local direction l
 *     three measured lights with weights wl (render/hemisphere.c);
 *  2. parallax mapping: the texture coordinate is shifted along the view's
 *     tangent-plane direction by the relief-scaled height h of the range
 *     map, (u, v) += r h (v_x, -v_y) / max(v_z, BTF_PARALLAX_MIN_Z) (the
 *     image's rows grow downwards, the frame's y upwards);
 *  3. the nine pairs' subspace images are sampled there (bilinear, wrapped:
 *     the images are tileable) and blended with the weights wv_i wl_j;
 *  4. bump mapping: the blend is multiplied by max(0, n . l) / max(l_z,
 *     BTF_FLAT_MIN_Z), n the range map's normal with its slopes scaled by
 *     r. The measured images already hold the flat surface's mean shading
 *     (l_z), so a flat range map multiplies by exactly 1; a light below the
 *     surface's horizon (l_z <= 0) gives nothing.
 *
 * Each light adds its intensity times that; a negative sum (the CAR
 * model's Gaussian tails) becomes 0; background pixels get the background
 * colour.
 */
#include "render/shade.h"
#include "core/core.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

typedef struct shade_job {
    btf_shade_ctx ctx;
    const btf_gbuffer *g;
    const float *background;
    float relief;
    btf_image *out;
    atomic_int missing; /* a subspace the material lacks (set by any row) */
} shade_job;

/* The shared per-pixel shading (btf_render_shared.h) on G-buffer pixel p;
 * -1 when the pixel selects a subspace the material lacks (its flag, not
 * its colour, says so). */
static int shade_pixel(const shade_job *j, size_t p, float out[3])
{
    const btf_gbuffer *g = j->g;
    const float *f = g->frame + 9 * p, *pos = g->position + 3 * p, *e = g->view + 3 * p;
    btf_pixel c = btf_shade_pixel(&j->ctx, f[0], f[1], f[2], f[3], f[4], f[5], f[6], f[7],
                                  f[8], pos[0], pos[1], pos[2], e[0], e[1], e[2],
                                  g->uv[2 * p], g->uv[2 * p + 1], j->relief);
    if (c.missing)
        return -1;
    out[0] = c.r;
    out[1] = c.g;
    out[2] = c.b;
    return 0;
}

static btf_status shade_row(void *user, int y, int worker, btf_error *err)
{
    (void)worker, (void)err;
    shade_job *j = user;
    int w = j->g->width;
    for (int x = 0; x < w; x++) {
        size_t p = (size_t)y * (size_t)w + (size_t)x;
        float *o = j->out->data + 3 * p;
        if (j->g->object[p] < 0) {
            memcpy(o, j->background, 3 * sizeof(float));
            continue;
        }
        if (shade_pixel(j, p, o) < 0)
            atomic_store(&j->missing, 1);
    }
    return BTF_OK;
}

btf_status btf__render_shade(const btf_render_material *rm, const btf_gbuffer *g,
                             const btf_light *lights, int n_lights, const float background[3],
                             double relief, int threads, btf_image *out, btf_error *err)
{
    static const float black[3] = {0.0f, 0.0f, 0.0f};
    if (!rm || !g || !out || (n_lights > 0 && !lights) || n_lights < 0)
        return btf__fail(err, BTF_E_ARG, "shade: missing material, G-buffer, lights or output");
    if (!isfinite(relief) || fabs(relief) > 1e6)
        return btf__fail(err, BTF_E_ARG, "relief %g: expected a finite scale up to 1e6", relief);
    memset(out, 0, sizeof *out);
    btf_status rc = btf_image_alloc(out, g->width, g->height, 3, err);
    if (rc)
        return rc;
    shade_job *j = btf__alloc(1, sizeof *j, err);
    if (!j) {
        btf_image_free(out);
        return BTF_E_NOMEM;
    }
    memset(j, 0, sizeof *j);
    btf__render_ctx_material(&j->ctx, rm);
    if ((rc = btf__render_ctx_lights(&j->ctx, lights, n_lights, err))) {
        free(j);
        btf_image_free(out);
        return rc;
    }
    j->g = g;
    j->background = background ? background : black;
    j->relief = (float)relief;
    j->out = out;
    rc = btf__pool_run(g->height, threads, shade_row, j, NULL, err);
    if (rc == BTF_OK && atomic_load(&j->missing))
        rc = btf__fail(err, BTF_E_ARG, "shade: a pixel selects a subspace the material was "
                       "not built with (btf_render_needed gives the set)");
    free(j);
    if (rc)
        btf_image_free(out);
    return rc;
}
