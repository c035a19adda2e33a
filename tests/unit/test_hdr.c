/*
 * test_hdr.c — linear float datasets in any units: the analysis of a linear
 * EXR dataset x 1000 gives the range map and the segmentation of the same
 * dataset x 1 (photometric stereo's clip level follows the data's peak beyond
 * 1, src/range/photostereo.c; the Lab features divide float data by their
 * white level, src/segment/features.c); most pixels without a fit is a
 * warning that names the dataset and --saturation; bad --saturation values
 * are usage errors.
 */
#include "testutil.h"
#include "analyse/analyse.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define SIDE 24
#define N_VIEWS 4
#define N_LIGHTS 25

static const btf_dir VIEWS[N_VIEWS] = {{0, 0}, {30, 0}, {30, 180}, {60, 90}};

/* Light l: the pole, then rings of 6, 8 and 10 at 20, 40 and 60 degrees. */
static btf_dir light_dir(int l)
{
    if (l == 0)
        return (btf_dir){0, 0};
    int ring = l <= 6 ? 0 : l <= 14 ? 1 : 2, first = (int[]){1, 7, 15}[ring];
    int count = (int[]){6, 8, 10}[ring];
    return (btf_dir){20.0 * (ring + 1), 360.0 * (l - first) / count};
}

/* Manifests: x1 (leather, half floats as btfcar export writes them), x1000
 * (the same values x 1000 in float EXR: exact, a half has 11 significant
 * bits) and the overexposed view 0 alone (x 200, clipped at 1). */
static char x1[4096], x1000[4096], over[4096];

static FILE *open_manifest(char *path, size_t n, const char *name)
{
    snprintf(path, n, "%s/%s.tsv", tu_dir, name);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, "path\ttheta_l\tphi_l\ttheta_v\tphi_v\n");
    return f;
}

/* Writes img x scale (clipped at 1 when clip) as float EXR name. */
static void write_scaled(const btf_image *img, float scale, int clip, const char *name)
{
    btf_error e = {0};
    btf_image s;
    TU_OK(btf_image_alloc(&s, img->width, img->height, img->channels, &e), &e);
    size_t n = (size_t)img->width * img->height * img->channels;
    for (size_t i = 0; i < n; i++) {
        float v = img->data[i] * scale;
        s.data[i] = clip && v > 1.0f ? 1.0f : v;
    }
    TU_OK(btf_image_write_exr_opts(tu_fmt("%s/%s", tu_dir, name), &s, NULL, NULL, &e), &e);
    btf_image_free(&s);
}

static int setup(void **state)
{
    tu_setup_dir(state);
    btf_error e = {0};
    btf_procedural mat;
    TU_OK(btf_procedural_make("leather", SIDE, 5, &mat, &e), &e);
    FILE *f1 = open_manifest(x1, sizeof x1, "x1");
    FILE *f1000 = open_manifest(x1000, sizeof x1000, "x1000");
    FILE *fo = open_manifest(over, sizeof over, "over");
    for (int v = 0; v < N_VIEWS; v++)
        for (int l = 0; l < N_LIGHTS; l++) {
            btf_dir light = light_dir(l);
            btf_image img, half;
            TU_OK(btf_procedural_render(&mat, VIEWS[v], light, &img, &e), &e);
            char name[64], path[4096], scaled[80];
            snprintf(name, sizeof name, "v%d_l%02d", v, l);
            snprintf(path, sizeof path, "%s/%s.exr", tu_dir, name);
            TU_OK(btf_image_write_exr_opts(path, &img, &(btf_exr_opts){.half = 1}, NULL, &e), &e);
            TU_OK(btf_image_read(path, NULL, &half, &e), &e); /* the values x1 holds */
            snprintf(scaled, sizeof scaled, "%s_k.exr", name);
            write_scaled(&half, 1000.0f, 0, scaled);
            char dirs[128];
            snprintf(dirs, sizeof dirs, "%g\t%g\t%g\t%g", light.theta, light.phi,
                     VIEWS[v].theta, VIEWS[v].phi);
            fprintf(f1, "%s.exr\t%s\n", name, dirs);
            fprintf(f1000, "%s_k.exr\t%s\n", name, dirs);
            if (v == 0) {
                snprintf(scaled, sizeof scaled, "%s_o.exr", name);
                write_scaled(&half, 200.0f, 1, scaled);
                fprintf(fo, "%s_o.exr\t%s\n", name, dirs);
            }
            btf_image_free(&img);
            btf_image_free(&half);
        }
    assert_int_equal(fclose(f1), 0);
    assert_int_equal(fclose(f1000), 0);
    assert_int_equal(fclose(fo), 0);
    btf_procedural_free(&mat);
    return 0;
}

