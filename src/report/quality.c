/*
 * quality.c — how close a model comes to the measurement it was analysed
 * from, (view, light) pair by pair (docs/report.md, "Quality per
 * direction"). The paper judges its results by eye (Haindl & Filip 2007,
 * section IV); here each measured image is compared with the model's flat
 * render of the same pair (paper section III: the nine-image interpolation,
 * which at a measured pair selects that pair's subspace image alone, plus
 * parallax and bump mapping) by the texture distances of src/measure/, which
 * need no pixel correspondence: a CAR synthesis is a new sample of the
 * material, not a copy of the photograph.
 */
#include "core/core.h"
#include "render/shade.h"
#include "report/measures.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

btf_quality_opts btf_quality_defaults(void)
{
    btf_quality_opts o;
    memset(&o, 0, sizeof o);
    o.struct_size = sizeof o;
    o.views = 9;
    o.lights = 9;
    o.relief = 1.0;
    return o;
}

int btf__spread_directions(const btf_dirset *set, int n, int *idx)
{
    int count = set ? set->count : 0;
    if (count <= 0 || !idx)
        return 0;
    if (n < 1)
        n = 1;
    if (n > count)
        n = count;
    /* Evenly strided through the set's order (ring by ring, theta
     * ascending, phi ascending in a ring), from its first direction: every
     * ring gets its share by the number of directions it holds, and the
     * azimuths within a ring walk round as the stride crosses it. (Farthest-
     * point sampling, tried first, takes the pole and the outermost ring
     * and leaves the middle rings out.) */
    for (int i = 0; i < n; i++)
        idx[i] = (int)((long long)i * count / n);
    return n;
}

/* Whether the model's direction sets are the dataset's (within the
 * file-name tolerance). */
static int same_sets(const btf_dataset_info *in, const btf_model *m)
{
    if (m->views.count != in->n_views || m->lights.count != in->n_lights)
        return 0;
    for (int i = 0; i < in->n_views; i++)
        if (btf_dir_angle(m->views.dirs[i], in->views->dirs[i]) > BTF_DIR_NAME_TOLERANCE)
            return 0;
    for (int i = 0; i < in->n_lights; i++)
        if (btf_dir_angle(m->lights.dirs[i], in->lights->dirs[i]) > BTF_DIR_NAME_TOLERANCE)
            return 0;
    return 1;
}

/* The model's subspace for the dataset's pair (view, light): its index
 * entry where the model measured the pair (the same directions within the
 * file-name tolerance), else -1: a pair the model did not measure (held
 * out of its analysis, or of a sparse set), which its render interpolates. */
static int model_subspace(const btf_dataset_info *in, const btf_model *m, int same, int view,
                          int light)
{
    int mv = view, ml = light;
    if (!same) {
        mv = btf_dirset_find(&m->views, in->views->dirs[view], BTF_DIR_NAME_TOLERANCE);
        ml = btf_dirset_find(&m->lights, in->lights->dirs[light], BTF_DIR_NAME_TOLERANCE);
        if (mv < 0 || ml < 0)
            return -1;
    }
    int k = m->index[(size_t)mv * m->lights.count + ml];
    return k == BTF_PAIR_NONE ? -1 : k;
}

/* The model must describe this dataset: the same direction sets, or
 * (a model of some of its pairs: leave-one-out) at least one pair the
 * dataset holds measured by the model. */
static btf_status check_match(const btf_dataset *ds, const btf_dataset_info *in,
                              const btf_model *m, btf_error *err)
{
    if (!m->index)
        return btf__fail(err, BTF_E_ARG, "the model has no index table: it does not describe "
                         "dataset %s", in->root);
    int same = same_sets(in, m);
    for (int v = 0; v < in->n_views; v++)
        for (int l = 0; l < in->n_lights; l++)
            if (btf_dataset_has(ds, v, l) && model_subspace(in, m, same, v, l) >= 0)
                return BTF_OK;
    return btf__fail(err, BTF_E_ARG,
                     "model of %d views x %d lights does not describe dataset %s "
                     "(%d views x %d lights): none of the dataset's pairs is one the model "
                     "measured", m->views.count, m->lights.count, in->root, in->n_views,
                     in->n_lights);
}

typedef struct measure_job {
    const btf_dataset *ds;
    const btf_dataset_info *in;
    const btf_model *m;
    const btf_render_material *rm;
    const btf_quality_opts *o;
    btf_quality *q;
} measure_job;

static double luminance(const float *p)
{
    return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
}

void btf__pixelwise_dy(const btf_image *meas, const btf_image *model, double *mean_abs_dy,
                       double *mean_y)
{
    size_t n = (size_t)meas->width * meas->height;
    double s = 0.0, y = 0.0;
    *mean_abs_dy = *mean_y = 0.0;
    if (meas->channels != 3 || model->channels != 3 || model->width != meas->width ||
        model->height != meas->height || n == 0)
        return;
    for (size_t k = 0; k < n; k++) {
        float m[3];
        for (int c = 0; c < 3; c++)
            m[c] = isfinite(meas->data[3 * k + c]) ? meas->data[3 * k + c] : 0.0f;
        double a = luminance(m), b = luminance(model->data + 3 * k);
        s += fabs(a - b);
        y += a;
    }
    *mean_abs_dy = s / (double)n;
    *mean_y = y / (double)n;
}

