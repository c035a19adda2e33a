/*
 * rf_render.c — the flat (view, light) render of docs/render.md with a
 * reflectance-field model (Meseth, Müller & Klein 2003, section 5, on the
 * CPU): an orthographic patch, pixel (x, y) on texel (x mod width,
 * y mod height), seen from one view and lit by one unit directional light
 * at the exact light direction; the four closest measured views' fields
 * (rf_interp.c) are evaluated and blended with their weights (equation (3)
 * with one light; rf.h's rf_views_at and rf_blend, which the scene render
 * shares). Rows are shaded in parallel. A sampled model's (section 6)
 * texels are its surface's, each looked up through the coordinate map
 * (rf_map.h).
 */
#include "rf/rf.h"
#include "rf/rf_map.h"

#include <stdlib.h>
#include <string.h>

typedef struct render_ctx {
    const btf_rf_model *m;
    btf_image *out;
    rf_views vs;         /* the fields blended (1..4), rf.h */
    double l[3];
} render_ctx;

static btf_status row_job(void *user, int y, int worker, btf_error *err)
{
    (void)worker, (void)err;
    const render_ctx *c = user;
    const btf_rf_model *m = c->m;
    float *row = c->out->data + (size_t)y * c->out->width * 3;
    int sw = rf_surface_w(m), ty = y % rf_surface_h(m);
    for (int x = 0; x < c->out->width; x++) {
        double sum[3];
        rf_blend(m, &c->vs, rf_surface_texel(m, x % sw, ty), c->l, sum);
        for (int k = 0; k < 3; k++)
            row[3 * x + k] = (float)sum[k];
    }
    return BTF_OK;
}

btf_status btf_rf_render_flat(const btf_rf_model *m, btf_dir view, btf_dir light, int width,
                              int height, int threads, btf_image *out, btf_error *err)
{
    if (!out)
        return btf_fail(err, BTF_E_ARG, "btf_rf_render_flat: no output image");
    memset(out, 0, sizeof *out);
    if (!m || !m->codes || m->width < 1 || m->height < 1 ||
        (m->map && (m->surface_width < 1 || m->surface_height < 1)))
        return btf_fail(err, BTF_E_ARG, "btf_rf_render_flat: no model");
    if (width < 0 || height < 0 || threads < 0 || !(view.theta >= 0 && view.theta <= 90) ||
        !(light.theta >= 0 && light.theta <= 90) || !isfinite(view.phi) || !isfinite(light.phi))
        return btf_fail(err, BTF_E_ARG, "flat render: size %dx%d, threads %d, view (%g, %g), "
                        "light (%g, %g) (expected sizes and threads >= 0, theta in [0, 90])",
                        width, height, threads, view.theta, view.phi, light.theta, light.phi);
    render_ctx c;
    memset(&c, 0, sizeof c);
    c.m = m;
    btf_dir_to_vec(light, c.l);
    double vv[3];
    btf_dir_to_vec(view, vv);
    rf_views_at(m, view, vv, &c.vs);
    btf_status rc = btf_image_alloc(out, width ? width : rf_surface_w(m),
                                    height ? height : rf_surface_h(m), 3, err);
    if (rc)
        return rc;
    c.out = out;
    rc = btf_pool_run(out->height, threads, row_job, &c, NULL, err);
    if (rc)
        btf_image_free(out);
    return rc;
}
