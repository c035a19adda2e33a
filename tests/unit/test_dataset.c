/* test_dataset.c — layouts, detection, completeness and every bad input;
 * the manifest parser on buffers and files. */
#include "testutil.h"

#include "io/io.h"
#include "core/core.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* A small custom sampling: 3 views x 2 lights. */
static const int VIEWS[3][2] = {{0, 0}, {15, 0}, {15, 60}};
static const int LIGHTS[2][2] = {{0, 0}, {30, 90}};

static void make_image(btf_image *img, int w, int h, float v)
{
    btf_error e = {0};
    TU_OK(btf_image_alloc(img, w, h, 3, &e), &e);
    for (int i = 0; i < w * h * 3; i++)
        img->data[i] = v;
}

static const char *ubo_name(int idx, int l, int v)
{
    return tu_fmt("%05d tl%03d pl%03d tv%03d pv%03d.jpg", idx, LIGHTS[l][0], LIGHTS[l][1],
                  VIEWS[v][0], VIEWS[v][1]);
}

/* Writes the 6 images; skip = (v, l) pair not written, or -1. */
static char *make_ubo(int per_view_folders, int skip_v, int skip_l)
{
    char *dir = tu_tmpdir();
    btf_error e = {0};
    btf_image img;
    for (int v = 0; v < 3; v++) {
        const char *sub = dir;
        if (per_view_folders) {
            sub = tu_fmt("%s/tv%03d_pv%03d", dir, VIEWS[v][0], VIEWS[v][1]);
            mkdir(sub, 0777);
        }
        char subdir[4096];
        snprintf(subdir, sizeof subdir, "%s", sub);
        for (int l = 0; l < 2; l++) {
            if (v == skip_v && l == skip_l)
                continue;
            make_image(&img, 12, 10, 0.1f * (float)(1 + v + 3 * l));
            TU_OK(btf_image_write_jpeg(tu_fmt("%s/%s", subdir, ubo_name(l * 3 + v, l, v)), &img,
                                       95, &e),
                  &e);
            btf_image_free(&img);
        }
    }
    return dir;
}

static void check_small_set(const btf_dataset *ds, btf_layout layout)
{
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    assert_int_equal(in->layout, layout);
    assert_int_equal(in->n_views, 3);
    assert_int_equal(in->n_lights, 2);
    assert_int_equal(in->width, 12);
    assert_int_equal(in->height, 10);
    assert_string_equal(in->views->name, "custom");
    assert_true(in->bytes_on_disk > 0);
    /* Views are in ring order: (0,0), (15,0), (15,60). */
    for (int v = 0; v < 3; v++) {
        assert_true(in->views->dirs[v].theta == VIEWS[v][0]);
        assert_true(in->views->dirs[v].phi == VIEWS[v][1]);
    }
    /* Streaming: every pair once, view-major, the pixels of that pair. */
    btf_dataset_iter it;
    btf_dataset_iter_begin(&it, ds);
    btf_error e = {0};
    int count = 0, rc;
    while ((rc = btf_dataset_iter_next(&it, &e)) == 1) {
        const btf_sample *s = &it.sample;
        assert_int_equal(s->view, count / 2);
        assert_int_equal(s->light, count % 2);
        assert_true(s->light_dir.theta == LIGHTS[s->light][0]);
        float want = btf__srgb_to_linear(
            btf__linear_to_srgb(0.1f * (float)(1 + s->view + 3 * s->light)));
        assert_true(fabsf(s->image.data[0] - want) < 0.01f);
        assert_int_equal(s->image.channels, 3);
        count++;
    }
    assert_int_equal(rc, 0);
    assert_int_equal(count, 6);
    btf_dataset_iter_end(&it);
}

