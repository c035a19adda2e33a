/*
 * test_btf_file.c — Bonn .btf files (src/dataset/ubo_*.c; docs/datasets.md,
 * "UBO2014 .btf files"): DFMF and BDIF written and read back through the
 * dataset interface, the colour models, every bad input (signature,
 * truncation at many offsets, counts that do not fit, NaN factors, an
 * unsupported colour model), bounded memory, the CLI (info, export), and
 * a file of the database's published shape and length (400^2, 151 x 151,
 * 78 + 76 + 74 half components: 83,542,344 bytes, written sparse).
 */
#include "testutil.h"
#include "dataset/ubo2014.h"
#include "core/core.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <fcntl.h>
#include <unistd.h>

/* The small set of testutil.h: 3 views x 4 lights of 8 x 6 pixels. */
static const int W = TU_SMALL_W, H = TU_SMALL_H;

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
        assert_true(btf_dir_angle(in->views->dirs[i], tu_small_views.dirs[i]) < 1e-4);
    for (int i = 0; i < 4; i++)
        assert_true(btf_dir_angle(in->lights->dirs[i], tu_small_lights.dirs[i]) < 1e-4);
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
                    double d = fabs(s->image.data[(y * W + x) * 3 + c] -
                                    tu_small_value(s->view, s->light, x, y, c));
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
    int rc = btf_ubo2014_write(p, &tu_small_views, &tu_small_lights, W, H, tu_small_image, NULL, &o,
                               &st, &err);
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
        int rc = btf_ubo2014_write(p, &tu_small_views, &tu_small_lights, W, H, tu_small_image, NULL,
                                   &o, &st, &err);
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

/* The small DFMF (half) file's bytes, written once. */
static unsigned char *dfmf_bytes(size_t *n, int variant)
{
    const char *p = tu_fmt("%s/bytes_%d.btf", tu_dir, variant);
    btf_ubo2014_write_opts o = btf_ubo2014_write_defaults();
    o.variant = variant;
    o.components = 5;
    assert_int_equal(btf_ubo2014_write(p, &tu_small_views, &tu_small_lights, W, H, tu_small_image,
                                       NULL, &o, NULL, NULL), 0);
    return tu_slurp(p, n);
}

static void test_truncated_everywhere(void **state)
{
    (void)state;
    for (int variant = 0; variant < 2; variant++) {
        size_t n;
        unsigned char *d = dfmf_bytes(&n, variant);
        /* every offset of the header, then a stride through the data */
        for (size_t cut = 1; cut < n; cut += cut < 1200 ? 1 : 97) {
            ubo_file f;
            btf_error err = {0};
            int rc = ubo_parse(d, cut, "cut", 0, &f, &err);
            assert_int_not_equal(rc, 0);
            assert_non_null(strstr(err.msg, "cut"));
            ubo_free(&f);
        }
        tu_expect_open_fails(d, n - 1, "truncated", BTF_E_FORMAT);
        tu_expect_open_fails(d, 12, "truncated", BTF_E_FORMAT);
        /* one byte too many */
        unsigned char *e = malloc(n + 1);
        memcpy(e, d, n);
        e[n] = 0;
        tu_expect_open_fails(e, n + 1, "after the end", BTF_E_FORMAT);
        free(e);
        free(d);
    }
}

