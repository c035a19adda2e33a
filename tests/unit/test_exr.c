/*
 * test_exr.c — src/io/exr_read.c and exr_write.c: EXR round trips (half/float, 1/3 channels, odd
 * sizes, extreme values), the streaming writer, atomic writes, and reading
 * hostile input (NaN/Inf, truncation, garbage, unsupported layouts),
 * decoding from memory, and the provenance attributes. Files
 * the writer cannot produce (Inf, tiles, UINT, other compressions, offset
 * data windows) are made here directly with the OpenEXR core API.
 */
#define _GNU_SOURCE /* memmem */
#include "io/io.h"
#include "testutil.h"

#include "core/core.h"

#include <openexr.h>

#include <dirent.h>
#include <fcntl.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>


/* ------------------------------------------------------------ helpers */

static uint32_t rng_next(uint32_t *s)
{
    *s ^= *s << 13;
    *s ^= *s >> 17;
    *s ^= *s << 5;
    return *s;
}

/* Values in [lo, hi). */
static void random_image(btf_image *img, int w, int h, int c, uint32_t seed, float lo, float hi)
{
    btf_error e = {0};
    TU_OK(btf_image_alloc(img, w, h, c, &e), &e);
    uint32_t s = seed ? seed : 1;
    for (size_t i = 0; i < (size_t)w * h * c; i++)
        img->data[i] = lo + (hi - lo) * (float)(rng_next(&s) >> 8) / 16777216.0f;
}

/* Values exactly representable in half (multiples of 1/1024 in [0, 2)). */
static void half_exact_image(btf_image *img, int w, int h, int c, uint32_t seed)
{
    btf_error e = {0};
    TU_OK(btf_image_alloc(img, w, h, c, &e), &e);
    uint32_t s = seed ? seed : 1;
    for (size_t i = 0; i < (size_t)w * h * c; i++)
        img->data[i] = (float)(rng_next(&s) % 2048) / 1024.0f;
}

static void assert_same_image(const btf_image *a, const btf_image *b)
{
    assert_int_equal(a->width, b->width);
    assert_int_equal(a->height, b->height);
    assert_int_equal(a->channels, b->channels);
    size_t n = (size_t)a->width * a->height * a->channels;
    assert_memory_equal(a->data, b->data, n * sizeof(float));
}

static unsigned char *slurp(const char *path, size_t *n)
{
    unsigned char *d = NULL;
    btf_error e = {0};
    TU_OK(btf__read_file(path, (size_t)1 << 30, &d, n, &e), &e);
    return d;
}

/* A new empty folder tu_dir/name (into out) for one test, so that file counts
 * are its own. */
static void fresh_dir(char *out, size_t n, const char *name)
{
    snprintf(out, n, "%s/%s", tu_dir, name);
    btf_error e = {0};
    TU_OK(btf_mkdirs(out, &e), &e);
}

/* Entries in folder d other than `keep` (temporary files left behind). */
static int stray_files(const char *d, const char *keep)
{
    DIR *dd = opendir(d);
    assert_non_null(dd);
    int n = 0;
    struct dirent *ent;
    while ((ent = readdir(dd)))
        if (strcmp(ent->d_name, ".") && strcmp(ent->d_name, "..") &&
            (!keep || strcmp(ent->d_name, keep)))
            n++;
    closedir(dd);
    return n;
}

static int file_exists(const char *path)
{
    return access(path, F_OK) == 0;
}

/* A smooth test pattern, exact in half: channel c of (x, y). */
static float pattern(int c, int x, int y)
{
    return (float)((x * 3 + y * 5 + c * 7) % 64) / 32.0f;
}

static float inf_at_3_2(int c, int x, int y)
{
    return (x == 3 && y == 2 && c == 0) ? INFINITY : pattern(c, x, y);
}

static float nan_at_0_4(int c, int x, int y)
{
    return (x == 0 && y == 4 && c == 0) ? NAN : pattern(c, x, y);
}

/* The image read from a tu_exr_write_raw(s, pattern) file: output channel k is the
 * file channel named want[k]. */
static void assert_pattern(const btf_image *img, const tu_exr_spec *s, const char *const *want)
{
    for (int k = 0; k < img->channels; k++) {
        int src = -1;
        for (int j = 0; j < s->nch; j++)
            if (!strcmp(s->names[j], want[k]))
                src = j;
        assert_true(src >= 0);
        for (int y = 0; y < img->height; y++)
            for (int x = 0; x < img->width; x++)
                assert_true(img->data[((size_t)y * img->width + x) * img->channels + k] ==
                            pattern(src, x, y));
    }
}

/* ------------------------------------------------------------ round trips */

static void round_trip_sizes(void **state)
{
    (void)state;
    btf_error e = {0};
    char d[1024];
    fresh_dir(d, sizeof d, "rt");
    int sizes[][2] = {{1, 1}, {7, 13}, {1000, 3}, {3, 100}, {17, 16}, {5, 33}};
    const char *p = tu_fmt("%s/rt.exr", d);
    for (int s = 0; s < 6; s++)
        for (int c = 1; c <= 3; c += 2)
            for (int half = 0; half <= 1; half++) {
                btf_image a, b;
                int w = sizes[s][0], h = sizes[s][1];
                if (half)
                    half_exact_image(&a, w, h, c, (uint32_t)(s * 7 + c));
                else
                    random_image(&a, w, h, c, (uint32_t)(s * 7 + c), -1000.0f, 1000.0f);
                TU_OK(btf_image_write_exr_opts(p, &a, &(btf_exr_opts){.half = half}, NULL, &e), &e);
                btf_image_header hd;
                TU_OK(btf__exr_probe(p, &hd, &e), &e);
                assert_int_equal(hd.format, BTF_FILE_EXR);
                assert_int_equal(hd.width, w);
                assert_int_equal(hd.height, h);
                assert_int_equal(hd.channels, c);
                assert_int_equal(hd.bits, half ? 16 : 32);
                assert_true(hd.file_bytes > 0);
                /* Through the public API too: it dispatches on the signature. */
                TU_OK(btf_image_probe(p, &hd, &e), &e);
                assert_int_equal(hd.format, BTF_FILE_EXR);
                TU_OK(btf__exr_read(p, 0, &b, &e), &e);
                assert_same_image(&a, &b);
                btf_image_free(&a);
                btf_image_free(&b);
            }
    assert_int_equal(stray_files(d, "rt.exr"), 0);
}

static void half_rounds_to_nearest(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image a, b;
    random_image(&a, 31, 9, 3, 5, 0.0f, 8.0f);
    const char *p = tu_fmt("%s/h.exr", tu_dir);
    TU_OK(btf_image_write_exr_opts(p, &a, &(btf_exr_opts){.half = 1}, NULL, &e), &e);
    TU_OK(btf__exr_read(p, 0, &b, &e), &e);
    for (size_t i = 0; i < (size_t)31 * 9 * 3; i++)
        assert_true(fabsf(a.data[i] - b.data[i]) <= a.data[i] * (1.0f / 2048.0f) + 1e-7f);
    btf_image_free(&a);
    btf_image_free(&b);
}

