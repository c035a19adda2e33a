/* test_car.c — the CAR model (Haindl & Filip 2007, section II.C):
 * decorrelation, pyramid, estimation, Bayesian neighbourhood selection,
 * stability, synthesis and its margins. */
#include "synth/synth.h"
#include "synth/synth_testing.h"
#include "car/car.h"
#include "testutil.h"

#include "core/core.h"
#include "btf_shared.h" /* the sum order and the noise, for the direct recursion */

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static btf_car_band model(const char *spec, const float *gamma, float sigma, float mean)
{
    btf_car_band b;
    memset(&b, 0, sizeof b);
    btf_error e = {0};
    assert_int_equal(btf_neighbourhood_parse(spec, b.offsets, &b.n, &e), 0);
    for (int i = 0; i < b.n; i++)
        b.gamma[i] = gamma[i];
    b.sigma = sigma;
    b.mean = mean;
    return b;
}

typedef struct collect {
    double *data;
    int width;
    double sum, sum2;
    long n;
    int finite;
} collect;

static int collect_rows(void *user, int y, int nrows, const float *rows, btf_error *err)
{
    (void)err;
    collect *c = user;
    size_t n = (size_t)nrows * c->width;
    for (size_t i = 0; i < n; i++) {
        double v = rows[i];
        if (!isfinite(v))
            c->finite = 0;
        if (c->data)
            c->data[(size_t)y * c->width + i] = v;
        c->sum += v;
        c->sum2 += v * v;
    }
    c->n += (long)n;
    return 0;
}

/* A field of the model, w x h, with the given margin (< 0: the band's
 * own), row by row or as the generators choose, into a malloc'd double
 * array. */
static double *field_with(const btf_car_band *b, int margin, int w, int h, uint64_t seed,
                          int row_by_row)
{
    collect c = {.data = malloc((size_t)w * h * sizeof(double)), .width = w, .finite = 1};
    btf_error e = {0};
    btf_synth_opts o = {.width = w, .height = h, .seed = seed, .row_by_row = row_by_row};
    TU_OK(btf__car_synthesise_field(b, margin, 7, &o, collect_rows, &c, &e), &e);
    assert_true(c.finite);
    return c.data;
}

static double *field(const btf_car_band *b, int w, int h, uint64_t seed)
{
    return field_with(b, -1, w, h, seed, 0);
}

/* Subspace 0 of m, w x h (0: the analysed size), into an image. */
/* The CAR synthesis itself: colour matching (on by default) off. */
static void synth_image(const btf_model *m, int w, int h, uint64_t seed, btf_image *out)
{
    btf_error e = {0};
    btf_synth_opts o = {.width = w, .height = h, .seed = seed, .match_colours = -1};
    TU_OK(btf_synthesise_image(m, 0, &o, out, &e), &e);
}

/* A w x h colour texture from one 4-neighbour CAR field: red the field,
 * green the field read with column step green_step (1: the same pixels),
 * blue with step 7, each with its own offset and scale. */
static void car_texture(int w, int h, uint64_t seed, int green_step, btf_image *tex)
{
    btf_error e = {0};
    TU_OK(btf_image_alloc(tex, w, h, 3, &e), &e);
    const float g[4] = {0.45f, 0.4f, -0.2f, 0.1f};
    btf_car_band b = model("0:-1,-1:0,-1:-1,-1:1", g, 0.1f, 0.0f);
    double *f = field(&b, w, h, seed);
    int n = w * h;
    for (int i = 0; i < n; i++) {
        tex->data[3 * i] = (float)(0.5 + f[i]);
        tex->data[3 * i + 1] = (float)(0.3 + 0.5 * f[(i * green_step) % n]);
        tex->data[3 * i + 2] = (float)(0.2 + 0.2 * f[(i * 7) % n]);
    }
    free(f);
}

static void neighbourhood_spec(void **state)
{
    (void)state;
    btf_offset o[BTF_CAR_MAX_NEIGHBOURS];
    int n;
    btf_error e = {0};
    TU_OK(btf_neighbourhood_parse("0:-1,-1:0,-1:-1,-1:1", o, &n, &e), &e);
    assert_int_equal(n, 4);
    assert_true(o[3].row == -1 && o[3].col == 1);
    char buf[128];
    btf_neighbourhood_format(o, n, buf, sizeof buf);
    assert_string_equal(buf, "0:-1,-1:0,-1:-1,-1:1");
    const char *bad[] = {"0:1", "1:0", "0:0", "", "0:-1,", "a:b", "0:-1,0:-1", "-1", "-100:0"};
    for (int i = 0; i < 9; i++)
        assert_int_equal(btf_neighbourhood_parse(bad[i], o, &n, &e), BTF_E_ARG);
    assert_int_equal(btf_neighbourhood_parse("1:0", o, &n, &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, "not causal"));
}

static void decorrelation_and_pyramid(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image img;
    TU_OK(btf_image_alloc(&img, 37, 23, 3, &e), &e);
    btf_rng r;
    btf__rng_seed(&r, 4);
    for (int i = 0; i < 37 * 23; i++) {
        double a = btf__rng_uniform(&r), b = btf__rng_uniform(&r);
        img.data[3 * i] = (float)(0.5 * a + 0.1 * b);
        img.data[3 * i + 1] = (float)(0.4 * a + 0.05);
        img.data[3 * i + 2] = (float)(0.2 * b);
    }
    float mean[3], basis[9];
    double var[3];
    TU_OK(btf__pca3(&img, mean, basis, var, &e), &e);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double d = 0;
            for (int k = 0; k < 3; k++)
                d += (double)basis[3 * i + k] * basis[3 * j + k];
            assert_true(fabs(d - (i == j)) < 1e-6); /* orthonormal */
        }
    assert_true(var[0] >= var[1] && var[1] >= var[2] && var[2] >= 0);
    /* Decorrelated bands are uncorrelated, and the inverse restores RGB. */
    double *bands[3];
    for (int b = 0; b < 3; b++)
        bands[b] = malloc(37 * 23 * sizeof(double));
    btf__decorrelate(&img, mean, basis, bands);
    double c01 = 0;
    for (int i = 0; i < 37 * 23; i++) {
        c01 += bands[0][i] * bands[1][i];
        for (int k = 0; k < 3; k++) {
            double v = mean[k] + basis[k] * bands[0][i] + basis[3 + k] * bands[1][i] +
                       basis[6 + k] * bands[2][i];
            assert_true(fabs(v - img.data[3 * i + k]) < 1e-5);
        }
    }
    assert_true(fabs(c01 / (37 * 23)) < 1e-6);
    /* The pyramid collapses back exactly, for odd sizes and every depth. */
    for (int levels = 1; levels <= 5; levels++) {
        btf_pyramid p;
        TU_OK(btf__pyramid_build(bands[0], 37, 23, levels, &p, &e), &e);
        assert_int_equal(p.width[levels - 1], levels == 1 ? 37 : (37 + (1 << (levels - 1)) - 1) >> (levels - 1));
        double *back;
        TU_OK(btf__pyramid_collapse(&p, &back, &e), &e);
        for (int i = 0; i < 37 * 23; i++)
            assert_true(fabs(back[i] - bands[0][i]) < 1e-12);
        free(back);
        btf__pyramid_free(&p);
    }
    /* A grey constant image: zero-variance bands, no division, finite basis. */
    for (int i = 0; i < 37 * 23 * 3; i++)
        img.data[i] = 0.25f;
    TU_OK(btf__pca3(&img, mean, basis, var, &e), &e);
    for (int i = 0; i < 9; i++)
        assert_true(isfinite(basis[i]));
    assert_true(var[0] == 0.0 && mean[1] == 0.25f);
    for (int b = 0; b < 3; b++)
        free(bands[b]);
    btf_image_free(&img);
}

