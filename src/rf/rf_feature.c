/*
 * rf_feature.c — the representative image on which the memory reduction
 * of Meseth, Müller & Klein 2003, section 6, chooses its sample and
 * synthesises its coordinate map. The paper's synthesis (Tong et al.'s)
 * compares texels by "the m most significant view- and lighting
 * conditions"; one map must serve every view and light, so the image has
 * to hold what decides a texel's look in all of them: its albedo and the
 * orientation of its relief. Per texel of the head-on view (the smallest
 * theta) the Lambertian fit over all its lights, b = argmin sum_l
 * (y_l - b.l)^2 = rho n (Woodham's photometric stereo; b_z ~ albedo, b_x
 * and b_y ~ albedo times the slope), three channels on one scale. The
 * average over all directions would blur the relief away, and a single
 * head-on image under a head-on light shows no shading at all.
 *
 * The view's images are read in parallel into luminance planes, then each
 * texel is combined in light order, so the image does not depend on the
 * thread count.
 */
#include "rf/rf.h"
#include "rf/rf_sample.h"

#include <stdlib.h>
#include <string.h>

typedef struct feat_ctx {
    const btf_dataset *ds;
    int view, n, w, h;
    const double *p;   /* [3 * n] (LᵀL)⁻¹Lᵀ */
    float *lum;        /* [n * w * h] */
    float *out;        /* [w * h * 3] */
} feat_ctx;

static btf_status read_job(void *user, int l, int worker, btf_error *err)
{
    (void)worker;
    feat_ctx *c = user;
    btf_image img = {0};
    btf_status rc = btf_dataset_read(c->ds, c->view, l, &img, err);
    if (rc)
        return rc;
    if (img.width != c->w || img.height != c->h || img.channels != 3) {
        rc = btf__fail(err, BTF_E_DATA, "%s: %dx%d image (expected %dx%d like the dataset)",
                       btf_dataset_path(c->ds, c->view, l), img.width, img.height, c->w, c->h);
        btf_image_free(&img);
        return rc;
    }
    float *plane = c->lum + (size_t)l * c->w * c->h;
    size_t texels = (size_t)c->w * c->h;
    for (size_t t = 0; t < texels; t++) {
        float rgb[3];
        for (int k = 0; k < 3; k++)
            rgb[k] = isfinite(img.data[3 * t + k]) ? img.data[3 * t + k] : 0.0f;
        plane[t] = rf_luminance(rgb);
    }
    btf_image_free(&img);
    return BTF_OK;
}

static btf_status row_job(void *user, int y, int worker, btf_error *err)
{
    (void)worker, (void)err;
    feat_ctx *c = user;
    size_t texels = (size_t)c->w * c->h;
    for (int x = 0; x < c->w; x++) {
        size_t t = (size_t)y * c->w + x;
        double b[3] = {0, 0, 0};
        for (int l = 0; l < c->n; l++) {
            double v = c->lum[(size_t)l * texels + t];
            for (int k = 0; k < 3; k++)
                b[k] += c->p[k * c->n + l] * v;
        }
        for (int k = 0; k < 3; k++)
            c->out[3 * t + k] = isfinite(b[k]) ? (float)b[k] : 0.0f;
    }
    return BTF_OK;
}

/* p = (LᵀL + ridge)⁻¹Lᵀ for the unit light vectors; the ridge keeps a light
 * set that cannot pin b (fewer than three independent lights) defined. */
static btf_status lambert_operator(const btf_dirset *lights, double *p, btf_error *err)
{
    int n = lights->count;
    double ata[9] = {0};
    for (int j = 0; j < n; j++) {
        double l[3];
        btf_dir_to_vec(lights->dirs[j], l);
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++)
                ata[r * 3 + c] += l[r] * l[c];
    }
    double trace = ata[0] + ata[4] + ata[8];
    for (int r = 0; r < 3; r++)
        ata[r * 3 + r] += 1e-6 * trace / 3.0 + 1e-300;
    for (int j = 0; j < n; j++) {
        double l[3], x[3];
        btf_dir_to_vec(lights->dirs[j], l);
        if (rf_cholesky_solve(ata, l, 3, x) != 0)
            return btf__fail(err, BTF_E_NUMERIC, "representative image: the %d light "
                             "directions give no Lambertian fit (expected lights above the "
                             "surface)", n);
        for (int r = 0; r < 3; r++)
            p[r * n + j] = x[r];
    }
    return BTF_OK;
}

btf_status rf_feature_image(const btf_dataset *ds, int threads, float **out, int *view,
                            btf_error *err)
{
    *out = NULL;
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    feat_ctx c;
    memset(&c, 0, sizeof c);
    c.ds = ds, c.n = in->n_lights, c.w = in->width, c.h = in->height;
    for (int v = 1; v < in->n_views; v++)
        if (in->views->dirs[v].theta < in->views->dirs[c.view].theta)
            c.view = v;
    *view = c.view;
    double *p = btf__alloc((size_t)3 * c.n, sizeof(double), err);
    c.lum = btf__alloc((size_t)c.n * c.w * c.h, sizeof(float), err);
    c.out = btf__alloc((size_t)c.w * c.h * RF_FEATURES, sizeof(float), err);
    c.p = p;
    btf_status rc = p && c.lum && c.out ? lambert_operator(in->lights, p, err) : BTF_E_NOMEM;
    if (rc == BTF_OK)
        rc = btf__pool_run(c.n, threads, read_job, &c, NULL, err);
    if (rc == BTF_OK)
        rc = btf__pool_run(c.h, threads, row_job, &c, NULL, err);
    free(p);
    free(c.lum);
    if (rc) {
        free(c.out);
        return rc;
    }
    *out = c.out;
    return BTF_OK;
}
