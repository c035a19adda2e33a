/*
 * segment.c — BTF space segmentation (paper section II.A): the n_views x
 * n_lights images are clustered by k-means on their Lab cumulative histograms
 * (segment/features.c, segment/kmeans.c) into K subspaces; each subspace is
 * represented by the member image closest to its cluster centre — a real
 * measured image, which the CAR stage models. The index table says, for each
 * (view, light) pair, which subspace image stands for it.
 *
 * Choosing K (--subspaces auto). The distortion D(K) (sum of squared feature
 * distances to the centres) falls as K grows; D(1) is the total scatter of the
 * features. btfcar takes the smallest K with D(K) <= tau * D(1), tau = 0.10
 * by default: the subspaces explain at least 90 % of the feature scatter.
 * Past it, K grows while one more subspace still removes at least a fraction
 * g of the distortion left, D(K + 1) <= (1 - g) D(K), g = 0.12 by default:
 * a split that clear is a group of images the model would otherwise render
 * from a stranger's exemplar (measured: docs/segmentation.md, "Choosing K"). It
 * grows to at most twice the threshold's K: a continuum of images (one
 * brightness ramp) splits with a gain that falls only slowly.
 * K is capped at 20 (the paper's bound) and at the number of distinct
 * features. If every feature is the same, K = 1.
 */
#include <stdio.h>
#include "core/core.h"
#include "segment/segment.h"
#include "dataset/dataset.h"
#include "io/io.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define SEGMENT_MAX_K 255 /* the index table stores one byte per pair */

void btf_segmentation_free(btf_segmentation *s)
{
    if (!s)
        return;
    BTF_FREE_ALL(s->index, s->rep_view, s->rep_light, s->members, s->distortion_by_k, s->means);
    memset(s, 0, sizeof *s);
}

/* The member closest to each centre (ties: lowest index). */
static btf_status pick_representatives(const float *f, int n, int dim, const btf_kmeans_result *km,
                                       const int *pair_of, int n_lights, btf_segmentation *s,
                                       btf_error *err)
{
    double *best = btf__alloc((size_t)km->k, sizeof(double), err);
    if (!best)
        return BTF_E_NOMEM;
    for (int c = 0; c < km->k; c++) {
        best[c] = -1.0;
        s->members[c] = 0;
    }
    for (int i = 0; i < n; i++) {
        int c = km->labels[i];
        s->members[c]++;
        double d = 0.0;
        for (int j = 0; j < dim; j++) {
            double t = (double)f[(size_t)i * dim + j] - km->centres[(size_t)c * dim + j];
            d += t * t;
        }
        if (best[c] < 0.0 || d < best[c]) {
            best[c] = d;
            int pair = pair_of ? pair_of[i] : i;
            s->rep_view[c] = pair / n_lights;
            s->rep_light[c] = pair % n_lights;
        }
    }
    free(best);
    return BTF_OK;
}

/* The result of the rows' clustering on the pair grid: row i is pair
 * pair_of[i] (NULL: pair i), every other pair BTF_PAIR_NONE. */
static btf_status fill_result(const float *f, int n, int dim, const int *pair_of, int n_pairs,
                              int n_lights, const btf_kmeans_result *km, btf_segmentation *s,
                              btf_error *err)
{
    s->k = km->k;
    s->distortion = km->distortion;
    s->index = btf__alloc((size_t)n_pairs, 1, err);
    s->rep_view = btf__alloc((size_t)km->k, sizeof(int), err);
    s->rep_light = btf__alloc((size_t)km->k, sizeof(int), err);
    s->members = btf__alloc((size_t)km->k, sizeof(int), err);
    if (!s->index || !s->rep_view || !s->rep_light || !s->members)
        return BTF_E_NOMEM;
    memset(s->index, BTF_PAIR_NONE, (size_t)n_pairs);
    for (int i = 0; i < n; i++)
        s->index[pair_of ? pair_of[i] : i] = (uint8_t)km->labels[i];
    return pick_representatives(f, n, dim, km, pair_of, n_lights, s, err);
}

/* Whether the K-means result next (K + 1 clusters asked) splits clearly
 * enough to be kept over km (the split gain of the file comment; the
 * caller tries no split when it is off). */
