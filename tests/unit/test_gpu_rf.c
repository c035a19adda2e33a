/*
 * test_gpu_rf.c — the GPU render pass of reflectance-field models
 * (gpu/rf_render_gpu.c, gpu/rf_render.comp; docs/rf.md, "Rendering on the
 * GPU") against the CPU renders (src/rf/), on lavapipe with the Khronos
 * validation layer on; any validation message fails the test.
 *
 * Both paths evaluate src/rf/btf_rf_shared.h, so what may differ is the
 * rounding of sqrt and division on a device that does not round them as
 * IEEE 754 does. The stated tolerance: every channel within 1e-5 of the
 * image's range plus 1e-5 relative, except at most 0.1 % of the pixels
 * (where a rounding moves a texel or a view's ring); the test prints the
 * measured figures. On lavapipe (the CPU's own IEEE sqrt and division) the
 * two are bit for bit the same, and there the test requires it.
 *
 * The models are built here (every fit: PTM, lobes with k = 2 and 4,
 * Lafortune; random codes over parameter ranges that reach the clamps),
 * and one with ranges of +-1e30 (a damaged but CRC-valid file); renders at
 * the extremes: the view on the pole and on the horizon, past the last
 * ring, the light at grazing angles and on the horizon, 1 x 1 frames.
 */
#include "testutil.h"
#include "synth/synth_testing.h" /* btf__gpu_set_max_buffer_bytes */
#include "rf/rf.h"
#include "synth_gpu.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static btf_gpu *gpu;

static int setup(void **state)
{
    (void)state;
    return tu_gpu_open(&gpu, "test_gpu_rf");
}

static int teardown(void **state)
{
    (void)state;
    btf_gpu_close(gpu);
    return 0;
}

/* A small deterministic generator (xorshift32). */
static uint32_t next(uint32_t *s)
{
    *s ^= *s << 13, *s ^= *s >> 17, *s ^= *s << 5;
    return *s;
}

/* The range [lo, hi] of slot s of a fit (per field a little different). */
static void slot_range(int fit, int s, int params, int f, float *lo, float *hi)
{
    float d = 0.01f * (float)(f % 7);
    if (s >= params) { /* chromaticity */
        *lo = 0.5f + d, *hi = 1.5f;
        return;
    }
    if (fit == BTF_RF_PTM) {
        *lo = s == 5 ? 0.1f : -0.5f - d, *hi = s == 5 ? 0.6f : 0.5f;
    } else if (fit == BTF_RF_LOBES) {
        int k = s % 4; /* rho, x, y, log2 n: x, y and n reach past the box */
        *lo = k == 0 ? 0.0f : k == 3 ? -3.0f : -20.0f;
        *hi = k == 0 ? 2.0f + d : k == 3 ? 11.0f : 20.0f;
    } else {
        int k = s == 0 ? -1 : (s - 1) % 5; /* rho_d, then rho, cx, cy, cz, log2 n */
        *lo = k == -1 || k == 0 ? 0.0f : k == 4 ? -3.0f : -1.5f;
        *hi = k == -1 ? 1.0f : k == 0 ? 3.0f : k == 4 ? 11.0f : 1.5f;
    }
}

/* A model of fit with k lobes, w x h texels, random codes; wild: every
 * range +-1e30. */
static void make_model(btf_rf_model *m, int fit, int k, int w, int h, uint32_t seed, int wild)
{
    btf_error e = {0};
    memset(m, 0, sizeof *m);
    TU_OK(btf_dirset_ubo81(&m->views, &e), &e);
    TU_OK(btf_dirset_ubo81(&m->lights, &e), &e);
    m->fit = fit, m->lobes = fit == BTF_RF_PTM ? 0 : k;
    m->width = w, m->height = h;
    m->params = btf__rf_param_count(fit, m->lobes);
    m->slots = m->params + 3;
    m->fields = fit == BTF_RF_LAFORTUNE ? 1 : m->views.count;
    size_t planes = (size_t)m->fields * m->slots, codes = planes * w * h;
    m->lo = malloc(planes * sizeof(float));
    m->hi = malloc(planes * sizeof(float));
    m->codes = malloc(codes * sizeof(uint16_t));
    assert_non_null(m->codes);
    for (int f = 0; f < m->fields; f++)
        for (int s = 0; s < m->slots; s++) {
            float *lo = m->lo + (size_t)f * m->slots + s, *hi = m->hi + (size_t)f * m->slots + s;
            slot_range(fit, s, m->params, f, lo, hi);
            if (wild)
                *lo = -1e30f, *hi = 1e30f;
        }
    uint32_t st = seed | 1u;
    for (size_t i = 0; i < codes; i++)
        m->codes[i] = (uint16_t)(next(&st) >> 16);
}

