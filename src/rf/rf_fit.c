/*
 * rf_fit.c — a BTF dataset into a reflectance-field model (Meseth, Müller &
 * Klein 2003, sections 3.1 and 4): for every measured view v, the surface
 * reflectance field RF_v(x, l) = BTF(x, l, v) of every texel x is fitted
 * over the measured lights, on luminance (a PTM, rf_ptm.c, or k lobes,
 * rf_lobes.c), with the per-view, per-texel average colour; or, for
 * contrast, one Lafortune model per texel over every image
 * (rf_lafortune.c).
 *
 * Streaming: the per-view fits read one view's lights at a time (decoded
 * in parallel); the Lafortune fit needs every image of a texel, so it holds
 * the luminance of as many texel rows as opts->memory allows and passes
 * over the dataset once per band of rows. Texels are fitted in parallel
 * (core/pool.c), one job per texel row; a row's result depends only on its
 * data, so the model is the same for any thread count. After a field is
 * fitted its slots are quantised (rf_quant.c), and the quantised model's
 * luminance error is measured against the view's images still in memory
 * (the Lafortune model's by btf__rf_error, another pass).
 *
 * A crop (opts->crop_*) fits one window of the images only, the sample of
 * the memory reduction of section 6 (rf_sampled.c): each image is cut to
 * the window as it is read, and everything after sees a smaller dataset.
 */
#include "rf/rf.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct fit_ctx {
    const btf_dataset *ds;
    const btf_dataset_info *in;
    btf_rf_opts o;
    btf_rf_model *m;
    int nl, nv, w, h, workers;
    int iw, ih, cx, cy, cropped; /* the images' size; the window fitted */
    size_t texels;
    double *lvec;        /* [nl * 3] light vectors */
    double *pinv;        /* [6 * nl] the PTM operator */
    btf_image *imgs;     /* [nl] the current view's images */
    int view;
    float *vals;         /* [texels * slots] the current field's float slots */
    float *scratch;      /* [workers * nl] luminances of one texel */
    double *row_err, *row_lum; /* [h] */
    long long *row_steps, *row_runs; /* [h] */
    /* lafortune */
    int n_img, y0, rows;
    float *lum;          /* [rows * w * n_img] */
    double *rgbsum;      /* [rows * w * 3] */
    double *lall, *vall; /* [n_img * 3] light and view vectors of every image */
} fit_ctx;

/* The window (x, y, w, h) of an RGB image, in place: each row moves to an
 * address at or before its own, so front-to-back memmove is safe. */
static void crop_image(btf_image *img, int x, int y, int w, int h)
{
    for (int r = 0; r < h; r++)
        memmove(img->data + (size_t)r * w * 3,
                img->data + ((size_t)(y + r) * img->width + x) * 3, (size_t)w * 3 * sizeof(float));
    img->width = w, img->height = h;
}

static btf_status read_job(void *user, int l, int worker, btf_error *err)
{
    (void)worker;
    fit_ctx *c = user;
    btf_image_free(&c->imgs[l]);
    btf_status rc = btf_dataset_read(c->ds, c->view, l, &c->imgs[l], err);
    if (rc == BTF_OK && (c->imgs[l].width != c->iw || c->imgs[l].height != c->ih))
        rc = btf__fail(err, BTF_E_DATA, "%s: %dx%d image (expected %dx%d like the dataset)",
                       btf_dataset_path(c->ds, c->view, l), c->imgs[l].width, c->imgs[l].height,
                       c->iw, c->ih);
    if (rc == BTF_OK && c->cropped)
        crop_image(&c->imgs[l], c->cx, c->cy, c->w, c->h);
    return rc;
}

static btf_status read_view(fit_ctx *c, int v, btf_error *err)
{
    c->view = v;
    return btf__pool_run(c->nl, c->o.threads, read_job, c, NULL, err);
}