static int clear_split(const btf_kmeans_result *km, const btf_kmeans_result *next, int k,
                       double gain)
{
    return next->k == k + 1 && next->distortion <= (1.0 - gain) * km->distortion;
}

/* The reason of a K grown past the threshold's k_tau by clear splits. */
static void split_reason(btf_segmentation *s, int k, int k_tau, double tau, double gain,
                         int max_k)
{
    const double *d = s->distortion_by_k;
    char stop[96];
    if (k >= 2 * k_tau || k >= max_k)
        snprintf(stop, sizeof stop, "at most %d", k);
    else if (d[k] > 0.0 && d[k + 1] > 0.0)
        snprintf(stop, sizeof stop, "D(%d)/D(%d) = %.3f", k + 1, k, d[k + 1] / d[k]);
    else
        snprintf(stop, sizeof stop, "no further split");
    snprintf(s->reason, sizeof s->reason,
             "K = %d: D(K)/D(1) <= %.3f from K = %d (%.4f), then split while one more "
             "removes >= %.0f%% of the distortion left (D(%d)/D(%d) = %.3f; stop: %s)",
             k, tau, k_tau, d[k_tau] / d[1], 100.0 * gain, k, k - 1,
             d[k - 1] > 0.0 ? d[k] / d[k - 1] : 0.0, stop);
}

/* Runs k-means for K = 1, 2, ... until the rule of the file comment holds. */
static btf_status choose_k(const float *f, int n, int dim, const btf_segment_opts *o, int max_k,
                           double tau, btf_segmentation *s, btf_kmeans_result *chosen,
                           btf_error *err)
{
    double d1 = 0.0;
    int have = 0;    /* km already holds this K's result (a kept split) */
    int k_tau = 0;   /* the smallest K the threshold held at */
    btf_kmeans_result km = {0}, next = {0};
    for (int k = 1; k <= max_k; k++) {
        btf_status rc = have ? BTF_OK : btf__kmeans(f, n, dim, k, &o->kmeans, &km, err);
        have = 0;
        if (rc)
            return rc;
        s->distortion_by_k[k] = km.distortion;
        if (k == 1)
            d1 = km.distortion;
        int fewer = km.k < k; /* ran out of distinct features */
        int pass = !(d1 > 0.0) || km.distortion <= tau * d1;
        if (pass && !k_tau)
            k_tau = k;
        if (pass && !fewer && k < max_k && k < 2 * k_tau && d1 > 0.0 && o->split_gain > 0.0) {
            if ((rc = btf__kmeans(f, n, dim, k + 1, &o->kmeans, &next, err))) {
                btf__kmeans_free(&km);
                return rc;
            }
            if (clear_split(&km, &next, k, o->split_gain)) {
                btf__kmeans_free(&km);
                km = next; /* K + 1's result, taken up by the next round */
                memset(&next, 0, sizeof next);
                have = 1;
                continue;
            }
            s->distortion_by_k[k + 1] = next.distortion;
            btf__kmeans_free(&next);
        }
        if (pass || fewer || k == max_k) {
            if (!(d1 > 0.0))
                snprintf(s->reason, sizeof s->reason,
                         "K = 1: every image has the same feature (no scatter to explain)");
            else if (fewer)
                snprintf(s->reason, sizeof s->reason,
                         "K = %d: only %d distinct features; D(%d)/D(1) = %.4f", km.k, km.k, km.k,
                         km.distortion / d1);
            else if (pass && k == 1)
                snprintf(s->reason, sizeof s->reason, "K = 1: D(1) is already within %.3f", tau);
            else if (pass && k > k_tau)
                split_reason(s, k, k_tau, tau, o->split_gain, max_k);
            else if (pass)
                snprintf(s->reason, sizeof s->reason,
                         "K = %d: smallest K with D(K)/D(1) <= %.3f (D(%d)/D(1) = %.4f, "
                         "D(%d)/D(1) = %.4f)", k, tau, k, km.distortion / d1, k - 1,
                         s->distortion_by_k[k - 1] / d1);
            else
                snprintf(s->reason, sizeof s->reason,
                         "K = %d: the cap; D(%d)/D(1) = %.4f is still above %.3f", k, k,
                         km.distortion / d1, tau);
            *chosen = km;
            return BTF_OK;
        }
        btf__kmeans_free(&km);
    }
    return btf__fail(err, BTF_E_ARG, "segmentation: no K tried (max %d)", max_k);
}