/* Compares a CPU and a GPU image: finite and non-negative both, and bit
 * for bit on lavapipe, else within the stated tolerance. */
static void compare(const char *what, const btf_image *c, const btf_image *g)
{
    assert_int_equal(c->width, g->width);
    assert_int_equal(c->height, g->height);
    size_t n = (size_t)c->width * c->height;
    float lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < 3 * n; i++) {
        assert_true(isfinite(c->data[i]) && c->data[i] >= 0.0f);
        assert_true(isfinite(g->data[i]) && g->data[i] >= 0.0f);
        lo = fminf(lo, c->data[i]);
        hi = fmaxf(hi, c->data[i]);
    }
    double range = hi > lo ? hi - lo : 1.0, worst = 0.0;
    size_t beyond = 0, equal = 0;
    for (size_t p = 0; p < n; p++) {
        double d = 0.0, tol = 0.0;
        for (int k = 0; k < 3; k++) {
            double a = c->data[3 * p + k], b = g->data[3 * p + k];
            d = fmax(d, fabs(a - b));
            tol = fmax(tol, 1e-5 * range + 1e-5 * fabs(a));
        }
        worst = fmax(worst, d / range);
        beyond += d > tol;
        equal += memcmp(c->data + 3 * p, g->data + 3 * p, 3 * sizeof(float)) == 0;
    }
    print_message("%s: max |cpu - gpu| %.3g of the range, %zu of %zu pixels beyond the "
                  "tolerance, %zu bit-identical\n", what, worst, beyond, n, equal);
    assert_true((double)beyond <= 0.001 * (double)n);
    if (btf__gpu_is_cpu(gpu))
        assert_int_equal(equal, n);
}

/* The fits the tests run: PTM, lobes k = 2 and k = 4, Lafortune k = 2. */
static const int fits[][2] = {{BTF_RF_PTM, 0}, {BTF_RF_LOBES, 2}, {BTF_RF_LOBES, 4},
                              {BTF_RF_LAFORTUNE, 2}};
#define NFITS (sizeof fits / sizeof fits[0])

static void flat_parity_every_fit(void **state)
{
    (void)state;
    /* views: measured, between rings, the pole, past the last ring, the
     * horizon; lights: measured, grazing (89.9), on the horizon, the pole */
    const btf_dir pairs[][2] = {{{30, 60}, {45, 0}},     {{37.5, 100}, {45, 20}},
                                {{0, 0}, {70, 200}},     {{0, 123}, {0, 0}},
                                {{82, 350}, {89.9, 10}}, {{90, 33}, {90, 200}},
                                {{62, 17}, {89.99, 300}}};
    const int sizes[][2] = {{0, 0}, {1, 1}, {40, 23}, {7, 5}};
    btf_error e = {0};
    for (size_t f = 0; f < NFITS; f++) {
        btf_rf_model m;
        make_model(&m, fits[f][0], fits[f][1], 13, 11, 7u + (uint32_t)f, 0);
        for (size_t i = 0; i < sizeof pairs / sizeof pairs[0]; i++)
            for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++) {
                btf_image c = {0}, g = {0};
                btf_render_info info;
                TU_OK(btf__rf_render_flat(&m, pairs[i][0], pairs[i][1], sizes[s][0],
                                          sizes[s][1], 2, &c, &e), &e);
                TU_OK(btf__gpu_rf_render_flat(gpu, &m, pairs[i][0], pairs[i][1], sizes[s][0],
                                              sizes[s][1], &g, &info, &e), &e);
                assert_true(info.shade_s >= 0.0 && info.synth_s >= 0.0);
                if (s == 0 || s == 2)
                    compare(tu_fmt("%s k %d, flat %dx%d, view %g,%g light %g,%g",
                                   btf_rf_fit_name(m.fit), m.lobes, c.width, c.height,
                                   pairs[i][0].theta, pairs[i][0].phi, pairs[i][1].theta,
                                   pairs[i][1].phi), &c, &g);
                else
                    compare("", &c, &g);
                btf_image_free(&c);
                btf_image_free(&g);
            }
        btf_rf_model_free(&m);
    }
    tu_gpu_no_validation_messages(gpu);
}

