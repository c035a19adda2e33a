/*
 * test_report_page.c — `btfcar report` as a user runs it (docs/report.md):
 * the folder's files, every picture the page names is there, no script,
 * report.json parses and agrees with the model file, the page opens in
 * headless Chromium with no console error and no missing image
 * (tools/check-page.c), --all, the sweep and its resume, bad input.
 *
 * One small generated material (81 x 81 images of 32^2) and its model.
 */
#include "testutil.h"

#include <cjson/cJSON.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static char dataset[4096], model_path[4096];

static int setup(void **state)
{
    tu_setup_dir(state);
    btf_error e = {0};
    snprintf(dataset, sizeof dataset, "%s/leather", tu_dir);
    snprintf(model_path, sizeof model_path, "%s/leather.btfcar", tu_dir);
    btf_generate_opts g = btf_generate_defaults();
    g.size = 32;
    g.seed = 4;
    btf_dataset *ds;
    btf_model m;
    btf_analyse_opts o = btf_analyse_defaults();
    o.segment.subspaces = 3;
    o.fit.levels = 1;
    if (btf_generate("leather", dataset, &g, &e) || btf_dataset_open(dataset, NULL, &ds, &e) ||
        btf_analyse(ds, &o, &m, &e) || btf_model_write(model_path, &m, &e)) {
        fprintf(stderr, "setup: %s\n", e.msg);
        return -1;
    }
    btf_model_free(&m);
    btf_dataset_close(ds);
    return 0;
}

static const char *checker(void)
{
    const char *c = getenv("BTF_CHECK_PAGE");
    return c && *c ? c : "build/check-page";
}

static char *read_text(const char *path)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *s = malloc((size_t)n + 1);
    assert_int_equal(fread(s, 1, (size_t)n, f), (size_t)n);
    s[n] = '\0';
    fclose(f);
    return s;
}

static long file_size(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 ? (long)st.st_size : -1;
}

/* Every src="..." of the page names a file of the folder; returns how many. */
static int check_sources(const char *dir, const char *html)
{
    int n = 0;
    for (const char *p = strstr(html, "src=\""); p; p = strstr(p + 1, "src=\"")) {
        const char *a = p + 5, *b = strchr(a, '"');
        assert_non_null(b);
        char name[256];
        assert_true((size_t)(b - a) < sizeof name);
        memcpy(name, a, (size_t)(b - a));
        name[b - a] = '\0';
        assert_null(strchr(name, '/')); /* beside the page, nothing fetched */
        if (file_size(tu_fmt("%s/%s", dir, name)) <= 0)
            fail_msg("the page names %s, which is not in %s", name, dir);
        n++;
    }
    return n;
}

static cJSON *read_json(const char *dir)
{
    char *text = read_text(tu_fmt("%s/report.json", dir));
    cJSON *j = cJSON_Parse(text);
    free(text);
    assert_non_null(j);
    return j;
}

static double num(const cJSON *o, const char *path)
{
    char buf[256];
    snprintf(buf, sizeof buf, "%s", path);
    const cJSON *j = o;
    for (char *k = strtok(buf, "."); k; k = strtok(NULL, "."))
        j = cJSON_GetObjectItemCaseSensitive(j, k);
    if (!cJSON_IsNumber(j))
        fail_msg("report.json: %s is not a number", path);
    return j->valuedouble;
}

