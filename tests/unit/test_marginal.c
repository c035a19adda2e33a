/*
 * test_marginal.c — the marginal transfer (docs/synthesis.md, "Marginals";
 * src/synth/marginal.c, src/analyse/marginal_fit.c): the map is monotone
 * and stays in the exemplar's range for any input, hits the quantiles at
 * the knots; syntheses of fitted generated materials have no negative
 * pixel, stay in the exemplar's RGB box, and match its histogram better
 * than without; degenerate images stay finite; the model file keeps the
 * transfer bit for bit, writes 1.2 only with one, and the validator
 * refuses broken transfers.
 */
#include "testutil.h"
#include "synth/synth.h"
#include "synth/synth_testing.h"

#include "btf_shared.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static btf_subspace_model skewed_subspace(void)
{
    btf_subspace_model sm = {0};
    sm.basis[0] = sm.basis[4] = sm.basis[8] = 1.0f;
    sm.marginal.knots = BTF_MARGIN_KNOTS;
    for (int b = 0; b < 3; b++) {
        sm.marginal.synth_mean[b] = 0.1f * (float)b;
        sm.marginal.synth_sd[b] = 0.5f;
        for (int j = 0; j < BTF_MARGIN_KNOTS; j++) /* skewed, with a flat run */
            sm.marginal.quantile[b][j] = j < 5 ? -0.1f : -0.1f + 0.002f * (float)((j - 4) * (j - 4));
    }
    for (int k = 0; k < 3; k++)
        sm.marginal.rgb_lo[k] = 0.0f, sm.marginal.rgb_hi[k] = 2.0f;
    return sm;
}

/* The model's map through (z_j, q_j) at v, in double (the definition the
 * table resamples). */
static double model_map(const btf_marginal *mg, int b, double v)
{
    double z[BTF_MARGIN_KNOTS];
    for (int j = 0; j < BTF_MARGIN_KNOTS; j++)
        z[j] = (double)mg->synth_mean[b] + (double)mg->synth_sd[b] * btf__marginal_normal_knots[j];
    if (v <= z[0])
        return mg->quantile[b][0];
    for (int j = 0; j + 1 < BTF_MARGIN_KNOTS; j++)
        if (v < z[j + 1])
            return mg->quantile[b][j] + (v - z[j]) / (z[j + 1] - z[j]) *
                                            ((double)mg->quantile[b][j + 1] - mg->quantile[b][j]);
    return mg->quantile[b][BTF_MARGIN_KNOTS - 1];
}

static void transfer_is_monotone_and_bounded(void **state)
{
    (void)state;
    btf_subspace_model sm = skewed_subspace();
    btf_marginal_table t;
    btf__marginal_table_make(&sm, &t);
    assert_true(t.on);
    enum { N = 20001 };
    static float v[N + 4], out[N + 4];
    for (int i = 0; i < N; i++)
        v[i] = -6.0f + 12.0f * (float)i / (float)(N - 1);
    v[N] = -FLT_MAX, v[N + 1] = FLT_MAX, v[N + 2] = -0.0f, v[N + 3] = 1e30f;
    for (int b = 0; b < 3; b++) {
        assert_int_equal(btf__marginal_row(&t, b, v, N + 4, out), 0);
        const float *q = sm.marginal.quantile[b];
        double worst = 0;
        for (int i = 0; i < N + 4; i++) {
            assert_true(out[i] >= q[0] && out[i] <= q[BTF_MARGIN_KNOTS - 1]);
            if (i > 0 && i < N)
                assert_true(out[i] >= out[i - 1]); /* monotone */
            double e = fabs(out[i] - model_map(&sm.marginal, b, v[i]));
            worst = e > worst ? e : worst;
        }
        assert_true(out[N] == q[0] && out[N + 1] == q[BTF_MARGIN_KNOTS - 1]);
        /* the resampled map stays close to the model's: within a few
         * thousandths of the range here (it cuts the corners at the knots) */
        print_message("band %d: largest difference from the model's map %.2e of a range %.3f\n",
                      b, worst, (double)(q[BTF_MARGIN_KNOTS - 1] - q[0]));
        assert_true(worst < 0.01 * (q[BTF_MARGIN_KNOTS - 1] - q[0]));
        /* at a point of the grid, its table value */
        for (int k = 0; k < BTF_MARGIN_SEGS; k++) {
            float z = t.origin[b] + (float)k / t.inv_h[b], o, x = (z - t.origin[b]) * t.inv_h[b];
            btf__marginal_row(&t, b, &z, 1, &o);
            if (x == (float)k)
                assert_true(o == t.q[b][k]);
        }
    }
    float inf = INFINITY;
    assert_int_equal(btf__marginal_row(&t, 0, &inf, 1, out), 1); /* reported */
    /* no transfer: the table is off */
    sm.marginal.knots = 0;
    btf__marginal_table_make(&sm, &t);
    assert_false(t.on);
}

