/*
 * report_run.c — the steps every family's report takes (report_base.h,
 * docs/report.md): the options, the start, which pairs get pictures, the
 * worst pairs and their pictures, the preview sphere, and the run itself:
 * everything is measured and written into a temporary folder that moves
 * into place as a whole, then the summary.
 */
#include "core/core.h"
#include "report/report_base.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

btf_report_opts btf_report_defaults(void)
{
    btf_report_opts o;
    memset(&o, 0, sizeof o);
    o.struct_size = sizeof o;
    o.quality = btf_quality_defaults();
    o.sphere_light = (btf_dir){45.0, 135.0};
    o.sphere_light_set = 1;
    o.sphere_size = 384;
    o.worst = 6;
    o.pca = btf_pca_defaults();
    o.jpeg_quality = 90;
    o.sweep_opts = btf_sweep_defaults();
    return o;
}

btf_status btf__report_resolve(const btf_report_opts *in, btf_report_opts *o, btf_error *err)
{
    btf_report_opts d = btf_report_defaults();
    if (btf__opts_take(o, sizeof *o, in, &d, "btf_report_write", err))
        return BTF_E_ARG;
    if (!o->sphere_light_set && o->sphere_light.theta == 0.0 && o->sphere_light.phi == 0.0)
        o->sphere_light = d.sphere_light;
    if (o->sphere_size == 0)
        o->sphere_size = d.sphere_size;
    if (o->worst == 0)
        o->worst = d.worst;
    if (o->sphere_size < 16 || o->sphere_size > 4096)
        return btf__fail(err, BTF_E_ARG, "report: preview size %d: expected 16..4096",
                         o->sphere_size);
    if (o->worst < 0 || o->worst > 100)
        return btf__fail(err, BTF_E_ARG, "report: %d worst pairs: expected 0..100", o->worst);
    return BTF_OK;
}

void btf__report_begin(btf_report_base *r, const btf_dataset *ds, const btf_report_opts *o)
{
    r->t0 = btf__now();
    r->in = btf_dataset_get_info(ds);
    r->o = o;
    r->dataset_name = o->dataset_name ? o->dataset_name : r->in->root;
    r->model_name = o->model_name ? o->model_name : "model";
    time_t now = time(NULL);
    struct tm tm;
    gmtime_r(&now, &tm);
    strftime(r->date, sizeof r->date, "%Y-%m-%d %H:%M UTC", &tm);
}

btf_status btf__report_pictures_begin(btf_report_base *r, unsigned char **want, btf_error *err)
{
    const btf_dataset_info *in = r->in;
    size_t every = (size_t)in->n_views * in->n_lights;
    *want = btf__calloc(every, 1, err);
    r->pictured = *want ? btf__calloc(every, 1, err) : NULL;
    int *vi = r->pictured ? btf__alloc((size_t)in->n_views + in->n_lights, sizeof(int), err) : NULL;
    if (!vi) {
        free(*want);
        *want = NULL;
        return BTF_E_NOMEM;
    }
    int *li = vi + in->n_views;
    const btf_quality_opts *q = &r->o->quality;
    btf_quality_opts def = btf_quality_defaults();
    int nv = btf__spread_directions(in->views, q->all ? def.views : (q->views > 0 ? q->views : 9), vi);
    int nl = btf__spread_directions(in->lights,
                                    q->all ? def.lights : (q->lights > 0 ? q->lights : 9), li);
    for (int a = 0; a < nv; a++)
        for (int b = 0; b < nl; b++)
            (*want)[(size_t)vi[a] * in->n_lights + li[b]] = 1;
    free(vi);
    return BTF_OK;
}

btf_status btf__report_pairs_alloc(btf_report_base *r, int n, btf_error *err)
{
    r->pairs = btf__calloc(n > 0 ? (size_t)n : 1, sizeof *r->pairs, err);
    if (!r->pairs)
        return BTF_E_NOMEM;
    r->n_pairs = n;
    return BTF_OK;
}

typedef struct ranked {
    double rank;
    int pair;
} ranked;

static int worse_first(const void *a, const void *b)
{
    const ranked *x = a, *y = b;
    if (x->rank != y->rank)
        return x->rank < y->rank ? 1 : -1;
    return x->pair - y->pair;
}

typedef struct worst_job {
    btf_report_base *r;
    const btf_report_family *f;
    const btf_dataset *ds;
    const char *dir;
} worst_job;

/* A worst pair's picture, where the measurement did not keep one: the
 * family's flat render gives the same pixels again. */
