/*
 * bench_rf.c — the reflectance-field family (Meseth, Müller &
 * Klein 2003; docs/rf.md) on a generated 81 x 81 material: the time of
 * each fit (PTM, k = 2 lobes, Lafortune with 2 lobes) with 2 threads, its
 * Table-1 error, its bytes per texel against the CAR model of the same
 * material; then, per fit, the flat render's and a sphere frame's
 * throughput on the CPU (2 threads) and on the GPU (any Vulkan device,
 * lavapipe included: LP_NUM_THREADS sets its threads), each the median of
 * several runs in this same process, and the GPU/CPU ratio. Figures only;
 * never fails on time.
 *
 * Usage: bench_rf [SIZE [MATERIAL [FIT_RUNS]]]   (default 64 leather;
 * make bench: 128). FIT_RUNS: fits timed per fit (default 3 for the PTM,
 * 1 for the two Levenberg-Marquardt fits, which take minutes at 128^2).
 */
#include "testutil.h"
#include "rf/rf_render.h"
#include "synth_gpu.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define RENDER_RUNS 5

static int bench_fail(const btf_error *e)
{
    fprintf(stderr, "bench_rf: %s\n", e->msg);
    return 1;
}

/* The CAR model of the material: its whole file's bytes. */
static int car_bytes(const btf_dataset *ds, size_t *bytes)
{
    btf_error e = {0};
    btf_model car;
    unsigned char *data = NULL;
    double t0 = tu_now();
    if (btf_analyse(ds, NULL, &car, &e) || btf_model_encode(&car, &data, bytes, &e))
        return bench_fail(&e);
    printf("CAR model (analyse defaults): %zu bytes in all, %.1f s\n", *bytes, tu_now() - t0);
    free(data);
    btf_model_free(&car);
    return 0;
}

/* One fit, timed `runs` times (the last model kept). */
static int bench_fit(const btf_dataset *ds, int fit, int runs, size_t car, double texels,
                     btf_rf_model *out)
{
    btf_error e = {0};
    double t[9];
    btf_rf_fit_info info;
    for (int r = 0; r < runs; r++) {
        btf_rf_opts o = btf_rf_defaults();
        o.fit = fit, o.threads = 2, o.info = &info;
        if (r > 0)
            btf_rf_model_free(out);
        double t0 = tu_now();
        if (btf_rf_fit(ds, &o, out, &e))
            return bench_fail(&e);
        t[r] = tu_now() - t0;
    }
    unsigned char *bytes = NULL;
    size_t n = 0;
    if (btf_rf_encode(out, &bytes, &n, &e))
        return bench_fail(&e);
    free(bytes);
    printf("fit %-9s median %.1f s of %d run%s (last: reading %.1f s, fitting %.1f s, %.2f us "
           "per texel and field, %.1f LM steps per solve); error %.5f of mean Y %.4f; file %zu "
           "bytes = %.1f bytes per texel = %.0f x the CAR model's %zu bytes\n",
           btf_rf_fit_name(fit), tu_median(t, runs), runs, runs > 1 ? "s" : "", info.read_s,
           info.fit_s, 1e6 * info.fit_s / (texels * out->fields),
           info.lm_runs ? (double)info.lm_iterations / (double)info.lm_runs : 0.0,
           info.mean_abs_error, info.mean_luminance, n, n / texels, (double)n / (double)car, car);
    return 0;
}

/* A 1024^2 flat render between views (the fields of three or four views
 * blended; Lafortune's one): the CPU's and the GPU's medians. */
static int bench_flat(const btf_rf_model *m, btf_gpu *gpu)
{
    btf_error e = {0};
    btf_dir v = {37.5, 100}, l = {45, 20};
    double tc[RENDER_RUNS], tg[RENDER_RUNS];
    btf_image img;
    for (int r = 0; r < RENDER_RUNS; r++) {
        double t0 = tu_now();
        if (btf__rf_render_flat(m, v, l, 1024, 1024, 2, &img, &e))
            return bench_fail(&e);
        tc[r] = tu_now() - t0;
        btf_image_free(&img);
    }
    double c = tu_median(tc, RENDER_RUNS);
    int idx[4], fields = 0;
    double w[4];
    btf__rf_view_weights(&m->views, v, idx, w);
    for (int i = 0; i < 4; i++)
        fields += w[i] != 0.0;
    printf("  flat 1024^2 (%dx%d distinct texels, %d field%s blended), cpu 2 threads: median "
           "%.1f ms, %.0f Mpixel/s", m->width, m->height,
           m->fit == BTF_RF_LAFORTUNE ? 1 : fields,
           m->fit == BTF_RF_LAFORTUNE || fields == 1 ? "" : "s", 1e3 * c,
           1024.0 * 1024.0 / c / 1e6);
    if (!gpu) {
        printf("\n");
        return 0;
    }
    btf_render_info info;
    double up = 0.0;
    for (int r = 0; r < RENDER_RUNS; r++) {
        double t0 = tu_now();
        if (btf__gpu_rf_render_flat(gpu, m, v, l, 1024, 1024, &img, &info, &e))
            return bench_fail(&e);
        tg[r] = tu_now() - t0;
        up += info.synth_s / RENDER_RUNS;
        btf_image_free(&img);
    }
    double g = tu_median(tg, RENDER_RUNS);
    printf("; gpu: median %.1f ms (upload and pipeline %.1f ms), gpu/cpu time %.2f\n", 1e3 * g,
           1e3 * up, g / c);
    return 0;
}