static void ubo_per_view_and_flat(void **state)
{
    (void)state;
    for (int per_view = 0; per_view <= 1; per_view++) {
        char *dir = make_ubo(per_view, -1, -1);
        /* Files that follow no layout are ignored. */
        tu_write_file(tu_fmt("%s/README.txt", dir), "notes", 5);
        btf_dataset *ds;
        btf_error e = {0};
        TU_OK(btf_dataset_open(dir, NULL, &ds, &e), &e);
        check_small_set(ds, BTF_LAYOUT_UBO2003);
        assert_non_null(strstr(btf_dataset_path(ds, 2, 1), "tl030 pl090 tv015 pv060.jpg"));
        assert_null(btf_dataset_path(ds, 3, 0));
        btf_dataset_close(ds);
        tu_rmtree(dir);
        free(dir);
    }
}

static char *make_utia(const char *ext)
{
    char *dir = tu_tmpdir();
    btf_error e = {0};
    btf_image img;
    for (int v = 0; v < 3; v++) {
        char sub[4096];
        snprintf(sub, sizeof sub, "%s/tv%03d_pv%03d", dir, VIEWS[v][0], VIEWS[v][1]);
        mkdir(sub, 0777);
        for (int l = 0; l < 2; l++) {
            make_image(&img, 12, 10, 0.1f * (float)(1 + v + 3 * l));
            const char *p = tu_fmt("%s/tl%03d_pl%03d_tv%03d_pv%03d.%s", sub, LIGHTS[l][0],
                                   LIGHTS[l][1], VIEWS[v][0], VIEWS[v][1], ext);
            if (!strcmp(ext, "png")) {
                TU_OK(btf_image_write_png(p, &img, &e), &e);
            } else {
                /* EXR holds the linear value; make it equal to what 8 bits give. */
                for (int i = 0; i < 12 * 10 * 3; i++)
                    img.data[i] = btf__srgb_to_linear(btf__linear_to_srgb(img.data[i]));
                TU_OK(btf_image_write_exr_opts(p, &img, &(btf_exr_opts){.half = 1}, NULL, &e), &e);
            }
            btf_image_free(&img);
        }
    }
    return dir;
}

static void utia_png_and_exr(void **state)
{
    (void)state;
    const char *exts[2] = {"png", "exr"};
    for (int k = 0; k < 2; k++) {
        char *dir = make_utia(exts[k]);
        btf_dataset *ds;
        btf_error e = {0};
        TU_OK(btf_dataset_open(dir, NULL, &ds, &e), &e);
        check_small_set(ds, BTF_LAYOUT_UTIA);
        assert_int_equal(btf_dataset_get_info(ds)->format, k ? BTF_FILE_EXR : BTF_FILE_PNG);
        btf_dataset_close(ds);
        tu_rmtree(dir);
        free(dir);
    }
}

static void manifest_layout(void **state)
{
    (void)state;
    char *dir = make_ubo(1, -1, -1);
    FILE *f = fopen(tu_fmt("%s/list.tsv", dir), "w");
    assert_non_null(f);
    /* Columns in another order than documented, a comment and a blank line. */
    fprintf(f, "theta_v\tphi_v\tpath\ttheta_l\tphi_l\n# comment\n\n");
    for (int v = 0; v < 3; v++)
        for (int l = 0; l < 2; l++)
            fprintf(f, "%d\t%d\ttv%03d_pv%03d/%s\t%d\t%d\n", VIEWS[v][0], VIEWS[v][1], VIEWS[v][0],
                    VIEWS[v][1], ubo_name(l * 3 + v, l, v), LIGHTS[l][0], LIGHTS[l][1]);
    fclose(f);
    btf_dataset *ds;
    btf_error e = {0};
    TU_OK(btf_dataset_open(tu_fmt("%s/list.tsv", dir), NULL, &ds, &e), &e);
    check_small_set(ds, BTF_LAYOUT_MANIFEST);
    btf_dataset_close(ds);

    /* A manifest without a required column, and one with a bad number. */
    const char *bad1 = "path\ttheta_l\tphi_l\ttheta_v\nx\t1\t2\t3\n";
    tu_write_file(tu_fmt("%s/bad1.tsv", dir), bad1, strlen(bad1));
    assert_int_equal(btf_dataset_open(tu_fmt("%s/bad1.tsv", dir), NULL, &ds, &e), BTF_E_FORMAT);
    assert_non_null(strstr(e.msg, "phi_v"));
    const char *bad2 = "path\ttheta_l\tphi_l\ttheta_v\tphi_v\nx.png\t1\tabc\t3\t4\n";
    tu_write_file(tu_fmt("%s/bad2.tsv", dir), bad2, strlen(bad2));
    assert_int_equal(btf_dataset_open(tu_fmt("%s/bad2.tsv", dir), NULL, &ds, &e), BTF_E_FORMAT);
    assert_non_null(strstr(e.msg, "bad2.tsv:2"));
    const char *bad3 = "path\ttheta_l\tphi_l\ttheta_v\tphi_v\nx.png\t1\t2\n";
    tu_write_file(tu_fmt("%s/bad3.tsv", dir), bad3, strlen(bad3));
    assert_int_equal(btf_dataset_open(tu_fmt("%s/bad3.tsv", dir), NULL, &ds, &e), BTF_E_FORMAT);
    tu_rmtree(dir);
    free(dir);
}