static void test_bad_signature_and_counts(void **state)
{
    (void)state;
    size_t n;
    unsigned char *d = dfmf_bytes(&n, 0);
    unsigned char *e = malloc(n);
    /* unknown signatures */
    memcpy(e, d, n);
    memcpy(e, "!DFMF09FCR", 10);
    tu_expect_open_fails(e, n, "unknown signature", BTF_E_FORMAT);
    memcpy(e, d, n);
    memcpy(e, "!BDIF06R3!", 10);
    tu_expect_open_fails(e, n, "unknown signature", BTF_E_FORMAT);
    /* meta_size that lies */
    memcpy(e, d, n);
    e[10] ^= 1;
    tu_expect_open_fails(e, n, "meta_size", BTF_E_FORMAT);
    /* the sampling: nV at 10 + meta_size */
    uint32_t meta = ubo_rd32(d + 10);
    size_t nv_at = 10 + meta;
    memcpy(e, d, n);
    e[nv_at + 3] = 0x7f; /* 2^30 views */
    tu_expect_open_fails(e, n, "views do not fit", BTF_E_FORMAT);
    memcpy(e, d, n);
    e[nv_at + 12] = 0xff; /* view 0's light count */
    tu_expect_open_fails(e, n, NULL, BTF_E_FORMAT);
    /* the second view's light count differs */
    memcpy(e, d, n);
    size_t v1 = nv_at + 4 + 12 + 4 * 8;
    e[v1 + 8] = 3;
    tu_expect_open_fails(e, n, "lights, view 0 has", BTF_E_FORMAT);
    /* a NaN theta */
    memcpy(e, d, n);
    e[nv_at + 4 + 2] = 0xc0, e[nv_at + 4 + 3] = 0x7f;
    tu_expect_open_fails(e, n, "theta", BTF_E_FORMAT);
    /* width: after 3 views of (12 + 4 * 8) bytes */
    size_t w_at = nv_at + 4 + 3 * (12 + 32);
    memcpy(e, d, n);
    e[w_at] = 9;
    tu_expect_open_fails(e, n, "channel 0 is", BTF_E_FORMAT);
    memcpy(e, d, n);
    memset(e + w_at, 0, 4);
    tu_expect_open_fails(e, n, "image size", BTF_E_FORMAT);
    /* DFMF body: rotations (4), num_components (4), model (4) */
    size_t model_at = w_at + 8 + 4 + 4;
    memcpy(e, d, n);
    e[model_at] = 2;
    tu_expect_open_fails(e, n, "colour model 2 not supported", BTF_E_UNSUPPORTED);
    memcpy(e, d, n);
    e[model_at] = 77;
    tu_expect_open_fails(e, n, "colour model 77 not supported", BTF_E_UNSUPPORTED);
    /* channel 0: scalar size, K */
    size_t ch0 = model_at + 4 + 12 + 36;
    memcpy(e, d, n);
    e[ch0] = 3;
    tu_expect_open_fails(e, n, "scalar size 3", BTF_E_FORMAT);
    memcpy(e, d, n);
    e[ch0 + 4] = 0xff; /* K huge */
    tu_expect_open_fails(e, n, "does not fit", BTF_E_FORMAT);
    memcpy(e, d, n);
    memset(e + ch0 + 1, 0, 4); /* K = 0 */
    tu_expect_open_fails(e, n, "0 components", BTF_E_FORMAT);
    /* a NaN in U (after S): half 0x7e00, at row 1, component 1 */
    uint32_t k = ubo_rd32(d + ch0 + 1);
    assert_true(k >= 2 && k <= 5);
    size_t u0 = ch0 + 13 + 2 * k;
    memcpy(e, d, n);
    e[u0 + 2 * (k + 1)] = 0x00, e[u0 + 2 * (k + 1) + 1] = 0x7e;
    tu_expect_open_fails(e, n, "U of channel R/0 has a NaN or Inf at row 1, component 1",
                         BTF_E_DATA);
    /* an Inf in SxV of channel 0 */
    size_t sxv0 = u0 + 2 * k * 12;
    memcpy(e, d, n);
    e[sxv0 + 1] = 0x7c, e[sxv0] = 0;
    tu_expect_open_fails(e, n, "SxV of channel R/0 has a NaN or Inf", BTF_E_DATA);
    /* not a .btf at all: a text file that starts like one is still checked */
    tu_expect_open_fails((const unsigned char *)"!DFMF", 5, NULL, 0);
    free(e);
    free(d);
}

/* Colour model 11 (Ylog_UdivY_VdivY) and the cosine flag, exactly as the
 * notes' §3b and §3c give them, from factors of one component. */
