/* test_validate.c — bad input caught before the work: unstable models
 * rejected by the validator with the file, subspace, band and level named;
 * multi-view photometric stereo manifests; the CAR fit's relative variance
 * floor; periodic patterns reported; strict numbers; duplicate manifest
 * paths; info on an image. */
#include "testutil.h"
#include "car/car.h"
#include "range/range.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <zlib.h>

static void put_u32le(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

static uint32_t get_u32le(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* A fitted texture model with band 1, level 1 of subspace 0 set to n (1 or
 * 2) neighbours 0:-1 and -1:0 of gammas `markers` (stable), encoded. */
static void marked_model(const float *markers, int n, unsigned char **data, size_t *size)
{
    btf_error e = {0};
    btf_image img;
    tu_material_image("leather", 32, 5, (btf_dir){0, 0}, (btf_dir){30, 0}, &img);
    btf_fit_opts fo = btf_fit_defaults();
    fo.levels = 2;
    btf_model m;
    TU_OK(btf_texture_fit(&img, &fo, &m, &e), &e);
    btf_image_free(&img);
    btf_car_band *b = &m.subspaces[0].bands[1][1];
    b->n = n;
    b->offsets[0] = (btf_offset){0, -1};
    b->offsets[1] = (btf_offset){-1, 0};
    b->gamma[0] = markers[0];
    b->gamma[1] = n > 1 ? markers[1] : 0.0f;
    b->sigma = 0.0123457f; /* a second marker */
    TU_OK(btf_model_encode(&m, data, size, &e), &e);
    btf_model_free(&m);
}

/* Replaces the float `from` by `to` in an encoded model: inflates the
 * payload, patches it, and stores it (compression 0) with a fresh CRC. */
static unsigned char *patch_model(const unsigned char *data, size_t size, float from, float to,
                                  size_t *out_size)
{
    enum { HDR = 26 };
    size_t raw_n = get_u32le(data + 18), stored_n = get_u32le(data + 22);
    unsigned char *out = malloc(HDR + raw_n + 4);
    assert_non_null(out);
    memcpy(out, data, HDR);
    if (data[17] == 1) {
        uLongf got = (uLongf)raw_n;
        assert_int_equal(uncompress(out + HDR, &got, data + HDR, (uLong)stored_n), Z_OK);
        assert_int_equal(got, raw_n);
    } else {
        memcpy(out + HDR, data + HDR, raw_n);
    }
    (void)size;
    unsigned char f[4], t[4];
    memcpy(f, &from, 4);
    memcpy(t, &to, 4);
    int hits = 0;
    for (size_t i = HDR; i + 4 <= HDR + raw_n; i++)
        if (!memcmp(out + i, f, 4)) {
            memcpy(out + i, t, 4);
            hits++;
        }
    assert_int_equal(hits, 1);
    out[17] = 0;
    put_u32le(out + 22, (uint32_t)raw_n);
    put_u32le(out + HDR + raw_n, (uint32_t)crc32(0L, out, (uInt)(HDR + raw_n)));
    *out_size = HDR + raw_n + 4;
    return out;
}

/* An unstable gamma in a file whose CRC is right: the validator rejects it
 * (library, info, synthesise), naming the file, subspace, band and level. */
static void unstable_model_rejected(void **state)
{
    (void)state;
    const float marker = 0.3141592f, unstable = 1.5f;
    unsigned char *data, *bad;
    size_t size, bad_size;
    marked_model(&marker, 1, &data, &size);
    bad = patch_model(data, size, marker, unstable, &bad_size);
    char path[4096];
    snprintf(path, sizeof path, "%s/unstable.btfcar", tu_dir);
    tu_write_file(path, bad, bad_size);
    /* The same patch with a stable value reads. */
    btf_error e = {0};
    btf_model m;
    size_t ok_size;
    unsigned char *ok = patch_model(data, size, marker, 0.25f, &ok_size);
    TU_OK(btf_model_decode(ok, ok_size, "ok", &m, &e), &e);
    btf_model_free(&m);
    free(ok);
    assert_int_equal(btf_model_decode(bad, bad_size, "bad.btfcar", &m, &e), BTF_E_FORMAT);
    assert_non_null(strstr(e.msg, "bad.btfcar: subspace 0, band 1, level 1"));
    assert_non_null(strstr(e.msg, "unstable"));
    assert_int_equal(btf_model_read(path, &m, &e), BTF_E_FORMAT);
    assert_non_null(strstr(e.msg, path));
    free(data);
    free(bad);
    const char *cmds[] = {"%s info %s", "%s synthesise %s --size 8x8 --backend cpu -o %s.out"};
    for (int i = 0; i < 2; i++) {
        char *err = NULL;
        assert_int_equal(tu_run(tu_fmt(cmds[i], tu_cli(), path, path), &err), 1);
        assert_non_null(strstr(err, path));
        assert_non_null(strstr(err, "subspace 0, band 1, level 1"));
        assert_non_null(strstr(err, "unstable"));
        assert_true(strchr(err, '\n') == err + strlen(err) - 1); /* one line */
        free(err);
    }
    struct stat st;
    assert_int_not_equal(stat(tu_fmt("%s.out/subspace_00.exr", path), &st), 0);
    /* A valid model whose synthesis overflows (sigma near FLT_MAX): the
     * library's error comes prefixed with the model file. */
    marked_model(&marker, 1, &data, &size);
    bad = patch_model(data, size, marker, 0.25f, &bad_size);
    free(data);
    unsigned char *huge = patch_model(bad, bad_size, 0.0123457f, 3e38f, &size);
    free(bad);
    snprintf(path, sizeof path, "%s/overflow.btfcar", tu_dir);
    tu_write_file(path, huge, size);
    free(huge);
    char *err = NULL;
    int rc = tu_run(tu_fmt("%s synthesise %s --size 16x16 --backend cpu -o %s.out", tu_cli(), path,
                           path), &err);
    print_message("%s", err);
    assert_int_equal(rc, 1);
    assert_true(strncmp(err, tu_fmt("btfcar synthesise: %s: ", path), strlen(path) + 21) == 0);
    assert_true(strchr(err, '\n') == err + strlen(err) - 1);
    free(err);
}

/* Slow growth: 0:-1 of gamma 1.002, and 0.501, 0.501 on
 * 0:-1,-1:0, grow too slowly for a 160 x 192 test field to see, but
 * without bound in synthesis (1.002^2000 along a row). The reader refuses
 * both, naming the file, the band and the recursion that grows; info says
 * so in one line. */
static void slowly_growing_model_rejected(void **state)
{
    (void)state;
    static const struct {
        int n;
        float markers[2], bad[2];
        const char *why;
    } CASES[2] = {
        {1, {0.3141592f}, {1.002f}, "its recursion along a row has a root"},
        {2, {0.2718281f, 0.1414213f}, {0.501f, 0.501f}, "its rows do not decay"},
    };
    for (int k = 0; k < 2; k++) {
        unsigned char *data, *bad, *bad2 = NULL;
        size_t size, bad_size;
        marked_model(CASES[k].markers, CASES[k].n, &data, &size);
        bad = patch_model(data, size, CASES[k].markers[0], CASES[k].bad[0], &bad_size);
        if (CASES[k].n > 1) {
            bad2 = patch_model(bad, bad_size, CASES[k].markers[1], CASES[k].bad[1], &bad_size);
            free(bad);
            bad = bad2;
        }
        btf_error e = {0};
        btf_model m;
        assert_int_equal(btf_model_decode(bad, bad_size, "slow.btfcar", &m, &e), BTF_E_FORMAT);
        print_message("%s\n", e.msg);
        assert_non_null(strstr(e.msg, "slow.btfcar: subspace 0, band 1, level 1: the CAR "
                                      "coefficients are unstable: "));
        assert_non_null(strstr(e.msg, CASES[k].why));
        char path[4096];
        snprintf(path, sizeof path, "%s/slow%d.btfcar", tu_dir, k);
        tu_write_file(path, bad, bad_size);
        char *err = NULL;
        assert_int_equal(tu_run(tu_fmt("%s info %s", tu_cli(), path), &err), 1);
        assert_non_null(strstr(err, "subspace 0, band 1, level 1"));
        assert_non_null(strstr(err, CASES[k].why));
        assert_true(strchr(err, '\n') == err + strlen(err) - 1); /* one line */
        free(err);
        free(data);
        free(bad);
    }
}

/* Reading a model stays fast with the stability checks: a 20-subspace model
 * of 3 levels with wide-neighbourhood bands (the most expensive check) reads
 * in about 0.7 s on the 2-core development VM since the 24-offset family
 * (the recursion and the margins dominate; docs/synthesis.md). The bound is
 * for an order-of-magnitude regression, not a benchmark: at 1 s it failed
 * on a loaded machine (1.1 s at load 8). */
static void stability_check_is_cheap(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image img;
    tu_material_image("wood", 48, 2, (btf_dir){0, 0}, (btf_dir){30, 0}, &img);
    btf_fit_opts fo = btf_fit_defaults();
    fo.levels = 3;
    btf_model one;
    TU_OK(btf_texture_fit(&img, &fo, &one, &e), &e);
    btf_image_free(&img);
    btf_model m = one;
    m.n_subspaces = 20;
    m.subspaces = calloc(20, sizeof *m.subspaces);
    assert_non_null(m.subspaces);
    for (int k = 0; k < 20; k++)
        m.subspaces[k] = one.subspaces[0];
    m.internal = NULL;
    unsigned char *data;
    size_t size;
    TU_OK(btf_model_encode(&m, &data, &size, &e), &e);
    free(m.subspaces);
    btf_model_free(&one);
    double t0 = tu_now();
    btf_model r;
    TU_OK(btf_model_decode(data, size, "m", &r, &e), &e);
    double dt = tu_now() - t0;
    print_message("decoded a 20-subspace model in %.1f ms\n", 1e3 * dt);
    assert_true(dt < 5.0);
    btf_model_free(&r);
    free(data);
}

/* A manifest of 2 views (theta_v 0 and 45) x 6 lights of rendered leather,
 * rows interleaved by view; with `dup` the last row repeats the first path.
 * Returns the manifest path (static). */
static const char *multiview_manifest(const char *name, int dup, int only_view)
{
    static char path[4096];
    static int rendered;
    const btf_dir views[2] = {{0, 0}, {45, 90}};
    const btf_dir lights[6] = {{30, 0}, {30, 120}, {30, 240}, {50, 60}, {50, 180}, {50, 300}};
    btf_error e = {0};
    if (!rendered) {
        for (int v = 0; v < 2; v++)
            for (int l = 0; l < 6; l++) {
                btf_image img;
                tu_material_image("leather", 24, 3, views[v], lights[l], &img);
                TU_OK(btf_image_write_png(tu_fmt("%s/mv_v%d_l%d.png", tu_dir, v, l), &img, &e),
                      &e);
                btf_image_free(&img);
            }
        rendered = 1;
    }
    snprintf(path, sizeof path, "%s/%s.tsv", tu_dir, name);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, only_view >= 0 ? "path\ttheta_l\tphi_l\n" : "path\ttheta_l\tphi_l\ttheta_v\tphi_v\n");
    for (int l = 0; l < 6; l++)
        for (int v = 0; v < 2; v++) {
            if (only_view >= 0 && v != only_view)
                continue;
            fprintf(f, "mv_v%d_l%d.png\t%g\t%g", v, l, lights[l].theta, lights[l].phi);
            if (only_view < 0)
                fprintf(f, "\t%g\t%g", views[v].theta, views[v].phi);
            fprintf(f, "\n");
        }
    if (dup)
        fprintf(f, "mv_v0_l0.png\t70\t10\t0\t0\n");
    fclose(f);
    return path;
}

static int same_image(const btf_image *a, const btf_image *b)
{
    return a->width == b->width && a->height == b->height && a->channels == b->channels &&
           !memcmp(a->data, b->data, (size_t)a->width * a->height * a->channels * sizeof(float));
}

/* Photometric stereo on a manifest of several views uses the images of one
 * view (the one nearest the normal, or --view's), never a mix; a view far
 * from all is an error; the same file twice is an error. */
static void photostereo_multiview_manifest(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_ps_result all, one, v45, only45;
    char mv[4096], single[4096], single45[4096];
    snprintf(mv, sizeof mv, "%s", multiview_manifest("mv", 0, -1));
    snprintf(single, sizeof single, "%s", multiview_manifest("mv0", 0, 0));
    snprintf(single45, sizeof single45, "%s", multiview_manifest("mv1", 0, 1));
    TU_OK(btf__photostereo_manifest(mv, NULL, &all, &e), &e);
    assert_int_equal(all.view, 0);
    assert_true(all.view_dir.theta == 0.0);
    TU_OK(btf__photostereo_manifest(single, NULL, &one, &e), &e);
    assert_int_equal(one.view, -1);
    assert_true(same_image(&all.normal, &one.normal)); /* only view 0's images */
    const btf_dir want = {44, 91};
    TU_OK(btf_photostereo_manifest_view(mv, &want, NULL, &v45, &e), &e);
    assert_int_equal(v45.view, 1);
    assert_true(v45.view_dir.theta == 45.0 && v45.view_dir.phi == 90.0);
    TU_OK(btf__photostereo_manifest(single45, NULL, &only45, &e), &e);
    assert_true(same_image(&v45.normal, &only45.normal));
    btf_ps_result_free(&all);
    btf_ps_result_free(&one);
    btf_ps_result_free(&v45);
    btf_ps_result_free(&only45);
    btf_ps_result r;
    const btf_dir far = {80, 270};
    assert_int_equal(btf_photostereo_manifest_view(mv, &far, NULL, &r, &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, mv));
    assert_non_null(strstr(e.msg, "no view near theta 80 phi 270"));
    assert_int_equal(btf_photostereo_manifest_view(single, &want, NULL, &r, &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, "no theta_v and phi_v columns"));
    const char *dup = multiview_manifest("mvdup", 1, -1);
    assert_int_equal(btf__photostereo_manifest(dup, NULL, &r, &e), BTF_E_FORMAT);
    assert_non_null(strstr(e.msg, "mv_v0_l0.png is listed again (first on line 2)"));
    /* The command: --view picks the view and the summary names it. */
    char *err = NULL;
    assert_int_equal(tu_run(tu_fmt("%s photostereo --manifest %s --view 45,90 -o %s/mv.out",
                                   tu_cli(), mv, tu_dir), &err), 0);
    assert_non_null(strstr(err, "view theta 45 phi 90"));
    free(err);
    const char *bad[] = {"--view 45", "--view ' 45,90'", "--view 95,0", "--view 45,-1",
                         "--view +45,90"};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        assert_int_equal(tu_run(tu_fmt("%s photostereo --manifest %s %s -o %s/mv.bad", tu_cli(),
                                       mv, bad[i], tu_dir), &err), 2);
        free(err);
    }
    assert_int_equal(tu_run(tu_fmt("%s photostereo --manifest %s --view 80,270 -o %s/mv.bad",
                                   tu_cli(), mv, tu_dir), &err), 1);
    if (!strstr(err, "no view near"))
        print_message("%s", err);
    assert_non_null(strstr(err, "no view near"));
    assert_true(strchr(err, '\n') == err + strlen(err) - 1);
    free(err);
}