static void missing_pair(void **state)
{
    (void)state;
    char *dir = make_ubo(1, 2, 0); /* no (view 2, light 0) */
    btf_dataset *ds = (btf_dataset *)1;
    btf_error e = {0};
    assert_int_equal(btf_dataset_open(dir, NULL, &ds, &e), BTF_E_DATA);
    assert_null(ds);
    assert_non_null(strstr(e.msg, "tv015_pv060/00002 tl000 pl000 tv015 pv060.jpg"));
    assert_non_null(strstr(e.msg, "missing"));
    tu_rmtree(dir);
    free(dir);
    /* The expected path follows the dataset: a flat folder has no view
     * folder, a UTIA dataset of EXR files names an .exr. */
    dir = make_ubo(0, 2, 0);
    assert_int_equal(btf_dataset_open(dir, NULL, &ds, &e), BTF_E_DATA);
    assert_non_null(strstr(e.msg, tu_fmt("%s/00002 tl000 pl000 tv015 pv060.jpg", dir)));
    tu_rmtree(dir);
    free(dir);
    dir = make_utia("exr");
    char victim[4096];
    snprintf(victim, sizeof victim, "%s/tv015_pv060/tl030_pl090_tv015_pv060.exr", dir);
    remove(victim);
    assert_int_equal(btf_dataset_open(dir, NULL, &ds, &e), BTF_E_DATA);
    assert_non_null(strstr(e.msg, victim));
    tu_rmtree(dir);
    free(dir);
}

static void duplicate_pair(void **state)
{
    (void)state;
    char *dir = make_ubo(1, -1, -1);
    /* The same pair under another running index. */
    btf_image img;
    btf_error e = {0};
    make_image(&img, 12, 10, 0.5f);
    const char *dup = tu_fmt("%s/tv015_pv000/00099 tl030 pl090 tv015 pv000.jpg", dir);
    TU_OK(btf_image_write_jpeg(dup, &img, 90, &e), &e);
    btf_image_free(&img);
    btf_dataset *ds;
    assert_int_equal(btf_dataset_open(dir, NULL, &ds, &e), BTF_E_DATA);
    assert_non_null(strstr(e.msg, "tl030 pl090 tv015 pv000.jpg"));
    assert_non_null(strstr(e.msg, "second file"));
    tu_rmtree(dir);
    free(dir);
}

static void mixed_sizes(void **state)
{
    (void)state;
    char *dir = make_ubo(1, -1, -1);
    btf_image img;
    btf_error e = {0};
    make_image(&img, 13, 10, 0.5f);
    const char *odd = tu_fmt("%s/tv015_pv060/%s", dir, ubo_name(5, 1, 2));
    TU_OK(btf_image_write_jpeg(odd, &img, 90, &e), &e);
    btf_image_free(&img);
    btf_dataset *ds;
    assert_int_equal(btf_dataset_open(dir, NULL, &ds, &e), BTF_E_DATA);
    assert_non_null(strstr(e.msg, odd));
    assert_non_null(strstr(e.msg, "13x10"));
    tu_rmtree(dir);
    free(dir);
}