static void test_colour_model_11(void **state)
{
    (void)state;
    int n = 12, px = W * H;
    float *u[3], *sxv[3];
    for (int c = 0; c < 3; c++) {
        u[c] = malloc((size_t)n * sizeof(float));
        sxv[c] = malloc((size_t)px * sizeof(float));
        for (int i = 0; i < n; i++)
            u[c][i] = 0.5f + 0.25f * (float)((i + c) % 4);
        for (int i = 0; i < px; i++)
            sxv[c][i] = c == 0 ? -1.0f + 0.03125f * (float)i : 0.0625f * (float)(c == 1 ? 1 : -1);
    }
    for (int cosine = 0; cosine < 2; cosine++) {
        btf_ubo2014_factors f = {.colour_model = 11, .cosine_flag = cosine, .scalar_size = 4,
                                 .components = {1, 1, 1}, .u = {u[0], u[1], u[2]},
                                 .sxv = {sxv[0], sxv[1], sxv[2]}};
        const char *p = tu_fmt("%s/m11_%d.btf", tu_dir, cosine);
        btf_error err = {0};
        assert_int_equal(btf__ubo2014_write_factors(p, &tu_small_views, &tu_small_lights, W, H, &f,
                                                    &err), 0);
        btf_dataset *ds;
        assert_int_equal(btf_dataset_open(p, NULL, &ds, &err), 0);
        assert_int_equal(btf_dataset_ubo2014(ds)->colour_model, 11);
        for (int v = 0; v < 3; v++)
            for (int l = 0; l < 4; l++) {
                btf_image img = {0};
                assert_int_equal(btf_dataset_read(ds, v, l, &img, &err), 0);
                int lv = v * 4 + l;
                double cl = cos((double)(float)(tu_small_lights.dirs[l].theta *
                                                3.14159265358979323846 / 180.0));
                for (int i = 0; i < px; i++) {
                    double d0 = (double)(u[0][lv] * sxv[0][i]), d1 = (double)(u[1][lv] * sxv[1][i]),
                           d2 = (double)(u[2][lv] * sxv[2][i]);
                    double y = exp(d0) - 1e-5, uu = d1 * exp(d0), vv = d2 * exp(d0);
                    double rgb[3] = {y + 1.13983 * vv, y - 0.39465 * uu - 0.5806 * vv,
                                     y + 2.03211 * uu};
                    for (int c = 0; c < 3; c++) {
                        double want = cosine ? rgb[c] / cl : rgb[c];
                        assert_true(fabs(img.data[3 * i + c] - want) <= 2e-6 * fmax(1, fabs(want)));
                    }
                }
                btf_image_free(&img);
            }
        btf_dataset_close(ds);
    }
    for (int c = 0; c < 3; c++) {
        free(u[c]);
        free(sxv[c]);
    }
}

static long rss_anon_kb(void)
{
    FILE *f = fopen("/proc/self/status", "r");
    char line[256];
    long kb = -1;
    while (f && fgets(line, sizeof line, f))
        if (sscanf(line, "RssAnon: %ld", &kb) == 1)
            break;
    if (f)
        fclose(f);
    return kb;
}

/* Reading every image of a 50 MB DFMF file keeps the heap at a few images:
 * the factors stay in the mapping. */