btf_segment_opts btf_segment_defaults(void)
{
    return (btf_segment_opts){.struct_size = sizeof(btf_segment_opts), .subspaces = 0,
                              .max_subspaces = 20,
                              .auto_threshold = 0.10,
                              .split_gain = 0.12,
                              .features = btf_feature_defaults(),
                              .kmeans = btf_kmeans_defaults()};
}

/* The options with zero (or negative) cap and threshold replaced by their
 * defaults; subspaces 0 stays (it means auto), and the nested features and
 * k-means options are resolved by their own calls. */
static btf_status resolve_opts(const btf_segment_opts *opts, btf_segment_opts *o, btf_error *err)
{
    btf_segment_opts d = btf_segment_defaults();
    if (btf__opts_take(o, sizeof *o, opts, &d, "btf_segment", err))
        return BTF_E_ARG;
    if (o->max_subspaces <= 0)
        o->max_subspaces = d.max_subspaces;
    if (!(o->auto_threshold > 0.0))
        o->auto_threshold = d.auto_threshold;
    if (o->split_gain == 0.0 || isnan(o->split_gain))
        o->split_gain = d.split_gain;
    return BTF_OK;
}

btf_status btf__segment_features(const float *features, int n_views, int n_lights, int dim,
                                 const btf_segment_opts *opts, btf_segmentation *out,
                                 btf_error *err)
{
    memset(out, 0, sizeof *out);
    btf_segment_opts o;
    if (resolve_opts(opts, &o, err))
        return BTF_E_ARG;
    if (n_views < 1 || n_lights < 1 || dim < 1)
        return btf__fail(err, BTF_E_ARG, "segmentation of %d x %d images", n_views, n_lights);
    int n_pairs = n_views * n_lights;
    int n = n_pairs;
    int *pair_of = NULL;         /* a sparse set: row i of rows is pair pair_of[i] */
    float *rows = NULL;
    if (o.present) {
        n = 0;
        for (int i = 0; i < n_pairs; i++)
            n += o.present[i] != 0;
        if (n == 0)
            return btf__fail(err, BTF_E_ARG, "segmentation of a set without images");
    }
    if (o.present && n < n_pairs) {
        pair_of = btf__alloc((size_t)n, sizeof(int), err);
        rows = btf__alloc((size_t)n * dim, sizeof(float), err);
        if (!pair_of || !rows) {
            free(pair_of);
            free(rows);
            return BTF_E_NOMEM;
        }
        for (int i = 0, r = 0; i < n_pairs; i++)
            if (o.present[i]) {
                pair_of[r] = i;
                memcpy(rows + (size_t)r * dim, features + (size_t)i * dim, (size_t)dim * sizeof(float));
                r++;
            }
        features = rows;
    }
    btf_status rc = BTF_OK;
    double tau = o.auto_threshold;
    if (o.subspaces < 0 || o.subspaces > SEGMENT_MAX_K)
        rc = btf__fail(err, BTF_E_ARG, "subspaces %d: expected 1..%d or auto", o.subspaces,
                       SEGMENT_MAX_K);
    else if (!(tau < 1.0))
        rc = btf__fail(err, BTF_E_ARG, "auto threshold %g: expected in (0, 1)", tau);
    else if (!(o.split_gain < 1.0))
        rc = btf__fail(err, BTF_E_ARG, "split gain %g: expected below 1 (negative: off)",
                       o.split_gain);
    if (rc) {
        free(pair_of);
        free(rows);
        return rc;
    }
    int max_k = o.max_subspaces;
    if (max_k > SEGMENT_MAX_K)
        max_k = SEGMENT_MAX_K;
    if (o.subspaces > max_k)
        max_k = o.subspaces;
    out->n_views = n_views;
    out->n_lights = n_lights;
    out->max_k = max_k;
    out->distortion_by_k = btf__calloc((size_t)max_k + 1, sizeof(double), err);
    if (!out->distortion_by_k) {
        free(pair_of);
        free(rows);
        return BTF_E_NOMEM;
    }
    btf_kmeans_result km;
    if (o.subspaces > 0) {
        rc = btf__kmeans(features, n, dim, o.subspaces, &o.kmeans, &km, err);
        if (rc == 0) {
            out->distortion_by_k[km.k] = km.distortion;
            if (km.k < o.subspaces)
                snprintf(out->reason, sizeof out->reason,
                         "K = %d: %d asked, but only %d distinct features", km.k, o.subspaces, km.k);
            else
                snprintf(out->reason, sizeof out->reason, "K = %d: fixed by --subspaces", km.k);
        }
    } else {
        rc = choose_k(features, n, dim, &o, max_k, tau, out, &km, err);
    }
    if (rc == 0) {
        rc = fill_result(features, n, dim, pair_of, n_pairs, n_lights, &km, out, err);
        btf__kmeans_free(&km);
    }
    free(pair_of);
    free(rows);
    if (rc)
        btf_segmentation_free(out);
    return rc;
}

