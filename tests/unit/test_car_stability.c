/* test_car_stability.c — the exact stability test of a CAR band's causal
 * recursion (car/stability.c, docs/model.md
 * "Stability"): one- and two-neighbour bands at and near the boundary,
 * bands whose roots are known in closed form, a recursion run as synthesis
 * runs it that grows exactly where the test says unstable, every band of
 * the three generated materials' models, the fit of a 1.002^x ramp, and the
 * writer's and reader's refusal of an unstable band. */
#include "car/car.h"
#include "core/core.h"
#include "model/model.h"
#include "testutil.h"

#include <complex.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MARGIN BTF_CAR_STABILITY_MARGIN

static btf_car_band band(const char *spec, const float *gamma)
{
    btf_car_band b;
    memset(&b, 0, sizeof b);
    btf_error e = {0};
    TU_OK(btf_neighbourhood_parse(spec, b.offsets, &b.n, &e), &e);
    for (int i = 0; i < b.n; i++)
        b.gamma[i] = gamma[i];
    b.sigma = 1.0f;
    return b;
}

/* ------------------------------------------------- the recursion itself */

/* The variance of pixel (ty, tx) of an h x w field of the band's recursion
 * as synthesis runs it (synth/field.c: rows top to bottom, each left to
 * right, zeros outside the field), driven by white noise of unit
 * variance, exactly: the field is X = G E, G = (I - Gamma)^-1, so
 * var X_t = sum_i G_ti^2, and row t of G is the solution of the transposed
 * system, y_i = [i = t] + sum_s gamma_s y_{i - o_s}: the same recursion run
 * backwards from a unit impulse at t (zero after t and outside). */
static double pixel_variance(const btf_car_band *b, int h, int w, int ty, int tx)
{
    assert_true(ty < h && tx < w);
    double *y = calloc((size_t)(ty + 1) * w, sizeof *y), sum = 0.0;
    assert_non_null(y);
    for (long i = (long)ty * w + tx; i >= 0; i--) {
        int r = (int)(i / w), c = (int)(i % w);
        double v = i == (long)ty * w + tx ? 1.0 : 0.0;
        for (int k = 0; k < b->n; k++) {
            int rr = r - b->offsets[k].row, cc = c - b->offsets[k].col;
            if (rr <= ty && cc >= 0 && cc < w && (long)rr * w + cc <= (long)ty * w + tx)
                v += b->gamma[k] * y[(size_t)rr * w + cc];
        }
        y[i] = v;
        sum += v * v;
    }
    free(y);
    return isfinite(sum) ? sum : INFINITY;
}

/* The field's variance early and late down the rows (the middle column, at
 * rows h/8 and h) and along them (the middle row, at columns w/8 and w).
 * With w = 3 h the middle column is reached by a chain of h rows,
 * whichever way a neighbour leans. */
typedef struct spread {
    double rows_early, rows_late, cols_early, cols_late;
} spread;

static spread run_recursion(const btf_car_band *b, int h, int w)
{
    return (spread){pixel_variance(b, h, w, h / 8, w / 2), pixel_variance(b, h, w, h - 1, w / 2),
                    pixel_variance(b, h, w, h / 2, w / 8), pixel_variance(b, h, w, h / 2, w - 1)};
}

static double peak(spread sp)
{
    return fmax(fmax(sp.rows_early, sp.rows_late), fmax(sp.cols_early, sp.cols_late));
}

/* Grows: eight times the rows (or columns) give more than twice the
 * variance. A stable band's field settles below its stationary variance;
 * an unstable one grows exponentially, and one on the unit circle like a
 * random walk (eightfold) or, in 2-D, like its square root (about 2.8-fold
 * for 0.5, 0.5 on 0:-1,-1:0). */
static int grows(spread sp)
{
    return !(sp.rows_late <= 2.0 * sp.rows_early) || !(sp.cols_late <= 2.0 * sp.cols_early);
}

/* ------------------------------------------ the roots, independently */

