/*
 * test_rf.c — the reflectance-field family (Meseth, Müller &
 * Klein 2003; src/rf/, docs/rf.md): a PTM texel recovered exactly, a known
 * lobe recovered by Levenberg–Marquardt, finite fits at the extremes (black,
 * saturated, constant, NaN, grazing), the four-view weights, fits of a
 * generated dataset (thread-independent, errors consistent), the file's
 * round trip and its corrupt forms, the flat render at a measured view,
 * and the command line.
 */
#include "testutil.h"

#include "rf/rf.h"
#include "report/report.h" /* btf__rf_report_write */

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static btf_dataset *ds;
static btf_rf_model ptm, lobes, laf;
static btf_rf_fit_info ptm_info, lobes_info, laf_info;
static char dataset_path[4096];

static void fit(int kind, int threads, btf_rf_model *m, btf_rf_fit_info *info)
{
    btf_error e = {0};
    btf_rf_opts o = btf_rf_defaults();
    o.fit = kind;
    o.threads = threads;
    o.info = info;
    TU_OK(btf_rf_fit(ds, &o, m, &e), &e);
}

static int setup(void **state)
{
    if (tu_setup_dir(state) ||
        tu_generate_dataset("leather", 16, 3, dataset_path, sizeof dataset_path, &ds))
        return -1;
    btf_error e = {0};
    btf_rf_opts o = btf_rf_defaults();
    o.threads = 2;
    o.info = &ptm_info;
    if (btf_rf_fit(ds, &o, &ptm, &e) != 0)
        return fprintf(stderr, "setup: %s\n", e.msg), -1;
    o.fit = BTF_RF_LOBES, o.info = &lobes_info;
    if (btf_rf_fit(ds, &o, &lobes, &e) != 0)
        return fprintf(stderr, "setup: %s\n", e.msg), -1;
    o.fit = BTF_RF_LAFORTUNE, o.info = &laf_info;
    if (btf_rf_fit(ds, &o, &laf, &e) != 0)
        return fprintf(stderr, "setup: %s\n", e.msg), -1;
    return 0;
}

static int teardown(void **state)
{
    btf_rf_model_free(&ptm);
    btf_rf_model_free(&lobes);
    btf_rf_model_free(&laf);
    btf_dataset_close(ds);
    return tu_teardown_dir(state);
}

/* The unit light vectors of ubo81. */
static int ubo_lights(double *l, btf_dirset *set)
{
    btf_error e = {0};
    TU_OK(btf_dirset_ubo81(set, &e), &e);
    for (int j = 0; j < set->count; j++)
        btf_dir_to_vec(set->dirs[j], l + 3 * j);
    return set->count;
}

/* ------------------------------------------------------------ the fits */

static void ptm_recovers_known_coefficients(void **state)
{
    (void)state;
    btf_dirset set;
    double l[81 * 3], pinv[6 * 81], a[6];
    int n = ubo_lights(l, &set);
    const double truth[6] = {-0.31, 0.12, 0.05, 0.2, -0.07, 0.45};
    float y[81];
    for (int j = 0; j < n; j++) {
        double b[6], s = 0.0;
        rf_ptm_basis(l[3 * j], l[3 * j + 1], b);
        for (int r = 0; r < 6; r++)
            s += truth[r] * b[r];
        y[j] = (float)s;
    }
    btf_error e = {0};
    TU_OK(rf_ptm_operator(&set, pinv, &e), &e);
    rf_ptm_apply(pinv, n, y, a);
    for (int r = 0; r < 6; r++) /* exact up to the float data */
        assert_true(fabs(a[r] - truth[r]) < 1e-6);
    /* Quantised: within the stated (hi - lo) / 131070 of the fitted value. */
    float vals[4 * 6], lo[6], hi[6];
    uint16_t codes[4 * 6];
    for (int t = 0; t < 4; t++)
        for (int r = 0; r < 6; r++)
            vals[t * 6 + r] = (float)(truth[r] * (1.0 + 0.3 * t) + 0.01 * t);
    rf_quantise_field(vals, 4, 6, lo, hi, codes);
    for (int t = 0; t < 4; t++)
        for (int r = 0; r < 6; r++) {
            float back = rf_dequantise(codes[t * 6 + r], lo[r], hi[r]);
            assert_true(fabsf(back - vals[t * 6 + r]) <= (hi[r] - lo[r]) / 131070.0f * 1.001f +
                                                               1e-7f);
        }
    btf_dirset_free(&set);
}

static double lobes_residual(int k, const float *p, const double *l, const float *y, int n)
{
    double worst = 0.0;
    for (int j = 0; j < n; j++) {
        double d = fabs(rf_lum_eval(BTF_RF_LOBES, k, p, l + 3 * j, NULL) - y[j]);
        worst = d > worst ? d : worst;
    }
    return worst;
}

static void lm_recovers_a_known_lobe(void **state)
{
    (void)state;
    btf_dirset set;
    double l[81 * 3], pinv[6 * 81], a[6];
    int n = ubo_lights(l, &set);
    btf_error e = {0};
    TU_OK(rf_ptm_operator(&set, pinv, &e), &e);
    const float truth[4] = {0.8f, 0.3f, -0.2f, (float)log2(12.0)};
    float y[81], out[8];
    for (int j = 0; j < n; j++)
        y[j] = (float)rf_lobe_eval(truth, l + 3 * j);
    rf_ptm_apply(pinv, n, y, a);
    int steps = rf_lobes_fit(1, n, l, y, a, 100, out);
    assert_true(steps > 0);
    assert_true(fabsf(out[0] - truth[0]) < 2e-3f);
    assert_true(fabsf(out[1] - truth[1]) < 2e-3f);
    assert_true(fabsf(out[2] - truth[2]) < 2e-3f);
    assert_true(fabsf(out[3] - truth[3]) < 1e-2f);
    assert_true(lobes_residual(1, out, l, y, n) < 1e-4);
    /* Two lobes, a broad and a narrow one, initialised from the high pass. */
    const float two[8] = {0.3f, 0.0f, 0.1f, 0.0f, 0.6f, -0.5f, 0.4f, (float)log2(30.0)};
    for (int j = 0; j < n; j++)
        y[j] = (float)(rf_lobe_eval(two, l + 3 * j) + rf_lobe_eval(two + 4, l + 3 * j));
    rf_ptm_apply(pinv, n, y, a);
    rf_lobes_fit(2, n, l, y, a, 200, out);
    assert_true(lobes_residual(2, out, l, y, n) < 2e-3);
    btf_dirset_free(&set);
}

