/*
 * test_structure.c — the structure layer of format 1.5 (docs/model.md,
 * "Structure"; docs/model-format.md, "STRC" and "GAIN"): the pair gains'
 * codes, the horizon map and the light's visibility over it
 * (src/render/btf_horizon.h, src/model/horizon.c), the file's round trip
 * and its refusals, and the analysis of generated materials: a weave of
 * two yarns gets a colour layer and a leather does not, every model gets
 * shadows and gains, and a measured pair's render keeps its mean colour.
 */
#include "testutil.h"
#include "model/model.h"
#include "render/btf_horizon.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void gain_codes(void **state)
{
    (void)state;
    assert_int_equal(btf__gain_code(1.0f), 0);
    assert_int_equal(btf__gain_code(2.0f), 64);
    assert_int_equal(btf__gain_code(0.25f), -128);
    assert_int_equal(btf__gain_code(100.0f), 127); /* held at the grid's end */
    assert_int_equal(btf__gain_code(1e-9f), -128);
    assert_int_equal(btf__gain_code(NAN), 0);      /* nothing known: 1 */
    assert_int_equal(btf__gain_code(-3.0f), 0);
    assert_int_equal(btf__gain_code(INFINITY), 0);
    for (float g = 0.3f; g < 3.9f; g *= 1.013f) {
        float back = btf__gain_value(btf__gain_code(g));
        assert_true(fabsf(back / g - 1.0f) < 0.0055f); /* half a 1/64-octave step */
    }
}

/* A wall 4 texels high from column 16 on, 32 x 8 texels. */
static float *wall(void)
{
    float *h = malloc(32 * 8 * sizeof(float));
    for (int i = 0; i < 32 * 8; i++)
        h[i] = i % 32 >= 16 ? 4.0f : 0.0f;
    return h;
}

static float horizon(const uint32_t *hz, int x, int y, int d)
{
    size_t i = (size_t)y * 32 + x;
    return btf_horizon_decode(hz[2 * i], hz[2 * i + 1], d);
}

static void horizon_of_a_wall(void **state)
{
    (void)state;
    btf_error e = {0};
    float *h = wall();
    uint32_t *hz = NULL, *wrapped = NULL;
    TU_OK(btf__horizon_map(h, 32, 8, 0, 1, &hz, &e), &e);
    TU_OK(btf__horizon_map(h, 32, 8, 1, 2, &wrapped, &e), &e);
    /* two texels before the wall, towards it (+x, direction 0): tan 4/2 */
    assert_true(fabsf(horizon(hz, 14, 4, 0) - 2.0f) < 1.0f / 64);
    /* diagonally (direction 1, +x +y: one row up the image per column) the
     * wall is 2 steps of sqrt 2 away */
    assert_true(fabsf(horizon(hz, 14, 4, 1) - 4.0f / (2.0f * sqrtf(2.0f))) < 1.0f / 64);
    assert_true(horizon(hz, 14, 4, 4) == 0.0f); /* away from it: open sky */
    assert_true(horizon(hz, 20, 4, 0) == 0.0f); /* on top of it */
    /* beyond the sample nothing is known; round the torus the wall is 3
     * texels behind column 2 (columns 16..29 are 3 or more away) */
    assert_true(horizon(hz, 2, 4, 4) == 0.0f);
    assert_true(fabsf(horizon(wrapped, 2, 4, 4) - 4.0f / 3.0f) < 1.0f / 64);
    /* the same threads count the same */
    uint32_t *again = NULL;
    TU_OK(btf__horizon_map(h, 32, 8, 1, 1, &again, &e), &e);
    assert_memory_equal(again, wrapped, 32 * 8 * 2 * sizeof(uint32_t));
    free(again);
    free(hz);
    free(wrapped);
    free(h);
}