/* (a) Parameters of fields synthesised by the model itself are estimated
 * back. With t ~ 2.6e5 equations the standard error of each coefficient is
 * about 1/sqrt(t) ~ 0.002 (times a factor for correlated regressors), so a
 * tolerance of 0.03 is ~10 standard errors; sigma to 2 %. */
static void estimates_recover_known_parameters(void **state)
{
    (void)state;
    struct {
        const char *spec;
        float gamma[6];
    } cases[] = {
        {"0:-1,-1:0", {0.45f, 0.4f}},
        {"0:-1,-1:0,-1:-1", {0.6f, 0.55f, -0.3f}},
        {"0:-1,-1:0,-1:-1,-1:1", {0.35f, 0.3f, -0.1f, 0.2f}},
        {"0:-2,-2:0,-1:1", {0.3f, -0.3f, 0.25f}},
    };
    for (int c = 0; c < 4; c++) {
        btf_car_band truth = model(cases[c].spec, cases[c].gamma, 0.7f, 2.0f);
        assert_true(btf__car_is_stable(&truth));
        double *f = field(&truth, 512, 512, 100 + c);
        btf_car_fit_opts o = {.n_fixed = truth.n};
        memcpy(o.fixed, truth.offsets, sizeof o.fixed);
        btf_car_band fit;
        btf_car_fit_info info;
        btf_error e = {0};
        TU_OK(btf__car_fit(f, 512, 512, &o, &fit, &info, &e), &e);
        assert_int_equal(fit.n, truth.n);
        for (int i = 0; i < truth.n; i++)
            assert_true(fabsf(fit.gamma[i] - truth.gamma[i]) < 0.03f);
        assert_true(fabsf(fit.sigma - truth.sigma) < 0.02f * truth.sigma);
        assert_true(fabsf(fit.mean - truth.mean) < 0.2f);
        assert_true(info.shrink == 1.0);
        free(f);
    }
}

/* The recursion written out directly: field row by row, pixel by pixel,
 * zero outside the field, in the order of btf_shared.h (earlier rows in
 * stored order, the noise, same-row offsets farthest first). */
static float *direct_field(const btf_car_band *b, int margin, int w, int h, uint64_t seed,
                           uint32_t stream)
{
    int m = margin < 0 ? btf__car_margin(b) : margin, fw = w + 2 * m, fh = h + m;
    float *f = calloc((size_t)fw * fh, sizeof(float)), *out = malloc((size_t)w * h * sizeof(float));
    assert_true(f && out);
    int same[BTF_CAR_MAX_NEIGHBOURS];
    int nsame = btf__car_same_row_order(b, same);
    for (int r = 0; r < fh; r++)
        for (int c = 0; c < fw; c++) {
            float a = 0.0f;
            for (int s = 0; s < b->n; s++) {
                btf_offset o = b->offsets[s];
                int rr = r + o.row, cc = c + o.col;
                if (o.row != 0)
                    a = btf_car_accumulate(a, b->gamma[s], rr >= 0 && cc >= 0 && cc < fw
                                                               ? f[(size_t)rr * fw + cc] : 0.0f);
            }
            uint32_t urow = (uint32_t)(r - m + BTF_NOISE_ORIGIN); /* field row r is row r - m */
            uint32_t ucol = (uint32_t)(c - m + BTF_NOISE_ORIGIN);
            a = btf_car_output(a, b->sigma, btf_noise1((uint32_t)seed, (uint32_t)(seed >> 32),
                                                       stream, urow, ucol));
            for (int t = 0; t < nsame; t++) {
                int cc = c + b->offsets[same[t]].col;
                a = btf_car_accumulate(a, b->gamma[same[t]], cc >= 0 ? f[(size_t)r * fw + cc] : 0.0f);
            }
            f[(size_t)r * fw + c] = a;
        }
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            out[(size_t)y * w + x] = btf_add_mean(b->mean, f[(size_t)(y + m) * fw + x + m]);
    free(f);
    return out;
}

/* How many values of the synthesised field (stream 7) differ from the
 * direct recursion's. */
static size_t values_off_direct(const btf_car_band *b, int margin, int w, int h, uint64_t seed)
{
    double *got = field_with(b, margin, w, h, seed, 0);
    float *want = direct_field(b, margin, w, h, seed, 7);
    size_t diff = 0;
    for (int i = 0; i < w * h; i++)
        diff += (float)got[i] != want[i];
    free(got);
    free(want);
    return diff;
}

/* CPU synthesis steps two rows at once where it can (src/synth/rows.c,
 * btf__rows_pair), with row r + 1 trailing row r by a chunk plus its reach;
 * every value must still be the direct recursion's, bit for bit: the
 * family's shapes and others, same-row offsets only, no neighbours, reaches
 * past a chunk, widths on both sides of the pairing threshold (for the
 * first spec, field width 130 is exactly twice the lead and 193 leaves
 * whole chunks), odd and even heights. */
