/*
 * test_btf_variants.c — the FMF and PVF variants of the Bonn .btf files
 * (src/dataset/ubo_parse.c, ubo_decode.c, ubo_write.c, ubo_write_pvf.c;
 * docs/datasets.md, "UBO2014 .btf files", §4, §5): each signature
 * written from images and read back within the writer's stated error; a
 * generated material in each variant against its exact renders and its
 * UBO2003 twin; every layout the reader accepts
 * (transposed FMF, K_file < K, FMF header versions 0-2 with a non-square
 * height map, the dynamic-range reduction, PVF in both orientations, the
 * legacy PVF header, scalars of 4 and 8 bytes; and the transposed DFMF)
 * from factors whose values the test computes itself; the !FMF06FC /
 * !PVF06FC hazard; what the writer refuses; and bad input
 * for each variant (truncation at many offsets, counts that do not fit,
 * NaN factors). Also writes the fuzz seeds (BTF_FUZZ_SEEDS=DIR).
 */
#include "testutil.h"
#include "dataset/ubo2014.h"
#include "core/core.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* The small set of testutil.h: 3 views x 4 lights of 8 x 6 pixels. */
static const int W = TU_SMALL_W, H = TU_SMALL_H, NV = TU_SMALL_NV, NL = TU_SMALL_NL;

static btf_dataset *open_ok(const char *path)
{
    btf_error err = {0};
    btf_dataset *ds = NULL;
    int rc = btf_dataset_open(path, NULL, &ds, &err);
    if (rc)
        print_error("%s\n", err.msg);
    assert_int_equal(rc, 0);
    return ds;
}

/* The largest |read - expected| over every image of the small set,
 * expected(v, l, x, y, c) given by a function of the test; *rel, the
 * largest |read - expected| / max(1, |expected|). */
typedef double (*expect_fn)(const void *user, int v, int l, int x, int y, int c);

static double worst_error(btf_dataset *ds, expect_fn want, const void *user, double *rel)
{
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    assert_int_equal(in->n_views, NV);
    assert_int_equal(in->n_lights, NL);
    assert_int_equal(in->width, W);
    assert_int_equal(in->height, H);
    double worst = 0, worst_rel = 0;
    for (int v = 0; v < NV; v++)
        for (int l = 0; l < NL; l++) {
            btf_image img = {0};
            btf_error err = {0};
            int rc = btf_dataset_read(ds, v, l, &img, &err);
            if (rc)
                print_error("%s\n", err.msg);
            assert_int_equal(rc, 0);
            for (int y = 0; y < H; y++)
                for (int x = 0; x < W; x++)
                    for (int c = 0; c < 3; c++) {
                        double e = want(user, v, l, x, y, c);
                        double d = fabs(img.data[(y * W + x) * 3 + c] - e);
                        worst = fmax(worst, d);
                        worst_rel = fmax(worst_rel, d / fmax(1.0, fabs(e)));
                    }
            btf_image_free(&img);
        }
    if (rel)
        *rel = worst_rel;
    return worst;
}

static double small_want(const void *user, int v, int l, int x, int y, int c)
{
    (void)user;
    return tu_small_value(v, l, x, y, c);
}

/* ------------------------------------------------- written from images */

typedef struct variant_case {
    int variant;
    const char *sig;                     /* the signature it has */
    int scalar, components, log_values;  /* log_values: the file's DRR flag */
} variant_case;

static void write_small(const char *p, const variant_case *vc, btf_ubo2014_write_stats *st)
{
    btf_ubo2014_write_opts o = btf_ubo2014_write_defaults();
    o.variant = vc->variant;
    o.scalar_size = vc->scalar;
    o.components = vc->components;
    btf_error err = {0};
    int rc = btf_ubo2014_write(p, &tu_small_views, &tu_small_lights, W, H, tu_small_image, NULL, &o,
                               st, &err);
    if (rc)
        print_error("%s\n", err.msg);
    assert_int_equal(rc, 0);
}

/* Every FMF and PVF signature, half and float, full rank and truncated:
 * read back within the error the writer states (the reader sums as the
 * writer measured; the logarithm's rounding adds a little). */
static void test_round_trip_from_images(void **state)
{
    (void)state;
    static const variant_case cases[] = {
        {BTF_UBO2014_FMF, "!FMF12FCER", 2, 36, 0}, {BTF_UBO2014_FMF, "!FMF12FCER", 4, 4, 0},
        {BTF_UBO2014_FMF_LOG, "!FMF12FCER", 2, 36, 1}, {BTF_UBO2014_FMF_LOG, "!FMF12FCER", 4, 3, 1},
        {BTF_UBO2014_FMF06R, "!FMF06FCR", 2, 36, 0},  {BTF_UBO2014_FMF06R, "!FMF06FCR", 4, 2, 0},
        {BTF_UBO2014_FMF06, "!FMF06FC", 4, 36, 0},   {BTF_UBO2014_FMF06, "!FMF06FC", 2, 5, 0},
        {BTF_UBO2014_PVF, "!PVF06FCR", 2, 12, 0},  {BTF_UBO2014_PVF, "!PVF06FCR", 4, 2, 0},
        {BTF_UBO2014_PVF06, "!PVF06FC", 4, 12, 0},   {BTF_UBO2014_PVF06, "!PVF06FC", 2, 1, 0},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const variant_case *vc = &cases[i];
        const char *p = tu_fmt("%s/rt_%zu.btf", tu_dir, i);
        btf_ubo2014_write_stats st;
        write_small(p, vc, &st);
        btf_dataset *ds = open_ok(p);
        const btf_ubo2014_info *u = btf_dataset_ubo2014(ds);
        assert_string_equal(u->signature, vc->sig);
        assert_string_equal(u->variant, vc->sig[1] == 'F' ? "FMF" : "PVF");
        assert_int_equal(u->scalar_size, vc->scalar);
        assert_int_equal(u->dynamic_range, vc->log_values);
        assert_int_equal(u->transposed, 0);
        assert_int_equal(u->components[0], st.components[0]);
        double stated = fmax(st.max_error[0], fmax(st.max_error[1], st.max_error[2]));
        double rel, worst = worst_error(ds, small_want, NULL, &rel);
        print_message("%s %s K %d (asked %d), %d-byte scalars: stated max error %.3g (RMS %.3g "
                      "%.3g %.3g), read back %.3g\n", vc->sig, vc->log_values ? "log" : "linear",
                      st.components[0], vc->components, vc->scalar, stated, st.rms_error[0],
                      st.rms_error[1], st.rms_error[2], worst);
        assert_true(worst <= stated * (1 + 1e-3) + (vc->log_values ? 2e-6 : 1e-7));
        /* full rank: only the rounding of the stored scalars */
        int full = vc->components >= (vc->sig[1] == 'F' ? 36 : 12);
        if (full)
            assert_true(worst < (vc->scalar == 2 ? 2e-3 : 2e-6));
        btf_dataset_close(ds);
    }
}