/* The largest root modulus of z^n + p[n-1] z^(n-1) + ... + p[0] by the
 * Durand-Kerner iteration: a check of the Schur-Cohn test by other means. */
static double largest_root(const double complex *p, int n)
{
    double complex z[64];
    double big = 1.0;
    assert_true(n <= 64);
    for (int k = 0; k < n; k++)
        big = fmax(big, 1.0 + cabs(p[k]));
    for (int k = 0; k < n; k++)
        z[k] = big * cexp(I * (2.0 * M_PI * k / n + 0.4));
    for (int it = 0; it < 2000; it++)
        for (int k = 0; k < n; k++) {
            double complex v = 1.0, d = 1.0;
            for (int j = n - 1; j >= 0; j--)
                v = v * z[k] + p[j];
            for (int j = 0; j < n; j++)
                if (j != k)
                    d *= z[k] - z[j];
            z[k] -= v / d;
        }
    double m = 0.0;
    for (int k = 0; k < n; k++)
        m = fmax(m, cabs(z[k]));
    return m;
}

/* The largest root of the band's recursions, along a row and (at `freqs`
 * column frequencies) from row to row: at most 1 - margin for a stable
 * band (the grid cannot miss what the verdict promises for every
 * frequency), and above it at a grid frequency for the bands here that are
 * not (their largest roots sit at w = 0 or pi, on the grid). */
static double largest_root_of_band(const btf_car_band *b, int freqs)
{
    double complex p[64];
    int q = 0, rows = 0;
    for (int s = 0; s < b->n; s++) {
        if (b->offsets[s].row == 0 && -b->offsets[s].col > q)
            q = -b->offsets[s].col;
        if (-b->offsets[s].row > rows)
            rows = -b->offsets[s].row;
    }
    double m = 0.0;
    if (q > 0) {
        for (int k = 0; k < q; k++)
            p[k] = 0.0;
        for (int s = 0; s < b->n; s++)
            if (b->offsets[s].row == 0)
                p[q + b->offsets[s].col] -= b->gamma[s];
        m = largest_root(p, q);
    }
    for (int i = 0; rows > 0 && i < freqs; i++) {
        double w = 2.0 * M_PI * i / freqs;
        double complex c[65] = {1.0};
        for (int s = 0; s < b->n; s++)
            c[-b->offsets[s].row] += (b->offsets[s].row == 0 ? -1.0 : 1.0) * b->gamma[s] *
                                     cexp(I * w * b->offsets[s].col);
        for (int k = 1; k <= rows; k++)
            p[rows - k] = -c[k] / c[0];
        m = fmax(m, largest_root(p, rows));
    }
    return m;
}

/* The test's verdict against the truth, and against the recursion and the
 * roots: a stable band's field stays below its stationary variance (var,
 * known in closed form for the gammas before their rounding to float;
 * unit noise) and its roots below 1 - margin; an unstable one's field
 * grows and a root lies on or beyond that. */
static void check_band(const char *spec, const float *gamma, int stable, double var, int h)
{
    btf_car_band b = band(spec, gamma);
    char why[256] = "";
    int got = btf__car_stability_why(&b, why, sizeof why);
    spread sp = run_recursion(&b, h, 3 * h);
    double root = largest_root_of_band(&b, 512);
    print_message("%-16s %9.6f %9.6f: %s, root %.6f, variance %.4g .. %.4g down the rows, %.4g "
                  ".. %.4g along them%s%s\n", spec, gamma[0], b.n > 1 ? gamma[1] : 0.0,
                  got ? "stable" : "unstable", root, sp.rows_early, sp.rows_late, sp.cols_early,
                  sp.cols_late, got ? "" : ": ", why);
    assert_int_equal(got, stable);
    if (stable) {
        assert_true(peak(sp) <= var * (1.0 + 1e-4)); /* var of the rounded gammas */
        assert_true(root < 1.0 - MARGIN);
    } else {
        assert_true(grows(sp));
        assert_true(root >= 1.0 - MARGIN - 1e-9);
    }
}