static void sphere_scene(btf_scene *s)
{
    memset(s, 0, sizeof *s);
    s->camera = (btf_camera){{0, 0, 4}, {0, 0, 0}, {0, 1, 0}, 40};
    s->n_lights = 3;
    s->lights = calloc(3, sizeof *s->lights);
    s->lights[0] = (btf_light){.kind = BTF_LIGHT_DIRECTIONAL,
                               .direction = {0.57735, 0.57735, 0.57735}, .rgb = {1, 0.9f, 0.8f}};
    s->lights[1] = (btf_light){.kind = BTF_LIGHT_POINT, .position = {-3, 1, 3},
                               .rgb = {6, 6, 6}};
    /* from the side: grazing over much of the sphere */
    s->lights[2] = (btf_light){.kind = BTF_LIGHT_DIRECTIONAL, .direction = {0.99995, 0, 0.0099995},
                               .rgb = {0.5f, 0.5f, 0.5f}};
    s->n_objects = 1;
    s->objects = calloc(1, sizeof *s->objects);
    s->objects[0] = (btf_object){.kind = BTF_OBJECT_SPHERE, .center = {0, 0, 0}, .radius = 1,
                                 .axis = {0, 1, 0}, .texture_scale = 9.5};
    s->background[0] = 0.1f;
    s->background[2] = 0.3f;
}

/* A sphere (every view from the pole to the horizon at its limb, lights
 * from head-on to grazing) with every fit; the 1 x 1 frame too. */
static void sphere_parity_every_fit(void **state)
{
    (void)state;
    btf_scene s;
    sphere_scene(&s);
    btf_error e = {0};
    for (size_t f = 0; f < NFITS; f++) {
        btf_rf_model m;
        make_model(&m, fits[f][0], fits[f][1], 13, 11, 31u + (uint32_t)f, 0);
        btf_image c = {0}, g = {0};
        btf_render_info info;
        TU_OK(btf__rf_render_scene(&m, &s, 96, 80, 2, &c, NULL, &e), &e);
        TU_OK(btf__gpu_rf_render_scene(gpu, &m, &s, 96, 80, 2, &g, &info, &e), &e);
        assert_true(info.trace_s >= 0.0 && info.shade_s >= 0.0);
        compare(tu_fmt("%s k %d, sphere 96x80, three lights", btf_rf_fit_name(m.fit), m.lobes),
                &c, &g);
        /* a background pixel is the background */
        assert_true(g.data[0] == 0.1f && g.data[1] == 0.0f && g.data[2] == 0.3f);
        btf_image_free(&c);
        btf_image_free(&g);
        TU_OK(btf__rf_render_scene(&m, &s, 1, 1, 1, &c, NULL, &e), &e);
        TU_OK(btf__gpu_rf_render_scene(gpu, &m, &s, 1, 1, 1, &g, NULL, &e), &e);
        compare("", &c, &g);
        btf_image_free(&c);
        btf_image_free(&g);
        btf_rf_model_free(&m);
    }
    btf_scene_free(&s);
    tu_gpu_no_validation_messages(gpu);
}

/* A plane seen at grazing angles: views from the pole to 89.9 degrees
 * over the frame, a light skimming it at 89.5 degrees. */