/* The colour step's AVX2 loop (8 pixels at a time, the gamut on vectors)
 * gives the bits of its portable loop, hence of the shader, on colours
 * inside and outside the box, extremes and zeros included; every colour
 * ends in the box, on the segment from the mean towards where it was. */
static void colour_step_paths_agree(void **state)
{
    (void)state;
    btf_subspace_model sm = skewed_subspace();
    const float basis[9] = {0.57735f, 0.57735f, 0.57735f, 0.70711f, 0.0f, -0.70711f,
                            0.40825f, -0.8165f, 0.40825f};
    memcpy(sm.basis, basis, sizeof basis);
    sm.mean[0] = 0.3f, sm.mean[1] = 0.2f, sm.mean[2] = 0.1f;
    for (int k = 0; k < 3; k++)
        sm.marginal.rgb_lo[k] = 0.02f * (float)k, sm.marginal.rgb_hi[k] = 0.45f - 0.1f * (float)k;
    btf_marginal_table t, tp;
    btf__marginal_table_make(&sm, &t);
    tp = t;
    tp.portable = 1;
    enum { W = 4099 };
    static float b[3][W], ra[3 * W], rp[3 * W], plain[3 * W];
    uint64_t r = 12345;
    for (int i = 0; i < W; i++)
        for (int k = 0; k < 3; k++) {
            r = r * 6364136223846793005ull + 1442695040888963407ull;
            b[k][i] = ((float)(r >> 40) / 16777216.0f - 0.5f) * (i % 7 == 0 ? 40.0f : 2.0f);
        }
    b[0][5] = -0.0f, b[1][6] = FLT_MAX, b[2][7] = -FLT_MAX, b[0][8] = 1e-30f;
    int outside = 0;
    assert_int_equal(btf__marginal_unmix_row(&sm, &t, b[0], b[1], b[2], W, ra), 0);
    assert_int_equal(btf__marginal_unmix_row(&sm, &tp, b[0], b[1], b[2], W, rp), 0);
    assert_memory_equal(ra, rp, sizeof ra);
    /* the colours before the gamut: the transfer's bands unmixed */
    for (int i = 0; i < W; i++) {
        float v[3];
        for (int k = 0; k < 3; k++)
            btf__marginal_row(&t, k, &b[k][i], 1, &v[k]);
        for (int k = 0; k < 3; k++)
            plain[3 * i + k] = sm.mean[k] + basis[k] * v[0] + basis[3 + k] * v[1] +
                               basis[6 + k] * v[2];
    }
    for (int i = 0; i < W; i++) {
        int in = 1;
        for (int k = 0; k < 3; k++) {
            assert_true(ra[3 * i + k] >= t.lo[k] && ra[3 * i + k] <= t.hi[k]);
            in &= plain[3 * i + k] >= t.lo[k] && plain[3 * i + k] <= t.hi[k];
        }
        if (in)
            continue;
        outside++;
        /* moved along the line to the mean, to its border: the shares of
         * the three channels agree where the mean is inside the box */
        double s = -1;
        for (int k = 0; k < 3; k++) {
            double d = (double)plain[3 * i + k] - sm.mean[k];
            if (fabs(d) < 1e-3)
                continue;
            double sk = ((double)ra[3 * i + k] - sm.mean[k]) / d;
            assert_true(sk >= -1e-5 && sk <= 1.0 + 1e-5);
            if (s >= 0)
                assert_true(fabs(sk - s) < 1e-4);
            s = sk;
        }
    }
    print_message("%d of %d colours outside the box\n", outside, W);
    assert_true(outside > W / 10);
    /* Inf or NaN in a band, within the vector loop or its tail: reported on
     * both paths, and btf__unmix_row then carries it into the colours, so
     * that the finite test refuses the row (the GPU skips the transfer) */
    const float odd[2] = {INFINITY, NAN};
    const int at[3] = {100, W - 2, 0};
    static float scratch[BTF_UNMIX_SCRATCH * W];
    for (int o = 0; o < 2; o++)
        for (int a = 0; a < 3; a++) {
            float keep = b[a][at[a]];
            b[a][at[a]] = odd[o];
            assert_int_not_equal(btf__marginal_unmix_row(&sm, &t, b[0], b[1], b[2], W, ra), 0);
            assert_int_not_equal(btf__marginal_unmix_row(&sm, &tp, b[0], b[1], b[2], W, rp), 0);
            assert_int_not_equal(btf__unmix_row(&sm, &t, b[0], b[1], b[2], W, scratch, ra), 0);
            btf_error e = {0};
            assert_int_equal(btf__check_finite_row(ra, 3 * W, 0, 0, &e), BTF_E_NUMERIC);
            b[a][at[a]] = keep;
        }
}

