/*
 * test_gpu_render.c — the GPU render pass (gpu/render_gpu.c, render.comp)
 * against the CPU renderer (src/render/), on lavapipe with the Khronos
 * validation layer on and any validation message failing the test
 * (docs/render.md, "On the GPU"). Both backends trace the same G-buffer on
 * the host and synthesise bit-identical tileable subspace images, so what
 * differs is the shading arithmetic alone: sqrt and division, whose last
 * bits the driver does not pin down. The stated tolerance: every pixel
 * within 1e-3 of the image's range, except a counted share of at most
 * 0.1 % of the pixels (those where a rounding moves a texel tap or a
 * triangle choice); the test prints the figures. On lavapipe the result is
 * bit-identical (its sqrt and division are the CPU's), and there the test
 * requires it.
 */
#include "testutil.h"
#include "model/model.h" /* periodic cells */
#include "synth/synth_testing.h" /* btf__gpu_set_max_buffer_bytes */

#include "scene_sphere_obj.h"
#include "synth_gpu.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static btf_gpu *gpu;

static int setup(void **state)
{
    (void)state;
    return tu_gpu_open(&gpu, "test_gpu_render");
}

static int teardown(void **state)
{
    (void)state;
    btf_gpu_close(gpu);
    return 0;
}

static void no_validation_messages(void)
{
    tu_gpu_no_validation_messages(gpu);
}

/* The 81 views and lights, 4 subspaces by view ring and light half, each a
 * CAR model with neighbours (so the images have structure), and a rough
 * range tile (so parallax and bump mapping act). */
static void test_model(btf_model *m)
{
    btf_error e = {0};
    memset(m, 0, sizeof *m);
    TU_OK(btf_dirset_ubo81(&m->views, &e), &e);
    TU_OK(btf_dirset_ubo81(&m->lights, &e), &e);
    m->n_subspaces = 4;
    m->subspaces = calloc(4, sizeof *m->subspaces);
    m->index = malloc(81 * 81);
    for (int v = 0; v < 81; v++)
        for (int l = 0; l < 81; l++)
            m->index[v * 81 + l] = (uint8_t)((m->views.dirs[v].theta >= 40 ? 2 : 0) +
                                             (m->lights.dirs[l].phi >= 180 ? 1 : 0));
    for (int k = 0; k < 4; k++) {
        btf_subspace_model *s = &m->subspaces[k];
        s->width = s->height = 64;
        s->mean[0] = 0.2f + 0.1f * k;
        s->mean[1] = 0.3f;
        s->mean[2] = 0.5f - 0.05f * k;
        s->basis[0] = s->basis[4] = s->basis[8] = 1.0f;
        s->levels = 2;
        for (int b = 0; b < 3; b++)
            for (int l = 0; l < 2; l++) {
                btf_car_band *band = &s->bands[b][l];
                band->n = 2;
                band->offsets[0] = (btf_offset){0, -1};
                band->offsets[1] = (btf_offset){-1, 0};
                band->gamma[0] = 0.45f;
                band->gamma[1] = 0.35f;
                band->sigma = 0.03f;
            }
    }
    m->range_width = m->range_height = 16;
    m->range_texel = 2.0f;
    m->range = malloc(256 * sizeof(float));
    for (int i = 0; i < 256; i++)
        m->range[i] = 2.0f * sinf(0.7f * (float)(i % 16)) * cosf(0.4f * (float)(i / 16));
    TU_OK(btf_range_make_periodic(m->range, 16, 16, &e), &e);
}

/* Compares two renders: the largest difference in units of the CPU image's
 * range, and the share of pixels beyond 1e-3 of it. */