static inline void pixel(const btf_image *img, size_t t, float rgb[3])
{
    const float *p = img->data + t * 3;
    for (int i = 0; i < 3; i++)
        rgb[i] = isfinite(p[i]) ? p[i] : 0.0f;
}

/* One texel row of one view: PTM (and lobes), chroma, into c->vals. */
static btf_status fit_row_job(void *user, int y, int worker, btf_error *err)
{
    (void)err;
    fit_ctx *c = user;
    const btf_rf_model *m = c->m;
    float *lum = c->scratch + (size_t)worker * c->nl;
    long long steps = 0, runs = 0;
    for (int x = 0; x < c->w; x++) {
        size_t t = (size_t)y * c->w + x;
        double sum[3] = {0, 0, 0};
        for (int l = 0; l < c->nl; l++) {
            float rgb[3];
            pixel(&c->imgs[l], t, rgb);
            lum[l] = rf_luminance(rgb);
            sum[0] += rgb[0], sum[1] += rgb[1], sum[2] += rgb[2];
        }
        float *out = c->vals + t * m->slots;
        double a[6];
        rf_ptm_apply(c->pinv, c->nl, lum, a);
        if (m->fit == BTF_RF_PTM) {
            for (int i = 0; i < 6; i++)
                out[i] = (float)a[i];
        } else {
            steps += rf_lobes_fit(m->lobes, c->nl, c->lvec, lum, a, c->o.iterations, out);
            runs++;
        }
        rf_chroma(sum[0], sum[1], sum[2], out + m->params);
    }
    c->row_steps[y] += steps;
    c->row_runs[y] += runs;
    return BTF_OK;
}

/* The quantised field's luminance error on one texel row. */
static btf_status error_row_job(void *user, int y, int worker, btf_error *err)
{
    (void)worker, (void)err;
    fit_ctx *c = user;
    const btf_rf_model *m = c->m;
    float p[BTF_RF_MAX_SLOTS];
    double e = 0.0, s = 0.0, v[3] = {0, 0, 1};
    for (int x = 0; x < c->w; x++) {
        size_t t = (size_t)y * c->w + x;
        rf_texel_params(m, c->view, t, p);
        for (int l = 0; l < c->nl; l++) {
            float rgb[3];
            pixel(&c->imgs[l], t, rgb);
            double d = rf_luminance(rgb);
            e += fabs(d - rf_lum_eval(m->fit, m->lobes, p, c->lvec + 3 * l, v));
            s += d;
        }
    }
    c->row_err[y] += e;
    c->row_lum[y] += s;
    return BTF_OK;
}

static void progress(const fit_ctx *c, double f)
{
    if (c->o.progress)
        c->o.progress(c->o.progress_user, f, "fitting reflectance fields");
}

static btf_status fit_per_view(fit_ctx *c, btf_rf_opts *o, btf_error *err)
{
    btf_rf_model *m = c->m;
    btf_status rc = BTF_OK;
    double t_read = 0.0, t_fit = 0.0;
    for (int v = 0; v < c->nv && rc == BTF_OK; v++) {
        double t0 = btf__now();
        rc = read_view(c, v, err);
        t_read += btf__now() - t0;
        if (rc)
            break;
        t0 = btf__now();
        rc = btf__pool_run(c->h, o->threads, fit_row_job, c, NULL, err);
        if (rc)
            break;
        rf_quantise_field(c->vals, c->texels, m->slots, m->lo + (size_t)v * m->slots,
                          m->hi + (size_t)v * m->slots,
                          m->codes + (size_t)v * c->texels * m->slots);
        rc = btf__pool_run(c->h, o->threads, error_row_job, c, NULL, err);
        t_fit += btf__now() - t0;
        progress(c, (double)(v + 1) / c->nv);
    }
    if (o->info) {
        o->info->read_s = t_read;
        o->info->fit_s = t_fit;
    }
    return rc;
}

/* Lafortune: one pass's texel rows [y0, y0 + rows) of one view's images
 * into c->lum and c->rgbsum. */