/* btf_recip: within 1e-6 of 1/x over its range, and the same on both ends. */
static void reciprocal_is_close(void **state)
{
    (void)state;
    double worst = 0;
    for (int e = -40; e < 40; e++)
        for (int m = 0; m < 1000; m++) {
            float x = ldexpf(1.0f + (float)m / 1000.0f, e);
            if (x > BTF_RECIP_MAX)
                continue;
            double err = fabs((double)btf_recip(x) * x - 1.0);
            worst = err > worst ? err : worst;
        }
    print_message("btf_recip: largest relative error %.2e\n", worst);
    assert_true(worst < 1e-6);
}

/* The earth mover's distance of band b between two images of equal size
 * (sorted samples; linear RGB units, the basis is orthonormal); *sd: the
 * exemplar band's standard deviation. */
static double band_emd(const btf_image *a, const btf_image *s, const btf_subspace_model *sm,
                       int b, double *sd)
{
    size_t n = (size_t)a->width * a->height;
    double *x = malloc(n * sizeof *x), *y = malloc(n * sizeof *y), m = 0, var = 0, d = 0;
    for (size_t i = 0; i < n; i++) {
        x[i] = y[i] = 0;
        for (int k = 0; k < 3; k++) {
            x[i] += sm->basis[3 * b + k] * ((double)a->data[3 * i + k] - sm->mean[k]);
            y[i] += sm->basis[3 * b + k] * ((double)s->data[3 * i + k] - sm->mean[k]);
        }
        m += x[i];
    }
    m /= (double)n;
    for (size_t i = 0; i < n; i++)
        var += (x[i] - m) * (x[i] - m);
    qsort(x, n, sizeof *x, cmp_double);
    qsort(y, n, sizeof *y, cmp_double);
    for (size_t i = 0; i < n; i++)
        d += fabs(x[i] - y[i]);
    free(x);
    free(y);
    *sd = sqrt(var / (double)n);
    return d / (double)n;
}

/* Generated materials, dark and grazing pairs among them: with the
 * transfer no pixel is negative and every pixel is in the exemplar's box;
 * the summed EMD of the bands drops (each material). */
static void materials_keep_their_marginals(void **state)
{
    (void)state;
    const char *names[3] = {"leather", "fabric", "wood"};
    btf_dir pairs[3][2] = {{{0, 0}, {45, 30}}, {{30, 90}, {75, 120}}, {{60, 18}, {60, 200}}};
    btf_error e = {0};
    for (int mi = 0; mi < 3; mi++)
        for (int p = 0; p < 3; p++) {
            btf_image img;
            tu_material_image(names[mi], 64, 3, pairs[p][0], pairs[p][1], &img);
            btf_model m;
            btf_fit_opts fo = btf_fit_defaults();
            fo.levels = 2;
            TU_OK(btf_texture_fit(&img, &fo, &m, &e), &e);
            btf_subspace_model *sm = &m.subspaces[0];
            assert_int_equal(sm->marginal.knots, BTF_MARGIN_KNOTS);
            btf_synth_opts so = btf_synth_defaults();
            so.seed = 11;
            so.match_colours = -1; /* the band transfer alone */
            btf_image on, off;
            TU_OK(btf_synthesise_image(&m, 0, &so, &on, &e), &e);
            btf_marginal keep = sm->marginal;
            sm->marginal.knots = 0;
            TU_OK(btf_synthesise_image(&m, 0, &so, &off, &e), &e);
            sm->marginal = keep;
            size_t n = (size_t)img.width * img.height;
            float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {0, 0, 0};
            for (size_t i = 0; i < 3 * n; i++) {
                lo[i % 3] = fminf(lo[i % 3], img.data[i]);
                hi[i % 3] = fmaxf(hi[i % 3], img.data[i]);
            }
            for (size_t i = 0; i < 3 * n; i++) {
                assert_true(on.data[i] >= 0.0f);
                assert_true(on.data[i] >= lo[i % 3] && on.data[i] <= hi[i % 3]);
            }
            /* each band's distance, their sum in RGB units, and band 0's
             * relative distance */
            double e_on = 0, e_off = 0, sd, r_on = 0, r_off = 0;
            for (int b = 0; b < 3; b++) {
                double a = band_emd(&img, &on, sm, b, &sd), c = band_emd(&img, &off, sm, b, &sd);
                print_message("%s pair %d band %d: EMD/sd %.3f without, %.3f with\n", names[mi],
                              p, b, c / sd, a / sd);
                assert_true(a < c); /* every band closer to the exemplar's histogram */
                e_on += a;
                e_off += c;
                if (b == 0)
                    r_on = a / sd, r_off = c / sd;
            }
            assert_true(e_on < e_off);
            assert_true(r_on < r_off);
            btf_image_free(&on);
            btf_image_free(&off);
            btf_image_free(&img);
            btf_model_free(&m);
        }
}

