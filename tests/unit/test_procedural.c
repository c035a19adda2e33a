/*
 * test_procedural.c — the procedural materials (src/generate/material.c): every material
 * makes and renders at any size, deterministically, with periodic heights,
 * unit normals and finite images for every (view, light) pair; the images
 * behave like the physics they model (Lambertian falloff, cast shadows on the
 * fabric, a specular highlight on the wood at the mirror configuration); the
 * axis convention (y up in the image) holds for normals, lighting and
 * parallax. Prints the render time at 128^2 (never fails on time).
 */
#include "generate/material.h"
#include "testutil.h"
#include "core/core.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static const char *const names[] = {"leather", "fabric", "wood"};
#define N_NAMES 3

static btf_dir dir(double theta, double phi)
{
    btf_dir d = {theta, phi};
    return d;
}

static int all_finite(const float *p, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (!isfinite(p[i]))
            return 0;
    return 1;
}

static double image_mean(const btf_image *img)
{
    size_t n = (size_t)img->width * img->height * img->channels;
    double s = 0;
    for (size_t i = 0; i < n; i++)
        s += img->data[i];
    return s / (double)n;
}

static void make(const char *name, int size, uint64_t seed, btf_procedural *m)
{
    btf_error err = {0};
    TU_OK(btf_procedural_make(name, size, seed, m, &err), &err);
}

static void render(const btf_procedural *m, btf_dir v, btf_dir l, btf_image *img)
{
    btf_error err = {0};
    TU_OK(btf_procedural_render(m, v, l, img, &err), &err);
}

static void test_names(void **state)
{
    (void)state;
    const char *const *n = btf_procedural_names();
    assert_non_null(n);
    int count = 0;
    while (n[count])
        count++;
    assert_true(count >= 3);
    for (int i = 0; i < N_NAMES; i++) {
        int found = 0;
        for (int j = 0; j < count; j++)
            found |= !strcmp(n[j], names[i]);
        assert_true(found);
    }
}

static void test_sizes(void **state)
{
    (void)state;
    static const int sizes[] = {1, 2, 7, 64, 128, 256};
    static const btf_dir pairs[][2] = {{{0, 0}, {0, 0}}, {{45, 30}, {30, 200}},
                                       {{75, 345}, {75, 165}}, {{90, 10}, {90, 190}}};
    for (int i = 0; i < N_NAMES; i++) {
        for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++) {
            btf_procedural m;
            make(names[i], sizes[s], 7, &m);
            size_t n = (size_t)sizes[s] * sizes[s];
            assert_int_equal(m.size, sizes[s]);
            assert_string_equal(m.name, names[i]);
            assert_true(all_finite(m.height, n) && all_finite(m.normal, 3 * n) &&
                        all_finite(m.albedo, 3 * n));
            for (size_t p = 0; p < sizeof pairs / sizeof pairs[0]; p++) {
                btf_image img = {0};
                render(&m, pairs[p][0], pairs[p][1], &img);
                assert_int_equal(img.width, sizes[s]);
                assert_int_equal(img.height, sizes[s]);
                assert_int_equal(img.channels, 3);
                assert_true(all_finite(img.data, 3 * n));
                for (size_t k = 0; k < 3 * n; k++)
                    assert_true(img.data[k] >= 0.0f && img.data[k] < 4.0f);
                btf_image_free(&img);
            }
            btf_procedural_free(&m);
            assert_null(m.height);
        }
    }
}

static void test_deterministic(void **state)
{
    (void)state;
    for (int i = 0; i < N_NAMES; i++) {
        btf_procedural a, b, c;
        make(names[i], 33, 42, &a);
        make(names[i], 33, 42, &b);
        make(names[i], 33, 43, &c);
        size_t n = 33 * 33;
        assert_memory_equal(a.height, b.height, n * sizeof(float));
        assert_memory_equal(a.albedo, b.albedo, 3 * n * sizeof(float));
        assert_memory_equal(a.normal, b.normal, 3 * n * sizeof(float));
        assert_true(memcmp(a.albedo, c.albedo, 3 * n * sizeof(float)) != 0);
        btf_image ia = {0}, ib = {0}, ic = {0};
        render(&a, dir(45, 60), dir(60, 270), &ia);
        render(&b, dir(45, 60), dir(60, 270), &ib);
        render(&c, dir(45, 60), dir(60, 270), &ic);
        assert_memory_equal(ia.data, ib.data, 3 * n * sizeof(float));
        assert_true(memcmp(ia.data, ic.data, 3 * n * sizeof(float)) != 0);
        btf_image_free(&ia);
        btf_image_free(&ib);
        btf_image_free(&ic);
        btf_procedural_free(&a);
        btf_procedural_free(&b);
        btf_procedural_free(&c);
    }
}