static void test_memory_bounded(void **state)
{
    (void)state;
    btf_dirset d81, all81;
    assert_int_equal(btf_dirset_ubo81(&all81, NULL), 0);
    assert_int_equal(btf_dirset_from_list(&d81, all81.dirs, 9, NULL), 0);
    btf_dirset_free(&all81);
    int w = 512, h = 512, k = 32, n = 81, px = w * h;
    float *u[3], *sxv[3];
    for (int c = 0; c < 3; c++) {
        u[c] = malloc((size_t)n * k * sizeof(float));
        sxv[c] = malloc((size_t)px * k * sizeof(float));
        for (int i = 0; i < n * k; i++)
            u[c][i] = (float)((i * 7 + c) % 13) / 13.0f;
        for (int i = 0; i < px * k; i++)
            sxv[c][i] = (float)((i * 5 + c) % 11) / 110.0f;
    }
    btf_ubo2014_factors f = {.components = {k, k, k}, .scalar_size = 2,
                             .u = {u[0], u[1], u[2]}, .sxv = {sxv[0], sxv[1], sxv[2]}};
    const char *p = tu_fmt("%s/big.btf", tu_dir);
    assert_int_equal(btf__ubo2014_write_factors(p, &d81, &d81, w, h, &f, NULL), 0);
    for (int c = 0; c < 3; c++) {
        free(u[c]);
        free(sxv[c]);
    }
    btf_dirset_free(&d81);
    long before = rss_anon_kb();
    btf_dataset *ds;
    btf_error err = {0};
    assert_int_equal(btf_dataset_open(p, NULL, &ds, &err), 0);
    const btf_ubo2014_info *in = btf_dataset_ubo2014(ds);
    assert_true(in->data_bytes > 50000000ull); /* (81 + 262144) x 32 x 2 bytes x 3 */
    btf_dataset_iter it;
    btf_dataset_iter_begin(&it, ds);
    int rc, count = 0;
    long peak = before;
    while ((rc = btf_dataset_iter_next(&it, &err)) == 1)
        if (++count % 8 == 0)
            peak = fmax(peak, rss_anon_kb());
    btf_dataset_iter_end(&it);
    assert_int_equal(rc, 0);
    assert_int_equal(count, n);
    unsigned long long data_bytes = in->data_bytes; /* in lives as long as ds */
    btf_dataset_close(ds);
    print_message("heap (RssAnon) %ld kB before, %ld kB peak while reading %d images of a %llu-byte "
                  "factor file\n", before, peak, count, data_bytes);
    assert_true(before > 0);
    /* Under ASan freed blocks wait in its quarantine (256 MB), so the heap
     * grows with every image read: the bound means nothing there. */
    if (!getenv("BTF_ASAN"))
        assert_true(peak - before < 16 * 1024); /* < 16 MB: a few 3 MB images, not the 50 MB */
}