/* Numbers are parsed strictly: no leading space, no '+', no sign on
 * unsigned values, no hex floats; each a usage error before any work. */
static void numbers_are_strict(void **state)
{
    (void)state;
    const char *bad[] = {
        "synthesise m --size 4x4 -o x --seed ' -1'", "synthesise m --size 4x4 -o x --seed +5",
        "synthesise m --size 4x4 -o x --seed ' 5'", "synthesise m --size 4x4 -o x --seed '5 '",
        "synthesise m --size 4x4 -o x --seed -1", "synthesise m --size ' 4x4' -o x",
        "synthesise m --size 4x+4 -o x", "synthesise m --size 4x4 -o x --device ' 0'",
        "texture-fit t.png -o x --levels +2", "texture-fit t.png -o x --levels ' 2'",
        "photostereo d -o x --dark ' 0.5'", "photostereo d -o x --outlier +2",
        "photostereo d -o x --outlier 0x2p0", "photostereo d -o x --saturation inf",
        "photostereo d -o x --threads ' 2'", "photostereo d -o x --trim ' 0.1,0.1'",
        "photostereo d -o x --trim 0.1,+0.1"};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        char *err = NULL;
        int rc = tu_run(tu_fmt("%s %s", tu_cli(), bad[i]), &err);
        if (rc != 2)
            print_error("%s: exit %d, %s\n", bad[i], rc, err ? err : "");
        assert_int_equal(rc, 2);
        free(err);
    }
}