/* 1x1, constant and huge-valued images: a transfer (or none where synthesis
 * would overflow float), finite output, in the box. */
static void degenerate_images(void **state)
{
    (void)state;
    btf_error e = {0};
    int sizes[3][2] = {{1, 1}, {8, 8}, {3, 17}};
    for (int s = 0; s < 3; s++) {
        btf_image img;
        TU_OK(btf_image_alloc(&img, sizes[s][0], sizes[s][1], 3, &e), &e);
        for (int i = 0; i < sizes[s][0] * sizes[s][1] * 3; i++)
            img.data[i] = s == 2 ? (float)(i % 5) * 0.2f : 0.25f; /* constant, then not */
        btf_model m;
        TU_OK(btf_texture_fit(&img, NULL, &m, &e), &e);
        assert_int_equal(m.subspaces[0].marginal.knots, BTF_MARGIN_KNOTS);
        btf_synth_opts so = {.width = 33, .height = 9, .seed = 2};
        btf_image out;
        TU_OK(btf_synthesise_image(&m, 0, &so, &out, &e), &e);
        for (int i = 0; i < 33 * 9 * 3; i++) {
            assert_true(isfinite(out.data[i]) && out.data[i] >= 0.0f);
            if (s < 2)
                assert_true(fabsf(out.data[i] - 0.25f) < 1e-6f);
        }
        btf_image_free(&out);
        btf_image_free(&img);
        btf_model_free(&m);
    }
}

static void file_keeps_the_transfer(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image img;
    tu_material_image("wood", 32, 1, (btf_dir){0, 0}, (btf_dir){30, 0}, &img);
    btf_model m, r;
    TU_OK(btf_texture_fit(&img, NULL, &m, &e), &e);
    unsigned char *d = NULL, *d0 = NULL;
    size_t n, n0;
    TU_OK(btf_model_encode(&m, &d, &n, &e), &e);
    assert_int_equal(d[13], 3); /* format 1.3: with the Lab histogram */
    TU_OK(btf_model_decode(d, n, "t", &r, &e), &e);
    assert_memory_equal(&r.subspaces[0].marginal, &m.subspaces[0].marginal, sizeof(btf_marginal));
    btf_model_free(&r);
    /* without the Lab histogram: 1.2 as before, and it reads back with none */
    {
        btf_model m2 = m;
        btf_subspace_model sub = m.subspaces[0];
        sub.marginal.lab_knots = 0;
        memset(sub.marginal.lab_quantile, 0, sizeof sub.marginal.lab_quantile);
        m2.subspaces = &sub;
        unsigned char *d2 = NULL;
        size_t n2;
        TU_OK(btf_model_encode(&m2, &d2, &n2, &e), &e);
        assert_int_equal(d2[13], 2);
        print_message("bytes added by the Lab histogram (one subspace, deflated): %zu\n", n - n2);
        TU_OK(btf_model_decode(d2, n2, "t", &r, &e), &e);
        assert_int_equal(r.subspaces[0].marginal.lab_knots, 0);
        btf_synth_opts so = {.width = 16, .height = 16, .seed = 1, .match_colours = 1};
        btf_image out;
        btf_error me = {0};
        assert_int_equal(btf_synthesise_image(&r, 0, &so, &out, &me), BTF_E_ARG);
        print_message("refused: %s\n", me.msg);
        assert_non_null(strstr(me.msg, "no Lab histogram"));
        btf_model_free(&r);
        free(d2);
    }
    /* without a transfer: 1.0 as before, and it reads back with none */
    btf_marginal keep = m.subspaces[0].marginal;
    memset(&m.subspaces[0].marginal, 0, sizeof keep);
    TU_OK(btf_model_encode(&m, &d0, &n0, &e), &e);
    assert_int_equal(d0[13], 0);
    print_message("bytes added by the transfer (one subspace, deflated): %zu\n", n - n0);
    TU_OK(btf_model_decode(d0, n0, "t", &r, &e), &e);
    assert_int_equal(r.subspaces[0].marginal.knots, 0);
    btf_model_free(&r);
    /* the validator: broken transfers are refused with a message */
    struct { int what; const char *needle; } cases[] = {
        {0, "nondecreasing"}, {1, "sd"}, {2, "RGB range"}, {3, "knots"}, {4, "quantile"},
        {5, "Lab histogram of 5 knots"}, {6, "a* quantile 4"}, {7, "L* quantile 0"}};
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        m.subspaces[0].marginal = keep;
        btf_marginal *mg = &m.subspaces[0].marginal;
        switch (cases[c].what) {
        case 0: mg->quantile[1][5] = mg->quantile[1][4] - 1.0f; break;
        case 1: mg->synth_sd[2] = -1.0f; break;
        case 2: mg->rgb_lo[0] = -0.5f; break;
        case 3: mg->knots = 7; break;
        case 5: mg->lab_knots = 5; break;
        case 6: mg->lab_quantile[1][4] = mg->lab_quantile[1][3] - 1.0f; break;
        case 7: mg->lab_quantile[0][0] = -1.0f; break;
        default: mg->quantile[0][3] = NAN; break;
        }
        unsigned char *bad = NULL;
        size_t nb;
        btf_error be = {0};
        assert_int_equal(btf_model_encode(&m, &bad, &nb, &be), BTF_E_DATA);
        print_message("refused: %s\n", be.msg);
        assert_non_null(strstr(be.msg, cases[c].needle));
        assert_null(bad);
    }
    m.subspaces[0].marginal = keep;
    free(d);
    free(d0);
    btf_model_free(&m);
    btf_image_free(&img);
}

