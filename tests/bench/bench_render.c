/*
 * bench_render.c — the CPU renderer's frame rate: a scene is
 * traced once, its needed subspaces synthesised once, then the G-buffer is
 * shaded RUNS times with 1 and with 2 threads; prints the median shading
 * time and frames per second of each, and the trace and synthesis times.
 * Then the GPU backend (any Vulkan device, lavapipe included; LP_NUM_THREADS
 * sets lavapipe's threads): the whole btf_gpu_render_scene RUNS times, its
 * render pass (G-buffer upload, the shader, download) and synthesis pass,
 * and the render pass against the CPU's 2-thread shading of the same run.
 *
 *   bench_render MODEL SCENE WxH [RUNS]
 * Without arguments (make bench runs every bench program so) it says how to
 * call it and exits 0. Never fails on time.
 */
#include "btfcar.h"
#include "testutil.h"
#include "render/render.h"
#include "scene/gbuffer.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int bench_fail(const btf_error *e)
{
    fprintf(stderr, "bench_render: %s\n", e->msg);
    return 1;
}

int main(int argc, char **argv)
{
    if (argc < 4) {
        printf("bench_render: MODEL SCENE WxH [RUNS] (tests/bench/bench.sh runs it on a sphere)\n");
        return 0;
    }
    int w = 0, h = 0, runs = argc > 4 ? atoi(argv[4]) : 7;
    if (sscanf(argv[3], "%dx%d", &w, &h) != 2 || w < 1 || h < 1 || runs < 1 || runs > 99) {
        fprintf(stderr, "bench_render: bad size '%s' or runs\n", argv[3]);
        return 2;
    }
    btf_error e = {0};
    btf_model m;
    btf_scene s;
    if (btf_model_read(argv[1], &m, &e) || btf_scene_load(argv[2], &s, &e))
        return bench_fail(&e);
    btf_gbuffer g;
    double t0 = tu_now();
    if (btf__scene_trace(&s, w, h, 0, &g, &e))
        return bench_fail(&e);
    double t1 = tu_now();
    uint8_t *need = malloc((size_t)m.n_subspaces);
    int count = 0;
    if (btf__render_needed(&m, &g, s.lights, s.n_lights, need, &count, &e))
        return bench_fail(&e);
    double t2 = tu_now();
    btf_render_material *rm;
    if (btf__render_material_build(&m, need, 512, 1, 0, &rm, &e))
        return bench_fail(&e);
    double t3 = tu_now(), cpu2 = 0.0;
    printf("render %dx%d of %s: trace %.3f s, needed-subspace walk %.3f s (%d of %d), "
           "synthesis of those at 512^2 %.3f s\n", w, h, argv[2], t1 - t0, t2 - t1, count,
           m.n_subspaces, t3 - t2);
    for (int threads = 1; threads <= 2; threads++) {
        double t[99];
        for (int r = 0; r < runs; r++) {
            btf_image img;
            double a = tu_now();
            if (btf__render_shade(rm, &g, s.lights, s.n_lights, s.background, 1.0, threads, &img,
                                  &e))
                return bench_fail(&e);
            t[r] = tu_now() - a;
            btf_image_free(&img);
        }
        double med = tu_median(t, runs);
        cpu2 = med;
        printf("   shade, %d thread%s: median %.4f s (%d runs), %.1f frames/s, %.1f Mpixel/s%s\n",
               threads, threads == 1 ? "" : "s", med, runs, 1.0 / med, (double)w * h / med / 1e6,
               threads == 2 ? " (goal >= 10 frames/s)" : "");
    }
    btf__render_material_free(rm);
    btf_gpu_opts go = btf_gpu_defaults();
    go.allow_cpu = 1;
    btf_gpu *gpu = NULL;
    if (btf_gpu_open(&go, &gpu, &e) != 0) {
        printf("   GPU render: no Vulkan device (%s)\n", e.msg);
    } else {
        double pass[99], synth[99];
        btf_render_opts ro = btf_render_defaults();
        ro.width = w, ro.height = h, ro.texture_size = 512, ro.seed = 1;
        for (int r = 0; r < runs; r++) {
            btf_image img;
            btf_render_info info;
            if (btf_gpu_render_scene(gpu, &m, &s, &ro, &img, &info, &e))
                return bench_fail(&e);
            pass[r] = info.shade_s;
            synth[r] = info.synth_s;
            btf_image_free(&img);
        }
        const char *lp = getenv("LP_NUM_THREADS");
        double mp = tu_median(pass, runs);
        printf("   GPU render on %s%s%s: render pass median %.4f s (upload, shader, download), "
               "%.1f frames/s, %.1f x the CPU's 2-thread shading; synthesis pass %.3f s\n",
               btf_gpu_device_name(gpu), lp ? ", LP_NUM_THREADS=" : "", lp ? lp : "", mp,
               1.0 / mp, mp / cpu2, tu_median(synth, runs));
        btf_gpu_close(gpu);
    }
    free(need);
    btf__gbuffer_free(&g);
    btf_scene_free(&s);
    btf_model_free(&m);
    return 0;
}
