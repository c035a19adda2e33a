/*
 * bench_marginals.c — what the marginal transfer (docs/synthesis.md,
 * "Marginals") does to a model's syntheses: for every subspace of MODEL,
 * its exemplar (the representative image read from DATASET) against a
 * synthesis at the analysed size (seed 1) without the transfer (the
 * Gaussian bands of format 1.1) and with it:
 *   - the share of pixels with a negative channel, and of pixels outside
 *     the exemplar's RGB box,
 *   - per decorrelated channel the earth mover's distance between the
 *     exemplar's and the synthesis' values (1-D: the mean absolute
 *     difference of the sorted samples, equal sizes), divided by the
 *     exemplar channel's standard deviation.
 *
 *   bench_marginals DATASET MODEL      prints one line per subspace and the means
 * BENCH_NO_RGB_CLAMP=1 leaves out the RGB clamp (the transfer alone).
 * Without arguments (make bench runs every bench program so) it says how to
 * call it and exits 0.
 */
#include "btfcar.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Channel b of img decorrelated with the subspace's basis, sorted. */
static double *channel_sorted(const btf_image *img, const btf_subspace_model *sm, int b)
{
    size_t n = (size_t)img->width * img->height;
    double *v = malloc(n * sizeof *v);
    if (!v)
        return NULL;
    for (size_t i = 0; i < n; i++) {
        double s = 0;
        for (int k = 0; k < 3; k++)
            s += sm->basis[3 * b + k] * ((double)img->data[3 * i + k] - sm->mean[k]);
        v[i] = s;
    }
    qsort(v, n, sizeof *v, cmp_double);
    return v;
}

typedef struct stats {
    double negative, outside, emd[3];
} stats;

static int measure(const btf_image *ex, const btf_image *syn, const btf_subspace_model *sm,
                   stats *st)
{
    size_t n = (size_t)ex->width * ex->height, neg = 0, out = 0;
    float lo[3], hi[3];
    for (int k = 0; k < 3; k++)
        lo[k] = hi[k] = ex->data[k];
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++) {
            float v = ex->data[3 * i + k];
            lo[k] = v < lo[k] ? v : lo[k];
            hi[k] = v > hi[k] ? v : hi[k];
        }
    for (size_t i = 0; i < n; i++) {
        int ng = 0, ou = 0;
        for (int k = 0; k < 3; k++) {
            float v = syn->data[3 * i + k];
            ng |= v < 0.0f;
            ou |= v < lo[k] || v > hi[k];
        }
        neg += ng;
        out += ou;
    }
    st->negative = (double)neg / (double)n;
    st->outside = (double)out / (double)n;
    for (int b = 0; b < 3; b++) {
        double *a = channel_sorted(ex, sm, b), *s = channel_sorted(syn, sm, b);
        if (!a || !s) {
            free(a);
            free(s);
            return -1;
        }
        double d = 0, m = 0, var = 0;
        for (size_t i = 0; i < n; i++) {
            d += fabs(a[i] - s[i]);
            m += a[i];
        }
        m /= (double)n;
        for (size_t i = 0; i < n; i++)
            var += (a[i] - m) * (a[i] - m);
        double sd = sqrt(var / (double)n);
        st->emd[b] = sd > 0 ? d / (double)n / sd : 0.0;
        free(a);
        free(s);
    }
    return 0;
}

int main(int argc, char **argv)
{
    if (argc < 3) {
        printf("bench_marginals: DATASET MODEL (tests/bench/bench.sh runs it on the generated "
               "materials)\n");
        return 0;
    }
    btf_error e = {0};
    btf_dataset *ds;
    btf_model m;
    if (btf_dataset_open(argv[1], NULL, &ds, &e) || btf_model_read(argv[2], &m, &e)) {
        fprintf(stderr, "bench_marginals: %s\n", e.msg);
        return 1;
    }
    stats sum[2] = {{0}};
    double worst_neg[2] = {0, 0};
    printf("subspace  negative px (off -> on)  outside RGB box (off -> on)  EMD/sd band 0, 1, 2 "
           "(off -> on)\n");
    for (int k = 0; k < m.n_subspaces; k++) {
        btf_subspace_model *sm = &m.subspaces[k];
        btf_image ex;
        if (btf_dataset_read(ds, sm->view, sm->light, &ex, &e)) {
            fprintf(stderr, "bench_marginals: %s\n", e.msg);
            return 1;
        }
        stats st[2];
        btf_marginal keep = sm->marginal;
        for (int on = 0; on < 2; on++) {
            sm->marginal = keep;
            if (getenv("BENCH_NO_RGB_CLAMP")) /* the transfer alone, for a diagnosis */
                for (int c = 0; c < 3; c++)
                    sm->marginal.rgb_lo[c] = -1e30f, sm->marginal.rgb_hi[c] = 1e30f;
            if (!on)
                sm->marginal.knots = 0;
            btf_synth_opts so = btf_synth_defaults();
            so.seed = 1;
            btf_image syn;
            if (btf_synthesise_image(&m, k, &so, &syn, &e)) {
                fprintf(stderr, "bench_marginals: %s\n", e.msg);
                return 1;
            }
            if (measure(&ex, &syn, sm, &st[on])) {
                fprintf(stderr, "bench_marginals: out of memory\n");
                return 1;
            }
            btf_image_free(&syn);
            sum[on].negative += st[on].negative;
            sum[on].outside += st[on].outside;
            for (int b = 0; b < 3; b++)
                sum[on].emd[b] += st[on].emd[b];
            worst_neg[on] = st[on].negative > worst_neg[on] ? st[on].negative : worst_neg[on];
        }
        sm->marginal = keep;
        btf_image_free(&ex);
        printf("%8d  %6.2f%% -> %6.2f%%         %6.2f%% -> %6.2f%%             %.3f %.3f %.3f -> "
               "%.3f %.3f %.3f\n", k, 100 * st[0].negative, 100 * st[1].negative,
               100 * st[0].outside, 100 * st[1].outside, st[0].emd[0], st[0].emd[1],
               st[0].emd[2], st[1].emd[0], st[1].emd[1], st[1].emd[2]);
    }
    double n = m.n_subspaces;
    printf("    mean  %6.2f%% -> %6.2f%% (worst %.2f%% -> %.2f%%)  %6.2f%% -> %6.2f%%  %.3f %.3f "
           "%.3f -> %.3f %.3f %.3f\n", 100 * sum[0].negative / n, 100 * sum[1].negative / n,
           100 * worst_neg[0], 100 * worst_neg[1], 100 * sum[0].outside / n,
           100 * sum[1].outside / n, sum[0].emd[0] / n, sum[0].emd[1] / n, sum[0].emd[2] / n,
           sum[1].emd[0] / n, sum[1].emd[1] / n, sum[1].emd[2] / n);
    btf_model_free(&m);
    btf_dataset_close(ds);
    return 0;
}