static void row_pairs_match_direct_recursion(void **state)
{
    (void)state;
    const char *specs[] = {"0:-1,-1:0,-1:-1,-1:1", "-1:0", "0:-2,-1:0,-1:1",
                           "0:-1,0:-2,0:-3,-1:3,-2:-2", "0:-1,-1:40,-1:-7,-3:0",
                           "0:-1,0:-2,-1:0,-1:2,-2:0,-2:1", "0:-1", "0:-2,0:-5", ""};
    const float g[6] = {0.3f, 0.2f, -0.1f, 0.15f, 0.05f, -0.05f};
    int widths[] = {1, 5, 64, 114, 129, 150, 177, 300}, heights[] = {1, 2, 7};
    for (int s = 0; s < 9; s++) {
        btf_car_band b = s < 8 ? model(specs[s], g, 0.7f, 0.25f) : model("0:-1", g, 0.7f, 0.25f);
        if (s == 8)
            b.n = 0; /* white noise */
        int margin = s == 0 ? 8 : 8 + 4 * s; /* of the size fitting gives */
        for (int wi = 0; wi < 8; wi++)
            for (int hi = 0; hi < 3; hi++) {
                int w = widths[wi], h = heights[hi];
                size_t diff = values_off_direct(&b, margin, w, h, 1234 + s);
                if (diff)
                    print_error("%s at %dx%d: %zu values differ\n", specs[s], w, h, diff);
                assert_int_equal(diff, 0);
            }
    }
}

/* Rows of RGB into an image of their width (the user). */
static int rows_into_image(void *user, int y, int nrows, const float *rows, btf_error *err)
{
    (void)err;
    btf_image *img = user;
    memcpy(img->data + (size_t)y * img->width * 3, rows,
           (size_t)nrows * img->width * 3 * sizeof(float));
    return 0;
}

/* The same through btf_synthesise with three bands stepping together:
 * one level, identity basis and zero means, so each channel is its band's
 * field. The bands differ in margin (band 0 the widest), same-row shape
 * and reach into the row above (the pair's lead is the largest); one band
 * has no earlier-row offset at all (its ring holds a row and the one being
 * paired). */
static void row_pairs_of_three_bands(void **state)
{
    (void)state;
    const char *mixed[3] = {"0:-1,0:-2", "0:-1,0:-2,0:-3,-1:40,-2:-2", "0:-2,0:-5,-1:0,-1:1"};
    const char *one_shape[3] = {"0:-1,0:-2,-1:0", "0:-2,0:-1,-1:40,-2:-2",
                                "0:-1,0:-2,-1:1,-3:0"};
    const float g[6] = {0.3f, 0.2f, -0.1f, 0.15f, 0.05f, -0.05f};
    int margins[3][BTF_MAX_LEVELS] = {{200}, {8}, {33}};
    for (int cfg = 0; cfg < 2; cfg++) {
        const char *const *specs = cfg ? one_shape : mixed;
        btf_subspace_model sm;
        memset(&sm, 0, sizeof sm);
        sm.levels = 1;
        sm.basis[0] = sm.basis[4] = sm.basis[8] = 1.0f;
        for (int b = 0; b < 3; b++)
            sm.bands[b][0] = model(specs[b], g, 0.7f, 0.0f);
        btf_model m = {.n_subspaces = 1, .subspaces = &sm};
        int widths[] = {1, 100, 200, 257, 300, 600}, heights[] = {1, 2, 7};
        for (int wi = 0; wi < 6; wi++)
            for (int hi = 0; hi < 3; hi++) {
                int w = widths[wi], h = heights[hi];
                btf_image img;
                btf_error e = {0};
                TU_OK(btf_image_alloc(&img, w, h, 3, &e), &e);
                btf_synth_opts o = {.width = w, .height = h, .seed = 42};
                TU_OK(btf__synthesise_margins(&m, 0, margins, &o, rows_into_image, &img, &e), &e);
                size_t diff = 0;
                for (int b = 0; b < 3; b++) {
                    float *want = direct_field(&sm.bands[b][0], margins[b][0], w, h, 42,
                                               btf_noise_stream(0, (uint32_t)b, 0));
                    for (int i = 0; i < w * h; i++)
                        diff += img.data[3 * i + b] != want[i];
                    free(want);
                }
                if (diff)
                    print_error("config %d at %dx%d: %zu values differ\n", cfg, w, h, diff);
                assert_int_equal(diff, 0);
                btf_image_free(&img);
            }
    }
}

/* The wavefront (src/synth/wave.c: eight rows per vector step, lane k trailing
 * lane k - 1, each lane running its rows back to back) must give the direct
 * recursion's values bit for bit: every shape it takes (rows up to 3 back,
 * columns up to 4 either way, same-row shapes 0..3 long, no neighbours),
 * field widths at its threshold (136) and far above, margins that move the
 * noise blocks against the lanes' laps, heights that end inside, at and
 * after the first eight rows and several laps. On a CPU with AVX2 the test
 * also checks that the wave takes these bands (else it tests the rows). */
static void wavefront_matches_direct_recursion(void **state)
{
    (void)state;
    const char *specs[] = {"0:-1,-1:0,-1:-1,-1:1", "0:-1,-1:0,-1:1", "",
                           "0:-1,0:-2,0:-3,-1:4,-1:-4,-2:0,-3:2",
                           "0:-2,0:-1,-2:-1,-1:0,-3:-4,-2:3",
                           "-1:0,-1:-1,-1:1,-1:-2,-1:2,-2:0,-2:-1,-2:1,-2:-2,-2:2,-3:0",
                           "0:-1,0:-2"};
    const float g[11] = {0.2f, 0.15f, -0.1f, 0.12f, 0.05f, -0.05f, 0.04f, 0.03f, -0.03f,
                         0.02f, 0.01f};
    const int widths[] = {100, 119, 120, 121, 200, 1000}, heights[] = {1, 7, 8, 9, 30};
    const int margins[] = {8, 13, 22};
    int waved = 0;
    for (int s = 0; s < 7; s++) {
        btf_car_band b = model(s == 2 ? "0:-1" : specs[s], g, 0.7f, 0.25f);
        if (s == 2)
            b.n = 0; /* white noise */
        for (int mi = 0; mi < 3; mi++)
            for (int wi = 0; wi < 6; wi++)
                for (int hi = 0; hi < 5; hi++) {
                    int w = widths[wi], h = heights[hi];
                    int margin = b.n == 0 ? 0 : margins[(mi + wi + hi) % 3];
                    int fw = w + 2 * margin;
                    if (btf__wave_available() && fw >= 136) {
                        assert_true(btf__wave_supported(&b, fw));
                        waved++;
                    }
                    size_t diff = values_off_direct(&b, margin, w, h, 99 + s);
                    if (diff)
                        print_error("%s at %dx%d, margin %d: %zu values differ\n", specs[s], w, h,
                                    margin, diff);
                    assert_int_equal(diff, 0);
                }
    }
    print_message("%d of the fields above ran as a wavefront\n", waved);
    /* Out of its scope it declines: a row 4 back, a column 5 over, a
     * same-row gap, a field narrower than 136. */
    const char *outside[] = {"-4:0", "-1:5", "0:-2", "0:-1,0:-2,0:-3,0:-4"};
    for (int i = 0; i < 4; i++) {
        btf_car_band b = model(outside[i], g, 0.7f, 0.0f);
        assert_false(btf__wave_supported(&b, 1000));
    }
    btf_car_band b = model("0:-1,-1:0", g, 0.7f, 0.0f);
    assert_false(btf__wave_supported(&b, 135));
}