static void extreme_values(void **state)
{
    (void)state;
    btf_error e = {0};
    const float in[] = {3e38f, -3e38f, FLT_MAX, -FLT_MAX, FLT_MIN, 1e-45f, -1e-40f, 0.0f,
                        -0.0f, 1e6f,  65504.0f, 65519.0f, 70000.0f, -1e5f, 1e-8f, 6e-8f};
    const int n = (int)(sizeof in / sizeof in[0]);
    btf_image a, b;
    TU_OK(btf_image_alloc(&a, n, 1, 1, &e), &e);
    memcpy(a.data, in, sizeof in);
    const char *p = tu_fmt("%s/x.exr", tu_dir);

    /* Float keeps every value bit for bit, subnormals and -0 included. */
    TU_OK(btf_image_write_exr_opts(p, &a, NULL, NULL, &e), &e);
    TU_OK(btf__exr_read(p, 0, &b, &e), &e);
    assert_memory_equal(a.data, b.data, sizeof in);
    btf_image_free(&b);

    /* Half clamps to +-65504 (never Inf); tiny values go to 0 or a half
     * subnormal, keeping their sign. */
    TU_OK(btf_image_write_exr_opts(p, &a, &(btf_exr_opts){.half = 1}, NULL, &e), &e);
    TU_OK(btf__exr_read(p, 0, &b, &e), &e);
    for (int i = 0; i < n; i++) {
        float v = b.data[i];
        assert_true(isfinite(v));
        if (in[i] >= 65504.0f)
            assert_true(v == 65504.0f);
        else if (in[i] <= -65504.0f)
            assert_true(v == -65504.0f);
        else if (fabsf(in[i]) < 1e-7f)
            assert_true(fabsf(v) <= 6e-8f && (v == 0.0f || (v > 0) == (in[i] > 0)));
        else
            assert_true(fabsf(v - in[i]) <= fabsf(in[i]) / 1024.0f);
    }
    assert_true(b.data[15] > 0.0f); /* 6e-8 is about the smallest half subnormal */
    btf_image_free(&a);
    btf_image_free(&b);
}

static void channel_conversion(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image rgb, grey, b;
    random_image(&rgb, 9, 4, 3, 11, 0.0f, 10.0f);
    const char *p = tu_fmt("%s/c.exr", tu_dir);
    TU_OK(btf_image_write_exr_opts(p, &rgb, NULL, NULL, &e), &e);
    TU_OK(btf__exr_read(p, 1, &b, &e), &e);
    assert_int_equal(b.channels, 1);
    for (int i = 0; i < 36; i++) {
        const float *q = rgb.data + 3 * i;
        float l = 0.2126f * q[0] + 0.7152f * q[1] + 0.0722f * q[2];
        assert_true(fabsf(b.data[i] - l) <= 1e-5f * (1.0f + l));
    }
    btf_image_free(&b);
    TU_OK(btf__exr_read(p, 3, &b, &e), &e);
    assert_same_image(&rgb, &b);
    btf_image_free(&b);

    random_image(&grey, 5, 6, 1, 12, -5.0f, 5.0f);
    TU_OK(btf_image_write_exr_opts(p, &grey, &(btf_exr_opts){.half = 1}, NULL, &e), &e);
    TU_OK(btf__exr_read(p, 3, &b, &e), &e);
    assert_int_equal(b.channels, 3);
    for (int i = 0; i < 30; i++) {
        assert_true(b.data[3 * i] == b.data[3 * i + 1] && b.data[3 * i] == b.data[3 * i + 2]);
        assert_true(fabsf(b.data[3 * i] - grey.data[i]) <= fabsf(grey.data[i]) / 1024.0f);
    }
    btf_image_free(&b);
    /* An RGB image of FLT_MAX has a luminance of FLT_MAX, not Inf. */
    for (int i = 0; i < 36 * 3; i++)
        rgb.data[i] = FLT_MAX;
    TU_OK(btf_image_write_exr_opts(p, &rgb, NULL, NULL, &e), &e);
    TU_OK(btf__exr_read(p, 1, &b, &e), &e);
    for (int i = 0; i < 36; i++)
        assert_true(isfinite(b.data[i]) && b.data[i] > 3e38f);
    btf_image_free(&b);
    assert_int_equal(btf__exr_read(p, 2, &b, &e), BTF_E_ARG);
    assert_null(b.data);
    btf_image_free(&rgb);
    btf_image_free(&grey);
}

/* --------------------------------------------------- the streaming writer */

static void streaming_equals_one_shot(void **state)
{
    (void)state;
    btf_error e = {0};
    char d[1024];
    fresh_dir(d, sizeof d, "stream");
    for (int half = 0; half <= 1; half++) {
        btf_image a, b;
        int w = 37, h = 101, c = 3;
        random_image(&a, w, h, c, 99 + half, -3.0f, 3.0f);
        const char *p1 = tu_fmt("%s/one.exr", d), *p2 = tu_fmt("%s/stream.exr", d);
        TU_OK(btf_image_write_exr_opts(p1, &a, &(btf_exr_opts){.half = half}, NULL, &e), &e);

        btf_exr_writer *wr = NULL;
        TU_OK(btf_exr_writer_open_opts(p2, w, h, c, &(btf_exr_opts){.half = half}, NULL, &wr, &e),
              &e);
        /* Batches that straddle the 16-row chunks, and empty ones. */
        const int batches[] = {1, 0, 2, 15, 16, 17, 3, 33, 0, 14};
        int row = 0;
        for (int i = 0; i < 10; i++) {
            TU_OK(btf_exr_writer_put_rows(wr, a.data + (size_t)row * w * c, batches[i], &e), &e);
            row += batches[i];
            assert_false(file_exists(p2)); /* nothing visible before close */
        }
        assert_int_equal(row, h);
        TU_OK(btf_exr_writer_close(wr, &e), &e);

        size_t n1, n2;
        unsigned char *d1 = slurp(p1, &n1), *d2 = slurp(p2, &n2);
        assert_int_equal(n1, n2);
        assert_memory_equal(d1, d2, n1);
        free(d1);
        free(d2);
        TU_OK(btf__exr_read(p2, 0, &b, &e), &e);
        assert_int_equal(b.width, w);
        assert_int_equal(b.height, h);
        if (!half)
            assert_same_image(&a, &b);
        btf_image_free(&a);
        btf_image_free(&b);
        remove(p1);
        remove(p2);
    }
    assert_int_equal(stray_files(d, NULL), 0);
}

/* The writer's options: every compression it offers, half and float, with
 * and without the background thread. The thread's file is the caller's,
 * byte for byte; the lossless ones give the pixels back (half: those of the
 * default half file); the figures count both files. Wide rows (25 KB) make
 * several 256 KiB slabs per image, so the queue fills and wraps. */
