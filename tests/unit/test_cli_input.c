/* test_cli_input.c — the command line's input edges: direction numbers are
 * decimals, JSON stays UTF-8 whatever the file names, errors name the model,
 * and a frame that cannot fit in memory is refused before the work. */
#include "testutil.h"
#include "core/core.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* Whether the n bytes at s are well-formed UTF-8 (RFC 3629: no overlong
 * forms, no surrogates, nothing past U+10FFFF). */
static int is_utf8(const unsigned char *s, size_t n)
{
    size_t i = 0;
    while (i < n) {
        unsigned b = s[i];
        int more = b < 0x80 ? 0 : b >= 0xC2 && b <= 0xDF ? 1 : b >= 0xE0 && b <= 0xEF ? 2
                 : b >= 0xF0 && b <= 0xF4 ? 3 : -1;
        if (more < 0 || i + (size_t)more >= n)
            return 0;
        unsigned lo = b == 0xE0 ? 0xA0 : b == 0xF0 ? 0x90 : 0x80;
        unsigned hi = b == 0xED ? 0x9F : b == 0xF4 ? 0x8F : 0xBF;
        for (int k = 1; k <= more; k++) {
            unsigned c = s[i + (size_t)k];
            if (c < (k == 1 ? lo : 0x80) || c > (k == 1 ? hi : 0xBF))
                return 0;
        }
        i += (size_t)more + 1;
    }
    return 1;
}

/* The validator itself: what it must refuse and accept. */
static void utf8_validator(void **state)
{
    (void)state;
    const char *good = "plain \xC3\xA9 \xE2\x82\xAC \xF0\x9F\x98\x80";
    assert_true(is_utf8((const unsigned char *)good, strlen(good)));
    assert_false(is_utf8((const unsigned char *)"\xff", 1));
    assert_false(is_utf8((const unsigned char *)"\xC3", 1));         /* cut short */
    assert_false(is_utf8((const unsigned char *)"\xC0\xAF", 2));     /* overlong */
    assert_false(is_utf8((const unsigned char *)"\xED\xA0\x80", 3)); /* a surrogate */
}

/* --view and --light take decimals only: "0x10" is a usage error as
 * docs/cli.md says (strtod would read it as 16), so are inf and nan; a
 * tiny value such as 1e-320 (subnormal: strtod's ERANGE) is a number. */
static void directions_are_decimal(void **state)
{
    (void)state;
    char ds[4096];
    snprintf(ds, sizeof ds, "%s/ds", tu_dir);
    assert_int_equal(tu_run(tu_fmt("%s generate -q --material wood --size 4 %s", tu_cli(), ds),
                            NULL), 0);
    const char *bad[] = {"0x10,0", "0X10,0", "16,0x0", "inf,0", "nan,0", "1e400,0"};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        char *err = NULL;
        int rc = tu_run(tu_fmt("%s export %s --view %s --light 0,0 -o %s/x.png", tu_cli(), ds,
                               bad[i], tu_dir), &err);
        if (rc != 2)
            print_error("--view %s: exit %d, %s\n", bad[i], rc, err);
        assert_int_equal(rc, 2);
        assert_non_null(strstr(err, "--view"));
        free(err);
    }
    char *err = NULL;
    int rc = tu_run(tu_fmt("%s export -q %s --view 1e-320,0 --light 0,1e-320 -o %s/tiny.png",
                           tu_cli(), ds, tu_dir), &err);
    if (rc)
        print_error("%s", err);
    assert_int_equal(rc, 0);
    free(err);
    struct stat st;
    assert_int_equal(stat(tu_fmt("%s/tiny.png", tu_dir), &st), 0);
}

/* info --json of a model whose file name is not UTF-8 (byte 0xff): the
 * document is UTF-8 all the same, the byte written as U+FFFD. */