/* (i) One neighbour, every direction synthesis meets: the recursion along
 * a row (0:-1), down a column (-1:0) or a diagonal (-1:-1, -1:1) is stable
 * exactly when |gamma| < 1, within the margin. */
static void one_neighbour_bands(void **state)
{
    (void)state;
    static const char *const OFFSETS[4] = {"0:-1", "-1:0", "-1:-1", "-1:1"};
    static const float G[] = {0.0f,   0.5f,   0.99f,  0.999f, 0.9999f,
                              1.0f,   1.001f, 1.002f, 1.01f};
    for (int o = 0; o < 4; o++)
        for (size_t i = 0; i < sizeof G / sizeof *G; i++)
            for (int sign = 1; sign >= -1; sign -= 2) {
                float g = sign * G[i];
                int stable = fabsf(g) < 1.0f - (float)MARGIN;
                check_band(OFFSETS[o], &g, stable, 1.0 / (1.0 - (double)g * g), 1024);
            }
    /* The margin itself: roots of modulus 1 - 5e-7 count as unstable,
     * 1 - 2e-6 as stable; the recursion cannot tell them apart here. */
    for (int o = 0; o < 4; o++) {
        float in = 1.0f - 2e-6f, on = 1.0f - 5e-7f;
        btf_car_band a = band(OFFSETS[o], &in), c = band(OFFSETS[o], &on);
        assert_true(btf__car_is_stable(&a));
        assert_false(btf__car_is_stable(&c));
    }
}

/* (ii) Two neighbours g, g on 0:-1,-1:0. At column frequency w the rows
 * follow X_r (1 - g e^{-iw}) = g X_{r-1} + noise: the root g / (1 - g
 * e^{-iw}) is largest at w = 0 (w = pi for g < 0), |g| / (1 - |g|), so
 * the band is stable iff 2 |g| < 1 (|g| < (1 - m) / (2 - m) with the margin
 * m). Its stationary variance is 1 / sqrt(1 - 4 g^2). */
static void two_neighbour_bands(void **state)
{
    (void)state;
    static const float G[] = {0.49f, 0.4999f, 0.5f, 0.501f, 0.51f};
    double edge = (1.0 - MARGIN) / (2.0 - MARGIN);
    for (size_t i = 0; i < sizeof G / sizeof *G; i++)
        for (int sign = 1; sign >= -1; sign -= 2) {
            float g[2] = {sign * G[i], sign * G[i]};
            int stable = fabs(g[0]) < edge;
            double var = stable ? 1.0 / sqrt(1.0 - 4.0 * (double)g[0] * g[0]) : 0.0;
            check_band("0:-1,-1:0", g, stable, var, 1024);
        }
}

/* Bands that the sufficient test (sum |gamma| < 1) leaves to the exact one,
 * with roots known in closed form: products of one-dimensional recursions,
 * A = (1 - a u^-1)(1 - b u^c v^-p), whose roots are a along the row and
 * b^(1/p) down the rows at every column frequency. Stable iff |a| and
 * |b|^(1/p) are below 1 - m; the stationary variance is
 * 1 / ((1 - a^2)(1 - b^2)). */
