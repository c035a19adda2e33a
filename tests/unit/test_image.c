/* test_image.c — float images, sRGB, PNG/JPEG files and buffers, the
 * structural probe, the read options' defaults. */
#include "testutil.h"
#include "core/core.h"
#include "io/io.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>


static void gradient(btf_image *img, int w, int h, int c)
{
    btf_error e = {0};
    TU_OK(btf_image_alloc(img, w, h, c, &e), &e);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            for (int k = 0; k < c; k++)
                img->data[(y * w + x) * c + k] = (float)((x + 2 * y + 50 * k) % 64) / 63.0f;
}

static void srgb_transfer(void **state)
{
    (void)state;
    for (int i = 0; i <= 1000; i++) {
        float v = i / 1000.0f;
        assert_true(fabsf(btf__linear_to_srgb(btf__srgb_to_linear(v)) - v) < 1e-5f);
    }
    assert_true(btf__srgb_to_linear(0.0f) == 0.0f && btf__srgb_to_linear(1.0f) == 1.0f);
    assert_true(fabsf(btf__srgb_to_linear(0.5f) - 0.2140f) < 1e-3f);
    /* Out of range, NaN and Inf clamp instead of propagating. */
    assert_true(btf__srgb_to_linear(NAN) == 0.0f && btf__linear_to_srgb(NAN) == 0.0f);
    assert_true(btf__linear_to_srgb(INFINITY) == 1.0f && btf__linear_to_srgb(-3.0f) == 0.0f);
    assert_true(btf__linear_to_srgb(FLT_MAX) == 1.0f);
}

static void alloc_limits(void **state)
{
    (void)state;
    btf_image img;
    btf_error e = {0};
    TU_OK(btf_image_alloc(&img, 1, 1, 1, &e), &e);
    btf_image_free(&img);
    btf_image_free(&img); /* twice is harmless */
    assert_int_equal(btf_image_alloc(&img, 0, 5, 3, &e), BTF_E_ARG);
    assert_int_equal(btf_image_alloc(&img, 5, -1, 3, &e), BTF_E_ARG);
    assert_int_equal(btf_image_alloc(&img, 5, 5, 2, &e), BTF_E_ARG);
    assert_int_equal(btf_image_alloc(&img, 1 << 20, 1 << 20, 3, &e), BTF_E_ARG);
    assert_null(img.data);
}

static void png_round_trip(void **state)
{
    (void)state;
    btf_error e = {0};
    int sizes[][2] = {{1, 1}, {7, 13}, {1000, 3}, {64, 64}};
    for (int s = 0; s < 4; s++)
        for (int c = 1; c <= 3; c += 2) {
            btf_image a, b;
            gradient(&a, sizes[s][0], sizes[s][1], c);
            const char *p = tu_fmt("%s/rt.png", tu_dir);
            TU_OK(btf_image_write_png(p, &a, &e), &e);
            btf_image_header h;
            TU_OK(btf_image_probe(p, &h, &e), &e);
            assert_int_equal(h.format, BTF_FILE_PNG);
            assert_int_equal(h.width, sizes[s][0]);
            assert_int_equal(h.height, sizes[s][1]);
            assert_int_equal(h.channels, c);
            TU_OK(btf_image_read(p, NULL, &b, &e), &e);
            assert_int_equal(b.channels, c);
            size_t n = (size_t)a.width * a.height * c;
            for (size_t i = 0; i < n; i++) /* 8-bit sRGB quantisation */
                assert_true(fabsf(a.data[i] - b.data[i]) < 0.01f);
            btf_image_free(&a);
            btf_image_free(&b);
        }
}

