/*
 * test_rf_sample.c — the memory reduction of Meseth, Müller & Klein 2003,
 * section 6 (src/rf/rf_sampled.c, rf_quilt.c,
 * rf_sample.c, rf_feature.c, rf_cut.c; docs/rf.md, "Memory reduction"):
 * the coordinate map stays in the sample, a sample of the whole image is
 * the whole fit exactly, the map is the same for a seed and any thread
 * count, the sample keeps its place, 1x1 and whole-image samples work, no
 * render gives NaN or Inf, every evaluation path goes through the map, the
 * file's RFMP section round-trips and every damaged form of it is an
 * error, and the command line refuses bad --sample values in one line.
 */
#include "testutil.h"

#include "rf/rf.h"
#include "report/report.h" /* btf__rf_report_write */
#include "rf/rf_map.h"
#include "rf/rf_sample.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define SIDE 16

static btf_dataset *ds;
static char dataset_path[4096];
static btf_rf_model full, s8;          /* the whole PTM fit; an 8x8 sample on a 24x20 surface */
static btf_rf_fit_info full_info, s8_info;

static btf_rf_sample_opts sample_opts(int n, int sw, int sh, uint64_t seed)
{
    btf_rf_sample_opts so = btf_rf_sample_defaults();
    so.width = so.height = n;
    so.surface_width = sw, so.surface_height = sh;
    so.seed = seed;
    return so;
}

static int setup(void **state)
{
    if (tu_setup_dir(state) ||
        tu_generate_dataset("fabric", SIDE, 5, dataset_path, sizeof dataset_path, &ds))
        return -1;
    btf_error e = {0};
    btf_rf_opts o = btf_rf_defaults();
    o.threads = 2, o.info = &full_info;
    if (btf_rf_fit(ds, &o, &full, &e) != 0)
        return fprintf(stderr, "setup: %s\n", e.msg), -1;
    btf_rf_sample_opts so = sample_opts(8, 24, 20, 7);
    o.info = &s8_info;
    if (btf_rf_fit_sampled(ds, &o, &so, &s8, &e) != 0)
        return fprintf(stderr, "setup: %s\n", e.msg), -1;
    return 0;
}

static int teardown(void **state)
{
    btf_rf_model_free(&full);
    btf_rf_model_free(&s8);
    btf_dataset_close(ds);
    return tu_teardown_dir(state);
}

static void assert_map_in_range(const btf_rf_model *m)
{
    assert_non_null(m->map);
    for (int t = 0; t < m->surface_width * m->surface_height; t++) {
        assert_true(m->map[2 * t] < m->width);
        assert_true(m->map[2 * t + 1] < m->height);
    }
}

static void assert_image_finite(const btf_image *img)
{
    for (size_t i = 0; i < (size_t)img->width * img->height * 3; i++)
        assert_true(isfinite(img->data[i]) && img->data[i] >= 0.0f);
}

/* ------------------------------------------------------------- the map */

static void map_stays_in_the_sample(void **state)
{
    (void)state;
    assert_int_equal(s8.width, 8);
    assert_int_equal(s8.height, 8);
    assert_int_equal(s8.surface_width, 24);
    assert_int_equal(s8.surface_height, 20);
    assert_map_in_range(&s8);
    assert_true(s8.sample_x >= 0 && s8.sample_x <= SIDE - 8);
    assert_true(s8.sample_y >= 0 && s8.sample_y <= SIDE - 8);
    int w, h;
    btf_rf_surface_size(&s8, &w, &h);
    assert_int_equal(w, 24);
    assert_int_equal(h, 20);
    btf_rf_surface_size(&full, &w, &h);
    assert_int_equal(w, SIDE);
    assert_int_equal(h, SIDE);
    /* the figures of the call */
    assert_int_equal(s8_info.quilt_block, 4);
    assert_int_equal(s8_info.quilt_overlap, 1);
    assert_true(s8_info.mean_abs_error > 0.0 && isfinite(s8_info.mean_abs_error));
    assert_true(s8_info.sample_mean_abs_error > 0.0);
    double e, y;
    btf_error err = {0};
    TU_OK(btf__rf_error(ds, &s8, 2, &e, &y, &err), &err);
    assert_true(e == s8_info.mean_abs_error && y == s8_info.mean_luminance);
    /* the pixel correspondence is lost outside the sample: a larger error */
    assert_true(e > full_info.mean_abs_error);
}