/* The step across the tile's seam (last column to first, last row to first)
 * is no larger than the steps inside it: the height field continues. */
static void test_periodic(void **state)
{
    (void)state;
    static const int sizes[] = {64, 50};
    for (int i = 0; i < N_NAMES; i++) {
        for (int s = 0; s < 2; s++) {
            btf_procedural m;
            int n = sizes[s];
            make(names[i], n, 3, &m);
            const float *h = m.height;
            double inner = 0, seam = 0, sum = 0;
            for (int r = 0; r < n; r++) {
                for (int c = 0; c < n; c++) {
                    sum += h[r * n + c];
                    double dx = fabs(h[r * n + (c + 1) % n] - h[r * n + c]);
                    double dy = fabs(h[((r + 1) % n) * n + c] - h[r * n + c]);
                    if (c == n - 1)
                        seam = fmax(seam, dx);
                    else
                        inner = fmax(inner, dx);
                    if (r == n - 1)
                        seam = fmax(seam, dy);
                    else
                        inner = fmax(inner, dy);
                }
            }
            assert_true(seam <= inner + 1e-6);
            assert_true(fabs(sum / (n * n)) < 1e-4); /* zero mean: z = 0 is the reference */
            btf_procedural_free(&m);
        }
    }
}

static void test_unit_normals(void **state)
{
    (void)state;
    for (int i = 0; i < N_NAMES; i++) {
        btf_procedural m;
        make(names[i], 37, 1, &m);
        for (int k = 0; k < 37 * 37; k++) {
            const float *p = m.normal + 3 * k;
            double len = sqrt((double)p[0] * p[0] + (double)p[1] * p[1] + (double)p[2] * p[2]);
            assert_true(fabs(len - 1.0) < 1e-5);
            assert_true(p[2] > 0.0f);
        }
        btf_procedural_free(&m);
    }
}

/* Every one of the 81 x 81 pairs at size 8 is finite, and the map path gives
 * exactly what btf_procedural_render gives. */
static void test_all_pairs_finite(void **state)
{
    (void)state;
    btf_error err = {0};
    btf_dirset set;
    TU_OK(btf_dirset_ubo81(&set, &err), &err);
    assert_int_equal(set.count, 81);
    for (int i = 0; i < N_NAMES; i++) {
        btf_procedural m;
        make(names[i], 8, 11, &m);
        btf_view_map *vm[81];
        btf_light_map *lm[81];
        for (int d = 0; d < 81; d++) {
            TU_OK(btf__view_map_make(&m, set.dirs[d], &vm[d], &err), &err);
            TU_OK(btf__light_map_make(&m, set.dirs[d], &lm[d], &err), &err);
        }
        for (int v = 0; v < 81; v++) {
            for (int l = 0; l < 81; l++) {
                btf_image img = {0};
                TU_OK(btf__material_render_maps(&m, vm[v], lm[l], set.dirs[v], set.dirs[l], &img,
                                                &err),
                      &err);
                assert_true(all_finite(img.data, 3 * 64));
                if ((v * 81 + l) % 97 == 0 || (v == 80 && l == 80)) {
                    btf_image ref = {0};
                    render(&m, set.dirs[v], set.dirs[l], &ref);
                    assert_memory_equal(ref.data, img.data, 3 * 64 * sizeof(float));
                    btf_image_free(&ref);
                }
                btf_image_free(&img);
            }
        }
        for (int d = 0; d < 81; d++) {
            btf__view_map_free(vm[d]);
            btf__light_map_free(lm[d]);
        }
        btf_procedural_free(&m);
    }
    btf_dirset_free(&set);
}