static void truncated_and_unreadable(void **state)
{
    (void)state;
    char *dir = make_ubo(1, -1, -1);
    const char *victim = tu_fmt("%s/tv015_pv000/%s", dir, ubo_name(4, 1, 1));
    FILE *f = fopen(victim, "r+b");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fclose(f);
    assert_int_equal(truncate(victim, n / 2), 0);
    btf_dataset *ds;
    btf_error e = {0};
    assert_int_equal(btf_dataset_open(dir, NULL, &ds, &e), BTF_E_FORMAT);
    assert_non_null(strstr(e.msg, victim));
    assert_non_null(strstr(e.msg, "truncated"));
    /* Replaced by bytes that are no image at all. */
    tu_write_file(victim, "GIF89a......", 12);
    assert_int_equal(btf_dataset_open(dir, NULL, &ds, &e), BTF_E_FORMAT);
    assert_non_null(strstr(e.msg, victim));
    /* With skip_verify the open succeeds; reading that image fails, naming it,
     * and the iterator goes on with the next image. */
    btf_dataset_opts o = {.skip_verify = 1};
    TU_OK(btf_dataset_open(dir, &o, &ds, &e), &e);
    btf_dataset_iter it;
    btf_dataset_iter_begin(&it, ds);
    int ok = 0, bad = 0, rc;
    while ((rc = btf_dataset_iter_next(&it, &e)) != 0) {
        if (rc == 1)
            ok++;
        else {
            bad++;
            assert_non_null(strstr(e.msg, victim));
        }
    }
    assert_int_equal(ok, 5);
    assert_int_equal(bad, 1);
    btf_dataset_iter_end(&it);
    assert_int_equal(btf_dataset_verify_pixels(ds, NULL, NULL, &e), BTF_E_FORMAT);
    btf_dataset_close(ds);
    tu_rmtree(dir);
    free(dir);
}

static float nan_at_5_3(int c, int x, int y)
{
    return (c == 1 && x == 5 && y == 3) ? NAN : 0.25f;
}

static void nan_in_exr(void **state)
{
    (void)state;
    char *dir = make_utia("exr");
    /* Replace one image by a float EXR holding a NaN, written with the core
     * API (the library's writer refuses NaN). */
    char victim[4096];
    snprintf(victim, sizeof victim, "%s/tv015_pv060/tl030_pl090_tv015_pv060.exr", dir);
    tu_exr_spec spec = {.storage = EXR_STORAGE_SCANLINE, .compression = EXR_COMPRESSION_ZIP,
                        .width = 12, .height = 10, .nch = 3, .names = {"B", "G", "R"},
                        .types = {EXR_PIXEL_FLOAT, EXR_PIXEL_FLOAT, EXR_PIXEL_FLOAT}};
    tu_exr_write_raw(victim, &spec, nan_at_5_3);
    btf_dataset *ds;
    btf_error e = {0};
    /* The structure is sound, so opening succeeds; decoding finds the NaN. */
    TU_OK(btf_dataset_open(dir, NULL, &ds, &e), &e);
    assert_int_equal(btf_dataset_verify_pixels(ds, NULL, NULL, &e), BTF_E_DATA);
    assert_non_null(strstr(e.msg, victim));
    assert_non_null(strstr(e.msg, "NaN or Inf at pixel (5, 3)"));
    btf_dataset_close(ds);
    tu_rmtree(dir);
    free(dir);
}

