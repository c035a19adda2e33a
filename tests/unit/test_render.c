/*
 * test_render.c — the CPU renderer (src/render/, docs/render.md): the flat
 * (view, light) render against the subspace image its pair selects, the
 * bump factor of a flat range map, the "only what is needed" rule on a
 * model whose index table is known, seeds, extremes and bad input.
 *
 * The model is built by hand: the 81 measured views and lights, one
 * subspace per view ring (6), each a white-noise CAR model (no neighbours)
 * of its own mean colour, so that a pixel's colour says which subspaces it
 * blended.
 */
#include "testutil.h"
#include "render/render.h"
#include "scene/gbuffer.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define RINGS 6

static int ring_of(const btf_dirset *s, int i)
{
    static const double thetas[RINGS] = {0, 15, 30, 45, 60, 75};
    for (int r = 0; r < RINGS; r++)
        if (fabs(s->dirs[i].theta - thetas[r]) < 1e-6)
            return r;
    return -1;
}

/* Subspace r: mean colour (0.1 + 0.1 r, 0.5, 0.9 - 0.1 r), noise sigma. */
static void ring_model(btf_model *m, float sigma)
{
    btf_error e = {0};
    memset(m, 0, sizeof *m);
    TU_OK(btf_dirset_ubo81(&m->views, &e), &e);
    TU_OK(btf_dirset_ubo81(&m->lights, &e), &e);
    m->n_subspaces = RINGS;
    m->subspaces = calloc(RINGS, sizeof *m->subspaces);
    m->index = malloc(81 * 81);
    for (int v = 0; v < 81; v++)
        for (int l = 0; l < 81; l++)
            m->index[v * 81 + l] = (uint8_t)ring_of(&m->views, v);
    for (int r = 0; r < RINGS; r++) {
        btf_subspace_model *s = &m->subspaces[r];
        s->view = s->light = 0;
        s->width = s->height = 64;
        s->mean[0] = 0.1f + 0.1f * r;
        s->mean[1] = 0.5f;
        s->mean[2] = 0.9f - 0.1f * r;
        s->basis[0] = s->basis[4] = s->basis[8] = 1.0f;
        s->levels = 1;
        for (int b = 0; b < 3; b++)
            s->bands[b][0].sigma = sigma;
    }
}

static btf_render_opts opts_of(int w, int h, double relief)
{
    btf_render_opts o = btf_render_defaults();
    o.width = w;
    o.height = h;
    o.relief = relief;
    o.seed = 7;
    return o;
}

/* At a measured (view, light) pair with relief 0, the flat render is the
 * subspace image that pair selects, synthesised tileable at the frame's
 * size. */
static void test_flat_equals_subspace(void **state)
{
    (void)state;
    btf_model m;
    ring_model(&m, 0.05f);
    btf_error e = {0};
    btf_dir view = {30, 60}, light = {45, 0};
    btf_render_opts o = opts_of(64, 64, 0.0);
    btf_image img = {0}, ref = {0};
    btf_render_info info;
    TU_OK(btf_render_flat(&m, view, light, &o, &img, &info, &e), &e);
    assert_int_equal(info.needed, 1);
    assert_int_equal(info.total, RINGS);
    btf_synth_opts so = btf_synth_defaults();
    so.width = so.height = 64;
    so.seed = 7;
    so.tileable = 1;
    TU_OK(btf_synthesise_image(&m, 2, &so, &ref, &e), &e);
    double worst = 0.0;
    for (size_t i = 0; i < (size_t)64 * 64 * 3; i++) {
        double d = fabs(img.data[i] - fmax(ref.data[i], 0.0)); /* no negative radiance */
        worst = d > worst ? d : worst;
    }
    assert_true(worst < 1e-5);
    btf_image_free(&img);
    btf_image_free(&ref);
    btf_model_free(&m);
}

/* A format 1.0 model (no marginal transfer: the synthesis is the plain,
 * unclamped Gaussian) whose colours reach far below -0.5: real values,
 * which once read as the shading's "subspace not synthesised" marker and
 * failed the render. The render succeeds and is the selected
 * subspace image with its negative radiance set to 0, as for any model. */