static void writer_options(void **state)
{
    (void)state;
    btf_error e = {0};
    char d[1024];
    fresh_dir(d, sizeof d, "opts");
    int w = 2100, h = 203, c = 3;
    btf_image a, ref[2];
    random_image(&a, w, h, c, 7, -2.0f, 2.0f);
    for (int half = 0; half <= 1; half++) {
        const char *p = tu_fmt("%s/ref.exr", d);
        TU_OK(btf_image_write_exr_opts(p, &a, &(btf_exr_opts){.half = half}, NULL, &e), &e);
        TU_OK(btf__exr_read(p, 0, &ref[half], &e), &e);
        remove(p);
    }
    assert_string_equal(btf__exr_compression_name(BTF_EXR_PIZ), "piz");
    assert_string_equal(btf__exr_compression_name(0), "zip");
    assert_null(btf__exr_compression_name(BTF_EXR_PXR24 + 1));
    assert_null(btf__exr_compression_name(-1));
    for (int comp = BTF_EXR_ZIP; comp <= BTF_EXR_PXR24; comp++)
        for (int half = 0; half <= 1; half++) {
            char path[2][1024];
            btf_exr_times t = {0};
            for (int bg = 0; bg <= 1; bg++) {
                snprintf(path[bg], sizeof path[bg], "%s/%s_%d_%d.exr", d,
                         btf__exr_compression_name(comp), half, bg);
                btf_exr_opts o = btf_exr_defaults();
                o.half = half, o.compression = comp, o.background = bg, o.times = &t;
                btf_exr_writer *wr = NULL;
                TU_OK(btf_exr_writer_open_opts(path[bg], w, h, c, &o, NULL, &wr, &e), &e);
                for (int row = 0, n = 1; row < h; row += n, n = n * 3 % 37 + 1) {
                    n = n < h - row ? n : h - row;
                    TU_OK(btf_exr_writer_put_rows(wr, a.data + (size_t)row * w * c, n, &e), &e);
                    assert_false(file_exists(path[bg]));
                }
                TU_OK(btf_exr_writer_close(wr, &e), &e);
            }
            size_t n1, n2;
            unsigned char *d1 = slurp(path[0], &n1), *d2 = slurp(path[1], &n2);
            assert_int_equal(n1, n2);
            assert_memory_equal(d1, d2, n1);
            free(d1);
            free(d2);
            assert_int_equal(t.files, 2);
            assert_true(t.bytes == 2 * (uint64_t)n1);
            assert_true(t.write_s > 0 && t.convert_s > 0 && t.stage_s > 0);
            btf_image b;
            TU_OK(btf__exr_read(path[1], 0, &b, &e), &e);
            int lossless = comp <= BTF_EXR_PIZ || (comp == BTF_EXR_PXR24 && half);
            if (lossless)
                assert_same_image(&ref[half], &b);
            /* The lossy one: PXR24 keeps 16 bits of float mantissa. */
            double worst = 0;
            for (size_t i = 0; i < (size_t)w * h * c; i++)
                worst = fmax(worst, fabs((double)b.data[i] - ref[half].data[i]));
            assert_true(worst < (comp == BTF_EXR_PXR24 ? 4e-5 : 4.0));
            btf_image_free(&b);
            remove(path[0]);
            remove(path[1]);
        }
    /* One row, and fewer rows than a slab, through the thread. */
    for (int rows = 1; rows <= 3; rows += 2) {
        const char *p = tu_fmt("%s/small.exr", d);
        btf_exr_opts o = btf_exr_defaults();
        o.background = 1, o.compression = BTF_EXR_PIZ;
        btf_image small = {.width = w, .height = rows, .channels = c, .data = a.data};
        TU_OK(btf_image_write_exr_opts(p, &small, &o, NULL, &e), &e);
        btf_image b;
        TU_OK(btf__exr_read(p, 0, &b, &e), &e);
        assert_int_equal(b.height, rows);
        assert_memory_equal(b.data, a.data, (size_t)w * rows * c * sizeof(float));
        btf_image_free(&b);
        remove(p);
    }
    btf_exr_opts bad = btf_exr_defaults();
    bad.compression = BTF_EXR_PXR24 + 1;
    btf_exr_writer *wr = NULL;
    assert_int_equal(btf_exr_writer_open_opts(tu_fmt("%s/bad.exr", d), 4, 4, 3, &bad, NULL, &wr,
                                              &e), BTF_E_ARG);
    assert_null(wr);
    assert_int_equal(stray_files(d, NULL), 0);
    /* A non-finite value with the thread: refused at once, nothing left. */
    btf_exr_opts o = btf_exr_defaults();
    o.background = 1;
    const char *p = tu_fmt("%s/nan.exr", d);
    TU_OK(btf_exr_writer_open_opts(p, w, h, c, &o, NULL, &wr, &e), &e);
    TU_OK(btf_exr_writer_put_rows(wr, a.data, 100, &e), &e);
    a.data[(size_t)150 * w * c + 5] = NAN;
    assert_int_equal(btf_exr_writer_put_rows(wr, a.data + (size_t)100 * w * c, 103, &e),
                     BTF_E_ARG);
    assert_non_null(strstr(e.msg, "(1, 150)"));
    assert_int_equal(btf_exr_writer_close(wr, &e), BTF_E_ARG);
    assert_false(file_exists(p));
    assert_int_equal(stray_files(d, NULL), 0);
    btf_image_free(&a);
    btf_image_free(&ref[0]);
    btf_image_free(&ref[1]);
}

/* The writer's own packer (F16C) against OpenEXRCore's, byte for byte:
 * values at half's rounding ties, its subnormals and limits, float
 * subnormals, signed zeros, random ones; widths past the 1024-pixel blocks;
 * grey and RGB; each lossless compression. */
static void fast_pack_is_the_library_s(void **state)
{
    (void)state;
    btf_error e = {0};
    char d[1024];
    fresh_dir(d, sizeof d, "pack");
    int w = 1500, h = 20;
    for (int c = 1; c <= 3; c += 2) {
        btf_image a;
        random_image(&a, w, h, c, 11, -70000.0f, 70000.0f);
        uint32_t s = 5;
        for (size_t i = 0; i < (size_t)w * h * c; i++) {
            uint32_t r = rng_next(&s);
            float v;
            switch (i % 6) {
            case 0: /* a tie or near one: 11 bits plus a half ulp, +-1 */
                v = ldexpf((float)((r & 0x7ff) | 0x800) + 0.5f, (int)(r >> 11) % 40 - 36);
                v = nextafterf(v, (r >> 20) % 3 == 0 ? 0.0f : (r >> 20) % 3 == 1 ? 1e9f : v);
                break;
            case 1: /* half subnormals and below */
                v = ldexpf((float)(r & 0xffff), -30 - (int)(r >> 16) % 12);
                break;
            case 2: /* float subnormals, signed zeros */
                v = (r & 1) ? -0.0f : ldexpf((float)(r >> 8), -150);
                break;
            default:
                v = a.data[i] / (float)(1u << (r % 20));
            }
            a.data[i] = (r & 0x80000000u) ? -v : v;
        }
        for (int half = 0; half <= 1; half++)
            for (int comp = BTF_EXR_ZIP; comp <= BTF_EXR_PIZ; comp++) {
                char path[2][1024];
                for (int lib = 0; lib <= 1; lib++) {
                    snprintf(path[lib], sizeof path[lib], "%s/p%d.exr", d, lib);
                    btf__exr_library_pack = lib;
                    btf_exr_opts o = btf_exr_defaults();
                    o.half = half, o.compression = comp, o.background = lib;
                    TU_OK(btf_image_write_exr_opts(path[lib], &a, &o, NULL, &e), &e);
                }
                btf__exr_library_pack = 0;
                size_t n1, n2;
                unsigned char *d1 = slurp(path[0], &n1), *d2 = slurp(path[1], &n2);
                assert_int_equal(n1, n2);
                assert_memory_equal(d1, d2, n1);
                free(d1);
                free(d2);
            }
        btf_image_free(&a);
    }
}