static void grazing_plane(void **state)
{
    (void)state;
    btf_scene s;
    memset(&s, 0, sizeof s);
    s.camera = (btf_camera){{0, -0.02, 1.0}, {0, 40, 0}, {0, 0, 1}, 60};
    s.n_lights = 1;
    s.lights = calloc(1, sizeof *s.lights);
    double a = 89.5 * M_PI / 180.0;
    s.lights[0] = (btf_light){.kind = BTF_LIGHT_DIRECTIONAL,
                              .direction = {0.0, sin(a), cos(a)}, .rgb = {1, 1, 1}};
    s.n_objects = 1;
    s.objects = calloc(1, sizeof *s.objects);
    s.objects[0] = (btf_object){.kind = BTF_OBJECT_PLANE, .center = {0, 0, 0},
                                .axis = {0, 0, 1}, .size = 400, .texture_scale = 3};
    btf_error e = {0};
    for (size_t f = 0; f < NFITS; f++) {
        btf_rf_model m;
        make_model(&m, fits[f][0], fits[f][1], 9, 9, 77u + (uint32_t)f, 0);
        btf_image c = {0}, g = {0};
        TU_OK(btf__rf_render_scene(&m, &s, 64, 48, 2, &c, NULL, &e), &e);
        TU_OK(btf__gpu_rf_render_scene(gpu, &m, &s, 64, 48, 2, &g, NULL, &e), &e);
        compare(tu_fmt("%s k %d, grazing plane", btf_rf_fit_name(m.fit), m.lobes), &c, &g);
        btf_image_free(&c);
        btf_image_free(&g);
        btf_rf_model_free(&m);
    }
    btf_scene_free(&s);
    tu_gpu_no_validation_messages(gpu);
}

/* Ranges of +-1e30 (a damaged but CRC-valid file): every value is clamped
 * into the box, so both paths stay finite (and equal). */
static void wild_ranges_stay_finite(void **state)
{
    (void)state;
    btf_scene s;
    sphere_scene(&s);
    btf_error e = {0};
    for (size_t f = 0; f < NFITS; f++) {
        btf_rf_model m;
        make_model(&m, fits[f][0], fits[f][1], 5, 4, 99u + (uint32_t)f, 1);
        btf_image c = {0}, g = {0};
        TU_OK(btf__rf_render_flat(&m, (btf_dir){37.5, 100}, (btf_dir){89.9, 20}, 0, 0, 1, &c,
                                  &e), &e);
        TU_OK(btf__gpu_rf_render_flat(gpu, &m, (btf_dir){37.5, 100}, (btf_dir){89.9, 20}, 0, 0,
                                      &g, NULL, &e), &e);
        compare("", &c, &g);
        btf_image_free(&c);
        btf_image_free(&g);
        TU_OK(btf__rf_render_scene(&m, &s, 32, 24, 1, &c, NULL, &e), &e);
        TU_OK(btf__gpu_rf_render_scene(gpu, &m, &s, 32, 24, 1, &g, NULL, &e), &e);
        compare(tu_fmt("%s k %d, ranges of 1e30", btf_rf_fit_name(m.fit), m.lobes), &c, &g);
        btf_image_free(&c);
        btf_image_free(&g);
        btf_rf_model_free(&m);
    }
    btf_scene_free(&s);
    tu_gpu_no_validation_messages(gpu);
}

/* Small device buffers (the limit lowered for the test): the codes spread
 * over several buffers and the frame and the tile go in bands, with the
 * same pixels (a flat render's tile is always smaller than its fields'
 * codes, so it never needs bands); below one field per buffer, or beyond
 * four buffers, a
 * one-line error, and the device still works. */