/* ------------------------------------ a generated material, twin of UBO2003 */

typedef struct material_src {
    btf_procedural m;
    btf_dirset d;
} material_src;

static btf_status render_pair(void *user, int v, int l, btf_image *out, btf_error *err)
{
    material_src *s = user;
    return btf_procedural_render(&s->m, s->d.dirs[v], s->d.dirs[l], out, err);
}

/* The fabric at 8^2 written in every FMF and PVF signature (and with the
 * dynamic-range reduction) at full rank: its images against the exact
 * renders and against the UBO2003 twin (8-bit JPEG): the .btf is far
 * closer to the renders than the twin, and differs from the twin by the
 * twin's JPEG error. The twin is `btfcar generate` of the same seed. */
static void test_generated_twins(void **state)
{
    (void)state;
    const char *twin = tu_fmt("%s/twin", tu_dir);
    assert_int_equal(tu_run(tu_fmt("%s generate -q --material fabric --size 8 --seed 3 %s",
                                   tu_cli(), twin), NULL), 0);
    char twin_path[4096];
    snprintf(twin_path, sizeof twin_path, "%s", twin);
    btf_dataset *b = open_ok(twin_path);
    material_src src;
    assert_int_equal(btf_procedural_make("fabric", 8, 3, &src.m, NULL), 0);
    assert_int_equal(btf_dirset_ubo81(&src.d, NULL), 0);
    static const variant_case cases[] = {
        {BTF_UBO2014_FMF, "!FMF12FCER", 2, 64, 0}, {BTF_UBO2014_FMF_LOG, "!FMF12FCER", 2, 64, 1},
        {BTF_UBO2014_FMF06R, "!FMF06FCR", 2, 64, 0},  {BTF_UBO2014_FMF06, "!FMF06FC", 2, 64, 0},
        {BTF_UBO2014_PVF, "!PVF06FCR", 2, 64, 0},  {BTF_UBO2014_PVF06, "!PVF06FC", 2, 64, 0},
        {BTF_UBO2014_FMF, "!FMF12FCER", 2, 8, 0},  {BTF_UBO2014_PVF, "!PVF06FCR", 2, 4, 0},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const variant_case *vc = &cases[i];
        const char *p = tu_fmt("%s/gen_%zu.btf", tu_dir, i);
        btf_ubo2014_write_opts o = btf_ubo2014_write_defaults();
        o.variant = vc->variant;
        o.components = vc->components;
        btf_ubo2014_write_stats st;
        btf_error err = {0};
        TU_OK(btf_ubo2014_write(p, &src.d, &src.d, 8, 8, render_pair, &src, &o, &st, &err), &err);
        btf_dataset *a = open_ok(p);
        double btf_err = 0, jpeg_err = 0, between = 0, btf_max = 0;
        long cnt = 0;
        for (int v = 0; v < 81; v += 7)
            for (int l = 0; l < 81; l += 5) {
                btf_image x = {0}, y = {0}, t = {0};
                assert_int_equal(btf_dataset_read(a, v, l, &x, NULL), 0);
                assert_int_equal(btf_dataset_read(b, v, l, &y, NULL), 0);
                assert_int_equal(render_pair(&src, v, l, &t, NULL), 0);
                for (int j = 0; j < 8 * 8 * 3; j++, cnt++) {
                    double tx = btf__linear_to_srgb(fminf(1, t.data[j]));
                    double xs = btf__linear_to_srgb(fmaxf(0, fminf(1, x.data[j])));
                    btf_err += fabs(xs - tx);
                    jpeg_err += fabs(btf__linear_to_srgb(y.data[j]) - tx);
                    between += fabs(xs - btf__linear_to_srgb(y.data[j]));
                    btf_max = fmax(btf_max, fabs(x.data[j] - t.data[j]));
                }
                btf_image_free(&x);
                btf_image_free(&y);
                btf_image_free(&t);
            }
        double stated = fmax(st.max_error[0], fmax(st.max_error[1], st.max_error[2]));
        print_message("%s%s K %d: vs exact renders mean %.5f sRGB, max linear %.2g (stated "
                      "%.2g, RMS %.2g); UBO2003 twin vs exact %.5f; .btf vs twin %.5f\n",
                      vc->sig, vc->log_values ? " (log)" : "", st.components[0], btf_err / cnt,
                      btf_max, stated, st.rms_error[0], jpeg_err / cnt, between / cnt);
        assert_true(btf_max <= stated * (1 + 1e-3) + 1e-5);
        if (vc->components == 64) { /* full rank (64 pixels): the rounding alone */
            assert_true(btf_max < 2e-3);
            assert_true(btf_err < 0.1 * jpeg_err);
        }
        assert_true(between <= jpeg_err + btf_err + 1e-9);
        btf_dataset_close(a);
    }
    btf_dataset_close(b);
    btf_dirset_free(&src.d);
    btf_procedural_free(&src.m);
    /* the command line writes the same variants */
    for (int f = 0; f < 2; f++) {
        const char *fmt = f ? "btf-pvf" : "btf-fmf";
        const char *p = tu_fmt("%s/cli_%s.btf", tu_dir, fmt);
        char *msg = NULL;
        assert_int_equal(tu_run(tu_fmt("%s generate --material fabric --size 8 --seed 3 "
                                       "--format %s --components 64 %s", tu_cli(), fmt, p),
                                &msg), 0);
        assert_non_null(strstr(msg, f ? "(PVF, " : "(FMF, "));
        assert_non_null(strstr(msg, "error of the stored values"));
        free(msg);
        char *out = tu_capture(tu_fmt("%s info %s", tu_cli(), p), &(int){0});
        assert_non_null(strstr(out, f ? "PVF (!PVF06FCR)" : "FMF (!FMF12FCER)"));
        free(out);
    }
}