static void writer_closed_early(void **state)
{
    (void)state;
    btf_error e = {0};
    char d[1024];
    fresh_dir(d, sizeof d, "early");
    const char *p = tu_fmt("%s/early.exr", d);
    float row[20 * 3] = {0};
    btf_exr_writer *w = NULL;
    TU_OK(btf_exr_writer_open_opts(p, 20, 40, 3, &(btf_exr_opts){.half = 1}, NULL, &w, &e), &e);
    for (int i = 0; i < 17; i++)
        TU_OK(btf_exr_writer_put_rows(w, row, 1, &e), &e);
    assert_int_equal(btf_exr_writer_close(w, &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, "17 of 40"));
    assert_false(file_exists(p));
    assert_int_equal(stray_files(d, NULL), 0);

    /* Abort removes the temporary file too, at any point. */
    TU_OK(btf_exr_writer_open_opts(p, 20, 40, 1, NULL, NULL, &w, &e), &e);
    assert_int_equal(stray_files(d, NULL), 1);
    TU_OK(btf_exr_writer_put_rows(w, row, 3, &e), &e);
    btf_exr_writer_abort(w);
    btf_exr_writer_abort(NULL);
    assert_int_equal(stray_files(d, NULL), 0);
}

static void writer_misuse(void **state)
{
    (void)state;
    btf_error e = {0};
    char d[1024];
    fresh_dir(d, sizeof d, "misuse");
    const char *p = tu_fmt("%s/m.exr", d);
    float rows[4 * 10] = {0};
    btf_exr_writer *w = (btf_exr_writer *)&e;
    assert_int_equal(btf_exr_writer_open_opts(p, 0, 5, 1, NULL, NULL, &w, &e), BTF_E_ARG);
    assert_null(w);
    assert_int_equal(btf_exr_writer_open_opts(p, 5, 65537, 1, NULL, NULL, &w, &e), BTF_E_ARG);
    assert_int_equal(btf_exr_writer_open_opts(p, 5, 5, 2, NULL, NULL, &w, &e), BTF_E_ARG);
    assert_int_equal(btf_exr_writer_open_opts(NULL, 5, 5, 1, NULL, NULL, &w, &e), BTF_E_ARG);
    assert_int_equal(btf_exr_writer_open_opts(p, 5, 5, 1, NULL, NULL, NULL, &e), BTF_E_ARG);
    assert_int_equal(btf_exr_writer_put_rows(NULL, rows, 1, &e), BTF_E_ARG);
    assert_int_equal(btf_exr_writer_close(NULL, &e), BTF_E_ARG);
    /* A folder that does not exist. */
    assert_int_equal(btf_exr_writer_open_opts(tu_fmt("%s/no/such/x.exr", d), 4, 4, 1, NULL, NULL,
                                              &w, &e),
                     BTF_E_IO);
    assert_non_null(strstr(e.msg, "no/such/x.exr"));

    /* Too many rows: an error, final for the writer. */
    TU_OK(btf_exr_writer_open_opts(p, 4, 3, 1, NULL, NULL, &w, &e), &e);
    assert_int_equal(btf_exr_writer_put_rows(w, rows, 4, &e), BTF_E_ARG);
    assert_int_equal(btf_exr_writer_put_rows(w, rows, 3, &e), BTF_E_ARG);
    assert_int_equal(btf_exr_writer_close(w, &e), BTF_E_ARG);
    assert_false(file_exists(p));
    assert_int_equal(stray_files(d, NULL), 0);

    /* No image. */
    btf_image none = {0};
    assert_int_equal(btf_image_write_exr_opts(p, &none, NULL, NULL, &e), BTF_E_ARG);
    assert_int_equal(btf_image_write_exr_opts(p, NULL, NULL, NULL, &e), BTF_E_ARG);
}

static void non_finite_input_refused(void **state)
{
    (void)state;
    btf_error e = {0};
    char d[1024];
    fresh_dir(d, sizeof d, "nonfinite");
    const char *p = tu_fmt("%s/nan.exr", d);
    for (int half = 0; half <= 1; half++)
        for (int kind = 0; kind < 3; kind++) {
            btf_image a;
            random_image(&a, 6, 40, 3, 3, 0.0f, 1.0f);
            /* Pixel (4, 35), past the first chunks, so some were written. */
            a.data[(35 * 6 + 4) * 3 + 1] = kind == 0 ? NAN : kind == 1 ? INFINITY : -INFINITY;
            assert_int_equal(
                btf_image_write_exr_opts(p, &a, &(btf_exr_opts){.half = half}, NULL, &e),
                BTF_E_ARG);
            assert_non_null(strstr(e.msg, "(4, 35)"));
            assert_non_null(strstr(e.msg, kind == 0 ? "NaN" : "Inf"));
            assert_false(file_exists(p));
            assert_int_equal(stray_files(d, NULL), 0);
            btf_image_free(&a);
        }
}

static void writes_are_atomic(void **state)
{
    (void)state;
    btf_error e = {0};
    char d[1024];
    fresh_dir(d, sizeof d, "atomic");
    const char *p = tu_fmt("%s/atomic.exr", d);
    btf_image a, b, bad;
    half_exact_image(&a, 12, 12, 3, 1);
    TU_OK(btf_image_write_exr_opts(p, &a, &(btf_exr_opts){.half = 1}, NULL, &e), &e);
    assert_int_equal(stray_files(d, "atomic.exr"), 0);
    /* A failed rewrite leaves the old file as it was. */
    random_image(&bad, 12, 12, 3, 2, 0.0f, 1.0f);
    bad.data[100] = NAN;
    assert_int_equal(btf_image_write_exr_opts(p, &bad, NULL, NULL, &e), BTF_E_ARG);
    assert_int_equal(stray_files(d, "atomic.exr"), 0);
    TU_OK(btf__exr_read(p, 0, &b, &e), &e);
    assert_same_image(&a, &b);
    btf_image_free(&b);
    /* A successful rewrite replaces it. */
    bad.data[100] = 0.5f;
    TU_OK(btf_image_write_exr_opts(p, &bad, NULL, NULL, &e), &e);
    TU_OK(btf__exr_read(p, 0, &b, &e), &e);
    assert_same_image(&bad, &b);
    assert_int_equal(stray_files(d, "atomic.exr"), 0);
    btf_image_free(&a);
    btf_image_free(&b);
    btf_image_free(&bad);
    remove(p);
}

/* --------------------------------------------- files made by other writers */

static void inf_and_nan_in_file(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image b;
    const char *p = tu_fmt("%s/inf.exr", tu_dir);
    tu_exr_spec s = {EXR_STORAGE_SCANLINE, EXR_COMPRESSION_NONE, 0, 0, 0, 8, 6, 1, {"Y"},
                  {EXR_PIXEL_FLOAT}};
    tu_exr_write_raw(p, &s, inf_at_3_2);
    TU_OK(btf__exr_probe(p, &(btf_image_header){0}, &e), &e); /* the header is fine */
    assert_int_equal(btf__exr_read(p, 0, &b, &e), BTF_E_DATA);
    assert_string_equal(e.msg, tu_fmt("%s: NaN or Inf at pixel (3, 2)", p));
    assert_null(b.data);
    /* Through the public reader as well. */
    assert_int_equal(btf_image_read(p, NULL, &b, &e), BTF_E_DATA);

    /* NaN in a half RGB file, with compression. */
    tu_exr_spec s2 = {EXR_STORAGE_SCANLINE, EXR_COMPRESSION_ZIP, 0, 0, 0, 5, 20, 3, {"B", "G", "R"},
                   {EXR_PIXEL_HALF, EXR_PIXEL_HALF, EXR_PIXEL_HALF}};
    tu_exr_write_raw(p, &s2, nan_at_0_4);
    assert_int_equal(btf__exr_read(p, 1, &b, &e), BTF_E_DATA);
    assert_string_equal(e.msg, tu_fmt("%s: NaN or Inf at pixel (0, 4)", p));
    assert_null(b.data);
}

