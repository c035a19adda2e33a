/*
 * bench_synth_model.c — the in-memory synthesis time of a model file:
 * btf_synthesise_images of every subspace at WxH on the CPU, the same images
 * `btfcar synthesise --size WxH --backend cpu` writes (same seed, same
 * pixels), with no output. tests/bench/bench.sh runs it on the paper's workload
 * beside the whole `btfcar synthesise` process and prints the ratio.
 *
 *   bench_synth_model MODEL WxH [RUNS]   prints "in-memory synthesis: ..."
 *                                        and last "median_s S"
 * Without arguments (make bench runs every bench program so) it says how to
 * call it and exits 0. Never fails on time. A model with marginal transfers
 * is also timed without them and without colour matching, in alternate
 * runs, and its file size given with and without the transfers.
 */
#include "btfcar.h"
#include "testutil.h"

#include <stdio.h>
#include <stdlib.h>
#include <sys/types.h>

int main(int argc, char **argv)
{
    if (argc < 3) {
        printf("bench_synth_model: MODEL WxH [RUNS] (tests/bench/bench.sh runs it on the paper's "
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
    /* Three syntheses in alternate runs, so that they share the machine's
     * state: 0, a model without marginal transfers (format 1.1, before the
     * MARG section of format 1.2); 1, with the transfers (docs/synthesis.md,
     * "Marginals"), colour matching off; 2, the default: transfers and colour matching
     * (docs/synthesis.md, "Colour matching"; format 1.3 models). */
    btf_marginal *keep = malloc(sizeof *keep * (size_t)m.n_subspaces);
    int with = 0;
    for (int k = 0; k < m.n_subspaces; k++)
        keep[k] = m.subspaces[k].marginal, with += keep[k].knots != 0;
    int lab = with;
    for (int k = 0; k < m.n_subspaces; k++)
        lab = lab && keep[k].lab_knots;
    double t[4][99];
    int *subs = malloc(sizeof *subs * (size_t)m.n_subspaces);
    btf_image *imgs = malloc(sizeof *imgs * (size_t)m.n_subspaces);
    for (int k = 0; k < m.n_subspaces; k++)
        subs[k] = k;
    for (int r = 0; r < runs; r++)
        for (int v = with ? 0 : 1; v < 2 + 2 * lab; v++) {
            for (int k = 0; k < m.n_subspaces; k++) {
                m.subspaces[k].marginal = keep[k];
                if (v == 0)
                    m.subspaces[k].marginal.knots = 0;
            }
            so.match_colours = v >= 2 ? 0 : -1;
            double t0 = tu_now();
            if (v < 3) { /* all images in one call: the default's matching overlaps */
                if (btf_synthesise_images(&m, subs, m.n_subspaces, &so, imgs, &e)) {
                    fprintf(stderr, "bench_synth_model: %s\n", e.msg);
                    return 1;
                }
            } else { /* 3: the default, an image a call */
                for (int k = 0; k < m.n_subspaces; k++)
                    if (btf_synthesise_image(&m, k, &so, &imgs[k], &e)) {
                        fprintf(stderr, "bench_synth_model: %s\n", e.msg);
                        return 1;
                    }
            }
            t[v][r] = tu_now() - t0;
            for (int k = 0; k < m.n_subspaces; k++)
                btf_image_free(&imgs[k]);
        }
    free(subs);
    free(imgs);
    double med1 = tu_median(t[1], runs), med = lab ? tu_median(t[2], runs) : med1;
    if (with) {
        double moff = tu_median(t[0], runs);
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
               1e3 * med1, 100.0 * (med1 / moff - 1.0), n_on, n_off,
               (ssize_t)n_on - (ssize_t)n_off);
        if (lab) {
            double one = tu_median(t[3], runs);
            printf("colour matching (the default; --no-match-colours skips it): median %.1f ms, "
                   "%+.1f%% on the transfers alone, %+.1f%% on the synthesis without either; "
                   "an image a call (btf_synthesise_image, no overlap) %.1f ms, %+.1f%% on the "
                   "transfers alone\n", 1e3 * med, 100.0 * (med / med1 - 1.0),
                   100.0 * (med / moff - 1.0), 1e3 * one, 100.0 * (one / med1 - 1.0));
        }
    }
    free(keep);
    printf("in-memory synthesis (cpu, btf_synthesise_images, default options): %d subspace images "
           "of %dx%d: median %.1f ms (%d runs), %.2f Mpixel/s\n", m.n_subspaces, w, h, 1e3 * med,
           runs, (double)w * h * m.n_subspaces / med / 1e6);
    printf("median_s %.6f\n", med);
    btf_model_free(&m);
    return 0;
}