static size_t header_end(const unsigned char *d, size_t sig_len);

/* ------------------------------------------ layouts from given factors */

/* A value that differs per index and stays small. */
static float wave(uint64_t i, int salt)
{
    return (float)(0.25 * sin(0.7 * (double)i + 1.3 * salt) + 0.05 * salt);
}

static float *wave_matrix(uint64_t n, int salt)
{
    float *m = malloc(n * sizeof *m);
    for (uint64_t i = 0; i < n; i++)
        m[i] = wave(i, salt);
    return m;
}

/* An FMF's expected value (§4), from the factors as stored (rounded). */
typedef struct fmf_case {
    const ubo_fmf *f;
    uint32_t use;  /* components the reader uses: min(K_file, K) */
    int transposed, log;
} fmf_case;

static double fmf_want(const void *user, int v, int l, int x, int y, int c)
{
    const fmf_case *fc = user;
    const ubo_fmf *f = fc->f;
    uint64_t lv = (uint64_t)v * NL + l, xy = (uint64_t)y * W + x;
    uint64_t ur = fc->transposed ? xy * 3 + c : lv * 3 + c, sr = fc->transposed ? lv : xy;
    double d = 0;
    for (uint32_t k = 0; k < fc->use; k++)
        d += (double)ubo_stored(f->u[ur * f->k + k], f->scalar_size) *
             ubo_stored(f->sxv[sr * f->k + k], f->scalar_size);
    return fc->log ? exp(d) - 1e-5 : d;
}

static void check_fmf(const char *name, const ubo_fmf *f, uint32_t use, int transposed)
{
    const char *p = tu_fmt("%s/%s.btf", tu_dir, name);
    btf_error err = {0};
    TU_OK(ubo_write_fmf(p, &tu_small_views, &tu_small_lights, W, H, f, &err), &err);
    btf_dataset *ds = open_ok(p);
    const btf_ubo2014_info *u = btf_dataset_ubo2014(ds);
    assert_string_equal(u->signature, f->signature);
    assert_int_equal(u->transposed, transposed);
    assert_int_equal(u->components[0], (int)use);
    int log = !strcmp(f->signature, "!FMF12FCER") && f->header_version >= 1 && f->drr;
    assert_int_equal(u->dynamic_range, log);
    fmf_case fc = {f, use, transposed, log};
    double rel, worst = worst_error(ds, fmf_want, &fc, &rel);
    print_message("FMF %s: largest error %.2g (relative to max(1, value) %.2g)\n", name, worst,
                  rel);
    assert_true(rel < 2e-6); /* the reader's float sums of K products */
    btf_dataset_close(ds);
}

/* §4 in every form: both orientations, K_file < K (the reader uses the
 * smaller), header versions 0, 1 and 2 (with a non-square height map that
 * is skipped), the dynamic-range reduction, scalars of 2, 4 and 8 bytes. */
static void test_fmf_layouts(void **state)
{
    (void)state;
    uint32_t n = NV * NL, px = W * H, k = 4;
    float *u = wave_matrix(3 * (uint64_t)px * k, 1), *sxv = wave_matrix((uint64_t)px * k, 2);
    float *ut = wave_matrix(3 * (uint64_t)px * k, 3), *st = wave_matrix((uint64_t)n * k, 4);
    float hm[15];
    for (int i = 0; i < 15; i++)
        hm[i] = 0.1f * (float)i;
    ubo_fmf f = {.signature = "!FMF12FCER", .header_version = 2, .scalar_size = 4, .k = k,
                 .rows = 3 * n, .cols = px, .u = u, .sxv = sxv};
    check_fmf("fmf_plain", &f, k, 0);
    f.hm_a = 3, f.hm_b = 5, f.height_map = hm; /* non-square: the reader skips 15 halves */
    check_fmf("fmf_heightmap", &f, k, 0);
    f.drr = 1;
    check_fmf("fmf_drr_v2", &f, k, 0);
    f.header_version = 1;
    check_fmf("fmf_drr_v1", &f, k, 0);
    f.header_version = 0; /* no DRR field: linear whatever drr says */
    check_fmf("fmf_v0", &f, k, 0);
    f.header_version = 2, f.drr = 0, f.hm_a = f.hm_b = 0;
    f.k_file = 2; /* §4: min(K_file, K) */
    check_fmf("fmf_kfile2", &f, 2, 0);
    f.k_file = 9;
    check_fmf("fmf_kfile9", &f, k, 0);
    f.k_file = 0;
    f.scalar_size = 8;
    check_fmf("fmf_double", &f, k, 0);
    f.scalar_size = 2;
    check_fmf("fmf_half", &f, k, 0);
    /* transposed (btflib): U rows (y W + x) 3 + c, S x V rows v nL + l */
    ubo_fmf t = {.signature = "!FMF06FCR", .scalar_size = 4, .k = k, .rows = 3 * px, .cols = n,
                 .u = ut, .sxv = st};
    check_fmf("fmf_transposed", &t, k, 1);
    t.signature = "!FMF06FC";
    check_fmf("fmf_transposed_norot", &t, k, 1);
    t.signature = "!FMF12FCER", t.header_version = 1, t.drr = 1;
    check_fmf("fmf_transposed_drr", &t, k, 1);
    free(u);
    free(sxv);
    free(ut);
    free(st);
}