/* Random bands within the wavefront's scope (same-row shapes 0..3, rows
 * 1..3 up, columns within 4, repeated offsets, any order, gammas and sigma
 * of 0 and -0, margins 0..40, widths around its threshold and far above,
 * heights up to 400): with it on and off, the same bits. 300 fields from a
 * fixed xorshift seed keep the suite quick and the cases the same on every
 * run; raise the loop's count for a deeper search. */
static uint64_t xorshift(uint64_t *st)
{
    *st ^= *st << 13;
    *st ^= *st >> 7;
    *st ^= *st << 17;
    return *st >> 11;
}

static int rand_in(uint64_t *st, int lo, int hi)
{
    return lo + (int)(xorshift(st) % (uint64_t)(hi - lo + 1));
}

static btf_car_band random_wave_band(uint64_t *st, int *margin)
{
    btf_car_band b;
    memset(&b, 0, sizeof b);
    int k = rand_in(st, 0, 3), ne = rand_in(st, 0, 12);
    btf_offset o[BTF_CAR_MAX_NEIGHBOURS];
    for (int i = 0; i < ne; i++) /* repeats allowed */
        o[i] = (btf_offset){(int8_t)-rand_in(st, 1, 3), (int8_t)rand_in(st, -4, 4)};
    for (int i = 0; i < k; i++)
        o[ne + i] = (btf_offset){0, (int8_t)(-1 - i)};
    int n = ne + k;
    for (int i = n - 1; i > 0; i--) { /* any stored order */
        int j = rand_in(st, 0, i);
        btf_offset t = o[i];
        o[i] = o[j];
        o[j] = t;
    }
    for (int i = 0; i < n; i++) {
        b.offsets[i] = o[i];
        int pick = rand_in(st, 0, 19);
        b.gamma[i] = pick == 0 ? 0.0f : pick == 1 ? -0.0f
                                               : 0.95f * (float)rand_in(st, -1000, 1000) / 1000.0f / (float)n;
    }
    b.n = n;
    int pick = rand_in(st, 0, 19);
    b.sigma = pick == 0 ? 0.0f : pick == 1 ? -0.0f : (float)rand_in(st, 1, 1000) / 500.0f;
    *margin = rand_in(st, 0, 1) ? rand_in(st, 1, 40) : -1; /* -1: the band's own */
    return b;
}

static void wavefront_random_bands(void **state)
{
    (void)state;
    uint64_t st = 88172645463325252ull;
    int waved = 0;
    for (int it = 0; it < 300; it++) {
        int margin;
        btf_car_band b = random_wave_band(&st, &margin);
        int m = margin < 0 ? btf__car_margin(&b) : margin;
        int w = rand_in(&st, 1, 500), h = rand_in(&st, 0, 3) ? rand_in(&st, 1, 45)
                                                            : rand_in(&st, 100, 400);
        if (rand_in(&st, 0, 2) == 0) /* fields at the threshold */
            w = rand_in(&st, 100, 160) - 2 * m > 0 ? rand_in(&st, 100, 160) - 2 * m : 1;
        uint64_t seed = xorshift(&st);
        waved += btf__wave_supported(&b, w + 2 * m);
        double *on = field_with(&b, margin, w, h, seed, 0);
        double *off = field_with(&b, margin, w, h, seed, 1);
        size_t diff = 0;
        for (size_t i = 0; i < (size_t)w * h; i++)
            diff += memcmp(&on[i], &off[i], sizeof on[i]) != 0;
        if (diff)
            print_error("band %d at %dx%d, margin %d: %zu values differ\n", it, w, h, m, diff);
        assert_int_equal(diff, 0);
        free(on);
        free(off);
    }
    print_message("%d of 300 random fields ran as a wavefront\n", waved);
    if (btf__wave_available())
        assert_true(waved > 100);
}

/* Whole syntheses of fitted multi-level models are the same bytes with the
 * wavefront on and off (btf_synth_opts.row_by_row), and with the portable
 * noise loop: level windows start at odd and
 * negative columns, bands of one level run different margins, sizes from
 * 1 x 1 up. */
static void wavefront_and_rows_give_the_same_images(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image tex;
    car_texture(96, 80, 5, 3, &tex);
    const char *specs[] = {NULL, "0:-1,-1:0,-1:-1,-1:1", "0:-1,-1:0,-1:1"};
    for (int sp = 0; sp < 3; sp++) {
        btf_fit_opts fo = {.levels = 3};
        if (specs[sp])
            TU_OK(btf_neighbourhood_parse(specs[sp], fo.car.fixed, &fo.car.n_fixed, &e), &e);
        btf_model m;
        TU_OK(btf_texture_fit(&tex, &fo, &m, &e), &e);
        int sizes[][2] = {{1, 1}, {131, 3}, {257, 19}, {600, 41}};
        for (int s = 0; s < 4; s++) {
            int w = sizes[s][0], h = sizes[s][1];
            btf_image on, off, portable;
            btf_synth_opts o = {.width = w, .height = h, .seed = 7 + s};
            TU_OK(btf_synthesise_image(&m, 0, &o, &on, &e), &e);
            o.row_by_row = 1;
            TU_OK(btf_synthesise_image(&m, 0, &o, &off, &e), &e);
            o.row_by_row = 0, o.portable_noise = 1;
            TU_OK(btf_synthesise_image(&m, 0, &o, &portable, &e), &e);
            assert_memory_equal(on.data, off.data, (size_t)w * h * 3 * sizeof(float));
            assert_memory_equal(on.data, portable.data, (size_t)w * h * 3 * sizeof(float));
            btf_image_free(&on);
            btf_image_free(&off);
            btf_image_free(&portable);
        }
        btf_model_free(&m);
    }
    btf_image_free(&tex);
}

/* (b) A long synthesis stays bounded and its sample variance matches the
 * model's stationary variance within 5 %. 10^8 pixels (10^7 under the
 * sanitizers, which are 10-20x slower). */
static void long_synthesis_is_stationary(void **state)
{
    (void)state;
    const float g[4] = {0.45f, 0.4f, -0.2f, 0.1f};
    btf_car_band b = model("0:-1,-1:0,-1:-1,-1:1", g, 1.0f, 0.0f);
    int side = getenv("BTF_ASAN") ? 3163 : 10000;
    collect c = {.width = side, .finite = 1};
    btf_error e = {0};
    btf_synth_opts o = {.width = side, .height = side, .seed = 2026};
    TU_OK(btf__car_synthesise_field(&b, -1, 1, &o, collect_rows, &c, &e), &e);
    assert_true(c.finite);
    double mean = c.sum / c.n, var = c.sum2 / c.n - mean * mean;
    double stat = btf__car_stationary_variance(&b);
    print_message("%ld pixels: sample variance %.5f, stationary %.5f (ratio %.4f)\n", c.n, var,
                  stat, var / stat);
    assert_true(fabs(var / stat - 1.0) < 0.05);
    assert_true(fabs(mean) < 0.05 * sqrt(stat));
}