static btf_status scatter_row_job(void *user, int r, int worker, btf_error *err)
{
    (void)worker, (void)err;
    fit_ctx *c = user;
    int y = c->y0 + r;
    for (int x = 0; x < c->w; x++) {
        size_t t = (size_t)y * c->w + x, tl = (size_t)r * c->w + x;
        float *lum = c->lum + tl * c->n_img + (size_t)c->view * c->nl;
        double *s = c->rgbsum + tl * 3;
        for (int l = 0; l < c->nl; l++) {
            float rgb[3];
            pixel(&c->imgs[l], t, rgb);
            lum[l] = rf_luminance(rgb);
            s[0] += rgb[0], s[1] += rgb[1], s[2] += rgb[2];
        }
    }
    return BTF_OK;
}

static btf_status laf_row_job(void *user, int r, int worker, btf_error *err)
{
    (void)worker, (void)err;
    fit_ctx *c = user;
    const btf_rf_model *m = c->m;
    int y = c->y0 + r;
    long long steps = 0;
    for (int x = 0; x < c->w; x++) {
        size_t t = (size_t)y * c->w + x, tl = (size_t)r * c->w + x;
        float *out = c->vals + t * m->slots;
        steps += rf_lafortune_fit(m->lobes, c->n_img, c->lall, c->vall, c->lum + tl * c->n_img,
                                  c->o.iterations, out);
        const double *s = c->rgbsum + tl * 3;
        rf_chroma(s[0], s[1], s[2], out + m->params);
    }
    c->row_steps[y] += steps;
    c->row_runs[y] += c->w;
    return BTF_OK;
}

static btf_status fit_lafortune(fit_ctx *c, btf_rf_opts *o, btf_error *err)
{
    btf_rf_model *m = c->m;
    c->n_img = c->nv * c->nl;
    size_t per_row = (size_t)c->w * c->n_img * sizeof(float);
    size_t rows = o->memory / (per_row ? per_row : 1);
    c->rows = rows < 1 ? 1 : rows > (size_t)c->h ? c->h : (int)rows;
    c->lum = btf__alloc((size_t)c->rows * c->w, (size_t)c->n_img * sizeof(float), err);
    c->rgbsum = btf__alloc((size_t)c->rows * c->w * 3, sizeof(double), err);
    c->lall = btf__alloc((size_t)c->n_img * 3, sizeof(double), err);
    c->vall = btf__alloc((size_t)c->n_img * 3, sizeof(double), err);
    if (!c->lum || !c->rgbsum || !c->lall || !c->vall)
        return BTF_E_NOMEM;
    for (int v = 0; v < c->nv; v++)
        for (int l = 0; l < c->nl; l++) {
            btf_dir_to_vec(c->in->views->dirs[v], c->vall + 3 * ((size_t)v * c->nl + l));
            memcpy(c->lall + 3 * ((size_t)v * c->nl + l), c->lvec + 3 * l, 3 * sizeof(double));
        }
    btf_status rc = BTF_OK;
    double t_read = 0.0, t_fit = 0.0, t_start = btf__now();
    int passes = (c->h + c->rows - 1) / c->rows;
    for (c->y0 = 0; c->y0 < c->h && rc == BTF_OK; c->y0 += c->rows) {
        int rows_now = c->h - c->y0 < c->rows ? c->h - c->y0 : c->rows;
        memset(c->rgbsum, 0, (size_t)c->rows * c->w * 3 * sizeof(double));
        for (int v = 0; v < c->nv && rc == BTF_OK; v++) {
            double t0 = btf__now();
            rc = read_view(c, v, err);
            if (rc == BTF_OK)
                rc = btf__pool_run(rows_now, o->threads, scatter_row_job, c, NULL, err);
            t_read += btf__now() - t0;
            progress(c, 0.5 * ((double)(c->y0 / c->rows) + (double)(v + 1) / c->nv) / passes);
        }
        if (rc)
            break;
        double t0 = btf__now();
        rc = btf__pool_run(rows_now, o->threads, laf_row_job, c, NULL, err);
        t_fit += btf__now() - t0;
        progress(c, (double)(c->y0 + rows_now) / c->h);
    }
    if (rc)
        return rc;
    rf_quantise_field(c->vals, c->texels, m->slots, m->lo, m->hi, m->codes);
    if (o->info) {
        o->info->read_s = t_read;
        o->info->fit_s = t_fit;
        (void)t_start;
    }
    /* The error of the quantised model: one more pass over the images (a
     * window's is measured by btf_rf_fit_sampled, through its map). */
    if (c->cropped)
        return BTF_OK;
    double e = 0.0, s = 0.0;
    rc = btf__rf_error(c->ds, m, o->threads, &e, &s, err);
    if (rc == BTF_OK && o->info) {
        o->info->mean_abs_error = e;
        o->info->mean_luminance = s;
    }
    return rc;
}