/* A PVF's expected value (§5), from the slots as stored. */
typedef struct pvf_case {
    const ubo_pvf *p;
} pvf_case;

static double pvf_want(const void *user, int v, int l, int x, int y, int c)
{
    const ubo_pvf *p = ((const pvf_case *)user)->p;
    const ubo_pvf_view *sl = &p->views[v];
    int s = p->scalar_size;
    uint64_t xy = (uint64_t)y * W + x;
    double d = 0;
    if (sl->dim == 3 * (uint32_t)NL) { /* W per pixel, C per (light, channel) */
        uint64_t r = (uint64_t)l * 3 + c;
        for (uint32_t k = 0; k < sl->k; k++)
            d += (double)ubo_stored(sl->w[xy * sl->k + k], s) * ubo_stored(sl->c[r * sl->k + k], s);
        return d + ubo_stored(sl->mean[r], s);
    }
    uint64_t r = xy * 3 + c; /* C per (pixel, channel), W per light */
    for (uint32_t k = 0; k < sl->k; k++)
        d += (double)ubo_stored(sl->c[r * sl->k + k], s) * ubo_stored(sl->w[(uint64_t)l * sl->k + k], s);
    return d + ubo_stored(sl->mean[r], s);
}

static void check_pvf(const char *name, const ubo_pvf *p)
{
    const char *path = tu_fmt("%s/%s.btf", tu_dir, name);
    btf_error err = {0};
    TU_OK(ubo_write_pvf(path, &tu_small_views, &tu_small_lights, W, H, p, &err), &err);
    btf_dataset *ds = open_ok(path);
    const btf_ubo2014_info *u = btf_dataset_ubo2014(ds);
    assert_string_equal(u->signature, p->signature);
    assert_string_equal(u->variant, "PVF");
    pvf_case pc = {p};
    double rel, worst = worst_error(ds, pvf_want, &pc, &rel);
    print_message("PVF %s: largest error %.2g (relative to max(1, value) %.2g)\n", name, worst,
                  rel);
    assert_true(rel < 2e-6); /* the reader's float sums of K products */
    btf_dataset_close(ds);
}

/* §5 in every form: both orientations (per view, each its own K), the
 * legacy header (magic 301074, no meta block) under both signatures,
 * scalars of 2, 4 and 8 bytes. */
static void test_pvf_layouts(void **state)
{
    (void)state;
    uint32_t px = W * H;
    ubo_pvf_view pp[3], pl[3];
    float *mats[24];
    int m = 0;
    for (int v = 0; v < NV; v++) {
        uint32_t k = (uint32_t)v + 1; /* K differs per view */
        uint32_t dim = 3 * NL;
        pp[v] = (ubo_pvf_view){k, px, dim, NULL, mats[m] = wave_matrix(dim, 10 + v),
                               mats[m + 1] = wave_matrix((uint64_t)dim * k, 20 + v),
                               mats[m + 2] = wave_matrix((uint64_t)px * k, 30 + v)};
        m += 3;
        dim = 3 * px;
        pl[v] = (ubo_pvf_view){k + 1, NL, dim, mats[m] = wave_matrix(k + 1, 5),
                               mats[m + 1] = wave_matrix(dim, 40 + v),
                               mats[m + 2] = wave_matrix((uint64_t)dim * (k + 1), 50 + v),
                               mats[m + 3] = wave_matrix((uint64_t)NL * (k + 1), 60 + v)};
        m += 4;
    }
    ubo_pvf p = {"!PVF06FCR", 0, 4, 3, pp};
    check_pvf("pvf_per_pixel", &p);
    p.signature = "!PVF06FC", p.scalar_size = 2;
    check_pvf("pvf_per_pixel_norot_half", &p);
    p.views = pl, p.scalar_size = 4;
    check_pvf("pvf_per_light", &p);
    p.signature = "!PVF06FCR", p.scalar_size = 8;
    check_pvf("pvf_per_light_double", &p);
    p.legacy = 1;
    check_pvf("pvf_legacy_r", &p);
    p.signature = "!PVF06FC", p.views = pp, p.scalar_size = 4;
    check_pvf("pvf_legacy", &p);
    for (int i = 0; i < m; i++)
        free(mats[i]);
}

/* §3's transposed DFMF (btflib: rows = pixels, columns = views x lights,
 * the roles of U and S x V swapped): a DFMF file rewritten so, per
 * channel, decodes to the same bits. */
