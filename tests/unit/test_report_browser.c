/* test_report_browser.c — the report's page as a reader's browser sees it: a
 * small page of the report's kind (SVG plots from src/report/, a PNG from
 * btf_image_write_png, escaped text) opened in headless Chromium by
 * build/check-page (tools/check-page.c) loads with no console error or
 * warning and every image shown, and a screenshot of the asked size is taken;
 * and the checker fails, as it must, on a missing image, a PNG that does not
 * decode, a script error and a console warning. Chromium is installed by
 * `make deps`: when it is missing this test fails (it does not skip). */
#include "testutil.h"

#include "report/report.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static const char *checker(void)
{
    const char *c = getenv("BTF_CHECK_PAGE");
    return c && *c ? c : "build/check-page";
}

static void write_text(const char *path, const char *text)
{
    tu_write_file(path, text, strlen(text));
}

/* Runs the checker on dir/page; returns its exit status, its stderr in *msg. */
static int check(const char *page, const char *shot, const char *size, char **msg)
{
    const char *cmd = tu_fmt("%s --timeout 25 --size %s '%s/%s' %s%s%s </dev/null", checker(), size,
                             tu_dir, page, shot ? "'" : "", shot ? tu_fmt("%s/%s", tu_dir, shot) : "",
                             shot ? "'" : "");
    return tu_run(cmd, msg);
}

static void browser_is_installed(void **state)
{
    (void)state;
    const char *b = getenv("BTF_CHROMIUM");
    b = b && *b ? b : "/usr/bin/chromium";
    if (access(b, X_OK) != 0)
        fail_msg("%s is missing: `make deps` installs Debian's chromium for this test", b);
    if (access(checker(), X_OK) != 0)
        fail_msg("%s is missing: `make` builds it (tools/check-page.c)", checker());
}

/* The sample page: two SVG plots, a PNG, escaped text; no scripts. */
static void good_page_passes(void **state)
{
    (void)state;
    btf_error e = {0};
    enum { N = 9 };
    double v[N * N];
    const char *labels[N];
    char names[N][32];
    for (int i = 0; i < N; i++) {
        snprintf(names[i], sizeof names[i], "\xCE\xB8 %d \xCF\x86 %d", 15 * (i / 3), 120 * (i % 3));
        labels[i] = names[i];
        for (int j = 0; j < N; j++)
            v[i * N + j] = i == j ? NAN : 1 + 0.3 * i + 0.1 * j;
    }
    btf_svg_cell worst = {8, 7};
    btf_heatmap h = {.rows = N, .cols = N, .values = v, .title = "ΔE per pair", .x_title = "light",
                     .y_title = "view", .legend_label = "ΔE", .row_labels = labels,
                     .col_labels = labels, .marked = &worst, .n_marked = 1, .marked_label = "worst"};
    TU_OK(btf__svg_heatmap_write(tu_fmt("%s/heat.svg", tu_dir), &h, &e), &e);
    double x[5] = {0.01, 0.03, 0.1, 0.2, 1}, y[5] = {5, 3, 3.5, 2, 1.5};
    const char *l[5] = {"a", "b", "c", "d", "e"};
    btf_scatter s = {.n = 5, .x = x, .y = y, .labels = l, .log_x = 1, .x_title = "time (s)",
                     .y_title = "ΔE", .marked_label = "default", .marked = 2};
    TU_OK(btf__svg_scatter_write(tu_fmt("%s/sweep.svg", tu_dir), &s, &e), &e);
    btf_image img = {0};
    TU_OK(btf_image_alloc(&img, 64, 48, 3, &e), &e);
    for (int i = 0; i < 64 * 48 * 3; i++)
        img.data[i] = (float)((i % 192) / 191.0);
    TU_OK(btf_image_write_png(tu_fmt("%s/render.png", tu_dir), &img, &e), &e);
    btf_image_free(&img);

    btf_buf b = {0};
    btf__buf_puts(&b, "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
                     "<title>btfcar report</title><style>body{font-family:sans-serif;margin:16px}"
                     "img{display:block;margin:8px 0}</style></head><body>\n<h1>");
    btf__buf_html(&b, "Report: leather <sample> & \"friends\"");
    btf__buf_puts(&b, "</h1>\n<img src=\"heat.svg\" alt=\"heat map\">\n"
                     "<img src=\"sweep.svg\" alt=\"sweep\">\n"
                     "<img src=\"render.png\" alt=\"render\" width=\"128\" height=\"96\">\n"
                     "<img src=\"render.png\" alt=\"lazy\" loading=\"lazy\" style=\"margin-top:3000px\">\n"
                     "</body></html>\n");
    TU_OK(btf__buf_write(&b, tu_fmt("%s/index.html", tu_dir), &e), &e);
    btf__buf_free(&b);

    char *msg = NULL;
    int rc = check("index.html", "shot.png", "1024x768", &msg);
    if (rc != 0)
        print_error("check-page: exit %d\n%s\n", rc, msg);
    assert_int_equal(rc, 0);
    free(msg);
    btf_image_header hdr;
    TU_OK(btf_image_probe(tu_fmt("%s/shot.png", tu_dir), &hdr, &e), &e);
    assert_int_equal(hdr.format, BTF_FILE_PNG);
    assert_int_equal(hdr.width, 1024);
    assert_int_equal(hdr.height, 768);
    /* The screenshot shows something: not one flat colour. */
    btf_image shot = {0};
    TU_OK(btf_image_read(tu_fmt("%s/shot.png", tu_dir), NULL, &shot, &e), &e);
    float lo = 1, hi = 0;
    for (size_t i = 0; i < (size_t)shot.width * shot.height * 3; i++)
        lo = shot.data[i] < lo ? shot.data[i] : lo, hi = shot.data[i] > hi ? shot.data[i] : hi;
    assert_true(hi - lo > 0.5f);
    btf_image_free(&shot);
}