static void other_layouts(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image b;
    btf_image_header hd;
    const char *p = tu_fmt("%s/layout.exr", tu_dir);

    /* Tiled, with partial tiles at the right and bottom edges. */
    tu_exr_spec t = {EXR_STORAGE_TILED, EXR_COMPRESSION_ZIP, 4, 0, 0, 10, 7, 3, {"B", "G", "R"},
                  {EXR_PIXEL_FLOAT, EXR_PIXEL_HALF, EXR_PIXEL_FLOAT}};
    tu_exr_write_raw(p, &t, pattern);
    TU_OK(btf__exr_probe(p, &hd, &e), &e);
    assert_int_equal(hd.width, 10);
    assert_int_equal(hd.height, 7);
    assert_int_equal(hd.channels, 3);
    assert_int_equal(hd.bits, 32);
    TU_OK(btf__exr_read(p, 0, &b, &e), &e);
    assert_pattern(&b, &t, (const char *const[]){"R", "G", "B"});
    btf_image_free(&b);

    /* A data window that does not start at (0, 0); an alpha channel that is
     * ignored; a single-channel tiled file of any name. */
    tu_exr_spec o = {EXR_STORAGE_SCANLINE, EXR_COMPRESSION_PIZ, 0, -3, 5, 9, 40, 2, {"A", "Y"},
                  {EXR_PIXEL_HALF, EXR_PIXEL_HALF}};
    tu_exr_write_raw(p, &o, pattern);
    TU_OK(btf__exr_probe(p, &hd, &e), &e);
    assert_int_equal(hd.channels, 1);
    assert_int_equal(hd.bits, 16);
    TU_OK(btf__exr_read(p, 0, &b, &e), &e);
    assert_int_equal(b.width, 9);
    assert_int_equal(b.height, 40);
    assert_pattern(&b, &o, (const char *const[]){"Y"});
    btf_image_free(&b);

    tu_exr_spec z = {EXR_STORAGE_TILED, EXR_COMPRESSION_NONE, 3, 2, 2, 8, 8, 1, {"Z"},
                  {EXR_PIXEL_FLOAT}};
    tu_exr_write_raw(p, &z, pattern);
    TU_OK(btf__exr_read(p, 3, &b, &e), &e);
    assert_int_equal(b.channels, 3);
    assert_pattern(&b, &z, (const char *const[]){"Z", "Z", "Z"});
    btf_image_free(&b);
}

static void every_compression(void **state)
{
    (void)state;
    btf_error e = {0};
    const char *p = tu_fmt("%s/comp.exr", tu_dir);
    const exr_compression_t comp[] = {
        EXR_COMPRESSION_NONE,  EXR_COMPRESSION_RLE, EXR_COMPRESSION_ZIPS,
        EXR_COMPRESSION_ZIP,   EXR_COMPRESSION_PIZ, EXR_COMPRESSION_PXR24,
        EXR_COMPRESSION_B44,   EXR_COMPRESSION_B44A};
    /* DWAA/DWAB: OpenEXRCore 3.1 can neither write nor read them (see
     * dwa_is_unsupported). B44/B44A: refused before decoding, because the
     * library's B44 decoder crashes on damaged files (fuzz_exr). */
    for (int i = 0; i < 8; i++) {
        tu_exr_spec s = {EXR_STORAGE_SCANLINE, comp[i], 0, 0, 0, 45, 70, 4, {"A", "B", "G", "R"},
                      {EXR_PIXEL_HALF, EXR_PIXEL_HALF, EXR_PIXEL_HALF, EXR_PIXEL_HALF}};
        tu_exr_write_raw(p, &s, pattern);
        btf_image b;
        if (comp[i] == EXR_COMPRESSION_B44 || comp[i] == EXR_COMPRESSION_B44A) {
            assert_int_equal(btf__exr_read(p, 0, &b, &e), BTF_E_UNSUPPORTED);
            assert_non_null(strstr(e.msg, "B44"));
            assert_non_null(strstr(e.msg, p));
            continue;
        }
        TU_OK(btf__exr_read(p, 0, &b, &e), &e);
        assert_int_equal(b.channels, 3);
        /* Exact for the lossless ones (PXR24 is lossless on half); B44 and
         * DWA are lossy, worst at the pattern's jumps. Output R, G, B are
         * file channels 3, 2, 1. */
        int lossless = comp[i] <= EXR_COMPRESSION_PXR24;
        double sum = 0.0, worst = 0.0;
        for (int y = 0; y < 70; y++)
            for (int x = 0; x < 45; x++)
                for (int k = 0; k < 3; k++) {
                    double d = fabs(b.data[(y * 45 + x) * 3 + k] - pattern(3 - k, x, y));
                    sum += d;
                    worst = d > worst ? d : worst;
                }
        if (lossless)
            assert_true(worst == 0.0);
        else
            assert_true(worst < 0.5 && sum / (45 * 70 * 3) < 0.02);
        btf_image_free(&b);
    }
}

/* OpenEXRCore 3.1 has no DWA codec: such files are BTF_E_UNSUPPORTED, not
 * "corrupt". The test file is a ZIP file relabelled as DWAA (one chunk
 * either way), since the core library cannot write DWA. */
static void dwa_is_unsupported(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image b;
    const char *p = tu_fmt("%s/dwa.exr", tu_dir);
    tu_exr_spec s = {EXR_STORAGE_SCANLINE, EXR_COMPRESSION_ZIP, 0, 0, 0, 16, 8, 1, {"Y"},
                  {EXR_PIXEL_HALF}};
    tu_exr_write_raw(p, &s, pattern);
    size_t n;
    unsigned char *d = slurp(p, &n);
    static const char key[] = "compression\0compression\0\1\0\0\0";
    unsigned char *at = memmem(d, n, key, sizeof key - 1);
    assert_non_null(at);
    assert_int_equal(at[sizeof key - 1], EXR_COMPRESSION_ZIP);
    at[sizeof key - 1] = EXR_COMPRESSION_DWAA;
    tu_write_file(p, d, n);
    free(d);
    int rc = btf__exr_read(p, 0, &b, &e);
    if (rc != BTF_E_UNSUPPORTED)
        print_error("DWA read gave %d: %s\n", rc, e.msg);
    assert_int_equal(rc, BTF_E_UNSUPPORTED);
    assert_non_null(strstr(e.msg, p));
    assert_null(b.data);
}