static void test_dfmf_transposed(void **state)
{
    (void)state;
    uint32_t n = NV * NL, px = W * H, k = 3;
    float *u[3], *sxv[3];
    for (int c = 0; c < 3; c++) {
        u[c] = wave_matrix((uint64_t)n * k, 70 + c);
        sxv[c] = wave_matrix((uint64_t)px * k, 80 + c);
    }
    btf_ubo2014_factors f = {.colour_model = 11, .scalar_size = 4, .components = {3, 3, 3},
                             .u = {u[0], u[1], u[2]}, .sxv = {sxv[0], sxv[1], sxv[2]}};
    const char *p = tu_fmt("%s/dfmf_plain.btf", tu_dir);
    btf_error err = {0};
    TU_OK(btf__ubo2014_write_factors(p, &tu_small_views, &tu_small_lights, W, H, &f, &err), &err);
    size_t len;
    unsigned char *d = tu_slurp(p, &len), *t = malloc(len);
    /* rotations, num_components, color_model, color_mean, color_transform */
    size_t at = header_end(d, 10) + 4 + 4 + 4 + 12 + 36;
    memcpy(t, d, at);
    for (int c = 0; c < 3; c++) {
        size_t sz = 4, s_bytes = sz * k, ub = sz * n * k, vb = sz * px * k;
        assert_int_equal(d[at], 4);
        assert_int_equal(ubo_rd32(d + at + 5), n);
        memcpy(t + at, d + at, 5);
        ubo_wr32(t + at + 5, px); /* rows: the pixels */
        ubo_wr32(t + at + 9, n);  /* columns: the (view, light) pairs */
        memcpy(t + at + 13, d + at + 13, s_bytes);
        memcpy(t + at + 13 + s_bytes, d + at + 13 + s_bytes + ub, vb); /* S x V first */
        memcpy(t + at + 13 + s_bytes + vb, d + at + 13 + s_bytes, ub);
        at += 13 + s_bytes + ub + vb;
    }
    assert_int_equal(at, len);
    const char *q = tu_fmt("%s/dfmf_transposed.btf", tu_dir);
    tu_write_file(q, t, len);
    char pp[4096];
    snprintf(pp, sizeof pp, "%s", p);
    btf_dataset *a = open_ok(pp), *b = open_ok(q);
    assert_int_equal(btf_dataset_ubo2014(a)->transposed, 0);
    assert_int_equal(btf_dataset_ubo2014(b)->transposed, 1);
    for (int v = 0; v < NV; v++)
        for (int l = 0; l < NL; l++) {
            btf_image x = {0}, y = {0};
            assert_int_equal(btf_dataset_read(a, v, l, &x, NULL), 0);
            assert_int_equal(btf_dataset_read(b, v, l, &y, NULL), 0);
            assert_memory_equal(x.data, y.data, sizeof(float) * 3 * px);
            btf_image_free(&x);
            btf_image_free(&y);
        }
    btf_dataset_close(a);
    btf_dataset_close(b);
    free(d);
    free(t);
    for (int c = 0; c < 3; c++) {
        free(u[c]);
        free(sxv[c]);
    }
}

/* ------------------------------------------------- the signature hazard */

/* Inserts an XML text of len bytes into the meta block of a file with a
 * signature of sig_len bytes (§2a: xml_len at 268 in the block, version
 * >= 3), fixing xml_len and meta_size. */
static unsigned char *with_xml(const unsigned char *d, size_t n, size_t sig_len, uint32_t len,
                               size_t *out)
{
    unsigned char *e = malloc(n + len);
    size_t at = sig_len + 272;
    memcpy(e, d, at);
    memset(e + at, 'x', len);
    memcpy(e + at + len, d + at, n - at);
    ubo_wr32(e + sig_len, ubo_rd32(d + sig_len) + len);
    ubo_wr32(e + sig_len + 268, len);
    *out = n + len;
    return e;
}

/* §1: "!FMF06FC" and "!PVF06FC" whose meta_size has the low byte 0x52
 * ('R') start like "!FMF06FCR" and "!PVF06FCR"; the longer reading fails
 * and the shorter one is kept. Files that are really "R" stay "R". */
static void test_signature_hazard(void **state)
{
    (void)state;
    static const variant_case cases[] = {{BTF_UBO2014_FMF06, "!FMF06FC", 4, 3, 0},
                                         {BTF_UBO2014_PVF06, "!PVF06FC", 4, 3, 0},
                                         {BTF_UBO2014_FMF06R, "!FMF06FCR", 4, 3, 0},
                                         {BTF_UBO2014_PVF, "!PVF06FCR", 4, 3, 0}};
    for (size_t i = 0; i < 4; i++) {
        const char *p = tu_fmt("%s/hz_%zu.btf", tu_dir, i);
        write_small(p, &cases[i], NULL);
        size_t n, m;
        unsigned char *d = tu_slurp(p, &n);
        size_t sl = strlen(cases[i].sig);
        uint32_t meta = ubo_rd32(d + sl);
        uint32_t len = (0x152u - meta % 256u) % 256u; /* meta_size's low byte becomes 0x52 */
        unsigned char *e = with_xml(d, n, sl, len, &m);
        assert_int_equal(e[sl], 'R');
        const char *q = tu_fmt("%s/hz_%zu_xml.btf", tu_dir, i);
        tu_write_file(q, e, m);
        btf_dataset *ds = open_ok(q);
        assert_string_equal(btf_dataset_ubo2014(ds)->signature, cases[i].sig);
        assert_true(worst_error(ds, small_want, NULL, NULL) < 0.2);
        btf_dataset_close(ds);
        free(d);
        free(e);
    }
}

/* ---------------------------------------------------------- bad input */

/* Cut at every offset of the header and a stride through the data, one
 * byte short, one byte too many: one line naming the input each time. */
static void expect_truncations_fail(const unsigned char *d, size_t n, size_t header)
{
    for (size_t cut = 1; cut < n; cut += cut < header + 64 ? 1 : 37) {
        ubo_file f;
        btf_error err = {0};
        int rc = ubo_parse(d, cut, "cut", 0, &f, &err);
        if (rc == 0)
            print_error("parsed %zu of %zu bytes\n", cut, n);
        assert_int_not_equal(rc, 0);
        assert_non_null(strstr(err.msg, "cut"));
        assert_null(strchr(err.msg, '\n'));
        ubo_free(&f);
    }
    tu_expect_open_fails(d, n - 1, "truncated", BTF_E_FORMAT);
    unsigned char *e = malloc(n + 1);
    memcpy(e, d, n);
    e[n] = 0;
    tu_expect_open_fails(e, n + 1, "after the end", BTF_E_FORMAT);
    free(e);
}

