/*
 * test_analyse.c — the whole analysis (src/analyse/analyse.c, btf_analyse) and
 * `btfcar analyse`: the range tile of non-square images, the report of the
 * segmentation, the options --stage segment refuses, and the tables it
 * writes (atomically, errors naming the file).
 */
#include "testutil.h"
#include "range/range.h"

#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>

/* The lights of the small datasets: three rings of four. */
#define N_LIGHTS 12
static const double LIGHT_THETA[3] = {30, 45, 60};

/* A manifest dataset of one view (theta_v = 0) under N_LIGHTS lights, of
 * width x height pixels: the top-left corner of leather rendered square.
 * The generator only makes square images; a manifest takes any size. The
 * manifest's path goes to manifest. */
static void make_dataset(const char *where, int width, int height, char *manifest, size_t n)
{
    char dir[4096];
    snprintf(dir, sizeof dir, "%s", where); /* tu_fmt's slots get reused */
    btf_error e = {0};
    btf_procedural mat;
    int side = width > height ? width : height;
    TU_OK(btf_procedural_make("leather", side, 5, &mat, &e), &e);
    mkdir(dir, 0777);
    snprintf(manifest, n, "%s/list.tsv", dir);
    FILE *f = fopen(manifest, "w");
    assert_non_null(f);
    fprintf(f, "path\ttheta_l\tphi_l\ttheta_v\tphi_v\n");
    for (int l = 0; l < N_LIGHTS; l++) {
        btf_dir light = {LIGHT_THETA[l / 4], 90.0 * (l % 4) + 20.0 * (l / 4)};
        btf_image full, img;
        TU_OK(btf_procedural_render(&mat, (btf_dir){0, 0}, light, &full, &e), &e);
        TU_OK(btf_image_alloc(&img, width, height, 3, &e), &e);
        for (int y = 0; y < height; y++)
            memcpy(img.data + (size_t)y * width * 3, full.data + (size_t)y * side * 3,
                   (size_t)width * 3 * sizeof(float));
        TU_OK(btf_image_write_exr_opts(tu_fmt("%s/l%02d.exr", dir, l), &img, NULL, NULL, &e), &e);
        fprintf(f, "l%02d.exr\t%g\t%g\t0\t0\n", l, light.theta, light.phi);
        btf_image_free(&full);
        btf_image_free(&img);
    }
    assert_int_equal(fclose(f), 0);
    btf_procedural_free(&mat);
}

static char wide[4096], tall[4096]; /* manifests: 48 x 20 and 20 x 48 */

static int setup(void **state)
{
    tu_setup_dir(state);
    make_dataset(tu_fmt("%s/wide", tu_dir), 48, 20, wide, sizeof wide);
    make_dataset(tu_fmt("%s/tall", tu_dir), 20, 48, tall, sizeof tall);
    return 0;
}

/* Quick options: the range tile is what is looked at, not the CAR models. */
static btf_analyse_opts quick_opts(int range_size)
{
    btf_analyse_opts o = {.range_size = range_size};
    o.segment.subspaces = 2;
    o.segment.kmeans.seed = 1;
    o.fit.levels = 1;
    o.fit.car.max_neighbours = 2;
    return o;
}

/* The tile of a W x H image: a texel of s = texel image pixels along both
 * axes, tw x th whole texels, each the mean height of the pixels whose
 * centres fall in it (pixels beyond the last whole texel left out), the
 * whole then made periodic. */
