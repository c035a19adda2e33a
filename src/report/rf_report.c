/*
 * rf_report.c — btf__rf_report_write: the report of a reflectance-field
 * model (docs/report.md, "Reflectance-field models"): beside the CAR
 * model's compression and quality, the pixel-wise error, by which only
 * this family can be judged. Compression: the model file's bytes against
 * the raw BTF. Quality per sampled (view, light) pair: the measured image
 * against the model's flat render of that pair (btf__rf_render_flat, at a
 * measured pair the fitted field itself) by the texture distances the CAR
 * report uses, and — since this family keeps every texel — the pixel-wise
 * mean |dY|; over every image the model was fitted to the paper's Table 1
 * error (btf__rf_error_over). Directions of the dataset that the model does
 * not hold were held out of its fit: their pairs are measured apart, as the
 * CAR report does (leave-out tests). Pictures of the sampled and the worst pairs, the preview
 * sphere (btf__rf_render_scene). No sweep: an RF model has no CAR settings
 * to trade. A sampled model (the paper's section 6) is measured like any
 * other, its surface through the coordinate map, and its compression
 * figures split into the sample's coefficients and the map. The shared run
 * (report_run.c) writes everything into a temporary folder that moves into
 * place as a whole; the sections are in rf_report_page.c.
 */
#include "core/core.h"
#include "report/rf_report_data.h"
#include "rf/rf_render.h"
#include "rf/rf_error.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Where the model's directions are among the dataset's: of[i] is the
 * model's index of the dataset's direction i, or -1 (held out of the fit).
 * Every direction of the model must be one of the dataset's. */
static btf_status map_dirs(const btf_dirset *model, const btf_dirset *data, const char *what,
                           const char *root, int *of, btf_error *err)
{
    for (int i = 0; i < data->count; i++)
        of[i] = btf_dirset_find(model, data->dirs[i], BTF_DIR_NAME_TOLERANCE);
    for (int j = 0; j < model->count; j++)
        if (btf_dirset_find(data, model->dirs[j], BTF_DIR_NAME_TOLERANCE) < 0)
            return btf__fail(err, BTF_E_ARG, "reflectance-field model's %s %d (theta %g, phi "
                             "%g) is not one of dataset %s's: the model does not describe it",
                             what, j, model->dirs[j].theta, model->dirs[j].phi, root);
    return BTF_OK;
}

/* The model must be of this dataset: its texels (a sampled model's surface
 * is compared as the flat render shows it) and its views and lights among
 * the dataset's. The dataset's other directions were held out of the fit,
 * as the CAR report allows (leave-out tests): their pairs, rendered at the
 * exact directions, are measured apart. */
static btf_status check_match(const btf_dataset_info *in, btf_rf_report *d, btf_error *err)
{
    const btf_rf_model *m = d->m;
    if (!m->map && (m->width != in->width || m->height != in->height))
        return btf__fail(err, BTF_E_ARG, "reflectance-field model of %d views x %d lights of "
                         "%dx%d texels does not describe dataset %s (%d views x %d lights of "
                         "%dx%d)", m->views.count, m->lights.count, m->width, m->height,
                         in->root, in->n_views, in->n_lights, in->width, in->height);
    d->view_of = btf__alloc((size_t)in->n_views + in->n_lights, sizeof(int), err);
    if (!d->view_of)
        return BTF_E_NOMEM;
    d->light_of = d->view_of + in->n_views;
    btf_status rc = map_dirs(&m->views, in->views, "view", in->root, d->view_of, err);
    if (rc == BTF_OK)
        rc = map_dirs(&m->lights, in->lights, "light", in->root, d->light_of, err);
    return rc;
}

typedef struct pair_job {
    const btf_dataset *ds;
    btf_rf_report *d;
    const char *dir;
    const unsigned char *want; /* [view * n_lights + light]: picture this pair */
} pair_job;

static btf_status render_flat(const btf_report_base *r, int view, int light, btf_image *out,
                              btf_error *err)
{
    const btf_rf_report *d = (const btf_rf_report *)r;
    return btf__rf_render_flat(d->m, r->in->views->dirs[view], r->in->lights->dirs[light],
                               r->in->width, r->in->height, 1, out, err);
}

/* One pair: the measured image against the flat render, by texture
 * distance and pixel by pixel; its picture when wanted. */