/* Synthesis margins (src/car/margin.c) follow the band's correlation: none for
 * white noise, the minimum for a weak band, more as the correlation grows,
 * the cap for an unstable one; and with its margin a strongly correlated
 * field is stationary from its first row, which a short margin is not. */
static void margins_follow_correlation(void **state)
{
    (void)state;
    btf_car_band white = model("0:-1", (const float[]){0.0f}, 1.0f, 0.0f);
    white.n = 0;
    assert_int_equal(btf__car_margin(&white), 0);
    btf_car_band weak = model("0:-1", (const float[]){0.2f}, 1.0f, 0.0f);
    assert_int_equal(btf__car_margin(&weak), BTF_SYNTH_MARGIN_MIN);
    const float strengths[] = {0.2f, 0.35f, 0.45f, 0.49f, 0.499f};
    int last = 0;
    for (int i = 0; i < 5; i++) {
        float g = strengths[i];
        btf_car_band b = model("0:-1,-1:0", (const float[]){g, g}, 1.0f, 0.0f);
        int m = btf__car_margin(&b);
        print_message("gamma %.3f %.3f: margin %d\n", g, g, m);
        assert_true(m >= last && m <= BTF_SYNTH_MARGIN_MAX);
        last = m;
    }
    assert_true(last > 64); /* a fixed margin of 64 would be too short */
    btf_car_band unstable = model("0:-1,-1:0", (const float[]){0.6f, 0.6f}, 1.0f, 0.0f);
    assert_int_equal(btf__car_margin(&unstable), BTF_SYNTH_MARGIN_MAX);

    /* The first row's variance over many seeds, against the stationary one. */
    btf_car_band strong = model("0:-1,-1:0", (const float[]){0.45f, 0.45f}, 1.0f, 0.0f);
    double stat = btf__car_stationary_variance(&strong);
    int seeds = getenv("BTF_ASAN") ? 60 : 200, w = 2000;
    for (int pass = 0; pass < 2; pass++) {
        int margin = pass == 0 ? -1 : 2; /* its own, then far too short */
        collect c = {.width = w, .finite = 1};
        btf_error e = {0};
        for (int s = 0; s < seeds; s++) {
            btf_synth_opts o = {.width = w, .height = 1, .seed = 100 + s};
            TU_OK(btf__car_synthesise_field(&strong, margin, 3, &o, collect_rows, &c, &e), &e);
        }
        double ratio = (c.sum2 / c.n) / stat;
        print_message("margin %d: first-row variance / stationary = %.4f\n",
                      pass == 0 ? btf__car_margin(&strong) : 2, ratio);
        if (pass == 0)
            assert_true(fabs(ratio - 1.0) < 0.05);
        else
            assert_true(ratio < 0.9); /* 0.86: the transient shows */
    }
    /* A margin beyond the cap is refused, not run. */
    btf_error e = {0};
    collect c = {.width = 4, .finite = 1};
    btf_synth_opts o = {.width = 4, .height = 4, .seed = 1};
    assert_int_equal(btf__car_synthesise_field(&strong, BTF_SYNTH_MARGIN_MAX + 1, 3, &o,
                                               collect_rows, &c, &e), BTF_E_ARG);
}

/* A fitted model's margins follow from its coefficients, and reading its
 * file gives the same (margins are not stored in the file), also for a band
 * changed after reading (its kept margin no longer applies). */
static void fitted_and_read_models_carry_margins(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image img;
    tu_material_image("fabric", 64, 5, (btf_dir){0, 0}, (btf_dir){45, 30}, &img);
    btf_fit_opts fo = {.levels = 2};
    btf_model m, back;
    TU_OK(btf_texture_fit(&img, &fo, &m, &e), &e);
    unsigned char *bytes;
    size_t size;
    TU_OK(btf_model_encode(&m, &bytes, &size, &e), &e);
    TU_OK(btf_model_decode(bytes, size, "fitted", &back, &e), &e);
    for (int b = 0; b < 3; b++)
        for (int l = 0; l < 2; l++) {
            const btf_car_band *fit = &m.subspaces[0].bands[b][l];
            int mf, mb;
            TU_OK(btf_synth_margin(&m, 0, b, l, &mf, &e), &e);
            TU_OK(btf_synth_margin(&back, 0, b, l, &mb, &e), &e);
            assert_true(fit->n == 0 || mf >= BTF_SYNTH_MARGIN_MIN);
            assert_int_equal(mf, btf__car_margin(fit));
            assert_int_equal(mb, mf);
        }
    assert_non_null(back.internal); /* kept by the reader */
    btf_car_band *cb = &back.subspaces[0].bands[0][0];
    cb->n = 1, cb->offsets[0] = (btf_offset){0, -1}, cb->gamma[0] = 0.499f;
    int changed;
    TU_OK(btf_synth_margin(&back, 0, 0, 0, &changed, &e), &e);
    assert_int_equal(changed, btf__car_margin(cb));
    assert_int_equal(btf_synth_margin(&back, 0, 3, 0, &changed, &e), BTF_E_ARG);
    assert_int_equal(btf_synth_margin(&back, 0, 0, 2, &changed, &e), BTF_E_ARG);
    free(bytes);
    btf_model_free(&m);
    btf_model_free(&back);
    btf_image_free(&img);
}

/* Reading a model computes its margins within a work budget: a small file
 * of thousands of nearly unstable bands (24 neighbours, gammas summing to
 * 0.998) reads in seconds, not minutes, its bands taking the safe largest
 * margin; a band whose correlation outreaches the largest margin is
 * reported by btf__car_margin_shortfall. */