static void check_tile(const char *manifest, int range_size, int want_w, int want_h,
                       double want_texel)
{
    btf_error e = {0};
    btf_dataset *ds;
    TU_OK(btf_dataset_open(manifest, NULL, &ds, &e), &e);
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    btf_analyse_opts o = quick_opts(range_size);
    btf_model m;
    TU_OK(btf_analyse(ds, &o, &m, &e), &e);
    assert_int_equal(m.range_width, want_w);
    assert_int_equal(m.range_height, want_h);
    assert_true(fabs(m.range_texel - want_texel) < 1e-6);
    /* One scale for both axes: the tile covers the image up to less than one
     * texel on each axis. */
    double s = want_texel; /* range_texel is its float */
    assert_true(m.range_width * s <= in->width + 1e-9 && in->width - m.range_width * s < s);
    assert_true(m.range_height * s <= in->height + 1e-9 && in->height - m.range_height * s < s);

    /* The tile's values against the height map binned here. */
    btf_ps_result ps;
    TU_OK(btf__photostereo_dataset(ds, &o.photostereo, &ps, &e), &e);
    int tw = m.range_width, th = m.range_height, cells = tw * th;
    double *acc = calloc((size_t)cells, sizeof *acc);
    int *cnt = calloc((size_t)cells, sizeof *cnt);
    for (int y = 0; y < in->height; y++)
        for (int x = 0; x < in->width; x++) {
            int tx = (int)floor((x + 0.5) / s), ty = (int)floor((y + 0.5) / s);
            if (tx < tw && ty < th) {
                acc[ty * tw + tx] += ps.height.data[y * in->width + x];
                cnt[ty * tw + tx]++;
            }
        }
    /* ... made periodic (docs/render.md, "Range and normal map"). */
    float *want = malloc(sizeof *want * (size_t)cells);
    for (int i = 0; i < cells; i++) {
        assert_true(cnt[i] > 0);
        want[i] = (float)(acc[i] / cnt[i]);
    }
    /* at texel 1 kept as measured, to 1/32 texel, and not made periodic
     * (it is quilted: model/structure_map.c) */
    double tol = s == 1.0 ? 0.5 / 32 + 1e-5 : 0.0;
    if (s != 1.0)
        TU_OK(btf_range_make_periodic(want, tw, th, &e), &e);
    for (int i = 0; i < cells; i++)
        if (fabs(m.range[i] - want[i]) > tol + 1e-5 * (1.0 + fabs(want[i])))
            fail_msg("%s, size %d: tile texel %d is %g, expected %g", manifest, range_size, i,
                     m.range[i], want[i]);
    free(want);
    free(acc);
    free(cnt);
    btf_ps_result_free(&ps);
    /* The model file keeps it. */
    const char *path = tu_fmt("%s/tile.btfcar", tu_dir);
    TU_OK(btf_model_write(path, &m, &e), &e);
    btf_model r;
    TU_OK(btf_model_read(path, &r, &e), &e);
    assert_int_equal(r.range_width, tw);
    assert_int_equal(r.range_height, th);
    assert_true(r.range_texel == m.range_texel);
    btf_model_free(&r);
    btf_model_free(&m);
    btf_dataset_close(ds);
}

static void range_tile_non_square(void **state)
{
    (void)state;
    /* The longer side gets range_size texels; the shorter as many of the
     * same size as fit: 48 x 20 at 16 is a 3-pixel texel, 16 x 6. */
    check_tile(wide, 16, 16, 6, 3.0);
    check_tile(tall, 16, 6, 16, 3.0);
    /* A scale that is no whole number: 48 / 10 = 4.8 pixels, 10 x 4. */
    check_tile(wide, 10, 10, 4, 4.8);
    check_tile(tall, 10, 4, 10, 4.8);
    /* At most the image: 48 x 20 at 64 keeps every pixel. */
    check_tile(wide, 64, 48, 20, 1.0);
    /* Aspect beyond range_size : 1: a texel is at most the shorter side. */
    check_tile(wide, 2, 2, 1, 20.0);
}

/* btf_analyse reports the segmentation's reason: the one btf_segment gives
 * for the same options. */
