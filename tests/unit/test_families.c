/*
 * test_families.c — the material interface over the model families
 * (include/btfcar/material.h, src/material/): one read that sniffs the
 * signature and gives each family its own model, the description, the
 * renders (the same pixels as each family's own renderer), the report
 * dispatch, and the errors: a file of no family, a missing file, NULL
 * arguments, a model that cannot be rendered.
 */
#include "testutil.h"
#include "rf/rf_render.h" /* the family's own render, to compare with */

#include <cjson/cJSON.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static btf_dataset *ds;
static char dataset_path[4096], car_path[4200], rf_path[4200];
static btf_model car;
static btf_rf_model rf;

static int setup(void **state)
{
    if (tu_setup_dir(state) ||
        tu_generate_dataset("leather", 16, 3, dataset_path, sizeof dataset_path, &ds))
        return -1;
    btf_error e = {0};
    btf_analyse_opts ao = btf_analyse_defaults();
    ao.segment.subspaces = 2;
    btf_rf_opts ro = btf_rf_defaults();
    snprintf(car_path, sizeof car_path, "%s/car.btfcar", tu_dir);
    snprintf(rf_path, sizeof rf_path, "%s/rf.btfcar", tu_dir);
    if (btf_analyse(ds, &ao, &car, &e) || btf_model_write(car_path, &car, &e) ||
        btf_rf_fit(ds, &ro, &rf, &e) || btf_rf_write(rf_path, &rf, &e))
        return fprintf(stderr, "setup: %s\n", e.msg), -1;
    return 0;
}

static int teardown(void **state)
{
    btf_model_free(&car);
    btf_rf_model_free(&rf);
    btf_dataset_close(ds);
    return tu_teardown_dir(state);
}

static btf_material *read_ok(const char *path)
{
    btf_error e = {0};
    btf_material *m = NULL;
    TU_OK(btf_material_read(path, &m, &e), &e);
    assert_non_null(m);
    return m;
}

/* Each file is read by its own family, whose model the accessor gives. */
static void test_read_sniffs_the_family(void **state)
{
    (void)state;
    btf_material *a = read_ok(car_path), *b = read_ok(rf_path);
    btf_material_info ia, ib;
    btf_material_get_info(a, &ia);
    btf_material_get_info(b, &ib);
    assert_int_equal(ia.family, BTF_FAMILY_CAR);
    assert_string_equal(ia.family_name, "car");
    assert_true(ia.caps & BTF_MATERIAL_SYNTHESISES);
    assert_int_equal(ib.family, BTF_FAMILY_RF);
    assert_string_equal(ib.family_name, "rf");
    assert_false(ib.caps & BTF_MATERIAL_SYNTHESISES);
    assert_non_null(btf_material_car(a));
    assert_null(btf_material_rf(a));
    assert_non_null(btf_material_rf(b));
    assert_null(btf_material_car(b));
    assert_int_equal(btf_material_car(a)->n_subspaces, car.n_subspaces);
    assert_int_equal(ia.views->count, car.views.count);
    assert_int_equal(ib.lights->count, rf.lights.count);
    assert_true(ia.file_bytes > 0 && ib.file_bytes > 0);
    assert_int_equal(ia.major, 1);
    btf_material_free(a);
    btf_material_free(b);
    btf_material_free(NULL);
}

static void test_sniff(void **state)
{
    (void)state;
    size_t n;
    unsigned char *a = tu_slurp(car_path, &n), *b = tu_slurp(rf_path, &n);
    assert_int_equal(btf_material_sniff(a, 16), BTF_FAMILY_CAR);
    assert_int_equal(btf_material_sniff(b, 16), BTF_FAMILY_RF);
    assert_int_equal(btf_material_sniff(a, 3), BTF_FAMILY_NONE);
    assert_int_equal(btf_material_sniff((const unsigned char *)"P6\n1 1\n", 7), BTF_FAMILY_NONE);
    assert_int_equal(btf_material_sniff(NULL, 0), BTF_FAMILY_NONE);
    free(a);
    free(b);
}

/* A file of no family gets the CAR reader's message; every message names
 * the file; NULL arguments are BTF_E_ARG. */
static void test_errors(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_material *m = (btf_material *)&e;
    const char *junk = tu_fmt("%s/junk.btfcar", tu_dir);
    tu_write_file(junk, "not a model at all, just text\n", 30);
    assert_int_equal(btf_material_read(junk, &m, &e), BTF_E_FORMAT);
    assert_null(m);
    assert_non_null(strstr(e.msg, junk));
    const char *missing = tu_fmt("%s/none.btfcar", tu_dir);
    assert_int_not_equal(btf_material_read(missing, &m, &e), BTF_OK);
    assert_non_null(strstr(e.msg, missing));
    assert_int_equal(btf_material_read(NULL, &m, &e), BTF_E_ARG);
    assert_int_equal(btf_material_read(car_path, NULL, &e), BTF_E_ARG);
    btf_render_opts o = btf_render_defaults();
    btf_image img = {0};
    assert_int_equal(btf_material_render_flat(NULL, NULL, (btf_dir){0, 0}, (btf_dir){0, 0}, &o,
                                              &img, NULL, &e), BTF_E_ARG);
    assert_int_equal(btf_material_describe(NULL, stdout, 0, &e), BTF_E_ARG);
}