btf_status btf__rf_refuse_sparse(const btf_dataset *ds, btf_error *err)
{
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    if (in->n_pairs == in->n_views * in->n_lights)
        return BTF_OK;
    return btf__fail(err, BTF_E_DATA, "%s: the reflectance-field family fits every light at each "
                     "view, and this sparse set holds %d of the %d x %d pairs (the CAR family, "
                     "the default, takes any set)", in->root, in->n_pairs,
                     in->n_views, in->n_lights);
}

btf_status btf_rf_fit(const btf_dataset *ds, const btf_rf_opts *opts, btf_rf_model *out,
                      btf_error *err)
{
    if (!out)
        return btf__fail(err, BTF_E_ARG, "btf_rf_fit: no output model");
    memset(out, 0, sizeof *out);
    if (!ds)
        return btf__fail(err, BTF_E_ARG, "btf_rf_fit: no dataset");
    if (btf__rf_refuse_sparse(ds, err))
        return BTF_E_DATA;
    btf_rf_opts d = btf_rf_defaults(), o;
    if (btf__opts_take(&o, sizeof o, opts, &d, "btf_rf_fit", err))
        return BTF_E_ARG;
    if (o.lobes == 0)
        o.lobes = d.lobes;
    if (o.iterations == 0)
        o.iterations = d.iterations;
    if (o.memory == 0)
        o.memory = d.memory;
    if (!btf_rf_fit_name(o.fit))
        return btf__fail(err, BTF_E_ARG, "reflectance-field fit %d (expected 0 ptm, 1 lobes or "
                         "2 lafortune)", o.fit);
    if (o.lobes < 1 || o.lobes > BTF_RF_MAX_LOBES)
        return btf__fail(err, BTF_E_ARG, "%d lobes (expected 1..%d)", o.lobes, BTF_RF_MAX_LOBES);
    if (o.iterations < 0 || o.threads < 0)
        return btf__fail(err, BTF_E_ARG, "iterations %d, threads %d (expected >= 0)",
                         o.iterations, o.threads);
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    int cropped = o.crop_width != 0 || o.crop_height != 0;
    if (cropped && (o.crop_width < 1 || o.crop_height < 1 || o.crop_x < 0 || o.crop_y < 0 ||
                    o.crop_x > in->width - o.crop_width || o.crop_y > in->height - o.crop_height))
        return btf__fail(err, BTF_E_ARG, "crop of %dx%d at (%d, %d) (expected a window inside "
                         "the %dx%d images)", o.crop_width, o.crop_height, o.crop_x, o.crop_y,
                         in->width, in->height);
    double t_start = btf__now();
    if (o.info)
        memset(o.info, 0, sizeof *o.info);
    fit_ctx c;
    memset(&c, 0, sizeof c);
    c.ds = ds, c.in = in, c.o = o, c.m = out;
    c.nl = in->n_lights, c.nv = in->n_views, c.iw = in->width, c.ih = in->height;
    c.cropped = cropped;
    c.cx = cropped ? o.crop_x : 0, c.cy = cropped ? o.crop_y : 0;
    c.w = cropped ? o.crop_width : c.iw, c.h = cropped ? o.crop_height : c.ih;
    c.texels = (size_t)c.w * c.h;
    c.workers = btf__pool_workers(o.threads, c.h > c.nl ? c.h : c.nl);
    out->fit = o.fit;
    out->lobes = o.fit == BTF_RF_PTM ? 0 : o.lobes;
    out->width = c.w, out->height = c.h;
    out->params = btf__rf_param_count(o.fit, o.lobes);
    out->slots = out->params + 3;
    out->fields = o.fit == BTF_RF_LAFORTUNE ? 1 : c.nv;
    btf_status rc = btf__dirset_copy(&out->views, in->views, err);
    if (rc == BTF_OK)
        rc = btf__dirset_copy(&out->lights, in->lights, err);
    if (rc == BTF_OK) {
        size_t fs = (size_t)out->fields * out->slots;
        out->lo = btf__alloc(fs, sizeof(float), err);
        out->hi = btf__alloc(fs, sizeof(float), err);
        out->codes = btf__alloc(fs * c.texels, sizeof(uint16_t), err);
        c.lvec = btf__alloc((size_t)c.nl * 3, sizeof(double), err);
        c.pinv = btf__alloc((size_t)c.nl * 6, sizeof(double), err);
        c.imgs = btf__calloc((size_t)c.nl, sizeof(btf_image), err);
        c.vals = btf__alloc(c.texels * out->slots, sizeof(float), err);
        c.scratch = btf__alloc((size_t)c.workers * c.nl, sizeof(float), err);
        c.row_err = btf__calloc((size_t)c.h, sizeof(double), err);
        c.row_lum = btf__calloc((size_t)c.h, sizeof(double), err);
        c.row_steps = btf__calloc((size_t)c.h, sizeof(long long), err);
        c.row_runs = btf__calloc((size_t)c.h, sizeof(long long), err);
        if (!out->lo || !out->hi || !out->codes || !c.lvec || !c.pinv || !c.imgs || !c.vals ||
            !c.scratch || !c.row_err || !c.row_lum || !c.row_steps || !c.row_runs)
            rc = BTF_E_NOMEM;
    }
    if (rc == BTF_OK) {
        for (int l = 0; l < c.nl; l++)
            btf_dir_to_vec(in->lights->dirs[l], c.lvec + 3 * l);
        rc = rf_ptm_operator(in->lights, c.pinv, err);
    }
    if (rc == BTF_OK)
        rc = o.fit == BTF_RF_LAFORTUNE ? fit_lafortune(&c, &o, err) : fit_per_view(&c, &o, err);
    if (rc == BTF_OK && o.info) {
        double e = 0.0, s = 0.0;
        long long steps = 0, runs = 0;
        for (int y = 0; y < c.h; y++)
            e += c.row_err[y], s += c.row_lum[y], steps += c.row_steps[y],
                runs += c.row_runs[y];
        if (o.fit != BTF_RF_LAFORTUNE) {
            double n = (double)c.texels * c.nl * c.nv;
            o.info->mean_abs_error = e / n;
            o.info->mean_luminance = s / n;
        }
        o.info->lm_iterations = steps;
        o.info->lm_runs = runs;
        o.info->seconds = btf__now() - t_start;
    }
    if (c.imgs)
        for (int l = 0; l < c.nl; l++)
            btf_image_free(&c.imgs[l]);
    BTF_FREE_ALL(c.imgs, c.lvec, c.pinv, c.vals, c.scratch, c.row_err, c.row_lum, c.row_steps,
                 c.row_runs, c.lum, c.rgbsum, c.lall, c.vall);
    if (rc)
        btf_rf_model_free(out);
    return rc;
}