static void product_bands(void **state)
{
    (void)state;
    static const struct {
        int c, p; /* the second factor's column and rows up */
        float a, b;
    } CASES[] = {
        {0, 1, 0.9f, 0.9f},     {0, 1, 0.99f, 0.99f},   {0, 1, -0.99f, 0.99f},
        {0, 1, 0.9f, 1.002f},   {0, 1, 1.002f, 0.9f},   {0, 1, 0.9f, -1.002f},
        {1, 1, 0.99f, 0.99f},   {1, 1, 0.9f, 1.001f},   {-1, 1, 0.95f, -0.99f},
        {-1, 1, 0.5f, 1.01f},   {0, 2, 0.9f, 0.98f},    {0, 2, 0.9f, 1.003f},
        {1, 3, -0.95f, -0.97f}, {1, 3, -0.95f, 1.004f},
    };
    for (size_t i = 0; i < sizeof CASES / sizeof *CASES; i++) {
        int c = CASES[i].c, p = CASES[i].p;
        float a = CASES[i].a, b = CASES[i].b, g[3] = {a, b, -a * b};
        char spec[64];
        snprintf(spec, sizeof spec, "0:-1,%d:%d,%d:%d", -p, c, -p, c - 1);
        double rb = pow(fabs((double)b), 1.0 / p);
        int stable = fabs(a) < 1.0 - MARGIN && rb < 1.0 - MARGIN;
        double var = 1.0 / ((1.0 - (double)a * a) * (1.0 - (double)b * b));
        check_band(spec, g, stable, var, 512);
    }
    /* Near the margin the verdict is exact too, for products that floats
     * hold exactly (a and b of 24 significant bits between them): roots
     * 1.5e-5 inside it are proven stable, 1.5e-5 beyond it not. */
    const float a = 1.0f - 0x1p-8f, in = 1.0f - 0x1p-16f, out = 1.0f + 0x1p-16f;
    const float near[3][3] = {{a, in, -a * in}, {in, a, -a * in}, {a, out, -a * out}};
    for (int k = 0; k < 3; k++) {
        btf_car_band b = band("0:-1,-1:0,-1:-1", near[k]);
        assert_true((double)near[k][2] == -(double)near[k][0] * near[k][1]);
        assert_int_equal(btf__car_is_stable(&b), k < 2);
    }
    /* Rounded to float, a = b = 0.9999 is no product: -ab rounds by up to
     * 3e-8, and at w = 0 the root, (b - fl(ab)) / (1 - a), moves by that over
     * 1e-4. The test judges the coefficients as stored. */
    const float r = 0.9999f, rounded[3] = {r, r, -r * r};
    double root0 = ((double)rounded[1] + rounded[2]) / (1.0 - rounded[0]);
    btf_car_band b = band("0:-1,-1:0,-1:-1", rounded);
    print_message("0.9999 x 0.9999 as floats: the root at w = 0 is %.9f\n", root0);
    assert_int_equal(btf__car_is_stable(&b), root0 < 1.0 - MARGIN);
}

/* What the band was found to do, in words: the validator's and the fit's
 * messages name the recursion that grows. */
static void reasons_name_the_recursion(void **state)
{
    (void)state;
    char why[256];
    const float along = 1.002f, two[2] = {0.501f, 0.501f}, bad[1] = {NAN};
    btf_car_band b = band("0:-1", &along);
    assert_int_equal(btf__car_stability_why(&b, why, sizeof why), 0);
    assert_non_null(strstr(why, "along a row"));
    b = band("0:-1,-1:0", two);
    assert_int_equal(btf__car_stability_why(&b, why, sizeof why), 0);
    assert_non_null(strstr(why, "rows do not decay"));
    b = band("-1:0", bad);
    assert_int_equal(btf__car_stability_why(&b, why, sizeof why), 0);
    assert_non_null(strstr(why, "gamma[0]"));
    b = band("-1:0", &along);
    b.offsets[0] = (btf_offset){0, 1}; /* not causal: no recursion at all */
    assert_int_equal(btf__car_stability_why(&b, why, sizeof why), 0);
    assert_non_null(strstr(why, "not a causal offset"));
}

/* ------------------------------------------- fitted models and the fit */

/* (iv) Every band of the models of the three generated materials passes,
 * and its roots (Durand-Kerner, 256 column frequencies) agree. */