/* Each bad page: the checker exits 1 (a verdict, not a browser failure)
 * and names the problem. */
static void expect_problem(const char *page, const char *html, const char *expect)
{
    write_text(tu_fmt("%s/%s", tu_dir, page), html);
    char *msg = NULL;
    int rc = check(page, NULL, "640x480", &msg);
    if (rc != 1 || !strstr(msg, expect))
        print_error("%s: exit %d, expected 1 and \"%s\":\n%s\n", page, rc, expect, msg);
    assert_int_equal(rc, 1);
    assert_non_null(strstr(msg, expect));
    free(msg);
}

static void missing_image_fails(void **state)
{
    (void)state;
    expect_problem("missing.html",
                   "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>t</title></head>"
                   "<body><p>text</p><img src=\"absent.png\" alt=\"gone\"></body></html>",
                   "absent.png");
}

static void broken_png_fails(void **state)
{
    (void)state;
    /* The signature and a header's worth of bytes, then nothing valid:
     * the file loads, the image does not decode, the console says nothing. */
    static const unsigned char junk[] = "\x89PNG\r\n\x1a\n\0\0\0\rIHDR\0\0\0\x10\0\0\0\x10\x08\x02"
                                        "\0\0\0garbage-instead-of-a-crc-and-data";
    tu_write_file(tu_fmt("%s/broken.png", tu_dir), junk, sizeof junk - 1);
    expect_problem("broken.html",
                   "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>t</title></head>"
                   "<body><img src=\"broken.png\" alt=\"broken\"></body></html>",
                   "image not shown: broken.png");
}

static void script_error_fails(void **state)
{
    (void)state;
    expect_problem("script.html",
                   "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>t</title></head>"
                   "<body><p>text</p><script>no_such_function();</script></body></html>",
                   "no_such_function");
}

static void console_warning_fails(void **state)
{
    (void)state;
    expect_problem("warn.html",
                   "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>t</title></head>"
                   "<body><script>setTimeout(function(){console.warn('careful')}, 50);</script>"
                   "</body></html>",
                   "console warning: careful");
}

/* Without a browser the checker gives no verdict: exit 3, not 0 or 1. */
static void no_browser_is_not_a_verdict(void **state)
{
    (void)state;
    write_text(tu_fmt("%s/plain.html", tu_dir), "<!DOCTYPE html><title>t</title><p>x</p>");
    char *msg = NULL;
    int rc = tu_run(tu_fmt("BTF_CHROMIUM=/nonexistent/chromium %s '%s/plain.html' </dev/null",
                           checker(), tu_dir), &msg);
    assert_int_equal(rc, 3);
    assert_non_null(strstr(msg, "/nonexistent/chromium"));
    free(msg);
    rc = tu_run(tu_fmt("%s '%s/no-such-page.html' </dev/null", checker(), tu_dir), &msg);
    assert_int_equal(rc, 1);
    free(msg);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(browser_is_installed),
        cmocka_unit_test(good_page_passes),
        cmocka_unit_test(missing_image_fails),
        cmocka_unit_test(broken_png_fails),
        cmocka_unit_test(script_error_fails),
        cmocka_unit_test(console_warning_fails),
        cmocka_unit_test(no_browser_is_not_a_verdict),
    };
    return cmocka_run_group_tests(tests, tu_setup_dir, tu_teardown_dir);
}