static btf_status picture_worst(void *user, int job, int worker, btf_error *err)
{
    (void)worker;
    worst_job *J = user;
    int i = J->r->worst[job];
    if (J->r->pictured[i])
        return BTF_OK;
    const btf_report_pair *p = &J->r->pairs[i];
    btf_image meas = {0}, model = {0};
    btf_status rc = btf_dataset_read(J->ds, p->view, p->light, &meas, err);
    if (rc == BTF_OK)
        rc = J->f->render_flat(J->r, p->view, p->light, &model, err);
    if (rc == BTF_OK)
        rc = btf__report_picture(J->r, J->dir, i, p->view, p->light, &meas, &model, err);
    btf_image_free(&meas);
    btf_image_free(&model);
    return rc;
}

btf_status btf__report_worst(btf_report_base *r, const btf_report_family *f,
                             const btf_dataset *ds, const char *dir, int threads,
                             btf_error *err)
{
    int n = r->n_pairs;
    int *order = btf__alloc((size_t)n, sizeof(int), err);
    ranked *k = btf__alloc((size_t)n, sizeof(ranked), err);
    if (!order || !k) {
        free(order);
        free(k);
        return BTF_E_NOMEM;
    }
    for (int i = 0; i < n; i++)
        k[i] = (ranked){r->pairs[i].rank, i};
    qsort(k, (size_t)n, sizeof *k, worse_first);
    for (int i = 0; i < n; i++)
        order[i] = k[i].pair;
    free(k);
    r->worst = order;
    r->n_worst = r->o->worst < n ? r->o->worst : n;
    worst_job J = {r, f, ds, dir};
    return btf__pool_run(r->n_worst, threads, picture_worst, &J, NULL, err);
}

btf_status btf__report_preview(btf_report_base *r, const btf_report_family *f, const char *dir,
                               btf_error *err)
{
    btf_scene sc;
    int side = r->o->sphere_size;
    btf_status rc = btf_scene_sphere(r->o->sphere_light, side / 2.4, &sc, err);
    if (rc)
        return rc;
    btf_image img = {0};
    double t0 = btf__now();
    rc = f->render_scene(r, &sc, side, &img, err);
    r->sphere_s = btf__now() - t0;
    char path[4096];
    if (rc == BTF_OK)
        rc = btf__path_join(path, sizeof path, dir, "sphere.png", err);
    if (rc == BTF_OK)
        rc = btf_image_write_png(path, &img, err);
    btf_image_free(&img);
    btf_scene_free(&sc);
    return rc;
}

/* The sections' files, the page and report.json into dir. */
static btf_status write_all(const btf_report_base *r, const btf_report_family *f,
                            const char *dir, btf_error *err)
{
    btf_status rc = BTF_OK;
    for (int i = 0; rc == BTF_OK && i < f->n_sections; i++)
        if (f->sections[i]->files)
            rc = f->sections[i]->files(r, dir, err);
    if (rc == BTF_OK)
        rc = btf__report_page(r, f, dir, err);
    if (rc == BTF_OK)
        rc = btf__report_json(r, f, dir, err);
    return rc;
}

btf_status btf__report_run(btf_report_base *r, const btf_report_family *f,
                           const btf_dataset *ds, const char *dir, btf_report_summary *summary,
                           btf_error *err)
{
    btf_output_dir *od = NULL;
    btf_status rc = btf_output_dir_begin(dir, &od, err);
    if (rc)
        return rc;
    const char *tmp = btf_output_dir_path(od);
    rc = f->measure(r, ds, tmp, dir, err);
    r->seconds = btf__now() - r->t0;
    if (rc == BTF_OK)
        rc = write_all(r, f, tmp, err);
    if (rc == BTF_OK)
        rc = btf_output_dir_commit(od, err);
    else
        btf_output_dir_fail(od, err);
    if (rc == BTF_OK && summary) {
        summary->model_bytes = r->model_bytes;
        summary->raw_bytes = r->raw.raw;
        summary->ratio = btf__report_ratio(r->raw.raw, r->model_bytes);
        summary->pairs = r->n_pairs;
        f->summarise(r, summary);
        summary->seconds = btf__now() - r->t0;
    }
    if (r->o->progress)
        r->o->progress(r->o->progress_user, 1.0, "done");
    return rc;
}

void btf__report_base_free(btf_report_base *r)
{
    BTF_FREE_ALL(r->pairs, r->pictured, r->worst);
    r->pairs = NULL;
    r->pictured = NULL;
    r->worst = NULL;
}
