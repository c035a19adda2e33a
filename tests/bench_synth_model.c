/*
 * bench_synth_model.c — the in-memory synthesis time of a model file:
 * btf_synthesise_image of every subspace at WxH on the CPU, the same images
 * `btfcar synthesise --size WxH --backend cpu` writes (same seed, same
 * pixels), with no output. tests/bench.sh runs it on the paper's workload
 * beside the whole `btfcar synthesise` process and prints the ratio.
 *
 *   bench_synth_model MODEL WxH [RUNS]   prints "in-memory synthesis: ..."
 *                                        and last "median_s S"
 * Without arguments (make bench runs every bench program so) it says how to
 * call it and exits 0. Never fails on time. A model with marginal transfers
 * is also timed without them, in alternate runs, and its file size given
 * both ways.
 */
#include "btfcar.h"
#include "testutil.h"

#include <stdio.h>
#include <stdlib.h>
#include <sys/types.h>

int main(int argc, char **argv)
{
    if (argc < 3) {
        printf("bench_synth_model: MODEL WxH [RUNS] (tests/bench.sh runs it on the paper's "
               "workload)\n");
        return 0;
    }
    int w = 0, h = 0, runs = argc > 3 ? atoi(argv[3]) : 5;
    if (sscanf(argv[2], "%dx%d", &w, &h) != 2 || w < 1 || h < 1 || runs < 1 || runs > 99) {
        fprintf(stderr, "bench_synth_model: bad size '%s' or runs\n", argv[2]);
        return 2;
    }
    btf_error e = {0};
    btf_model m;
    double tr[99];
    for (int r = 0; r < runs; r++) {
        double t0 = tu_now();
        if (btf_model_read(argv[1], &m, &e)) {
            fprintf(stderr, "bench_synth_model: %s\n", e.msg);
            return 1;
        }
        tr[r] = tu_now() - t0;
        if (r < runs - 1)
            btf_model_free(&m);
    }
    printf("model read (btf_model_read, margins included): median %.1f ms (%d runs)\n",
           1e3 * tu_median(tr, runs), runs);
    btf_synth_opts so = btf_synth_defaults();
    so.width = w, so.height = h, so.seed = 1;
    /* The marginal transfers (docs/synthesis.md, "Marginals") off and on in
     * alternate runs: off is the synthesis of a model without them (format
     * 1.1), the comparison of the same run. */
    btf_marginal *keep = malloc(sizeof *keep * (size_t)m.n_subspaces);
    int with = 0;
    for (int k = 0; k < m.n_subspaces; k++)
        keep[k] = m.subspaces[k].marginal, with += keep[k].knots != 0;
    double t[99], toff[99];
    for (int r = 0; r < runs; r++)
        for (int on = with ? 0 : 1; on < 2; on++) {
            for (int k = 0; k < m.n_subspaces; k++) {
                m.subspaces[k].marginal = keep[k];
                if (!on)
                    m.subspaces[k].marginal.knots = 0;
            }
            double t0 = tu_now();
            for (int k = 0; k < m.n_subspaces; k++) {
                btf_image img;
                if (btf_synthesise_image(&m, k, &so, &img, &e)) {
                    fprintf(stderr, "bench_synth_model: %s\n", e.msg);
                    return 1;
                }
                btf_image_free(&img);
            }
            (on ? t : toff)[r] = tu_now() - t0;
        }
    double med = tu_median(t, runs);
    if (with) {
        double moff = tu_median(toff, runs);
        unsigned char *d = NULL;
        size_t n_on = 0, n_off = 0;
        if (btf_model_encode(&m, &d, &n_on, &e) == 0)
            free(d);
        for (int k = 0; k < m.n_subspaces; k++)
            m.subspaces[k].marginal.knots = 0;
        if (btf_model_encode(&m, &d, &n_off, &e) == 0)
            free(d);
        for (int k = 0; k < m.n_subspaces; k++)
            m.subspaces[k].marginal = keep[k];
        printf("marginal transfers (%d subspaces): synthesis without median %.1f ms, with %.1f ms "
               "(%+.1f%%); model file %zu bytes, %zu without (%+zd bytes)\n", with, 1e3 * moff,
               1e3 * med, 100.0 * (med / moff - 1.0), n_on, n_off, (ssize_t)n_on - (ssize_t)n_off);
    }
    free(keep);
    printf("in-memory synthesis (cpu, btf_synthesise_image): %d subspace images of %dx%d: "
           "median %.1f ms (%d runs), %.2f Mpixel/s\n", m.n_subspaces, w, h, 1e3 * med, runs,
           (double)w * h * m.n_subspaces / med / 1e6);
    printf("median_s %.6f\n", med);
    btf_model_free(&m);
    return 0;
}