static void unknown_and_mixed_layouts(void **state)
{
    (void)state;
    btf_dataset *ds;
    btf_error e = {0};
    char *dir = tu_tmpdir();
    assert_int_equal(btf_dataset_open(dir, NULL, &ds, &e), BTF_E_FORMAT);
    assert_non_null(strstr(e.msg, "unknown layout"));
    tu_write_file(tu_fmt("%s/image1.jpg", dir), "x", 1);
    assert_int_equal(btf_dataset_open(dir, NULL, &ds, &e), BTF_E_FORMAT);
    assert_non_null(strstr(e.msg, dir));
    assert_int_equal(btf_dataset_open(tu_fmt("%s/nothing-here", dir), NULL, &ds, &e), BTF_E_IO);
    tu_rmtree(dir);
    free(dir);
    /* A UTIA file in a UBO2003 dataset. */
    dir = make_ubo(1, -1, -1);
    btf_image img;
    make_image(&img, 12, 10, 0.5f);
    TU_OK(btf_image_write_png(tu_fmt("%s/tv000_pv000/tl000_pl000_tv000_pv000.png", dir), &img, &e),
          &e);
    btf_image_free(&img);
    assert_int_equal(btf_dataset_open(dir, NULL, &ds, &e), BTF_E_DATA);
    assert_non_null(strstr(e.msg, "mixed layouts"));
    tu_rmtree(dir);
    free(dir);
    /* A file whose view differs from its folder's. */
    dir = make_ubo(1, -1, -1);
    make_image(&img, 12, 10, 0.5f);
    TU_OK(btf_image_write_jpeg(tu_fmt("%s/tv000_pv000/00077 tl000 pl000 tv015 pv000.jpg", dir),
                               &img, 90, &e),
          &e);
    btf_image_free(&img);
    assert_int_equal(btf_dataset_open(dir, NULL, &ds, &e), BTF_E_DATA);
    assert_non_null(strstr(e.msg, "folder"));
    tu_rmtree(dir);
    free(dir);
}

/* The TSV parser on a buffer gives what the file reader gives, and its
 * messages carry the buffer's name. */
static void tsv_from_memory(void **state)
{
    (void)state;
    btf_error e = {0};
    const char text[] = "# a comment\npath\ttheta_l\tphi_l\r\n\n a b.png \t 10\t20\r\n"
                        "c.exr\t-1e3\tx\n";
    char *dir = tu_tmpdir();
    const char *p = tu_fmt("%s/mem.tsv", dir);
    tu_write_file(p, text, sizeof text - 1);
    btf_tsv a, b;
    TU_OK(btf__tsv_read(p, &a, &e), &e);
    TU_OK(btf__tsv_parse(text, sizeof text - 1, "buf", &b, &e), &e);
    assert_int_equal(a.ncols, 3);
    assert_int_equal(a.nrows, 2);
    assert_int_equal(b.ncols, a.ncols);
    assert_int_equal(b.nrows, a.nrows);
    for (int c = 0; c < a.ncols; c++)
        assert_string_equal(a.names[c], b.names[c]);
    for (int r = 0; r < a.nrows; r++) {
        assert_int_equal(a.line_no[r], b.line_no[r]);
        for (int c = 0; c < a.ncols; c++)
            assert_string_equal(btf__tsv_cell(&a, r, c), btf__tsv_cell(&b, r, c));
    }
    assert_string_equal(btf__tsv_cell(&b, 0, 0), "a b.png");
    assert_int_equal(b.line_no[1], 5);
    double v;
    assert_int_equal(btf__tsv_number(&b, "buf", 1, 2, &v, &e), BTF_E_FORMAT);
    assert_non_null(strstr(e.msg, "buf:5: phi_l 'x'"));
    btf__tsv_free(&a);
    btf__tsv_free(&b);
    tu_rmtree(dir);
    free(dir);
    /* The input is copied: the caller's buffer is left as it was. */
    char copy[sizeof text];
    memcpy(copy, text, sizeof text);
    TU_OK(btf__tsv_parse(copy, sizeof copy - 1, NULL, &b, &e), &e);
    assert_memory_equal(copy, text, sizeof text);
    btf__tsv_free(&b);

    assert_int_equal(btf__tsv_parse("a\tb\n1\n", 6, "short", &b, &e), BTF_E_FORMAT);
    assert_string_equal(e.msg, "short:2: 1 fields, the header names 2");
    assert_int_equal(btf__tsv_parse("a\0b", 3, "nul", &b, &e), BTF_E_FORMAT);
    assert_string_equal(e.msg, "nul: not a text file (contains NUL bytes)");
    assert_int_equal(btf__tsv_parse("", 0, NULL, &b, &e), BTF_E_FORMAT);
    assert_string_equal(e.msg, "manifest: empty manifest (no header line)");
    assert_int_equal(btf__tsv_parse(NULL, 0, "none", &b, &e), BTF_E_FORMAT);
    assert_null(b.text);
}