static void test_deep_gaussian_tails(void **state)
{
    (void)state;
    btf_model m;
    ring_model(&m, 1.0f);
    btf_error e = {0};
    unsigned char *bytes = NULL;
    size_t nbytes = 0;
    TU_OK(btf_model_encode(&m, &bytes, &nbytes, &e), &e);
    assert_int_equal(bytes[11], 1); /* a valid model of format 1.0 */
    assert_int_equal(bytes[13], 0);
    free(bytes);
    btf_dir view = {30, 60}, light = {45, 0};
    btf_render_opts o = opts_of(64, 64, 0.0);
    btf_synth_opts so = btf_synth_defaults();
    so.width = so.height = 64;
    so.seed = 7;
    so.tileable = 1;
    btf_image img = {0}, ref = {0};
    TU_OK(btf_synthesise_image(&m, 2, &so, &ref, &e), &e);
    size_t deep = 0;
    for (size_t i = 0; i < (size_t)64 * 64 * 3; i += 3)
        deep += ref.data[i] < -0.5f;
    assert_true(deep > 64 * 64 / 10); /* the case at hand: many red texels below -0.5 */
    TU_OK(btf_render_flat(&m, view, light, &o, &img, NULL, &e), &e);
    double worst = 0.0;
    for (size_t i = 0; i < (size_t)64 * 64 * 3; i++) {
        assert_true(isfinite(img.data[i]) && img.data[i] >= 0.0f);
        worst = fmax(worst, fabs(img.data[i] - fmax(ref.data[i], 0.0)));
    }
    assert_true(worst < 1e-5);
    btf_image_free(&img);
    btf_image_free(&ref);
    btf_model_free(&m);
}

/* A flat range map (none in the model) multiplies by exactly 1: relief 0
 * and relief 5 give the same bytes. With a sloped range map and relief,
 * the shading follows the light: the side facing it is brighter. */
static void test_flat_range_multiplies_by_one(void **state)
{
    (void)state;
    btf_model m;
    ring_model(&m, 0.05f);
    btf_error e = {0};
    btf_dir view = {20, 10}, light = {50, 200};
    btf_image a = {0}, b = {0};
    btf_render_opts o0 = opts_of(40, 24, 0.0), o5 = opts_of(40, 24, 5.0);
    TU_OK(btf_render_flat(&m, view, light, &o0, &a, NULL, &e), &e);
    TU_OK(btf_render_flat(&m, view, light, &o5, &b, NULL, &e), &e);
    assert_memory_equal(a.data, b.data, (size_t)40 * 24 * 3 * sizeof(float));
    btf_image_free(&a);
    btf_image_free(&b);
    btf_model_free(&m);
}

/* A bumpy range map: relit, the mean brightness stays near the flat one
 * and pixels vary with the light; with the light on the other side the
 * bright and dark pixels swap (correlation < 0). */
static void test_relief_follows_light(void **state)
{
    (void)state;
    btf_model m;
    ring_model(&m, 0.0f); /* constant subspaces: all variation is relief */
    m.range_width = m.range_height = 16;
    m.range_texel = 4.0f;
    m.range = malloc(16 * 16 * sizeof(float));
    for (int y = 0; y < 16; y++)
        for (int x = 0; x < 16; x++)
            m.range[y * 16 + x] = 3.0f * sinf(6.2831853f * x / 16.0f);
    btf_error e = {0};
    btf_dir view = {0, 0}, east = {60, 0}, west = {60, 180};
    btf_image a = {0}, b = {0};
    btf_render_opts o = opts_of(64, 64, 1.0);
    TU_OK(btf_render_flat(&m, view, east, &o, &a, NULL, &e), &e);
    TU_OK(btf_render_flat(&m, view, west, &o, &b, NULL, &e), &e);
    double ma = 0, mb = 0, va = 0, vb = 0, cab = 0;
    size_t n = (size_t)64 * 64;
    for (size_t i = 0; i < n; i++) {
        ma += a.data[3 * i];
        mb += b.data[3 * i];
    }
    ma /= (double)n;
    mb /= (double)n;
    for (size_t i = 0; i < n; i++) {
        double da = a.data[3 * i] - ma, db = b.data[3 * i] - mb;
        va += da * da;
        vb += db * db;
        cab += da * db;
        assert_true(isfinite(a.data[3 * i]) && a.data[3 * i] >= 0.0f);
    }
    assert_true(va > 1e-6 && vb > 1e-6);
    assert_true(cab / sqrt(va * vb) < -0.5);
    btf_image_free(&a);
    btf_image_free(&b);
    btf_model_free(&m);
}

