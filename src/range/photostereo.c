/*
 * photostereo.c — the range-map stage of Haindl & Filip 2007, section
 * II.B: normals and albedo per pixel from images of one view under N >= 3
 * known lights by robust Lambertian photometric stereo (Woodham 1980), and
 * the height field integrated from the normals. This file holds the public
 * entry points for images in memory and for a BTF dataset, the options and
 * their defaults, the check of the light set, and the run that ties the
 * parts together (range/range.h lists them):
 *
 *   lights checked -> mask -> pass 1: grey samples (ps_passes.c)
 *     -> every pixel's robust fit (ps_solve.c, ps_fit.c)
 *     -> pass 2: colour albedo with the normals fixed (ps_passes.c)
 *     -> heights (integrate.c)
 *
 * The whole light set must be well conditioned, else the call fails, before
 * any file is read, with a message naming the direction the lights cannot
 * resolve: that is a property of the capture, not of a pixel.
 */
#include "range/range.h"
#include "core/core.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PS_PI 3.14159265358979323846

/* ---------------------------------------------------------------- options */

btf_photostereo_opts btf_photostereo_defaults(void)
{
    btf_photostereo_opts o = {
        .struct_size = sizeof o,
        .dark = 0.1,
        .trim_low = 0.0,
        .trim_high = 0.1,
        .outlier = 2.0,
        .saturation = 0.99,
        .max_condition = 1e4,
        .specular_cone = 20.0, /* degrees between the half vector and the normal */
        .iterations = 5,
        .integrate = btf_integrate_defaults(),
    };
    return o;
}

/* The fit's parameters: 0 takes the default (btf_photostereo_defaults, so
 * each default is written once), a negative value switches a rule off
 * where the header says so. */
static btf_status resolve_opts(const btf_photostereo_opts *o, btf_ps_params *p, btf_error *err)
{
    const btf_photostereo_opts def = btf_photostereo_defaults();
    if (!isfinite(o->dark) || o->dark >= 1.0 || !isfinite(o->trim_low) || o->trim_low < 0.0 ||
        !isfinite(o->trim_high) || o->trim_high >= 1.0)
        return btf__fail(err, BTF_E_ARG,
                         "photostereo: dark %g, trim_low %g, trim_high %g: expected dark < 1, "
                         "trim_low in [0, 1), trim_high < 1",
                         o->dark, o->trim_low, o->trim_high);
    p->dark = o->dark == 0.0 ? def.dark : o->dark < 0.0 ? 0.0 : o->dark;
    p->trim_low = o->trim_low == 0.0 ? def.trim_low : o->trim_low;
    p->trim_high = o->trim_high == 0.0 ? def.trim_high : o->trim_high < 0.0 ? 0.0 : o->trim_high;
    if (p->trim_low + p->trim_high >= 1.0)
        return btf__fail(err, BTF_E_ARG, "photostereo: trim_low %g + trim_high %g leave no samples",
                         p->trim_low, p->trim_high);
    if (!(o->outlier >= 0.0) || !isfinite(o->outlier))
        return btf__fail(err, BTF_E_ARG, "photostereo: outlier %g: expected a finite value >= 0",
                         o->outlier);
    p->outlier = o->outlier == 0.0 ? def.outlier : o->outlier;
    if (!(o->saturation <= 1.0))
        return btf__fail(err, BTF_E_ARG, "photostereo: saturation %g: expected a fraction of "
                         "full scale, at most 1 (< 0: no saturation rule)", o->saturation);
    p->saturation = o->saturation == 0.0 ? def.saturation
                    : o->saturation < 0.0 ? INFINITY : o->saturation;
    if (!(o->max_condition == 0.0 || (o->max_condition >= 1.0 && isfinite(o->max_condition))))
        return btf__fail(err, BTF_E_ARG, "photostereo: max_condition %g: expected 0 or >= 1",
                         o->max_condition);
    p->max_condition = o->max_condition == 0.0 ? def.max_condition : o->max_condition;
    if (!isfinite(o->specular_cone) || o->specular_cone >= 90.0)
        return btf__fail(err, BTF_E_ARG, "photostereo: specular_cone %g: expected < 90 degrees",
                         o->specular_cone);
    /* A cosine above 1 no half vector reaches: no highlight rule. */
    p->specular_cos = o->specular_cone < 0.0 ? 2.0
                      : cos((o->specular_cone == 0.0 ? def.specular_cone : o->specular_cone) *
                            (PS_PI / 180.0));
    p->iterations = o->iterations == 0 ? def.iterations : o->iterations < 0 ? 0 : o->iterations;
    p->plain = o->plain != 0;
    if (o->threads < 0)
        return btf__fail(err, BTF_E_ARG, "photostereo: threads %d: expected >= 0", o->threads);
    return BTF_OK;
}