/* A dataset manifest listing one file under two directions is an error
 * naming both lines; info on an image says what it is and what to run. */
static void duplicates_and_info_on_image(void **state)
{
    (void)state;
    multiview_manifest("mvimg", 0, 0); /* renders the images */
    const char *ds = tu_fmt("%s/dup_ds.tsv", tu_dir);
    char dsp[4096];
    snprintf(dsp, sizeof dsp, "%s", ds);
    const char *text = "path\ttheta_l\tphi_l\ttheta_v\tphi_v\n"
                       "mv_v0_l0.png\t0\t0\t0\t0\n"
                       "mv_v0_l1.png\t30\t0\t0\t0\n"
                       "mv_v0_l0.png\t30\t90\t0\t0\n";
    tu_write_file(dsp, text, strlen(text));
    btf_error e = {0};
    btf_dataset *d;
    btf_dataset_opts o = {.skip_verify = 1};
    assert_int_not_equal(btf_dataset_open(dsp, &o, &d, &e), 0);
    assert_non_null(strstr(e.msg, "mv_v0_l0.png is listed again (first on line 2)"));
    assert_non_null(strstr(e.msg, tu_fmt("%s:4", dsp)));
    char *err = NULL;
    assert_int_equal(tu_run(tu_fmt("%s info %s", tu_cli(), dsp), &err), 1);
    assert_non_null(strstr(err, "listed again"));
    free(err);
    const char *png = tu_fmt("%s/mv_v0_l0.png", tu_dir);
    assert_int_equal(tu_run(tu_fmt("%s info %s", tu_cli(), png), &err), 1);
    assert_non_null(strstr(err, "a PNG image of 24x24"));
    assert_non_null(strstr(err, "texture-fit"));
    assert_null(strstr(err, "not a text file"));
    assert_true(strchr(err, '\n') == err + strlen(err) - 1);
    free(err);
}