static void generated_materials_bands(void **state)
{
    (void)state;
    const char *const *names = btf_procedural_names();
    int materials = 0;
    for (int k = 0; names[k]; k++, materials++) {
        char path[512];
        btf_dataset *ds = NULL;
        assert_int_equal(tu_generate_dataset(names[k], 32, 3, path, sizeof path, &ds), 0);
        btf_model m;
        btf_error e = {0};
        btf_analyse_opts o = btf_analyse_defaults();
        TU_OK(btf_analyse(ds, &o, &m, &e), &e);
        int bands = 0, exact = 0;
        double worst = 0.0;
        for (int s = 0; s < m.n_subspaces; s++)
            for (int c = 0; c < 3; c++)
                for (int l = 0; l < m.subspaces[s].levels; l++) {
                    btf_car_band b = m.subspaces[s].bands[c][l];
                    double sum = 0.0;
                    for (int i = 0; i < b.n; i++)
                        sum += fabs(b.gamma[i]);
                    exact += sum >= 1.0;
                    assert_true(btf__car_is_stable(&b));
                    worst = fmax(worst, largest_root_of_band(&b, 256));
                    bands++;
                }
        print_message("%s: %d subspaces, %d bands stable, %d of them past the sufficient "
                      "test; largest root %.6f\n", names[k], m.n_subspaces, bands, exact, worst);
        assert_true(worst < 1.0 - MARGIN);
        btf_model_free(&m);
        btf_dataset_close(ds);
    }
    assert_int_equal(materials, 3);
}

typedef struct warnings {
    int count;
    char text[1024];
} warnings;

static void keep_warning(void *user, const char *msg)
{
    warnings *w = user;
    if (w->count++ == 0)
        snprintf(w->text, sizeof w->text, "%s", msg);
}

/* (v) texture-fit of a 2048-wide 1.002^x ramp, one level, neighbourhood 0:-1
 * (a growth too slow for a small test field to see): least squares says
 * gamma = 1.002, which grows along every row of a synthesis (to +-1100 at 2000
 * pixels for a texture of mean 0.3). The fit writes a band that passes
 * instead, shrunk below 1 by more than the margin, and says so naming the
 * band; its synthesis, without the marginal transfer that would hide a growth
 * by clamping, stays near the texture's range. */
static void ramp_fit_is_stable(void **state)
{
    (void)state;
    enum { W = 2048, H = 16 };
    btf_error e = {0};
    btf_image img;
    TU_OK(btf_image_alloc(&img, W, H, 3, &e), &e);
    double mean = (pow(1.002, W) - 1.0) / (0.002 * W);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++)
            for (int c = 0; c < 3; c++)
                img.data[((size_t)y * W + x) * 3 + c] = (float)(0.3 * pow(1.002, x) / mean);
    warnings w = {0};
    btf_fit_opts fo = btf_fit_defaults();
    fo.levels = 1;
    fo.car.n_fixed = 1;
    fo.car.fixed[0] = (btf_offset){0, -1};
    fo.car.warn = keep_warning;
    fo.car.warn_user = &w;
    btf_model m;
    TU_OK(btf_texture_fit(&img, &fo, &m, &e), &e);
    btf_image_free(&img);
    const btf_car_band *b = &m.subspaces[0].bands[0][0];
    print_message("gamma %.6f, sigma %.4g; %s\n", b->gamma[0], b->sigma, w.text);
    assert_int_equal(b->n, 1);
    assert_true(fabsf(b->gamma[0]) < 1.0f - (float)MARGIN);
    assert_true(btf__car_is_stable(b));
    assert_true(w.count >= 1);
    assert_non_null(strstr(w.text, "band 0 level 0: unstable estimate (its recursion along a row"));
    for (int c = 0; c < 3; c++)
        for (int l = 0; l < m.subspaces[0].levels; l++)
            assert_true(btf__car_is_stable(&m.subspaces[0].bands[c][l]));
    m.subspaces[0].marginal.knots = 0;
    btf_synth_opts so = {.width = W, .height = 4, .seed = 5, .match_colours = -1};
    btf_image out;
    TU_OK(btf_synthesise_image(&m, 0, &so, &out, &e), &e);
    double big = 0.0;
    for (size_t i = 0; i < (size_t)W * 4 * 3; i++)
        big = fmax(big, fabs(out.data[i]));
    print_message("synthesis %d wide: largest magnitude %.3g\n", W, big);
    assert_true(big < 10.0);
    btf_image_free(&out);
    btf_model_free(&m);
}

