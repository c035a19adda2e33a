/*
 * bench_rf.c — the reflectance-field family (issue 19; Meseth, Müller &
 * Klein 2003; docs/rf.md) on a generated 81 x 81 material: the time of
 * each fit (PTM, k = 2 lobes, Lafortune) with 2 threads, its Table-1 error,
 * its bytes per texel against the CAR model of the same material, and the
 * flat render's throughput. Figures only; never fails on time.
 *
 * Usage: bench_rf [SIZE [MATERIAL]]   (default 64 leather)
 */
#include "testutil.h"

#include <stdio.h>
#include <stdlib.h>

int main(int argc, char **argv)
{
    int size = argc > 1 ? atoi(argv[1]) : 64;
    const char *material = argc > 2 ? argv[2] : "leather";
    char *dir = tu_tmpdir();
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, material);
    btf_error e = {0};
    btf_generate_opts g = btf_generate_defaults();
    g.size = size, g.threads = 2;
    btf_dataset *ds = NULL;
    if (btf_generate(material, path, &g, &e) || btf_dataset_open(path, NULL, &ds, &e)) {
        fprintf(stderr, "bench_rf: %s\n", e.msg);
        return 1;
    }
    double texels = (double)size * size;
    printf("== reflectance fields (docs/rf.md): %s, 81 x 81 images of %dx%d, 2 threads\n",
           material, size, size);
    /* The CAR model of the same material, for the size comparison. */
    btf_model car;
    unsigned char *bytes = NULL;
    size_t car_bytes = 0;
    double t0 = tu_now();
    if (btf_analyse(ds, NULL, &car, &e) || btf_model_encode(&car, &bytes, &car_bytes, &e)) {
        fprintf(stderr, "bench_rf: CAR analysis: %s\n", e.msg);
        return 1;
    }
    printf("CAR model (analyse defaults): %zu bytes in all, %.3f bytes per texel, %.1f s\n",
           car_bytes, car_bytes / texels, tu_now() - t0);
    free(bytes);
    btf_model_free(&car);
    btf_rf_model lobes = {0};
    for (int fit = 0; fit < 3; fit++) {
        btf_rf_opts o = btf_rf_defaults();
        btf_rf_fit_info info;
        o.fit = fit, o.threads = 2, o.info = &info;
        btf_rf_model m;
        t0 = tu_now();
        if (btf_rf_fit(ds, &o, &m, &e)) {
            fprintf(stderr, "bench_rf: %s\n", e.msg);
            return 1;
        }
        double s = tu_now() - t0;
        size_t n = 0;
        if (btf_rf_encode(&m, &bytes, &n, &e)) {
            fprintf(stderr, "bench_rf: %s\n", e.msg);
            return 1;
        }
        free(bytes);
        printf("fit %-9s %7.1f s (reading %.1f s, fitting %.1f s, %.2f us per texel and "
               "field); error %.5f of mean Y %.4f; file %zu bytes = %.1f bytes per texel = "
               "%.0f x the CAR model\n",
               btf_rf_fit_name(fit), s, info.read_s, info.fit_s,
               1e6 * info.fit_s / (texels * m.fields), info.mean_abs_error,
               info.mean_luminance, n, n / texels, (double)n / car_bytes);
        if (fit == BTF_RF_LOBES)
            lobes = m;
        else
            btf_rf_model_free(&m);
    }
    /* Flat render throughput: 1024^2 between views (four fields blended). */
    double times[5];
    btf_image img;
    for (int r = 0; r < 5; r++) {
        t0 = tu_now();
        if (btf_rf_render_flat(&lobes, (btf_dir){37.5, 100}, (btf_dir){45, 20}, 1024, 1024, 2,
                               &img, &e)) {
            fprintf(stderr, "bench_rf: %s\n", e.msg);
            return 1;
        }
        times[r] = tu_now() - t0;
        btf_image_free(&img);
    }
    double med = tu_median(times, 5);
    printf("flat render, lobes k = 2, 1024^2, 4 views blended, 2 threads: median %.1f ms, "
           "%.1f Mpixel/s\n", 1e3 * med, 1024.0 * 1024.0 / med / 1e6);
    btf_rf_model_free(&lobes);
    btf_dataset_close(ds);
    tu_rmtree(dir);
    free(dir);
    return 0;
}
