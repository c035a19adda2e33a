/*
 * kmeans.c — k-means clustering (Lloyd's algorithm) with k-means++ seeding
 * (Arthur & Vassilvitskii 2007) and restarts, the best run kept by its
 * within-cluster distortion. Used by segmentation (paper section II.A).
 *
 * Degenerate inputs are part of the contract: k = 1; k above the number of
 * distinct points (k-means++ runs out of points at positive distance, and k
 * is reduced to the distinct count); duplicate points; clusters that go empty
 * during the iterations (re-seeded at the point farthest from its centre, so
 * no centre is ever a 0/0 mean). Every choice comes from a seeded stream, and
 * ties go to the lowest index, so a seed gives one result.
 */
#include "core/core.h"
#include "segment/segment.h"

#include <float.h>
#include <stdlib.h>
#include <string.h>

static double dist2(const float *a, const float *b, int dim)
{
    double s = 0.0;
    for (int i = 0; i < dim; i++) {
        double d = (double)a[i] - (double)b[i];
        s += d * d;
    }
    return s;
}

/* k-means++: the first centre uniformly, each next one with probability
 * proportional to the squared distance to the nearest chosen centre. Returns
 * the number of centres chosen: fewer than k when the points run out of
 * distinct values (every point then coincides with a centre). */
static int seed_plus_plus(const float *x, int n, int dim, int k, btf_rng *rng, float *centres,
                          double *d2)
{
    int first = (int)(btf__rng_uniform(rng) * n);
    memcpy(centres, x + (size_t)first * dim, (size_t)dim * sizeof(float));
    for (int i = 0; i < n; i++)
        d2[i] = dist2(x + (size_t)i * dim, centres, dim);
    int chosen = 1;
    while (chosen < k) {
        double total = 0.0;
        for (int i = 0; i < n; i++)
            total += d2[i];
        if (!(total > 0.0))
            break; /* all points coincide with chosen centres */
        double target = btf__rng_uniform(rng) * total, run = 0.0;
        int pick = -1;
        for (int i = 0; i < n; i++) {
            if (d2[i] <= 0.0)
                continue;
            pick = i; /* the last positive one also absorbs rounding */
            run += d2[i];
            if (run > target)
                break;
        }
        float *c = centres + (size_t)chosen * dim;
        memcpy(c, x + (size_t)pick * dim, (size_t)dim * sizeof(float));
        for (int i = 0; i < n; i++) {
            double d = dist2(x + (size_t)i * dim, c, dim);
            if (d < d2[i])
                d2[i] = d;
        }
        chosen++;
    }
    return chosen;
}

/* Assigns every point to its nearest centre; returns the distortion and
 * whether any label changed (through *changed). */
static double assign(const float *x, int n, int dim, const float *centres, int k, int *labels,
                     double *d2, int *changed)
{
    double total = 0.0;
    *changed = 0;
    for (int i = 0; i < n; i++) {
        const float *p = x + (size_t)i * dim;
        int best = 0;
        double bd = dist2(p, centres, dim);
        for (int c = 1; c < k; c++) {
            double d = dist2(p, centres + (size_t)c * dim, dim);
            if (d < bd) {
                bd = d;
                best = c;
            }
        }
        if (labels[i] != best) {
            labels[i] = best;
            *changed = 1;
        }
        d2[i] = bd;
        total += bd;
    }
    return total;
}

/* An empty cluster takes the point farthest from its own centre among
 * clusters that keep at least one other member. */
static void reseed_empty(const float *x, int n, int dim, float *centres, int c, int *labels,
                         double *d2, int *count)
{
    int far = -1;
    for (int i = 0; i < n; i++)
        if (count[labels[i]] > 1 && (far < 0 || d2[i] > d2[far]))
            far = i;
    if (far < 0)
        return; /* cannot happen with k <= distinct points; leave the centre */
    count[labels[far]]--;
    labels[far] = c;
    count[c] = 1;
    d2[far] = 0.0;
    memcpy(centres + (size_t)c * dim, x + (size_t)far * dim, (size_t)dim * sizeof(float));
}

/* New centres as the means of their members (double accumulators). */
static void update_centres(const float *x, int n, int dim, float *centres, int k, int *labels,
                           double *d2, int *count, double *acc)
{
    memset(acc, 0, (size_t)k * dim * sizeof(double));
    memset(count, 0, (size_t)k * sizeof(int));
    for (int i = 0; i < n; i++) {
        const float *p = x + (size_t)i * dim;
        double *a = acc + (size_t)labels[i] * dim;
        for (int j = 0; j < dim; j++)
            a[j] += p[j];
        count[labels[i]]++;
    }
    for (int c = 0; c < k; c++)
        if (count[c] > 0)
            for (int j = 0; j < dim; j++)
                centres[(size_t)c * dim + j] = (float)(acc[(size_t)c * dim + j] / count[c]);
    for (int c = 0; c < k; c++)
        if (count[c] == 0)
            reseed_empty(x, n, dim, centres, c, labels, d2, count);
}

typedef struct km_work {
    int *labels, *count;
    float *centres;
    double *d2, *acc;
} km_work;

static double one_run(const float *x, int n, int dim, int k, int max_iter, btf_rng *rng,
                      km_work *w, int *k_out)
{
    int kk = seed_plus_plus(x, n, dim, k, rng, w->centres, w->d2);
    for (int i = 0; i < n; i++)
        w->labels[i] = -1;
    int changed;
    double dist = assign(x, n, dim, w->centres, kk, w->labels, w->d2, &changed);
    for (int it = 0; it < max_iter && changed; it++) {
        update_centres(x, n, dim, w->centres, kk, w->labels, w->d2, w->count, w->acc);
        dist = assign(x, n, dim, w->centres, kk, w->labels, w->d2, &changed);
    }
    *k_out = kk;
    return dist;
}