static void test_cli_info_export(void **state)
{
    (void)state;
    char p[4096];
    snprintf(p, sizeof p, "%s/cli.btf", tu_dir);
    btf_ubo2014_write_opts o = btf_ubo2014_write_defaults();
    o.components = 4;
    assert_int_equal(btf_ubo2014_write(p, &tu_small_views, &tu_small_lights, W, H, tu_small_image,
                                       NULL, &o, NULL, NULL), 0);
    int st;
    char *out = tu_capture(tu_fmt("%s info %s", tu_cli(), p), &st);
    assert_int_equal(st, 0);
    assert_non_null(strstr(out, "layout      UBO2014"));
    assert_non_null(strstr(out, "12 (3 views x 4 lights)"));
    assert_non_null(strstr(out, "DFMF (!DFMF08FCR)"));
    assert_non_null(strstr(out, "components  R "));
    assert_non_null(strstr(out, "colour      model 0"));
    free(out);
    out = tu_capture(tu_fmt("%s info --json %s", tu_cli(), p), &st);
    assert_int_equal(st, 0);
    assert_non_null(strstr(out, "\"variant\": \"DFMF\""));
    free(out);
    /* export one pair: the read-back image */
    const char *img = tu_fmt("%s/one.exr", tu_dir);
    assert_int_equal(tu_run(tu_fmt("%s export -q %s --view 30,90 --light 45,180 -o %s", tu_cli(), p,
                                   img), NULL), 0);
    btf_image a = {0}, b = {0};
    assert_int_equal(btf_image_read(img, NULL, &a, NULL), 0);
    btf_dataset *ds;
    assert_int_equal(btf_dataset_open(p, NULL, &ds, NULL), 0);
    assert_int_equal(btf_dataset_read(ds, 1, 2, &b, NULL), 0);
    assert_int_equal(a.width, W);
    assert_memory_equal(a.data, b.data, sizeof(float) * W * H * 3);
    btf_image_free(&a);
    btf_image_free(&b);
    /* export all: a UTIA dataset of the same directions */
    char dir[4096];
    snprintf(dir, sizeof dir, "%s/all", tu_dir);
    assert_int_equal(tu_run(tu_fmt("%s export -q %s --all -o %s", tu_cli(), p, dir), NULL), 0);
    assert_int_equal(tu_count_files(dir), 12);
    btf_dataset *utia;
    assert_int_equal(btf_dataset_open(dir, NULL, &utia, NULL), 0);
    assert_int_equal(btf_dataset_get_info(utia)->layout, BTF_LAYOUT_UTIA);
    assert_int_equal(btf_dataset_get_info(utia)->n_lights, 4);
    btf_dataset_close(utia);
    btf_dataset_close(ds);
    /* photometric stereo reads the pairs through the dataset (no file per image) */
    assert_int_equal(tu_run(tu_fmt("%s photostereo -q %s -o %s/ps", tu_cli(), p, tu_dir), NULL), 0);
    assert_true(tu_count_files(tu_fmt("%s/ps", tu_dir)) >= 3);
    /* no such direction; bad input through the CLI */
    char *msg = NULL;
    st = tu_run(tu_fmt("%s export %s --view 10,10 --light 0,0 -o %s/x.png", tu_cli(), p, tu_dir), &msg);
    assert_int_equal(st, 1);
    assert_non_null(strstr(msg, "no view direction"));
    free(msg);
    char bad[4096];
    snprintf(bad, sizeof bad, "%s/trunc.btf", tu_dir);
    size_t n;
    unsigned char *d = tu_slurp(p, &n);
    tu_write_file(bad, d, n / 2);
    free(d);
    st = tu_run(tu_fmt("%s info %s", tu_cli(), bad), &msg);
    assert_int_equal(st, 1);
    assert_non_null(strstr(msg, "trunc.btf: truncated"));
    assert_null(strchr(msg, '\n') == msg + strlen(msg) - 1 ? NULL : "one line");
    free(msg);
    st = tu_run(tu_fmt("%s analyse %s -o %s/m.btfcar", tu_cli(), bad, tu_dir), &msg);
    assert_int_equal(st, 1);
    assert_non_null(strstr(msg, "truncated"));
    free(msg);
}

/* generate --format btf and its UBO2003 twin: the same images. The twin's
 * JPEGs are lossy; the .btf of full rank (64 components of 8 x 8 images)
 * stores them up to half rounding, so against the exact renders the .btf
 * is far closer than the twin, and the two differ by the JPEG's error. */
static void test_generate_twin(void **state)
{
    (void)state;
    char p[4096], twin[4096];
    snprintf(p, sizeof p, "%s/gen.btf", tu_dir);
    snprintf(twin, sizeof twin, "%s/twin", tu_dir);
    char *msg = NULL;
    assert_int_equal(tu_run(tu_fmt("%s generate --material fabric --size 8 --seed 3 --format btf "
                                   "--components 64 %s", tu_cli(), p), &msg), 0);
    assert_non_null(strstr(msg, "error of the stored values"));
    free(msg);
    assert_int_equal(tu_run(tu_fmt("%s generate -q --material fabric --size 8 --seed 3 %s",
                                   tu_cli(), twin), NULL), 0);
    btf_dataset *a, *b;
    assert_int_equal(btf_dataset_open(p, NULL, &a, NULL), 0);
    assert_int_equal(btf_dataset_open(twin, NULL, &b, NULL), 0);
    const btf_dataset_info *ia = btf_dataset_get_info(a), *ib = btf_dataset_get_info(b);
    assert_int_equal(ia->n_views, ib->n_views);
    assert_string_equal(ia->views->name, "ubo81");
    double btf_err = 0, jpeg_err = 0, between = 0, btf_max = 0;
    long cnt = 0;
    for (int v = 0; v < 81; v += 7)
        for (int l = 0; l < 81; l += 5) {
            btf_image x = {0}, y = {0}, t = {0};
            assert_int_equal(btf_dataset_read(a, v, l, &x, NULL), 0);
            assert_int_equal(btf_dataset_read(b, v, l, &y, NULL), 0);
            tu_material_image("fabric", 8, 3, ia->views->dirs[v], ia->lights->dirs[l], &t);
            for (int i = 0; i < 8 * 8 * 3; i++, cnt++) {
                double tx = btf__linear_to_srgb(fminf(1, t.data[i]));
                btf_err += fabs(btf__linear_to_srgb(fmaxf(0, fminf(1, x.data[i]))) - tx);
                jpeg_err += fabs(btf__linear_to_srgb(y.data[i]) - tx);
                between += fabs(btf__linear_to_srgb(fmaxf(0, fminf(1, x.data[i]))) -
                                btf__linear_to_srgb(y.data[i]));
                btf_max = fmax(btf_max, fabs(x.data[i] - t.data[i]));
            }
            btf_image_free(&x);
            btf_image_free(&y);
            btf_image_free(&t);
        }
    print_message("generate --format btf vs exact: mean %.5f (max linear %.2g); UBO2003 twin vs "
                  "exact %.5f; btf vs twin %.5f (sRGB)\n", btf_err / cnt, btf_max, jpeg_err / cnt,
                  between / cnt);
    assert_true(btf_max < 2e-3);
    assert_true(btf_err < 0.1 * jpeg_err);
    assert_true(between <= jpeg_err + btf_err);
    btf_dataset_close(a);
    btf_dataset_close(b);
}