/* Manifest numbers are decimals: "0x1e" is not thirty, "inf" and "nan" are
 * not numbers; a subnormal such as 1e-320 (strtod's ERANGE) is a value. */
static void tsv_numbers_are_decimal(void **state)
{
    (void)state;
    btf_error e = {0};
    const char text[] = "v\n0x1e\n0X1E\ninf\nnan\n1e400\n 1\n1e-320\n-2.5e1\n+.5\n";
    btf_tsv t;
    TU_OK(btf__tsv_parse(text, sizeof text - 1, "n.tsv", &t, &e), &e);
    assert_int_equal(t.nrows, 9);
    double v;
    for (int r = 0; r < 5; r++) {
        assert_int_equal(btf__tsv_number(&t, "n.tsv", r, 0, &v, &e), BTF_E_FORMAT);
        assert_non_null(strstr(e.msg, tu_fmt("n.tsv:%d: v '", r + 2)));
        assert_non_null(strstr(e.msg, "not a finite decimal number"));
    }
    const double want[] = {1, 1e-320, -25, 0.5}; /* " 1": cells are trimmed */
    for (int r = 5; r < 9; r++) {
        TU_OK(btf__tsv_number(&t, "n.tsv", r, 0, &v, &e), &e);
        assert_true(v == want[r - 5]);
    }
    btf__tsv_free(&t);
}

/* A manifest saved with a UTF-8 byte order mark (Excel, Notepad) reads as
 * one without: the mark is not part of the first column's name. */
static void tsv_byte_order_mark(void **state)
{
    (void)state;
    btf_error e = {0};
    const char text[] = "\xEF\xBB\xBFpath\ttheta_l\nx.png\t1\n";
    btf_tsv t;
    TU_OK(btf__tsv_parse(text, sizeof text - 1, "bom.tsv", &t, &e), &e);
    assert_string_equal(t.names[0], "path");
    assert_int_equal(btf__tsv_column(&t, "path"), 0);
    assert_int_equal(t.line_no[0], 2);
    btf__tsv_free(&t);
    /* The whole dataset path: the BOM manifest opens as the plain one. */
    char *dir = make_ubo(1, -1, -1);
    FILE *f = fopen(tu_fmt("%s/bom.tsv", dir), "w");
    assert_non_null(f);
    fprintf(f, "\xEF\xBB\xBFpath\ttheta_l\tphi_l\ttheta_v\tphi_v\n");
    for (int v = 0; v < 3; v++)
        for (int l = 0; l < 2; l++)
            fprintf(f, "tv%03d_pv%03d/%s\t%d\t%d\t%d\t%d\n", VIEWS[v][0], VIEWS[v][1],
                    ubo_name(l * 3 + v, l, v), LIGHTS[l][0], LIGHTS[l][1], VIEWS[v][0],
                    VIEWS[v][1]);
    fclose(f);
    btf_dataset *ds;
    TU_OK(btf_dataset_open(tu_fmt("%s/bom.tsv", dir), NULL, &ds, &e), &e);
    check_small_set(ds, BTF_LAYOUT_MANIFEST);
    btf_dataset_close(ds);
    tu_rmtree(dir);
    free(dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(ubo_per_view_and_flat),
        cmocka_unit_test(utia_png_and_exr),
        cmocka_unit_test(manifest_layout),
        cmocka_unit_test(missing_pair),
        cmocka_unit_test(duplicate_pair),
        cmocka_unit_test(mixed_sizes),
        cmocka_unit_test(truncated_and_unreadable),
        cmocka_unit_test(nan_in_exr),
        cmocka_unit_test(unknown_and_mixed_layouts),
        cmocka_unit_test(tsv_from_memory),
        cmocka_unit_test(tsv_numbers_are_decimal),
        cmocka_unit_test(tsv_byte_order_mark),
    };
    return cmocka_run_group_tests_name("dataset", tests, NULL, NULL);
}