static void visibility(void **state)
{
    (void)state;
    /* horizon tangent 2: a light from that side at elevation tangent 1 is
     * hidden, at 3 seen, at 2 half seen (the soft edge) */
    float e45 = sqrtf(0.5f);
    assert_true(btf_horizon_vis(2.0f, e45, 0.0f, e45, 1.0f) == 0.0f);
    float c = 1.0f / sqrtf(10.0f);
    assert_true(btf_horizon_vis(2.0f, c, 0.0f, 3.0f * c, 1.0f) == 1.0f);
    float d = 1.0f / sqrtf(5.0f);
    assert_true(fabsf(btf_horizon_vis(2.0f, d, 0.0f, 2.0f * d, 1.0f) - 0.5f) < 1e-4f);
    /* the relief scales heights: at a quarter of it the same light is seen */
    assert_true(btf_horizon_vis(2.0f, e45, 0.0f, e45, 0.25f) == 1.0f);
    assert_true(fabsf(btf_horizon_vis(2.0f, e45, 0.0f, e45, 0.5f) - 0.5f) < 1e-4f);
    assert_true(btf_horizon_vis(2.0f, e45, 0.0f, e45, 0.0f) == 1.0f); /* flat */
    assert_true(btf_horizon_vis(2.0f, 0.0f, 0.0f, 1.0f, 1.0f) == 1.0f); /* the pole */
    assert_true(btf_horizon_vis(NAN, e45, 0.0f, e45, 1.0f) == 0.0f);  /* never NaN */
    assert_true(btf_horizon_vis(1e30f, e45, 0.0f, e45, 1e30f) == 0.0f);
    /* the diamond azimuth: exact at the eight mapped directions, monotone */
    float want[8][3] = {{1, 0, 0}, {1, 1, 1}, {0, 1, 2}, {-1, 1, 3},
                        {-1, 0, 4}, {-1, -1, 5}, {0, -1, 6}, {1, -1, 7}};
    for (int i = 0; i < 8; i++)
        assert_true(btf_horizon_azimuth(want[i][0], want[i][1]) == want[i][2]);
    float prev = -1.0f;
    for (int k = 0; k < 360; k++) {
        double a = k * 3.14159265358979 / 180.0;
        float t = btf_horizon_azimuth((float)cos(a), (float)sin(a));
        assert_true(t >= 0.0f && t < 8.0f && (t > prev || k == 0));
        prev = t;
    }
    assert_true(btf_horizon_azimuth(0.0f, 0.0f) == 0.0f);
}

/* A small model with every layer of format 1.5. */
static void layered_model(btf_model *m)
{
    btf_error e = {0};
    memset(m, 0, sizeof *m);
    btf_dir v[3] = {{0, 0}, {30, 90}, {30, 270}}, l[2] = {{0, 0}, {45, 90}};
    TU_OK(btf_dirset_from_list(&m->views, v, 3, &e), &e);
    TU_OK(btf_dirset_from_list(&m->lights, l, 2, &e), &e);
    m->n_subspaces = 1;
    m->subspaces = calloc(1, sizeof *m->subspaces);
    m->subspaces[0].width = m->subspaces[0].height = 16;
    m->subspaces[0].basis[0] = m->subspaces[0].basis[4] = m->subspaces[0].basis[8] = 1.0f;
    m->subspaces[0].mean[0] = m->subspaces[0].mean[1] = m->subspaces[0].mean[2] = 0.4f;
    m->subspaces[0].levels = 1;
    m->index = calloc(6, 1);
    int n = 16;
    m->range_width = m->range_height = n;
    m->range_texel = 1.0f;
    m->range = malloc((size_t)n * n * sizeof(float));
    m->albedo = malloc((size_t)n * n * sizeof(float));
    m->chroma = malloc((size_t)n * n * 3 * sizeof(float));
    for (int i = 0; i < n * n; i++) {
        m->range[i] = (float)(i % 7) / 32.0f;
        m->albedo[i] = btf__albedo_value(100u + (unsigned)(i % 50));
        for (int c = 0; c < 3; c++)
            m->chroma[3 * i + c] = btf__albedo_value(128u + (unsigned)((i + 3 * c) % 9) - 4u);
    }
    m->ambient = 0.125f;
    m->shadows = 1;
    m->gain = malloc(6 * 3 * sizeof(float));
    for (int i = 0; i < 18; i++)
        m->gain[i] = btf__gain_value(i * 13 - 100);
}