static void info_json_is_utf8(void **state)
{
    (void)state;
    size_t n;
    unsigned char *model = tu_slurp("tests/data/model-v1.0.btfcar", &n);
    const char *path = tu_fmt("%s/model-\xff.btfcar", tu_dir);
    tu_write_file(path, model, n);
    free(model);
    int st;
    char *out = tu_capture(tu_fmt("%s info --json '%s'", tu_cli(), path), &st);
    assert_int_equal(st, 0);
    assert_true(is_utf8((const unsigned char *)out, strlen(out)));
    assert_non_null(strstr(out, "model-\\ufffd.btfcar"));
    free(out);
}

/* A single-texture model (texture-fit) cannot be rendered: the one-line
 * error names the model file, not only what is wrong with it. */
static void single_texture_render_names_model(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image img;
    tu_material_image("leather", 32, 2, (btf_dir){0, 0}, (btf_dir){30, 0}, &img);
    char png[4096], model[4096];
    snprintf(png, sizeof png, "%s/tex.png", tu_dir);
    snprintf(model, sizeof model, "%s/tex.btfcar", tu_dir);
    TU_OK(btf_image_write_png(png, &img, &e), &e);
    btf_image_free(&img);
    assert_int_equal(tu_run(tu_fmt("%s texture-fit -q %s -o %s --levels 1", tu_cli(), png,
                                   model), NULL), 0);
    char *err = NULL;
    assert_int_equal(tu_run(tu_fmt("%s render %s --view 0,0 --light 30,0 --size 8x8 "
                                   "--backend cpu -o %s/flat.png", tu_cli(), model, tu_dir),
                            &err), 1);
    assert_non_null(strstr(err, tu_fmt("%s: the model is a single texture", model)));
    assert_true(strchr(err, '\n') == err + strlen(err) - 1);
    free(err);
}

/* A model whose view set the renderer cannot triangulate (3 directions on
 * one great circle: a valid model, whose subspaces synthesise, but nothing
 * to interpolate over) is refused by render with an error naming the model
 * and the set; 2 directions render (the renderer's ghost directions,
 * docs/render.md, "Sparse pair sets"). */
static void render_names_model_of_bad_set(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_model m;
    TU_OK(btf_model_read("tests/data/model-v1.0.btfcar", &m, &e), &e);
    m.views.count = 2; /* the index is view-major: its first 2 x 81 entries */
    for (int k = 0; k < m.n_subspaces; k++)
        m.subspaces[k].view = m.subspaces[k].view % 2;
    char model[4096];
    snprintf(model, sizeof model, "%s/two-views.btfcar", tu_dir);
    TU_OK(btf_model_write(model, &m, &e), &e);
    assert_int_equal(tu_run(tu_fmt("%s render -q %s --view 0,0 --light 30,0 --size 8x8 "
                                   "--backend cpu -o %s/two.png", tu_cli(), model, tu_dir),
                            NULL), 0);
    m.views.count = 3; /* the pole and theta 15 at phi 0 and 180: one line */
    m.views.dirs[0] = (btf_dir){0.0, 0.0};
    m.views.dirs[1] = (btf_dir){15.0, 0.0};
    m.views.dirs[2] = (btf_dir){15.0, 180.0};
    for (int k = 0; k < m.n_subspaces; k++)
        m.subspaces[k].view = m.subspaces[k].view % 2;
    snprintf(model, sizeof model, "%s/line-views.btfcar", tu_dir);
    TU_OK(btf_model_write(model, &m, &e), &e);
    btf_model_free(&m);
    char *err = NULL;
    assert_int_equal(tu_run(tu_fmt("%s render %s --view 0,0 --light 30,0 --size 8x8 "
                                   "--backend cpu -o %s/line.png", tu_cli(), model, tu_dir),
                            &err), 1);
    assert_non_null(strstr(err, tu_fmt("%s: its views cannot be rendered: ", model)));
    assert_true(strchr(err, '\n') == err + strlen(err) - 1);
    free(err);
}

/* A direction set with the same direction twice (theta -0 and 0) is not a
 * model: writing it fails naming the file and the set; the renderer could
 * not triangulate it either. */