static void all_finite(const float *p, int n)
{
    for (int i = 0; i < n; i++)
        assert_true(isfinite(p[i]));
}

static void extremes_give_finite_fits(void **state)
{
    (void)state;
    btf_dirset set;
    double l[81 * 3], pinv[6 * 81], a[6], v[81 * 3];
    int n = ubo_lights(l, &set);
    btf_error e = {0};
    TU_OK(rf_ptm_operator(&set, pinv, &e), &e);
    for (int j = 0; j < n; j++) /* views for the Lafortune fit: a grazing one */
        v[3 * j] = 0.99, v[3 * j + 1] = 0.0, v[3 * j + 2] = sqrt(1 - 0.99 * 0.99);
    float y[81], out[BTF_RF_MAX_SLOTS];
    for (int c = 0; c < 7; c++) {
        for (int j = 0; j < n; j++)
            y[j] = c == 0   ? 0.0f                               /* black */
                   : c == 1 ? 1.0f                               /* saturated */
                   : c == 2 ? 0.37f                              /* constant */
                   : c == 3 ? (j == 40 ? 1.0f : 0.0f)            /* one light only */
                   : c == 4 ? (j % 2 ? NAN : 0.5f)               /* NaN in the data */
                   : c == 5 ? 1e30f                              /* huge */
                            : (l[3 * j + 2] < 0.3 ? 1.0f : 0.0f); /* grazing lights only */
        float clean[81];
        for (int j = 0; j < n; j++)
            clean[j] = isfinite(y[j]) ? y[j] : 0.0f;
        rf_ptm_apply(pinv, n, clean, a);
        for (int k = 1; k <= BTF_RF_MAX_LOBES; k++) {
            rf_lobes_fit(k, n, l, y, a, 40, out);
            all_finite(out, 4 * k);
            rf_lafortune_fit(k, n, l, v, y, 40, out);
            all_finite(out, 1 + 5 * k);
        }
        /* evaluation anywhere, grazing and below the horizon too */
        for (int j = 0; j <= 180; j++) {
            double th = j * M_PI / 180.0, lv[3] = {sin(th), 0.0, cos(th)};
            assert_true(isfinite(rf_lum_eval(BTF_RF_LOBES, BTF_RF_MAX_LOBES, out, lv, lv)));
            assert_true(isfinite(rf_lum_eval(BTF_RF_LAFORTUNE, BTF_RF_MAX_LOBES, out, lv, lv)));
        }
    }
    /* Stored values at their extremes (a damaged but CRC-valid file) are clamped. */
    const float wild[BTF_RF_MAX_SLOTS] = {1e30f, -1e30f, 1e30f, 1e30f, 1e30f, 1e30f,
                                          -1e30f, 1e30f, 3e38f, 3e38f, -3e38f};
    for (int j = 0; j < n; j++) {
        double yl = rf_lum_eval(BTF_RF_LOBES, 2, wild, l + 3 * j, l + 3 * j);
        double yf = rf_lum_eval(BTF_RF_LAFORTUNE, 2, wild, l + 3 * j, l + 3 * j);
        assert_true(isfinite(yl) && yl <= 2.0 * BTF_RF_MAX_RHO);
        assert_true(isfinite(yf) && yf <= 3.0 * BTF_RF_MAX_RHO);
    }
    btf_dirset_free(&set);
}

/* The float functions of src/rf/btf_rf_shared.h (what both renderers run)
 * against libm in double: exp2, pow and atan2 within the accuracy the
 * header states, a lobe within 1e-5 relative of the double formula, and
 * nothing subnormal, infinite or NaN at the ends. */