/* Away from its border (one overlap), the sample's place maps to itself. */
static void sample_keeps_its_place(void **state)
{
    (void)state;
    int ov = s8_info.quilt_overlap;
    for (int y = ov; y < 8 - ov; y++)
        for (int x = ov; x < 8 - ov; x++) {
            int X = s8.sample_x + x, Y = s8.sample_y + y;
            const uint16_t *c = s8.map + 2 * ((size_t)Y * s8.surface_width + X);
            assert_int_equal(c[0], x);
            assert_int_equal(c[1], y);
        }
    /* and its codes are the whole fit's texels there, requantised over the
     * sample: each within the two fields' quantisation steps */
    float a[BTF_RF_MAX_SLOTS], b[BTF_RF_MAX_SLOTS];
    for (int f = 0; f < full.fields; f += 20)
        for (int y = 0; y < 8; y++)
            for (int x = 0; x < 8; x++) {
                rf_texel_params(&s8, f, (size_t)y * 8 + x, a);
                rf_texel_params(&full, f, (size_t)(s8.sample_y + y) * SIDE + s8.sample_x + x, b);
                for (int s = 0; s < full.slots; s++) {
                    float step = (full.hi[f * full.slots + s] - full.lo[f * full.slots + s]) /
                                 65535.0f;
                    assert_true(fabsf(a[s] - b[s]) <= 1.01f * step + 1e-6f);
                }
            }
}

static void same_seed_same_model(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_rf_opts o = btf_rf_defaults();
    o.threads = 1;
    btf_rf_sample_opts so = sample_opts(8, 24, 20, 7);
    btf_rf_model m;
    TU_OK(btf_rf_fit_sampled(ds, &o, &so, &m, &e), &e);
    assert_int_equal(m.sample_x, s8.sample_x);
    assert_int_equal(m.sample_y, s8.sample_y);
    assert_memory_equal(m.map, s8.map, (size_t)24 * 20 * 2 * sizeof(uint16_t));
    assert_memory_equal(m.codes, s8.codes, (size_t)m.fields * 64 * m.slots * sizeof(uint16_t));
    btf_rf_model_free(&m);
    /* another seed draws other blocks (the sample's place stays) */
    float *feat;
    int view;
    TU_OK(rf_feature_image(ds, 2, &feat, &view, &e), &e);
    assert_int_equal(view, 0);
    uint16_t *a = malloc((size_t)24 * 20 * 4), *b = malloc((size_t)24 * 20 * 4);
    rf_quilt_args q = {feat, SIDE, s8.sample_x, s8.sample_y, 8, 8, 24, 20, 4, 1, 0.1, 7, 2, 0,
                       {0, 0, 0, 0}};
    TU_OK(rf_quilt(&q, a, &e), &e);
    assert_memory_equal(a, s8.map, (size_t)24 * 20 * 4);
    q.seed = 8, q.threads = 1;
    TU_OK(rf_quilt(&q, b, &e), &e);
    assert_memory_not_equal(a, b, (size_t)24 * 20 * 4);
    q.threads = 2;
    TU_OK(rf_quilt(&q, a, &e), &e);
    assert_memory_equal(a, b, (size_t)24 * 20 * 4);
    free(a), free(b), free(feat);
}

/* A place that covers most of a side (a 64 x 43 sample on a 64 x 64
 * torus: 21 rows left, less than a block of 43 less two overlaps of 7)
 * keeps its texels beyond one overlap of its edges: the one block of the
 * rest is shortened to the rest and an overlap at each end. A whole block
 * there wrapped 15 rows into the place. */
static void short_rest_keeps_the_place(void **state)
{
    (void)state;
    enum { W = 64, H = 43, N = 64, BLOCK = 43, OV = 7 };
    float *feat = malloc((size_t)W * H * RF_FEATURES * sizeof(float));
    uint16_t *map = malloc((size_t)N * N * 2 * sizeof(uint16_t));
    assert_non_null(feat);
    assert_non_null(map);
    uint64_t x = 12345;
    for (size_t i = 0; i < (size_t)W * H * RF_FEATURES; i++) {
        x = x * 6364136223846793005ull + 1442695040888963407ull;
        feat[i] = (float)(x >> 40) / (float)(1u << 24);
    }
    for (int seed = 1; seed <= 4; seed++) {
        rf_quilt_args q = {feat, W, 0, 0, W, H, N, N, BLOCK, OV, 0.0, (uint64_t)seed, 1, 96,
                           {0, 0, 0, 0}};
        btf_error e = {0};
        TU_OK(rf_quilt(&q, map, &e), &e);
        for (int y = OV; y < H - OV; y++)
            for (int c = 0; c < W; c++) {
                size_t s = (size_t)y * N + c;
                assert_int_equal(map[2 * s], c);
                assert_int_equal(map[2 * s + 1], y);
            }
        for (size_t s = 0; s < (size_t)N * N; s++)
            assert_true(map[2 * s] < W && map[2 * s + 1] < H);
    }
    free(feat);
    free(map);
}