static btf_dataset *open_dataset(const char *manifest)
{
    btf_error e = {0};
    btf_dataset *ds;
    TU_OK(btf_dataset_open(manifest, NULL, &ds, &e), &e);
    return ds;
}

/* The range tile of btfcar analyse (stage 2 with the default options). */
static void range_of(const char *manifest, btf_model *m)
{
    btf_error e = {0};
    btf_dataset *ds = open_dataset(manifest);
    btf_analyse_opts o = btf_analyse_defaults();
    o.photostereo.threads = 2;
    memset(m, 0, sizeof *m);
    TU_OK(btf__analyse_range(ds, &o, m, &e), &e);
    btf_dataset_close(ds);
}

static double spread(const btf_model *m)
{
    double lo = INFINITY, hi = -INFINITY;
    for (int i = 0; i < m->range_width * m->range_height; i++) {
        lo = fmin(lo, m->range[i]);
        hi = fmax(hi, m->range[i]);
    }
    return hi - lo;
}

/* x 1000 beyond full scale 1: photometric stereo clips at 0.99 x the peak,
 * not at 0.99, so the range map is the x 1 one (heights are kept to 1/32
 * texel), not flat. */
static void range_map_does_not_depend_on_units(void **state)
{
    (void)state;
    btf_model a, b;
    range_of(x1, &a);
    range_of(x1000, &b);
    print_message("height spread: x1 %.4f, x1000 %.4f texels\n", spread(&a), spread(&b));
    assert_true(spread(&a) > 0.5); /* leather's relief, not a flat map */
    assert_int_equal(a.range_width, b.range_width);
    assert_int_equal(a.range_height, b.range_height);
    int differ = 0;
    for (int i = 0; i < a.range_width * a.range_height; i++)
        differ += fabsf(a.range[i] - b.range[i]) > 1.0f / 32 + 1e-6f;
    assert_int_equal(differ, 0);
    assert_true(fabs(spread(&a) - spread(&b)) <= 1.0 / 16 + 1e-6);
    btf_model_free(&a);
    btf_model_free(&b);
}

static void segment_of(const char *manifest, btf_segmentation *s)
{
    btf_error e = {0};
    btf_dataset *ds = open_dataset(manifest);
    btf_segment_opts o = btf_segment_defaults();
    o.kmeans.seed = 1;
    o.features.threads = 2;
    TU_OK(btf_segment(ds, &o, s, &e), &e);
    btf_dataset_close(ds);
}

/* The Lab features divide float data by their white level: x 1000 gives
 * the same features bit for bit, so the same K and the same index table,
 * where it used to turn most images white (one subspace). */
static void segmentation_does_not_depend_on_units(void **state)
{
    (void)state;
    btf_segmentation a, b;
    segment_of(x1, &a);
    segment_of(x1000, &b);
    int n = N_VIEWS * N_LIGHTS, largest = 0;
    for (int k = 0; k < a.k; k++)
        largest = a.members[k] > largest ? a.members[k] : largest;
    print_message("x1: K = %d, largest subspace %d of %d images; x1000: K = %d\n", a.k, largest,
                  n, b.k);
    assert_true(a.k >= 3 && 2 * largest < n); /* a segmentation, not one subspace */
    assert_int_equal(b.k, a.k);
    assert_memory_equal(b.index, a.index, (size_t)n);
    assert_memory_equal(b.members, a.members, (size_t)a.k * sizeof *a.members);
    btf_segmentation_free(&a);
    btf_segmentation_free(&b);
}

/* An overexposed capture (most samples clipped at 1) leaves most pixels
 * without a fit: btfcar analyse warns in one line naming the dataset and
 * --saturation (--quiet silences it, as every warning); with the rule off
 * (--saturation 0) every pixel is fitted and there is no warning. */
