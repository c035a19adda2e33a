/*
 * bench_photostereo.c — analyse stage 2: robust photometric stereo on 256^2
 * pixels x 81 lights (the leather material at view theta 0 under the ubo81
 * lights), normals + albedo + integration, with each integrator; and the
 * integrators alone. Median of 5 runs. Prints figures; never fails on time
 * (the target is <= 1 s for normals + integration on the 2-core machine).
 */
#include "generate/material.h"
#include "core/core.h"
#include "range/range.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define RUNS 5
#define SIZE 256

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double median(double *t, int n)
{
    qsort(t, (size_t)n, sizeof *t, cmp_double);
    return t[n / 2];
}

static int render(btf_image *imgs, double *L, int *n, btf_error *err)
{
    btf_procedural m;
    btf_dirset set;
    btf_view_map *vm = NULL;
    btf_dir v = {0, 0};
    int rc = btf_procedural_make("leather", SIZE, 1, &m, err);
    if (rc)
        return rc;
    if ((rc = btf_dirset_ubo81(&set, err)) == 0) {
        if ((rc = btf__view_map_make(&m, v, &vm, err)) == 0)
            for (int i = 0; i < set.count && rc == 0; i++) {
                btf_light_map *lm;
                if ((rc = btf__light_map_make(&m, set.dirs[i], &lm, err)) == 0)
                    rc = btf__material_render_maps(&m, vm, lm, v, set.dirs[i], &imgs[i], err);
                btf__light_map_free(lm);
                btf_dir_to_vec(set.dirs[i], L + 3 * i);
            }
        *n = set.count;
        btf_dirset_free(&set);
    }
    btf__view_map_free(vm);
    btf_procedural_free(&m);
    return rc;
}

int main(void)
{
    btf_image imgs[81] = {{0}};
    double L[81 * 3];
    int n = 0;
    btf_error err = {0};
    if (render(imgs, L, &n, &err) != 0) {
        fprintf(stderr, "bench_photostereo: %s\n", err.msg);
        return 1;
    }
    double px = (double)SIZE * SIZE;
    printf("== photostereo: %dx%d pixels x %d lights, %d CPUs, median of %d runs\n", SIZE, SIZE,
           n, btf__cpu_count(), RUNS);
    static const struct {
        const char *name;
        btf_integrate_method method;
        int plain;
    } cases[] = {
        {"robust + Poisson (default)", BTF_INTEGRATE_POISSON, 0},
        {"robust + Frankot-Chellappa", BTF_INTEGRATE_FC, 0},
        {"plain LS + Poisson", BTF_INTEGRATE_POISSON, 1},
    };
    btf_image normals = {0};
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        double t[RUNS];
        for (int r = 0; r < RUNS; r++) {
            btf_photostereo_opts o = {.plain = cases[c].plain};
            o.integrate.method = cases[c].method;
            btf_ps_input in = {imgs, n, L, NULL};
            btf_ps_result res;
            double t0 = now();
            if (btf_photostereo(&in, &o, &res, &err) != 0) {
                fprintf(stderr, "bench_photostereo: %s\n", err.msg);
                return 1;
            }
            t[r] = now() - t0;
            if (c == 0 && r == 0) {
                normals = res.normal;
                res.normal.data = NULL;
            }
            btf_ps_result_free(&res);
        }
        double m = median(t, RUNS);
        printf("photostereo %-28s median %.3f s, %.2f Mpixel/s (target <= 1 s)\n",
               cases[c].name, m, px / m * 1e-6);
    }
    static const struct {
        const char *name;
        btf_integrate_method method;
    } ints[] = {{"Poisson (DCT)", BTF_INTEGRATE_POISSON}, {"Frankot-Chellappa", BTF_INTEGRATE_FC}};
    for (size_t c = 0; c < 2; c++) {
        double t[RUNS];
        for (int r = 0; r < RUNS; r++) {
            btf_integrate_opts o = {.method = ints[c].method};
            btf_image h;
            double t0 = now();
            if (btf__integrate(&normals, NULL, &o, &h, &err) != 0) {
                fprintf(stderr, "bench_photostereo: %s\n", err.msg);
                return 1;
            }
            t[r] = now() - t0;
            btf_image_free(&h);
        }
        double m = median(t, RUNS);
        printf("integrate   %-28s median %.4f s, %.1f Mpixel/s\n", ints[c].name, m,
               px / m * 1e-6);
    }
    /* The masked Poisson solver: a disc (conjugate gradients). */
    btf_image mask;
    if (btf_image_alloc(&mask, SIZE, SIZE, 1, &err) == 0) {
        for (int y = 0; y < SIZE; y++)
            for (int x = 0; x < SIZE; x++) {
                double dx = x - SIZE / 2.0, dy = y - SIZE / 2.0;
                mask.data[y * SIZE + x] = dx * dx + dy * dy < 0.2 * SIZE * SIZE ? 1.0f : 0.0f;
            }
        double t[RUNS];
        for (int r = 0; r < RUNS; r++) {
            btf_image h;
            double t0 = now();
            if (btf__integrate(&normals, &mask, NULL, &h, &err) != 0) {
                fprintf(stderr, "bench_photostereo: %s\n", err.msg);
                return 1;
            }
            t[r] = now() - t0;
            btf_image_free(&h);
        }
        double m = median(t, RUNS);
        printf("integrate   %-28s median %.4f s, %.1f Mpixel/s\n", "Poisson, disc mask (PCG)", m,
               px / m * 1e-6);
        btf_image_free(&mask);
    }
    btf_image_free(&normals);
    for (int i = 0; i < n; i++)
        btf_image_free(&imgs[i]);
    return 0;
}