static btf_status measure_pair(void *user, int job, int worker, btf_error *err)
{
    (void)worker;
    pair_job *J = user;
    btf_report_base *r = &J->d->r;
    const btf_report_pair *rp = &r->pairs[job];
    btf_rf_pair *p = &J->d->pairs[job];
    p->held_out = J->d->view_of[rp->view] < 0 || J->d->light_of[rp->light] < 0;
    btf_image meas = {0}, model = {0};
    btf_status rc = btf_dataset_read(J->ds, rp->view, rp->light, &meas, err);
    if (rc == BTF_OK)
        rc = render_flat(r, rp->view, rp->light, &model, err);
    if (rc == BTF_OK) {
        btf_texture_distance_opts o = btf_texture_distance_defaults();
        o.reference_name = btf_dataset_path(J->ds, rp->view, rp->light);
        o.image_name = "the reflectance-field model's flat render";
        rc = btf_texture_distance(&meas, &model, &o, &p->d, err);
        double mean_y; /* the Table 1 pass has the data's luminance */
        btf__pixelwise_dy(&meas, &model, &p->mean_abs_dy, &mean_y);
    }
    if (rc == BTF_OK && J->want[(size_t)rp->view * r->in->n_lights + rp->light])
        rc = btf__report_picture(r, J->dir, job, rp->view, rp->light, &meas, &model, err);
    btf_image_free(&meas);
    btf_image_free(&model);
    return rc;
}

/* The pairs: all, or the spread of views x lights. */
static btf_status choose_pairs(btf_rf_report *d, btf_error *err)
{
    const btf_dataset_info *in = d->r.in;
    const btf_quality_opts *q = &d->r.o->quality;
    int *vi = btf__alloc((size_t)in->n_views + in->n_lights, sizeof(int), err);
    if (!vi)
        return BTF_E_NOMEM;
    int *li = vi + in->n_views, nv, nl;
    if (q->all) {
        for (int i = 0; i < in->n_views; i++)
            vi[i] = i;
        for (int i = 0; i < in->n_lights; i++)
            li[i] = i;
        nv = in->n_views, nl = in->n_lights;
    } else {
        nv = btf__spread_directions(in->views, q->views > 0 ? q->views : 9, vi);
        nl = btf__spread_directions(in->lights, q->lights > 0 ? q->lights : 9, li);
    }
    btf_status rc = btf__report_pairs_alloc(&d->r, nv * nl, err);
    if (rc == BTF_OK && !(d->pairs = btf__calloc((size_t)nv * nl, sizeof *d->pairs, err)))
        rc = BTF_E_NOMEM;
    for (int a = 0; rc == BTF_OK && a < nv; a++)
        for (int b = 0; b < nl; b++) {
            btf_report_pair *p = &d->r.pairs[a * nl + b];
            p->view = vi[a], p->light = li[b];
            p->d = &d->pairs[a * nl + b].d;
        }
    free(vi);
    return rc;
}

/* Means and worsts over the pairs the model was fitted to (every pair,
 * unless some directions were held out); the held-out pairs' means apart;
 * every pair ranked by its pixel-wise error. */
static void summarise_pairs(btf_rf_report *d)
{
    int n = 0;
    double held = 0.0, held_dy = 0.0;
    for (int i = 0; i < d->r.n_pairs; i++) {
        const btf_rf_pair *p = &d->pairs[i];
        d->r.pairs[i].rank = p->mean_abs_dy;
        if (p->held_out) {
            d->n_held_out++;
            held += p->d.combined;
            held_dy += p->mean_abs_dy;
            continue;
        }
        n++;
        d->mean_combined += p->d.combined;
        d->mean_spectrum += p->d.spectrum.normalised;
        d->mean_first_order += p->d.first_order.normalised;
        d->mean_structure += p->d.structure.normalised;
        d->mean_pair_dy += p->mean_abs_dy;
        if (p->d.combined > d->worst_combined)
            d->worst_combined = p->d.combined;
        if (p->mean_abs_dy > d->worst_pair_dy)
            d->worst_pair_dy = p->mean_abs_dy;
    }
    if (n > 0) {
        d->mean_combined /= n;
        d->mean_spectrum /= n;
        d->mean_first_order /= n;
        d->mean_structure /= n;
        d->mean_pair_dy /= n;
    }
    if (d->n_held_out) {
        d->mean_held_out = held / d->n_held_out;
        d->mean_held_out_dy = held_dy / d->n_held_out;
    }
}

static btf_status render_scene(btf_report_base *r, const btf_scene *sc, int side, btf_image *out,
                               btf_error *err)
{
    const btf_rf_report *d = (const btf_rf_report *)r;
    return btf__rf_render_scene(d->m, sc, side, side, r->o->threads, out, NULL, err);
}