static void duplicate_direction_refused(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_model m;
    TU_OK(btf_model_read("tests/data/model-v1.0.btfcar", &m, &e), &e);
    m.lights.dirs[1] = (btf_dir){-0.0, m.lights.dirs[0].phi};
    m.lights.dirs[0].theta = 0.0;
    const char *path = tu_fmt("%s/dup.btfcar", tu_dir);
    assert_int_equal(btf_model_write(path, &m, &e), BTF_E_DATA);
    assert_non_null(strstr(e.msg, path));
    assert_non_null(strstr(e.msg, "lights"));
    assert_non_null(strstr(e.msg, "directions 0 and 1 are both (theta 0, phi 0)"));
    btf_model_free(&m);
}

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* A float EXR exemplar name in tu_dir: a 32 x 32 rendered leather texture
 * (values about 0..1) times scale plus offset. Its path (static, tu_fmt). */
static const char *scaled_exemplar(const char *name, float scale, float offset)
{
    btf_error e = {0};
    btf_image img;
    tu_material_image("leather", 32, 2, (btf_dir){0, 0}, (btf_dir){30, 0}, &img);
    for (size_t i = 0; i < (size_t)32 * 32 * 3; i++)
        img.data[i] = img.data[i] * scale + offset;
    const char *path = tu_fmt("%s/%s", tu_dir, name);
    TU_OK(btf_image_write_exr_opts(path, &img, NULL, NULL, &e), &e);
    btf_image_free(&img);
    return path;
}

/* texture-fit of exr: exit status, its stderr in *err (malloc'd); the model
 * goes to tu_dir/model-of-NAME, its path in model (4096 bytes). */
static int fit_exemplar(const char *exr, const char *name, char *model, char **err)
{
    snprintf(model, 4096, "%s/model-of-%s.btfcar", tu_dir, name);
    return tu_run(tu_fmt("%s texture-fit %s -o %s --levels 1 >/dev/null", tu_cli(), exr, model),
                  err);
}

/* An exemplar of values near the float limit (up to 3e38, finite in float
 * EXR) is refused before fitting: one line naming the file and the bound,
 * exit 1, no model written (its bands would overflow synthesis). Values of
 * 1e27, inside the bound, are a model that synthesises (synthesis refuses
 * any row that is not finite). */
static void exemplar_too_large_refused(void **state)
{
    (void)state;
    char model[4096], *err = NULL;
    const char *exr = scaled_exemplar("huge.exr", 3e38f, 0.0f);
    assert_int_equal(fit_exemplar(exr, "huge", model, &err), 1);
    assert_non_null(strstr(err, tu_fmt("%s: values of magnitude up to ", exr)));
    assert_non_null(strstr(err, "are too large to model (expected at most 1e+28"));
    assert_true(strchr(err, '\n') == err + strlen(err) - 1);
    free(err);
    struct stat st;
    assert_int_not_equal(stat(model, &st), 0);
    exr = scaled_exemplar("large.exr", 1e27f, 0.0f);
    assert_int_equal(fit_exemplar(exr, "large", model, NULL), 0);
    assert_int_equal(tu_run(tu_fmt("%s synthesise -q %s --size 96x64 --backend cpu -o %s/large",
                                   tu_cli(), model, tu_dir), NULL), 0); /* finite rows */
    assert_int_equal(stat(tu_fmt("%s/large/subspace_00.exr", tu_dir), &st), 0);
}

/* An exemplar of only negative values (all -0.5) is refused naming the
 * file, exit 1, no model (its synthesis was all zeros, silently); one of
 * about half negative values fits with a warning naming the file (--quiet:
 * none); an all-zero image is a black texture and fits silently. */