static void shared_math_matches_libm(void **state)
{
    (void)state;
    double worst = 0.0;
    for (double t = -124.9; t <= 126.0; t += 0.0137) {
        double r = btf_rf_exp2((float)t), want = exp2((double)(float)t);
        worst = fmax(worst, fabs(r - want) / want);
    }
    print_message("exp2: %.3g relative\n", worst);
    assert_true(worst < 1.5e-7);
    assert_true(btf_rf_exp2(-125.0f) == 0.0f && btf_rf_exp2(-1e30f) == 0.0f);
    assert_true(btf_rf_exp2(NAN) == 0.0f && isfinite(btf_rf_exp2(1e30f)));
    assert_true(btf_rf_exp2(3.0f) == 8.0f && btf_rf_exp2(0.0f) == 1.0f);
    worst = 0.0;
    const float ns[] = {0.25f, 1.0f, 2.5f, 7.3f, 64.0f, 1024.0f};
    for (size_t k = 0; k < sizeof ns / sizeof ns[0]; k++)
        for (double c = 1e-6; c <= 1.0; c *= 1.0137) {
            double want = pow((double)(float)c, ns[k]);
            if (want < 1e-30)
                continue;
            double got = btf_rf_pow((float)c, ns[k]);
            double bound = 1.5e-7 * (2.0 + fabs(ns[k] * log2((float)c)));
            worst = fmax(worst, fabs(got - want) / want / bound);
        }
    print_message("pow: %.3g of the stated bound\n", worst);
    assert_true(worst <= 1.0);
    assert_true(btf_rf_pow(0.0f, 0.25f) == 0.0f && btf_rf_pow(1e-39f, 0.25f) == 0.0f);
    assert_true(btf_rf_pow(NAN, 2.0f) == 0.0f && btf_rf_pow(1.0f, 1024.0f) == 1.0f);
    worst = 0.0;
    for (double a = -180.0; a <= 180.0; a += 0.0731)
        for (double r = 1e-3; r < 1e4; r *= 17.0) {
            float y = (float)(r * sin(a * M_PI / 180)), x = (float)(r * cos(a * M_PI / 180));
            worst = fmax(worst, fabs(btf_rf_atan2(y, x) - atan2((double)y, (double)x)));
        }
    print_message("atan2: %.3g rad\n", worst);
    assert_true(worst < 3e-7);
    assert_true(btf_rf_atan2(0.0f, 0.0f) == 0.0f && btf_rf_atan2(0.0f, 1.0f) == 0.0f);
    /* a lobe against its double formula */
    worst = 0.0;
    const float lobe[4] = {0.8f, 0.3f, -0.2f, (float)log2(12.0)};
    for (double th = 0.0; th < 90.0; th += 0.7)
        for (double ph = 0.0; ph < 360.0; ph += 11.0) {
            double l[3];
            btf_dir_to_vec((btf_dir){th, ph}, l);
            float lf[3] = {(float)l[0], (float)l[1], (float)l[2]};
            double c = (0.3 * lf[0] - 0.2 * lf[1] + lf[2]) / sqrt(0.09 + 0.04 + 1.0);
            double want = c > 0 ? 0.8 * pow(c, exp2(lobe[3])) : 0.0;
            double got = rf_lobe_eval(lobe, l);
            worst = fmax(worst, fabs(got - want) / (want + 1e-6));
        }
    print_message("lobe: %.3g relative\n", worst);
    /* the float cosine's rounding (a few 1e-8) times n = 12 */
    assert_true(worst < 1e-5);
}

static void view_weights_are_bilinear(void **state)
{
    (void)state;
    btf_dirset set;
    btf_error e = {0};
    TU_OK(btf_dirset_ubo81(&set, &e), &e);
    int idx[4];
    double w[4];
    /* at every measured view: weight 1 on it */
    for (int v = 0; v < set.count; v++) {
        btf__rf_view_weights(&set, set.dirs[v], idx, w);
        double on = 0.0;
        for (int i = 0; i < 4; i++)
            on += idx[i] == v ? w[i] : 0.0;
        assert_true(fabs(on - 1.0) < 1e-12);
    }
    /* everywhere: four weights in [0, 1] summing to 1 (to float rounding:
     * the weights are btf_rf_shared.h's, the renderers' own), views from
     * two rings */
    for (double th = 0; th <= 90; th += 2.5)
        for (double ph = 0; ph < 360; ph += 7.3) {
            btf__rf_view_weights(&set, (btf_dir){th, ph}, idx, w);
            double s = 0.0;
            for (int i = 0; i < 4; i++) {
                assert_true(w[i] >= 0.0 && w[i] <= 1.0);
                assert_true(idx[i] >= 0 && idx[i] < set.count);
                s += w[i];
            }
            assert_true(fabs(s - 1.0) < 1e-6);
        }
    /* halfway between rings 15 and 30 at phi 0: 1/2 on (15, 0) and (30, 0) */
    btf__rf_view_weights(&set, (btf_dir){22.5, 0}, idx, w);
    assert_true(fabs(set.dirs[idx[0]].theta - 15) < 1e-9 && fabs(w[0] - 0.5) < 1e-12);
    assert_true(fabs(set.dirs[idx[2]].theta - 30) < 1e-9 && fabs(w[2] - 0.5) < 1e-12);
    /* between two azimuths of ring 15 (60 degrees apart): linear in phi */
    btf__rf_view_weights(&set, (btf_dir){15, 45}, idx, w);
    assert_true(fabs(set.dirs[idx[0]].phi - 0) < 1e-9 && fabs(w[0] - 0.25) < 1e-12);
    assert_true(fabs(set.dirs[idx[1]].phi - 60) < 1e-9 && fabs(w[1] - 0.75) < 1e-12);
    /* past the last ring: that ring alone, wrapping around phi = 360 */
    btf__rf_view_weights(&set, (btf_dir){85, 355}, idx, w);
    assert_true(fabs(set.dirs[idx[0]].theta - 75) < 1e-9 && fabs(w[0] + w[1] - 1.0) < 1e-12);
    btf_dirset_free(&set);
}

/* ---------------------------------------------------------- the dataset */

