/*
 * test_defaults.c — the btf_*_defaults() of the options structs: each
 * returns the documented defaults, and a call given the zeroed struct, NULL
 * or the defaults struct gives the same result (btf_analyse's is in
 * test_analyse.c, where a dataset is at hand).
 */
#include "testutil.h"
#include "car/car.h"
#include "core/core.h"
#include "segment/segment.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

static void documented_values(void **state)
{
    (void)state;
    btf_kmeans_opts k = btf_kmeans_defaults();
    assert_int_equal(k.restarts, 5);
    assert_int_equal(k.max_iter, 100);
    assert_true(k.seed == 0);

    btf_feature_opts f = btf_feature_defaults();
    assert_int_equal(f.bins, 32);
    assert_int_equal(f.threads, 0);
    assert_null(f.progress);

    btf_segment_opts s = btf_segment_defaults();
    assert_int_equal(s.subspaces, 0);
    assert_int_equal(s.max_subspaces, 20);
    assert_true(s.auto_threshold == 0.10);
    assert_true(s.split_gain == 0.12);
    assert_memory_equal(&s.features, &f, sizeof f);
    assert_memory_equal(&s.kmeans, &k, sizeof k);

    btf_car_fit_opts c = btf_car_fit_defaults();
    assert_int_equal(c.n_fixed, 0);
    assert_int_equal(c.max_neighbours, 24); /* the candidate family reaches BTF_CAR_MAX_NEIGHBOURS */
    assert_null(c.warn);
    assert_null(c.what);

    btf_fit_opts fit = btf_fit_defaults();
    assert_int_equal(fit.levels, 0);
    assert_int_equal(fit.max_auto_levels, 0);
    assert_memory_equal(&fit.car, &c, sizeof c);

    btf_generate_opts g = btf_generate_defaults();
    assert_int_equal(g.size, 128);
    assert_true(g.seed == 0);
    assert_int_equal(g.jpeg_quality, 95);
    assert_int_equal(g.threads, 0);

    /* Field by field: padding bytes of a returned struct are unspecified. */
    btf_dataset_opts d = btf_dataset_defaults();
    assert_int_equal(d.skip_verify, 0);
    assert_null(d.progress);
    assert_null(d.progress_user);
    assert_true(d.max_pixels == BTF_DEFAULT_MAX_PIXELS);
    btf_read_opts r = btf_read_defaults();
    assert_int_equal(r.channels, 0);
    assert_int_equal(r.linear_8bit, 0);
    assert_int_equal(r.srgb_16bit, 0);
    assert_true(r.max_pixels == BTF_DEFAULT_MAX_PIXELS);
    btf_exr_opts x = btf_exr_defaults();
    assert_int_equal(x.half, 0);
    assert_int_equal(x.compression, BTF_EXR_ZIP);
    assert_int_equal(x.background, 0);
    assert_null(x.times);

    btf_analyse_opts a = btf_analyse_defaults();
    assert_memory_equal(&a.segment, &s, sizeof s);
    assert_int_equal(a.fit.levels, fit.levels);
    assert_memory_equal(&a.fit.car, &fit.car, sizeof fit.car);
    assert_int_equal(a.no_range, 0);
    assert_int_equal(a.range_size, 0); /* the image's size: texel 1 */
    assert_int_equal(a.no_structure, 0);
    assert_null(a.report);
}

/* Points in a few loose clusters. */
static float *cluster_points(int n, int dim)
{
    float *p = malloc((size_t)n * dim * sizeof *p);
    assert_non_null(p);
    btf_rng r;
    btf__rng_seed(&r, 17);
    for (int i = 0; i < n; i++)
        for (int j = 0; j < dim; j++)
            p[(size_t)i * dim + j] = (float)((i % 4) * 0.3 + 0.1 * btf__rng_uniform(&r) + 0.01 * j);
    return p;
}

static void same_kmeans(const btf_kmeans_result *a, const btf_kmeans_result *b, int n, int dim)
{
    assert_int_equal(a->k, b->k);
    assert_true(a->distortion == b->distortion);
    assert_memory_equal(a->labels, b->labels, (size_t)n * sizeof(int));
    assert_memory_equal(a->centres, b->centres, (size_t)a->k * dim * sizeof(float));
}