static void test_lambert_falloff(void **state)
{
    (void)state;
    for (int i = 0; i < N_NAMES; i++) {
        btf_procedural m;
        make(names[i], 64, 5, &m);
        btf_image front = {0};
        render(&m, dir(0, 0), dir(0, 0), &front);
        for (double phi = 0; phi < 360; phi += 90) {
            btf_image graze = {0};
            render(&m, dir(0, 0), dir(75, phi), &graze);
            assert_true(image_mean(&front) > 1.5 * image_mean(&graze));
            btf_image_free(&graze);
        }
        btf_image_free(&front);
        btf_procedural_free(&m);
    }
}

static double shadow_fraction(const btf_procedural *m, btf_dir light)
{
    btf_error err = {0};
    btf_light_map *lm = NULL;
    TU_OK(btf__light_map_make(m, light, &lm, &err), &err);
    int n = m->size, dark = 0;
    for (int k = 0; k < n * n; k++)
        dark += lm->vis[k] < 0.5f;
    btf__light_map_free(lm);
    return (double)dark / (n * n);
}

/* The weave casts shadows at grazing light and none from above; the rendered
 * image shows them (pixels left with only the ambient term). */
static void test_fabric_shadows(void **state)
{
    (void)state;
    btf_procedural m;
    make("fabric", 64, 9, &m);
    double top = shadow_fraction(&m, dir(0, 0));
    double graze = shadow_fraction(&m, dir(75, 30));
    print_message("fabric: shadowed fraction %.3f at light theta 0, %.3f at 75\n", top, graze);
    assert_true(top == 0.0);
    assert_true(graze > 0.1);
    assert_true(shadow_fraction(&m, dir(45, 30)) > top);

    /* In the image: count pixels at most a little above the ambient level. */
    btf_image lo = {0}, hi = {0};
    render(&m, dir(0, 0), dir(0, 0), &hi);
    render(&m, dir(0, 0), dir(75, 30), &lo);
    int dark_hi = 0, dark_lo = 0;
    for (int k = 0; k < 64 * 64; k++) {
        float a = m.albedo[3 * k] + m.albedo[3 * k + 1] + m.albedo[3 * k + 2];
        float thr = (m.ambient + 0.02f) * a;
        dark_hi += hi.data[3 * k] + hi.data[3 * k + 1] + hi.data[3 * k + 2] <= thr;
        dark_lo += lo.data[3 * k] + lo.data[3 * k + 1] + lo.data[3 * k + 2] <= thr;
    }
    assert_true(dark_lo > dark_hi + 64 * 64 / 20);
    btf_image_free(&lo);
    btf_image_free(&hi);
    btf_procedural_free(&m);
}

static void test_wood_specular(void **state)
{
    (void)state;
    btf_procedural m;
    make("wood", 64, 2, &m);
    btf_image mirror = {0}, retro = {0}, side = {0}, graze = {0};
    render(&m, dir(30, 0), dir(30, 180), &mirror);
    render(&m, dir(30, 0), dir(30, 0), &retro);
    render(&m, dir(30, 0), dir(30, 90), &side);
    render(&m, dir(75, 0), dir(75, 180), &graze);
    double mm = image_mean(&mirror), mr = image_mean(&retro), ms = image_mean(&side);
    print_message("wood: mean %.3f at the mirror pair, %.3f retro, %.3f side, %.3f grazing "
                  "mirror\n", mm, mr, ms, image_mean(&graze));
    assert_true(mm > 1.3 * mr);
    assert_true(mm > 1.3 * ms);
    /* Fresnel: the coat's highlight grows towards grazing. */
    assert_true(image_mean(&graze) > mm);
    btf_image_free(&mirror);
    btf_image_free(&retro);
    btf_image_free(&side);
    btf_image_free(&graze);
    btf_procedural_free(&m);
}

/* A hand-made material: a Gaussian bump of height 4 at (16, 16) on flat
 * ground z = 0, albedo 1 on the bump's top and 0.1 elsewhere. */