static void fits_are_finite_and_measured(void **state)
{
    (void)state;
    const btf_rf_model *ms[3] = {&ptm, &lobes, &laf};
    const btf_rf_fit_info *is[3] = {&ptm_info, &lobes_info, &laf_info};
    for (int k = 0; k < 3; k++) {
        const btf_rf_model *m = ms[k];
        assert_int_equal(m->width, 16);
        assert_int_equal(m->fields, k == 2 ? 1 : 81);
        assert_int_equal(m->slots, btf__rf_param_count(m->fit, k ? 2 : 0) + 3);
        for (int i = 0; i < m->fields * m->slots; i++)
            assert_true(isfinite(m->lo[i]) && m->lo[i] <= m->hi[i]);
        /* the fit's own error equals btf__rf_error's on the same data */
        double e = -1, s = -1;
        btf_error err = {0};
        TU_OK(btf__rf_error(ds, m, 2, &e, &s, &err), &err);
        assert_true(fabs(e - is[k]->mean_abs_error) <= 1e-9 * (e + 1e-12));
        assert_true(fabs(s - is[k]->mean_luminance) <= 1e-9 * s);
        assert_true(e > 0.0 && e < s);
        print_message("fit %-9s mean |dY| %.5f (mean Y %.4f)\n", btf_rf_fit_name(m->fit), e, s);
    }
    /* The non-linear lobes fit the measured reflectance fields better than
     * the biquadratic (the paper's Table 1), and the per-view fields better
     * than one Lafortune model over all views. */
    assert_true(lobes_info.mean_abs_error < ptm_info.mean_abs_error);
    assert_true(ptm_info.mean_abs_error < laf_info.mean_abs_error);
    assert_true(lobes_info.lm_runs == 81 * 16 * 16);
}

static void fit_does_not_depend_on_threads(void **state)
{
    (void)state;
    btf_rf_model one;
    fit(BTF_RF_LOBES, 1, &one, NULL);
    size_t n = (size_t)one.fields * one.slots * one.width * one.height;
    assert_memory_equal(one.codes, lobes.codes, n * sizeof(uint16_t));
    assert_memory_equal(one.lo, lobes.lo, (size_t)one.fields * one.slots * sizeof(float));
    btf_rf_model_free(&one);
}

static void zero_null_and_defaults_agree(void **state)
{
    (void)state;
    btf_rf_opts d = btf_rf_defaults();
    assert_int_equal(d.fit, BTF_RF_PTM);
    assert_int_equal(d.lobes, 2);
    assert_int_equal(d.iterations, 40);
    assert_true(d.memory == (size_t)256 << 20);
    btf_rf_opts z;
    memset(&z, 0, sizeof z);
    btf_rf_model a, b;
    btf_error e = {0};
    TU_OK(btf_rf_fit(ds, &z, &a, &e), &e);
    TU_OK(btf_rf_fit(ds, NULL, &b, &e), &e);
    size_t n = (size_t)ptm.fields * ptm.slots * ptm.width * ptm.height;
    assert_memory_equal(a.codes, ptm.codes, n * sizeof(uint16_t));
    assert_memory_equal(b.codes, ptm.codes, n * sizeof(uint16_t));
    btf_rf_model_free(&a);
    btf_rf_model_free(&b);
    /* invalid options are BTF_E_ARG, and the output is left empty */
    z.lobes = BTF_RF_MAX_LOBES + 1;
    assert_int_equal(btf_rf_fit(ds, &z, &a, &e), BTF_E_ARG);
    assert_null(a.codes);
    z.lobes = 0, z.fit = 3;
    assert_int_equal(btf_rf_fit(ds, &z, &a, &e), BTF_E_ARG);
}

static void flat_render_at_a_measured_view_is_the_field(void **state)
{
    (void)state;
    const btf_rf_model *ms[3] = {&ptm, &lobes, &laf};
    btf_error e = {0};
    for (int k = 0; k < 3; k++) {
        const btf_rf_model *m = ms[k];
        int v = 23, l = 47;
        btf_dir view = m->views.dirs[v], light = m->lights.dirs[l];
        btf_image img;
        TU_OK(btf__rf_render_flat(m, view, light, 0, 0, 2, &img, &e), &e);
        assert_int_equal(img.width, 16);
        double lv[3], vv[3];
        btf_dir_to_vec(light, lv);
        btf_dir_to_vec(view, vv);
        for (int y = 0; y < 16; y++)
            for (int x = 0; x < 16; x++) {
                float p[BTF_RF_MAX_SLOTS], rgb[3];
                int field = m->fit == BTF_RF_LAFORTUNE ? 0 : v;
                rf_texel_params(m, field, (size_t)y * 16 + x, p);
                double lum = rf_lum_eval(m->fit, m->lobes, p, lv, vv);
                btf__rf_eval_field(m, field, view, light, x, y, rgb);
                for (int c = 0; c < 3; c++) {
                    float want = (float)(lum * p[m->params + c]);
                    assert_true(img.data[(y * 16 + x) * 3 + c] == want);
                    assert_true(rgb[c] == want);
                }
            }
        /* a larger frame repeats the texels; between views it blends them */
        btf_image big, mid;
        TU_OK(btf__rf_render_flat(m, view, light, 40, 20, 1, &big, &e), &e);
        assert_true(big.data[(3 * 40 + 37) * 3 + 1] == img.data[(3 * 16 + 5) * 3 + 1]);
        TU_OK(btf__rf_render_flat(m, (btf_dir){37.5, 100}, light, 0, 0, 2, &mid, &e), &e);
        for (size_t i = 0; i < (size_t)16 * 16 * 3; i++)
            assert_true(isfinite(mid.data[i]) && mid.data[i] >= 0.0f);
        btf_image_free(&img);
        btf_image_free(&big);
        btf_image_free(&mid);
    }
}

/* ---------------------------------------------------------------- scenes */

/* A plane (normal +z, side n world units, one texel per unit) seen head-on
 * by a camera 10^4 units away whose frame of n x n pixels spans it exactly:
 * pixel (x, y) is texel (x, y), the tangent frame the world's axes and the
 * view within 0.05 degree of the normal. One light. */