/* One pair: read the measured image, shade the flat patch as btf_render_flat
 * does (a unit white directional light, black background), measure. */
static btf_status measure_pair(void *user, int job, int worker, btf_error *err)
{
    (void)worker;
    measure_job *J = user;
    btf_pair_quality *pq = &J->q->pairs[job];
    btf_image meas = {0}, model = {0};
    btf_gbuffer g;
    memset(&g, 0, sizeof g);
    double v[3], l[3];
    btf_dir_to_vec(J->in->views->dirs[pq->view], v);
    btf_dir_to_vec(J->in->lights->dirs[pq->light], l);
    float vf[3] = {(float)v[0], (float)v[1], (float)v[2]};
    btf_light sun;
    memset(&sun, 0, sizeof sun);
    sun.kind = BTF_LIGHT_DIRECTIONAL;
    for (int i = 0; i < 3; i++) {
        sun.direction[i] = l[i];
        sun.rgb[i] = 1.0f;
    }
    static const float black[3] = {0, 0, 0};
    btf_status rc = btf_dataset_read(J->ds, pq->view, pq->light, &meas, err);
    if (rc == BTF_OK)
        rc = btf__render_flat_gbuffer(J->in->width, J->in->height, vf, &g, err);
    if (rc == BTF_OK)
        rc = btf__render_shade(J->rm, &g, &sun, 1, black, J->o->relief, 1, &model, err);
    if (rc == BTF_OK) {
        btf_texture_distance_opts d = btf_texture_distance_defaults();
        d.reference_name = btf_dataset_path(J->ds, pq->view, pq->light);
        d.image_name = "the model's flat render";
        rc = btf_texture_distance(&meas, &model, &d, &pq->d, err);
    }
    if (rc == BTF_OK)
        btf__pixelwise_dy(&meas, &model, &pq->mean_abs_dy, &pq->luminance);
    if (rc == BTF_OK && J->o->on_pair)
        rc = J->o->on_pair(J->o->on_pair_user, job, pq->view, pq->light, &meas, &model, err);
    btf__gbuffer_free(&g);
    btf_image_free(&meas);
    btf_image_free(&model);
    return rc;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The summary over the pairs the model measured (every pair, unless some
 * were held out of its analysis); the held-out pairs' mean apart. */
static void summarise(btf_quality *q)
{
    int n = 0, worst = -1;
    double *c = malloc((size_t)(q->n_pairs > 0 ? q->n_pairs : 1) * sizeof *c);
    double s = 0, sp = 0, fo = 0, st = 0, held = 0, dy = 0, held_dy = 0, lum = 0;
    q->n_held_out = 0;
    for (int i = 0; i < q->n_pairs; i++) {
        const btf_texture_distances *d = &q->pairs[i].d;
        if (q->pairs[i].held_out) {
            q->n_held_out++;
            held += d->combined;
            held_dy += q->pairs[i].mean_abs_dy;
            continue;
        }
        dy += q->pairs[i].mean_abs_dy;
        lum += q->pairs[i].luminance;
        s += d->combined;
        sp += d->spectrum.normalised;
        fo += d->first_order.normalised;
        st += d->structure.normalised;
        if (worst < 0 || d->combined > q->pairs[worst].d.combined)
            worst = i;
        if (c)
            c[n] = d->combined;
        n++;
    }
    q->mean_held_out = q->n_held_out ? held / q->n_held_out : 0.0;
    q->mean_held_out_abs_dy = q->n_held_out ? held_dy / q->n_held_out : 0.0;
    q->mean_abs_dy = n ? dy / n : q->mean_held_out_abs_dy;
    q->mean_luminance = n ? lum / n : 0.0;
    q->worst = worst < 0 ? 0 : worst;
    if (n == 0) { /* only held-out pairs were sampled */
        free(c);
        q->mean_combined = q->median_combined = q->worst_combined = q->mean_held_out;
        return;
    }
    q->mean_combined = s / n;
    q->mean_spectrum = sp / n;
    q->mean_first_order = fo / n;
    q->mean_structure = st / n;
    q->worst_combined = q->pairs[q->worst].d.combined;
    if (c) {
        qsort(c, (size_t)n, sizeof *c, cmp_double);
        q->median_combined = n % 2 ? c[n / 2] : 0.5 * (c[n / 2 - 1] + c[n / 2]);
    } else {
        q->median_combined = q->mean_combined;
    }
    free(c);
}

/* A sparse set's pairs to measure: every pair it holds, or (more than
 * views x lights of them, without all) that many spread evenly over them. */
static btf_status choose_sparse(const btf_dataset *ds, const btf_dataset_info *in,
                                const btf_model *m, const btf_quality_opts *o, btf_quality *q,
                                btf_error *err)
{
    int want = o->all ? in->n_pairs : o->views * o->lights;
    want = want < in->n_pairs ? want : in->n_pairs;
    q->pairs = btf__calloc((size_t)(want > 0 ? want : 1), sizeof *q->pairs, err);
    if (!q->pairs)
        return BTF_E_NOMEM;
    int same = same_sets(in, m), seen = 0;
    for (int v = 0; v < in->n_views; v++)
        for (int l = 0; l < in->n_lights; l++) {
            if (!btf_dataset_has(ds, v, l))
                continue;
            /* the i-th of want picks held pair floor(i * n_pairs / want) */
            int i = seen++;
            if (q->n_pairs < want && (long long)q->n_pairs * in->n_pairs / want == i) {
                btf_pair_quality *p = &q->pairs[q->n_pairs++];
                p->view = v;
                p->light = l;
                p->subspace = model_subspace(in, m, same, v, l);
                p->held_out = p->subspace < 0;
            }
        }
    return BTF_OK;
}

/* The pairs to measure: all, or the spread of views x the spread of lights
 * (a sparse set: choose_sparse). */
static btf_status choose_pairs(const btf_dataset *ds, const btf_dataset_info *in,
                               const btf_model *m, const btf_quality_opts *o, btf_quality *q,
                               btf_error *err)
{
    if (in->n_pairs < in->n_views * in->n_lights)
        return choose_sparse(ds, in, m, o, q, err);
    int same = same_sets(in, m);
    int *vi = btf__alloc((size_t)in->n_views, sizeof(int), err);
    int *li = btf__alloc((size_t)in->n_lights, sizeof(int), err);
    if (!vi || !li) {
        free(vi);
        free(li);
        return BTF_E_NOMEM;
    }
    int nv, nl;
    if (o->all) {
        for (int i = 0; i < in->n_views; i++)
            vi[i] = i;
        for (int i = 0; i < in->n_lights; i++)
            li[i] = i;
        nv = in->n_views;
        nl = in->n_lights;
    } else {
        nv = btf__spread_directions(in->views, o->views, vi);
        nl = btf__spread_directions(in->lights, o->lights, li);
    }
    btf_status rc = BTF_OK;
    q->pairs = nv && nl ? btf__calloc((size_t)nv * nl, sizeof *q->pairs, err) : NULL;
    if (!q->pairs)
        rc = (nv && nl) ? BTF_E_NOMEM : btf__fail(err, BTF_E_NOMEM, "out of memory");
    for (int a = 0; rc == BTF_OK && a < nv; a++)
        for (int b = 0; b < nl; b++) {
            btf_pair_quality *p = &q->pairs[q->n_pairs++];
            p->view = vi[a];
            p->light = li[b];
            p->subspace = model_subspace(in, m, same, vi[a], li[b]);
            p->held_out = p->subspace < 0;
        }
    free(vi);
    free(li);
    return rc;
}

btf_status btf__quality_measure(const btf_dataset *ds, const btf_model *m,
                                const btf_quality_opts *opts, btf_quality *out, btf_error *err)
{
    if (!out)
        return btf__fail(err, BTF_E_ARG, "quality: no output given");
    memset(out, 0, sizeof *out);
    if (!ds || !m)
        return btf__fail(err, BTF_E_ARG, "quality: no dataset or no model given");
    btf_quality_opts d = btf_quality_defaults(), o;
    if (btf__opts_take(&o, sizeof o, opts, &d, "btf_quality_measure", err))
        return BTF_E_ARG;
    if (o.views <= 0)
        o.views = 9;
    if (o.lights <= 0)
        o.lights = 9;
    if (o.relief < 0.0)
        o.relief = 1.0;
    if (!isfinite(o.relief) || o.relief > 1e6)
        return btf__fail(err, BTF_E_ARG, "quality: relief %g: expected 0..1e6", o.relief);
    double t0 = btf__now();
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    btf_status rc = btf__render_check_model(m, err);
    if (rc || (rc = check_match(ds, in, m, err)) ||
        (rc = choose_pairs(ds, in, m, &o, out, err))) {
        btf__quality_free(out);
        return rc;
    }
    int side = btf__render_texture_side(m, in->width > in->height ? in->width : in->height);
    out->texture_size = side;
    if (o.progress)
        o.progress(o.progress_user, 0.0, "synthesising the subspace images");
    btf_render_material *rm = NULL;
    rc = btf__render_material_build(m, NULL, side, o.seed, o.threads, &rm, err);
    if (rc == BTF_OK) {
        measure_job J = {ds, in, m, rm, &o, out};
        btf_pool_progress pp = {o.progress, o.progress_user, "measuring (view, light) pairs",
                                0.0, 1.0, 1};
        rc = btf__pool_run(out->n_pairs, o.threads, measure_pair, &J, &pp, err);
    }
    btf__render_material_free(rm);
    if (rc) {
        btf__quality_free(out);
        return rc;
    }
    summarise(out);
    out->seconds = btf__now() - t0;
    return BTF_OK;
}

void btf__quality_free(btf_quality *q)
{
    if (!q)
        return;
    free(q->pairs);
    memset(q, 0, sizeof *q);
}