/* The report of a 3 x 3 spread: its files, the page, the JSON, Chromium. */
static void test_report_spread(void **state)
{
    (void)state;
    const char *dir = tu_fmt("%s/rep", tu_dir);
    char *dir_copy = strdup(dir);
    char *err = NULL;
    int rc = tu_run(tu_fmt("%s report %s %s -o %s --views 3 --lights 3 --worst 2 "
                           "--preview-size 96 -q", tu_cli(), dataset, model_path, dir_copy),
                    &err);
    if (rc != 0)
        fail_msg("btfcar report failed (%d): %s", rc, err ? err : "");
    free(err);
    char *html = read_text(tu_fmt("%s/index.html", dir_copy));
    assert_null(strstr(html, "<script"));
    assert_null(strstr(html, "http://"));
    assert_null(strstr(html, "https://"));
    assert_non_null(strstr(html, "sphere.png"));
    assert_non_null(strstr(html, "heatmap.svg"));
    /* 9 pictured pairs (the 2 worst among them, shown twice) + sphere + heat map */
    assert_int_equal(check_sources(dir_copy, html), 9 + 2 + 2);
    assert_int_equal(tu_count_files(dir_copy), 9 + 4);
    free(html);
    cJSON *j = read_json(dir_copy);
    assert_int_equal((long)num(j, "compression.model_bytes"), file_size(model_path));
    assert_int_equal((long)num(j, "compression.raw_bytes"), 81L * 81 * 32 * 32 * 3);
    assert_int_equal((int)num(j, "quality.pairs"), 9);
    assert_true(num(j, "quality.worst_combined") >= num(j, "quality.mean_combined"));
    assert_true(cJSON_IsNull(cJSON_GetObjectItemCaseSensitive(j, "sweep")));
    const cJSON *pairs = cJSON_GetObjectItemCaseSensitive(
        cJSON_GetObjectItemCaseSensitive(j, "quality"), "pairs_measured");
    assert_int_equal(cJSON_GetArraySize(pairs), 9);
    /* the parts of the model file add up to it */
    const cJSON *parts = cJSON_GetObjectItemCaseSensitive(
        cJSON_GetObjectItemCaseSensitive(j, "compression"), "model_parts");
    double sum = 0;
    for (const cJSON *p = parts->child; p; p = p->next)
        sum += p->valuedouble;
    assert_int_equal((long)sum, file_size(model_path));
    cJSON_Delete(j);
    /* In a real browser: loads with no console error and no missing image. */
    const char *shot = tu_fmt("%s/shot.png", tu_dir);
    char *shot_copy = strdup(shot);
    err = NULL;
    rc = tu_run(tu_fmt("%s --size 1024x1400 %s/index.html %s", checker(), dir_copy, shot_copy),
                &err);
    if (rc != 0)
        fail_msg("check-page on the report: %d: %s", rc, err ? err : "");
    free(err);
    assert_true(file_size(shot_copy) > 10000);
    free(shot_copy);
    free(dir_copy);
}

/* --all: every pair measured; pictures stay the default spread's and the
 * worst pairs'. */
static void test_report_all(void **state)
{
    (void)state;
    char *dir = strdup(tu_fmt("%s/rep-all", tu_dir));
    char *err = NULL;
    int rc = tu_run(tu_fmt("%s report %s %s -o %s --all --preview-size 32 -q", tu_cli(), dataset,
                           model_path, dir), &err);
    if (rc != 0)
        fail_msg("btfcar report --all failed (%d): %s", rc, err ? err : "");
    free(err);
    cJSON *j = read_json(dir);
    assert_int_equal((int)num(j, "quality.pairs"), 81 * 81);
    cJSON_Delete(j);
    int files = tu_count_files(dir);
    assert_true(files >= 81 + 4 && files <= 81 + 6 + 4);
    char *html = read_text(tu_fmt("%s/index.html", dir));
    check_sources(dir, html);
    free(html);
    free(dir);
}

/* The sweep: 2 settings measured, then resumed; the page has its plots. */
static void test_report_sweep(void **state)
{
    (void)state;
    char *dir = strdup(tu_fmt("%s/rep-sweep", tu_dir));
    const char *args = "--views 2 --lights 2 --preview-size 32 --sweep --sweep-subspaces 2 "
                       "--sweep-levels 1 --sweep-neighbours auto,4";
    char *cmd = strdup(tu_fmt("%s report %s %s -o %s %s", tu_cli(), dataset, model_path, dir,
                              args));
    char *out = tu_capture(cmd, &(int){0});
    assert_non_null(strstr(out, "2 settings (0 resumed"));
    free(out);
    assert_int_equal(tu_count_files(tu_fmt("%s/sweep", dir)), 2);
    cJSON *j = read_json(dir);
    const cJSON *pts = cJSON_GetObjectItemCaseSensitive(
        cJSON_GetObjectItemCaseSensitive(j, "sweep"), "points");
    assert_int_equal(cJSON_GetArraySize(pts), 2);
    cJSON_Delete(j);
    assert_true(file_size(tu_fmt("%s/pareto-bytes.svg", dir)) > 0);
    assert_true(file_size(tu_fmt("%s/pareto-time.svg", dir)) > 0);
    out = tu_capture(cmd, &(int){0});
    assert_non_null(strstr(out, "2 settings (2 resumed"));
    free(out);
    char *err = NULL;
    int rc = tu_run(tu_fmt("%s %s/index.html", checker(), dir), &err);
    if (rc != 0)
        fail_msg("check-page on the sweep's report: %d: %s", rc, err ? err : "");
    free(err);
    free(cmd);
    free(dir);
}

