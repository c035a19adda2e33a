/*
 * rf_scene.c — a scene rendered with a reflectance-field model (Meseth,
 * Müller & Klein 2003, section 5, on the CPU; docs/rf.md, "Rendering"):
 * the scene is traced into the G-buffer the CAR renderer shades
 * (btf__scene_trace), and every pixel is shaded by btf_rf_shade_pixel of
 * src/rf/btf_rf_shared.h, the text the GPU pass (gpu/rf_render.comp) runs:
 * the local view and light directions in the pixel's tangent frame as
 * src/render/ takes them (T, B, N rows, the view held at least 1e-3 above
 * the horizon, a light below the surface's horizon giving nothing, a point
 * light falling off as 1/d^2); the texel floor(uv) wrapped into the
 * surface's texels (as the flat render's pixel (x, y) is texel (x, y)),
 * through a sampled model's coordinate map (section 6, rf_map.h); the
 * four closest measured views' fields at the exact light direction,
 * blended. No parallax and no bump mapping: the fields hold the surface's
 * relief themselves.
 */
#include "rf/rf.h"
#include "rf/rf_map.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct scene_job {
    rf_ctx c;
    const btf_scene *s;
    const btf_gbuffer *g;
    btf_image *out;
} scene_job;

static btf_status row_job(void *user, int y, int worker, btf_error *err)
{
    (void)worker, (void)err;
    const scene_job *j = user;
    int w = j->g->width;
    for (int x = 0; x < w; x++) {
        size_t p = (size_t)y * (size_t)w + (size_t)x;
        float *o = j->out->data + 3 * p;
        if (j->g->object[p] < 0) {
            memcpy(o, j->s->background, 3 * sizeof(float));
            continue;
        }
        const float *f = j->g->frame + 9 * p, *pos = j->g->position + 3 * p;
        const float *e = j->g->view + 3 * p, *uv = j->g->uv + 2 * p;
        btf_rf_rgb c = btf_rf_shade_pixel(&j->c, f[0], f[1], f[2], f[3], f[4], f[5], f[6],
                                          f[7], f[8], pos[0], pos[1], pos[2], e[0], e[1], e[2],
                                          uv[0], uv[1]);
        o[0] = c.r, o[1] = c.g, o[2] = c.b;
    }
    return BTF_OK;
}

btf_status rf_scene_trace(const btf_rf_model *m, const btf_scene *s, int *width, int *height,
                          int threads, btf_gbuffer *g, btf_error *err)
{
    memset(g, 0, sizeof *g);
    if (!m || !m->codes || m->width < 1 || m->height < 1 || m->fields < 1 ||
        (m->map && (m->surface_width < 1 || m->surface_height < 1)))
        return btf__fail(err, BTF_E_ARG, "RF scene render: no model");
    if (!s)
        return btf__fail(err, BTF_E_ARG, "RF scene render: no scene given");
    *width = *width ? *width : 512;
    *height = *height ? *height : 512;
    if (*width < 1 || *height < 1 || *width > BTF_RENDER_MAX_SIDE ||
        *height > BTF_RENDER_MAX_SIDE || threads < 0)
        return btf__fail(err, BTF_E_ARG, "scene render: frame %dx%d, threads %d (expected "
                         "each side 1..%d, threads >= 0)", *width, *height, threads,
                         BTF_RENDER_MAX_SIDE);
    btf_status rc = btf_scene_check(s, err);
    if (rc)
        return rc;
    if (s->n_lights > 0 && !s->lights)
        return btf__fail(err, BTF_E_ARG, "scene: %d lights but no light array", s->n_lights);
    return btf__scene_trace(s, *width, *height, threads, g, err);
}

btf_status btf__rf_render_scene(const btf_rf_model *m, const btf_scene *s, int width,
                                int height, int threads, btf_image *out, btf_render_info *info,
                                btf_error *err)
{
    if (info)
        memset(info, 0, sizeof *info);
    if (!out)
        return btf__fail(err, BTF_E_ARG, "btf_rf_render_scene: no output image");
    memset(out, 0, sizeof *out);
    btf_gbuffer g;
    double t0 = btf__now();
    btf_status rc = rf_scene_trace(m, s, &width, &height, threads, &g, err);
    double t1 = btf__now();
    if (rc == BTF_OK)
        rc = btf_image_alloc(out, width, height, 3, err);
    if (rc == BTF_OK) {
        scene_job j = {rf_ctx_of(m), s, &g, out};
        j.c.lights = s->lights, j.c.n_lights = s->n_lights;
        rc = btf__pool_run(height, threads, row_job, &j, NULL, err);
        if (rc)
            btf_image_free(out);
    }
    btf__gbuffer_free(&g);
    if (rc == BTF_OK && info) {
        info->trace_s = t1 - t0;
        info->shade_s = btf__now() - t1;
    }
    return rc;
}