static void kmeans_and_segmentation(void **state)
{
    (void)state;
    btf_error e = {0};
    int nv = 6, nl = 8, n = nv * nl, dim = 5;
    float *p = cluster_points(n, dim);
    btf_kmeans_opts kz = {0}, kd = btf_kmeans_defaults();
    btf_kmeans_result r0, r1, r2;
    TU_OK(btf__kmeans(p, n, dim, 3, NULL, &r0, &e), &e);
    TU_OK(btf__kmeans(p, n, dim, 3, &kz, &r1, &e), &e);
    TU_OK(btf__kmeans(p, n, dim, 3, &kd, &r2, &e), &e);
    same_kmeans(&r0, &r1, n, dim);
    same_kmeans(&r0, &r2, n, dim);
    btf__kmeans_free(&r0);
    btf__kmeans_free(&r1);
    btf__kmeans_free(&r2);

    btf_segment_opts sz = {0}, sd = btf_segment_defaults();
    btf_segmentation s0, s1, s2;
    TU_OK(btf__segment_features(p, nv, nl, dim, NULL, &s0, &e), &e);
    TU_OK(btf__segment_features(p, nv, nl, dim, &sz, &s1, &e), &e);
    TU_OK(btf__segment_features(p, nv, nl, dim, &sd, &s2, &e), &e);
    const btf_segmentation *s[3] = {&s0, &s1, &s2};
    for (int i = 1; i < 3; i++) {
        assert_int_equal(s[i]->k, s0.k);
        assert_int_equal(s[i]->max_k, s0.max_k);
        assert_true(s[i]->distortion == s0.distortion);
        assert_memory_equal(s[i]->index, s0.index, (size_t)n);
        assert_memory_equal(s[i]->rep_view, s0.rep_view, (size_t)s0.k * sizeof(int));
        assert_memory_equal(s[i]->rep_light, s0.rep_light, (size_t)s0.k * sizeof(int));
        assert_memory_equal(s[i]->distortion_by_k, s0.distortion_by_k,
                            (size_t)(s0.max_k + 1) * sizeof(double));
        assert_string_equal(s[i]->reason, s0.reason);
    }
    assert_int_equal(s0.max_k, 20);
    for (int i = 0; i < 3; i++)
        btf_segmentation_free((btf_segmentation *)s[i]);
    free(p);
}

/* The leading struct_size of every options struct (docs/api.md, "Options
 * structs"): the defaults set it; a caller's shorter struct (an older
 * header) is read only as far as its size says, the rest taken as zero,
 * that is as the defaults; a size larger than the library's, or too small
 * to hold the member, is refused with the function's name. */
static void struct_size_layouts(void **state)
{
    (void)state;
#define SIZE_SET(T, D) assert_int_equal(D().struct_size, sizeof(T))
    SIZE_SET(btf_feature_opts, btf_feature_defaults);
    SIZE_SET(btf_kmeans_opts, btf_kmeans_defaults);
    SIZE_SET(btf_segment_opts, btf_segment_defaults);
    SIZE_SET(btf_integrate_opts, btf_integrate_defaults);
    SIZE_SET(btf_photostereo_opts, btf_photostereo_defaults);
    SIZE_SET(btf_car_fit_opts, btf_car_fit_defaults);
    SIZE_SET(btf_fit_opts, btf_fit_defaults);
    SIZE_SET(btf_analyse_opts, btf_analyse_defaults);
    SIZE_SET(btf_rf_opts, btf_rf_defaults);
    SIZE_SET(btf_rf_sample_opts, btf_rf_sample_defaults);
    SIZE_SET(btf_dataset_opts, btf_dataset_defaults);
    SIZE_SET(btf_ubo2014_write_opts, btf_ubo2014_write_defaults);
    SIZE_SET(btf_generate_opts, btf_generate_defaults);
    SIZE_SET(btf_gpu_opts, btf_gpu_defaults);
    SIZE_SET(btf_read_opts, btf_read_defaults);
    SIZE_SET(btf_exr_opts, btf_exr_defaults);
    SIZE_SET(btf_render_opts, btf_render_defaults);
    SIZE_SET(btf_texture_distance_opts, btf_texture_distance_defaults);
    SIZE_SET(btf_pca_opts, btf_pca_defaults);
    SIZE_SET(btf_quality_opts, btf_quality_defaults);
    SIZE_SET(btf_sweep_opts, btf_sweep_defaults);
    SIZE_SET(btf_report_opts, btf_report_defaults);
    SIZE_SET(btf_synth_opts, btf_synth_defaults);
#undef SIZE_SET
    /* The nested structs of the defaults carry their own sizes. */
    assert_int_equal(btf_analyse_defaults().segment.kmeans.struct_size, sizeof(btf_kmeans_opts));
    assert_int_equal(btf_analyse_defaults().fit.car.struct_size, sizeof(btf_car_fit_opts));

    btf_error e = {0};
    int n = 48, dim = 5;
    float *p = cluster_points(n, dim);
    btf_kmeans_result r0, r1;
    TU_OK(btf__kmeans(p, n, dim, 3, NULL, &r0, &e), &e);
    /* An older caller's struct that ends before max_iter: the junk after it
     * is not read. */
    btf_kmeans_opts old;
    memset(&old, 0xA5, sizeof old);
    old.struct_size = offsetof(btf_kmeans_opts, max_iter);
    old.restarts = 0;
    TU_OK(btf__kmeans(p, n, dim, 3, &old, &r1, &e), &e);
    same_kmeans(&r0, &r1, n, dim);
    btf__kmeans_free(&r0);
    btf__kmeans_free(&r1);

    btf_kmeans_opts newer = btf_kmeans_defaults();
    newer.struct_size = sizeof newer + 8;
    assert_int_equal(btf__kmeans(p, n, dim, 3, &newer, &r1, &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, "btf_kmeans: options struct of"));
    newer.struct_size = 3;
    assert_int_equal(btf__kmeans(p, n, dim, 3, &newer, &r1, &e), BTF_E_ARG);
    btf_segment_opts seg = btf_segment_defaults();
    seg.struct_size = 1u << 20;
    btf_segmentation s;
    assert_int_equal(btf__segment_features(p, 6, 8, dim, &seg, &s, &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, "btf_segment"));
    free(p);
}