static int rows_to_image(void *user, int y, int nrows, const float *rows, btf_error *err)
{
    (void)err;
    btf_image *img = user;
    size_t n = (size_t)img->width * 3;
    memcpy(img->data + (size_t)y * n, rows, (size_t)nrows * n * sizeof(float));
    return 0;
}

/* The float Lab conversion of colour matching (src/synth/colour_lab.c):
 * a row (AVX2 blocks of 8 where the CPU has it) and the same pixels one at
 * a time (the scalar code) give the same bits both ways; within 1e-3 of
 * the CIE formulas in double (for colours of [0, 1.5]); finite at the extremes (0, negative light,
 * 1e-30, the linear segment's edge, 1e30, FLT_MAX); the way back returns
 * the colour (within 1e-5 + 1e-4 of it: float near black cancels in the
 * XYZ-to-RGB matrix) and stays inside the box. */
static double lab_f_ref(double t)
{
    return t > 0.008856 ? cbrt(t) : 7.787 * t + 16.0 / 116.0;
}

static void lab_conversion_paths_agree(void **state)
{
    (void)state;
    enum { N = 203 }; /* 25 blocks of 8 and a tail of 3 */
    static const double M[3][3] = {{0.412453, 0.357580, 0.180423},
                                   {0.212671, 0.715160, 0.072169},
                                   {0.019334, 0.119193, 0.950227}};
    static const double W[3] = {0.950456, 1.0, 1.088754};
    const float odd[] = {0.0f, -0.5f, 1e-30f, 0.008856f, 0.0088561f, 1.0f, 1e30f, FLT_MAX};
    float rgb[3 * N], lab[3][N], one[3], back[3 * N], back1[3];
    srand(5);
    for (int i = 0; i < 3 * N; i++) {
        double u = rand() / (double)RAND_MAX;
        rgb[i] = i < 3 * 40 ? odd[(i * 7 + i / 3) % 8] : (float)(u * u * u * 1.5);
    }
    btf__lab_row(rgb, N, 1.0f, lab[0], lab[1], lab[2]);
    const float lo[3] = {0.0f, 0.0f, 0.0f}, hi[3] = {1.5f, 1.5f, 1.5f};
    btf__rgb_row_from_lab(lab[0], lab[1], lab[2], N, 1.0f, lo, hi, back);
    for (int x = 0; x < N; x++) {
        btf__lab_row(rgb + 3 * x, 1, 1.0f, &one[0], &one[1], &one[2]);
        double c[3], xyz[3], f[3];
        for (int k = 0; k < 3; k++) {
            assert_memory_equal(&one[k], &lab[k][x], sizeof(float));
            assert_true(isfinite(lab[k][x]));
            c[k] = rgb[3 * x + k] > 0.0f ? fmin(rgb[3 * x + k], 1e6) : 0.0;
        }
        for (int i = 0; i < 3; i++)
            f[i] = lab_f_ref((M[i][0] * c[0] + M[i][1] * c[1] + M[i][2] * c[2]) / W[i]);
        xyz[0] = 116.0 * f[1] - 16.0, xyz[1] = 500.0 * (f[0] - f[1]), xyz[2] = 200.0 * (f[1] - f[2]);
        /* float's few roundings of f, times a*'s 500: 1e-3 in the colours
         * of [0, 1.5], more for light far beyond (1e6: flat in every map) */
        double tol = 1e-3 + 1e-6 * 500.0 * fmax(f[0], fmax(f[1], f[2]));
        for (int k = 0; k < 3; k++)
            assert_true(fabs(xyz[k] - lab[k][x]) <= tol);
        btf__rgb_row_from_lab(&lab[0][x], &lab[1][x], &lab[2][x], 1, 1.0f, lo, hi, back1);
        for (int k = 0; k < 3; k++) {
            assert_memory_equal(&back1[k], &back[3 * x + k], sizeof(float));
            assert_true(back[3 * x + k] >= lo[k] && back[3 * x + k] <= hi[k]);
            float want = rgb[3 * x + k];
            if (x >= 40 && want > 0.01f && c[0] <= 1.5 && c[1] <= 1.5 && c[2] <= 1.5)
                assert_true(fabs(back[3 * x + k] - want) <= 1e-5 + 1e-4 * want);
        }
    }
}