static void margins_bounded_on_read(void **state)
{
    (void)state;
    btf_model m;
    memset(&m, 0, sizeof m);
    m.n_subspaces = 255; /* the most a model holds (255 is BTF_PAIR_NONE) */
    m.subspaces = calloc(255, sizeof *m.subspaces);
    assert_non_null(m.subspaces);
    for (int s = 0; s < 255; s++) {
        btf_subspace_model *sm = &m.subspaces[s];
        sm->view = sm->light = -1;
        sm->width = sm->height = 64;
        sm->levels = 8;
        sm->basis[0] = sm->basis[4] = sm->basis[8] = 1.0f;
        for (int b = 0; b < 3; b++)
            for (int l = 0; l < 8; l++) {
                btf_car_band *cb = &sm->bands[b][l];
                for (int r = -3; r <= 0; r++)
                    for (int c = -3; c <= 3 && cb->n < 24; c++)
                        if (r < 0 || c < 0) {
                            cb->offsets[cb->n].row = (int8_t)r;
                            cb->offsets[cb->n].col = (int8_t)c;
                            cb->gamma[cb->n++] = 0.0416f;
                        }
                cb->sigma = 1.0f;
            }
    }
    unsigned char *bytes;
    size_t size;
    btf_error e = {0};
    TU_OK(btf_model_encode(&m, &bytes, &size, &e), &e);
    btf_model back;
    double t0 = tu_now();
    TU_OK(btf_model_decode(bytes, size, "crafted", &back, &e), &e);
    double took = tu_now() - t0;
    print_message("%zu-byte file of %d bands read in %.2f s\n", size, 255 * 3 * 8, took);
    assert_true(took < (getenv("BTF_ASAN") ? 60.0 : 10.0)); /* unbounded: about 20 s */
    int last;
    TU_OK(btf_synth_margin(&back, 254, 2, 7, &last, &e), &e);
    assert_int_equal(last, BTF_SYNTH_MARGIN_MAX);
    free(bytes);
    btf_model_free(&back);
    free(m.subspaces);

    btf_car_band edge = model("0:-1,-1:0", (const float[]){0.499f, 0.499f}, 1.0f, 0.0f);
    assert_int_equal(btf__car_margin(&edge), BTF_SYNTH_MARGIN_MAX);
    double short_by = btf__car_margin_shortfall(&edge, BTF_SYNTH_MARGIN_MAX);
    print_message("gamma 0.499, 0.499: %.3g of the variance beyond 256 pixels\n", short_by);
    assert_true(short_by > BTF_SYNTH_MARGIN_EPS);
    btf_car_band fine = model("0:-1,-1:0", (const float[]){0.45f, 0.45f}, 1.0f, 0.0f);
    assert_true(btf__car_margin_shortfall(&fine, btf__car_margin(&fine)) <= BTF_SYNTH_MARGIN_EPS);
}

/* (c) The Bayesian choice finds the true neighbourhood (a member of the
 * candidate family) far more often than any wrong one. */
static void selection_finds_true_neighbourhood(void **state)
{
    (void)state;
    struct {
        const char *spec;
        float gamma[6];
    } truths[] = {
        {"0:-1,-1:0", {0.5f, 0.3f}},
        {"0:-1,-1:0,-1:-1,-1:1", {0.4f, 0.4f, -0.25f, 0.15f}},
        {"0:-1,-1:0,-1:-1,-1:1,0:-2,-2:0", {0.4f, 0.3f, -0.1f, 0.1f, -0.2f, 0.15f}},
    };
    for (int t = 0; t < 3; t++) {
        btf_car_band truth = model(truths[t].spec, truths[t].gamma, 1.0f, 0.0f);
        int hits = 0, other[BTF_CAR_MAX_NEIGHBOURS + 1] = {0}, trials = 12;
        for (int k = 0; k < trials; k++) {
            double *f = field(&truth, 192, 192, 1000 * t + k);
            btf_car_band fit;
            btf_error e = {0};
            TU_OK(btf__car_fit(f, 192, 192, NULL, &fit, NULL, &e), &e);
            if (fit.n == truth.n)
                hits++;
            else
                other[fit.n]++;
            free(f);
        }
        int worst = 0;
        for (int n = 0; n <= BTF_CAR_MAX_NEIGHBOURS; n++)
            if (other[n] > worst)
                worst = other[n];
        print_message("true %d neighbours: chosen %d of %d times; most frequent wrong %d\n",
                      truth.n, hits, trials, worst);
        assert_true(hits >= 9);
        assert_true(hits >= 3 * worst);
    }
    /* A white band gets the smallest model, not the largest. */
    btf_car_band white = model("0:-1", (const float[]){0.0f}, 1.0f, 0.0f);
    double *f = field(&white, 128, 128, 5);
    btf_car_band fit;
    btf_error e = {0};
    TU_OK(btf__car_fit(f, 128, 128, NULL, &fit, NULL, &e), &e);
    assert_true(fit.n <= 2);
    free(f);
}

static int warnings;
static void count_warning(void *user, const char *msg)
{
    (void)user;
    (void)msg;
    warnings++;
}

/* (d) Degenerate inputs: finite, stable parameters, always. */
static void degenerate_bands(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_car_band fit;
    btf_car_fit_info info;
    double *band = malloc(64 * 64 * sizeof(double));
    /* Constant: no model beyond the mean. */
    for (int i = 0; i < 64 * 64; i++)
        band[i] = 3.5;
    TU_OK(btf__car_fit(band, 64, 64, NULL, &fit, &info, &e), &e);
    assert_int_equal(fit.n, 0);
    assert_true(fit.sigma == 0.0f && fit.mean == 3.5f);
    /* 1x1, 1xN, Nx1: white noise of the band's spread. */
    TU_OK(btf__car_fit(band, 1, 1, NULL, &fit, &info, &e), &e);
    assert_int_equal(fit.n, 0);
    for (int i = 0; i < 64; i++)
        band[i] = (i * 37) % 11;
    TU_OK(btf__car_fit(band, 64, 1, NULL, &fit, &info, &e), &e);
    assert_true(isfinite(fit.sigma) && fit.sigma > 0);
    assert_true(btf__car_is_stable(&fit));
    TU_OK(btf__car_fit(band, 1, 64, NULL, &fit, &info, &e), &e);
    assert_true(isfinite(fit.sigma) && fit.sigma > 0);
    /* Scale: a field times 1e-30 and times 1e36 gives the same coefficients
     * and proportionally scaled sigma, all finite. */
    const float g[2] = {0.5f, 0.3f};
    btf_car_band truth = model("0:-1,-1:0", g, 1.0f, 0.0f);
    double *f = field(&truth, 64, 64, 3);
    btf_car_band ref, tiny, huge;
    TU_OK(btf__car_fit(f, 64, 64, NULL, &ref, NULL, &e), &e);
    for (int i = 0; i < 64 * 64; i++)
        band[i] = f[i] * 1e-30;
    TU_OK(btf__car_fit(band, 64, 64, NULL, &tiny, NULL, &e), &e);
    for (int i = 0; i < 64 * 64; i++)
        band[i] = f[i] * 1e36;
    TU_OK(btf__car_fit(band, 64, 64, NULL, &huge, NULL, &e), &e);
    assert_int_equal(tiny.n, ref.n);
    assert_int_equal(huge.n, ref.n);
    for (int i = 0; i < ref.n; i++) {
        assert_true(fabsf(tiny.gamma[i] - ref.gamma[i]) < 1e-5f);
        assert_true(fabsf(huge.gamma[i] - ref.gamma[i]) < 1e-5f);
    }
    assert_true(isfinite(huge.sigma) && fabs(huge.sigma / 1e36 - ref.sigma) < 1e-4 * ref.sigma);
    assert_true(tiny.sigma > 0 && fabs(tiny.sigma / 1e-30 - ref.sigma) < 1e-4 * ref.sigma);
    /* Beyond the float range (|values| ~ 1e300): parameters clamp, finite. */
    for (int i = 0; i < 64 * 64; i++)
        band[i] = f[i] * 1e300;
    TU_OK(btf__car_fit(band, 64, 64, NULL, &huge, NULL, &e), &e);
    assert_true(isfinite(huge.sigma) && isfinite(huge.mean));
    /* A non-stationary ramp makes least squares predict a unit root: the
     * estimate is shrunk until stable, with a warning. */
    for (int y = 0; y < 64; y++)
        for (int x = 0; x < 64; x++)
            band[y * 64 + x] = 3.0 * x + 2.0 * y + ((x * 7 + y * 13) % 5) * 0.01;
    warnings = 0;
    btf_car_fit_opts o = {.warn = count_warning};
    TU_OK(btf__car_fit(band, 64, 64, &o, &fit, &info, &e), &e);
    assert_true(btf__car_is_stable(&fit));
    for (int i = 0; i < fit.n; i++)
        assert_true(isfinite(fit.gamma[i]));
    assert_true(info.shrink < 1.0);
    assert_true(warnings >= 1);
    /* NaN in the band is refused. */
    band[5] = NAN;
    assert_int_equal(btf__car_fit(band, 64, 64, NULL, &fit, NULL, &e), BTF_E_ARG);
    free(f);
    free(band);
}