static void compare(const char *what, const btf_image *c, const btf_image *g)
{
    assert_int_equal(c->width, g->width);
    assert_int_equal(c->height, g->height);
    size_t n = (size_t)c->width * c->height;
    float lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < 3 * n; i++) {
        assert_true(isfinite(g->data[i]));
        lo = fminf(lo, c->data[i]);
        hi = fmaxf(hi, c->data[i]);
    }
    double range = hi > lo ? hi - lo : 1.0, worst = 0.0;
    size_t beyond = 0, equal = 0;
    for (size_t p = 0; p < n; p++) {
        double d = 0.0;
        for (int k = 0; k < 3; k++)
            d = fmax(d, fabs((double)c->data[3 * p + k] - g->data[3 * p + k]));
        worst = fmax(worst, d / range);
        beyond += d > 1e-3 * range;
        equal += d == 0.0;
    }
    print_message("%s: max |cpu - gpu| = %.3g of the range, %zu of %zu pixels beyond 1e-3 "
                  "(%.4f %%), %zu bit-identical\n", what, worst, beyond, n,
                  100.0 * (double)beyond / (double)n, equal);
    assert_true((double)beyond <= 0.001 * (double)n);
    /* On lavapipe (the CPU's own IEEE sqrt and division) the two paths are
     * bit for bit the same: reachable, so required there. */
    if (btf__gpu_is_cpu(gpu))
        assert_int_equal(equal, n);
}

static void test_flat_parity(void **state)
{
    (void)state;
    btf_model m;
    test_model(&m);
    btf_error e = {0};
    btf_dir pairs[][2] = {{{30, 60}, {45, 0}}, {{0, 0}, {70, 200}}, {{62, 17}, {12, 300}},
                          {{80, 100}, {80, 280}}};
    for (size_t i = 0; i < sizeof pairs / sizeof pairs[0]; i++) {
        btf_render_opts o = btf_render_defaults();
        o.width = 96;
        o.height = 64;
        o.seed = 5;
        btf_image c = {0}, g = {0};
        btf_render_info ic, ig;
        TU_OK(btf_render_flat(&m, pairs[i][0], pairs[i][1], &o, &c, &ic, &e), &e);
        TU_OK(btf_gpu_render_flat(gpu, &m, pairs[i][0], pairs[i][1], &o, &g, &ig, &e), &e);
        assert_int_equal(ic.needed, ig.needed);
        compare(tu_fmt("flat view %g,%g light %g,%g", pairs[i][0].theta, pairs[i][0].phi,
                       pairs[i][1].theta, pairs[i][1].phi), &c, &g);
        btf_image_free(&c);
        btf_image_free(&g);
    }
    no_validation_messages();
    btf_model_free(&m);
}

/* test_model with the structure layer of format 1.5 (docs/model.md): a
 * range map at texel 1, an albedo pattern with a colour layer, cast
 * shadows (so the horizon map and the view march act) and pair gains. */
static void structured_model(btf_model *m)
{
    test_model(m);
    int n = 64;
    free(m->range);
    m->range_width = m->range_height = n;
    m->range_texel = 1.0f;
    m->range = malloc((size_t)n * n * sizeof(float));
    m->albedo = malloc((size_t)n * n * sizeof(float));
    m->chroma = malloc((size_t)n * n * 3 * sizeof(float));
    for (int i = 0; i < n * n; i++) {
        int x = i % n, y = i / n;
        m->range[i] = 3.0f * sinf(0.4f * (float)x) * cosf(0.3f * (float)y);
        m->albedo[i] = 1.0f + 0.4f * sinf(0.9f * (float)(x + 2 * y));
        m->chroma[3 * i] = 1.0f + 0.2f * cosf(0.5f * (float)x);
        m->chroma[3 * i + 1] = 1.0f;
        m->chroma[3 * i + 2] = 1.0f - 0.2f * cosf(0.5f * (float)x);
    }
    m->ambient = 0.1f;
    m->shadows = 1;
    m->gain = malloc(81 * 81 * 3 * sizeof(float));
    for (int i = 0; i < 81 * 81 * 3; i++)
        m->gain[i] = 0.6f + 0.1f * (float)(i % 9);
}