static void summarise(const btf_report_base *r, btf_report_summary *s)
{
    const btf_rf_report *d = (const btf_rf_report *)r;
    s->mean_combined = d->mean_combined;
    s->worst_combined = d->worst_combined;
    s->mean_abs_error = d->mean_abs_error;
    s->mean_luminance = d->mean_luminance;
    s->held_out = d->n_held_out;
    s->mean_held_out = d->mean_held_out;
}

static btf_status measure(btf_report_base *r, const btf_dataset *ds, const char *dir,
                          const char *final_dir, btf_error *err);

static const btf_report_section *const rf_sections[] = {
    &btf__rf_top, &btf__rf_compression, &btf__rf_pixelwise, &btf__rf_quality, &btf__rf_preview,
};

static const btf_report_family rf_family = {
    .name = "rf",
    .style = "",
    .citation = "Meseth, Müller &amp; Klein, <i>Preserving realism in real-time rendering of "
                "bidirectional texture functions</i>, 2003",
    .measure = measure,
    .render_flat = render_flat,
    .render_scene = render_scene,
    .summarise = summarise,
    .about = &btf__rf_about,
    .sections = rf_sections,
    .n_sections = (int)(sizeof rf_sections / sizeof rf_sections[0]),
};

static btf_status measure(btf_report_base *r, const btf_dataset *ds, const char *dir,
                          const char *final_dir, btf_error *err)
{
    (void)final_dir; /* no state outlives a run: there is no sweep */
    btf_rf_report *d = (btf_rf_report *)r;
    const btf_report_opts *o = r->o;
    if (o->progress)
        o->progress(o->progress_user, 0.0, "model file and raw bytes");
    unsigned char *want = NULL;
    btf_status rc = btf_rf_model_bytes(d->m, &d->bytes, err);
    r->model_bytes = d->bytes.file;
    if (rc == BTF_OK)
        rc = btf__dataset_raw_bytes(ds, &r->raw, err);
    if (rc == BTF_OK && o->progress)
        o->progress(o->progress_user, 0.05, "pixel-wise error over every image");
    if (rc == BTF_OK)
        rc = btf__rf_error_over(ds, d->m, d->view_of, d->light_of, o->threads,
                                &d->mean_abs_error, &d->mean_luminance, err);
    if (rc == BTF_OK)
        rc = btf__report_pictures_begin(r, &want, err);
    if (rc == BTF_OK)
        rc = choose_pairs(d, err);
    if (rc == BTF_OK) {
        pair_job J = {ds, d, dir, want};
        btf_pool_progress pp = {o->progress, o->progress_user,
                                "measuring (view, light) pairs", 0.5, 0.9, 1};
        rc = btf__pool_run(r->n_pairs, o->threads, measure_pair, &J, &pp, err);
    }
    free(want);
    if (rc == BTF_OK) {
        summarise_pairs(d);
        rc = btf__report_worst(r, &rf_family, ds, dir, o->threads, err);
    }
    if (rc == BTF_OK && o->progress)
        o->progress(o->progress_user, 0.9, "the preview");
    if (rc == BTF_OK)
        rc = btf__report_preview(r, &rf_family, dir, err);
    return rc;
}

btf_status btf__rf_report_write(const btf_dataset *ds, const btf_rf_model *m, const char *dir,
                                const btf_report_opts *opts, btf_report_summary *summary,
                                btf_error *err)
{
    if (summary)
        memset(summary, 0, sizeof *summary);
    if (!ds || !m || !m->codes || !dir)
        return btf__fail(err, BTF_E_ARG, "report: no dataset, reflectance-field model or "
                         "folder given");
    if (opts && opts->sweep)
        return btf__fail(err, BTF_E_ARG, "report: the sweep varies the CAR analysis; a "
                         "reflectance-field model has no such settings");
    btf_report_opts o;
    btf_status rc = btf__report_resolve(opts, &o, err);
    if (rc)
        return rc;
    if (o.threads < 0)
        return btf__fail(err, BTF_E_ARG, "report: threads %d: expected >= 0", o.threads);
    btf_rf_report d;
    memset(&d, 0, sizeof d);
    d.m = m;
    btf__report_begin(&d.r, ds, &o);
    rc = check_match(d.r.in, &d, err);
    if (rc == BTF_OK)
        rc = btf__report_run(&d.r, &rf_family, ds, dir, summary, err);
    free(d.pairs);
    free(d.view_of);
    btf__report_base_free(&d.r);
    return rc;
}