/* A sample of the whole image on a surface of its size is the whole fit:
 * the same codes, the identity map, the same renders and error. */
static void whole_sample_is_the_whole_fit(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_rf_opts o = btf_rf_defaults();
    o.threads = 2;
    btf_rf_fit_info info;
    o.info = &info;
    btf_rf_sample_opts so = sample_opts(SIDE, 0, 0, 3);
    btf_rf_model m;
    TU_OK(btf_rf_fit_sampled(ds, &o, &so, &m, &e), &e);
    assert_int_equal(m.sample_x, 0);
    assert_int_equal(m.sample_y, 0);
    assert_int_equal(m.surface_width, SIDE);
    size_t planes = (size_t)m.fields * m.slots;
    assert_memory_equal(m.lo, full.lo, planes * sizeof(float));
    assert_memory_equal(m.hi, full.hi, planes * sizeof(float));
    assert_memory_equal(m.codes, full.codes, planes * SIDE * SIDE * sizeof(uint16_t));
    for (int t = 0; t < SIDE * SIDE; t++) {
        assert_int_equal(m.map[2 * t], t % SIDE);
        assert_int_equal(m.map[2 * t + 1], t / SIDE);
    }
    /* btf__rf_error adds per image, the fit per texel row: the same sum in
     * another order */
    assert_true(fabs(info.mean_abs_error - full_info.mean_abs_error) <=
                1e-9 * full_info.mean_abs_error);
    assert_true(info.sample_mean_abs_error == full_info.mean_abs_error);
    btf_dir views[3] = {{0, 0}, {37.5, 100}, {75, 345}}, light = {45, 20};
    for (int k = 0; k < 3; k++) {
        btf_image a, b;
        TU_OK(btf__rf_render_flat(&m, views[k], light, 40, 23, 2, &a, &e), &e);
        TU_OK(btf__rf_render_flat(&full, views[k], light, 40, 23, 2, &b, &e), &e);
        assert_memory_equal(a.data, b.data, (size_t)40 * 23 * 3 * sizeof(float));
        btf_image_free(&a);
        btf_image_free(&b);
    }
    btf_rf_model_free(&m);
}

static void one_texel_sample(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_rf_opts o = btf_rf_defaults();
    o.threads = 2;
    btf_rf_sample_opts so = sample_opts(1, 9, 5, 1);
    btf_rf_model m;
    TU_OK(btf_rf_fit_sampled(ds, &o, &so, &m, &e), &e);
    assert_int_equal(m.width, 1);
    assert_int_equal(m.height, 1);
    for (int t = 0; t < 9 * 5; t++)
        assert_true(m.map[2 * t] == 0 && m.map[2 * t + 1] == 0);
    btf_image img;
    TU_OK(btf__rf_render_flat(&m, (btf_dir){30, 60}, (btf_dir){45, 0}, 0, 0, 1, &img, &e), &e);
    assert_int_equal(img.width, 9);
    assert_int_equal(img.height, 5);
    assert_image_finite(&img);
    for (size_t i = 3; i < (size_t)9 * 5 * 3; i++) /* one texel everywhere */
        assert_true(img.data[i] == img.data[i % 3]);
    btf_image_free(&img);
    double err;
    TU_OK(btf__rf_error(ds, &m, 2, &err, NULL, &e), &e);
    assert_true(isfinite(err) && err > 0.0);
    btf_rf_model_free(&m);
}

/* ------------------------------------------------- every evaluation path */