/* (vi) The writer refuses a model with an unstable band (the caller's
 * model is wrong), naming the band and the recursion, on one line; the
 * reader's refusal of such a file is test_validate's (it patches a file). */
static void writer_refuses_unstable_band(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image img;
    tu_material_image("leather", 32, 5, (btf_dir){0, 0}, (btf_dir){30, 0}, &img);
    btf_fit_opts fo = btf_fit_defaults();
    fo.levels = 2;
    btf_model m;
    TU_OK(btf_texture_fit(&img, &fo, &m, &e), &e);
    btf_image_free(&img);
    btf_car_band *b = &m.subspaces[0].bands[2][1];
    *b = band("0:-1,-1:0", (const float[]){0.501f, 0.501f});
    unsigned char *data = NULL;
    size_t size = 0;
    assert_int_equal(btf_model_encode(&m, &data, &size, &e), BTF_E_DATA);
    print_message("%s\n", e.msg);
    assert_non_null(strstr(e.msg, "subspace 0, band 2, level 1: the CAR coefficients are unstable: "
                                  "its rows do not decay"));
    assert_null(strchr(e.msg, '\n'));
    assert_null(data);
    btf_model_free(&m);
}

/* The validator checks each distinct band once: a model of 6120 copies of
 * one band that takes the exact test 0.4 ms (roots 1.2e-6 inside the
 * margin) validates in milliseconds, not seconds (a crafted file of a few
 * KB can repeat a band that often), and among the copies the first unstable
 * band in file order is the one named. */
static void validator_checks_distinct_bands(void **state)
{
    (void)state;
    btf_model m;
    memset(&m, 0, sizeof m);
    m.n_subspaces = 255; /* the most a model holds (255 is BTF_PAIR_NONE) */
    m.subspaces = calloc(255, sizeof *m.subspaces);
    assert_non_null(m.subspaces);
    const float g[2] = {0.4999997f, 0.4999997f};
    for (int s = 0; s < 255; s++) {
        btf_subspace_model *sm = &m.subspaces[s];
        sm->view = sm->light = -1;
        sm->width = sm->height = 64;
        sm->levels = BTF_MAX_LEVELS;
        sm->basis[0] = sm->basis[4] = sm->basis[8] = 1.0f;
        for (int b = 0; b < 3; b++)
            for (int l = 0; l < BTF_MAX_LEVELS; l++)
                sm->bands[b][l] = band("0:-1,-1:0", g);
    }
    btf_error e = {0};
    double t0 = tu_now();
    TU_OK(btf__model_validate(&m, "copies", BTF_E_DATA, &e), &e);
    double took = tu_now() - t0;
    print_message("6120 copies validated in %.1f ms\n", 1e3 * took);
    assert_true(took < 0.5);
    m.subspaces[200].bands[1][3].gamma[1] = 0.5000001f;
    m.subspaces[17].bands[2][5].gamma[0] = 0.5000001f;
    assert_int_equal(btf__model_validate(&m, "copies", BTF_E_DATA, &e), BTF_E_DATA);
    print_message("%s\n", e.msg);
    assert_non_null(strstr(e.msg, "copies: subspace 17, band 2, level 5: the CAR coefficients "
                                  "are unstable: its rows do not decay"));
    free(m.subspaces);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(one_neighbour_bands),
        cmocka_unit_test(two_neighbour_bands),
        cmocka_unit_test(product_bands),
        cmocka_unit_test(reasons_name_the_recursion),
        cmocka_unit_test(generated_materials_bands),
        cmocka_unit_test(ramp_fit_is_stable),
        cmocka_unit_test(writer_refuses_unstable_band),
        cmocka_unit_test(validator_checks_distinct_bands),
    };
    return cmocka_run_group_tests(tests, tu_setup_dir, tu_teardown_dir);
}