/* Periodic cells (format 1.7) on structured_model's layers: a cell of
 * 8 x 4 texels, shift 3, for every subspace but the first. */
static void add_cells(btf_model *m)
{
    btf_error e = {0};
    btf_cells *c = btf__cells_new(8, 4, 3, m->n_subspaces, &e);
    assert_non_null(c);
    for (int k = 1; k < m->n_subspaces; k++) {
        c->kept[k] = 1;
        for (int i = 0; i < 8 * 4 * 3; i++)
            c->value[(size_t)k * 96 + (size_t)i] =
                btf__albedo_value(118u + (unsigned)((i * 5 + k * 3) % 21));
    }
    TU_OK(btf__model_set_cells(m, c, &e), &e);
}

static void structured_parity(int cells)
{
    btf_model m;
    structured_model(&m);
    if (cells)
        add_cells(&m);
    btf_error e = {0};
    unsigned char *bytes = NULL;
    size_t nbytes = 0;
    TU_OK(btf_model_encode(&m, &bytes, &nbytes, &e), &e); /* a valid 1.5 (1.7) model */
    assert_int_equal(bytes[13], cells ? 7 : 5);
    free(bytes);
    /* a grazing view (the march runs many steps) and a grazing light (shadows) */
    btf_dir pairs[][2] = {{{30, 60}, {45, 0}}, {{75, 225}, {75, 45}}, {{0, 0}, {80, 200}},
                          {{62, 17}, {12, 300}}};
    for (size_t i = 0; i < sizeof pairs / sizeof pairs[0]; i++) {
        btf_render_opts o = btf_render_defaults();
        o.width = 96;
        o.height = 64;
        o.seed = 9;
        btf_image c = {0}, g = {0}, flat = {0};
        btf_render_info ic, ig;
        TU_OK(btf_render_flat(&m, pairs[i][0], pairs[i][1], &o, &c, &ic, &e), &e);
        TU_OK(btf_gpu_render_flat(gpu, &m, pairs[i][0], pairs[i][1], &o, &g, &ig, &e), &e);
        compare(tu_fmt("structured%s view %g,%g light %g,%g", cells ? " with cells" : "",
                       pairs[i][0].theta,
                       pairs[i][0].phi, pairs[i][1].theta, pairs[i][1].phi), &c, &g);
        /* the relief acts: at relief 0 (no shadows, no march) the picture differs */
        o.relief = 0.0;
        TU_OK(btf_render_flat(&m, pairs[i][0], pairs[i][1], &o, &flat, &ic, &e), &e);
        size_t differ = 0;
        for (size_t k = 0; k < (size_t)96 * 64 * 3; k++)
            differ += flat.data[k] != c.data[k];
        assert_true(differ > 96 * 64);
        btf_image_free(&c);
        btf_image_free(&g);
        btf_image_free(&flat);
    }
    no_validation_messages();
    btf_model_free(&m);
}

static void test_structured_parity(void **state)
{
    (void)state;
    structured_parity(0);
    structured_parity(1);
}

static void sphere_scene(btf_scene *s)
{
    memset(s, 0, sizeof *s);
    s->camera = (btf_camera){{0, 0, 4}, {0, 0, 0}, {0, 1, 0}, 40};
    s->n_lights = 2;
    s->lights = calloc(2, sizeof *s->lights);
    s->lights[0] = (btf_light){.kind = BTF_LIGHT_DIRECTIONAL,
                               .direction = {0.57735, 0.57735, 0.57735}, .rgb = {1, 0.9f, 0.8f}};
    s->lights[1] = (btf_light){.kind = BTF_LIGHT_POINT, .position = {-3, 1, 3},
                               .rgb = {6, 6, 6}};
    s->n_objects = 1;
    s->objects = calloc(1, sizeof *s->objects);
    s->objects[0] = (btf_object){.kind = BTF_OBJECT_SPHERE, .center = {0, 0, 0}, .radius = 1,
                                 .axis = {0, 1, 0}, .texture_scale = 32};
    s->background[0] = 0.1f;
}