static void report_gives_segmentation_reason(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_dataset *ds;
    TU_OK(btf_dataset_open(wide, NULL, &ds, &e), &e);
    btf_analyse_opts o = quick_opts(8);
    o.segment.subspaces = 0; /* auto: the reason says why K */
    btf_analyse_report report;
    memset(&report, 0x55, sizeof report); /* filled in, not left as it was */
    o.report = &report;
    btf_model m;
    TU_OK(btf_analyse(ds, &o, &m, &e), &e);
    btf_segmentation s;
    TU_OK(btf_segment(ds, &o.segment, &s, &e), &e);
    assert_true(strlen(s.reason) > 0);
    assert_string_equal(report.segment_reason, s.reason);
    assert_int_equal(m.n_subspaces, s.k);
    btf_segmentation_free(&s);
    btf_model_free(&m);
    btf_dataset_close(ds);
}

/* NULL, the zeroed options and btf_analyse_defaults() give one model. */
static void defaults_equal_zero(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_dataset *ds;
    TU_OK(btf_dataset_open(wide, NULL, &ds, &e), &e);
    btf_analyse_opts zero = {0}, d = btf_analyse_defaults();
    const btf_analyse_opts *opts[3] = {NULL, &zero, &d};
    unsigned char *bytes[3];
    size_t n[3];
    for (int i = 0; i < 3; i++) {
        btf_model m;
        TU_OK(btf_analyse(ds, opts[i], &m, &e), &e);
        TU_OK(btf_model_encode(&m, &bytes[i], &n[i], &e), &e);
        btf_model_free(&m);
    }
    for (int i = 1; i < 3; i++) {
        assert_int_equal(n[i], n[0]);
        assert_memory_equal(bytes[i], bytes[0], n[0]);
    }
    for (int i = 0; i < 3; i++)
        free(bytes[i]);
    btf_dataset_close(ds);
}

/* The "segmentation: ..." line of a command's output (malloc'd), or NULL. */
static char *reason_line(const char *text)
{
    const char *p = strstr(text, "segmentation: ");
    if (!p)
        return NULL;
    size_t n = strcspn(p, "\n");
    return strndup(p, n);
}

static int models_equal(const char *a, const char *b)
{
    btf_error e = {0};
    btf_model ma, mb;
    unsigned char *x = NULL, *y = NULL;
    size_t nx = 0, ny = 0;
    if (btf_model_read(a, &ma, &e) || btf_model_read(b, &mb, &e))
        return 0;
    TU_OK(btf_model_encode(&ma, &x, &nx, &e), &e);
    TU_OK(btf_model_encode(&mb, &y, &ny, &e), &e);
    int eq = nx == ny && memcmp(x, y, nx) == 0;
    free(x);
    free(y);
    btf_model_free(&ma);
    btf_model_free(&mb);
    return eq;
}

/* The full analysis prints the segmentation's reason like --stage segment
 * does; --threads reaches every stage and changes no result. */
static void cli_prints_segmentation_reason(void **state)
{
    (void)state;
    int st;
    const char *model = tu_fmt("%s/cli.btfcar", tu_dir);
    char *full = tu_capture(tu_fmt("%s analyse %s -o %s --levels 1 --max-neighbours 2 --threads 1 "
                                "2>&1", tu_cli(), wide, model), &st);
    assert_int_equal(st, 0);
    char *seg = tu_capture(tu_fmt("%s analyse %s -o %s/seg --stage segment 2>&1", tu_cli(), wide,
                               tu_dir), &st);
    assert_int_equal(st, 0);
    char *a = reason_line(full), *b = reason_line(seg);
    if (!a)
        fail_msg("no segmentation line in:\n%s", full);
    assert_non_null(b);
    assert_true(strlen(a) > strlen("segmentation: "));
    assert_string_equal(a, b);
    free(a);
    free(b);
    free(full);
    free(seg);
    /* --quiet: no report at all. */
    const char *model3 = tu_fmt("%s/cli3.btfcar", tu_dir);
    full = tu_capture(tu_fmt("%s analyse -q %s -o %s --levels 1 --max-neighbours 2 --threads 3",
                          tu_cli(), wide, model3), &st);
    assert_int_equal(st, 0);
    assert_string_equal(full, "");
    free(full);
    assert_true(models_equal(tu_fmt("%s/cli.btfcar", tu_dir), model3));
}

