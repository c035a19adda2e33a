/*
 * rf_render.c — the flat (view, light) render of docs/render.md with a
 * reflectance-field model (Meseth, Müller & Klein 2003, section 5, on the
 * CPU): an orthographic patch, pixel (x, y) on texel (x mod width,
 * y mod height), seen from one view and lit by one unit directional light
 * at the exact light direction; the four closest measured views' fields
 * (rf_interp.c) are evaluated and blended with their weights (equation (3)
 * with one light). Rows are shaded in parallel.
 */
#include "rf/rf.h"

#include <stdlib.h>
#include <string.h>

typedef struct render_ctx {
    const btf_rf_model *m;
    btf_image *out;
    int n;               /* fields blended (1..4) */
    int field[4];
    double w[4];
    double l[3], v[4][3];
} render_ctx;

static btf_status row_job(void *user, int y, int worker, btf_error *err)
{
    (void)worker, (void)err;
    const render_ctx *c = user;
    const btf_rf_model *m = c->m;
    float p[BTF_RF_MAX_SLOTS];
    float *row = c->out->data + (size_t)y * c->out->width * 3;
    int ty = y % m->height;
    for (int x = 0; x < c->out->width; x++) {
        size_t t = (size_t)ty * m->width + x % m->width;
        double sum[3] = {0, 0, 0};
        for (int i = 0; i < c->n; i++) {
            rf_texel_params(m, c->field[i], t, p);
            double lum = rf_lum_eval(m->fit, m->lobes, p, c->l, c->v[i]);
            for (int k = 0; k < 3; k++)
                sum[k] += c->w[i] * (float)(lum * p[m->params + k]);
        }
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
    if (!m || !m->codes || m->width < 1 || m->height < 1)
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
    if (m->fit == BTF_RF_LAFORTUNE) {
        c.n = 1, c.field[0] = 0, c.w[0] = 1.0;
        btf_dir_to_vec(view, c.v[0]);
    } else {
        int idx[4];
        double w[4];
        btf_rf_view_weights(&m->views, view, idx, w);
        for (int i = 0; i < 4; i++)
            if (w[i] != 0.0) {
                c.field[c.n] = idx[i], c.w[c.n] = w[i];
                btf_dir_to_vec(m->views.dirs[idx[i]], c.v[c.n]);
                c.n++;
            }
    }
    btf_status rc = btf_image_alloc(out, width ? width : m->width, height ? height : m->height, 3,
                                    err);
    if (rc)
        return rc;
    c.out = out;
    rc = btf_pool_run(out->height, threads, row_job, &c, NULL, err);
    if (rc)
        btf_image_free(out);
    return rc;
}