static void test_sphere_parity(void **state)
{
    (void)state;
    btf_model m;
    test_model(&m);
    btf_error e = {0};
    btf_scene s;
    sphere_scene(&s);
    btf_render_opts o = btf_render_defaults();
    o.width = 160;
    o.height = 120;
    o.seed = 9;
    btf_image c = {0}, g = {0};
    btf_render_info ic, ig;
    TU_OK(btf_render_scene(&m, &s, &o, &c, &ic, &e), &e);
    TU_OK(btf_gpu_render_scene(gpu, &m, &s, &o, &g, &ig, &e), &e);
    assert_int_equal(ic.needed, ig.needed);
    assert_int_equal(ic.texture_size, ig.texture_size);
    compare("sphere, two lights", &c, &g);
    /* The background pixels are the background colour on both. */
    assert_true(g.data[0] == 0.1f && g.data[1] == 0.0f);
    btf_image_free(&c);
    btf_image_free(&g);
    no_validation_messages();
    btf_scene_free(&s);
    btf_model_free(&m);
}

/* A format 1.1 model (a range map, no marginal transfer: unclamped Gaussian
 * synthesis) whose colours reach far below -0.5, the value that once doubled
 * as the shading's "subspace not synthesised" marker and failed the render:
 * both backends render it, the same bits, a pair at a measured direction and
 * the sphere's blends of many pairs under two lights. */
static void test_deep_tails_parity(void **state)
{
    (void)state;
    btf_model m;
    test_model(&m);
    for (int k = 0; k < m.n_subspaces; k++)
        for (int b = 0; b < 3; b++)
            for (int l = 0; l < 2; l++)
                m.subspaces[k].bands[b][l].sigma = 0.5f;
    btf_error e = {0};
    unsigned char *bytes = NULL;
    size_t nbytes = 0;
    TU_OK(btf_model_encode(&m, &bytes, &nbytes, &e), &e);
    assert_int_equal(bytes[11], 1); /* a valid model of format 1.1 */
    assert_int_equal(bytes[13], 1);
    free(bytes);
    btf_synth_opts so = btf_synth_defaults();
    so.width = so.height = 64;
    so.seed = 9;
    so.tileable = 1;
    btf_image sub = {0};
    TU_OK(btf_synthesise_image(&m, 0, &so, &sub, &e), &e);
    size_t deep = 0;
    for (size_t i = 0; i < (size_t)64 * 64 * 3; i += 3)
        deep += sub.data[i] < -0.5f;
    assert_true(deep > 64 * 64 / 10); /* the case at hand: many red texels below -0.5 */
    btf_image_free(&sub);
    btf_render_opts o = btf_render_defaults();
    o.width = 96;
    o.height = 64;
    o.seed = 9;
    btf_dir view = {30, 60}, light = {45, 0};
    btf_image c = {0}, g = {0};
    TU_OK(btf_render_flat(&m, view, light, &o, &c, NULL, &e), &e);
    TU_OK(btf_gpu_render_flat(gpu, &m, view, light, &o, &g, NULL, &e), &e);
    compare("deep tails, flat", &c, &g);
    btf_image_free(&c);
    btf_image_free(&g);
    btf_scene s;
    sphere_scene(&s);
    o.width = 160;
    o.height = 120;
    TU_OK(btf_render_scene(&m, &s, &o, &c, NULL, &e), &e);
    TU_OK(btf_gpu_render_scene(gpu, &m, &s, &o, &g, NULL, &e), &e);
    compare("deep tails, sphere", &c, &g);
    btf_image_free(&c);
    btf_image_free(&g);
    no_validation_messages();
    btf_scene_free(&s);
    btf_model_free(&m);
}

/* A frame larger than the device's storage-buffer limit goes in bands
 * (the limit lowered for the test): the same pixels as in one band. */