static void collect_warning(void *user, const char *msg)
{
    char *buf = user;
    size_t n = strlen(buf);
    snprintf(buf + n, 4096 - n, "%s\n", msg);
}

/* The CAR fit's variance floor is relative: an image scaled by 1e-30 (or
 * 1e-35) gives the same neighbourhoods and coefficients as the original and
 * sigmas scaled alike, not an empty model. A band below the floor is
 * treated as constant with a warning. */
static void variance_floor_is_relative(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image img;
    tu_material_image("wood", 32, 4, (btf_dir){0, 0}, (btf_dir){30, 0}, &img);
    btf_fit_opts fo = btf_fit_defaults();
    fo.levels = 2;
    btf_model ref;
    TU_OK(btf_texture_fit(&img, &fo, &ref, &e), &e);
    const double scales[] = {1e-30, 1e-35, 1e30};
    for (int k = 0; k < 3; k++) {
        btf_image s;
        TU_OK(btf_image_alloc(&s, img.width, img.height, 3, &e), &e);
        for (size_t i = 0; i < (size_t)img.width * img.height * 3; i++)
            s.data[i] = (float)(img.data[i] * scales[k]);
        btf_model m;
        TU_OK(btf_texture_fit(&s, &fo, &m, &e), &e);
        int modelled = 0;
        for (int b = 0; b < 3; b++)
            for (int l = 0; l < 2; l++) {
                const btf_car_band *x = &m.subspaces[0].bands[b][l], *r = &ref.subspaces[0].bands[b][l];
                assert_int_equal(x->n, r->n);
                modelled += x->n > 0 && x->sigma > 0.0f;
                for (int i = 0; i < x->n; i++)
                    assert_true(fabs(x->gamma[i] - r->gamma[i]) < 0.02);
                if (r->sigma > 0.0f)
                    assert_true(fabs(x->sigma / (r->sigma * scales[k]) - 1.0) < 0.02);
            }
        assert_true(modelled > 0);
        btf_model_free(&m);
        btf_image_free(&s);
    }
    btf_model_free(&ref);
    btf_image_free(&img);
    /* A band of 1 + 1e-14 noise: constant, with a warning saying so. */
    enum { W = 16 };
    double band[W * W];
    for (int i = 0; i < W * W; i++)
        band[i] = 1.0 + 1e-14 * ((i * 7919) % 13 - 6);
    char warned[4096] = "";
    btf_car_fit_opts co = btf_car_fit_defaults();
    co.warn = collect_warning;
    co.warn_user = warned;
    btf_car_band out;
    TU_OK(btf__car_fit(band, W, W, &co, &out, NULL, &e), &e);
    assert_int_equal(out.n, 0);
    assert_non_null(strstr(warned, "treated as constant"));
}