static void file_round_trip(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_model m, back;
    layered_model(&m);
    unsigned char *f = NULL;
    size_t size = 0;
    TU_OK(btf_model_encode(&m, &f, &size, &e), &e);
    assert_int_equal(f[13], 5); /* format 1.5 */
    TU_OK(btf_model_decode(f, size, "layered", &back, &e), &e);
    size_t n = 16 * 16;
    assert_int_equal(back.shadows, 1);
    assert_true(back.ambient == m.ambient);
    assert_memory_equal(back.albedo, m.albedo, n * sizeof(float));
    assert_memory_equal(back.chroma, m.chroma, 3 * n * sizeof(float));
    assert_memory_equal(back.gain, m.gain, 18 * sizeof(float));
    btf_model_free(&back);

    /* an unknown flag bit in STRC, and a colour layer cut short */
    size_t pn;
    unsigned char *p = tu_model_payload(f, &pn);
    size_t strc = tu_rf_section(p, pn, "STRC"); /* after its tag and length */
    assert_true(strc > 0);
    unsigned char *flags = p + strc + 8 + n; /* w h ambient, the codes */
    assert_int_equal(*flags, 3);
    *flags = 0x83;
    size_t bad_n;
    unsigned char *bad = tu_model_rewrap(p, pn, 5, &bad_n);
    assert_int_equal(btf_model_decode(bad, bad_n, "flags", &back, &e), BTF_E_FORMAT);
    assert_non_null(strstr(e.msg, "STRC"));
    assert_null(strchr(e.msg, '\n'));
    free(bad);
    *flags = 1; /* shadows only, yet the colour planes follow */
    bad = tu_model_rewrap(p, pn, 5, &bad_n);
    assert_int_equal(btf_model_decode(bad, bad_n, "planes", &back, &e), BTF_E_FORMAT);
    free(bad);
    free(p);
    free(f);

    /* a gain of 0, shadows or colours without the albedo: refused to write */
    m.gain[5] = 0.0f;
    assert_int_equal(btf_model_encode(&m, &f, &size, &e), BTF_E_DATA);
    assert_non_null(strstr(e.msg, "pair gain"));
    m.gain[5] = 1.0f;
    free(m.albedo);
    m.albedo = NULL;
    assert_int_equal(btf_model_encode(&m, &f, &size, &e), BTF_E_DATA);
    assert_non_null(strstr(e.msg, "without a structure layer"));
    btf_model_free(&m);
}

/* A periodic relief of repeat (6, 6), (6, -6) (64 x 64 texels, texel 1)
 * with an albedo pattern; noise 1: random heights instead (no lattice). */
static void lattice_model(btf_model *m, int noise)
{
    memset(m, 0, sizeof *m);
    int n = 64;
    m->range_width = m->range_height = n;
    m->range_texel = 1.0f;
    m->range = malloc((size_t)n * n * sizeof(float));
    m->albedo = malloc((size_t)n * n * sizeof(float));
    btf_rng r;
    btf__rng_seed(&r, 5);
    for (int i = 0; i < n * n; i++) {
        double x = i % n, y = i / n, pi2 = 2.0 * 3.14159265358979 / 12.0;
        double c = cos(pi2 * x) * cos(pi2 * y);
        m->range[i] = noise ? (float)btf__rng_uniform(&r) : (float)(2.0 * c);
        m->albedo[i] = (float)(1.0 + 0.3 * (noise ? btf__rng_uniform(&r) : c));
    }
}

static void lattice_keeps_the_repeat(void **state)
{
    (void)state;
    btf_model m;
    lattice_model(&m, 1);
    int L[4];
    assert_int_equal(btf__structure_lattice(&m, L), 0); /* noise: no repeat */
    btf_model_free(&m);
    lattice_model(&m, 0);
    assert_int_equal(btf__structure_lattice(&m, L), 1);
    print_message("lattice (%d, %d) (%d, %d)\n", L[0], L[1], L[2], L[3]);
    assert_int_equal(abs(L[0] * L[3] - L[1] * L[2]), 72); /* the cell of (6,6), (6,-6) */
    for (int k = 0; k < 4; k += 2)
        assert_true((L[k] + L[k + 1]) % 12 == 0 && (L[k] - L[k + 1]) % 12 == 0);
    /* every texel of a quilted surface (a whole number of repeats) comes
     * from a block whose offset is a lattice vector */
    uint16_t *map = NULL;
    btf_error e = {0};
    TU_OK(btf__structure_coords(&m, 192, 144, 3, &map, &e), &e);
    int off = 0;
    for (int y = 0; y < 144; y++)
        for (int x = 0; x < 192; x++) {
            int dx = map[2 * (y * 192 + x)] - x, dy = map[2 * (y * 192 + x) + 1] - y;
            off += (dx + dy) % 12 != 0 || (dx - dy) % 12 != 0;
        }
    assert_int_equal(off, 0);
    free(map);
    btf_model_free(&m);
}