/* The quantiles of a colour match's sample (btf__lab_sample_quantiles:
 * order statistics from buckets, without a full sort) are exactly those of
 * a sorted copy, linear between order statistics at (n - 1) j / 31, for
 * spread values, heavy ties, two values, one value, and n of 1, 2, 9 and
 * 16,384. */
static int cmp_float_asc(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

static void sample_quantiles_are_exact(void **state)
{
    (void)state;
    const size_t sizes[] = {1, 2, 9, 1000, 16384};
    srand(11);
    for (size_t si = 0; si < sizeof sizes / sizeof *sizes; si++)
        for (int kind = 0; kind < 4; kind++) {
            size_t n = sizes[si];
            btf_error e = {0};
            btf_lab_sample s;
            TU_OK(btf__lab_sample_begin(&s, (int)n, 1, n, 1.0f, &e), &e);
            assert_int_equal(s.n, n);
            for (size_t i = 0; i < 3 * n; i++) {
                double u = rand() / (double)RAND_MAX;
                float v = kind == 0   ? (float)(100.0 * u * u * u)       /* skewed, spread */
                          : kind == 1 ? (float)(int)(u * 5.0) * 10.0f   /* 5 values, ties */
                          : kind == 2 ? (u < 0.7 ? 3.0f : 97.5f)        /* two values */
                                      : 42.0f;                          /* one value */
                s.v[i] = i >= 2 * n ? v - 50.0f : v;                     /* b* below 0 too */
            }
            float ref[3][BTF_MARGIN_KNOTS], got[3][BTF_MARGIN_KNOTS];
            for (int c = 0; c < 3; c++) {
                float *sorted = malloc(n * sizeof *sorted);
                memcpy(sorted, s.v + c * n, n * sizeof *sorted);
                qsort(sorted, n, sizeof *sorted, cmp_float_asc);
                for (int j = 0; j < BTF_MARGIN_KNOTS; j++) {
                    double h = (double)(n - 1) * j / (BTF_MARGIN_KNOTS - 1);
                    size_t k = (size_t)h;
                    double x = k + 1 < n ? sorted[k] + (h - (double)k) *
                                                           ((double)sorted[k + 1] - sorted[k])
                                         : sorted[n - 1];
                    float lim = c == 0 ? 100.0f : 128.0f, low = c == 0 ? 0.0f : -128.0f;
                    float q = (float)x;
                    q = q < low ? low : q > lim ? lim : q;
                    ref[c][j] = j > 0 && q < ref[c][j - 1] ? ref[c][j - 1] : q;
                }
                free(sorted);
            }
            TU_OK(btf__lab_sample_quantiles(&s, got, &e), &e);
            assert_memory_equal(got, ref, sizeof ref);
            btf__lab_sample_free(&s);
        }
}

/* Colour matching (btf_synth_opts.match_colours, btf__colour_match) on the
 * generated materials: the first-order texture distance (CIE Lab histograms,
 * src/measure/first_order.c) of a 64 x 64 synthesis comes within 1.2 of the
 * material's own (fabric: a tenth of the unmatched) and below the unmatched
 * synthesis'; the default matches (the bytes of match_colours 1); pixels stay
 * in the exemplar's box; the streaming synthesis gives the image's bytes,
 * whole image kept or synthesised twice. */
static void colour_match_keeps_lab_histograms(void **state)
{
    (void)state;
    const char *names[3] = {"leather", "fabric", "wood"};
    btf_error e = {0};
    for (int mi = 0; mi < 3; mi++) {
        btf_image img;
        tu_material_image(names[mi], 64, 3, (btf_dir){30, 90}, (btf_dir){45, 30}, &img);
        btf_model m;
        TU_OK(btf_texture_fit(&img, NULL, &m, &e), &e);
        const btf_marginal *mg = &m.subspaces[0].marginal;
        assert_int_equal(mg->lab_knots, BTF_MARGIN_KNOTS);
        btf_synth_opts so = btf_synth_defaults();
        so.seed = 5;
        btf_image plain, matched, asked;
        so.match_colours = -1;
        assert_int_equal(btf_synth_holds_whole(&m, 0, &so), 0); /* streams */
        assert_int_equal(btf_synth_holds_whole(&m, 1, NULL), 0); /* no such subspace */
        TU_OK(btf_synthesise_image(&m, 0, &so, &plain, &e), &e);
        so.match_colours = 0; /* the default matches */
        TU_OK(btf_synthesise_image(&m, 0, &so, &matched, &e), &e);
        so.match_colours = 1;
        TU_OK(btf_synthesise_image(&m, 0, &so, &asked, &e), &e);
        assert_memory_equal(asked.data, matched.data, (size_t)img.width * img.height * 3 * 4);
        btf_image_free(&asked);
        btf_texture_distances dp, dm;
        TU_OK(btf_texture_distance(&img, &plain, NULL, &dp, &e), &e);
        TU_OK(btf_texture_distance(&img, &matched, NULL, &dm, &e), &e);
        print_message("%s: first order %.2f without, %.2f with colour matching; combined %.2f, "
                      "%.2f\n", names[mi], dp.first_order.normalised, dm.first_order.normalised,
                      dp.combined, dm.combined);
        /* fabric's weave: a multimodal histogram whose 32 quantiles,
         * joined linearly, leave 3 x the tiny self-distance of its 32 x 32
         * quadrants at this size (0.7-0.9 on the 128 x 128 subspace images
         * of docs/fidelity.md); still a tenth of the unmatched distance */
        if (mi == 1)
            assert_true(dm.first_order.normalised < 0.15 * dp.first_order.normalised);
        else
            assert_true(dm.first_order.normalised <= 1.2);
        assert_true(dm.first_order.normalised < dp.first_order.normalised);
        size_t n = (size_t)img.width * img.height * 3;
        for (size_t i = 0; i < n; i++)
            assert_true(matched.data[i] >= mg->rgb_lo[i % 3] && matched.data[i] <= mg->rgb_hi[i % 3]);
        /* the streaming API, whole image kept inside, and synthesised twice
         * (its threshold forced down): the same bytes */
        btf_image streamed;
        TU_OK(btf_image_alloc(&streamed, img.width, img.height, 3, &e), &e);
        assert_int_equal(btf_synth_holds_whole(&m, 0, &so), 1);
        btf_synth_opts twice = so;
        twice.match_whole_bytes = 1;
        assert_int_equal(btf_synth_holds_whole(&m, 0, &twice), 0); /* synthesised twice */
        TU_OK(btf_synthesise(&m, 0, &twice, rows_to_image, &streamed, &e), &e);
        assert_memory_equal(streamed.data, matched.data, n * sizeof(float));
        memset(streamed.data, 0, n * sizeof(float));
        TU_OK(btf_synthesise(&m, 0, &so, rows_to_image, &streamed, &e), &e);
        assert_memory_equal(streamed.data, matched.data, n * sizeof(float));
        /* matching twice changes little: the image has the histogram (but
         * for the box and the 32 knots' linear segments) */
        TU_OK(btf__colour_match(&m, 0, &streamed, &e), &e);
        double moved = 0, first = 0;
        for (size_t i = 0; i < n; i++) {
            moved += fabs((double)streamed.data[i] - matched.data[i]);
            first += fabs((double)matched.data[i] - plain.data[i]);
        }
        print_message("%s: mean change of the match %.2e, of a second one %.2e\n", names[mi],
                      first / (double)n, moved / (double)n);
        assert_true(moved < 0.1 * first);
        btf_image_free(&streamed);
        btf_image_free(&plain);
        btf_image_free(&matched);
        btf_image_free(&img);
        btf_model_free(&m);
    }
}

/* Colour matching at the extremes: 1 x 1, constant, black and saturated
 * exemplars, huge values; every result finite and in the box; bad calls
 * refused with a message. */
static void colour_match_extremes(void **state)
{
    (void)state;
    btf_error e = {0};
    const float fill[5] = {0.25f, 0.0f, 1.0f, 3e30f, 1e-30f};
    for (int k = 0; k < 5; k++)
        for (int side = 1; side <= 17; side += 16) {
            btf_image img;
            TU_OK(btf_image_alloc(&img, side, side, 3, &e), &e);
            for (int i = 0; i < side * side * 3; i++)
                img.data[i] = fill[k] * (side > 1 ? (float)(1 + i % 7) / 7.0f : 1.0f);
            btf_model m;
            TU_OK(btf_texture_fit(&img, NULL, &m, &e), &e);
            const btf_marginal *mg = &m.subspaces[0].marginal;
            if (!mg->knots) { /* a model synthesis would overflow: no transfer, refused */
                btf_image_free(&img);
                btf_model_free(&m);
                continue;
            }
            int sizes[2][2] = {{1, 1}, {40, 3}};
            for (int z = 0; z < 2; z++) {
                btf_synth_opts so = {.width = sizes[z][0], .height = sizes[z][1], .seed = 3,
                                     .match_colours = 1};
                btf_image out;
                TU_OK(btf_synthesise_image(&m, 0, &so, &out, &e), &e);
                for (int i = 0; i < so.width * so.height * 3; i++)
                    assert_true(isfinite(out.data[i]) && out.data[i] >= mg->rgb_lo[i % 3] &&
                                out.data[i] <= mg->rgb_hi[i % 3]);
                btf_image_free(&out);
            }
            btf_image_free(&img);
            btf_model_free(&m);
        }
    /* a one-pixel image has one value: it takes the exemplar's median, not
     * its darkest colour (a half-dark, half-light grey exemplar) */
    {
        btf_image two;
        TU_OK(btf_image_alloc(&two, 16, 16, 3, &e), &e);
        for (int i = 0; i < 256 * 3; i++)
            two.data[i] = (i / 3 + i / 48) % 2 ? 0.6f : 0.1f;
        btf_model m2;
        TU_OK(btf_texture_fit(&two, NULL, &m2, &e), &e);
        btf_synth_opts so = {.width = 1, .height = 1, .seed = 9, .match_colours = 1};
        btf_image one;
        TU_OK(btf_synthesise_image(&m2, 0, &so, &one, &e), &e);
        print_message("1x1 of a 0.1 / 0.6 grey exemplar: %g %g %g\n", one.data[0], one.data[1],
                      one.data[2]);
        for (int k = 0; k < 3; k++)
            assert_true(one.data[k] > 0.15f && one.data[k] < 0.55f);
        btf_image_free(&one);
        btf_image_free(&two);
        btf_model_free(&m2);
    }
    btf_image img;
    tu_material_image("wood", 16, 1, (btf_dir){0, 0}, (btf_dir){30, 0}, &img);
    btf_model m;
    TU_OK(btf_texture_fit(&img, NULL, &m, &e), &e);
    btf_error be = {0};
    assert_int_equal(btf__colour_match(&m, 1, &img, &be), BTF_E_ARG);
    assert_non_null(strstr(be.msg, "subspace 1"));
    img.data[7] = NAN;
    assert_int_equal(btf__colour_match(&m, 0, &img, &be), BTF_E_ARG);
    assert_non_null(strstr(be.msg, "not finite"));
    btf_image_free(&img);
    btf_model_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(transfer_is_monotone_and_bounded),
        cmocka_unit_test(colour_step_paths_agree),
        cmocka_unit_test(reciprocal_is_close),
        cmocka_unit_test(materials_keep_their_marginals),
        cmocka_unit_test(degenerate_images),
        cmocka_unit_test(file_keeps_the_transfer),
        cmocka_unit_test(lab_conversion_paths_agree),
        cmocka_unit_test(sample_quantiles_are_exact),
        cmocka_unit_test(colour_match_keeps_lab_histograms),
        cmocka_unit_test(colour_match_extremes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