/* The end of the common header (§2: meta, sampling, width, height). */
static size_t header_end(const unsigned char *d, size_t sig_len)
{
    size_t at = sig_len + ubo_rd32(d + sig_len);
    uint32_t nv = ubo_rd32(d + at), nl = ubo_rd32(d + at + 12);
    return at + 4 + nv * (12 + 8 * (size_t)nl) + 8;
}

static unsigned char *patched(const unsigned char *d, size_t n, size_t at, uint32_t v)
{
    unsigned char *e = malloc(n);
    memcpy(e, d, n);
    ubo_wr32(e + at, v);
    return e;
}

static void expect_patch_fails(const unsigned char *d, size_t n, size_t at, uint32_t v,
                               const char *what, int code)
{
    unsigned char *e = patched(d, n, at, v);
    tu_expect_open_fails(e, n, what, code);
    free(e);
}

static void expect_half_nan_fails(const unsigned char *d, size_t n, size_t at, const char *what)
{
    unsigned char *e = malloc(n);
    memcpy(e, d, n);
    e[at] = 0x00, e[at + 1] = 0x7e; /* a half NaN */
    tu_expect_open_fails(e, n, what, BTF_E_DATA);
    e[at + 1] = 0x7c; /* +Inf */
    tu_expect_open_fails(e, n, what, BTF_E_DATA);
    free(e);
}

/* FMF: each signature truncated everywhere; K, rows, columns, the scalar
 * size, the header version, the height map's sides that do not fit; a
 * NaN and an Inf in U and in S x V. */
static void test_fmf_bad_input(void **state)
{
    (void)state;
    static const char *const sigs[] = {"!FMF12FCER", "!FMF06FCR", "!FMF06FC"};
    static const int variants[] = {BTF_UBO2014_FMF, BTF_UBO2014_FMF06R, BTF_UBO2014_FMF06};
    for (int i = 0; i < 3; i++) {
        variant_case vc = {variants[i], sigs[i], 2, 3, 0};
        const char *p = tu_fmt("%s/badfmf_%d.btf", tu_dir, i);
        write_small(p, &vc, NULL);
        size_t n, sl = strlen(sigs[i]);
        unsigned char *d = tu_slurp(p, &n);
        size_t at = header_end(d, sl) + (i < 2 ? 4 : 0); /* past the rotations field */
        if (i == 0) { /* the extended header: version, DRR, the height map's sides */
            unsigned char *e = malloc(n);
            memcpy(e, d, n);
            e[at] = 3;
            tu_expect_open_fails(e, n, "FMF header version 3 is not supported", BTF_E_UNSUPPORTED);
            free(e);
            unsigned char *big = patched(d, n, at + 5, 0x10000); /* a 2^16 x 2^16 map */
            expect_patch_fails(big, n, at + 9, 0x10000, "the height map", BTF_E_FORMAT);
            free(big);
            unsigned char *small = patched(d, n, at + 5, 2); /* 2 x 3: the rest shifts */
            expect_patch_fails(small, n, at + 9, 3, NULL, BTF_E_FORMAT);
            free(small);
            at += 13;
        }
        expect_truncations_fail(d, n, at + 17);
        /* K_file (at), scalar size (at + 4), K (at + 5), rows (at + 9), cols (at + 13) */
        unsigned char *e = malloc(n);
        memcpy(e, d, n);
        e[at + 4] = 3;
        tu_expect_open_fails(e, n, "scalar size 3", BTF_E_FORMAT);
        free(e);
        expect_patch_fails(d, n, at + 5, 0x7fffffff, "does not fit", BTF_E_FORMAT);
        expect_patch_fails(d, n, at + 5, 0, "0 components", BTF_E_FORMAT);
        expect_patch_fails(d, n, at + 9, 3 * NV * NL + 1, "FMF matrix is", BTF_E_FORMAT);
        expect_patch_fails(d, n, at + 13, W * H - 1, "FMF matrix is", BTF_E_FORMAT);
        expect_patch_fails(d, n, at + 9, NV * NL, "FMF matrix is", BTF_E_FORMAT);
        /* S (3 halves), U (36 x 3), S x V (48 x 3) */
        size_t s0 = at + 17, u0 = s0 + 2 * 3, sxv0 = u0 + 2 * 3 * 3 * NV * NL;
        expect_half_nan_fails(d, n, u0 + 2 * (3 * 5 + 2), "U has a NaN or Inf at row 5, component 2");
        expect_half_nan_fails(d, n, sxv0 + 2 * (3 * 47), "SxV has a NaN or Inf at row 47, component 0");
        assert_int_equal(sxv0 + 2 * 3 * W * H, n);
        free(d);
    }
}

/* PVF: each header (R, no R, legacy) truncated everywhere; the slot count,
 * a slot's K, num_weights, dim and scalar size that do not fit; a NaN and
 * an Inf in a mean, a C and a W. */