static void test_bands(void **state)
{
    (void)state;
    btf_model m;
    test_model(&m);
    btf_error e = {0};
    btf_scene s;
    sphere_scene(&s);
    btf_render_opts o = btf_render_defaults();
    o.width = 256;
    o.height = 192;
    btf_image one = {0}, banded = {0};
    TU_OK(btf_gpu_render_scene(gpu, &m, &s, &o, &one, NULL, &e), &e);
    /* 1 MiB: the subspace images still fit, the 3.5 MB G-buffer goes in 4
     * bands of 56 rows */
    btf__gpu_set_max_buffer_bytes(gpu, 1u << 20);
    TU_OK(btf_gpu_render_scene(gpu, &m, &s, &o, &banded, NULL, &e), &e);
    btf__gpu_set_max_buffer_bytes(gpu, 0);
    assert_memory_equal(one.data, banded.data, (size_t)256 * 192 * 3 * sizeof(float));
    btf_image_free(&one);
    btf_image_free(&banded);
    no_validation_messages();
    btf_scene_free(&s);
    btf_model_free(&m);
}

/* The subspace images over several storage buffers (gpu/gpu_images.c): with a
 * limit that holds one image per buffer, the sphere (every subspace
 * needed) renders to the same bits as without the limit and as the CPU. */
/* The range and normal maps past four buffers: a flat render that needs one
 * subspace image (view and light far from the test model's boundaries) at
 * 256^2 texels, buffers of 160,000 bytes: the maps (1 MiB) over seven
 * buffers (bindings 18 on), the image (768 KiB) over five; the bits of the
 * one-buffer render and, on lavapipe, the CPU's. */
static void test_split_maps(void **state)
{
    (void)state;
    btf_model m;
    test_model(&m);
    btf_error e = {0};
    btf_render_opts o = btf_render_defaults();
    o.width = o.height = 128;
    o.seed = 3;
    o.texture_size = 256;
    btf_dir view = {0, 0}, light = {45, 90};
    btf_image c = {0}, one = {0}, split = {0};
    btf_render_info ic, ig;
    TU_OK(btf_render_flat(&m, view, light, &o, &c, &ic, &e), &e);
    assert_int_equal(ic.needed, 1);
    TU_OK(btf_gpu_render_flat(gpu, &m, view, light, &o, &one, NULL, &e), &e);
    btf__gpu_set_max_buffer_bytes(gpu, 160000);
    TU_OK(btf_gpu_render_flat(gpu, &m, view, light, &o, &split, &ig, &e), &e);
    btf__gpu_set_max_buffer_bytes(gpu, 0);
    size_t bytes = (size_t)128 * 128 * 3 * sizeof(float);
    assert_memory_equal(one.data, split.data, bytes);
    if (btf__gpu_is_cpu(gpu))
        assert_memory_equal(c.data, split.data, bytes);
    print_message("maps over 7 buffers, the image over 5: the one-buffer render's bits\n");
    btf_image_free(&c);
    btf_image_free(&one);
    btf_image_free(&split);
    btf_model_free(&m);
    no_validation_messages();
}

