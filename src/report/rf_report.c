/*
 * rf_report.c — btf_rf_report_write: the report of a reflectance-field
 * model (issue 19, point 4: "in btfcar report beside the CAR model's
 * compression and quality — including the pixel-wise error, by which only
 * this family can be judged"; docs/report.md, "Reflectance-field models").
 * Compression: the model file's bytes against the raw BTF. Quality per
 * sampled (view, light) pair: the measured image against the model's flat
 * render of that pair (btf_rf_render_flat, at a measured pair the fitted
 * field itself) by the texture distances the CAR report uses, and — since
 * this family keeps every texel — the pixel-wise mean |dY|; over every
 * image of the dataset the paper's Table 1 error (btf_rf_error). Pictures
 * of the sampled and the worst pairs, the preview sphere
 * (btf_rf_render_scene). No sweep: an RF model has no CAR settings to
 * trade. A sampled model (the paper's section 6) is measured like any
 * other, its surface through the coordinate map, and its compression
 * figures split into the sample's coefficients and the map. Everything is written into a temporary folder that moves into
 * place as a whole.
 */
#include "core/core.h"
#include "report/report.h"
#include "report/rf_report_data.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static btf_status check_match(const btf_dataset_info *in, const btf_rf_model *m,
                              btf_error *err)
{
    /* a sampled model's surface is compared as the flat render shows it */
    if ((!m->map && (m->width != in->width || m->height != in->height)) ||
        m->views.count != in->n_views || m->lights.count != in->n_lights)
        return btf_fail(err, BTF_E_ARG, "reflectance-field model of %d views x %d lights of "
                        "%dx%d texels does not describe dataset %s (%d views x %d lights of "
                        "%dx%d)", m->views.count, m->lights.count, m->width, m->height,
                        in->root, in->n_views, in->n_lights, in->width, in->height);
    for (int i = 0; i < in->n_views + in->n_lights; i++) {
        btf_dir a = i < in->n_views ? m->views.dirs[i] : m->lights.dirs[i - in->n_views];
        btf_dir b = i < in->n_views ? in->views->dirs[i] : in->lights->dirs[i - in->n_views];
        if (btf_dir_angle(a, b) > BTF_DIR_NAME_TOLERANCE)
            return btf_fail(err, BTF_E_ARG, "reflectance-field model's %s %d (theta %g, phi "
                            "%g) is not dataset %s's (theta %g, phi %g)",
                            i < in->n_views ? "view" : "light",
                            i < in->n_views ? i : i - in->n_views, a.theta, a.phi, in->root,
                            b.theta, b.phi);
    }
    return BTF_OK;
}

static double lum(const float *p)
{
    return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
}

typedef struct pair_job {
    const btf_dataset *ds;
    btf_rf_report_data *d;
    const char *dir;
    const unsigned char *want; /* [view * n_lights + light] */
    int picture_all;           /* the worst pass: picture every job */
    const int *jobs;           /* NULL: job i is pair i */
} pair_job;

/* One pair: the measured image against the flat render, by texture
 * distance and pixel by pixel; its picture when wanted. */
static btf_status measure_pair(void *user, int job, int worker, btf_error *err)
{
    (void)worker;
    pair_job *J = user;
    btf_rf_report_data *d = J->d;
    int i = J->jobs ? J->jobs[job] : job;
    btf_rf_pair *p = &d->pairs[i];
    if (J->picture_all && p->pictured)
        return BTF_OK;
    btf_image meas = {0}, model = {0};
    btf_status rc = btf_dataset_read(J->ds, p->view, p->light, &meas, err);
    if (rc == BTF_OK)
        rc = btf_rf_render_flat(d->m, d->in->views->dirs[p->view],
                                d->in->lights->dirs[p->light], d->in->width, d->in->height, 1,
                                &model, err);
    if (rc == BTF_OK && !J->picture_all) {
        btf_texture_distance_opts o = btf_texture_distance_defaults();
        o.reference_name = btf_dataset_path(J->ds, p->view, p->light);
        o.image_name = "the reflectance-field model's flat render";
        rc = btf_texture_distance(&meas, &model, &o, &p->d, err);
        size_t n = (size_t)meas.width * meas.height;
        double s = 0.0;
        for (size_t k = 0; k < n && meas.channels == 3; k++)
            s += fabs(lum(meas.data + 3 * k) - lum(model.data + 3 * k));
        p->mean_abs_dy = n ? s / (double)n : 0.0;
    }
    if (rc == BTF_OK && !p->pictured &&
        (J->picture_all || J->want[(size_t)p->view * d->in->n_lights + p->light])) {
        char name[64];
        btf_rf_report_pair_file(d, i, name, sizeof name);
        rc = btf_report_write_pair(J->dir, name, &meas, &model, err);
        p->pictured = rc == BTF_OK;
    }
    btf_image_free(&meas);
    btf_image_free(&model);
    return rc;
}