/* ------------------------------------------------------------ the lights */

/* Normalises the lights into unit_lights and checks the intensities and
 * the conditioning of the whole set. */
static btf_status check_lights(const char *name, const double *lights, const double *intensity,
                               int count, const btf_ps_params *params, double *unit_lights,
                               double *condition, btf_error *err)
{
    btf_sym3 gram = {0};
    for (int i = 0; i < count; i++) {
        const double *l = lights + 3 * i;
        double len = sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]);
        if (!isfinite(len) || !(len > 1e-12))
            return btf__fail(err, BTF_E_ARG, "%s: light %d (%g, %g, %g) is not a finite "
                             "non-zero vector", name, i, l[0], l[1], l[2]);
        for (int c = 0; c < 3; c++)
            unit_lights[3 * i + c] = l[c] / len;
        btf_sym3_add_outer(&gram, unit_lights + 3 * i);
        if (intensity)
            for (int c = 0; c < 3; c++)
                if (!(intensity[3 * i + c] > 0.0) || !isfinite(intensity[3 * i + c]))
                    return btf__fail(err, BTF_E_ARG, "%s: light %d intensity (%g, %g, %g) "
                                     "must be finite and positive", name, i, intensity[3 * i],
                                     intensity[3 * i + 1], intensity[3 * i + 2]);
    }
    *condition = btf__sym3_condition(&gram);
    if (!(*condition <= params->max_condition)) {
        double axis[3];
        btf__sym3_weakest_axis(&gram, axis);
        return btf__fail(err, BTF_E_DATA, "%s: the %d light directions are (nearly) "
                         "coplanar: condition number %.3g exceeds %g, so the normal is not "
                         "determined along (%.3f, %.3f, %.3f); use lights spread over more than "
                         "one plane", name, count, *condition, params->max_condition, axis[0],
                         axis[1], axis[2]);
    }
    return BTF_OK;
}

/* The half vector of each light with the view, which is the camera axis
 * (0, 0, 1) in this frame; 0 for a light straight behind the surface. */
static void half_vectors(const double *unit_lights, int count, double *halfway)
{
    for (int i = 0; i < count; i++) {
        double h[3] = {unit_lights[3 * i], unit_lights[3 * i + 1], unit_lights[3 * i + 2] + 1.0};
        double len = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
        for (int c = 0; c < 3; c++)
            halfway[3 * i + c] = len > 1e-9 ? h[c] / len : 0.0;
    }
}

/* ---------------------------------------------------------------- result */

void btf_ps_result_free(btf_ps_result *r)
{
    if (!r)
        return;
    btf_image_free(&r->normal);
    btf_image_free(&r->albedo);
    btf_image_free(&r->height);
    btf_image_free(&r->lights_used);
    btf_image_free(&r->valid);
    memset(r, 0, sizeof *r);
    r->view = -1;
}

btf_status btf__ps_result_start(btf_ps_result *out, btf_error *err)
{
    if (!out)
        return btf__fail(err, BTF_E_ARG, "photostereo: no result given");
    memset(out, 0, sizeof *out);
    out->view = -1;
    return BTF_OK;
}

static btf_status alloc_result(btf_ps_result *r, int w, int h, int channels, btf_error *err)
{
    btf_status rc;
    if ((rc = btf_image_alloc(&r->normal, w, h, 3, err)) ||
        (rc = btf_image_alloc(&r->albedo, w, h, channels, err)) ||
        (rc = btf_image_alloc(&r->lights_used, w, h, 1, err)) ||
        (rc = btf_image_alloc(&r->valid, w, h, 1, err)))
        return rc;
    return BTF_OK;
}

/* ------------------------------------------------------------------- run */

/* Pass 1 with the clip level at saturation x full scale. Full scale is 1
 * unless the data exceed it, which only the pass itself finds out: data
 * beyond 1 (HDR, or linear data in other units) are read again with the
 * clip level at saturation x their peak, so that a dataset x 1000 loses
 * the samples it loses at x 1, not all of them (flat range maps). */
static btf_status grey_samples(const btf_ps_source *src, const double *intensity,
                               double saturation, const unsigned char *inside, float *grey,
                               const btf_photostereo_opts *o, btf_error *err)
{
    double peak;
    btf_status rc = btf__ps_pass_grey(src, intensity, saturation, inside, grey, &peak, o, err);
    if (rc || !isfinite(saturation) || btf__ps_full_scale(peak) == 1.0)
        return rc;
    return btf__ps_pass_grey(src, intensity, saturation * btf__ps_full_scale(peak), inside, grey,
                             NULL, o, err);
}