static void test_split_textures(void **state)
{
    (void)state;
    btf_model m;
    test_model(&m);
    btf_error e = {0};
    btf_scene s;
    sphere_scene(&s);
    btf_render_opts o = btf_render_defaults();
    o.width = 160;
    o.height = 120;
    o.seed = 9;
    o.texture_size = 128; /* 192 KiB an image */
    btf_image c = {0}, one = {0}, split = {0};
    btf_render_info ic, ig;
    TU_OK(btf_render_scene(&m, &s, &o, &c, &ic, &e), &e);
    TU_OK(btf_gpu_render_scene(gpu, &m, &s, &o, &one, NULL, &e), &e);
    assert_int_equal(ic.needed, 4);
    /* 250 KB: about one image per buffer, four buffers; the G-buffer in
     * bands */
    btf__gpu_set_max_buffer_bytes(gpu, 250000);
    TU_OK(btf_gpu_render_scene(gpu, &m, &s, &o, &split, &ig, &e), &e);
    btf__gpu_set_max_buffer_bytes(gpu, 0);
    assert_int_equal(ig.needed, 4);
    size_t bytes = (size_t)160 * 120 * 3 * sizeof(float);
    assert_memory_equal(one.data, split.data, bytes);
    compare("sphere, images over four buffers", &c, &split);
    if (btf__gpu_is_cpu(gpu))
        assert_memory_equal(c.data, split.data, bytes);
    /* 200 KB: the images straddle the buffers' edges: the same bits */
    btf_image straddle = {0};
    btf__gpu_set_max_buffer_bytes(gpu, 200000);
    TU_OK(btf_gpu_render_scene(gpu, &m, &s, &o, &straddle, NULL, &e), &e);
    btf__gpu_set_max_buffer_bytes(gpu, 0);
    assert_memory_equal(one.data, straddle.data, bytes);
    btf_image_free(&straddle);
    /* 150 KB: the images over six buffers (bindings 14 on): the same bits */
    btf_image six = {0};
    btf__gpu_set_max_buffer_bytes(gpu, 150000);
    TU_OK(btf_gpu_render_scene(gpu, &m, &s, &o, &six, NULL, &e), &e);
    btf__gpu_set_max_buffer_bytes(gpu, 0);
    assert_memory_equal(one.data, six.data, bytes);
    btf_image_free(&six);
    /* 90 KB: eight buffers cannot hold the four images: one clear error */
    btf_image none = {0};
    btf__gpu_set_max_buffer_bytes(gpu, 90000);
    assert_int_equal(btf_gpu_render_scene(gpu, &m, &s, &o, &none, NULL, &e), BTF_E_UNSUPPORTED);
    btf__gpu_set_max_buffer_bytes(gpu, 0);
    assert_non_null(strstr(e.msg, "more than 8 storage buffers"));
    assert_null(none.data);
    btf_image_free(&c);
    btf_image_free(&one);
    btf_image_free(&split);
    no_validation_messages();
    btf_scene_free(&s);
    btf_model_free(&m);
}

/* Limits: a device buffer too small for even the images is one clear
 * error, not a crash; the GPU stays usable after it. */
static void test_limits(void **state)
{
    (void)state;
    btf_model m;
    test_model(&m);
    btf_error e = {0};
    btf_render_opts o = btf_render_defaults();
    o.width = 64;
    o.height = 64;
    btf_image img = {0};
    btf_dir v = {10, 0}, l = {30, 90};
    btf__gpu_set_max_buffer_bytes(gpu, 4096);
    int rc = btf_gpu_render_flat(gpu, &m, v, l, &o, &img, NULL, &e);
    btf__gpu_set_max_buffer_bytes(gpu, 0);
    assert_true(rc == BTF_E_UNSUPPORTED || rc == BTF_E_ARG);
    assert_null(strchr(e.msg, '\n'));
    assert_non_null(strstr(e.msg, "buffer"));
    assert_null(img.data);
    TU_OK(btf_gpu_render_flat(gpu, &m, v, l, &o, &img, NULL, &e), &e);
    btf_image_free(&img);
    no_validation_messages();
    btf_model_free(&m);
}

/* The command: --backend gpu (validation on) names the device and both
 * passes and writes the CPU's bytes; --backend auto takes the CPU where
 * the only device is lavapipe. */