static void buffers_and_bands(void **state)
{
    (void)state;
    btf_rf_model m;
    make_model(&m, BTF_RF_LOBES, 2, 16, 16, 5u, 0); /* 81 fields of 16 x 16 x 11 x 2 bytes */
    btf_scene s;
    sphere_scene(&s);
    btf_error e = {0};
    btf_image one = {0}, banded = {0}, t1 = {0}, t2 = {0};
    TU_OK(btf__gpu_rf_render_scene(gpu, &m, &s, 80, 60, 2, &one, NULL, &e), &e);
    TU_OK(btf__gpu_rf_render_flat(gpu, &m, (btf_dir){40, 10}, (btf_dir){30, 250}, 0, 0, &t1,
                                  NULL, &e), &e);
    /* 200 KB: 35 fields of 5.6 KB a buffer (3 buffers), G-buffer bands of
     * 34 rows */
    btf__gpu_set_max_buffer_bytes(gpu, 200000);
    TU_OK(btf__gpu_rf_render_scene(gpu, &m, &s, 80, 60, 2, &banded, NULL, &e), &e);
    /* 70 KB: 12 fields a buffer, the 81 fields over 7 buffers (bindings 8 on) */
    btf_image seven = {0};
    btf__gpu_set_max_buffer_bytes(gpu, 70000);
    TU_OK(btf__gpu_rf_render_scene(gpu, &m, &s, 80, 60, 2, &seven, NULL, &e), &e);
    assert_memory_equal(one.data, seven.data, (size_t)80 * 60 * 3 * sizeof(float));
    btf_image_free(&seven);
    btf__gpu_set_max_buffer_bytes(gpu, 1200);
    btf_rf_model small;
    make_model(&small, BTF_RF_PTM, 0, 16, 16, 5u, 0); /* a field: 16 x 16 x 9 x 2 = 4.6 KB */
    int rc = btf__gpu_rf_render_flat(gpu, &small, (btf_dir){40, 10}, (btf_dir){30, 250}, 0, 0,
                                     &t2, NULL, &e);
    assert_int_equal(rc, BTF_E_UNSUPPORTED); /* a field is larger than a buffer */
    assert_null(strchr(e.msg, '\n'));
    assert_non_null(strstr(e.msg, "--backend cpu"));
    assert_null(t2.data);
    btf__gpu_set_max_buffer_bytes(gpu, 6000); /* one field a buffer: the flat render's 4 fit */
    TU_OK(btf__gpu_rf_render_flat(gpu, &m, (btf_dir){40, 10}, (btf_dir){30, 250}, 0, 0, &t2,
                                  NULL, &e), &e);
    btf_image img = {0};
    rc = btf__gpu_rf_render_scene(gpu, &m, &s, 8, 8, 1, &img, NULL, &e); /* 81 > 8 buffers */
    assert_int_equal(rc, BTF_E_UNSUPPORTED);
    assert_null(strchr(e.msg, '\n'));
    assert_null(img.data);
    btf__gpu_set_max_buffer_bytes(gpu, 0);
    assert_memory_equal(one.data, banded.data, (size_t)80 * 60 * 3 * sizeof(float));
    assert_memory_equal(t1.data, t2.data, (size_t)16 * 16 * 3 * sizeof(float));
    TU_OK(btf__gpu_rf_render_scene(gpu, &m, &s, 8, 8, 1, &img, NULL, &e), &e);
    btf_image_free(&img);
    btf_image_free(&one);
    btf_image_free(&banded);
    btf_image_free(&t1);
    btf_image_free(&t2);
    btf_rf_model_free(&m);
    btf_rf_model_free(&small);
    btf_scene_free(&s);
    tu_gpu_no_validation_messages(gpu);
}

/* A sampled model (paper section 6): a 7 x 5 surface over a 4 x 4 model
 * through a hand-made coordinate map with varied entries, some out of the
 * sample (u or v >= 4, up to 65535: clamped into it, rf_map.h); flat
 * renders smaller than, equal to and larger than the surface, and a
 * sphere, GPU against CPU, for every fit. */