static void jpeg_round_trip_and_channels(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image a, b, g;
    /* A smooth image: JPEG is lossy on edges by design. */
    TU_OK(btf_image_alloc(&a, 33, 17, 3, &e), &e);
    for (int i = 0; i < 33 * 17; i++)
        for (int k = 0; k < 3; k++)
            a.data[3 * i + k] = 0.1f + 0.6f * (float)(i % 33) / 32.0f + 0.1f * (float)k;
    const char *p = tu_fmt("%s/rt.jpg", tu_dir);
    TU_OK(btf_image_write_jpeg(p, &a, 100, &e), &e);
    assert_int_equal(btf__file_format_of(p), BTF_FILE_JPEG);
    TU_OK(btf_image_read(p, NULL, &b, &e), &e);
    double sum = 0;
    for (size_t i = 0; i < 33 * 17 * 3; i++)
        sum += fabsf(a.data[i] - b.data[i]);
    assert_true(sum / (33 * 17 * 3) < 0.03);
    btf_read_opts grey = {.channels = 1};
    TU_OK(btf_image_read(p, &grey, &g, &e), &e);
    assert_int_equal(g.channels, 1);
    float y0 = 0.2126f * b.data[0] + 0.7152f * b.data[1] + 0.0722f * b.data[2];
    assert_true(fabsf(g.data[0] - y0) < 1e-5f);
    /* 8-bit values read as linear when asked. */
    btf_read_opts lin = {.linear_8bit = 1};
    btf_image l;
    TU_OK(btf_image_read(p, &lin, &l, &e), &e);
    assert_true(fabsf(btf__srgb_to_linear(l.data[5]) - b.data[5]) < 1e-5f);
    assert_int_equal(btf_image_write_jpeg(p, &a, 0, &e), BTF_E_ARG);
    btf_image_free(&a);
    btf_image_free(&b);
    btf_image_free(&g);
    btf_image_free(&l);
}

static void cut_file(const char *src, const char *dst, long keep)
{
    FILE *f = fopen(src, "rb");
    assert_non_null(f);
    char *buf = malloc((size_t)keep);
    assert_int_equal(fread(buf, 1, (size_t)keep, f), (size_t)keep);
    fclose(f);
    tu_write_file(dst, buf, (size_t)keep);
    free(buf);
}

static long size_of(const char *p)
{
    struct stat st;
    assert_int_equal(stat(p, &st), 0);
    return (long)st.st_size;
}

static void truncated_files_are_errors(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image a, b;
    gradient(&a, 40, 30, 3);
    char png[4096], jpg[4096];
    snprintf(png, sizeof png, "%s/full.png", tu_dir);
    snprintf(jpg, sizeof jpg, "%s/full.jpg", tu_dir);
    TU_OK(btf_image_write_png(png, &a, &e), &e);
    TU_OK(btf_image_write_jpeg(jpg, &a, 90, &e), &e);
    const char *srcs[2] = {png, jpg};
    for (int s = 0; s < 2; s++) {
        long n = size_of(srcs[s]);
        long cuts[] = {1, 3, 10, 40, n / 2, n - 20, n - 1};
        for (int k = 0; k < 7; k++) {
            const char *cut = tu_fmt("%s/cut%d", tu_dir, k);
            cut_file(srcs[s], cut, cuts[k]);
            int rc = btf_image_read(cut, NULL, &b, &e);
            assert_true(rc == BTF_E_FORMAT);
            assert_non_null(strstr(e.msg, cut));
            assert_null(b.data);
        }
    }
    btf_image_free(&a);
}

static void garbage_and_missing(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image b;
    const char *g = tu_fmt("%s/garbage.jpg", tu_dir);
    tu_write_file(g, "this is not an image at all", 27);
    assert_int_equal(btf_image_read(g, NULL, &b, &e), BTF_E_FORMAT);
    assert_non_null(strstr(e.msg, "garbage.jpg"));
    const char *z = tu_fmt("%s/empty.png", tu_dir);
    tu_write_file(z, "", 0);
    btf_image_header h;
    assert_int_equal(btf_image_probe(z, &h, &e), BTF_E_FORMAT);
    assert_int_equal(btf_image_read(tu_fmt("%s/nope.png", tu_dir), NULL, &b, &e), BTF_E_IO);
    assert_non_null(strstr(e.msg, "nope.png"));
    /* A JPEG signature followed by junk: a corrupt marker, not a crash. */
    unsigned char junk[64] = {0xFF, 0xD8, 0xFF, 0xE0, 0x00, 0x02, 0x12, 0x34};
    const char *j = tu_fmt("%s/junk.jpg", tu_dir);
    tu_write_file(j, junk, sizeof junk);
    assert_int_equal(btf_image_read(j, NULL, &b, &e), BTF_E_FORMAT);
}