static void every_path_goes_through_the_map(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_dir view = {30, 60}, light = {45, 40};
    btf_image img;
    TU_OK(btf__rf_render_flat(&s8, view, light, 0, 0, 2, &img, &e), &e);
    assert_int_equal(img.width, 24); /* the surface, not the sample */
    assert_int_equal(img.height, 20);
    assert_image_finite(&img);
    for (int y = 0; y < 20; y++)
        for (int x = 0; x < 24; x++) {
            float rgb[3];
            btf__rf_eval(&s8, view, light, x + 48, y - 40, rgb); /* wrapped */
            const float *p = img.data + 3 * ((size_t)y * 24 + x);
            for (int k = 0; k < 3; k++)
                assert_true(fabsf(rgb[k] - p[k]) <= 1e-6f * (1.0f + fabsf(p[k])));
        }
    btf_image_free(&img);
    /* at a measured pair, surface texel (x, y) is the field of its sample texel */
    btf_dir mv = s8.views.dirs[7], ml = s8.lights.dirs[9];
    TU_OK(btf__rf_render_flat(&s8, mv, ml, 24, 20, 1, &img, &e), &e);
    btf_rf_model bare = s8; /* the sample alone, a model without a map */
    bare.map = NULL;
    for (int t = 0; t < 24 * 20; t++) {
        float want[3];
        btf__rf_eval_field(&bare, 7, mv, ml, s8.map[2 * t], s8.map[2 * t + 1], want);
        for (int k = 0; k < 3; k++)
            assert_true(fabsf(img.data[3 * t + k] - want[k]) <= 1e-6f * (1.0f + want[k]));
    }
    btf_image_free(&img);
    /* a scene: finite, non-negative */
    btf_scene sc;
    TU_OK(btf_scene_sphere((btf_dir){45, 135}, 8.0, &sc, &e), &e);
    btf_render_info ri;
    TU_OK(btf__rf_render_scene(&s8, &sc, 48, 40, 2, &img, &ri, &e), &e);
    assert_image_finite(&img);
    btf_image_free(&img);
    btf_scene_free(&sc);
}

/* ------------------------------------------------ choosing and refusing */

/* On a ramp in x the window whose mean is the whole's is the middle one;
 * every row is alike, so the first. A window of the whole image is (0, 0). */
static void sample_choice_is_the_closest_window(void **state)
{
    (void)state;
    float f[16 * 6 * RF_FEATURES];
    for (int y = 0; y < 6; y++)
        for (int x = 0; x < 16; x++)
            for (int k = 0; k < RF_FEATURES; k++)
                f[(y * 16 + x) * RF_FEATURES + k] = (float)x * (k + 1);
    int x, y;
    btf_error e = {0};
    TU_OK(rf_sample_choose(f, 16, 6, 4, 3, &x, &y, &e), &e);
    assert_int_equal(x, 6);
    assert_int_equal(y, 0);
    TU_OK(rf_sample_choose(f, 16, 6, 16, 6, &x, &y, &e), &e);
    assert_true(x == 0 && y == 0);
    assert_int_equal(rf_sample_choose(f, 16, 6, 17, 6, &x, &y, &e), BTF_E_ARG);
    assert_int_equal(rf_sample_choose(f, 16, 6, 0, 6, &x, &y, &e), BTF_E_ARG);
}

static void expect_arg_error(btf_rf_sample_opts so, const char *what)
{
    btf_error e = {0};
    btf_rf_model m;
    int rc = btf_rf_fit_sampled(ds, NULL, &so, &m, &e);
    if (rc != BTF_E_ARG)
        print_error("%s: rc %d, %s\n", what, rc, e.msg);
    assert_int_equal(rc, BTF_E_ARG);
    assert_null(strchr(e.msg, '\n'));
    assert_null(m.codes);
    assert_null(m.map);
}