static void test_pvf_bad_input(void **state)
{
    (void)state;
    for (int i = 0; i < 3; i++) {
        const char *sig = i == 1 ? "!PVF06FC" : "!PVF06FCR";
        const char *p = tu_fmt("%s/badpvf_%d.btf", tu_dir, i);
        size_t n, sl = strlen(sig), at;
        unsigned char *d;
        if (i < 2) {
            variant_case vc = {i ? BTF_UBO2014_PVF06 : BTF_UBO2014_PVF, sig, 2, 2, 0};
            write_small(p, &vc, NULL);
            d = tu_slurp(p, &n);
            at = header_end(d, sl) + (i == 0 ? 4 : 0); /* num_components */
        } else { /* the legacy header, from factors */
            uint32_t dim = 3 * NL, px = W * H, k = 2;
            float *mean = wave_matrix(dim, 1), *c = wave_matrix(dim * k, 2),
                  *w = wave_matrix(px * k, 3);
            ubo_pvf_view v = {k, px, dim, NULL, mean, c, w};
            ubo_pvf_view vv[3] = {v, v, v};
            ubo_pvf pv = {sig, 1, 2, k, vv};
            btf_error err = {0};
            TU_OK(ubo_write_pvf(p, &tu_small_views, &tu_small_lights, W, H, &pv, &err), &err);
            free(mean);
            free(c);
            free(w);
            d = tu_slurp(p, &n);
            assert_int_equal(ubo_rd32(d + sl), 301074);
            expect_patch_fails(d, n, sl + 12, 0, "image size", BTF_E_FORMAT);
            at = sl + 12; /* so that at + 4 is num_view_slots */
            expect_patch_fails(d, n, sl + 16, 2, "PVF view slots for 3 views", BTF_E_FORMAT);
            at = sl + 20 + 4 + NV * (12 + 8 * NL) - 8; /* slot 0 at at + 8 */
        }
        expect_truncations_fail(d, n, at + 8 + 13);
        if (i < 2)
            expect_patch_fails(d, n, at + 4, NV + 1, "PVF view slots for 3 views", BTF_E_FORMAT);
        size_t s0 = at + 8; /* slot 0: scalar, K, num_weights, dim */
        unsigned char *e = malloc(n);
        memcpy(e, d, n);
        e[s0] = 5;
        tu_expect_open_fails(e, n, "scalar size 5", BTF_E_FORMAT);
        free(e);
        expect_patch_fails(d, n, s0 + 1, 0x40000000, "does not fit", BTF_E_FORMAT);
        expect_patch_fails(d, n, s0 + 5, W * H + 1, "PVF slot 0 has dim", BTF_E_FORMAT);
        expect_patch_fails(d, n, s0 + 9, 3 * NL + 3, "PVF slot 0 has dim", BTF_E_FORMAT);
        uint32_t k = ubo_rd32(d + s0 + 1), dim = 3 * NL;
        size_t mean0 = s0 + 13 + 2 * k, c0 = mean0 + 2 * dim, w0 = c0 + 2 * dim * k;
        expect_half_nan_fails(d, n, mean0 + 2 * 7, "mean of PVF view slot 0 has a NaN or Inf at row 7");
        expect_half_nan_fails(d, n, c0 + 2 * (k * 4 + 1), "C of PVF view slot 0 has a NaN or Inf at row 4, component 1");
        expect_half_nan_fails(d, n, w0 + 2 * (k * 40), "W of PVF view slot 0 has a NaN or Inf at row 40, component 0");
        free(d);
    }
}

/* ------------------------------------------------- the writer refuses */

static btf_status negative_image(void *user, int v, int l, btf_image *out, btf_error *err)
{
    btf_status rc = tu_small_image(user, v, l, out, err);
    if (rc == BTF_OK && v == 1 && l == 2)
        out->data[7] = -0.5f; /* below -1e-5: no logarithm */
    return rc;
}

/* What the writer refuses, in one line naming the file, and leaves no file. */
static void expect_write_fails(int variant, int scalar, uint64_t max_bytes, btf_pair_image_fn fn,
                               const char *what, int code)
{
    const char *p = tu_fmt("%s/refused.btf", tu_dir);
    remove(p);
    btf_ubo2014_write_opts o = btf_ubo2014_write_defaults();
    o.variant = variant;
    o.scalar_size = scalar;
    o.max_bytes = max_bytes;
    o.components = 3;
    btf_error err = {0};
    int rc = btf_ubo2014_write(p, &tu_small_views, &tu_small_lights, W, H, fn, NULL, &o, NULL,
                               &err);
    assert_int_equal(rc, code);
    assert_non_null(strstr(err.msg, p));
    assert_null(strchr(err.msg, '\n'));
    if (!strstr(err.msg, what))
        print_error("message \"%s\" lacks \"%s\"\n", err.msg, what);
    assert_non_null(strstr(err.msg, what));
    assert_int_not_equal(access(p, F_OK), 0);
}

static void test_writer_refusals(void **state)
{
    (void)state;
    expect_write_fails(8, 2, 0, tu_small_image, "variant 8", BTF_E_ARG);
    expect_write_fails(-1, 2, 0, tu_small_image, "variant -1", BTF_E_ARG);
    expect_write_fails(BTF_UBO2014_FMF, 8, 0, tu_small_image, "scalar size 8", BTF_E_ARG);
    expect_write_fails(BTF_UBO2014_PVF06, 3, 0, tu_small_image, "scalar size 3", BTF_E_ARG);
    expect_write_fails(BTF_UBO2014_FMF_LOG, 2, 0, negative_image,
                       "image (view 1, light 2) has the value -0.5", BTF_E_ARG);
    expect_write_fails(BTF_UBO2014_FMF06, 2, 1000, tu_small_image, "over the cap",
                       BTF_E_UNSUPPORTED);
    expect_write_fails(BTF_UBO2014_PVF, 2, 1000, tu_small_image, "over the cap",
                       BTF_E_UNSUPPORTED);
    /* the linear FMF stores the negative value as it is */
    const char *p = tu_fmt("%s/negative.btf", tu_dir);
    btf_ubo2014_write_opts o = btf_ubo2014_write_defaults();
    o.variant = BTF_UBO2014_FMF;
    o.scalar_size = 4;
    o.components = 36;
    btf_error err = {0};
    TU_OK(btf_ubo2014_write(p, &tu_small_views, &tu_small_lights, W, H, negative_image, NULL, &o,
                            NULL, &err), &err);
    btf_dataset *ds = open_ok(p);
    btf_image img = {0};
    assert_int_equal(btf_dataset_read(ds, 1, 2, &img, NULL), 0);
    assert_true(fabsf(img.data[7] + 0.5f) < 1e-5f);
    btf_image_free(&img);
    btf_dataset_close(ds);
}