static void stability_check(void **state)
{
    (void)state;
    /* First-order quarter plane: stable iff 1-a-b-c, 1-a+b+c, 1+a-b+c,
     * 1+a+b-c are all > 0 (A(z1, z2) = 1 - a z1 - b z2 - c z1 z2 has no
     * zero on the closed unit bidisc). */
    const float stable[3] = {0.5f, 0.5f, -0.25f}, unstable[3] = {0.6f, 0.6f, 0.0f};
    btf_car_band s = model("-1:0,0:-1,-1:-1", stable, 1, 0);
    btf_car_band u = model("-1:0,0:-1,-1:-1", unstable, 1, 0);
    assert_true(btf__car_is_stable(&s));
    assert_false(btf__car_is_stable(&u));
    const float small[2] = {0.3f, 0.3f};
    btf_car_band w = model("0:-1,-1:1", small, 1, 0);
    assert_true(btf__car_is_stable(&w));
    const float big[1] = {1.2f};
    btf_car_band one = model("0:-1", big, 1, 0);
    assert_false(btf__car_is_stable(&one));
}

/* Synthesis of subspace images: sizes from 1x1 up, seeds, streaming. */
static void synthesis_sizes_and_seeds(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image tex;
    car_texture(64, 48, 9, 1, &tex);
    btf_model m;
    btf_fit_opts fo = {.levels = 2};
    TU_OK(btf_texture_fit(&tex, &fo, &m, &e), &e);
    assert_int_equal(m.subspaces[0].levels, 2);
    int sizes[][2] = {{1, 1}, {1, 9}, {9, 1}, {7, 13}, {1000, 3}, {300, 200}};
    for (int s = 0; s < 6; s++) {
        btf_image a, b2, c;
        int w = sizes[s][0], h = sizes[s][1];
        synth_image(&m, w, h, 42, &a);
        synth_image(&m, w, h, 42, &b2);
        synth_image(&m, w, h, 43, &c);
        size_t n = (size_t)w * h * 3;
        assert_memory_equal(a.data, b2.data, n * sizeof(float)); /* same seed, same bytes */
        int differ = 0;
        for (size_t i = 0; i < n; i++) {
            assert_true(isfinite(a.data[i]));
            differ |= a.data[i] != c.data[i];
        }
        assert_true(differ);
        btf_image_free(&a);
        btf_image_free(&b2);
        btf_image_free(&c);
        /* the default, colour-matched: finite, deterministic; a single
         * pixel takes the exemplar's median colour whatever the seed, more
         * differ with it */
        btf_synth_opts o = {.width = w, .height = h, .seed = 42};
        TU_OK(btf_synthesise_image(&m, 0, &o, &a, &e), &e);
        TU_OK(btf_synthesise_image(&m, 0, &o, &b2, &e), &e);
        o.seed = 43;
        TU_OK(btf_synthesise_image(&m, 0, &o, &c, &e), &e);
        assert_memory_equal(a.data, b2.data, n * sizeof(float));
        differ = 0;
        for (size_t i = 0; i < n; i++) {
            assert_true(isfinite(a.data[i]));
            differ |= a.data[i] != c.data[i];
        }
        assert_true(differ == (w * h > 1));
        btf_image_free(&a);
        btf_image_free(&b2);
        btf_image_free(&c);
    }
    /* The synthesis reproduces the texture's colour statistics. */
    btf_image big;
    synth_image(&m, 512, 512, 1, &big);
    double mean[3] = {0}, tm[3] = {0};
    for (int i = 0; i < 512 * 512; i++)
        for (int k = 0; k < 3; k++)
            mean[k] += big.data[3 * i + k] / (512.0 * 512.0);
    for (int i = 0; i < 64 * 48; i++)
        for (int k = 0; k < 3; k++)
            tm[k] += tex.data[3 * i + k] / (64.0 * 48.0);
    for (int k = 0; k < 3; k++)
        assert_true(fabs(mean[k] - tm[k]) < 0.05);
    btf_image_free(&big);
    btf_synth_opts o = {.width = 4, .height = 4, .seed = 1};
    assert_int_equal(btf_synthesise_image(&m, 1, &o, &big, &e), BTF_E_ARG);
    o.width = -1;
    assert_int_equal(btf_synthesise_image(&m, 0, &o, &big, &e), BTF_E_ARG);
    o.width = 1 << 25;
    assert_int_equal(btf_synthesise_image(&m, 0, &o, &big, &e), BTF_E_ARG);
    /* No options: the analysed size and seed 0, which zero options mean. */
    btf_image dflt, zero;
    TU_OK(btf_synthesise_image(&m, 0, NULL, &dflt, &e), &e);
    assert_true(dflt.width == 64 && dflt.height == 48);
    btf_synth_opts d = btf_synth_defaults();
    TU_OK(btf_synthesise_image(&m, 0, &d, &zero, &e), &e);
    assert_memory_equal(dflt.data, zero.data, (size_t)64 * 48 * 3 * sizeof(float));
    btf_image_free(&dflt);
    btf_image_free(&zero);
    /* (e) The model survives its file bit for bit. */
    unsigned char *bytes, *again;
    size_t n1, n2;
    TU_OK(btf_model_encode(&m, &bytes, &n1, &e), &e);
    btf_model back;
    TU_OK(btf_model_decode(bytes, n1, "memory", &back, &e), &e);
    TU_OK(btf_model_encode(&back, &again, &n2, &e), &e);
    assert_int_equal(n1, n2);
    assert_memory_equal(bytes, again, n1);
    assert_memory_equal(&back.subspaces[0], &m.subspaces[0], sizeof(btf_subspace_model));
    free(bytes);
    free(again);
    btf_model_free(&back);
    btf_model_free(&m);
    btf_image_free(&tex);
}