/* The pairs: all, or the spread of views x lights; which get pictures
 * (the measured spread; with every pair measured, the default spread). */
static btf_status choose_pairs(btf_rf_report_data *d, unsigned char **want, btf_error *err)
{
    const btf_dataset_info *in = d->in;
    const btf_quality_opts *q = &d->o->quality;
    int *vi = btf_alloc((size_t)in->n_views + in->n_lights, sizeof(int), err);
    *want = btf_calloc((size_t)in->n_views * in->n_lights, 1, err);
    if (!vi || !*want) {
        free(vi);
        return BTF_E_NOMEM;
    }
    int *li = vi + in->n_views, nv, nl;
    if (q->all) {
        for (int i = 0; i < in->n_views; i++)
            vi[i] = i;
        for (int i = 0; i < in->n_lights; i++)
            li[i] = i;
        nv = in->n_views, nl = in->n_lights;
    } else {
        nv = btf_spread_directions(in->views, q->views > 0 ? q->views : 9, vi);
        nl = btf_spread_directions(in->lights, q->lights > 0 ? q->lights : 9, li);
    }
    d->pairs = btf_calloc((size_t)nv * nl > 0 ? (size_t)nv * nl : 1, sizeof *d->pairs, err);
    if (!d->pairs) {
        free(vi);
        return BTF_E_NOMEM;
    }
    for (int a = 0; a < nv; a++)
        for (int b = 0; b < nl; b++) {
            btf_rf_pair *p = &d->pairs[d->n_pairs++];
            p->view = vi[a], p->light = li[b];
        }
    if (q->all) {
        nv = btf_spread_directions(in->views, 9, vi);
        nl = btf_spread_directions(in->lights, 9, li);
    }
    for (int a = 0; a < nv; a++)
        for (int b = 0; b < nl; b++)
            (*want)[(size_t)vi[a] * in->n_lights + li[b]] = 1;
    free(vi);
    return BTF_OK;
}

typedef struct ranked {
    double v;
    int i;
} ranked;

static int larger_first(const void *a, const void *b)
{
    const ranked *x = a, *y = b;
    if (x->v != y->v)
        return x->v < y->v ? 1 : -1;
    return x->i - y->i;
}

/* Means, worsts and the worst pairs by pixel-wise error. */
static btf_status summarise(btf_rf_report_data *d, btf_error *err)
{
    int n = d->n_pairs;
    ranked *r = btf_alloc((size_t)n, sizeof *r, err);
    d->worst = btf_alloc((size_t)n, sizeof(int), err);
    if (!r || !d->worst) {
        free(r);
        return BTF_E_NOMEM;
    }
    for (int i = 0; i < n; i++) {
        const btf_rf_pair *p = &d->pairs[i];
        d->mean_combined += p->d.combined / n;
        d->mean_spectrum += p->d.spectrum.normalised / n;
        d->mean_first_order += p->d.first_order.normalised / n;
        d->mean_structure += p->d.structure.normalised / n;
        d->mean_pair_dy += p->mean_abs_dy / n;
        if (p->d.combined > d->worst_combined)
            d->worst_combined = p->d.combined;
        if (p->mean_abs_dy > d->worst_pair_dy)
            d->worst_pair_dy = p->mean_abs_dy;
        r[i] = (ranked){p->mean_abs_dy, i};
    }
    qsort(r, (size_t)n, sizeof *r, larger_first);
    for (int i = 0; i < n; i++)
        d->worst[i] = r[i].i;
    free(r);
    d->n_worst = d->o->worst < n ? d->o->worst : n;
    return BTF_OK;
}

static btf_status preview(btf_rf_report_data *d, const char *dir, btf_error *err)
{
    btf_scene sc;
    int side = d->o->sphere_size;
    btf_status rc = btf_scene_sphere(d->o->sphere_light, side / 2.4, &sc, err);
    if (rc)
        return rc;
    btf_image img = {0};
    double t0 = btf_now();
    rc = btf_rf_render_scene(d->m, &sc, side, side, d->o->threads, &img, NULL, err);
    d->sphere_s = btf_now() - t0;
    char path[4096];
    if (rc == BTF_OK)
        rc = btf_path_join(path, sizeof path, dir, "sphere.png", err);
    if (rc == BTF_OK)
        rc = btf_image_write_png(path, &img, err);
    btf_image_free(&img);
    btf_scene_free(&sc);
    return rc;
}