static void most_pixels_clipped_is_a_warning(void **state)
{
    (void)state;
    char *err = NULL;
    const char *model = tu_fmt("%s/over.btfcar", tu_dir);
    int rc = tu_run(tu_fmt("%s analyse %s -o %s --levels 1 --max-neighbours 2 --threads 2",
                           tu_cli(), over, model), &err);
    assert_int_equal(rc, 0);
    assert_non_null(err);
    print_message("%s", err);
    const char *line = strstr(err, BTF_RANGE_FLAT_TEXT);
    assert_non_null(line);
    while (line > err && line[-1] != '\n') /* the warning's own line */
        line--;
    const char *end = strchr(line, '\n');
    assert_non_null(end);
    char one[4096];
    snprintf(one, sizeof one, "%.*s", (int)(end - line), line);
    assert_non_null(strstr(one, "btfcar analyse: warning: "));
    assert_non_null(strstr(one, over));
    assert_non_null(strstr(one, "--saturation"));
    free(err);
    err = NULL; /* --quiet: nothing but errors */
    rc = tu_run(tu_fmt("%s analyse %s -o %s --quiet --levels 1 --max-neighbours 2 --threads 2",
                       tu_cli(), over, model), &err);
    assert_int_equal(rc, 0);
    assert_true(err == NULL || strstr(err, BTF_RANGE_FLAT_TEXT) == NULL);
    free(err);
    err = NULL;
    rc = tu_run(tu_fmt("%s analyse %s -o %s --quiet --levels 1 --max-neighbours 2 --threads 2 "
                       "--saturation 0", tu_cli(), over, model), &err);
    assert_int_equal(rc, 0);
    assert_true(err == NULL || strstr(err, BTF_RANGE_FLAT_TEXT) == NULL);
    free(err);
    /* btfcar photostereo says the same of its height map. */
    err = NULL;
    rc = tu_run(tu_fmt("%s photostereo %s -o %s/over_ps --threads 2", tu_cli(), over, tu_dir),
                &err);
    assert_int_equal(rc, 0);
    assert_non_null(err);
    assert_non_null(strstr(err, "btfcar photostereo: warning: "));
    assert_non_null(strstr(err, BTF_RANGE_FLAT_TEXT));
    free(err);
}

/* --saturation takes a fraction of full scale: anything else, or a stage
 * that does not use it, is a one-line usage error (exit 2) naming it,
 * before any work; the library refuses the same values. */
static void bad_saturation_is_a_usage_error(void **state)
{
    (void)state;
    const char *bad[] = {"--saturation 1.5", "--saturation -0.5", "--saturation nan",
                         "--saturation inf", "--saturation x", "--saturation ''",
                         "--saturation 0.9 --stage segment", "--saturation 0.9 --no-range",
                         "--saturation 0.9 --family rf"};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        char *err = NULL;
        int rc = tu_run(tu_fmt("%s analyse %s -o %s/bad.out %s", tu_cli(), x1, tu_dir, bad[i]),
                        &err);
        if (rc != 2 || !err || !strstr(err, "--saturation") ||
            strchr(err, '\n') != err + strlen(err) - 1)
            fail_msg("analyse %s: exit %d, %s", bad[i], rc, err ? err : "(nothing)");
        free(err);
    }
    struct stat st;
    assert_int_not_equal(stat(tu_fmt("%s/bad.out", tu_dir), &st), 0);
    char *err = NULL;
    assert_int_equal(tu_run(tu_fmt("%s photostereo %s -o %s/bad_ps --saturation 2", tu_cli(), x1,
                                   tu_dir), &err), 2);
    free(err);

    double L[9] = {0, 0, 1, 1, 0, 1, 0, 1, 1};
    btf_image imgs[3];
    btf_error e = {0};
    for (int i = 0; i < 3; i++) {
        TU_OK(btf_image_alloc(&imgs[i], 2, 2, 1, &e), &e);
        for (int k = 0; k < 4; k++)
            imgs[i].data[k] = 0.5f;
    }
    const double wrong[] = {1.5, NAN, INFINITY};
    for (int i = 0; i < 3; i++) {
        btf_photostereo_opts o = {.saturation = wrong[i]};
        btf_ps_result r;
        assert_int_equal(btf_photostereo(&(btf_ps_input){imgs, 3, L, NULL}, &o, &r, &e),
                         BTF_E_ARG);
        assert_non_null(strstr(e.msg, "saturation"));
    }
    for (int i = 0; i < 3; i++)
        btf_image_free(&imgs[i]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(range_map_does_not_depend_on_units),
        cmocka_unit_test(segmentation_does_not_depend_on_units),
        cmocka_unit_test(most_pixels_clipped_is_a_warning),
        cmocka_unit_test(bad_saturation_is_a_usage_error),
    };
    return cmocka_run_group_tests(tests, setup, tu_teardown_dir);
}