static void sampled_parity(void **state)
{
    (void)state;
    enum { SW = 7, SH = 5 };
    uint16_t map[2 * SW * SH];
    uint32_t st = 99u;
    for (int i = 0; i < SW * SH; i++) {
        uint32_t r = next(&st);
        map[2 * i] = (uint16_t)((i * 3 + 1) % 5), map[2 * i + 1] = (uint16_t)(r % 5);
        if (i % 6 == 2)
            map[2 * i] = (uint16_t)(4 + r % 60000);
        if (i % 7 == 3)
            map[2 * i + 1] = 65535;
    }
    btf_scene s;
    sphere_scene(&s);
    const int sizes[][2] = {{0, 0}, {1, 1}, {3, 2}, {7, 5}, {6, 9}, {40, 23}};
    const btf_dir pairs[][2] = {{{30, 60}, {45, 0}}, {{82, 350}, {89.9, 10}}};
    btf_error e = {0};
    for (size_t f = 0; f < NFITS; f++) {
        btf_rf_model m;
        make_model(&m, fits[f][0], fits[f][1], 4, 4, 57u + (uint32_t)f, 0);
        m.map = map, m.surface_width = SW, m.surface_height = SH;
        for (size_t i = 0; i < sizeof pairs / sizeof pairs[0]; i++)
            for (size_t z = 0; z < sizeof sizes / sizeof sizes[0]; z++) {
                btf_image c = {0}, g = {0};
                TU_OK(btf__rf_render_flat(&m, pairs[i][0], pairs[i][1], sizes[z][0],
                                          sizes[z][1], 2, &c, &e), &e);
                TU_OK(btf__gpu_rf_render_flat(gpu, &m, pairs[i][0], pairs[i][1], sizes[z][0],
                                              sizes[z][1], &g, NULL, &e), &e);
                if (z == 0) {
                    assert_int_equal(g.width, SW);
                    assert_int_equal(g.height, SH);
                }
                compare(z == 5 ? tu_fmt("sampled %s k %d, flat %dx%d of a %dx%d surface",
                                        btf_rf_fit_name(m.fit), m.lobes, c.width, c.height,
                                        SW, SH)
                               : "", &c, &g);
                btf_image_free(&c);
                btf_image_free(&g);
            }
        btf_image c = {0}, g = {0};
        TU_OK(btf__rf_render_scene(&m, &s, 96, 80, 2, &c, NULL, &e), &e);
        TU_OK(btf__gpu_rf_render_scene(gpu, &m, &s, 96, 80, 2, &g, NULL, &e), &e);
        compare(tu_fmt("sampled %s k %d, sphere 96x80", btf_rf_fit_name(m.fit), m.lobes), &c,
                &g);
        btf_image_free(&c);
        btf_image_free(&g);
        m.map = NULL, m.surface_width = m.surface_height = 0;
        btf_rf_model_free(&m);
    }
    btf_scene_free(&s);
    tu_gpu_no_validation_messages(gpu);
}

/* Bad input: one-line BTF_E_ARG, the output left empty. */
static void bad_input(void **state)
{
    (void)state;
    btf_rf_model m;
    make_model(&m, BTF_RF_PTM, 0, 4, 4, 1u, 0);
    btf_scene s;
    sphere_scene(&s);
    btf_error e = {0};
    btf_image img;
    btf_dir v = {10, 0}, l = {30, 90};
    assert_int_equal(btf__gpu_rf_render_flat(NULL, &m, v, l, 4, 4, &img, NULL, &e), BTF_E_ARG);
    assert_null(img.data);
    assert_int_equal(btf__gpu_rf_render_flat(gpu, NULL, v, l, 4, 4, &img, NULL, &e), BTF_E_ARG);
    assert_int_equal(btf__gpu_rf_render_flat(gpu, &m, (btf_dir){91, 0}, l, 4, 4, &img, NULL, &e),
                     BTF_E_ARG);
    assert_int_equal(btf__gpu_rf_render_flat(gpu, &m, v, (btf_dir){10, NAN}, 4, 4, &img, NULL,
                                             &e), BTF_E_ARG);
    assert_int_equal(btf__gpu_rf_render_flat(gpu, &m, v, l, -1, 4, &img, NULL, &e), BTF_E_ARG);
    assert_int_equal(btf__gpu_rf_render_scene(gpu, &m, NULL, 8, 8, 1, &img, NULL, &e), BTF_E_ARG);
    assert_int_equal(btf__gpu_rf_render_scene(gpu, &m, &s, 8, BTF_RENDER_MAX_SIDE + 1, 1, &img,
                                              NULL, &e), BTF_E_ARG);
    m.slots = 30; /* inconsistent: not params + 3 */
    assert_int_equal(btf__gpu_rf_render_scene(gpu, &m, &s, 8, 8, 1, &img, NULL, &e), BTF_E_ARG);
    assert_null(strchr(e.msg, '\n'));
    assert_null(img.data);
    m.slots = m.params + 3;
    /* a sampled model's surface of 0 sides: refused, not read */
    uint16_t map1[2] = {0, 0};
    m.map = map1, m.surface_width = 0, m.surface_height = 1;
    assert_int_equal(btf__gpu_rf_render_flat(gpu, &m, v, l, 4, 4, &img, NULL, &e), BTF_E_ARG);
    assert_int_equal(btf__gpu_rf_render_scene(gpu, &m, &s, 8, 8, 1, &img, NULL, &e), BTF_E_ARG);
    assert_null(strchr(e.msg, '\n'));
    assert_null(img.data);
    m.map = NULL, m.surface_width = m.surface_height = 0;
    btf_rf_model_free(&m);
    btf_scene_free(&s);
    tu_gpu_no_validation_messages(gpu);
}