static void test_cli_backends(void **state)
{
    (void)state;
    char *dir = tu_tmpdir();
    btf_model m;
    test_model(&m);
    btf_error e = {0};
    char *mp = strdup(tu_fmt("%s/m.btfcar", dir));
    TU_OK(btf_model_write(mp, &m, &e), &e);
    btf_model_free(&m);
    const char *validate = getenv("BTF_ASAN") ? "" : "BTF_VK_VALIDATION=1";
    int st = -1;
    char *out = tu_capture(tu_fmt("%s %s render %s --view 40,10 --light 30,250 --size 48x40 "
                                  "--backend gpu -o %s/g.png", validate, tu_cli(), mp, dir), &st);
    assert_int_equal(st, 0);
    assert_non_null(strstr(out, "backend gpu ("));
    assert_non_null(strstr(out, "synthesis pass"));
    assert_non_null(strstr(out, "render pass"));
    free(out);
    assert_int_equal(tu_run(tu_fmt("%s render -q %s --view 40,10 --light 30,250 --size 48x40 "
                                   "--backend cpu -o %s/c.png", tu_cli(), mp, dir), NULL), 0);
    assert_int_equal(tu_run(tu_fmt("cmp -s %s/g.png %s/c.png", dir, dir), NULL), 0);
    if (btf__gpu_is_cpu(gpu)) {
        out = tu_capture(tu_fmt("%s render %s --view 40,10 --light 30,250 --size 8x8 "
                                "--backend auto -o %s/a.png", tu_cli(), mp, dir), &st);
        assert_int_equal(st, 0);
        assert_non_null(strstr(out, "backend cpu"));
        free(out);
    }
    char *err = NULL;
    assert_int_equal(tu_run(tu_fmt("%s render %s --view 1,1 --light 1,1 --backend cpu "
                                   "--device 0 -o %s/x.png", tu_cli(), mp, dir), &err), 2);
    free(err);
    free(mp);
    tu_rmtree(dir);
    free(dir);
}

/* A mesh of more than 100,000 triangles (a tessellated sphere, OBJ through
 * assimp) renders on the GPU as on the CPU: the G-buffer is traced on the
 * host, so the triangle count costs the render pass nothing. */
static void test_big_mesh(void **state)
{
    (void)state;
    char *dir = tu_tmpdir();
    char *obj = strdup(tu_fmt("%s/sphere.obj", dir)), *json = strdup(tu_fmt("%s/s.json", dir));
    assert_int_equal(write_sphere_obj(obj, 224, 256), 0);
    const char *text = "{\"camera\": {\"position\": [0, 0.8, 4], \"target\": [0, 0, 0], "
                       "\"fov\": 40}, \"lights\": [{\"type\": \"directional\", "
                       "\"direction\": [0.3, 0.5, 1]}], \"objects\": [{\"type\": \"mesh\", "
                       "\"file\": \"sphere.obj\", \"texture_scale\": 40}]}";
    tu_write_file(json, text, strlen(text));
    btf_scene s;
    btf_error e = {0};
    TU_OK(btf_scene_load(json, &s, &e), &e);
    assert_true(s.objects[0].mesh.n_triangles >= 100000);
    btf_model m;
    test_model(&m);
    btf_render_opts o = btf_render_defaults();
    o.width = 128;
    o.height = 96;
    btf_image c = {0}, g = {0};
    TU_OK(btf_render_scene(&m, &s, &o, &c, NULL, &e), &e);
    TU_OK(btf_gpu_render_scene(gpu, &m, &s, &o, &g, NULL, &e), &e);
    compare("114,688-triangle mesh", &c, &g);
    btf_image_free(&c);
    btf_image_free(&g);
    no_validation_messages();
    btf_scene_free(&s);
    btf_model_free(&m);
    free(obj);
    free(json);
    tu_rmtree(dir);
    free(dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_flat_parity),
        cmocka_unit_test(test_structured_parity),
        cmocka_unit_test(test_sphere_parity),
        cmocka_unit_test(test_deep_tails_parity),
        cmocka_unit_test(test_bands),
        cmocka_unit_test(test_split_textures),
        cmocka_unit_test(test_split_maps),
        cmocka_unit_test(test_limits),
        cmocka_unit_test(test_big_mesh),
        cmocka_unit_test(test_cli_backends),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