/* Bad input: one line naming the problem, non-zero, no report folder. */
static void test_report_errors(void **state)
{
    (void)state;
    char *err = NULL;
    const char *dir = tu_fmt("%s/bad", tu_dir);
    char *d = strdup(dir);
    int rc = tu_run(tu_fmt("%s report %s/none %s -o %s", tu_cli(), tu_dir, model_path, d), &err);
    assert_int_equal(rc, 1);
    assert_non_null(strstr(err, "none"));
    free(err);
    assert_int_equal(access(d, F_OK), -1);
    /* A model of another material (a texture model: no directions). */
    btf_error e = {0};
    btf_image img;
    TU_OK(btf_image_alloc(&img, 32, 32, 3, &e), &e);
    for (int i = 0; i < 32 * 32 * 3; i++)
        img.data[i] = 0.25f + 0.5f * (float)((i * 7919) % 101) / 101.0f;
    btf_model tex;
    btf_fit_opts fo = btf_fit_defaults();
    TU_OK(btf_texture_fit(&img, &fo, &tex, &e), &e);
    char *tex_path = strdup(tu_fmt("%s/tex.btfcar", tu_dir));
    TU_OK(btf_model_write(tex_path, &tex, &e), &e);
    btf_model_free(&tex);
    btf_image_free(&img);
    err = NULL;
    rc = tu_run(tu_fmt("%s report %s %s -o %s", tu_cli(), dataset, tex_path, d), &err);
    assert_int_equal(rc, 1);
    assert_non_null(strstr(err, "btfcar report:"));
    assert_null(strchr(strchr(err, '\n') + 1, '\n')); /* one line */
    free(err);
    assert_int_equal(access(d, F_OK), -1);
    /* A corrupt model file names it. */
    tu_write_file(tex_path, "BTFCAR\0\0garbage", 15);
    err = NULL;
    rc = tu_run(tu_fmt("%s report %s %s -o %s", tu_cli(), dataset, tex_path, d), &err);
    assert_int_equal(rc, 1);
    assert_non_null(strstr(err, "tex.btfcar"));
    free(err);
    assert_int_equal(access(d, F_OK), -1);
    /* Usage errors. */
    assert_int_equal(tu_run(tu_fmt("%s report %s %s -o %s --sweep-levels 1,,2", tu_cli(), dataset,
                                   model_path, d), NULL), 2);
    assert_int_equal(tu_run(tu_fmt("%s report %s -o %s", tu_cli(), dataset, d), NULL), 2);
    free(tex_path);
    free(d);
}

/* A reflectance-field model's report (btf__rf_report_write): its file
 * against the raw BTF, per pair the texture distances and the pixel-wise
 * |dY|, the pictures, the page in Chromium; --sweep is a usage error. */
static void test_report_rf(void **state)
{
    (void)state;
    char *rf = strdup(tu_fmt("%s/leather-rf.btfcar", tu_dir));
    char *dir = strdup(tu_fmt("%s/rep-rf", tu_dir));
    char *err = NULL;
    assert_int_equal(tu_run(tu_fmt("%s analyse -q %s --family rf --fit ptm --threads 2 -o %s",
                                   tu_cli(), dataset, rf), NULL), 0);
    int status;
    char *out = tu_capture(tu_fmt("%s report %s %s -o %s --views 3 --lights 3 --worst 2 "
                                  "--preview-size 96 --threads 2", tu_cli(), dataset, rf, dir),
                           &status);
    assert_int_equal(status, 0);
    assert_non_null(strstr(out, "pixel-wise    mean |dY|"));
    free(out);
    char *html = read_text(tu_fmt("%s/index.html", dir));
    assert_null(strstr(html, "<script"));
    assert_null(strstr(html, "http://"));
    assert_non_null(strstr(html, "reflectance-field model"));
    assert_non_null(strstr(html, "|ΔY|"));
    /* 9 pictured pairs (the 2 worst among them, shown twice) + sphere + heat map */
    assert_int_equal(check_sources(dir, html), 9 + 2 + 2);
    assert_int_equal(tu_count_files(dir), 9 + 4);
    free(html);
    cJSON *j = read_json(dir);
    const cJSON *fam = cJSON_GetObjectItemCaseSensitive(j, "family");
    assert_true(cJSON_IsString(fam) && strcmp(fam->valuestring, "rf") == 0);
    assert_int_equal((long)num(j, "compression.model_bytes"), file_size(rf));
    assert_int_equal((long)num(j, "compression.raw_bytes"), 81L * 81 * 32 * 32 * 3);
    assert_int_equal((int)num(j, "quality.pairs"), 9);
    assert_true(num(j, "pixelwise.mean_abs_dy") > 0.0);
    assert_true(num(j, "pixelwise.mean_abs_dy") < num(j, "pixelwise.mean_luminance"));
    assert_true(num(j, "pixelwise.worst_pair_abs_dy") >= num(j, "pixelwise.mean_pair_abs_dy"));
    assert_true(num(j, "quality.worst_combined") >= num(j, "quality.mean_combined"));
    const cJSON *pairs = cJSON_GetObjectItemCaseSensitive(
        cJSON_GetObjectItemCaseSensitive(j, "quality"), "pairs_measured");
    assert_int_equal(cJSON_GetArraySize(pairs), 9);
    assert_true(num(pairs->child, "mean_abs_dy") >= 0.0);
    cJSON_Delete(j);
    char *shot = strdup(tu_fmt("%s/shot-rf.png", tu_dir));
    int rc = tu_run(tu_fmt("%s --size 1024x1400 %s/index.html %s", checker(), dir, shot), &err);
    if (rc != 0)
        fail_msg("check-page on the RF report: %d: %s", rc, err ? err : "");
    free(err);
    assert_true(file_size(shot) > 10000);
    /* no sweep for this family: a usage error, nothing written */
    char *d2 = strdup(tu_fmt("%s/rep-rf-sweep", tu_dir));
    assert_int_equal(tu_run(tu_fmt("%s report %s %s -o %s --sweep", tu_cli(), dataset, rf, d2),
                            NULL), 2);
    assert_int_equal(tu_run(tu_fmt("%s report %s %s -o %s --sweep-levels 1,2", tu_cli(),
                                   dataset, rf, d2), NULL), 2);
    assert_int_equal(access(d2, F_OK), -1);
    free(d2);
    free(shot);
    free(dir);
    free(rf);
}

