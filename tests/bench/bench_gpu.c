/*
 * bench_gpu.c — the paper's synthesis workload (Haindl & Filip 2007,
 * section II.C, on the GPU as in section III: 15 subspace images of 512^2,
 * 3 bands, 3 levels) on the Vulkan path and on the CPU path in one run, as
 * a ratio. The Vulkan device is the one BTF_VK_DEVICE names, else the best
 * the loader offers; without a GPU that is lavapipe (set LP_NUM_THREADS to
 * choose its threads). The first job (pipeline creation and shader
 * compilation included) is reported apart from the medians. Never fails on
 * time. Then colour matching alone, on the device (gpu/match_gpu.c) and on
 * the host (btf__colour_match, the thread pool), on the same 15 images.
 */
#include "btfcar.h"
#include "model/model.h"
#include "synth/synth.h"
#include "synth_gpu.h"
#include "testutil.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static int drop(void *user, int y, int nrows, const float *rows, btf_error *err)
{
    (void)user, (void)y, (void)nrows, (void)rows, (void)err;
    return 0;
}

/* Colour matching of 15 images of 512^2 already synthesised: on the device
 * (sample, sort, apply: the images never read back) against the host's
 * btf__colour_match on the same images, each the median of 3 runs. */
static void bench_matching(btf_gpu *g, const btf_model *m)
{
    btf_error e = {0};
    btf_image img[15];
    int subs[15];
    for (int k = 0; k < 15; k++)
        subs[k] = k;
    btf_synth_opts so = {.width = 512, .height = 512, .seed = 1, .match_colours = -1};
    if (btf_gpu_synthesise(g, m, subs, 15, &so, img, &e)) {
        fprintf(stderr, "bench_gpu: %s\n", e.msg);
        return;
    }
    uint64_t floats = 512ull * 512 * 3, cap = btf__gpu_images_cap(g);
    btf_gpu_images dev;
    if (btf__gpu_images_create(btf__gpu_vk(g), 15 * floats, cap, btf__gpu_images_buffers(g), "bench", &dev, &e)) {
        fprintf(stderr, "bench_gpu: %s\n", e.msg);
        return;
    }
    double td[3], th[3];
    for (int r = 0; r < 3; r++) {
        for (int k = 0; k < 15; k++)
            btf__gpu_images_upload(btf__gpu_vk(g), &dev, k * floats, img[k].data, floats, &e);
        double t0 = tu_now();
        for (int k = 0; k < 15; k++)
            if (btf__gpu_match_images(btf__gpu_vk(g), btf__gpu_match_pipes(g), m, k, 1, &dev,
                                      k * floats, 512, 512, NULL, &e))
                fprintf(stderr, "bench_gpu: %s\n", e.msg);
        td[r] = tu_now() - t0;
    }
    btf_image copy;
    for (int r = 0; r < 3; r++) {
        th[r] = 0;
        for (int k = 0; k < 15; k++) {
            if (btf_image_alloc(&copy, 512, 512, 3, &e))
                return;
            memcpy(copy.data, img[k].data, floats * sizeof(float));
            double t0 = tu_now();
            btf__colour_match(m, k, &copy, &e);
            th[r] += tu_now() - t0;
            btf_image_free(&copy);
        }
    }
    printf("colour matching alone, 15 x 512^2: on the device median %.0f ms, on the host (CPU "
           "code, thread pool) median %.0f ms: device/host time ratio %.2f\n",
           1e3 * tu_median(td, 3), 1e3 * tu_median(th, 3), tu_median(td, 3) / tu_median(th, 3));
    btf__gpu_images_free(&dev);
    for (int k = 0; k < 15; k++)
        btf_image_free(&img[k]);
}

int main(void)
{
    const char *icd = "/usr/share/vulkan/icd.d/lvp_icd.x86_64.json";
    if (!getenv("VK_DRIVER_FILES"))
        setenv("VK_DRIVER_FILES", icd, 1);
    btf_error e = {0};
    btf_procedural mat;
    btf_image img;
    btf_model tex;
    btf_fit_opts fo = {.levels = 3};
    btf_neighbourhood_parse("0:-1,-1:0,-1:-1,-1:1", fo.car.fixed, &fo.car.n_fixed, &e);
    if (btf_procedural_make("leather", 256, 3, &mat, &e) ||
        btf_procedural_render(&mat, (btf_dir){0, 0}, (btf_dir){30, 45}, &img, &e) ||
        btf_texture_fit(&img, &fo, &tex, &e)) {
        fprintf(stderr, "bench_gpu: %s\n", e.msg);
        return 1;
    }
    btf_model m = {0};
    m.n_subspaces = 15;
    m.subspaces = calloc(15, sizeof(btf_subspace_model));
    int subs[15];
    for (int k = 0; k < 15; k++) {
        m.subspaces[k] = tex.subspaces[0];
        subs[k] = k;
    }
    if (btf__model_keep_margins(&m, -1.0) != BTF_OK) /* as a fitted model keeps them */
        return 1;
    const char *lp = getenv("LP_NUM_THREADS");
    double t0 = tu_now();
    btf_gpu *g;
    btf_gpu_opts go = {.allow_cpu = 1};
    const char *dev = getenv("BTF_VK_DEVICE");
    if (dev && *dev)
        go.use_device = 1, go.device = atoi(dev);
    if (btf_gpu_open(&go, &g, &e)) {
        printf("gpu: no Vulkan device: %s\n", e.msg);
        return 0;
    }
    double t_open = tu_now() - t0;
    btf_image out[15];
    double tg[4], tc[3];
    for (int r = 0; r < 4; r++) {
        t0 = tu_now();
        btf_synth_opts so = {.width = 512, .height = 512, .seed = 1};
        if (btf_gpu_synthesise(g, &m, subs, 15, &so, out, &e)) {
            fprintf(stderr, "bench_gpu: %s\n", e.msg);
            return 1;
        }
        tg[r] = tu_now() - t0;
        for (int k = 0; k < 15; k++)
            btf_image_free(&out[k]);
    }
    for (int r = 0; r < 3; r++) {
        t0 = tu_now();
        btf_synth_opts so = {.width = 512, .height = 512, .seed = 1};
        for (int k = 0; k < 15; k++)
            btf_synthesise(&m, k, &so, drop, NULL, &e);
        tc[r] = tu_now() - t0;
    }
        printf("gpu (%s, LP_NUM_THREADS=%s): open + pipelines %.0f ms, first job %.0f ms\n",
           btf_gpu_device_name(g), lp ? lp : "default", 1e3 * t_open, 1e3 * tg[0]);
    printf("gpu vs cpu, 15 x 512^2, 4 neighbours, 3 levels: vulkan median %.0f ms, cpu (1 core) "
           "median %.0f ms: vulkan/cpu time ratio %.2f\n", 1e3 * tu_median(tg + 1, 3), 1e3 * tu_median(tc, 3),
           tu_median(tg + 1, 3) / tu_median(tc, 3));
    bench_matching(g, &m);
    btf_gpu_close(g);
    btf__model_internal_free(m.internal);
    free(m.subspaces);
    btf_model_free(&tex);
    btf_image_free(&img);
    btf_procedural_free(&mat);
    return 0;
}