static void head_on_scene(btf_scene *sc, int n, btf_light light)
{
    memset(sc, 0, sizeof *sc);
    double d = 1e4;
    sc->camera = (btf_camera){{0, 0, d}, {0, 0, 0}, {0, 1, 0},
                              2.0 * atan(0.5 * n / d) * 180.0 / M_PI};
    sc->n_lights = 1;
    sc->lights = calloc(1, sizeof *sc->lights);
    sc->lights[0] = light;
    sc->n_objects = 1;
    sc->objects = calloc(1, sizeof *sc->objects);
    sc->objects[0] = (btf_object){.kind = BTF_OBJECT_PLANE, .center = {0, 0, 0},
                                  .axis = {0, 0, 1}, .size = n, .texture_scale = 1};
    sc->background[0] = 0.25f;
}

/* A copy of m whose every field is field f: any view blends to field f. */
static void uniform_fields(const btf_rf_model *m, int f, btf_rf_model *out)
{
    *out = *m;
    size_t texels = (size_t)m->width * m->height * m->slots;
    out->lo = malloc((size_t)m->fields * m->slots * sizeof(float));
    out->hi = malloc((size_t)m->fields * m->slots * sizeof(float));
    out->codes = malloc((size_t)m->fields * texels * sizeof(uint16_t));
    assert_non_null(out->codes);
    memset(&out->views, 0, sizeof out->views);
    memset(&out->lights, 0, sizeof out->lights);
    btf_error e = {0};
    TU_OK(btf_dirset_from_list(&out->views, m->views.dirs, m->views.count, &e), &e);
    TU_OK(btf_dirset_from_list(&out->lights, m->lights.dirs, m->lights.count, &e), &e);
    for (int k = 0; k < m->fields; k++) {
        memcpy(out->lo + (size_t)k * m->slots, m->lo + (size_t)f * m->slots,
               m->slots * sizeof(float));
        memcpy(out->hi + (size_t)k * m->slots, m->hi + (size_t)f * m->slots,
               m->slots * sizeof(float));
        memcpy(out->codes + k * texels, m->codes + f * texels, texels * sizeof(uint16_t));
    }
}

static int close_to(float a, float b, double rel)
{
    return isfinite(a) && fabs((double)a - b) <= rel * fabs((double)b) + 1e-7;
}

/* btf__rf_render_scene on a plane seen head-on under a light at a measured
 * direction is the flat render at the pole (texel for texel), for a
 * directional and a point light; a sphere renders finite, non-negative
 * pixels whatever the thread count; bad input is an error. */
static void scene_render_is_the_flat_render_head_on(void **state)
{
    (void)state;
    btf_error e = {0};
    const int n = 17; /* odd: the centre pixel looks straight down the normal */
    const btf_rf_model *ms[3] = {&ptm, &lobes, &laf};
    for (int k = 0; k < 3; k++) {
        btf_dir light = ms[k]->lights.dirs[47];
        btf_light sun = {.kind = BTF_LIGHT_DIRECTIONAL, .rgb = {1, 1, 1}};
        btf_dir_to_vec(light, sun.direction);
        btf_rf_model u;
        uniform_fields(ms[k], 0, &u);
        const btf_rf_model *both[2] = {ms[k], &u};
        for (int which = 0; which < 2; which++) {
            const btf_rf_model *m = both[which];
            btf_scene sc;
            head_on_scene(&sc, n, sun);
            btf_image flat, img;
            btf_render_info info;
            TU_OK(btf__rf_render_flat(m, (btf_dir){0, 0}, light, n, n, 1, &flat, &e), &e);
            TU_OK(btf__rf_render_scene(m, &sc, n, n, 2, &img, &info, &e), &e);
            assert_int_equal(img.width, n);
            assert_int_equal(img.height, n);
            assert_true(info.trace_s >= 0 && info.shade_s >= 0);
            /* the centre pixel: the pole itself (every model); elsewhere the
             * view is off the pole by < 0.05 degree, which only a model whose
             * fields are all one (u; not Lafortune's view-dependent lobes)
             * ignores */
            int all = which == 1 && m->fit != BTF_RF_LAFORTUNE;
            int nonzero = 0;
            for (int y = 0; y < n; y++)
                for (int x = 0; x < n; x++) {
                    if (!all && !(x == n / 2 && y == n / 2))
                        continue;
                    for (int c = 0; c < 3; c++) {
                        size_t i = ((size_t)y * n + x) * 3 + c;
                        assert_true(close_to(img.data[i], flat.data[i], 1e-5));
                        nonzero += flat.data[i] > 0.0f;
                    }
                }
            assert_true(nonzero > 0);
            /* a point light far along the same direction, its intensity
             * the squared distance: the centre pixel again */
            btf_image pt;
            btf_light *l = &sc.lights[0];
            l->kind = BTF_LIGHT_POINT;
            for (int c = 0; c < 3; c++)
                l->position[c] = 1000.0 * l->direction[c], l->rgb[c] = 1e6f;
            TU_OK(btf__rf_render_scene(m, &sc, n, n, 1, &pt, NULL, &e), &e);
            size_t ci = ((size_t)(n / 2) * n + n / 2) * 3;
            for (int c = 0; c < 3; c++)
                assert_true(close_to(pt.data[ci + c], flat.data[ci + c], 1e-5));
            btf_image_free(&pt);
            btf_image_free(&flat);
            btf_image_free(&img);
            btf_scene_free(&sc);
        }
        btf_rf_model_free(&u);
    }
    /* a sphere: finite, non-negative, lit somewhere, the background around
     * it, the same for any thread count */
    btf_scene sp;
    TU_OK(btf_scene_sphere((btf_dir){30, 45}, 16, &sp, &e), &e);
    sp.background[0] = 0.5f, sp.background[1] = 0.25f, sp.background[2] = 0.125f;
    for (int k = 0; k < 3; k++) {
        btf_image a, b;
        TU_OK(btf__rf_render_scene(ms[k], &sp, 48, 40, 1, &a, NULL, &e), &e);
        TU_OK(btf__rf_render_scene(ms[k], &sp, 48, 40, 2, &b, NULL, &e), &e);
        assert_memory_equal(a.data, b.data, (size_t)48 * 40 * 3 * sizeof(float));
        int lit = 0;
        for (size_t i = 0; i < (size_t)48 * 40 * 3; i++) {
            assert_true(isfinite(a.data[i]) && a.data[i] >= 0.0f);
            lit += a.data[i] > 0.0f;
        }
        assert_true(lit > 0);
        assert_true(a.data[0] == 0.5f && a.data[1] == 0.25f && a.data[2] == 0.125f);
        size_t ci = ((size_t)20 * 48 + 24) * 3;
        assert_true(a.data[ci] + a.data[ci + 1] + a.data[ci + 2] > 0.0f);
        btf_image_free(&a);
        btf_image_free(&b);
    }
    /* bad input: errors, the output left empty */
    btf_image img;
    assert_int_equal(btf__rf_render_scene(NULL, &sp, 8, 8, 1, &img, NULL, &e), BTF_E_ARG);
    assert_null(img.data);
    assert_int_equal(btf__rf_render_scene(&ptm, NULL, 8, 8, 1, &img, NULL, &e), BTF_E_ARG);
    assert_int_equal(btf__rf_render_scene(&ptm, &sp, -1, 8, 1, &img, NULL, &e), BTF_E_ARG);
    assert_int_equal(btf__rf_render_scene(&ptm, &sp, 8, BTF_RENDER_MAX_SIDE + 1, 1, &img, NULL,
                                          &e), BTF_E_ARG);
    assert_int_equal(btf__rf_render_scene(&ptm, &sp, 8, 8, 1, NULL, NULL, &e), BTF_E_ARG);
    btf_rf_model empty;
    memset(&empty, 0, sizeof empty);
    assert_int_equal(btf__rf_render_scene(&empty, &sp, 8, 8, 1, &img, NULL, &e), BTF_E_ARG);
    sp.objects[0].radius = 0.0;
    assert_int_not_equal(btf__rf_render_scene(&ptm, &sp, 8, 8, 1, &img, NULL, &e), BTF_OK);
    assert_null(img.data);
    btf_scene_free(&sp);
}