static uint32_t le32(const unsigned char *b)
{
    return b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

/* Relabels a single-part scanline file as deep scanline (the core API can
 * write deep files only with sample tables): type "deepscanline", the
 * non-image version flag, and the "version" and "chunkCount" attributes deep
 * parts require; the offset table moves with the header. The pixel data is
 * not deep data, but the reader must refuse the part before touching it. */
static void relabel_as_deep(const char *path, int nchunks)
{
    size_t n;
    unsigned char *d = slurp(path, &n);
    size_t p = 8; /* magic and version, then attributes until an empty name */
    while (p < n && d[p]) {
        size_t name = strlen((const char *)d + p) + 1;
        size_t type = strlen((const char *)d + p + name) + 1;
        p += name + type + 4 + le32(d + p + name + type);
        assert_true(p < n);
    }
    static const char old[] = "type\0string\0\15\0\0\0scanlineimage";
    static const char repl[] = "type\0string\0\14\0\0\0deepscanline";
    unsigned char extra[64];
    size_t ne = 0;
    memcpy(extra + ne, "version\0int\0\4\0\0\0\1\0\0\0", 20), ne += 20;
    memcpy(extra + ne, "chunkCount\0int\0\4\0\0\0", 19), ne += 19;
    for (int k = 0; k < 4; k++)
        extra[ne++] = (unsigned char)((unsigned)nchunks >> (8 * k));
    unsigned char *o = malloc(n + ne + 8);
    assert_non_null(o);
    unsigned char *at = memmem(d, p, old, sizeof old - 1);
    assert_non_null(at);
    size_t pre = (size_t)(at - d), m = 0;
    memcpy(o, d, pre), m = pre;
    memcpy(o + m, repl, sizeof repl - 1), m += sizeof repl - 1;
    size_t rest = p - pre - (sizeof old - 1);
    memcpy(o + m, at + sizeof old - 1, rest), m += rest;
    memcpy(o + m, extra, ne), m += ne;
    o[m++] = 0;
    long long delta = (long long)m - (long long)(p + 1);
    for (int k = 0; k < nchunks; k++) {
        uint64_t off = 0;
        for (int b = 0; b < 8; b++)
            off |= (uint64_t)d[p + 1 + 8 * k + b] << (8 * b);
        off += (uint64_t)delta;
        for (int b = 0; b < 8; b++)
            o[m++] = (unsigned char)(off >> (8 * b));
    }
    size_t body = p + 1 + 8 * (size_t)nchunks;
    memcpy(o + m, d + body, n - body), m += n - body;
    o[5] |= 0x08; /* the non-image (deep) flag */
    tu_write_file(path, o, m);
    free(o);
    free(d);
}

static void deep_is_unsupported(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image b;
    const char *p = tu_fmt("%s/deep.exr", tu_dir);
    tu_exr_spec s = {EXR_STORAGE_SCANLINE, EXR_COMPRESSION_NONE, 0, 0, 0, 6, 5, 1, {"Y"},
                  {EXR_PIXEL_FLOAT}};
    tu_exr_write_raw(p, &s, pattern);
    TU_OK(btf__exr_read(p, 0, &b, &e), &e);
    btf_image_free(&b);
    relabel_as_deep(p, 5); /* NONE: one scanline per chunk */
    int rc = btf__exr_read(p, 0, &b, &e);
    if (rc != BTF_E_UNSUPPORTED)
        print_error("deep read gave %d: %s\n", rc, e.msg);
    assert_int_equal(rc, BTF_E_UNSUPPORTED);
    assert_string_equal(e.msg, tu_fmt("%s: deep EXR images are not supported", p));
    assert_null(b.data);
    assert_int_equal(btf__exr_probe(p, &(btf_image_header){0}, &e), BTF_E_UNSUPPORTED);
}

static void unsupported_layouts(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image b;
    btf_image_header hd;
    const char *p = tu_fmt("%s/u.exr", tu_dir);

    tu_exr_spec u = {EXR_STORAGE_SCANLINE, EXR_COMPRESSION_NONE, 0, 0, 0, 4, 4, 1, {"Y"},
                  {EXR_PIXEL_UINT}};
    tu_exr_write_raw(p, &u, pattern);
    assert_int_equal(btf__exr_probe(p, &hd, &e), BTF_E_UNSUPPORTED);
    assert_int_equal(btf__exr_read(p, 0, &b, &e), BTF_E_UNSUPPORTED);
    assert_non_null(strstr(e.msg, p));
    assert_non_null(strstr(e.msg, "UINT"));

    tu_exr_spec uv = {EXR_STORAGE_SCANLINE, EXR_COMPRESSION_NONE, 0, 0, 0, 4, 4, 2, {"U", "V"},
                   {EXR_PIXEL_HALF, EXR_PIXEL_HALF}};
    tu_exr_write_raw(p, &uv, pattern);
    assert_int_equal(btf__exr_read(p, 0, &b, &e), BTF_E_UNSUPPORTED);
    assert_non_null(strstr(e.msg, "U, V"));

    /* Luminance/chroma: reading only Y would lose the colour. */
    tu_exr_spec yc = {EXR_STORAGE_SCANLINE, EXR_COMPRESSION_NONE, 0, 0, 0, 4, 4, 3,
                   {"BY", "RY", "Y"}, {EXR_PIXEL_HALF, EXR_PIXEL_HALF, EXR_PIXEL_HALF}};
    tu_exr_write_raw(p, &yc, pattern);
    assert_int_equal(btf__exr_read(p, 0, &b, &e), BTF_E_UNSUPPORTED);

    /* A UINT channel beside R, G, B is merely skipped. */
    tu_exr_spec id = {EXR_STORAGE_SCANLINE, EXR_COMPRESSION_ZIP, 0, 0, 0, 6, 5, 4,
                   {"B", "G", "R", "id"},
                   {EXR_PIXEL_HALF, EXR_PIXEL_HALF, EXR_PIXEL_HALF, EXR_PIXEL_UINT}};
    tu_exr_write_raw(p, &id, pattern);
    TU_OK(btf__exr_read(p, 0, &b, &e), &e);
    for (int i = 0; i < 30; i++)
        assert_true(b.data[3 * i] == pattern(2, i % 6, i / 6));
    btf_image_free(&b);
}

/* ------------------------------------------------------- damaged files */

/* Reading and probing must fail cleanly (never crash, leak or print). */
static void assert_rejected(const char *p)
{
    btf_error e = {0};
    btf_image b;
    btf_image_header hd;
    int rc = btf__exr_read(p, 0, &b, &e);
    if (rc != BTF_E_FORMAT && rc != BTF_E_IO)
        print_error("%s: read gave %d: %s\n", p, rc, e.msg);
    assert_true(rc == BTF_E_FORMAT || rc == BTF_E_IO);
    assert_null(b.data);
    assert_int_equal(strncmp(e.msg, p, strlen(p)), 0);
    assert_null(strchr(e.msg, '\n'));
    rc = btf__exr_probe(p, &hd, &e);
    assert_true(rc == BTF_E_FORMAT || rc == BTF_E_IO);
}

static void truncated_files(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image a;
    random_image(&a, 64, 50, 3, 7, 0.0f, 1.0f);
    const char *full = tu_fmt("%s/full.exr", tu_dir);
    TU_OK(btf_image_write_exr_opts(full, &a, NULL, NULL, &e), &e);
    btf_image_free(&a);
    size_t n;
    unsigned char *d = slurp(full, &n);
    const char *cut = tu_fmt("%s/cut.exr", tu_dir);
    /* Every length through the header and offset table, then a spread. */
    for (size_t len = 0; len < n; len += len < 400 ? 1 : 97) {
        tu_write_file(cut, d, len);
        assert_rejected(cut);
    }
    tu_write_file(cut, d, n - 1);
    assert_rejected(cut);
    free(d);
}

static void corrupt_bytes(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image a, b;
    random_image(&a, 40, 40, 3, 8, 0.0f, 1.0f);
    const char *full = tu_fmt("%s/good.exr", tu_dir), *bad = tu_fmt("%s/bad.exr", tu_dir);
    TU_OK(btf_image_write_exr_opts(full, &a, &(btf_exr_opts){.half = 1}, NULL, &e), &e);
    btf_image_free(&a);
    size_t n;
    unsigned char *d = slurp(full, &n);
    unsigned char *m = malloc(n);
    assert_non_null(m);
    uint32_t s = 12345;
    /* Flipped bytes anywhere: any outcome but a crash, a leak or a partial
     * image (decoding may succeed when only pixel data changed). */
    for (int round = 0; round < 300; round++) {
        memcpy(m, d, n);
        int flips = 1 + (int)(rng_next(&s) % 4);
        for (int f = 0; f < flips; f++)
            m[rng_next(&s) % n] ^= (unsigned char)(1 + rng_next(&s) % 255);
        tu_write_file(bad, m, n);
        int rc = btf__exr_read(bad, 0, &b, &e);
        if (rc == 0) {
            assert_int_equal(b.width, 40);
            btf_image_free(&b);
        } else {
            assert_null(b.data);
            assert_int_equal(strncmp(e.msg, bad, strlen(bad)), 0);
        }
        btf_image_header hd;
        btf__exr_probe(bad, &hd, &e);
    }
    free(m);
    free(d);
}

static void garbage_and_missing(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image b;
    btf_image_header hd;
    const char *p = tu_fmt("%s/garbage.exr", tu_dir);
    unsigned char buf[4096];
    uint32_t s = 777;
    for (int round = 0; round < 50; round++) {
        size_t n = 1 + rng_next(&s) % sizeof buf;
        for (size_t i = 0; i < n; i++)
            buf[i] = (unsigned char)rng_next(&s);
        if (round % 2) /* the EXR magic number and version, then garbage */
            memcpy(buf, "\x76\x2f\x31\x01\x02\x00\x00\x00", n < 8 ? n : 8);
        tu_write_file(p, buf, n);
        assert_rejected(p);
    }
    tu_write_file(p, "", 0);
    assert_rejected(p);

    const char *missing = tu_fmt("%s/missing.exr", tu_dir);
    assert_int_equal(btf__exr_read(missing, 0, &b, &e), BTF_E_IO);
    assert_null(b.data);
    assert_non_null(strstr(e.msg, missing));
    assert_int_equal(btf__exr_probe(missing, &hd, &e), BTF_E_IO);
    /* A folder is not a file. */
    assert_int_equal(btf__exr_read(tu_dir, 0, &b, &e), BTF_E_IO);
    assert_int_equal(btf__exr_read(NULL, 0, &b, &e), BTF_E_ARG);
}

/* Rewrites the data window of an EXR file in place. */
static void patch_data_window(const char *path, int x0, int y0, int x1, int y1)
{
    size_t n;
    unsigned char *d = slurp(path, &n);
    static const char key[] = "dataWindow\0box2i\0\20\0\0\0";
    unsigned char *at = memmem(d, n, key, sizeof key - 1);
    assert_non_null(at);
    int32_t v[4] = {x0, y0, x1, y1};
    for (int k = 0; k < 4; k++)
        for (int b = 0; b < 4; b++)
            at[sizeof key - 1 + 4 * k + b] = (unsigned char)((uint32_t)v[k] >> (8 * b));
    tu_write_file(path, d, n);
    free(d);
}

/* Headers that claim huge images are refused before anything is allocated
 * for them (this runs under ASan, which would abort on a 48 GB calloc). */
static void absurd_sizes(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image a;
    const char *p = tu_fmt("%s/huge.exr", tu_dir);
    const int windows[][4] = {
        {0, 0, 69999, 15},              /* wider than 65536 */
        {0, 0, 15, 65536},              /* 65537 rows */
        {0, 0, 65535, 65535},           /* allowed size, but 4096 chunks */
        {-2147483647, 0, 2147483647, 15}, /* overflowing width */
        {5, 5, 4, 20},                  /* empty */
    };
    for (int i = 0; i < 5; i++) {
        half_exact_image(&a, 16, 16, 1, 3);
        TU_OK(btf_image_write_exr_opts(p, &a, &(btf_exr_opts){.half = 1}, NULL, &e), &e);
        btf_image_free(&a);
        patch_data_window(p, windows[i][0], windows[i][1], windows[i][2], windows[i][3]);
        assert_rejected(p);
    }
}

/* OpenEXR must report through btf_error, never on stderr. */
static void library_is_silent(void **state)
{
    (void)state;
    const char *errpath = tu_fmt("%s/stderr.txt", tu_dir);
    const char *p = tu_fmt("%s/noisy.exr", tu_dir);
    fflush(stderr);
    int saved = dup(2);
    assert_true(saved >= 0);
    int fd = open(errpath, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    assert_true(fd >= 0);
    assert_true(dup2(fd, 2) >= 0);
    close(fd);

    btf_error e = {0};
    btf_image a, b;
    random_image(&a, 30, 30, 3, 4, 0.0f, 1.0f);
    int rc1 = btf_image_write_exr_opts(p, &a, NULL, NULL, &e);
    size_t n = 0;
    unsigned char *d = rc1 ? NULL : slurp(p, &n);
    int rc2 = BTF_OK, rc3 = BTF_OK, rc4 = BTF_OK, rc5 = BTF_OK;
    if (d) {
        tu_write_file(p, d, n / 2);
        rc2 = btf__exr_read(p, 0, &b, &e);
        rc3 = btf__exr_probe(p, &(btf_image_header){0}, &e);
        memset(d + 8, 0x7f, n - 8);
        tu_write_file(p, d, n);
        rc4 = btf__exr_read(p, 0, &b, &e);
    }
    rc5 = btf_image_write_exr_opts(tu_fmt("%s/no/such/folder.exr", tu_dir), &a,
                                   &(btf_exr_opts){.half = 1}, NULL, &e);
    fflush(stderr);
    dup2(saved, 2);
    close(saved);
    free(d);
    btf_image_free(&a);

    assert_int_equal(rc1, 0);
    assert_true(rc2 != 0 && rc3 != 0 && rc4 != 0 && rc5 != 0);
    size_t m;
    unsigned char *text = slurp(errpath, &m);
    if (m)
        print_error("unexpected stderr: %.*s\n", (int)m, (const char *)text);
    assert_int_equal(m, 0);
    free(text);
}

/* ------------------------------------------------------------ provenance */

static exr_context_t open_exr(const char *path)
{
    exr_context_t ctx = NULL;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    assert_int_equal(exr_start_read(&ctx, path, &init), EXR_ERR_SUCCESS);
    return ctx;
}

static void assert_same_pixels(const char *p1, const char *p2)
{
    btf_error e = {0};
    btf_image a, b;
    TU_OK(btf__exr_read(p1, 0, &a, &e), &e);
    TU_OK(btf__exr_read(p2, 0, &b, &e), &e);
    assert_int_equal(a.width, b.width);
    assert_int_equal(a.height, b.height);
    assert_int_equal(a.channels, b.channels);
    assert_memory_equal(a.data, b.data, (size_t)a.width * a.height * a.channels * sizeof(float));
    btf_image_free(&a);
    btf_image_free(&b);
}

static void provenance_attributes(void **state)
{
    (void)state;
    btf_error e = {0};
    char d[1024];
    fresh_dir(d, sizeof d, "meta");
    btf_exr_meta meta = {.model = "models/leather.btfcar", .seed = UINT64_MAX, .subspace = 7,
                         .has_dirs = 1, .view = {30, 45}, .light = {75, 352.5}};
    for (int half = 0; half <= 1; half++)
        for (int c = 1; c <= 3; c += 2) {
            btf_image a;
            random_image(&a, 21, 35, c, 5 + half + c, -2.0f, 2.0f);
            const char *plain = tu_fmt("%s/plain.exr", d), *with = tu_fmt("%s/meta.exr", d);
            const char *stream = tu_fmt("%s/stream.exr", d);
            TU_OK(btf_image_write_exr_opts(plain, &a, &(btf_exr_opts){.half = half}, NULL, &e), &e);
            TU_OK(btf_image_write_exr_opts(with, &a, &(btf_exr_opts){.half = half}, &meta, &e), &e);
            btf_exr_writer *w = NULL;
            TU_OK(btf_exr_writer_open_opts(stream, a.width, a.height, c,
                                           &(btf_exr_opts){.half = half}, &meta, &w, &e),
                  &e);
            TU_OK(btf_exr_writer_put_rows(w, a.data, a.height, &e), &e);
            TU_OK(btf_exr_writer_close(w, &e), &e);

            exr_context_t ctx = open_exr(with);
            assert_string_equal(tu_exr_string(ctx, "btfcarVersion"), BTF_VERSION_STRING);
            assert_string_equal(tu_exr_string(ctx, "btfcarModel"), "models/leather.btfcar");
            assert_string_equal(tu_exr_string(ctx, "btfcarSeed"), "18446744073709551615");
            assert_string_equal(tu_exr_string(ctx, "btfcarSubspace"), "7");
            assert_string_equal(tu_exr_string(ctx, "btfcarView"), "30 45");
            assert_string_equal(tu_exr_string(ctx, "btfcarLight"), "75 352.5");
            exr_attr_chromaticities_t ch;
            assert_int_equal(exr_attr_get_chromaticities(ctx, 0, "chromaticities", &ch),
                             EXR_ERR_SUCCESS);
            assert_true(ch.red_x == 0.64f && ch.red_y == 0.33f);
            assert_true(ch.green_x == 0.30f && ch.green_y == 0.60f);
            assert_true(ch.blue_x == 0.15f && ch.blue_y == 0.06f);
            assert_true(ch.white_x == 0.3127f && ch.white_y == 0.3290f);
            exr_finish(&ctx);

            /* Without metadata: none of it. */
            ctx = open_exr(plain);
            assert_null(tu_exr_string(ctx, "btfcarVersion"));
            assert_null(tu_exr_string(ctx, "btfcarModel"));
            assert_int_not_equal(exr_attr_get_chromaticities(ctx, 0, "chromaticities", &ch),
                                 EXR_ERR_SUCCESS);
            exr_finish(&ctx);

            /* The header changes, the pixels do not; streaming gives the
             * same file as the one-shot writer. */
            assert_same_pixels(plain, with);
            size_t n1, n2;
            unsigned char *d1 = slurp(with, &n1), *d2 = slurp(stream, &n2);
            assert_int_equal(n1, n2);
            assert_memory_equal(d1, d2, n1);
            free(d1);
            free(d2);
            btf_image_free(&a);
        }

    /* A model without directions, and provenance without a model. */
    btf_image a;
    random_image(&a, 4, 4, 3, 11, 0.0f, 1.0f);
    const char *p = tu_fmt("%s/partial.exr", d);
    btf_exr_meta some = {.model = "m.btfcar", .seed = 0, .subspace = 0};
    TU_OK(btf_image_write_exr_opts(p, &a, &(btf_exr_opts){.half = 1}, &some, &e), &e);
    exr_context_t ctx = open_exr(p);
    assert_string_equal(tu_exr_string(ctx, "btfcarSeed"), "0");
    assert_string_equal(tu_exr_string(ctx, "btfcarSubspace"), "0");
    assert_null(tu_exr_string(ctx, "btfcarView"));
    assert_null(tu_exr_string(ctx, "btfcarLight"));
    exr_finish(&ctx);
    btf_exr_meta none = {0};
    TU_OK(btf_image_write_exr_opts(p, &a, &(btf_exr_opts){.half = 1}, &none, &e), &e);
    ctx = open_exr(p);
    assert_string_equal(tu_exr_string(ctx, "btfcarVersion"), BTF_VERSION_STRING);
    assert_null(tu_exr_string(ctx, "btfcarModel"));
    assert_null(tu_exr_string(ctx, "btfcarSeed"));
    exr_finish(&ctx);
    btf_image_free(&a);
    remove(p);
}

/* ------------------------------------------------------ reading from memory */

static void decode_from_memory(void **state)
{
    (void)state;
    btf_error e = {0};
    char d[1024];
    fresh_dir(d, sizeof d, "memory");
    btf_image a, b, c;
    random_image(&a, 19, 40, 3, 21, -1.0f, 4.0f);
    const char *p = tu_fmt("%s/m.exr", d);
    TU_OK(btf_image_write_exr_opts(p, &a, NULL, NULL, &e), &e);
    size_t n;
    unsigned char *bytes = slurp(p, &n);
    for (int ch = 0; ch <= 3; ch += ch ? 2 : 1) {
        btf_read_opts ro = {.channels = ch};
        TU_OK(btf_image_read(p, &ro, &b, &e), &e);
        TU_OK(btf_image_decode(bytes, n, "buffer", &ro, &c, &e), &e);
        assert_same_image(&b, &c);
        btf_image_free(&b);
        btf_image_free(&c);
    }
    btf_image_header h1, h2;
    TU_OK(btf_image_probe(p, &h1, &e), &e);
    TU_OK(btf_image_probe_memory(bytes, n, "buffer", &h2, &e), &e);
    assert_memory_equal(&h1, &h2, sizeof h1);
    /* Damage is reported under the caller's name, like a file's. */
    for (size_t cut = 0; cut < n; cut += n / 7 + 1) {
        int rc = btf_image_decode(bytes, cut, "cut-buffer", NULL, &c, &e);
        assert_true(rc == BTF_E_FORMAT);
        assert_true(strncmp(e.msg, "cut-buffer: ", 12) == 0);
        assert_null(c.data);
    }
    assert_int_equal(btf_image_decode(NULL, 0, NULL, NULL, &c, &e), BTF_E_FORMAT);
    assert_true(strncmp(e.msg, "image: ", 7) == 0);
    free(bytes);
    btf_image_free(&a);
    remove(p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(round_trip_sizes),
        cmocka_unit_test(half_rounds_to_nearest),
        cmocka_unit_test(extreme_values),
        cmocka_unit_test(channel_conversion),
        cmocka_unit_test(streaming_equals_one_shot),
        cmocka_unit_test(writer_options),
        cmocka_unit_test(fast_pack_is_the_library_s),
        cmocka_unit_test(writer_closed_early),
        cmocka_unit_test(writer_misuse),
        cmocka_unit_test(non_finite_input_refused),
        cmocka_unit_test(writes_are_atomic),
        cmocka_unit_test(inf_and_nan_in_file),
        cmocka_unit_test(other_layouts),
        cmocka_unit_test(every_compression),
        cmocka_unit_test(dwa_is_unsupported),
        cmocka_unit_test(deep_is_unsupported),
        cmocka_unit_test(unsupported_layouts),
        cmocka_unit_test(truncated_files),
        cmocka_unit_test(corrupt_bytes),
        cmocka_unit_test(garbage_and_missing),
        cmocka_unit_test(absurd_sizes),
        cmocka_unit_test(library_is_silent),
        cmocka_unit_test(provenance_attributes),
        cmocka_unit_test(decode_from_memory),
    };
    return cmocka_run_group_tests(tests, tu_setup_dir, tu_teardown_dir);
}