btf_status btf__ps_run(btf_ps_source *src, const double *lights, const double *intensity,
                       const btf_photostereo_opts *o, btf_ps_result *out, btf_error *err)
{
    btf_ps_params params;
    btf_status rc = resolve_opts(o, &params, err);
    if (rc)
        return rc;
    int n = src->count;
    if (n < 3)
        return btf__fail(err, BTF_E_ARG, "%s: %d images; at least 3 lights are needed", src->name,
                         n);
    /* The unit lights, then their half vectors with the view. */
    double *unit_lights = btf__alloc((size_t)n * 6, sizeof(double), err);
    if (!unit_lights)
        return BTF_E_NOMEM;
    double *halfway = unit_lights + 3 * (size_t)n;
    /* The lights first: a coplanar set fails before any file is touched. */
    if ((rc = check_lights(src->name, lights, intensity, n, &params, unit_lights,
                           &out->condition, err)) ||
        (src->width == 0 && (rc = btf__ps_source_probe(src, err)))) {
        free(unit_lights);
        return rc;
    }
    int w = src->width, h = src->height;
    size_t wh = (size_t)w * h;
    unsigned char *inside = btf__alloc(wh, 1, err);
    if (!inside) {
        free(unit_lights);
        return BTF_E_NOMEM;
    }
    float *grey = NULL;
    btf_ps_solve job = {0};
    if ((rc = btf__ps_mask_inside(src->name, o->mask, w, h, inside, &out->pixels, err)) ||
        (rc = alloc_result(out, w, h, src->channels, err)))
        goto done;
    half_vectors(unit_lights, n, halfway);
    grey = btf__alloc(wh * (size_t)n, sizeof(float), err);
    if (!grey) {
        rc = BTF_E_NOMEM;
        goto done;
    }
    job = (btf_ps_solve){.width = w, .height = h, .count = n, .set_words = (n + 63) / 64,
                         .lights = unit_lights, .halfway = halfway, .grey = grey,
                         .inside = inside, .params = params, .normal = out->normal.data,
                         .lights_used = out->lights_used.data, .valid = out->valid.data};
    job.fit_sets = btf__calloc(wh * (size_t)job.set_words, sizeof(uint64_t), err);
    if (!job.fit_sets) {
        rc = BTF_E_NOMEM;
        goto done;
    }
    if ((rc = grey_samples(src, intensity, params.saturation, inside, grey, o, err)) ||
        (rc = btf__ps_solve_all(&job, o->threads, o->progress, o->progress_user, 0.4, 0.5, err)))
        goto done;
    free(grey); /* the largest buffer: gone before pass 2 decodes again */
    grey = NULL;
    out->fitted = job.fitted;
    out->fallback = job.fallback;
    if ((rc = btf__ps_pass_albedo(src, intensity, &job, &out->albedo, o, err)))
        goto done;
    btf__ps_report(o, 0.9, "integrating");
    rc = btf__integrate(&out->normal, o->mask, &o->integrate, &out->height, err);
    if (rc == BTF_OK)
        btf__ps_report(o, 1.0, "done");
done:
    BTF_FREE_ALL(job.fit_sets, grey, inside, unit_lights);
    return rc;
}

/* ---------------------------------------------------------- entry points */

btf_status btf_photostereo(const btf_ps_input *in, const btf_photostereo_opts *opts,
                           btf_ps_result *out, btf_error *err)
{
    btf_status rc = btf__ps_result_start(out, err);
    if (rc)
        return rc;
    btf_photostereo_opts zero = {0}, o;
    if (btf__opts_take(&o, sizeof o, opts, &zero, "btf_photostereo", err))
        return BTF_E_ARG;
    if (!in || !in->images || !in->lights || in->count < 3)
        return btf__fail(err, BTF_E_ARG, "photostereo: %d images given; at least 3 lights are "
                         "needed", in && in->images && in->lights ? in->count : 0);
    const btf_image *first = &in->images[0];
    for (int i = 0; i < in->count; i++) {
        const btf_image *b = &in->images[i];
        if (!b->data || b->width < 1 || b->height < 1 || (b->channels != 1 && b->channels != 3))
            return btf__fail(err, BTF_E_ARG, "photostereo: image %d is empty or has %d channels "
                             "(expected 1 or 3)", i, b->channels);
        if (b->width != first->width || b->height != first->height ||
            b->channels != first->channels)
            return btf__fail(err, BTF_E_ARG, "photostereo: image %d is %dx%dx%d, image 0 is "
                             "%dx%dx%d", i, b->width, b->height, b->channels, first->width,
                             first->height, first->channels);
    }
    btf_ps_source src = {.name = "photostereo", .count = in->count, .images = in->images,
                         .width = first->width, .height = first->height,
                         .channels = first->channels};
    rc = btf__ps_run(&src, in->lights, in->intensity, &o, out, err);
    if (rc)
        btf_ps_result_free(out);
    return rc;
}