btf_status btf_segment(const btf_dataset *ds, const btf_segment_opts *opts,
                       btf_segmentation *out, btf_error *err)
{
    memset(out, 0, sizeof *out);
    btf_segment_opts d = btf_segment_defaults(), o;
    if (btf__opts_take(&o, sizeof o, opts, &d, "btf_segment", err))
        return BTF_E_ARG;
    float *f;
    int dim;
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    float *means = btf__calloc((size_t)in->n_views * in->n_lights * 3, sizeof(float), err);
    if (!means)
        return BTF_E_NOMEM;
    o.features.means = means;
    unsigned char *present = NULL; /* a sparse set's measured pairs */
    btf_status rc = btf__dataset_present(ds, &present, err);
    if (rc == BTF_OK)
        rc = btf__dataset_features(ds, &o.features, &f, &dim, err);
    if (rc) {
        free(present);
        free(means);
        return rc;
    }
    o.present = present;
    rc = btf__segment_features(f, in->n_views, in->n_lights, dim, &o, out, err);
    free(f);
    free(present);
    if (rc == BTF_OK)
        out->means = means; /* the pair gains' measured colours */
    else
        free(means);
    return rc;
}

/* A palette of well-separated colours (sRGB 8-bit), repeated beyond 20. */
static const unsigned char PALETTE[20][3] = {
    {230, 25, 75},  {60, 180, 75},   {255, 225, 25}, {0, 130, 200},   {245, 130, 48},
    {145, 30, 180}, {70, 240, 240},  {240, 50, 230}, {210, 245, 60},  {250, 190, 212},
    {0, 128, 128},  {220, 190, 255}, {170, 110, 40}, {255, 250, 200}, {128, 0, 0},
    {170, 255, 195}, {128, 128, 0},  {255, 215, 180}, {0, 0, 128},    {128, 128, 128}};

btf_status btf_segmentation_write_png(const btf_segmentation *s, int cell, const char *path,
                                      btf_error *err)
{
    if (cell <= 0)
        cell = 6;
    if (cell > 64)
        return btf__fail(err, BTF_E_ARG, "%s: cell size %d: expected 1..64", path, cell);
    btf_image img;
    btf_status rc = btf_image_alloc(&img, s->n_views * cell, s->n_lights * cell, 3, err);
    if (rc)
        return rc;
    for (int y = 0; y < img.height; y++)
        for (int x = 0; x < img.width; x++) {
            int v = x / cell, l = y / cell;
            int k = s->index[v * s->n_lights + l];
            static const unsigned char NONE[3] = {0, 0, 0}; /* a pair not measured */
            const unsigned char *c = k == BTF_PAIR_NONE ? NONE : PALETTE[k % 20];
            for (int k = 0; k < 3; k++)
                img.data[(y * img.width + x) * 3 + k] = btf__srgb_to_linear(c[k] / 255.0f);
        }
    rc = btf_image_write_png(path, &img, err);
    btf_image_free(&img);
    return rc;
}