static void negative_exemplar(void **state)
{
    (void)state;
    char model[4096], *err = NULL;
    const char *exr = scaled_exemplar("negative.exr", 0.0f, -0.5f);
    assert_int_equal(fit_exemplar(exr, "negative", model, &err), 1);
    assert_non_null(strstr(err, tu_fmt("%s: no value is positive and 3072 of 3072 are negative",
                                       exr)));
    assert_true(strchr(err, '\n') == err + strlen(err) - 1);
    free(err);
    struct stat st;
    assert_int_not_equal(stat(model, &st), 0);
    /* leather's values lie about 0..1: shifted by its median, half negative */
    btf_image img;
    tu_material_image("leather", 32, 2, (btf_dir){0, 0}, (btf_dir){30, 0}, &img);
    float *v = malloc(sizeof(float) * 32 * 32 * 3);
    memcpy(v, img.data, sizeof(float) * 32 * 32 * 3);
    qsort(v, 32 * 32 * 3, sizeof(float), cmp_float);
    float median = v[32 * 32 * 3 / 2];
    free(v);
    btf_image_free(&img);
    exr = scaled_exemplar("half-negative.exr", 1.0f, -median);
    assert_int_equal(fit_exemplar(exr, "half-negative", model, &err), 0);
    assert_non_null(strstr(err, tu_fmt("warning: %s: ", exr)));
    assert_non_null(strstr(err, "% of the values are negative; synthesis keeps colours >= 0"));
    free(err);
    assert_int_equal(tu_run(tu_fmt("%s texture-fit -q %s -o %s --levels 1", tu_cli(), exr, model),
                            &err), 0);
    assert_string_equal(err, "");
    free(err);
    exr = scaled_exemplar("black.exr", 0.0f, 0.0f);
    assert_int_equal(fit_exemplar(exr, "black", model, &err), 0);
    assert_string_equal(err, "");
    free(err);
}

/* A frame whose G-buffer alone exceeds the memory this process may use is
 * refused at once with the estimate: ulimit -v bounds the address space
 * (RLIMIT_AS, which btf__memory_available honours) to 2 GB on any machine,
 * and 8192^2 pixels need 6.7 GB at least. Without the check the trace
 * would run and then fail an allocation. */
static void render_beyond_memory_refused(void **state)
{
    (void)state;
#if defined(__SANITIZE_ADDRESS__)
    /* AddressSanitizer reserves terabytes of address space: no ulimit -v
     * under it. The largest frame (16384^2, at least 26.8 GB) then, where
     * the machine has less than that. */
    const char *limit = "", *size = "16384x16384", *need = "needs at least 26.8 GB";
    if (btf__memory_available() >= 26.8e9) {
        print_message("skipped under ASan: this machine has room for a 16384^2 frame\n");
        skip();
    }
#else
    const char *limit = "ulimit -v 2000000 && ", *size = "8192x8192",
               *need = "needs at least 6.7 GB";
#endif
    char *err = NULL;
    double t = tu_now();
    int rc = tu_run(tu_fmt("%s%s render tests/data/model-v1.0.btfcar --view 30,0 --light 30,90 "
                           "--size %s --backend cpu -o %s/big.png",
                           limit, tu_cli(), size, tu_dir), &err);
    t = tu_now() - t;
    if (rc != 1)
        print_error("exit %d: %s\n", rc, err);
    assert_int_equal(rc, 1);
    assert_non_null(strstr(err, tu_fmt("render %s: %s of memory", size, need)));
#if !defined(__SANITIZE_ADDRESS__)
    assert_non_null(strstr(err, "more than the 2.0 GB available"));
#endif
    assert_true(strchr(err, '\n') == err + strlen(err) - 1);
    assert_true(t < 5.0);
    free(err);
    struct stat st;
    assert_int_not_equal(stat(tu_fmt("%s/big.png", tu_dir), &st), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(utf8_validator),
        cmocka_unit_test(directions_are_decimal),
        cmocka_unit_test(info_json_is_utf8),
        cmocka_unit_test(single_texture_render_names_model),
        cmocka_unit_test(render_names_model_of_bad_set),
        cmocka_unit_test(duplicate_direction_refused),
        cmocka_unit_test(render_beyond_memory_refused),
        cmocka_unit_test(exemplar_too_large_refused),
        cmocka_unit_test(negative_exemplar),
    };
    return cmocka_run_group_tests_name("cli_input", tests, tu_setup_dir, tu_teardown_dir);
}