/* Drops, at every depth, the keys that differ run to run (docs/report.md,
 * "What differs run to run"): "date" and every key containing "seconds". */
static void drop_times(cJSON *j)
{
    cJSON *c = j ? j->child : NULL;
    while (c) {
        cJSON *next = c->next;
        if (c->string && (!strcmp(c->string, "date") || strstr(c->string, "seconds")))
            cJSON_Delete(cJSON_DetachItemViaPointer(j, c));
        else
            drop_times(c);
        c = next;
    }
}

/* report.json without its times, as compact text (malloc'd). */
static char *json_without_times(const char *dir)
{
    cJSON *j = read_json(dir);
    drop_times(j);
    char *text = cJSON_PrintUnformatted(j);
    cJSON_Delete(j);
    return text;
}

/* The page with every <span class="time">...</span> taken out (in place),
 * and the number of spans taken. */
static int strip_time_spans(char *html)
{
    static const char OPEN[] = "<span class=\"time\">", CLOSE[] = "</span>";
    int n = 0;
    for (char *p = strstr(html, OPEN); p; p = strstr(p, OPEN)) {
        char *e = strstr(p, CLOSE);
        assert_non_null(e);
        e += strlen(CLOSE);
        memmove(p, e, strlen(e) + 1);
        n++;
    }
    return n;
}

/* The report of one model twice, on all threads and on one: report.json
 * without "date" and the "seconds" keys, the page without its time spans
 * (spans of them: the date and the times taken) and every picture are the
 * same bytes. */
static void report_twice(const char *model, const char *name, int spans)
{
    char dir[2][4096];
    for (int r = 0; r < 2; r++) {
        snprintf(dir[r], sizeof dir[r], "%s/%s-%d", tu_dir, name, r);
        assert_int_equal(tu_run(tu_fmt("%s report %s %s -o %s --views 2 --lights 3 --worst 2 "
                                       "--preview-size 64 -q %s", tu_cli(), dataset, model,
                                       dir[r], r ? "--threads 1" : ""), NULL), 0);
    }
    char *a = json_without_times(dir[0]), *b = json_without_times(dir[1]);
    assert_null(strstr(a, "seconds"));
    assert_string_equal(a, b);
    free(a), free(b);
    a = read_text(tu_fmt("%s/index.html", dir[0]));
    b = read_text(tu_fmt("%s/index.html", dir[1]));
    assert_int_equal(strip_time_spans(a), spans);
    assert_int_equal(strip_time_spans(b), spans);
    assert_string_equal(a, b);
    free(a), free(b);
    int files = tu_count_files(dir[0]);
    assert_int_equal(tu_count_files(dir[1]), files);
    assert_int_equal(tu_run(tu_fmt("diff -r -x report.json -x index.html %s %s", dir[0], dir[1]),
                            NULL), 0);
}

/* `report` differs run to run only in its times (the page's time spans,
 * report.json's date and *seconds keys): the CAR model's report and the
 * reflectance-field model's. */
static void test_report_repeatable(void **state)
{
    (void)state;
    report_twice(model_path, "again", 4); /* date, measured, sphere, quality */
    /* test_report_rf's model: date, measured, sphere */
    report_twice(tu_fmt("%s/leather-rf.btfcar", tu_dir), "again-rf", 3);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_report_spread),
        cmocka_unit_test(test_report_all),
        cmocka_unit_test(test_report_sweep),
        cmocka_unit_test(test_report_errors),
        cmocka_unit_test(test_report_rf),
        cmocka_unit_test(test_report_repeatable),
    };
    return cmocka_run_group_tests(tests, setup, tu_teardown_dir);
}
