/*
 * report_write.c — btf_report_write (issue 18, docs/report.md): measures
 * what a model costs and how close it comes, then hands the numbers to the
 * page and JSON writers. The steps: the model file by part and the two
 * plain contrasts (per-view PCA, JPEG of the subspace images); every
 * sampled (view, light) pair against the model's flat render (pictures of
 * the sampled pairs and of the worst); the preview sphere; the sweep of
 * settings when asked. Everything but the sweep's state is written into a
 * temporary folder that moves into place as a whole.
 */
#include "core/core.h"
#include "report/report.h"
#include "report/report_data.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

btf_report_opts btf_report_defaults(void)
{
    btf_report_opts o;
    memset(&o, 0, sizeof o);
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

static btf_status resolve(const btf_report_opts *in, btf_report_opts *o, btf_error *err)
{
    btf_report_opts d = btf_report_defaults();
    *o = in ? *in : d;
    if (!o->sphere_light_set && o->sphere_light.theta == 0.0 && o->sphere_light.phi == 0.0)
        o->sphere_light = d.sphere_light;
    if (o->sphere_size == 0)
        o->sphere_size = d.sphere_size;
    if (o->worst == 0)
        o->worst = d.worst;
    if (o->jpeg_quality == 0)
        o->jpeg_quality = d.jpeg_quality;
    if (o->sphere_size < 16 || o->sphere_size > 4096)
        return btf_fail(err, BTF_E_ARG, "report: preview size %d: expected 16..4096",
                        o->sphere_size);
    if (o->worst < 0 || o->worst > 100)
        return btf_fail(err, BTF_E_ARG, "report: %d worst pairs: expected 0..100", o->worst);
    if (o->jpeg_quality < 1 || o->jpeg_quality > 100)
        return btf_fail(err, BTF_E_ARG, "report: JPEG quality %d: expected 1..100",
                        o->jpeg_quality);
    o->quality.threads = o->threads;
    o->pca.threads = o->threads;
    return BTF_OK;
}

/* Progress of one step mapped into [from, to] of the whole report. */
typedef struct step_progress {
    btf_progress_fn fn;
    void *user;
    double from, to;
} step_progress;

static void step_report(void *user, double fraction, const char *what)
{
    step_progress *s = user;
    if (s->fn)
        s->fn(s->user, s->from + (s->to - s->from) * fraction, what);
}

static void step(step_progress *s, const btf_report_opts *o, double from, double to)
{
    s->fn = o->progress;
    s->user = o->progress_user;
    s->from = from;
    s->to = to;
}

typedef struct pair_ctx {
    btf_report_data *d;
    const char *dir;
    const unsigned char *want; /* [view * n_lights + light]: picture this pair */
} pair_ctx;

static btf_status on_pair(void *user, int pair, int view, int light, const btf_image *meas,
                          const btf_image *model, btf_error *err)
{
    pair_ctx *c = user;
    if (!c->want[(size_t)view * c->d->in->n_lights + light])
        return BTF_OK;
    char name[64];
    btf_report_pair_file(c->d, pair, name, sizeof name);
    c->d->pictured[pair] = 1;
    return btf_report_write_pair(c->dir, name, meas, model, err);
}

/* Which pairs get pictures: all measured ones for the spread; with every
 * pair measured, those of the default spread (the worst come later). */
static btf_status pictured_pairs(const btf_report_data *d, unsigned char **want, btf_error *err)
{
    const btf_dataset_info *in = d->in;
    *want = btf_calloc((size_t)in->n_views * in->n_lights, 1, err);
    int *vi = btf_alloc((size_t)in->n_views + in->n_lights, sizeof(int), err);
    if (!*want || !vi) {
        free(*want);
        free(vi);
        *want = NULL;
        return BTF_E_NOMEM;
    }
    int *li = vi + in->n_views;
    btf_quality_opts q = d->o->quality, def = btf_quality_defaults();
    int nv = btf_spread_directions(in->views, q.all ? def.views : (q.views ? q.views : 9), vi);
    int nl = btf_spread_directions(in->lights, q.all ? def.lights : (q.lights ? q.lights : 9), li);
    for (int a = 0; a < nv; a++)
        for (int b = 0; b < nl; b++)
            (*want)[(size_t)vi[a] * in->n_lights + li[b]] = 1;
    free(vi);
    return BTF_OK;
}

typedef struct ranked {
    double combined;
    int pair;
} ranked;

static int worse_first(const void *a, const void *b)
{
    const ranked *x = a, *y = b;
    if (x->combined != y->combined)
        return x->combined < y->combined ? 1 : -1;
    return x->pair - y->pair;
}

/* The worst pairs, worst first, each with its picture (rendered again
 * when the measurement did not keep it: btf_render_flat gives the same
 * pixels). */
static btf_status worst_pairs(btf_report_data *d, const btf_dataset *ds, const char *dir,
                              btf_error *err)
{
    int n = d->q.n_pairs;
    int *order = btf_alloc((size_t)n, sizeof(int), err);
    ranked *r = btf_alloc((size_t)n, sizeof(ranked), err);
    if (!order || !r) {
        free(order);
        free(r);
        return BTF_E_NOMEM;
    }
    for (int i = 0; i < n; i++)
        r[i] = (ranked){d->q.pairs[i].d.combined, i};
    qsort(r, (size_t)n, sizeof *r, worse_first);
    for (int i = 0; i < n; i++)
        order[i] = r[i].pair;
    free(r);
    d->n_worst = d->o->worst < n ? d->o->worst : n;
    d->worst = order;
    for (int k = 0; k < d->n_worst; k++) {
        int i = order[k];
        if (d->pictured[i])
            continue;
        const btf_pair_quality *p = &d->q.pairs[i];
        btf_render_opts ro = btf_render_defaults();
        ro.width = d->in->width;
        ro.height = d->in->height;
        ro.seed = d->o->quality.seed;
        ro.relief = d->o->quality.relief;
        ro.threads = d->o->threads;
        btf_image meas = {0}, model = {0};
        btf_status rc = btf_dataset_read(ds, p->view, p->light, &meas, err);
        if (rc == BTF_OK)
            rc = btf_render_flat(d->m, d->in->views->dirs[p->view], d->in->lights->dirs[p->light],
                                 &ro, &model, NULL, err);
        char name[64];
        btf_report_pair_file(d, i, name, sizeof name);
        if (rc == BTF_OK)
            rc = btf_report_write_pair(dir, name, &meas, &model, err);
        btf_image_free(&meas);
        btf_image_free(&model);
        if (rc)
            return rc;
        d->pictured[i] = 1;
    }
    return BTF_OK;
}

/* The preview: the material on a sphere under the chosen light. A texel
 * per pixel at the sphere's centre: the surface shows about side / 2.4
 * texels across its radius. */
static btf_status preview(btf_report_data *d, const char *dir, btf_error *err)
{
    btf_scene sc;
    int side = d->o->sphere_size;
    btf_status rc = btf_scene_sphere(d->o->sphere_light, side / 2.4, &sc, err);
    if (rc)
        return rc;
    btf_render_opts ro = btf_render_defaults();
    ro.width = ro.height = side;
    ro.seed = d->o->quality.seed;
    ro.relief = d->o->quality.relief;
    ro.threads = d->o->threads;
    btf_image img = {0};
    double t0 = btf_now();
    rc = btf_render_scene(d->m, &sc, &ro, &img, &d->sphere_info, err);
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

static btf_status run_sweep(btf_report_data *d, const btf_dataset *ds, const char *final_dir,
                            btf_report_opts *o, step_progress *sp, btf_error *err)
{
    char state[4096];
    btf_status rc = btf_path_join(state, sizeof state, final_dir, "sweep", err);
    if (rc)
        return rc;
    /* The state folder lives in the report's folder itself, not in the
     * temporary one: what an interrupted run finished must survive it. */
    if (mkdir(final_dir, 0777) != 0 && errno != EEXIST)
        return btf_fail(err, BTF_E_IO, "%s: cannot create the report folder", final_dir);
    btf_sweep_opts so = o->sweep_opts;
    so.state_dir = state;
    so.quality = o->quality;
    so.quality.on_pair = NULL;
    so.quality.progress = NULL;
    so.threads = o->threads;
    so.progress = step_report;
    so.progress_user = sp;
    rc = btf_sweep_run(ds, &so, &d->sweep, err);
    d->have_sweep = rc == BTF_OK;
    return rc;
}

static void free_data(btf_report_data *d)
{
    btf_pca_result_free(&d->pca);
    btf_quality_free(&d->q);
    btf_sweep_free(&d->sweep);
    free(d->pictured);
    free(d->worst);
}

static btf_status measure_all(btf_report_data *d, const btf_dataset *ds, const char *dir,
                              const char *final_dir, btf_report_opts *o, btf_error *err)
{
    double span = o->sweep ? 0.45 : 1.0; /* the sweep takes the rest */
    step_progress sp;
    step(&sp, o, 0.0, 0.02 * span);
    step_report(&sp, 0.0, "model file by part");
    btf_status rc = btf_model_byte_breakdown(d->m, &d->bytes, err);
    if (rc == BTF_OK)
        rc = btf_dataset_raw_bytes(ds, &d->raw, err);
    if (rc == BTF_OK)
        rc = btf_jpeg_subspace_contrast(ds, d->m, o->jpeg_quality, &d->jpeg, err);
    step(&sp, o, 0.02 * span, 0.45 * span);
    btf_pca_opts pca = o->pca;
    pca.progress = step_report;
    pca.progress_user = &sp;
    /* Per-view PCA compresses every light of a view: a sparse set has no
     * such images (the page says so; d->pca stays zero). */
    if (rc == BTF_OK && d->in->n_pairs == d->in->n_views * d->in->n_lights)
        rc = btf_pca_contrast(ds, &pca, &d->pca, err);
    unsigned char *want = NULL;
    if (rc == BTF_OK)
        rc = pictured_pairs(d, &want, err);
    step(&sp, o, 0.45 * span, 0.9 * span);
    btf_quality_opts q = o->quality;
    pair_ctx pc = {d, dir, want};
    q.progress = step_report;
    q.progress_user = &sp;
    q.on_pair = on_pair;
    q.on_pair_user = &pc;
    /* pictured[] is indexed by pair, known only once the pairs are chosen:
     * room for every pair of the dataset. */
    if (rc == BTF_OK &&
        !(d->pictured = btf_calloc((size_t)d->in->n_views * d->in->n_lights, 1, err)))
        rc = BTF_E_NOMEM;
    if (rc == BTF_OK)
        rc = btf_quality_measure(ds, d->m, &q, &d->q, err);
    free(want);
    step(&sp, o, 0.9 * span, span);
    step_report(&sp, 0.0, "the worst pairs and the preview");
    if (rc == BTF_OK)
        rc = worst_pairs(d, ds, dir, err);
    if (rc == BTF_OK)
        rc = preview(d, dir, err);
    step(&sp, o, span, 0.99);
    if (rc == BTF_OK && o->sweep)
        rc = run_sweep(d, ds, final_dir, o, &sp, err);
    return rc;
}

btf_status btf_report_write(const btf_dataset *ds, const btf_model *m, const char *dir,
                            const btf_report_opts *opts, btf_report_summary *summary,
                            btf_error *err)
{
    if (summary)
        memset(summary, 0, sizeof *summary);
    if (!ds || !m || !dir)
        return btf_fail(err, BTF_E_ARG, "report: no dataset, model or folder given");
    btf_report_opts o;
    btf_status rc = resolve(opts, &o, err);
    if (rc)
        return rc;
    if (o.sweep && o.sweep_opts.share_count > 0)
        return btf_fail(err, BTF_E_ARG, "report: a share of the sweep (%d of %d) writes its "
                        "points only (btf_report_sweep_points); the page comes from the merge",
                        o.sweep_opts.share_index, o.sweep_opts.share_count);
    double t0 = btf_now();
    btf_report_data d;
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
    btf_output_dir *od = NULL;
    if ((rc = btf_output_dir_begin(dir, &od, err)))
        return rc;
    const char *tmp = btf_output_dir_path(od);
    rc = measure_all(&d, ds, tmp, dir, &o, err);
    d.seconds = btf_now() - t0;
    if (rc == BTF_OK)
        rc = btf_report_html(&d, tmp, err);
    if (rc == BTF_OK)
        rc = btf_report_json(&d, tmp, err);
    if (rc == BTF_OK)
        rc = btf_output_dir_commit(od, err);
    else
        btf_output_dir_fail(od, err);
    if (rc == BTF_OK && summary) {
        summary->model_bytes = d.bytes.total;
        summary->raw_bytes = d.raw.raw;
        summary->ratio = d.bytes.total ? (double)d.raw.raw / (double)d.bytes.total : 0.0;
        summary->pairs = d.q.n_pairs;
        summary->mean_combined = d.q.mean_combined;
        summary->held_out = d.q.n_held_out;
        summary->mean_held_out = d.q.mean_held_out;
        summary->worst_combined = d.q.worst_combined;
        summary->sweep_points = d.sweep.n_points;
        summary->sweep_resumed = d.sweep.resumed;
        summary->seconds = btf_now() - t0;
    }
    if (o.progress)
        o.progress(o.progress_user, 1.0, "done");
    free_data(&d);
    return rc;
}

btf_status btf_report_sweep_points(const btf_dataset *ds, const char *dir,
                                   const btf_report_opts *opts, btf_sweep *out,
                                   btf_error *err)
{
    if (out)
        memset(out, 0, sizeof *out);
    if (!ds || !dir || !out)
        return btf_fail(err, BTF_E_ARG, "report: no dataset, folder or output given");
    btf_report_opts o;
    btf_status rc = resolve(opts, &o, err);
    if (rc)
        return rc;
    /* the options exactly as btf_report_write's sweep sets them (run_sweep),
     * so that the points carry the same fingerprint and the merge resumes
     * them */
    btf_report_data d;
    memset(&d, 0, sizeof d);
    step_progress sp;
    step(&sp, &o, 0.0, 1.0);
    rc = run_sweep(&d, ds, dir, &o, &sp, err);
    if (rc == BTF_OK)
        *out = d.sweep;
    return rc;
}