/* ------------------------------------------------------- the fuzz seeds */

/* Small files of every FMF and PVF form for the fuzz target's corpus
 * (tests/fuzz/corpus/fuzz_btf/): written here and parsed; copied to
 * $BTF_FUZZ_SEEDS when it is set (how the committed seeds were made). */
static void test_fuzz_seeds(void **state)
{
    (void)state;
    btf_dir two[2] = {{0, 0}, {45, 90}};
    btf_dirset d2;
    assert_int_equal(btf_dirset_from_list(&d2, two, 2, NULL), 0);
    const int w = 3, h = 2;
    uint32_t n = 4, px = (uint32_t)(w * h), k = 2;
    float *u = wave_matrix(3 * (uint64_t)n * k, 1), *sxv = wave_matrix((uint64_t)px * k, 2);
    float *ut = wave_matrix(3 * (uint64_t)px * k, 3), *st = wave_matrix((uint64_t)n * k, 4);
    float hm[2] = {0.5f, 0.25f};
    float *mean = wave_matrix(3 * 2, 5), *c = wave_matrix(3 * 2 * k, 6), *wt = wave_matrix(px * k, 7);
    float *meanl = wave_matrix(3 * px, 8), *cl = wave_matrix(3 * px * k, 9), *wl = wave_matrix(2 * k, 10);
    ubo_pvf_view pp = {k, px, 6, NULL, mean, c, wt}, pl = {k, 2, 3 * px, NULL, meanl, cl, wl};
    ubo_pvf_view vp[2] = {pp, pp}, vl[2] = {pl, pl};
    const struct {
        const char *name;
        ubo_fmf fmf;
        ubo_pvf pvf;
    } seeds[] = {
        {"fmf12_half.btf", {"!FMF12FCER", 2, 0, 0, 0, NULL, 2, k, 0, 3 * n, px, NULL, u, sxv}, {0}},
        {"fmf12_drr_heightmap.btf", {"!FMF12FCER", 2, 1, 1, 2, hm, 2, k, 0, 3 * n, px, NULL, u, sxv}, {0}},
        {"fmf12_v0_float.btf", {"!FMF12FCER", 0, 0, 0, 0, NULL, 4, k, 0, 3 * n, px, NULL, u, sxv}, {0}},
        {"fmf06r_transposed.btf", {"!FMF06FCR", 0, 0, 0, 0, NULL, 2, k, 1, 3 * px, n, NULL, ut, st}, {0}},
        {"fmf06_double.btf", {"!FMF06FC", 0, 0, 0, 0, NULL, 8, k, 0, 3 * n, px, NULL, u, sxv}, {0}},
        {"pvf06r_half.btf", {0}, {"!PVF06FCR", 0, 2, k, vp}},
        {"pvf06_per_light_float.btf", {0}, {"!PVF06FC", 0, 4, k, vl}},
        {"pvf_legacy.btf", {0}, {"!PVF06FCR", 1, 2, k, vp}},
    };
    const char *out = getenv("BTF_FUZZ_SEEDS");
    for (size_t i = 0; i < sizeof seeds / sizeof seeds[0]; i++) {
        const char *p = tu_fmt("%s/%s", tu_dir, seeds[i].name);
        btf_error err = {0};
        if (seeds[i].fmf.signature)
            TU_OK(ubo_write_fmf(p, &d2, &d2, w, h, &seeds[i].fmf, &err), &err);
        else
            TU_OK(ubo_write_pvf(p, &d2, &d2, w, h, &seeds[i].pvf, &err), &err);
        size_t len;
        unsigned char *bytes = tu_slurp(p, &len);
        ubo_file f;
        TU_OK(ubo_parse(bytes, len, "seed", 0, &f, &err), &err);
        float img[3 * 6];
        TU_OK(ubo_decode(&f, 1, 1, img, &err), &err);
        ubo_free(&f);
        if (out)
            tu_write_file(tu_fmt("%s/%s", out, seeds[i].name), bytes, len);
        if (!strcmp(seeds[i].name, "fmf06_double.btf")) { /* and the §1 hazard of it */
            size_t m;
            uint32_t meta = ubo_rd32(bytes + 8);
            unsigned char *e = with_xml(bytes, len, 8, (0x152u - meta % 256u) % 256u, &m);
            TU_OK(ubo_parse(e, m, "seed", 0, &f, &err), &err);
            assert_string_equal(f.info.signature, "!FMF06FC");
            ubo_free(&f);
            if (out)
                tu_write_file(tu_fmt("%s/fmf06_hazard_xml.btf", out), e, m);
            free(e);
        }
        free(bytes);
    }
    float *all[] = {u, sxv, ut, st, mean, c, wt, meanl, cl, wl};
    for (size_t i = 0; i < sizeof all / sizeof all[0]; i++)
        free(all[i]);
    btf_dirset_free(&d2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_round_trip_from_images),
        cmocka_unit_test(test_generated_twins),
        cmocka_unit_test(test_fmf_layouts),
        cmocka_unit_test(test_pvf_layouts),
        cmocka_unit_test(test_dfmf_transposed),
        cmocka_unit_test(test_signature_hazard),
        cmocka_unit_test(test_fmf_bad_input),
        cmocka_unit_test(test_pvf_bad_input),
        cmocka_unit_test(test_writer_refusals),
        cmocka_unit_test(test_fuzz_seeds),
    };
    return cmocka_run_group_tests(tests, tu_setup_small, tu_teardown_small);
}