/* Images near 0 and near the float limit: finite parameters always; the
 * model file refuses those beyond BTF_MODEL_MAX_VALUE; a synthesis of the
 * model in memory either gives finite pixels or refuses with BTF_E_NUMERIC
 * (values at 3e38 overflow float when the noise adds its tails), never Inf
 * or NaN. */
static void extreme_image_values(void **state)
{
    (void)state;
    const float scales[] = {1e-38f, 1e-30f, 1e30f, 1e37f, 3e38f};
    for (int s = 0; s < 5; s++) {
        btf_error e = {0};
        btf_image img;
        TU_OK(btf_image_alloc(&img, 64, 64, 3, &e), &e);
        for (int i = 0; i < 64 * 64 * 3; i++)
            img.data[i] = scales[s] * ((float)((i * 7919) % 101) / 100.0f);
        btf_model m;
        btf_fit_opts fo = {.levels = 2};
        TU_OK(btf_texture_fit(&img, &fo, &m, &e), &e);
        const btf_subspace_model *sm = &m.subspaces[0];
        for (int b = 0; b < 3; b++)
            for (int l = 0; l < sm->levels; l++) {
                const btf_car_band *cb = &sm->bands[b][l];
                assert_true(isfinite(cb->sigma) && isfinite(cb->mean));
                for (int k = 0; k < cb->n; k++)
                    assert_true(isfinite(cb->gamma[k]));
            }
        /* The file takes the model up to BTF_MODEL_MAX_VALUE (1e30 images
         * have band and colour means about 1e30), and refuses the larger
         * ones, which synthesis cannot be trusted to keep within float. */
        unsigned char *bytes = NULL;
        size_t n;
        int enc = btf_model_encode(&m, &bytes, &n, &e);
        if (scales[s] <= 1e30f) {
            TU_OK(enc, &e);
        } else {
            assert_int_equal(enc, BTF_E_DATA);
            assert_non_null(strstr(e.msg, "magnitude at most 1e+30"));
        }
        free(bytes);
        btf_image out;
        btf_synth_opts o = {.width = 96, .height = 80, .seed = 1};
        int rc = btf_synthesise_image(&m, 0, &o, &out, &e);
        if (scales[s] < 1e38f) {
            TU_OK(rc, &e);
            for (int i = 0; i < 96 * 80 * 3; i++)
                assert_true(isfinite(out.data[i]));
            btf_image_free(&out);
        } else {
            assert_int_equal(rc, BTF_E_NUMERIC);
            assert_non_null(strstr(e.msg, "overflowed"));
            assert_null(out.data);
        }
        btf_model_free(&m);
        btf_image_free(&img);
    }
}

/* The model file takes the parser's reach (|offset| <= 64), not all int8. */
static void model_offsets_within_64(void **state)
{
    (void)state;
    btf_model m = {0};
    btf_subspace_model sm = {0};
    sm.view = sm.light = -1;
    sm.width = sm.height = 8;
    sm.levels = 1;
    sm.basis[0] = sm.basis[4] = sm.basis[8] = 1.0f;
    m.n_subspaces = 1;
    m.subspaces = &sm;
    for (int b = 0; b < 3; b++) {
        sm.bands[b][0].n = 1;
        sm.bands[b][0].offsets[0] = (btf_offset){-1, 64};
        sm.bands[b][0].gamma[0] = 0.1f;
        sm.bands[b][0].sigma = 1.0f;
    }
    unsigned char *bytes;
    size_t n;
    btf_error e = {0};
    TU_OK(btf_model_encode(&m, &bytes, &n, &e), &e);
    free(bytes);
    sm.bands[1][0].offsets[0] = (btf_offset){-1, 65};
    assert_int_equal(btf_model_encode(&m, &bytes, &n, &e), BTF_E_DATA);
    assert_non_null(strstr(e.msg, "beyond 64"));
    /* Synthesis refuses such a band too, with the same bound as model
     * files and neighbourhood specs (btf_offset holds up to 127). */
    sm.bands[1][0].offsets[0] = (btf_offset){-1, 100};
    btf_image img;
    btf_synth_opts o = {.width = 4, .height = 4, .seed = 1};
    assert_int_equal(btf_synthesise_image(&m, 0, &o, &img, &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, "beyond 64"));
    assert_int_equal(btf__car_synthesise_field(&sm.bands[1][0], -1, 0, &o, NULL, NULL, &e),
                     BTF_E_ARG);
    sm.bands[1][0].offsets[0] = (btf_offset){-1, 64};
    TU_OK(btf_synthesise_image(&m, 0, &o, &img, &e), &e);
    btf_image_free(&img);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(neighbourhood_spec),
        cmocka_unit_test(decorrelation_and_pyramid),
        cmocka_unit_test(estimates_recover_known_parameters),
        cmocka_unit_test(row_pairs_match_direct_recursion),
        cmocka_unit_test(row_pairs_of_three_bands),
        cmocka_unit_test(wavefront_matches_direct_recursion),
        cmocka_unit_test(wavefront_and_rows_give_the_same_images),
        cmocka_unit_test(wavefront_random_bands),
        cmocka_unit_test(long_synthesis_is_stationary),
        cmocka_unit_test(margins_follow_correlation),
        cmocka_unit_test(fitted_and_read_models_carry_margins),
        cmocka_unit_test(margins_bounded_on_read),
        cmocka_unit_test(selection_finds_true_neighbourhood),
        cmocka_unit_test(degenerate_bands),
        cmocka_unit_test(stability_check),
        cmocka_unit_test(synthesis_sizes_and_seeds),
        cmocka_unit_test(extreme_image_values),
        cmocka_unit_test(model_offsets_within_64),
    };
    return cmocka_run_group_tests_name("car", tests, NULL, NULL);
}