static void bad_options_are_errors(void **state)
{
    (void)state;
    expect_arg_error(sample_opts(0, 0, 0, 1), "sample 0");
    expect_arg_error(sample_opts(SIDE + 1, 0, 0, 1), "sample larger than the image");
    expect_arg_error(sample_opts(-3, 0, 0, 1), "negative sample");
    expect_arg_error(sample_opts(8, BTF_RF_MAX_SURFACE_SIDE + 1, 8, 1), "surface too wide");
    expect_arg_error(sample_opts(8, 8, -1, 1), "negative surface");
    btf_rf_sample_opts so = sample_opts(8, 0, 0, 1);
    so.block = 9;
    expect_arg_error(so, "block larger than the sample");
    so.block = 8, so.overlap = 5;
    expect_arg_error(so, "overlap above half the block");
    so = sample_opts(8, 0, 0, 1);
    so.placed = 1, so.x = 9, so.y = 0;
    expect_arg_error(so, "placed outside");
    so.x = 0, so.tolerance = -1.0;
    expect_arg_error(so, "negative tolerance");
    btf_error e = {0};
    btf_rf_model m;
    assert_int_equal(btf_rf_fit_sampled(ds, NULL, NULL, &m, &e), BTF_E_ARG);
    assert_int_equal(btf_rf_fit_sampled(NULL, NULL, &so, &m, &e), BTF_E_ARG);
    /* the crop of btf_rf_fit itself */
    btf_rf_opts o = btf_rf_defaults();
    o.crop_width = 4, o.crop_height = 0;
    assert_int_equal(btf_rf_fit(ds, &o, &m, &e), BTF_E_ARG);
    o.crop_height = 4, o.crop_x = SIDE - 3;
    assert_int_equal(btf_rf_fit(ds, &o, &m, &e), BTF_E_ARG);
    assert_null(m.codes);
}

/* ---------------------------------------------------------------- files */

static void assert_same_sampled(const btf_rf_model *a, const btf_rf_model *b)
{
    assert_int_equal(a->width, b->width);
    assert_int_equal(a->height, b->height);
    assert_int_equal(a->fields, b->fields);
    assert_int_equal(a->surface_width, b->surface_width);
    assert_int_equal(a->surface_height, b->surface_height);
    assert_int_equal(a->sample_x, b->sample_x);
    assert_int_equal(a->sample_y, b->sample_y);
    assert_true(!a->map == !b->map);
    if (a->map)
        assert_memory_equal(a->map, b->map,
                            (size_t)a->surface_width * a->surface_height * 2 * sizeof(uint16_t));
    size_t planes = (size_t)a->fields * a->slots;
    assert_memory_equal(a->codes, b->codes, planes * a->width * a->height * sizeof(uint16_t));
}

static void file_round_trip(void **state)
{
    (void)state;
    btf_error e = {0};
    unsigned char *d1, *d2;
    size_t n1, n2;
    TU_OK(btf_rf_encode(&s8, &d1, &n1, &e), &e);
    assert_int_equal(d1[11] | d1[12] << 8, 2); /* format 2.0: a sampled model */
    assert_int_equal(d1[13] | d1[14] << 8, 0);
    btf_rf_model back;
    TU_OK(btf_rf_decode(d1, n1, "s.rf", &back, &e), &e);
    assert_same_sampled(&s8, &back);
    TU_OK(btf_rf_encode(&back, &d2, &n2, &e), &e);
    assert_int_equal(n1, n2);
    assert_memory_equal(d1, d2, n1);
    btf_rf_model_free(&back);
    free(d2);
    /* the bytes: the map is a small part of the file */
    btf_rf_bytes b;
    TU_OK(btf_rf_model_bytes(&s8, &b, &e), &e);
    assert_int_equal(b.file, n1);
    assert_int_equal(b.map, 24 * 20 * 4);
    assert_int_equal(b.coefficients, (uint64_t)s8.fields * s8.slots * (2 * 64 + 8));
    assert_true(b.file_map > 0 && b.file_map < b.map);
    free(d1);
    /* a model without a map is still written as format 1.0 */
    TU_OK(btf_rf_encode(&full, &d1, &n1, &e), &e);
    assert_int_equal(d1[11] | d1[12] << 8, 1);
    TU_OK(btf_rf_model_bytes(&full, &b, &e), &e);
    assert_true(b.map == 0 && b.file_map == 0 && b.file == n1);
    free(d1);
}

/* A tiny sampled model: 2 views, 1 light, a 2 x 1 sample on a 3 x 2 surface. */
static void tiny_sampled(btf_rf_model *m)
{
    tu_rf_tiny_model(m, 2, 1);
    m->surface_width = 3, m->surface_height = 2, m->sample_x = 1, m->sample_y = 0;
    m->map = calloc(12, sizeof(uint16_t));
    for (int t = 0; t < 6; t++)
        m->map[2 * t] = (uint16_t)((t + 1) % 2);
}

/* A format error of one line that leaves no map either. */
static void expect_format_error(const unsigned char *d, size_t n, const char *what)
{
    btf_rf_model m;
    btf_error e = {0};
    tu_rf_expect_format_error(d, n, what, &m, &e);
    assert_null(strchr(e.msg, '\n'));
    assert_null(m.map);
}