/* Options that only the later stages use are a usage error with --stage
 * segment (exit 2, the option named, nothing written), wherever they stand. */
static void cli_segment_rejects_model_options(void **state)
{
    (void)state;
    const char *opts[][2] = {
        {"--levels 2", "--levels"},
        {"--neighbourhood 0:-1", "--neighbourhood"},
        {"--neighborhood auto", "--neighborhood"},
        {"--max-neighbours 3", "--max-neighbours"},
        {"--no-range", "--no-range"},
        {"--range-size 8", "--range-size"},
    };
    const char *out = tu_fmt("%s/rejected", tu_dir);
    char outc[4096];
    snprintf(outc, sizeof outc, "%s", out);
    for (size_t i = 0; i < sizeof opts / sizeof opts[0]; i++) {
        char *err = NULL;
        int rc = tu_run(tu_fmt("%s analyse %s -o %s --stage segment %s", tu_cli(), wide, outc,
                               opts[i][0]), &err);
        assert_int_equal(rc, 2);
        if (!strstr(err, opts[i][1]) || !strstr(err, "--stage segment"))
            fail_msg("'%s': %s", opts[i][0], err);
        free(err);
        rc = tu_run(tu_fmt("%s analyse %s %s -o %s --stage segment", tu_cli(), opts[i][0], wide,
                           outc), &err);
        assert_int_equal(rc, 2);
        assert_non_null(strstr(err, opts[i][1]));
        free(err);
        struct stat sb;
        assert_int_not_equal(stat(outc, &sb), 0);
    }
    /* The segmentation's own options are fine. */
    char *err = NULL;
    int rc = tu_run(tu_fmt("%s analyse -q %s -o %s --stage segment --subspaces 2 --bins 16 "
                           "--seed 3 --restarts 2 --threads 2", tu_cli(), wide, outc), &err);
    if (rc)
        print_error("%s\n", err);
    assert_int_equal(rc, 0);
    free(err);
}

/* Names in a folder that look temporary ("*.tmp*"). */
static int temporaries(const char *dir)
{
    DIR *d = opendir(dir);
    assert_non_null(d);
    int n = 0;
    struct dirent *ent;
    while ((ent = readdir(d)))
        n += strstr(ent->d_name, ".tmp") != NULL;
    closedir(d);
    return n;
}

static int count_lines(const char *path)
{
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    int n = 0, c;
    while ((c = fgetc(f)) != EOF)
        n += c == '\n';
    fclose(f);
    return n;
}

/* --stage segment writes whole tables and no temporary files; a table that
 * cannot be written is an error naming it (exit 1) that leaves no temporary
 * file behind. */
/* `analyse --stage segment --subspaces 3` of the wide dataset into dir,
 * which must succeed. */
static void segment_into(const char *dir)
{
    char *err = NULL;
    int rc = tu_run(tu_fmt("%s analyse -q %s -o %s --stage segment --subspaces 3", tu_cli(), wide,
                           dir), &err);
    if (rc)
        print_error("%s\n", err);
    assert_int_equal(rc, 0);
    free(err);
}