/* The same seed gives the same bytes; another seed other bytes. */
static void test_seed(void **state)
{
    (void)state;
    btf_model m;
    ring_model(&m, 0.05f);
    btf_error e = {0};
    btf_dir view = {37, 100}, light = {22, 300};
    btf_image a = {0}, b = {0}, c = {0};
    btf_render_opts o = opts_of(32, 32, 1.0);
    TU_OK(btf_render_flat(&m, view, light, &o, &a, NULL, &e), &e);
    TU_OK(btf_render_flat(&m, view, light, &o, &b, NULL, &e), &e);
    o.seed = 8;
    TU_OK(btf_render_flat(&m, view, light, &o, &c, NULL, &e), &e);
    size_t bytes = (size_t)32 * 32 * 3 * sizeof(float);
    assert_memory_equal(a.data, b.data, bytes);
    assert_true(memcmp(a.data, c.data, bytes) != 0);
    btf_image_free(&a);
    btf_image_free(&b);
    btf_image_free(&c);
    btf_model_free(&m);
}

/* A hand-made G-buffer whose every pixel sees the surface from theta_v. */
static void gbuffer_from(btf_gbuffer *g, int w, int h, double theta_v, double spread)
{
    size_t n = (size_t)w * h;
    g->width = w;
    g->height = h;
    g->object = calloc(n, sizeof *g->object);
    g->uv = calloc(n, 2 * sizeof(float));
    g->frame = calloc(n, 9 * sizeof(float));
    g->position = calloc(n, 3 * sizeof(float));
    g->view = calloc(n, 3 * sizeof(float));
    for (size_t p = 0; p < n; p++) {
        g->frame[9 * p] = g->frame[9 * p + 4] = g->frame[9 * p + 8] = 1.0f;
        btf_dir d = {theta_v + spread * (double)(p % 7) / 6.0, 360.0 * (double)(p % 13) / 13.0};
        if (d.theta > 90)
            d.theta = 90;
        double v[3];
        btf_dir_to_vec(d, v);
        for (int i = 0; i < 3; i++)
            g->view[3 * p + i] = (float)v[i];
        g->uv[2 * p] = (float)(p % (size_t)w);
        g->uv[2 * p + 1] = (float)(p / (size_t)w);
    }
}

/* "K needed of N": views within the first ring need subspaces 0 and 1
 * only; views from 62 to 74 degrees need the rings 60 and 75 (4, 5); the
 * near-normal frame needs fewer than a frame of all views. */
static void test_needed(void **state)
{
    (void)state;
    btf_model m;
    ring_model(&m, 0.05f);
    btf_error e = {0};
    btf_light sun = {.kind = BTF_LIGHT_DIRECTIONAL, .direction = {0.3, 0.2, 0.9},
                     .rgb = {1, 1, 1}};
    uint8_t need[RINGS];
    int count;
    btf_gbuffer g = {0};
    gbuffer_from(&g, 16, 16, 2.0, 10.0);
    TU_OK(btf__render_needed(&m, &g, &sun, 1, need, &count, &e), &e);
    assert_int_equal(count, 2);
    assert_true(need[0] && need[1]);
    btf__gbuffer_free(&g);
    memset(&g, 0, sizeof g);
    gbuffer_from(&g, 16, 16, 62.0, 12.0);
    TU_OK(btf__render_needed(&m, &g, &sun, 1, need, &count, &e), &e);
    assert_int_equal(count, 2);
    assert_true(need[4] && need[5]);
    btf__gbuffer_free(&g);
    memset(&g, 0, sizeof g);
    gbuffer_from(&g, 16, 16, 0.0, 90.0);
    TU_OK(btf__render_needed(&m, &g, &sun, 1, need, &count, &e), &e);
    assert_int_equal(count, RINGS);
    /* No light above the horizon: nothing is needed. */
    btf_light under = sun;
    under.direction[2] = -0.9;
    TU_OK(btf__render_needed(&m, &g, &under, 1, need, &count, &e), &e);
    assert_int_equal(count, 0);
    btf__gbuffer_free(&g);
    btf_model_free(&m);
}

/* A light below the horizon gives black; background pixels get the
 * background colour; a material built without a needed subspace is an
 * error, not a guess. */