/* ---------------------------------------------------------------- files */

static void assert_same_model(const btf_rf_model *a, const btf_rf_model *b)
{
    assert_int_equal(a->fit, b->fit);
    assert_int_equal(a->lobes, b->lobes);
    assert_int_equal(a->width, b->width);
    assert_int_equal(a->height, b->height);
    assert_int_equal(a->fields, b->fields);
    assert_int_equal(a->slots, b->slots);
    assert_int_equal(a->views.count, b->views.count);
    assert_string_equal(a->views.name, b->views.name);
    assert_memory_equal(a->views.dirs, b->views.dirs, a->views.count * sizeof(btf_dir));
    assert_memory_equal(a->lights.dirs, b->lights.dirs, a->lights.count * sizeof(btf_dir));
    size_t planes = (size_t)a->fields * a->slots;
    assert_memory_equal(a->lo, b->lo, planes * sizeof(float));
    assert_memory_equal(a->hi, b->hi, planes * sizeof(float));
    assert_memory_equal(a->codes, b->codes,
                        planes * a->width * a->height * sizeof(uint16_t));
}

static void file_round_trip(void **state)
{
    (void)state;
    const btf_rf_model *ms[3] = {&ptm, &lobes, &laf};
    btf_error e = {0};
    for (int k = 0; k < 3; k++) {
        unsigned char *d1, *d2;
        size_t n1, n2;
        TU_OK(btf_rf_encode(ms[k], &d1, &n1, &e), &e);
        assert_true(btf__rf_sniff(d1, n1));
        btf_rf_model back;
        TU_OK(btf_rf_decode(d1, n1, "m.rf", &back, &e), &e);
        assert_same_model(ms[k], &back);
        TU_OK(btf_rf_encode(&back, &d2, &n2, &e), &e);
        assert_int_equal(n1, n2);
        assert_memory_equal(d1, d2, n1);
        const char *path = tu_fmt("%s/m%d.btfcar", tu_dir, k);
        TU_OK(btf_rf_write(path, ms[k], &e), &e);
        btf_rf_model_free(&back);
        TU_OK(btf__rf_read(path, &back, &e), &e);
        assert_same_model(ms[k], &back);
        btf_rf_model_free(&back);
        free(d1);
        free(d2);
    }
}

/* btf__rf_report_write: the summary's numbers are the model file's bytes,
 * the raw BTF and btf__rf_error's; a sweep, a model of another dataset and
 * missing arguments are errors that leave no folder. */
static void rf_report(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_report_opts o = btf_report_defaults();
    o.quality.views = 2, o.quality.lights = 3;
    o.sphere_size = 32, o.worst = 2, o.threads = 2;
    btf_report_summary sum;
    char d[4096];
    snprintf(d, sizeof d, "%s/rf-report", tu_dir);
    TU_OK(btf__rf_report_write(ds, &lobes, d, &o, &sum, &e), &e);
    unsigned char *data;
    size_t size;
    TU_OK(btf_rf_encode(&lobes, &data, &size, &e), &e);
    free(data);
    assert_int_equal(sum.model_bytes, size);
    assert_int_equal(sum.raw_bytes, 81ULL * 81 * 16 * 16 * 3);
    assert_true(fabs(sum.ratio - (double)sum.raw_bytes / size) < 1e-9 * sum.ratio);
    assert_int_equal(sum.pairs, 6);
    double mae, meany;
    TU_OK(btf__rf_error(ds, &lobes, 2, &mae, &meany, &e), &e);
    assert_true(sum.mean_abs_error == mae && sum.mean_luminance == meany);
    assert_true(isfinite(sum.mean_combined) && sum.worst_combined >= sum.mean_combined);
    assert_int_equal(tu_count_files(d), 6 + 4); /* pairs, index, json, sphere, heat map */
    o.sweep = 1;
    snprintf(d, sizeof d, "%s/rf-report-2", tu_dir);
    assert_int_equal(btf__rf_report_write(ds, &lobes, d, &o, &sum, &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, "sweep"));
    o.sweep = 0;
    btf_rf_model tiny;
    tu_rf_tiny_model(&tiny, 1, 2);
    assert_int_equal(btf__rf_report_write(ds, &tiny, d, &o, &sum, &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, "does not describe"));
    btf_rf_model_free(&tiny);
    assert_int_equal(btf__rf_report_write(NULL, &lobes, d, &o, &sum, &e), BTF_E_ARG);
    assert_int_equal(btf__rf_report_write(ds, NULL, d, &o, &sum, &e), BTF_E_ARG);
    assert_int_equal(access(d, F_OK), -1);
}