/* A small colour texture: a smoothed random field per channel. */
static void texture(btf_image *img, int w, int h)
{
    btf_error e = {0};
    TU_OK(btf_image_alloc(img, w, h, 3, &e), &e);
    btf_rng r;
    btf__rng_seed(&r, 3);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            for (int c = 0; c < 3; c++) {
                float *v = &img->data[((size_t)y * w + x) * 3 + c];
                float left = x ? v[-3] : 0.5f, up = y ? v[-(ptrdiff_t)w * 3] : 0.5f;
                *v = 0.4f * left + 0.4f * up + 0.2f * (float)btf__rng_uniform(&r);
            }
}

static void car_and_subspace_fits(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image img;
    texture(&img, 48, 40);
    double *band = malloc((size_t)48 * 40 * sizeof *band);
    assert_non_null(band);
    for (int i = 0; i < 48 * 40; i++)
        band[i] = img.data[3 * i + 1];
    btf_car_fit_opts cz = {0}, cd = btf_car_fit_defaults();
    btf_car_band b0, b1, b2;
    btf_car_fit_info i0, i1, i2;
    TU_OK(btf__car_fit(band, 48, 40, NULL, &b0, &i0, &e), &e);
    TU_OK(btf__car_fit(band, 48, 40, &cz, &b1, &i1, &e), &e);
    TU_OK(btf__car_fit(band, 48, 40, &cd, &b2, &i2, &e), &e);
    assert_memory_equal(&b0, &b1, sizeof b0);
    assert_memory_equal(&b0, &b2, sizeof b0);
    assert_memory_equal(&i0, &i1, sizeof i0);
    assert_memory_equal(&i0, &i2, sizeof i0);
    free(band);

    btf_fit_opts fz = {0}, fd = btf_fit_defaults();
    btf_model m[3];
    TU_OK(btf_texture_fit(&img, NULL, &m[0], &e), &e);
    TU_OK(btf_texture_fit(&img, &fz, &m[1], &e), &e);
    TU_OK(btf_texture_fit(&img, &fd, &m[2], &e), &e);
    unsigned char *bytes[3];
    size_t n[3];
    for (int i = 0; i < 3; i++)
        TU_OK(btf_model_encode(&m[i], &bytes[i], &n[i], &e), &e);
    for (int i = 1; i < 3; i++) {
        assert_int_equal(n[i], n[0]);
        assert_memory_equal(bytes[i], bytes[0], n[0]);
    }
    for (int i = 0; i < 3; i++) {
        free(bytes[i]);
        btf_model_free(&m[i]);
    }
    btf_image_free(&img);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(documented_values),
        cmocka_unit_test(kmeans_and_segmentation),
        cmocka_unit_test(car_and_subspace_fits),
        cmocka_unit_test(struct_size_layouts),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