static void test_shade_rules(void **state)
{
    (void)state;
    btf_model m;
    ring_model(&m, 0.05f);
    btf_error e = {0};
    btf_gbuffer g = {0};
    gbuffer_from(&g, 8, 8, 0.0, 90.0);
    g.object[5] = -1;
    uint8_t need[RINGS] = {1, 1, 1, 1, 1, 1};
    btf_render_material *rm;
    TU_OK(btf__render_material_build(&m, need, 16, 3, 0, &rm, &e), &e);
    btf_light under = {.kind = BTF_LIGHT_DIRECTIONAL, .direction = {0.1, 0, -1},
                       .rgb = {1, 1, 1}};
    float bg[3] = {0.25f, 0.5f, 0.75f};
    btf_image img = {0};
    TU_OK(btf__render_shade(rm, &g, &under, 1, bg, 1.0, 1, &img, &e), &e);
    for (int p = 0; p < 64; p++)
        for (int c = 0; c < 3; c++)
            assert_true(img.data[3 * p + c] == (p == 5 ? bg[c] : 0.0f));
    btf_image_free(&img);
    btf__render_material_free(rm);
    uint8_t only0[RINGS] = {1, 0, 0, 0, 0, 0};
    TU_OK(btf__render_material_build(&m, only0, 16, 3, 0, &rm, &e), &e);
    btf_light sun = {.kind = BTF_LIGHT_DIRECTIONAL, .direction = {0, 0, 1}, .rgb = {1, 1, 1}};
    assert_int_equal(btf__render_shade(rm, &g, &sun, 1, bg, 1.0, 1, &img, &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, "subspace"));
    btf__render_material_free(rm);
    btf__gbuffer_free(&g);
    btf_model_free(&m);
}

/* Extremes: grazing views and lights at 90 degrees, a huge relief, a 1x1
 * frame, a point light at the surface: finite, non-negative pixels. */
static void test_extremes(void **state)
{
    (void)state;
    btf_model m;
    ring_model(&m, 0.05f);
    m.range_width = m.range_height = 8;
    m.range_texel = 2.0f;
    m.range = malloc(64 * sizeof(float));
    for (int i = 0; i < 64; i++)
        m.range[i] = (float)((i * 37) % 11) - 5.0f;
    btf_error e = {0};
    btf_dir dirs[] = {{0, 0}, {90, 0}, {90, 123}, {89.999, 45}, {75, 359.9}};
    for (size_t a = 0; a < sizeof dirs / sizeof dirs[0]; a++)
        for (size_t b = 0; b < sizeof dirs / sizeof dirs[0]; b++) {
            btf_image img = {0};
            btf_render_opts o = opts_of(a == b ? 1 : 16, 16, a == 1 ? 1e6 : 2.0);
            TU_OK(btf_render_flat(&m, dirs[a], dirs[b], &o, &img, NULL, &e), &e);
            for (size_t i = 0; i < (size_t)img.width * img.height * 3; i++)
                assert_true(isfinite(img.data[i]) && img.data[i] >= 0.0f);
            btf_image_free(&img);
        }
    btf_gbuffer g = {0};
    gbuffer_from(&g, 4, 4, 10.0, 0.0);
    btf_render_material *rm;
    TU_OK(btf__render_material_build(&m, NULL, 8, 3, 0, &rm, &e), &e);
    btf_light at = {.kind = BTF_LIGHT_POINT, .position = {0, 0, 0}, .rgb = {1e30f, 1, 1}};
    btf_image img = {0};
    TU_OK(btf__render_shade(rm, &g, &at, 1, NULL, 1.0, 2, &img, &e), &e);
    for (size_t i = 0; i < 48; i++)
        assert_true(isfinite(img.data[i]));
    btf_image_free(&img);
    btf__render_material_free(rm);
    btf__gbuffer_free(&g);
    btf_model_free(&m);
}

/* Bad input: a texture model (no directions), frames out of range,
 * directions out of range, a texture size the pyramid does not divide. */