/* A 512^2 sphere under one light, the texels repeating (texture_scale
 * 128): the CPU's and the GPU's medians, tracing included in both. */
static int bench_sphere(const btf_rf_model *m, btf_gpu *gpu)
{
    btf_scene s;
    memset(&s, 0, sizeof s);
    s.camera = (btf_camera){{0, 0, 4}, {0, 0, 0}, {0, 1, 0}, 40};
    btf_light light = {.kind = BTF_LIGHT_DIRECTIONAL, .direction = {0.57735027, 0.57735027,
                       0.57735027}, .rgb = {1, 0.95f, 0.9f}};
    btf_object ball = {.kind = BTF_OBJECT_SPHERE, .radius = 1, .axis = {0, 1, 0},
                       .texture_scale = 128};
    s.lights = &light, s.n_lights = 1;
    s.objects = &ball, s.n_objects = 1;
    btf_error e = {0};
    double tc[RENDER_RUNS], tg[RENDER_RUNS], trace = 0.0, shade = 0.0;
    btf_image img;
    btf_render_info info;
    for (int r = 0; r < RENDER_RUNS; r++) {
        double t0 = tu_now();
        if (btf__rf_render_scene(m, &s, 512, 512, 2, &img, &info, &e))
            return bench_fail(&e);
        tc[r] = tu_now() - t0;
        trace += info.trace_s / RENDER_RUNS, shade += info.shade_s / RENDER_RUNS;
        btf_image_free(&img);
    }
    double c = tu_median(tc, RENDER_RUNS);
    printf("  sphere 512^2, cpu 2 threads: median %.1f ms = %.2f frames/s (trace %.1f ms, "
           "shade %.1f ms)", 1e3 * c, 1.0 / c, 1e3 * trace, 1e3 * shade);
    if (!gpu) {
        printf("\n");
        return 0;
    }
    double up = 0.0, pass = 0.0;
    for (int r = 0; r < RENDER_RUNS; r++) {
        double t0 = tu_now();
        if (btf__gpu_rf_render_scene(gpu, m, &s, 512, 512, 2, &img, &info, &e))
            return bench_fail(&e);
        tg[r] = tu_now() - t0;
        up += info.synth_s / RENDER_RUNS, pass += info.shade_s / RENDER_RUNS;
        btf_image_free(&img);
    }
    double g = tu_median(tg, RENDER_RUNS);
    printf("; gpu: median %.1f ms = %.2f frames/s (upload of every field and pipeline %.1f ms, "
           "render pass %.1f ms), gpu/cpu time %.2f\n", 1e3 * g, 1.0 / g, 1e3 * up, 1e3 * pass,
           g / c);
    return 0;
}

int main(int argc, char **argv)
{
    setvbuf(stdout, NULL, _IOLBF, 0); /* figures as they come, the fits take minutes */
    int size = argc > 1 ? atoi(argv[1]) : 64;
    const char *material = argc > 2 ? argv[2] : "leather";
    int fit_runs = argc > 3 ? atoi(argv[3]) : 0;
    if (size < 8 || size > 1024 || fit_runs < 0 || fit_runs > 9) {
        fprintf(stderr, "bench_rf: usage: bench_rf [SIZE [MATERIAL [FIT_RUNS]]]\n");
        return 2;
    }
    char *dir = tu_tmpdir();
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, material);
    btf_error e = {0};
    btf_generate_opts g = btf_generate_defaults();
    g.size = size, g.threads = 2;
    btf_dataset *ds = NULL;
    if (btf_generate(material, path, &g, &e) || btf_dataset_open(path, NULL, &ds, &e))
        return bench_fail(&e);
    double texels = (double)size * size;
    printf("== reflectance fields (docs/rf.md): %s, 81 x 81 images of %dx%d, 2 threads\n",
           material, size, size);
    size_t car = 0;
    if (car_bytes(ds, &car))
        return 1;
    btf_gpu *gpu = NULL;
    btf_gpu_opts go = btf_gpu_defaults();
    go.allow_cpu = 1;
    if (btf_gpu_open(&go, &gpu, &e)) {
        printf("no Vulkan device (%s): GPU figures skipped\n", e.msg);
        gpu = NULL;
    }
    int rc = 0;
    for (int fit = 0; fit < 3 && rc == 0; fit++) {
        btf_rf_model m;
        int runs = fit_runs ? fit_runs : fit == BTF_RF_PTM ? 3 : 1;
        rc = bench_fit(ds, fit, runs, car, texels, &m);
        if (rc)
            break;
        if (fit == 0)
            printf("renders (median of %d each; gpu: %s):\n", RENDER_RUNS,
                   gpu ? btf_gpu_device_name(gpu) : "none");
        printf(" %s:\n", btf_rf_fit_name(fit));
        rc = bench_flat(&m, gpu);
        if (rc == 0)
            rc = bench_sphere(&m, gpu);
        btf_rf_model_free(&m);
    }
    btf_gpu_close(gpu);
    btf_dataset_close(ds);
    tu_rmtree(dir);
    free(dir);
    return rc;
}