/* --levels beyond what the image allows is capped, and the cap is said. */
static void levels_cap_is_printed(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image img;
    tu_material_image("leather", 20, 1, (btf_dir){0, 0}, (btf_dir){30, 0}, &img);
    const char *png = tu_fmt("%s/small.png", tu_dir);
    char p[4096];
    snprintf(p, sizeof p, "%s", png);
    TU_OK(btf_image_write_png(p, &img, &e), &e);
    btf_image_free(&img);
    char *err = NULL;
    assert_int_equal(tu_run(tu_fmt("%s texture-fit %s -o %s.btfcar --levels 8", tu_cli(), p, p),
                            &err), 0);
    assert_non_null(strstr(err, "8 pyramid levels asked for, 5 used"));
    free(err);
    /* --quiet: nothing but errors, so not this warning either. */
    assert_int_equal(tu_run(tu_fmt("%s texture-fit -q %s -o %s.btfcar --levels 8", tu_cli(), p, p),
                            &err), 0);
    assert_string_equal(err, "");
    free(err);
    btf_model m;
    TU_OK(btf_model_read(tu_fmt("%s.btfcar", p), &m, &e), &e);
    assert_int_equal(m.subspaces[0].levels, 5);
    btf_model_free(&m);
}

/* A 1-pixel checkerboard: the fit says how much of the variance the model
 * misses (a warning, which --quiet silences as it does all but errors), and
 * info says it again. */