static btf_status measure_all(btf_rf_report_data *d, const btf_dataset *ds, const char *dir,
                              btf_error *err)
{
    const btf_report_opts *o = d->o;
    if (o->progress)
        o->progress(o->progress_user, 0.0, "model file and raw bytes");
    unsigned char *want = NULL;
    btf_status rc = btf_rf_model_bytes(d->m, &d->bytes, err);
    d->file_bytes = d->bytes.file;
    if (rc == BTF_OK)
        rc = btf_dataset_raw_bytes(ds, &d->raw, err);
    if (rc == BTF_OK && o->progress)
        o->progress(o->progress_user, 0.05, "pixel-wise error over every image");
    if (rc == BTF_OK)
        rc = btf_rf_error(ds, d->m, o->threads, &d->mean_abs_error, &d->mean_luminance, err);
    if (rc == BTF_OK)
        rc = choose_pairs(d, &want, err);
    if (rc == BTF_OK) {
        pair_job J = {ds, d, dir, want, 0, NULL};
        btf_pool_progress pp = {o->progress, o->progress_user,
                                "measuring (view, light) pairs", 0.5, 0.9, 1};
        rc = btf_pool_run(d->n_pairs, o->threads, measure_pair, &J, &pp, err);
    }
    if (rc == BTF_OK)
        rc = summarise(d, err);
    if (rc == BTF_OK) { /* the worst pairs' pictures, where not taken yet */
        pair_job J = {ds, d, dir, want, 1, d->worst};
        rc = btf_pool_run(d->n_worst, o->threads, measure_pair, &J, NULL, err);
    }
    free(want);
    if (rc == BTF_OK && o->progress)
        o->progress(o->progress_user, 0.9, "the preview");
    if (rc == BTF_OK)
        rc = preview(d, dir, err);
    return rc;
}

btf_status btf_rf_report_write(const btf_dataset *ds, const btf_rf_model *m, const char *dir,
                               const btf_report_opts *opts, btf_report_summary *summary,
                               btf_error *err)
{
    if (summary)
        memset(summary, 0, sizeof *summary);
    if (!ds || !m || !m->codes || !dir)
        return btf_fail(err, BTF_E_ARG, "report: no dataset, reflectance-field model or "
                        "folder given");
    btf_report_opts o = opts ? *opts : btf_report_defaults(), def = btf_report_defaults();
    if (o.sweep)
        return btf_fail(err, BTF_E_ARG, "report: the sweep varies the CAR analysis; a "
                        "reflectance-field model has no such settings");
    if (!o.sphere_light_set && o.sphere_light.theta == 0.0 && o.sphere_light.phi == 0.0)
        o.sphere_light = def.sphere_light;
    o.sphere_size = o.sphere_size ? o.sphere_size : def.sphere_size;
    o.worst = o.worst ? o.worst : def.worst;
    if (o.sphere_size < 16 || o.sphere_size > 4096 || o.worst < 0 || o.worst > 100 ||
        o.threads < 0)
        return btf_fail(err, BTF_E_ARG, "report: preview size %d, %d worst pairs, threads %d "
                        "(expected 16..4096, 0..100, >= 0)", o.sphere_size, o.worst,
                        o.threads);
    double t0 = btf_now();
    btf_rf_report_data d;
    memset(&d, 0, sizeof d);
    d.in = btf_dataset_get_info(ds);
    d.m = m;
    d.o = &o;
    d.dataset_name = o.dataset_name ? o.dataset_name : d.in->root;
    d.model_name = o.model_name ? o.model_name : "model";
    time_t now = time(NULL);
    struct tm tm;
    gmtime_r(&now, &tm);
    strftime(d.date, sizeof d.date, "%Y-%m-%d %H:%M UTC", &tm);
    btf_status rc = check_match(d.in, m, err);
    if (rc)
        return rc;
    btf_output_dir *od = NULL;
    if ((rc = btf_output_dir_begin(dir, &od, err)))
        return rc;
    const char *tmp = btf_output_dir_path(od);
    rc = measure_all(&d, ds, tmp, err);
    d.seconds = btf_now() - t0;
    if (rc == BTF_OK)
        rc = btf_rf_report_page(&d, tmp, err);
    if (rc == BTF_OK)
        rc = btf_output_dir_commit(od, err);
    else
        btf_output_dir_fail(od, err);
    if (rc == BTF_OK && summary) {
        summary->model_bytes = d.file_bytes;
        summary->raw_bytes = d.raw.raw;
        summary->ratio = d.file_bytes ? (double)d.raw.raw / (double)d.file_bytes : 0.0;
        summary->pairs = d.n_pairs;
        summary->mean_combined = d.mean_combined;
        summary->worst_combined = d.worst_combined;
        summary->mean_abs_error = d.mean_abs_error;
        summary->mean_luminance = d.mean_luminance;
        summary->seconds = btf_now() - t0;
    }
    if (o.progress)
        o.progress(o.progress_user, 1.0, "done");
    free(d.pairs);
    free(d.worst);
    return rc;
}