/* The description: the family's text, and JSON that parses with the
 * family's format name. */
static void test_describe(void **state)
{
    (void)state;
    const char *paths[2] = {car_path, rf_path};
    const char *formats[2] = {"btfcar-model", "btfcar-rf-model"};
    for (int i = 0; i < 2; i++) {
        btf_material *m = read_ok(paths[i]);
        btf_error e = {0};
        char *text = NULL;
        size_t size = 0;
        FILE *f = open_memstream(&text, &size);
        TU_OK(btf_material_describe(m, f, 1, &e), &e);
        fclose(f);
        cJSON *j = cJSON_Parse(text);
        assert_non_null(j);
        assert_string_equal(cJSON_GetObjectItem(j, "format")->valuestring, formats[i]);
        assert_string_equal(cJSON_GetObjectItem(j, "file")->valuestring, paths[i]);
        cJSON_Delete(j);
        free(text);
        f = open_memstream(&text, &size);
        TU_OK(btf_material_describe(m, f, 0, &e), &e);
        fclose(f);
        assert_non_null(strstr(text, paths[i]));
        assert_non_null(strstr(text, "views"));
        free(text);
        btf_material_free(m);
    }
}

static void assert_same_image(const btf_image *a, const btf_image *b)
{
    assert_int_equal(a->width, b->width);
    assert_int_equal(a->height, b->height);
    assert_int_equal(a->channels, b->channels);
    assert_memory_equal(a->data, b->data,
                        (size_t)a->width * a->height * a->channels * sizeof(float));
}

/* The material's flat render is its family's, pixel for pixel. */
static void test_render_is_the_family_render(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_dir view = {30, 60}, light = {45, 0};
    btf_render_opts o = btf_render_defaults();
    o.width = 24, o.height = 20, o.threads = 2;
    btf_material *a = read_ok(car_path), *b = read_ok(rf_path);
    btf_image x = {0}, y = {0};
    btf_render_info info;
    TU_OK(btf_material_render_flat(a, NULL, view, light, &o, &x, &info, &e), &e);
    TU_OK(btf_render_flat(&car, view, light, &o, &y, NULL, &e), &e);
    assert_same_image(&x, &y);
    char note[256];
    btf_material_render_note(a, NULL, view, &info, note, sizeof note);
    assert_non_null(strstr(note, "needed of"));
    btf_image_free(&x);
    btf_image_free(&y);
    TU_OK(btf_material_render_flat(b, NULL, view, light, &o, &x, NULL, &e), &e);
    TU_OK(btf__rf_render_flat(&rf, view, light, 24, 20, 2, &y, &e), &e);
    assert_same_image(&x, &y);
    btf_material_render_note(b, NULL, view, &info, note, sizeof note);
    assert_non_null(strstr(note, "reflectance-field model"));
    btf_image_free(&x);
    btf_image_free(&y);
    btf_material_free(a);
    btf_material_free(b);
}

/* A single texture has no directions to render with: BTF_E_ARG naming the
 * file, from the material, before the renderer runs. */
static void test_single_texture_does_not_render(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image tex = {0};
    TU_OK(btf_image_alloc(&tex, 32, 32, 3, &e), &e);
    for (size_t i = 0; i < 32 * 32 * 3; i++)
        tex.data[i] = 0.2f + 0.6f * (float)((i * 2654435761u) % 1000) / 1000.0f;
    btf_model t;
    TU_OK(btf_texture_fit(&tex, NULL, &t, &e), &e);
    const char *path = tu_fmt("%s/texture.btfcar", tu_dir);
    TU_OK(btf_model_write(path, &t, &e), &e);
    btf_model_free(&t);
    btf_image_free(&tex);
    btf_material *m = read_ok(path);
    btf_render_opts o = btf_render_defaults();
    o.width = o.height = 8;
    btf_image img = {0};
    assert_int_equal(btf_material_render_flat(m, NULL, (btf_dir){0, 0}, (btf_dir){0, 0}, &o,
                                              &img, NULL, &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, "single texture"));
    assert_non_null(strstr(e.msg, path));
    assert_null(img.data);
    btf_material_free(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_read_sniffs_the_family),
        cmocka_unit_test(test_sniff),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_describe),
        cmocka_unit_test(test_render_is_the_family_render),
        cmocka_unit_test(test_single_texture_does_not_render),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