static void bump_material(btf_procedural *m, float *store)
{
    const int n = 32;
    memset(m, 0, sizeof *m);
    snprintf(m->name, sizeof m->name, "bump");
    m->size = n;
    m->height = store;
    m->normal = store + n * n;
    m->albedo = store + 4 * n * n;
    for (int r = 0; r < n; r++) {
        for (int c = 0; c < n; c++) {
            double d2 = (r - 16.0) * (r - 16.0) + (c - 16.0) * (c - 16.0);
            float h = (float)(4.0 * exp(-d2 / (2 * 9.0)));
            m->height[r * n + c] = h;
            for (int k = 0; k < 3; k++)
                m->albedo[3 * (r * n + c) + k] = h > 2.5f ? 1.0f : 0.1f;
        }
    }
    btf__material_normals_from_height(m);
}

static void bright_centroid(const btf_image *img, double *cx, double *cy)
{
    double sx = 0, sy = 0, w = 0;
    for (int r = 0; r < img->height; r++)
        for (int c = 0; c < img->width; c++)
            if (img->data[3 * (r * img->width + c)] > 0.5f) {
                sx += c;
                sy += r;
                w += 1;
            }
    assert_true(w > 0);
    *cx = sx / w;
    *cy = sy / w;
}

static void test_axis_convention(void **state)
{
    (void)state;
    float *store = malloc(32 * 32 * 7 * sizeof(float));
    assert_non_null(store);
    btf_procedural m;
    bump_material(&m, store);
    /* Normals: y up in the image, so above the bump's centre n.y > 0. */
    assert_true(m.normal[3 * (12 * 32 + 16) + 1] > 0.1f);
    assert_true(m.normal[3 * (20 * 32 + 16) + 1] < -0.1f);
    assert_true(m.normal[3 * (16 * 32 + 20)] > 0.1f);

    /* Lighting: a light at phi = 90 comes from the top of the image. */
    btf_image img = {0};
    render(&m, dir(0, 0), dir(60, 90), &img);
    assert_true(img.data[3 * (12 * 32 + 16)] > img.data[3 * (20 * 32 + 16)] + 0.02f);
    btf_image_free(&img);

    /* Parallax: raised points appear shifted away from the camera. */
    double cx, cy;
    render(&m, dir(0, 0), dir(0, 0), &img);
    bright_centroid(&img, &cx, &cy);
    assert_true(fabs(cx - 16) < 0.5 && fabs(cy - 16) < 0.5);
    btf_image_free(&img);
    render(&m, dir(60, 0), dir(0, 0), &img); /* camera towards +x (right) */
    bright_centroid(&img, &cx, &cy);
    assert_true(cx < 12 && fabs(cy - 16) < 0.5);
    btf_image_free(&img);
    render(&m, dir(60, 90), dir(0, 0), &img); /* camera towards +y (image top) */
    bright_centroid(&img, &cx, &cy);
    assert_true(cy > 20 && fabs(cx - 16) < 0.5);
    btf_image_free(&img);

    /* A cast shadow of the bump, lit from the right, falls to its left. */
    btf_light_map *lm = NULL;
    btf_error err = {0};
    TU_OK(btf__light_map_make(&m, dir(75, 0), &lm, &err), &err);
    assert_true(lm->vis[16 * 32 + 8] < 0.5f);
    assert_true(lm->vis[16 * 32 + 26] > 0.99f);
    btf__light_map_free(lm);
    free(store);
}