static void test_bad_input(void **state)
{
    (void)state;
    btf_model m;
    ring_model(&m, 0.05f);
    btf_error e = {0};
    btf_image img = {0};
    btf_dir ok = {10, 10}, bad = {91, 0};
    btf_render_opts o = opts_of(8, 8, 1.0);
    assert_int_equal(btf_render_flat(&m, bad, ok, &o, &img, NULL, &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, "theta"));
    o.width = -1;
    assert_int_equal(btf_render_flat(&m, ok, ok, &o, &img, NULL, &e), BTF_E_ARG);
    o = opts_of(8, 8, NAN);
    assert_int_equal(btf_render_flat(&m, ok, ok, &o, &img, NULL, &e), BTF_E_ARG);
    m.subspaces[0].levels = 3; /* pyramid step 4 */
    o = opts_of(8, 8, 1.0);
    o.texture_size = 10;
    assert_int_equal(btf_render_flat(&m, ok, ok, &o, &img, NULL, &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, "multiple of"));
    m.subspaces[0].levels = 1;
    free(m.index);
    m.index = NULL;
    o = opts_of(8, 8, 1.0);
    assert_int_equal(btf_render_flat(&m, ok, ok, &o, &img, NULL, &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, "single texture"));
    btf_model_free(&m);
}

/* A plane (normal +z, side 60) seen by a camera at `theta` degrees from its
 * normal, 20 units away, with a field of view of fov degrees; one light. */
static void plane_scene(btf_scene *sc, double theta, double fov)
{
    memset(sc, 0, sizeof *sc);
    double t = theta * 3.14159265358979323846 / 180.0;
    sc->camera = (btf_camera){{0, -20 * sin(t), 20 * cos(t)}, {0, 0, 0}, {0, 0, 1}, fov};
    if (theta < 1e-9)
        sc->camera.up[1] = 1, sc->camera.up[2] = 0;
    sc->n_lights = 1;
    sc->lights = calloc(1, sizeof *sc->lights);
    sc->lights[0] = (btf_light){.kind = BTF_LIGHT_DIRECTIONAL, .direction = {0, 0.6, 0.8},
                                .rgb = {1, 1, 1}};
    sc->n_objects = 1;
    sc->objects = calloc(1, sizeof *sc->objects);
    sc->objects[0] = (btf_object){.kind = BTF_OBJECT_PLANE, .center = {0, 0, 0},
                                  .axis = {0, 0, 1}, .size = 60, .texture_scale = 16};
}

/* Model only what the scene requires: a plane seen along its normal needs
 * the subspaces of the first rings only, the same plane seen at 65 degrees
 * those of the outer rings, a sphere (every view from 0 to 90 degrees)
 * all six; each render reports the count it synthesised. */
static void test_scene_needs(void **state)
{
    (void)state;
    btf_model m;
    ring_model(&m, 0.05f);
    btf_error e = {0};
    btf_render_opts o = opts_of(48, 48, 1.0);
    btf_render_info near, grazing, all;
    btf_image img = {0};
    btf_scene sc;
    plane_scene(&sc, 0.0, 8.0);
    TU_OK(btf_render_scene(&m, &sc, &o, &img, &near, &e), &e);
    btf_image_free(&img);
    btf_scene_free(&sc);
    plane_scene(&sc, 65.0, 30.0);
    TU_OK(btf_render_scene(&m, &sc, &o, &img, &grazing, &e), &e);
    btf_image_free(&img);
    btf_scene_free(&sc);
    print_message("needed: head-on %d, at 65 degrees %d of %d\n", near.needed, grazing.needed,
                  RINGS);
    /* views within 4 degrees of the pole: the pole and the 15-degree ring */
    assert_int_equal(near.needed, 2);
    /* views from about 50 to 80 degrees: the rings 45, 60 and 75 */
    assert_int_equal(grazing.needed, 3);
    assert_true(near.needed < grazing.needed);
    plane_scene(&sc, 0.0, 8.0);
    sc.objects[0] = (btf_object){.kind = BTF_OBJECT_SPHERE, .center = {0, 0, 0}, .radius = 1.0,
                                 .axis = {0, 1, 0}, .texture_scale = 16};
    sc.camera.fov_deg = 30;
    TU_OK(btf_render_scene(&m, &sc, &o, &img, &all, &e), &e);
    assert_int_equal(all.needed, RINGS);
    /* --all-subspaces synthesises them all, and shades the same pixels. */
    btf_image every = {0};
    btf_render_opts oa = o;
    oa.all_subspaces = 1;
    btf_scene_free(&sc);
    plane_scene(&sc, 0.0, 8.0);
    btf_image_free(&img);
    btf_render_info ia;
    TU_OK(btf_render_scene(&m, &sc, &o, &img, &near, &e), &e);
    TU_OK(btf_render_scene(&m, &sc, &oa, &every, &ia, &e), &e);
    assert_int_equal(ia.needed, RINGS);
    assert_memory_equal(img.data, every.data, (size_t)48 * 48 * 3 * sizeof(float));
    btf_image_free(&img);
    btf_image_free(&every);
    btf_scene_free(&sc);
    btf_model_free(&m);
}