/* Opening path fails with BTF_E_FORMAT and one line naming the file that
 * contains each of the strings given (NULL-terminated). */
static void expect_refused(const char *path, ...)
{
    btf_error err = {0};
    btf_dataset *ds = NULL;
    int rc = btf_dataset_open(path, NULL, &ds, &err);
    assert_int_equal(rc, BTF_E_FORMAT);
    assert_null(ds);
    print_message("%s\n", err.msg);
    assert_non_null(strstr(err.msg, path));
    assert_null(strchr(err.msg, '\n'));
    va_list ap;
    va_start(ap, path);
    for (const char *w; (w = va_arg(ap, const char *)) != NULL;) {
        if (!strstr(err.msg, w))
            print_error("message \"%s\" lacks \"%s\"\n", err.msg, w);
        assert_non_null(strstr(err.msg, w));
    }
    va_end(ap);
}

/* A file of the Bonn database's published shape (docs/datasets.md,
 * "UBO2014 .btf files"): 400 x 400 texels, the 151 x 151 directions, DFMF
 * half floats with 78, 76 and 74 components per channel (228 in all, what
 * the published sizes of 82.9 to 84.3 MB imply), colour model 11. Its
 * length is exactly header 184,593 + 3 x 13 + 2 x 228 x (1 + 22,801 +
 * 160,000) = 83,542,344 bytes. Only the header and the channels' 13-byte
 * headers are written; the factors are a hole (zeros, finite) of a sparse
 * file, which the reader maps. It opens and decodes; one byte shorter or
 * longer it is refused with one line naming the file and the length its
 * header implies. */