static void expect_format_error(const unsigned char *d, size_t n, const char *what)
{
    btf_rf_model m;
    btf_error e = {0};
    tu_rf_expect_format_error(d, n, what, &m, &e);
}

static void corrupt_files_are_errors(void **state)
{
    (void)state;
    btf_rf_model m;
    tu_rf_tiny_model(&m, 1, 2);
    btf_error e = {0};
    unsigned char *d;
    size_t n;
    TU_OK(btf_rf_encode(&m, &d, &n, &e), &e);
    /* every truncation, every single flipped bit of the first bytes and the CRC */
    tu_rf_expect_damage_fails(d, n, expect_format_error);
    /* text-mode damage and a newer major version */
    unsigned char *t = malloc(n + 1);
    memcpy(t, d, 7);
    t[7] = '\n';
    memcpy(t + 8, d + 9, n - 9);
    expect_format_error(t, n - 1, "text mode");
    /* valid CRC, wrong content: the payload rewrapped after changes */
    unsigned char *payload = malloc(1 << 16);
    size_t plen = tu_rf_payload(d, payload, 1 << 16);
    unsigned char *p2 = malloc(plen);
    size_t sz;
    size_t rfhd = tu_rf_section(payload, plen, "RFHD");
    size_t rfqr = tu_rf_section(payload, plen, "RFQR");
    assert_true(rfhd && rfqr);
    unsigned char *w = tu_rf_rewrap(payload, plen, 1, &sz); /* unchanged: still valid */
    btf_rf_model ok;
    TU_OK(btf_rf_decode(w, sz, "ok", &ok, &e), &e);
    assert_same_model(&m, &ok);
    btf_rf_model_free(&ok);
    free(w);
    struct { size_t off; unsigned char val; const char *what; } bad[] = {
        {rfhd + 0, 7, "fit 7"},          {rfhd + 1, 2, "ptm with lobes"},
        {rfhd + 2, 9, "params"},         {rfhd + 14, 5, "fields"},
        {rfhd + 6, 0, "width 0"},        {rfqr + 3, 0x7f, "lo NaN or huge"},
        {rfqr + 7, 0xff, "hi NaN"},      {rfqr + 3, 0x4f, "lo above hi"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        memcpy(p2, payload, plen);
        p2[bad[i].off] = bad[i].val;
        if (bad[i].off == rfqr + 3)
            p2[rfqr + 2] = 0xc0; /* 0x7fc0....: NaN; 0x4fc0....: 6.4e9 > hi */
        w = tu_rf_rewrap(p2, plen, 1, &sz);
        expect_format_error(w, sz, bad[i].what);
        free(w);
    }
    /* a section missing; a section twice */
    memcpy(p2, payload, plen);
    memcpy(p2 + rfhd - 8, "XXXX", 4);
    w = tu_rf_rewrap(p2, plen, 1, &sz);
    expect_format_error(w, sz, "no RFHD");
    free(w);
    memcpy(p2, payload, plen);
    memcpy(p2 + rfqr - 8, "RFHD", 4);
    w = tu_rf_rewrap(p2, plen, 1, &sz);
    expect_format_error(w, sz, "RFHD twice");
    free(w);
    /* The CAR reader refuses an RF file and the RF reader a CAR file, by name. */
    const char *rfpath = tu_fmt("%s/tiny.btfcar", tu_dir);
    tu_write_file(rfpath, d, n);
    btf_model cm;
    assert_int_not_equal(btf_model_read(rfpath, &cm, &e), BTF_OK);
    assert_non_null(strstr(e.msg, "tiny.btfcar"));
    /* The encoder refuses what the decoder would */
    m.hi[3] = -1.0f;
    unsigned char *refused = NULL;
    assert_int_equal(btf_rf_encode(&m, &refused, &sz, &e), BTF_E_DATA);
    free(refused);
    free(payload);
    free(p2);
    free(t);
    free(d);
    btf_rf_model_free(&m);
}

/* ------------------------------------------------------------- commands */

static void command_line(void **state)
{
    (void)state;
    const char *cli = tu_cli();
    char *errtext = NULL;
    const char *model = tu_fmt("%s/cli-rf.btfcar", tu_dir);
    char m[4096];
    snprintf(m, sizeof m, "%s", model);
    assert_int_equal(tu_run(tu_fmt("%s analyse -q %s --family rf --fit lobes --lobes 1 "
                                   "--threads 2 -o %s", cli, dataset_path, m), NULL), 0);
    btf_rf_model back;
    btf_error e = {0};
    TU_OK(btf__rf_read(m, &back, &e), &e);
    assert_int_equal(back.fit, BTF_RF_LOBES);
    assert_int_equal(back.lobes, 1);
    btf_rf_model_free(&back);
    int status;
    char *out = tu_capture(tu_fmt("%s info %s", cli, m), &status);
    assert_int_equal(status, 0);
    assert_non_null(strstr(out, "reflectance-field model"));
    assert_non_null(strstr(out, "lobes: 1 non-linear lobe"));
    free(out);
    out = tu_capture(tu_fmt("%s info --json %s", cli, m), &status);
    assert_int_equal(status, 0);
    assert_non_null(strstr(out, "\"format\": \"btfcar-rf-model\""));
    free(out);
    const char *png = tu_fmt("%s/rf.png", tu_dir);
    char p[4096];
    snprintf(p, sizeof p, "%s", png);
    assert_int_equal(tu_run(tu_fmt("%s render -q %s --view 30,60 --light 45,0 --size 32x24 "
                                   "--beside %s -o %s", cli, m, dataset_path, p), NULL), 0);
    btf_image img;
    TU_OK(btf_image_read(p, NULL, &img, &e), &e);
    assert_int_equal(img.width, 16 + 32);
    assert_int_equal(img.height, 24);
    btf_image_free(&img);
    /* usage errors: exit status 2 */
    /* a scene: the objects under its lights */
    const char *scene = tu_fmt("%s/rf-scene.json", tu_dir);
    char sp[4096];
    snprintf(sp, sizeof sp, "%s", scene);
    const char *json = "{\"camera\": {\"position\": [0, 0, 4], \"target\": [0, 0, 0], "
                       "\"up\": [0, 1, 0], \"fov\": 40}, \"lights\": [{\"type\": "
                       "\"directional\", \"direction\": [1, 1, 1], \"intensity\": 1}], "
                       "\"objects\": [{\"type\": \"sphere\", \"center\": [0, 0, 0], "
                       "\"radius\": 1, \"texture_scale\": 16}]}";
    tu_write_file(sp, json, strlen(json));
    out = tu_capture(tu_fmt("%s render %s --scene %s --size 40x30 --threads 2 -o %s", cli, m,
                            sp, p), &status);
    assert_int_equal(status, 0);
    assert_non_null(strstr(out, "trace"));
    free(out);
    TU_OK(btf_image_read(p, NULL, &img, &e), &e);
    assert_int_equal(img.width, 40);
    assert_int_equal(img.height, 30);
    btf_image_free(&img);
    assert_int_equal(tu_run(tu_fmt("%s render %s --scene %s/missing.json -o %s", cli, m, tu_dir,
                                   p), NULL), 1);
    /* the CAR model's texture options do not apply: usage errors, one
     * line naming the option, no output */
    unlink(p);
    assert_int_equal(tu_run(tu_fmt("%s render %s --scene %s --texture-size 64 -o %s", cli, m,
                                   sp, p), &errtext), 2);
    assert_non_null(strstr(errtext, "--texture-size"));
    assert_true(strchr(errtext, '\n') == errtext + strlen(errtext) - 1);
    free(errtext);
    assert_int_equal(access(p, F_OK), -1);
    assert_int_equal(tu_run(tu_fmt("%s render %s --scene %s --view 0,0 --light 0,0 -o %s", cli,
                                   m, sp, p), NULL), 2);
    assert_int_equal(tu_run(tu_fmt("%s render %s --view 0,0 --light 0,0 --texture-size 8 -o %s",
                                   cli, m, p), NULL), 2);
    assert_int_equal(tu_run(tu_fmt("%s render %s --view 0,0 --light 0,0 --all-subspaces -o %s",
                                   cli, m, p), NULL), 2);
    assert_int_equal(access(p, F_OK), -1);
    assert_int_equal(tu_run(tu_fmt("%s analyse %s --fit ptm -o %s/x.btfcar", cli,
                                   dataset_path, tu_dir), NULL), 2);
    assert_int_equal(tu_run(tu_fmt("%s analyse %s --family rf --subspaces 3 -o %s/x.btfcar",
                                   cli, dataset_path, tu_dir), NULL), 2);
    assert_int_equal(tu_run(tu_fmt("%s analyse %s --family rf --fit cubic -o %s/x.btfcar",
                                   cli, dataset_path, tu_dir), NULL), 2);
    /* a damaged file: one line naming it, exit 1, no crash */
    FILE *f = fopen(m, "r+b");
    assert_non_null(f);
    fseek(f, 40, SEEK_SET);
    fputc(0x55, f);
    fclose(f);
    assert_int_equal(tu_run(tu_fmt("%s info %s", cli, m), &errtext), 1);
    assert_non_null(strstr(errtext, m));
    assert_non_null(strstr(errtext, "CRC-32"));
    free(errtext);
    assert_int_equal(tu_run(tu_fmt("%s render %s --view 0,0 --light 0,0 -o %s", cli, m, p),
                            &errtext), 1);
    assert_non_null(strstr(errtext, m));
    free(errtext);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(ptm_recovers_known_coefficients),
        cmocka_unit_test(lm_recovers_a_known_lobe),
        cmocka_unit_test(extremes_give_finite_fits),
        cmocka_unit_test(shared_math_matches_libm),
        cmocka_unit_test(view_weights_are_bilinear),
        cmocka_unit_test(fits_are_finite_and_measured),
        cmocka_unit_test(fit_does_not_depend_on_threads),
        cmocka_unit_test(zero_null_and_defaults_agree),
        cmocka_unit_test(flat_render_at_a_measured_view_is_the_field),
        cmocka_unit_test(scene_render_is_the_flat_render_head_on),
        cmocka_unit_test(file_round_trip),
        cmocka_unit_test(corrupt_files_are_errors),
        cmocka_unit_test(rf_report),
        cmocka_unit_test(command_line),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