int btf__photostereo_best_lights(const btf_dataset *ds)
{
    const btf_dataset_info *info = btf_dataset_get_info(ds);
    int best = 0;
    for (int v = 0; v < info->n_views; v++) {
        int n = 0;
        for (int l = 0; l < info->n_lights; l++)
            n += btf_dataset_has(ds, v, l);
        best = n > best ? n : best;
    }
    return best;
}

/* The view photometric stereo works on: the one asked for, else the one
 * closest to the normal (its images are then nearly orthographic and
 * unshifted by parallax), among the views at which the set holds at least
 * 3 lights (all of them in a full grid). */
static btf_status ps_usable_view(const btf_dataset *ds, const btf_dir *want, int *view,
                                 btf_error *err)
{
    const btf_dataset_info *info = btf_dataset_get_info(ds);
    btf_dir *dirs = btf__alloc((size_t)info->n_views, sizeof *dirs, err);
    int *which = btf__alloc((size_t)info->n_views, sizeof *which, err);
    btf_status rc = dirs && which ? BTF_OK : BTF_E_NOMEM;
    int n = 0;
    for (int v = 0; rc == BTF_OK && v < info->n_views; v++) {
        int lights = 0;
        for (int l = 0; l < info->n_lights; l++)
            lights += btf_dataset_has(ds, v, l);
        if (lights >= 3) {
            dirs[n] = info->views->dirs[v];
            which[n++] = v;
        }
    }
    if (rc == BTF_OK && n == 0)
        rc = btf__fail(err, BTF_E_DATA, "%s: photometric stereo needs one view with at least 3 "
                       "lights; the set holds at most %d at any view", info->root,
                       btf__photostereo_best_lights(ds));
    int pick = 0;
    if (rc == BTF_OK && (rc = btf__ps_pick_view(dirs, n, want, info->root, &pick, err)) == BTF_OK)
        *view = which[pick];
    free(dirs);
    free(which);
    return rc;
}

btf_status btf__photostereo_dataset(const btf_dataset *ds, const btf_photostereo_opts *opts,
                                    btf_ps_result *out, btf_error *err)
{
    return btf_photostereo_dataset_view(ds, NULL, opts, out, err);
}

btf_status btf_photostereo_dataset_view(const btf_dataset *ds, const btf_dir *want,
                                        const btf_photostereo_opts *opts, btf_ps_result *out,
                                        btf_error *err)
{
    btf_status rc = btf__ps_result_start(out, err);
    if (rc)
        return rc;
    if (!ds)
        return btf__fail(err, BTF_E_ARG, "photostereo: no dataset given");
    btf_photostereo_opts zero = {0}, o;
    if (btf__opts_take(&o, sizeof o, opts, &zero, "btf_photostereo", err))
        return BTF_E_ARG;
    const btf_dataset_info *info = btf_dataset_get_info(ds);
    int view = 0, nl = info->n_lights;
    if ((rc = ps_usable_view(ds, want, &view, err)))
        return rc;
    double *lights = btf__alloc((size_t)nl * 3, sizeof(double), err);
    const char **paths = btf__alloc((size_t)nl, sizeof(char *), err);
    int *light_of = btf__alloc((size_t)nl, sizeof(int), err);
    if (!lights || !paths || !light_of) {
        BTF_FREE_ALL(lights, paths, light_of);
        return BTF_E_NOMEM;
    }
    int n = 0; /* the lights the set holds at this view (all of a full grid) */
    for (int i = 0; i < nl; i++) {
        if (!btf_dataset_has(ds, view, i))
            continue;
        btf_dir_to_vec(info->lights->dirs[i], lights + 3 * n);
        paths[n] = btf_dataset_path(ds, view, i);
        light_of[n++] = i;
    }
    btf_ps_source src = {.name = info->root, .count = n, .paths = paths, .read = o.read,
                         .width = info->width, .height = info->height, .channels = 3,
                         .ds = ds, .view = view, .light_of = light_of};
    rc = btf__ps_run(&src, lights, NULL, &o, out, err);
    out->view = view;
    out->view_dir = info->views->dirs[view];
    BTF_FREE_ALL(lights, paths, light_of);
    if (rc)
        btf_ps_result_free(out);
    return rc;
}