static void test_bonn_shape_length(void **state)
{
    (void)state;
    btf_dirset d;
    assert_int_equal(btf__dirset_ubo151(&d, NULL), 0);
    assert_int_equal(d.count, 151);
    const int side = 400, k[3] = {78, 76, 74};
    const uint32_t pairs = 151 * 151, px = 400 * 400;
    ubo_bytes h = {0};
    ubo_common_header(&h, "!DFMF08FCR", &d, &d, side, side, 0);
    ubo_put_u32(&h, 0);  /* num_rotations */
    ubo_put_u32(&h, 78); /* num_components: the largest */
    ubo_put_u32(&h, 11); /* colour model 11, Ylog_UdivY_VdivY */
    for (int i = 0; i < 3; i++)
        ubo_put_f32(&h, 0.0f);
    for (int i = 0; i < 9; i++)
        ubo_put_f32(&h, i % 4 == 0 ? 1.0f : 0.0f);
    btf_dirset_free(&d);
    assert_int_equal(ubo_bytes_check(&h, "header", NULL), 0);
    /* signature 10, meta block 291, sampling 4 + 151 x (12 + 151 x 8),
     * width and height 8, rotations 4, DFMF fields 56 */
    assert_int_equal(h.n, 184593);
    char p[4096];
    snprintf(p, sizeof p, "%s/bonn_400_151.btf", tu_dir);
    int fd = open(p, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    assert_true(fd >= 0);
    assert_int_equal(pwrite(fd, h.p, h.n, 0), (ssize_t)h.n);
    uint64_t at = h.n;
    for (int c = 0; c < 3; c++) {
        unsigned char ch[13];
        ch[0] = 2; /* half floats */
        ubo_wr32(ch + 1, (uint32_t)k[c]);
        ubo_wr32(ch + 5, pairs);
        ubo_wr32(ch + 9, px);
        assert_int_equal(pwrite(fd, ch, 13, (off_t)at), 13);
        at += 13 + 2 * (uint64_t)k[c] * (1 + pairs + px);
    }
    free(h.p);
    const uint64_t expected = 83542344;
    assert_int_equal(at, expected);
    assert_int_equal(ftruncate(fd, (off_t)expected), 0);
    assert_int_equal(close(fd), 0);

    btf_error err = {0};
    btf_dataset *ds = NULL;
    int rc = btf_dataset_open(p, NULL, &ds, &err);
    if (rc)
        print_error("%s\n", err.msg);
    assert_int_equal(rc, 0);
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    assert_int_equal(in->layout, BTF_LAYOUT_UBO2014);
    assert_int_equal(in->n_views, 151);
    assert_int_equal(in->n_lights, 151);
    assert_int_equal(in->width, side);
    assert_int_equal(in->height, side);
    const btf_ubo2014_info *u = btf_dataset_ubo2014(ds);
    assert_string_equal(u->variant, "DFMF");
    assert_int_equal(u->scalar_size, 2);
    assert_int_equal(u->colour_model, 11);
    for (int c = 0; c < 3; c++)
        assert_int_equal(u->components[c], k[c]);
    assert_int_equal(u->file_bytes, expected);
    assert_int_equal(u->data_bytes, 2 * 228 * (uint64_t)(pairs + px));
    btf_image img = {0};
    assert_int_equal(btf_dataset_read(ds, 75, 75, &img, &err), 0);
    assert_int_equal(img.width, side);
    assert_true(isfinite(img.data[0]) && isfinite(img.data[3 * (px - 1) + 2]));
    btf_image_free(&img);
    btf_dataset_close(ds);

    assert_int_equal(truncate(p, (off_t)(expected - 1)), 0);
    expect_refused(p, "truncated", "DFMF channel 2", "expected a file of 83542344 bytes",
                   "the file has 83542343", (const char *)NULL);
    assert_int_equal(truncate(p, (off_t)(expected + 1)), 0);
    expect_refused(p, "1 byte after the end", "expected a file of 83542344 bytes",
                   "the file has 83542345", (const char *)NULL);
    /* cut inside channel 0: the later channels' sizes are not known yet */
    uint64_t ch1 = 184593 + 13 + 2 * 78 * (uint64_t)(1 + pairs + px);
    assert_int_equal(truncate(p, (off_t)(ch1 - 1)), 0);
    expect_refused(p, "truncated", "DFMF channel 0",
                   tu_fmt("expected a file of at least %llu bytes", (unsigned long long)ch1),
                   (const char *)NULL);
    unlink(p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bdif_round_trip),
        cmocka_unit_test(test_dfmf_round_trip),
        cmocka_unit_test(test_truncated_everywhere),
        cmocka_unit_test(test_bad_signature_and_counts),
        cmocka_unit_test(test_colour_model_11),
        cmocka_unit_test(test_memory_bounded),
        cmocka_unit_test(test_cli_info_export),
        cmocka_unit_test(test_generate_twin),
        cmocka_unit_test(test_bonn_shape_length),
    };
    return cmocka_run_group_tests(tests, tu_setup_small, tu_teardown_small);
}