static void periodic_pattern_reported(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image img;
    TU_OK(btf_image_alloc(&img, 48, 48, 3, &e), &e);
    for (int y = 0; y < 48; y++)
        for (int x = 0; x < 48; x++)
            for (int c = 0; c < 3; c++)
                img.data[(y * 48 + x) * 3 + c] = ((x + y) & 1) ? 0.8f : 0.2f;
    char png[4096];
    snprintf(png, sizeof png, "%s/checker.png", tu_dir);
    TU_OK(btf_image_write_png(png, &img, &e), &e);
    btf_image_free(&img);
    char *err = NULL;
    assert_int_equal(tu_run(tu_fmt("%s texture-fit %s -o %s.btfcar --levels 1", tu_cli(), png,
                                   png), &err), 0);
    assert_non_null(strstr(err, "btfcar texture-fit: warning: "));
    assert_non_null(strstr(err, "the model misses"));
    assert_non_null(strstr(err, "of the band's variance"));
    free(err);
    assert_int_equal(tu_run(tu_fmt("%s texture-fit -q %s -o %s.btfcar --levels 1", tu_cli(), png,
                                   png), &err), 0);
    assert_string_equal(err, "");
    free(err);
    int st;
    char *out = tu_capture(tu_fmt("%s info %s.btfcar", tu_cli(), png), &st);
    assert_int_equal(st, 0);
    assert_non_null(strstr(out, "of its variance in synthesis (a periodic pattern?)"));
    free(out);
    btf_model m;
    TU_OK(btf_model_read(tu_fmt("%s.btfcar", png), &m, &e), &e);
    double missed = -1;
    TU_OK(btf_synth_missed_variance(&m, 0, 0, 0, &missed, &e), &e);
    assert_true(missed > 0.5);
    btf_model_free(&m);
    /* An ordinary texture misses nothing and says nothing. */
    tu_material_image("wood", 32, 4, (btf_dir){0, 0}, (btf_dir){30, 0}, &img);
    TU_OK(btf_image_write_png(png, &img, &e), &e);
    btf_image_free(&img);
    assert_int_equal(tu_run(tu_fmt("%s texture-fit -q %s -o %s.btfcar", tu_cli(), png, png), &err),
                     0);
    assert_null(strstr(err, "the model misses"));
    free(err);
    out = tu_capture(tu_fmt("%s info %s.btfcar", tu_cli(), png), &st);
    assert_null(strstr(out, "misses"));
    free(out);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(unstable_model_rejected),
        cmocka_unit_test(slowly_growing_model_rejected),
        cmocka_unit_test(stability_check_is_cheap),
        cmocka_unit_test(photostereo_multiview_manifest),
        cmocka_unit_test(numbers_are_strict),
        cmocka_unit_test(duplicates_and_info_on_image),
        cmocka_unit_test(variance_floor_is_relative),
        cmocka_unit_test(levels_cap_is_printed),
        cmocka_unit_test(periodic_pattern_reported),
    };
    return cmocka_run_group_tests_name("validate", tests, tu_setup_dir, tu_teardown_dir);
}