static void writes_are_atomic(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image a;
    gradient(&a, 8, 8, 3);
    /* Writing into a folder that does not exist fails and leaves nothing. */
    const char *p = tu_fmt("%s/no/such/folder/x.png", tu_dir);
    assert_int_equal(btf_image_write_png(p, &a, &e), BTF_E_IO);
    assert_non_null(strstr(e.msg, "x.png"));
    /* A successful write leaves exactly the file, no temporary. */
    char *d2 = tu_tmpdir();
    TU_OK(btf_image_write_png(tu_fmt("%s/a.png", d2), &a, &e), &e);
    TU_OK(btf_image_write_jpeg(tu_fmt("%s/a.jpg", d2), &a, 80, &e), &e);
    assert_int_equal(tu_count_files(d2), 2);
    tu_rmtree(d2);
    free(d2);
    btf_image_free(&a);
}

static unsigned char *slurp(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    rewind(f);
    unsigned char *b = malloc(len > 0 ? (size_t)len : 1);
    assert_non_null(b);
    assert_int_equal(fread(b, 1, (size_t)len, f), (size_t)len);
    fclose(f);
    *n = (size_t)len;
    return b;
}

/* Decoding a buffer gives what reading its file gives, for every option,
 * and damage is reported under the buffer's name. */
static void decode_from_memory(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image a, b, c;
    gradient(&a, 23, 11, 3);
    const char *png = tu_fmt("%s/mem.png", tu_dir);
    char jpg[4096];
    snprintf(jpg, sizeof jpg, "%s/mem.jpg", tu_dir);
    TU_OK(btf_image_write_png(png, &a, &e), &e);
    TU_OK(btf_image_write_jpeg(jpg, &a, 90, &e), &e);
    const char *files[2] = {png, jpg};
    btf_read_opts opts[4] = {{0}, {.channels = 1}, {.channels = 3, .linear_8bit = 1},
                             btf_read_defaults()};
    for (int f = 0; f < 2; f++) {
        size_t n;
        unsigned char *bytes = slurp(files[f], &n);
        for (int k = 0; k < 4; k++) {
            TU_OK(btf_image_read(files[f], &opts[k], &b, &e), &e);
            TU_OK(btf_image_decode(bytes, n, "buf", &opts[k], &c, &e), &e);
            assert_int_equal(b.width, c.width);
            assert_int_equal(b.height, c.height);
            assert_int_equal(b.channels, c.channels);
            assert_memory_equal(b.data, c.data,
                                (size_t)b.width * b.height * b.channels * sizeof(float));
            btf_image_free(&b);
            btf_image_free(&c);
        }
        btf_image_header h1, h2;
        TU_OK(btf_image_probe(files[f], &h1, &e), &e);
        TU_OK(btf_image_probe_memory(bytes, n, "buf", &h2, &e), &e);
        assert_memory_equal(&h1, &h2, sizeof h1);
        size_t cuts[] = {0, 1, 3, 10, 40, n / 2, n - 1};
        for (int k = 0; k < 7; k++) {
            assert_int_equal(btf_image_decode(bytes, cuts[k], "cut", NULL, &c, &e), BTF_E_FORMAT);
            assert_true(strncmp(e.msg, "cut: ", 5) == 0);
            assert_null(c.data);
        }
        btf_read_opts bad = {.channels = 2};
        assert_int_equal(btf_image_decode(bytes, n, "buf", &bad, &c, &e), BTF_E_ARG);
        free(bytes);
    }
    btf_image_free(&a);
}

static void read_defaults(void **state)
{
    (void)state;
    btf_read_opts d = btf_read_defaults();
    assert_int_equal(d.channels, 0);
    assert_int_equal(d.linear_8bit, 0);
    assert_int_equal(d.srgb_16bit, 0);
    assert_true(d.max_pixels == BTF_DEFAULT_MAX_PIXELS);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(srgb_transfer),
        cmocka_unit_test(alloc_limits),
        cmocka_unit_test(png_round_trip),
        cmocka_unit_test(jpeg_round_trip_and_channels),
        cmocka_unit_test(truncated_files_are_errors),
        cmocka_unit_test(garbage_and_missing),
        cmocka_unit_test(writes_are_atomic),
        cmocka_unit_test(decode_from_memory),
        cmocka_unit_test(read_defaults),
    };
    return cmocka_run_group_tests_name("image", tests, tu_setup_dir, tu_teardown_dir);
}