/* Renumbers clusters by first appearance in point order, so that equal
 * partitions print equally whatever run produced them, and drops clusters
 * without members. */
static btf_status canonical_order(btf_kmeans_result *r, int n, int dim, btf_error *err)
{
    int *map = btf__alloc((size_t)r->k, sizeof(int), err);
    float *c = btf__alloc((size_t)r->k * dim, sizeof(float), err);
    if (!map || !c) {
        free(map);
        free(c);
        return BTF_E_NOMEM;
    }
    for (int i = 0; i < r->k; i++)
        map[i] = -1;
    int next = 0, used = 0;
    for (int i = 0; i < n; i++)
        if (map[r->labels[i]] < 0)
            map[r->labels[i]] = next++;
    for (int i = 0; i < r->k; i++)
        if (map[i] < 0)
            map[i] = next++;
    for (int i = 0; i < r->k; i++)
        memcpy(c + (size_t)map[i] * dim, r->centres + (size_t)i * dim, (size_t)dim * sizeof(float));
    for (int i = 0; i < n; i++)
        r->labels[i] = map[r->labels[i]];
    memcpy(r->centres, c, (size_t)r->k * dim * sizeof(float));
    /* A cluster left empty by the last iteration is dropped: every cluster
     * reported has at least one member. */
    for (int i = 0; i < n; i++)
        if (r->labels[i] + 1 > used)
            used = r->labels[i] + 1;
    r->k = used;
    free(map);
    free(c);
    return BTF_OK;
}

void btf__kmeans_free(btf_kmeans_result *r)
{
    if (!r)
        return;
    free(r->labels);
    free(r->centres);
    memset(r, 0, sizeof *r);
}

btf_kmeans_opts btf_kmeans_defaults(void)
{
    return (btf_kmeans_opts){.struct_size = sizeof(btf_kmeans_opts),
                             .restarts = 5, .max_iter = 100, .seed = 0};
}

/* The options with every zero (or negative) count replaced by its default;
 * the seed is taken as it is (0 is a seed like any other). */
static btf_status resolve_opts(const btf_kmeans_opts *opts, btf_kmeans_opts *o, btf_error *err)
{
    btf_kmeans_opts d = btf_kmeans_defaults();
    if (btf__opts_take(o, sizeof *o, opts, &d, "btf_kmeans", err))
        return BTF_E_ARG;
    if (o->restarts <= 0)
        o->restarts = d.restarts;
    if (o->max_iter <= 0)
        o->max_iter = d.max_iter;
    return BTF_OK;
}

btf_status btf__kmeans(const float *points, int n, int dim, int k, const btf_kmeans_opts *opts,
                       btf_kmeans_result *out, btf_error *err)
{
    memset(out, 0, sizeof *out);
    btf_kmeans_opts o;
    if (resolve_opts(opts, &o, err))
        return BTF_E_ARG;
    if (n < 1 || dim < 1 || k < 1)
        return btf__fail(err, BTF_E_ARG, "k-means on %d points of dimension %d with k = %d", n, dim, k);
    for (size_t i = 0; i < (size_t)n * dim; i++)
        if (!(points[i] > -FLT_MAX && points[i] < FLT_MAX))
            return btf__fail(err, BTF_E_ARG, "k-means: feature %zu of point %zu is not finite",
                             i % (size_t)dim, i / (size_t)dim);
    if (k > n)
        k = n;
    int restarts = o.restarts, max_iter = o.max_iter;
    km_work w = {0}, best = {0};
    w.labels = btf__alloc((size_t)n, sizeof(int), err);
    w.count = btf__alloc((size_t)k, sizeof(int), err);
    w.centres = btf__alloc((size_t)k * dim, sizeof(float), err);
    w.d2 = btf__alloc((size_t)n, sizeof(double), err);
    w.acc = btf__alloc((size_t)k * dim, sizeof(double), err);
    best.labels = btf__alloc((size_t)n, sizeof(int), err);
    best.centres = btf__alloc((size_t)k * dim, sizeof(float), err);
    btf_status rc = (w.labels && w.count && w.centres && w.d2 && w.acc && best.labels && best.centres)
                 ? BTF_OK : BTF_E_NOMEM;
    double best_dist = -1.0;
    int best_k = 0;
    btf_rng rng;
    btf__rng_seed(&rng, o.seed);
    for (int r = 0; rc == BTF_OK && r < restarts; r++) {
        int kk;
        double d = one_run(points, n, dim, k, max_iter, &rng, &w, &kk);
        if (best_dist < 0.0 || d < best_dist) {
            best_dist = d;
            best_k = kk;
            memcpy(best.labels, w.labels, (size_t)n * sizeof(int));
            memcpy(best.centres, w.centres, (size_t)kk * dim * sizeof(float));
        }
    }
    BTF_FREE_ALL(w.labels, w.count, w.centres, w.d2, w.acc);
    if (rc) {
        free(best.labels);
        free(best.centres);
        return rc;
    }
    out->k = best_k;
    out->labels = best.labels;
    out->centres = best.centres;
    out->distortion = best_dist;
    rc = canonical_order(out, n, dim, err);
    if (rc)
        btf__kmeans_free(out);
    return rc;
}
