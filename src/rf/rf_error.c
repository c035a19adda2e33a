/*
 * rf_error.c — the fitting error of Meseth, Müller & Klein 2003, Table 1:
 * "average luminance difference between data and model", here the mean of
 * |Y_data - Y_model| over every texel of every (view, light) image, with
 * Y = 0.2126 R + 0.7152 G + 0.0722 B of linear RGB, the model evaluated at
 * the measured view (its own field) and light. The dataset is streamed one
 * image at a time, images in parallel; per-image sums are added in image
 * order, so the figure does not depend on the thread count.
 *
 * A sampled model (section 6) is measured as the flat render shows it:
 * data texel (x, y) against surface texel (x, y), wrapped into the surface,
 * through the coordinate map (rf_map.h). Outside the sample's own place no
 * surface texel corresponds to the data's, and the figure says so.
 */
#include "rf/rf.h"
#include "rf/rf_map.h"

#include <stdlib.h>
#include <string.h>

typedef struct err_ctx {
    const btf_dataset *ds;
    const btf_rf_model *m;
    const int *view_of, *light_of; /* dataset -> model index, -1: held out; NULL: the same */
    int nl;
    double *e, *s; /* per image */
} err_ctx;

static btf_status image_job(void *user, int i, int worker, btf_error *err)
{
    (void)worker;
    err_ctx *c = user;
    const btf_rf_model *m = c->m;
    int v = i / c->nl, l = i % c->nl;
    int mv = c->view_of ? c->view_of[v] : v, ml = c->light_of ? c->light_of[l] : l;
    if (mv < 0 || ml < 0) /* held out of the fit: not part of its error */
        return BTF_OK;
    btf_image img = {0};
    btf_status rc = btf_dataset_read(c->ds, v, l, &img, err);
    if (rc)
        return rc;
    const btf_dataset_info *in = btf_dataset_get_info(c->ds);
    if (img.width != in->width || img.height != in->height) {
        rc = btf__fail(err, BTF_E_DATA, "%s: %dx%d image (expected %dx%d like the dataset)",
                       btf_dataset_path(c->ds, v, l), img.width, img.height, in->width,
                       in->height);
        btf_image_free(&img);
        return rc;
    }
    double lv[3], vv[3], e = 0.0, s = 0.0;
    btf_dir_to_vec(m->lights.dirs[ml], lv);
    btf_dir_to_vec(m->views.dirs[mv], vv);
    int field = m->fit == BTF_RF_LAFORTUNE ? 0 : mv;
    float p[BTF_RF_MAX_SLOTS];
    int sw = rf_surface_w(m), sh = rf_surface_h(m);
    for (int y = 0; y < img.height; y++)
        for (int x = 0; x < img.width; x++) {
            const float *px = img.data + 3 * ((size_t)y * img.width + x);
            float rgb[3];
            for (int k = 0; k < 3; k++)
                rgb[k] = isfinite(px[k]) ? px[k] : 0.0f;
            double d = rf_luminance(rgb);
            rf_texel_params(m, field, rf_surface_texel(m, x % sw, y % sh), p);
            e += fabs(d - rf_lum_eval(m->fit, m->lobes, p, lv, vv));
            s += d;
        }
    btf_image_free(&img);
    c->e[i] = e, c->s[i] = s;
    return BTF_OK;
}

btf_status btf__rf_error(const btf_dataset *ds, const btf_rf_model *m, int threads,
                         double *mean_abs_error, double *mean_luminance, btf_error *err)
{
    /* without maps the dataset must have the model's direction sets (checked there) */
    return btf__rf_error_over(ds, m, NULL, NULL, threads, mean_abs_error, mean_luminance, err);
}

btf_status btf__rf_error_over(const btf_dataset *ds, const btf_rf_model *m, const int *view_of,
                              const int *light_of, int threads, double *mean_abs_error,
                              double *mean_luminance, btf_error *err)
{
    if (!ds || !m || !m->codes)
        return btf__fail(err, BTF_E_ARG, "btf_rf_error: no dataset or no model");
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    if ((!view_of && in->n_views != m->views.count) ||
        (!light_of && in->n_lights != m->lights.count) ||
        (!m->map && (in->width != m->width || in->height != m->height)))
        return btf__fail(err, BTF_E_DATA, "%s: %d views x %d lights of %dx%d (expected the "
                         "model's %d x %d of %dx%d)", in->root, in->n_views, in->n_lights,
                         in->width, in->height, m->views.count, m->lights.count, m->width,
                         m->height);
    int n = in->n_views * in->n_lights, fitted = 0;
    for (int i = 0; i < n; i++)
        fitted += (!view_of || view_of[i / in->n_lights] >= 0) &&
                  (!light_of || light_of[i % in->n_lights] >= 0);
    if (fitted == 0)
        return btf__fail(err, BTF_E_DATA, "%s: none of its images is one the model was "
                         "fitted to", in->root);
    err_ctx c = {ds, m, view_of, light_of, in->n_lights,
                 btf__calloc((size_t)n, sizeof(double), err),
                 btf__calloc((size_t)n, sizeof(double), err)};
    btf_status rc = c.e && c.s ? btf__pool_run(n, threads, image_job, &c, NULL, err) : BTF_E_NOMEM;
    if (rc == BTF_OK) {
        double e = 0.0, s = 0.0;
        for (int i = 0; i < n; i++)
            e += c.e[i], s += c.s[i];
        double count = (double)fitted * in->width * in->height;
        if (mean_abs_error)
            *mean_abs_error = e / count;
        if (mean_luminance)
            *mean_luminance = s / count;
    }
    free(c.e);
    free(c.s);
    return rc;
}