/* The command: --backend gpu (validation on) renders what --backend cpu
 * renders, flat and a scene; auto takes the CPU where the only device is
 * lavapipe; --texture-size is a usage error with an RF model. */
static void command_line(void **state)
{
    (void)state;
    char *dir = tu_tmpdir();
    btf_rf_model m;
    make_model(&m, BTF_RF_LOBES, 2, 12, 12, 3u, 0);
    btf_error e = {0};
    char *mp = strdup(tu_fmt("%s/rf.btfcar", dir));
    TU_OK(btf_rf_write(mp, &m, &e), &e);
    btf_rf_model_free(&m);
    const char *validate = getenv("BTF_ASAN") ? "" : "BTF_VK_VALIDATION=1";
    const char *scene = "{\"camera\": {\"position\": [0, 0, 4], \"target\": [0, 0, 0], "
                        "\"fov\": 40}, \"lights\": [{\"type\": \"directional\", "
                        "\"direction\": [0.3, 0.5, 1]}], \"objects\": [{\"type\": \"sphere\", "
                        "\"radius\": 1, \"texture_scale\": 12}]}";
    char *json = strdup(tu_fmt("%s/s.json", dir));
    tu_write_file(json, scene, strlen(scene));
    const char *what[2] = {"--view 37.5,100 --light 45,20 --size 40x30", "--scene"};
    for (int k = 0; k < 2; k++) {
        const char *args = k ? tu_fmt("--scene %s --size 48x40", json) : what[0];
        char *a = strdup(args);
        int st = -1;
        char *out = tu_capture(tu_fmt("%s %s render %s %s --backend gpu -o %s/g%d.exr",
                                      validate, tu_cli(), mp, a, dir, k), &st);
        assert_int_equal(st, 0);
        assert_non_null(strstr(out, "backend gpu ("));
        assert_non_null(strstr(out, "render pass"));
        free(out);
        assert_int_equal(tu_run(tu_fmt("%s render -q %s %s --backend cpu -o %s/c%d.exr",
                                       tu_cli(), mp, a, dir, k), NULL), 0);
        if (btf__gpu_is_cpu(gpu))
            assert_int_equal(tu_run(tu_fmt("cmp -s %s/g%d.exr %s/c%d.exr", dir, k, dir, k),
                                    NULL), 0);
        if (btf__gpu_is_cpu(gpu)) {
            out = tu_capture(tu_fmt("%s render %s %s --backend auto -o %s/a%d.png", tu_cli(), mp,
                                    a, dir, k), &st);
            assert_int_equal(st, 0);
            assert_non_null(strstr(out, "backend cpu"));
            free(out);
        }
        /* --texture-size does not apply to an RF model: a usage error, no output */
        char *err = NULL;
        assert_int_equal(tu_run(tu_fmt("%s render %s %s --texture-size 64 -o %s/t%d.png",
                                       tu_cli(), mp, a, dir, k), &err), 2);
        assert_non_null(strstr(err, "--texture-size"));
        assert_true(strchr(err, '\n') == NULL || strchr(err, '\n') == err + strlen(err) - 1);
        free(err);
        assert_int_equal(tu_run(tu_fmt("test -e %s/t%d.png", dir, k), NULL), 1);
        free(a);
    }
    free(json);
    free(mp);
    tu_rmtree(dir);
    free(dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(flat_parity_every_fit),
        cmocka_unit_test(sphere_parity_every_fit),
        cmocka_unit_test(grazing_plane),
        cmocka_unit_test(wild_ranges_stay_finite),
        cmocka_unit_test(buffers_and_bands),
        cmocka_unit_test(sampled_parity),
        cmocka_unit_test(bad_input),
        cmocka_unit_test(command_line),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
