/*
 * car_report.c — btf_report_write (docs/report.md): measures
 * what a CAR model costs and how close it comes, then hands the numbers to
 * the shared run (report_run.c) and the family's sections
 * (car_report_page.c). The steps: the model file by part and the two plain
 * contrasts (per-view PCA, JPEG of the subspace images); every sampled
 * (view, light) pair against the model's flat render (pictures of the
 * sampled pairs and of the worst); the preview sphere; the sweep of
 * settings when asked. Everything but the sweep's state is written into a
 * temporary folder that moves into place as a whole.
 */
#include "core/core.h"
#include "report/car_report_data.h"
#include "report/report.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* The arguments given (given: none missing, else "report: no MISSING
 * given"), the shared options, then the CAR report's own: the JPEG
 * contrast's quality and the threads of the measurements it runs. */
static btf_status resolve(int given, const char *missing, const btf_report_opts *in,
                          btf_report_opts *o, btf_error *err)
{
    if (!given)
        return btf__fail(err, BTF_E_ARG, "report: no %s given", missing);
    btf_status rc = btf__report_resolve(in, o, err);
    if (rc)
        return rc;
    if (o->jpeg_quality == 0)
        o->jpeg_quality = btf_report_defaults().jpeg_quality;
    if (o->jpeg_quality < 1 || o->jpeg_quality > 100)
        return btf__fail(err, BTF_E_ARG, "report: JPEG quality %d: expected 1..100",
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
    btf_report_base *r;
    const char *dir;
    const unsigned char *want; /* [view * n_lights + light]: picture this pair */
} pair_ctx;

static btf_status on_pair(void *user, int pair, int view, int light, const btf_image *meas,
                          const btf_image *model, btf_error *err)
{
    pair_ctx *c = user;
    if (!c->want[(size_t)view * c->r->in->n_lights + light])
        return BTF_OK;
    return btf__report_picture(c->r, c->dir, pair, view, light, meas, model, err);
}

/* The renders' options: the quality's seed and relief, the report's threads. */
static btf_render_opts render_opts(const btf_report_base *r, int width, int height)
{
    btf_render_opts ro = btf_render_defaults();
    ro.width = width;
    ro.height = height;
    ro.seed = r->o->quality.seed;
    ro.relief = r->o->quality.relief;
    ro.threads = r->o->threads;
    return ro;
}

/* btf_render_flat gives the pixels the measurement compared. */
static btf_status render_flat(const btf_report_base *r, int view, int light, btf_image *out,
                              btf_error *err)
{
    const btf_car_report *d = (const btf_car_report *)r;
    btf_render_opts ro = render_opts(r, r->in->width, r->in->height);
    return btf_render_flat(d->m, r->in->views->dirs[view], r->in->lights->dirs[light], &ro, out,
                           NULL, err);
}

static btf_status render_scene(btf_report_base *r, const btf_scene *sc, int side, btf_image *out,
                               btf_error *err)
{
    btf_car_report *d = (btf_car_report *)r;
    btf_render_opts ro = render_opts(r, side, side);
    return btf_render_scene(d->m, sc, &ro, out, &d->sphere_info, err);
}

static btf_status run_sweep(const btf_dataset *ds, const char *final_dir,
                            const btf_report_opts *o, step_progress *sp, btf_sweep *out,
                            btf_error *err)
{
    char state[4096];
    btf_status rc = btf__path_join(state, sizeof state, final_dir, "sweep", err);
    if (rc)
        return rc;
    /* The state folder lives in the report's folder itself, not in the
     * temporary one: what an interrupted run finished must survive it. */
    if (mkdir(final_dir, 0777) != 0 && errno != EEXIST)
        return btf__fail(err, BTF_E_IO, "%s: cannot create the report folder", final_dir);
    btf_sweep_opts so = o->sweep_opts;
    so.state_dir = state;
    so.quality = o->quality;
    so.quality.on_pair = NULL;
    so.quality.progress = NULL;
    so.threads = o->threads;
    so.progress = step_report;
    so.progress_user = sp;
    return btf__sweep_run(ds, &so, out, err);
}

/* The measured pairs as the shared sections list them, ranked by the
 * combined distance. */
static btf_status list_pairs(btf_car_report *d, btf_error *err)
{
    btf_status rc = btf__report_pairs_alloc(&d->r, d->q.n_pairs, err);
    for (int i = 0; rc == BTF_OK && i < d->q.n_pairs; i++) {
        const btf_pair_quality *p = &d->q.pairs[i];
        d->r.pairs[i] = (btf_report_pair){p->view, p->light, &p->d, p->d.combined};
    }
    return rc;
}

static btf_status measure(btf_report_base *r, const btf_dataset *ds, const char *dir,
                          const char *final_dir, btf_error *err);

static void summarise(const btf_report_base *r, btf_report_summary *s)
{
    const btf_car_report *d = (const btf_car_report *)r;
    s->mean_combined = d->q.mean_combined;
    s->held_out = d->q.n_held_out;
    s->mean_held_out = d->q.mean_held_out;
    s->worst_combined = d->q.worst_combined;
    s->sweep_points = d->sweep.n_points;
    s->sweep_resumed = d->sweep.resumed;
}

static const btf_report_section *const car_sections[] = {
    &btf__car_top, &btf__car_compression, &btf__car_quality, &btf__car_preview, &btf__car_trade,
};

static const btf_report_family car_family = {
    .name = NULL,
    .style = "tr.def td{background:#fff7d6}tr.front td:first-child{font-weight:bold}",
    .citation = "Haindl &amp; Filip, <i>Extreme compression and modeling of bidirectional "
                "texture function</i>, TPAMI 2007",
    .measure = measure,
    .render_flat = render_flat,
    .render_scene = render_scene,
    .summarise = summarise,
    .about = &btf__car_about,
    .sections = car_sections,
    .n_sections = (int)(sizeof car_sections / sizeof car_sections[0]),
};

static btf_status measure(btf_report_base *r, const btf_dataset *ds, const char *dir,
                          const char *final_dir, btf_error *err)
{
    btf_car_report *d = (btf_car_report *)r;
    const btf_report_opts *o = r->o;
    double span = o->sweep ? 0.45 : 1.0; /* the sweep takes the rest */
    step_progress sp;
    step(&sp, o, 0.0, 0.02 * span);
    step_report(&sp, 0.0, "model file by part");
    btf_status rc = btf__model_byte_breakdown(d->m, &d->bytes, err);
    r->model_bytes = d->bytes.total;
    if (rc == BTF_OK)
        rc = btf__dataset_raw_bytes(ds, &r->raw, err);
    if (rc == BTF_OK)
        rc = btf__jpeg_subspace_contrast(ds, d->m, o->jpeg_quality, &d->jpeg, err);
    step(&sp, o, 0.02 * span, 0.45 * span);
    btf_pca_opts pca = o->pca;
    pca.progress = step_report;
    pca.progress_user = &sp;
    /* Per-view PCA compresses every light of a view: a sparse set has no
     * such images (the page says so; d->pca stays zero). */
    if (rc == BTF_OK && r->in->n_pairs == r->in->n_views * r->in->n_lights)
        rc = btf__pca_contrast(ds, &pca, &d->pca, err);
    unsigned char *want = NULL;
    if (rc == BTF_OK)
        rc = btf__report_pictures_begin(r, &want, err);
    step(&sp, o, 0.45 * span, 0.9 * span);
    btf_quality_opts q = o->quality;
    pair_ctx pc = {r, dir, want};
    q.progress = step_report;
    q.progress_user = &sp;
    q.on_pair = on_pair;
    q.on_pair_user = &pc;
    if (rc == BTF_OK)
        rc = btf__quality_measure(ds, d->m, &q, &d->q, err);
    free(want);
    if (rc == BTF_OK)
        rc = list_pairs(d, err);
    step(&sp, o, 0.9 * span, span);
    step_report(&sp, 0.0, "the worst pairs and the preview");
    /* one pair at a time: each render runs on every thread */
    if (rc == BTF_OK)
        rc = btf__report_worst(r, &car_family, ds, dir, 1, err);
    if (rc == BTF_OK)
        rc = btf__report_preview(r, &car_family, dir, err);
    step(&sp, o, span, 0.99);
    if (rc == BTF_OK && o->sweep) {
        rc = run_sweep(ds, final_dir, o, &sp, &d->sweep, err);
        d->have_sweep = rc == BTF_OK;
    }
    return rc;
}

btf_status btf_report_write(const btf_dataset *ds, const btf_model *m, const char *dir,
                            const btf_report_opts *opts, btf_report_summary *summary,
                            btf_error *err)
{
    btf_report_opts o;
    if (summary)
        memset(summary, 0, sizeof *summary);
    btf_status rc = resolve(ds && m && dir, "dataset, model or folder", opts, &o, err);
    if (rc == BTF_OK && o.sweep && o.sweep_opts.share_count > 0)
        rc = btf__fail(err, BTF_E_ARG, "report: a share of the sweep (%d of %d) writes its "
                       "points only (btf_report_sweep_points); the page comes from the merge",
                       o.sweep_opts.share_index, o.sweep_opts.share_count);
    if (rc)
        return rc;
    btf_car_report d;
    memset(&d, 0, sizeof d);
    d.m = m;
    btf__report_begin(&d.r, ds, &o);
    rc = btf__report_run(&d.r, &car_family, ds, dir, summary, err);
    btf__pca_result_free(&d.pca);
    btf__quality_free(&d.q);
    btf_sweep_free(&d.sweep);
    btf__report_base_free(&d.r);
    return rc;
}

btf_status btf_report_sweep_points(const btf_dataset *ds, const char *dir,
                                   const btf_report_opts *opts, btf_sweep *out,
                                   btf_error *err)
{
    if (out)
        memset(out, 0, sizeof *out);
    /* the options exactly as btf_report_write's sweep sets them (run_sweep),
     * so that the points carry the same fingerprint and the merge resumes
     * them */
    btf_report_opts o;
    btf_sweep s = {0};
    step_progress sp;
    btf_status rc = resolve(ds && dir && out, "dataset, folder or output", opts, &o, err);
    if (rc == BTF_OK) {
        step(&sp, &o, 0.0, 1.0);
        rc = run_sweep(ds, dir, &o, &sp, &s, err);
    }
    if (rc == BTF_OK)
        *out = s;
    return rc;
}