static void cli_segment_tables_atomic(void **state)
{
    (void)state;
    char out[4096];
    snprintf(out, sizeof out, "%s/tables", tu_dir);
    segment_into(out);
    assert_int_equal(count_lines(tu_fmt("%s/index.tsv", out)), 1 + N_LIGHTS);
    assert_int_equal(count_lines(tu_fmt("%s/subspaces.tsv", out)), 1 + 3);
    /* index.png, two tables, an EXR and a PNG per subspace: nothing else. */
    assert_int_equal(tu_count_files(out), 3 + 2 * 3);
    assert_int_equal(temporaries(out), 0);

    /* Temporary names are unique: files that happen to be called like a
     * fixed temporary name (NAME.tmp) neither block the tables nor get
     * overwritten. */
    char busy[4096];
    snprintf(busy, sizeof busy, "%s/busy", tu_dir);
    mkdir(busy, 0777);
    mkdir(tu_fmt("%s/index.tsv.tmp", busy), 0777);
    tu_write_file(tu_fmt("%s/subspaces.tsv.tmp", busy), "mine", 4);
    segment_into(busy);
    assert_int_equal(count_lines(tu_fmt("%s/index.tsv", busy)), 1 + N_LIGHTS);
    struct stat sb;
    assert_int_equal(stat(tu_fmt("%s/subspaces.tsv.tmp", busy), &sb), 0);
    assert_int_equal(sb.st_size, 4);
    assert_int_equal(temporaries(busy), 2);

    const char *names[] = {"index.tsv", "subspaces.tsv"};
    for (int i = 0; i < 2; i++) {
        char bad[4096];
        snprintf(bad, sizeof bad, "%s/bad%d", tu_dir, i);
        mkdir(bad, 0777);
        /* A folder where the table goes: the rename into place fails. */
        mkdir(tu_fmt("%s/%s", bad, names[i]), 0777);
        char *err = NULL;
        int rc = tu_run(tu_fmt("%s analyse -q %s -o %s --stage segment --subspaces 3", tu_cli(),
                               wide, bad), &err);
        assert_int_equal(rc, 1);
        /* One line naming the file (under ASan, LeakSanitizer may add its
         * summary of suppressions after it). */
        if (!getenv("BTF_ASAN"))
            assert_true(strchr(err, '\n') == err + strlen(err) - 1);
        err[strcspn(err, "\n")] = '\0';
        if (!strstr(err, tu_fmt("%s/%s", bad, names[i])))
            fail_msg("expected the path of %s in: %s", names[i], err);
        free(err);
        assert_int_equal(temporaries(bad), 0);
    }
}

/* The public atomic writer: whole files, errors with a code and the path. */
static void write_file_atomic(void **state)
{
    (void)state;
    btf_error e = {0};
    char dir[4096];
    snprintf(dir, sizeof dir, "%s/atomic", tu_dir);
    mkdir(dir, 0777);
    const char *path = tu_fmt("%s/a.txt", dir);
    char p[4096];
    snprintf(p, sizeof p, "%s", path);
    TU_OK(btf_write_file_atomic(p, "first\n", 6, &e), &e);
    TU_OK(btf_write_file_atomic(p, "second\n", 7, &e), &e);
    assert_int_equal(count_lines(p), 1);
    struct stat sb;
    assert_int_equal(stat(p, &sb), 0);
    assert_int_equal(sb.st_size, 7);
    TU_OK(btf_write_file_atomic(tu_fmt("%s/empty", dir), NULL, 0, &e), &e);
    /* A missing folder, and a folder in the way. */
    e = (btf_error){0};
    const char *missing = tu_fmt("%s/no/such/b.txt", dir);
    assert_int_equal(btf_write_file_atomic(missing, "x", 1, &e), BTF_E_IO);
    assert_int_equal(e.code, BTF_E_IO);
    assert_non_null(strstr(e.msg, missing));
    e = (btf_error){0};
    mkdir(tu_fmt("%s/d", dir), 0777);
    assert_int_equal(btf_write_file_atomic(tu_fmt("%s/d", dir), "x", 1, &e), BTF_E_IO);
    assert_int_equal(e.code, BTF_E_IO);
    assert_non_null(strstr(e.msg, tu_fmt("%s/d", dir)));
    assert_int_equal(temporaries(dir), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(range_tile_non_square),
        cmocka_unit_test(report_gives_segmentation_reason),
        cmocka_unit_test(defaults_equal_zero),
        cmocka_unit_test(cli_prints_segmentation_reason),
        cmocka_unit_test(cli_segment_rejects_model_options),
        cmocka_unit_test(cli_segment_tables_atomic),
        cmocka_unit_test(write_file_atomic),
    };
    return cmocka_run_group_tests_name("analyse", tests, setup, tu_teardown_dir);
}