/* The relative error of the render's mean colour at measured pairs against
 * the measured images' (flat renders at the sample's size), summed over
 * the pairs and channels. */
static double mean_colour_error(const btf_model *m, const btf_dataset *ds, const char *what,
                                double bound)
{
    btf_error e = {0};
    btf_dir pairs[4][2] = {{{0, 0}, {0, 0}}, {{45, 340}, {60, 144}}, {{75, 90}, {30, 60}},
                           {{30, 330}, {75, 225}}};
    double sum = 0.0;
    for (int i = 0; i < 4; i++) {
        int v = 0, l = 0;
        for (int j = 0; j < m->views.count; j++)
            if (fabs(m->views.dirs[j].theta - pairs[i][0].theta) < 0.5 &&
                fabs(m->views.dirs[j].phi - pairs[i][0].phi) < 0.5)
                v = j;
        for (int j = 0; j < m->lights.count; j++)
            if (fabs(m->lights.dirs[j].theta - pairs[i][1].theta) < 0.5 &&
                fabs(m->lights.dirs[j].phi - pairs[i][1].phi) < 0.5)
                l = j;
        btf_image meas = {0}, r = {0};
        TU_OK(btf_dataset_read(ds, v, l, &meas, &e), &e);
        btf_render_opts ro = btf_render_defaults();
        ro.width = ro.height = 32;
        TU_OK(btf_render_flat(m, m->views.dirs[v], m->lights.dirs[l], &ro, &r, NULL, &e), &e);
        float a[3], b[3];
        btf__image_mean_rgb(&meas, a);
        btf__image_mean_rgb(&r, b);
        for (int c = 0; c < 3; c++) {
            sum += fabs(b[c] / a[c] - 1.0);
            if (fabs(b[c] / a[c] - 1.0) >= bound)
                print_message("%s pair %d channel %d: measured %.4f, rendered %.4f\n", what, i,
                              c, a[c], b[c]);
            assert_true(fabs(b[c] / a[c] - 1.0) < bound);
        }
        btf_image_free(&meas);
        btf_image_free(&r);
    }
    print_message("%s: mean |rendered / measured - 1| of the mean colours %.4f\n", what,
                  sum / 12.0);
    return sum / 12.0;
}

/* Analysed generated materials (32 texels, all 81 x 81 pairs). */
static void analysed_layers(void **state)
{
    (void)state;
    btf_error e = {0};
    const char *names[2] = {"fabric", "leather"};
    for (int k = 0; k < 2; k++) {
        char path[512];
        btf_dataset *ds = NULL;
        assert_int_equal(tu_generate_dataset(names[k], 32, 3, path, sizeof path, &ds), 0);
        btf_model m, plain;
        btf_analyse_opts o = btf_analyse_defaults();
        TU_OK(btf_analyse(ds, &o, &m, &e), &e);
        o.no_gains = 1;
        TU_OK(btf_analyse(ds, &o, &plain, &e), &e);
        assert_non_null(m.albedo);
        assert_int_equal(m.shadows, 1);
        assert_non_null(m.gain);
        assert_null(plain.gain);
        assert_true(m.ambient >= 0.0f && m.ambient <= BTF_STRUCTURE_AMBIENT_MAX);
        /* the weave's blue and yellow yarns need colour; the brown leather not */
        assert_int_equal(m.chroma != NULL, k == 0);
        /* the gains bring each measured pair's mean colour closer */
        double with = mean_colour_error(&m, ds, tu_fmt("%s with gains", names[k]), 0.3);
        double without = mean_colour_error(&plain, ds, tu_fmt("%s without", names[k]), 1e9);
        assert_true(with < without);
        btf_model_free(&m);
        btf_model_free(&plain);
        btf_dataset_close(ds);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(gain_codes),
        cmocka_unit_test(horizon_of_a_wall),
        cmocka_unit_test(visibility),
        cmocka_unit_test(file_round_trip),
        cmocka_unit_test(lattice_keeps_the_repeat),
        cmocka_unit_test(analysed_layers),
    };
    return cmocka_run_group_tests(tests, tu_setup_dir, tu_teardown_dir);
}
