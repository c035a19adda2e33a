/*
 * bench_scene.c — ray casting speed (src/scene/, docs/scene.md): a
 * tessellated sphere of 114,688 triangles (written as OBJ, loaded through
 * assimp), its BVH build time and the rays per second of a 1024^2 G-buffer
 * on 1 and 2 threads (BVH build included in btf__scene_trace), against the
 * analytic sphere. Median of 3 runs; prints figures, never fails on time.
 */
#include "testutil.h"
#include "scene/scene.h"
#include "scene_sphere_obj.h"

#include <stdio.h>
#include <stdlib.h>

#define RUNS 3

static double trace_median(const btf_scene *s, int side, int threads)
{
    double t[RUNS];
    for (int r = 0; r < RUNS; r++) {
        btf_gbuffer g;
        btf_error err = {0};
        double t0 = tu_now();
        if (btf__scene_trace(s, side, side, threads, &g, &err)) {
            fprintf(stderr, "bench_scene: %s\n", err.msg);
            exit(1);
        }
        t[r] = tu_now() - t0;
        btf__gbuffer_free(&g);
    }
    return tu_median(t, RUNS);
}

int main(void)
{
    char *dir = tu_tmpdir();
    char obj[1024], json[1024];
    snprintf(obj, sizeof obj, "%s/sphere.obj", dir);
    snprintf(json, sizeof json, "%s/scene.json", dir);
    if (write_sphere_obj(obj, 224, 256)) {
        fprintf(stderr, "bench_scene: cannot write %s\n", obj);
        return 1;
    }
    FILE *f = fopen(json, "w");
    if (!f)
        return 1;
    fputs("{\"camera\": {\"position\": [0, 0.8, 4], \"target\": [0, 0, 0], \"fov\": 40},"
          " \"lights\": [{\"type\": \"directional\", \"direction\": [0, 0, 1]}],"
          " \"objects\": [{\"type\": \"mesh\", \"file\": \"sphere.obj\"}]}", f);
    fclose(f);
    btf_scene s;
    btf_error err = {0};
    double t0 = tu_now();
    if (btf_scene_load(json, &s, &err)) {
        fprintf(stderr, "bench_scene: %s\n", err.msg);
        return 1;
    }
    double t_load = tu_now() - t0;
    double tb[RUNS];
    for (int r = 0; r < RUNS; r++) {
        scene_bvh b;
        t0 = tu_now();
        if (scene_bvh_build(&s.objects[0].mesh, &b, &err))
            return 1;
        tb[r] = tu_now() - t0;
        if (r == 0)
            printf("scene: BVH of %d triangles: %d nodes\n", b.n_triangles, b.n_nodes);
        scene_bvh_free(&b);
    }
    printf("scene: OBJ load (assimp) %.3f s, BVH build median %.3f s\n", t_load,
           tu_median(tb, RUNS));
    const int side = 1024;
    for (int threads = 1; threads <= 2; threads++) {
        double t = trace_median(&s, side, threads);
        printf("scene: trace %dx%d mesh sphere, %d thread%s: %.3f s, %.2f Mrays/s\n", side, side,
               threads, threads > 1 ? "s" : "", t, side * (double)side / t * 1e-6);
    }
    btf_object sp = {.kind = BTF_OBJECT_SPHERE, .axis = {0, 1, 0}, .radius = 1.0,
                     .texture_scale = 256.0};
    btf_scene a = s;
    a.objects = &sp;
    for (int threads = 1; threads <= 2; threads++) {
        double t = trace_median(&a, side, threads);
        printf("scene: trace %dx%d analytic sphere, %d thread%s: %.3f s, %.2f Mrays/s\n", side,
               side, threads, threads > 1 ? "s" : "", t, side * (double)side / t * 1e-6);
    }
    btf_scene_free(&s);
    tu_rmtree(dir);
    free(dir);
    return 0;
}