static void corrupt_maps_are_errors(void **state)
{
    (void)state;
    btf_rf_model m;
    tiny_sampled(&m);
    btf_error e = {0};
    unsigned char *d;
    size_t n;
    TU_OK(btf_rf_encode(&m, &d, &n, &e), &e);
    btf_rf_model back;
    TU_OK(btf_rf_decode(d, n, "ok", &back, &e), &e);
    assert_same_sampled(&m, &back);
    btf_rf_model_free(&back);
    tu_rf_expect_damage_fails(d, n, expect_format_error);
    /* the payload, for changes with a valid CRC */
    unsigned char payload[4096];
    size_t plen = tu_rf_payload(d, payload, sizeof payload);
    size_t rfmp = tu_rf_section(payload, plen, "RFMP");
    assert_true(rfmp > 0);
    unsigned char p2[4096];
    size_t sz;
    unsigned char *w = tu_rf_rewrap(payload, plen, 2, &sz); /* unchanged: valid */
    TU_OK(btf_rf_decode(w, sz, "ok", &back, &e), &e);
    assert_same_sampled(&m, &back);
    btf_rf_model_free(&back);
    free(w);
    w = tu_rf_rewrap(payload, plen, 1, &sz); /* a map in a format 1 file */
    expect_format_error(w, sz, "RFMP in format 1");
    free(w);
    struct { size_t off; unsigned char val; const char *what; } bad[] = {
        {rfmp + 0, 2, "section version 2"},  {rfmp + 1, 0, "surface width 0"},
        {rfmp + 4, 1, "surface width huge"}, {rfmp + 5, 0, "surface height 0"},
        {rfmp + 12, 1, "sample x huge"},     {rfmp + 17, 2, "x shift past the sample"},
        {rfmp + 17 + 6 + 1, 1, "x shift high byte"}, {rfmp + 17 + 12, 1, "y shift past the sample"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        memcpy(p2, payload, plen);
        p2[bad[i].off] = bad[i].val;
        w = tu_rf_rewrap(p2, plen, 2, &sz);
        expect_format_error(w, sz, bad[i].what);
        free(w);
    }
    /* a section of the wrong size; a format 2 file without a map */
    memcpy(p2, payload, plen);
    p2[rfmp - 4] ^= 1;
    w = tu_rf_rewrap(p2, plen, 2, &sz);
    expect_format_error(w, sz, "RFMP length");
    free(w);
    memcpy(p2, payload, plen);
    memcpy(p2 + rfmp - 8, "XXXX", 4);
    w = tu_rf_rewrap(p2, plen, 2, &sz);
    expect_format_error(w, sz, "format 2 without RFMP");
    free(w);
    /* the encoder refuses a map entry out of the sample */
    m.map[4] = 2;
    unsigned char *refused = NULL;
    assert_int_equal(btf_rf_encode(&m, &refused, &sz, &e), BTF_E_DATA);
    assert_null(refused);
    m.map[4] = 1, m.surface_width = 0;
    assert_int_equal(btf_rf_encode(&m, &refused, &sz, &e), BTF_E_DATA);
    free(d);
    btf_rf_model_free(&m);
}

/* ---------------------------------------------------------------- report */

static void report_of_a_sampled_model(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_rf_opts o = btf_rf_defaults();
    o.threads = 2;
    btf_rf_sample_opts so = sample_opts(8, 0, 0, 2);
    btf_rf_model m;
    TU_OK(btf_rf_fit_sampled(ds, &o, &so, &m, &e), &e);
    btf_report_opts ro = btf_report_defaults();
    ro.quality.views = 2, ro.quality.lights = 2;
    ro.sphere_size = 32, ro.worst = 1, ro.threads = 2;
    btf_report_summary sum;
    char d[4096];
    snprintf(d, sizeof d, "%s/sampled-report", tu_dir);
    TU_OK(btf__rf_report_write(ds, &m, d, &ro, &sum, &e), &e);
    btf_rf_bytes b;
    TU_OK(btf_rf_model_bytes(&m, &b, &e), &e);
    assert_int_equal(sum.model_bytes, b.file);
    double mae;
    TU_OK(btf__rf_error(ds, &m, 2, &mae, NULL, &e), &e);
    assert_true(sum.mean_abs_error == mae);
    int status;
    char *json = tu_capture(tu_fmt("cat %s/report.json", d), &status);
    assert_non_null(strstr(json, "\"sample\""));
    assert_non_null(strstr(json, "\"map_bytes\":\t1024"));
    free(json);
    char *html = tu_capture(tu_fmt("cat %s/index.html", d), &status);
    assert_non_null(strstr(html, "coordinate map"));
    free(html);
    btf_rf_model_free(&m);
}

/* --------------------------------------------------------------- commands */

static void command_line(void **state)
{
    (void)state;
    const char *cli = tu_cli();
    char m[4096], out[4096];
    snprintf(m, sizeof m, "%s/cli-s.btfcar", tu_dir);
    snprintf(out, sizeof out, "%s", tu_fmt("%s/x.btfcar", tu_dir));
    int status;
    char *text = tu_capture(tu_fmt("%s analyse %s --family rf --sample 8 --surface 20x12 "
                                   "--seed 4 --threads 2 -o %s", cli, dataset_path, m), &status);
    assert_int_equal(status, 0);
    assert_non_null(strstr(text, "sample        8x8 texels"));
    assert_non_null(strstr(text, "20x12 surface texels"));
    free(text);
    btf_rf_model back;
    btf_error e = {0};
    TU_OK(btf__rf_read(m, &back, &e), &e);
    assert_int_equal(back.width, 8);
    assert_int_equal(back.surface_width, 20);
    assert_int_equal(back.surface_height, 12);
    btf_rf_model_free(&back);
    text = tu_capture(tu_fmt("%s info %s", cli, m), &status);
    assert_int_equal(status, 0);
    assert_non_null(strstr(text, "(format 2.0"));
    assert_non_null(strstr(text, "coordinate map"));
    free(text);
    text = tu_capture(tu_fmt("%s info --json %s", cli, m), &status);
    assert_int_equal(status, 0);
    assert_non_null(strstr(text, "\"sample\": {\"x\": "));
    assert_non_null(strstr(text, "\"map_bytes\": 960"));
    free(text);
    const char *png = tu_fmt("%s/s.png", tu_dir);
    char p[4096];
    snprintf(p, sizeof p, "%s", png);
    assert_int_equal(tu_run(tu_fmt("%s render -q %s --view 30,60 --light 45,0 --size 32x24 "
                                   "-o %s", cli, m, p), NULL), 0);
    /* bad --sample values: one line, exit status 2 */
    const char *bad[] = {"0", "17", "abc", "8x", "-2", "8x0", "1.5"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        char *err = NULL;
        int rc = tu_run(tu_fmt("%s analyse %s --family rf --sample %s -o %s", cli, dataset_path,
                               bad[i], out), &err);
        if (rc != 2)
            print_error("--sample %s: exit %d, %s\n", bad[i], rc, err ? err : "");
        assert_int_equal(rc, 2);
        assert_non_null(strstr(err, "--sample"));
        char *nl = strchr(err, '\n');
        assert_true(nl && nl[1] == '\0');
        free(err);
    }
    assert_int_equal(tu_run(tu_fmt("%s analyse %s --family rf --surface 20 -o %s", cli,
                                   dataset_path, out), NULL), 2);
    assert_int_equal(tu_run(tu_fmt("%s analyse %s --family rf --seed 3 -o %s", cli,
                                   dataset_path, out), NULL), 2);
    assert_int_equal(tu_run(tu_fmt("%s analyse %s --sample 8 -o %s", cli, dataset_path, out),
                            NULL), 2);
    assert_int_equal(tu_run(tu_fmt("%s analyse %s --family rf --sample 8 --surface 9000 -o %s",
                                   cli, dataset_path, out), NULL), 2);
    assert_int_equal(access(out, F_OK), -1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(map_stays_in_the_sample),
        cmocka_unit_test(sample_keeps_its_place),
        cmocka_unit_test(short_rest_keeps_the_place),
        cmocka_unit_test(same_seed_same_model),
        cmocka_unit_test(whole_sample_is_the_whole_fit),
        cmocka_unit_test(one_texel_sample),
        cmocka_unit_test(every_path_goes_through_the_map),
        cmocka_unit_test(sample_choice_is_the_closest_window),
        cmocka_unit_test(bad_options_are_errors),
        cmocka_unit_test(file_round_trip),
        cmocka_unit_test(corrupt_maps_are_errors),
        cmocka_unit_test(report_of_a_sampled_model),
        cmocka_unit_test(command_line),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