static void test_errors(void **state)
{
    (void)state;
    btf_error err = {0};
    btf_procedural m;
    assert_int_equal(btf_procedural_make("velvet", 16, 0, &m, &err), BTF_E_ARG);
    assert_int_equal(err.code, BTF_E_ARG);
    assert_non_null(strstr(err.msg, "velvet"));
    assert_null(m.height);
    assert_int_equal(btf_procedural_make(NULL, 16, 0, &m, &err), BTF_E_ARG);
    assert_int_equal(btf_procedural_make("wood", 0, 0, &m, &err), BTF_E_ARG);
    assert_non_null(strstr(err.msg, "0"));
    assert_int_equal(btf_procedural_make("wood", -5, 0, &m, &err), BTF_E_ARG);
    assert_int_equal(btf_procedural_make("wood", 16, 0, NULL, &err), BTF_E_ARG);
    btf_procedural_free(NULL);

    make("wood", 8, 0, &m);
    btf_image img = {0};
    assert_int_equal(btf_procedural_render(&m, dir(95, 0), dir(0, 0), &img, &err), BTF_E_ARG);
    assert_non_null(strstr(err.msg, "view"));
    assert_int_equal(btf_procedural_render(&m, dir(0, 0), dir(NAN, 0), &img, &err), BTF_E_ARG);
    assert_non_null(strstr(err.msg, "light"));
    assert_int_equal(btf_procedural_render(&m, dir(0, 0), dir(-1, 0), &img, &err), BTF_E_ARG);
    assert_int_equal(btf_procedural_render(&m, dir(0, INFINITY), dir(0, 0), &img, &err),
                     BTF_E_ARG);
    assert_null(img.data);
    assert_int_equal(btf_procedural_render(NULL, dir(0, 0), dir(0, 0), &img, &err), BTF_E_ARG);

    /* Maps of another size are refused. */
    btf_procedural big;
    make("wood", 9, 0, &big);
    btf_view_map *vm = NULL;
    btf_light_map *lm = NULL;
    TU_OK(btf__view_map_make(&big, dir(0, 0), &vm, &err), &err);
    TU_OK(btf__light_map_make(&m, dir(0, 0), &lm, &err), &err);
    assert_int_equal(btf__material_render_maps(&m, vm, lm, dir(0, 0), dir(0, 0), &img, &err),
                     BTF_E_ARG);
    btf__view_map_free(vm);
    btf__light_map_free(lm);
    btf_procedural_free(&big);

    /* A non-finite height is reported, not marched. */
    m.height[3] = NAN;
    assert_int_equal(btf__view_map_make(&m, dir(30, 0), &vm, &err), BTF_E_DATA);
    assert_null(vm);
    btf_procedural_free(&m);
}

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* Timing at 128^2 (printed, not asserted): btf_procedural_render over the 81
 * view rings x a few lights, and the per-pair cost once maps exist. */
static void test_timing(void **state)
{
    (void)state;
    btf_error err = {0};
    btf_dirset set;
    TU_OK(btf_dirset_ubo81(&set, &err), &err);
    for (int i = 0; i < N_NAMES; i++) {
        btf_procedural m;
        double t0 = now();
        make(names[i], 128, 1, &m);
        double t_make = now() - t0;
        int count = 0;
        t0 = now();
        for (int v = 0; v < 81; v += 4) {
            btf_image img = {0};
            render(&m, set.dirs[v], set.dirs[(v * 7) % 81], &img);
            btf_image_free(&img);
            count++;
        }
        double t_render = (now() - t0) / count;
        btf_image img = {0};
        t0 = now();
        render(&m, dir(75, 0), dir(75, 90), &img);
        double t_worst = now() - t0;
        btf_image_free(&img);
        btf_view_map *vm = NULL;
        btf_light_map *lm = NULL;
        TU_OK(btf__view_map_make(&m, dir(45, 30), &vm, &err), &err);
        TU_OK(btf__light_map_make(&m, dir(60, 120), &lm, &err), &err);
        t0 = now();
        for (int k = 0; k < 50; k++) {
            TU_OK(btf__material_render_maps(&m, vm, lm, dir(45, 30), dir(60, 120), &img, &err),
                  &err);
            btf_image_free(&img);
        }
        double t_maps = (now() - t0) / 50;
        print_message("%-8s 128^2: make %.1f ms, render %.2f ms (mean), %.2f ms (75/75), "
                      "render_maps %.3f ms\n",
                      names[i], 1e3 * t_make, 1e3 * t_render, 1e3 * t_worst, 1e3 * t_maps);
        btf__view_map_free(vm);
        btf__light_map_free(lm);
        btf_procedural_free(&m);
    }
    btf_dirset_free(&set);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_names),
        cmocka_unit_test(test_sizes),
        cmocka_unit_test(test_deterministic),
        cmocka_unit_test(test_periodic),
        cmocka_unit_test(test_unit_normals),
        cmocka_unit_test(test_all_pairs_finite),
        cmocka_unit_test(test_lambert_falloff),
        cmocka_unit_test(test_fabric_shadows),
        cmocka_unit_test(test_wood_specular),
        cmocka_unit_test(test_axis_convention),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_timing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