/* The command: a flat render and a scene render of a model file, the
 * summary lines, the same bytes for the same seed, and the usage errors. */
static void test_cli_render(void **state)
{
    (void)state;
    char *dir = tu_tmpdir();
    btf_model m;
    ring_model(&m, 0.05f);
    btf_error e = {0};
    const char *model = tu_fmt("%s/rings.btfcar", dir);
    char *mp = strdup(model);
    TU_OK(btf_model_write(mp, &m, &e), &e);
    btf_model_free(&m);
    char *err = NULL;
    int st = -1;
    const char *cli = tu_cli();
    char *out = tu_capture(tu_fmt("%s render %s --view 30,60 --light 45,0 --size 32x32 -o %s/a.png",
                                  cli, mp, dir), &st);
    assert_int_equal(st, 0);
    assert_non_null(strstr(out, "subspaces: 1 needed of 6"));
    assert_non_null(strstr(out, "backend cpu"));
    free(out);
    assert_int_equal(tu_run(tu_fmt("%s render -q %s --view 30,60 --light 45,0 --size 32x32 -o %s/b.png",
                                   cli, mp, dir), NULL), 0);
    assert_int_equal(tu_run(tu_fmt("cmp -s %s/a.png %s/b.png", dir, dir), NULL), 0);
    const char *scene = tu_fmt("%s/s.json", dir);
    char *sp = strdup(scene);
    const char *json = "{\"camera\": {\"position\": [0, 0, 4], \"target\": [0, 0, 0], "
                       "\"up\": [0, 1, 0], \"fov\": 40}, \"lights\": [{\"type\": "
                       "\"directional\", \"direction\": [1, 1, 1], \"intensity\": 1}], "
                       "\"objects\": [{\"type\": \"sphere\", \"center\": [0, 0, 0], "
                       "\"radius\": 1, \"texture_scale\": 16}]}";
    tu_write_file(sp, json, strlen(json));
    assert_int_equal(tu_run(tu_fmt("%s render -q %s --scene %s --size 40x30 -o %s/s.exr", cli, mp,
                                   sp, dir), NULL), 0);
    btf_image img = {0};
    TU_OK(btf_image_read(tu_fmt("%s/s.exr", dir), NULL, &img, &e), &e);
    assert_int_equal(img.width, 40);
    assert_int_equal(img.height, 30);
    btf_image_free(&img);
    /* usage errors: exit 2, no output */
    assert_int_equal(tu_run(tu_fmt("%s render %s --size 8x8 -o %s/c.png", cli, mp, dir), &err), 2);
    assert_non_null(strstr(err, "--scene"));
    free(err);
    assert_int_equal(tu_run(tu_fmt("%s render %s --view 1,1 --scene %s -o %s/c.png", cli, mp, sp,
                                   dir), &err), 2);
    free(err);
    assert_int_equal(tu_run(tu_fmt("%s render %s --view 1,1 --light 1,1 -o %s/c.tif", cli, mp,
                                   dir), &err), 2);
    free(err);
    assert_int_equal(tu_run(tu_fmt("%s render %s --view 95,1 --light 1,1 -o %s/c.png", cli, mp,
                                   dir), &err), 2);
    free(err);
    /* a bad scene: one line naming the file, exit 1, no output */
    tu_write_file(sp, "{\"camera\": 3}", 13);
    assert_int_equal(tu_run(tu_fmt("%s render %s --scene %s -o %s/c.png", cli, mp, sp, dir),
                            &err), 1);
    assert_non_null(strstr(err, "s.json"));
    free(err);
    assert_int_equal(tu_run(tu_fmt("test -e %s/c.png", dir), NULL), 1);
    free(mp);
    free(sp);
    tu_rmtree(dir);
    free(dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_flat_equals_subspace),
        cmocka_unit_test(test_deep_gaussian_tails),
        cmocka_unit_test(test_flat_range_multiplies_by_one),
        cmocka_unit_test(test_relief_follows_light),
        cmocka_unit_test(test_seed),
        cmocka_unit_test(test_needed),
        cmocka_unit_test(test_shade_rules),
        cmocka_unit_test(test_extremes),
        cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_scene_needs),
        cmocka_unit_test(test_cli_render),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
