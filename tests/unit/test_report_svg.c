/* test_report_svg.c — the report's SVG plots and text helpers
 * (src/report/): heat maps and scatter plots written as standalone SVG and
 * read back as well-formed XML with no "nan"/"inf" in them, whatever the
 * input (one point, equal values, NaN, Inf, zero on a log axis); the
 * Pareto front on known sets; HTML escaping; the colour scale; axis ticks. */
#include "testutil.h"

#include "report/report.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------ helpers */

static char *slurp(const char *path)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *s = malloc((size_t)n + 1);
    assert_non_null(s);
    assert_int_equal(fread(s, 1, (size_t)n, f), (size_t)n);
    s[n] = '\0';
    fclose(f);
    return s;
}

static int is_name_char(int c)
{
    return isalnum(c) || c == '-' || c == '_' || c == ':' || c == '.';
}

/* Text between tags: no '<', and every '&' starts a known entity. */
static int check_text(const char *s, const char *end)
{
    for (; s < end; s++) {
        if (*s == '<')
            return 0;
        if (*s == '&') {
            static const char *ent[] = {"&amp;", "&lt;", "&gt;", "&quot;", "&#39;", "&apos;"};
            int ok = 0;
            for (int i = 0; i < 6 && !ok; i++)
                ok = !strncmp(s, ent[i], strlen(ent[i]));
            if (!ok && s[1] == '#') {
                const char *p = s + 2;
                while (isdigit((unsigned char)*p))
                    p++;
                ok = p > s + 2 && *p == ';';
            }
            if (!ok)
                return 0;
        }
    }
    return 1;
}

/* A small well-formedness check: an XML declaration, then one root
 * element; tags balanced and properly nested, attributes quoted, text and
 * attribute values escaped. Returns the number of elements, or -1. */
static int xml_check(const char *doc, const char *root)
{
    const char *p = doc;
    if (strncmp(p, "<?xml ", 6))
        return -1;
    p = strstr(p, "?>");
    if (!p)
        return -1;
    p += 2;
    char stack[64][32];
    int depth = 0, elements = 0, roots = 0;
    while (*p) {
        const char *lt = strchr(p, '<');
        if (!lt) {
            for (; *p; p++)
                if (!isspace((unsigned char)*p))
                    return -1;
            break;
        }
        if (!check_text(p, lt) || (depth == 0 && lt > p && strspn(p, " \t\r\n") < (size_t)(lt - p)))
            return -1;
        p = lt + 1;
        if (!strncmp(p, "!--", 3)) {
            const char *e = strstr(p, "-->");
            if (!e)
                return -1;
            p = e + 3;
            continue;
        }
        int closing = *p == '/';
        p += closing;
        char name[32];
        int n = 0;
        while (is_name_char((unsigned char)*p) && n < 31)
            name[n++] = *p++;
        name[n] = '\0';
        if (n == 0 || is_name_char((unsigned char)*p))
            return -1;
        if (closing) {
            while (isspace((unsigned char)*p))
                p++;
            if (*p != '>' || depth == 0 || strcmp(stack[depth - 1], name))
                return -1;
            depth--;
            p++;
            continue;
        }
        /* Attributes. */
        for (;;) {
            while (isspace((unsigned char)*p))
                p++;
            if (*p == '>' || (*p == '/' && p[1] == '>'))
                break;
            const char *a = p;
            while (is_name_char((unsigned char)*p))
                p++;
            if (p == a || *p != '=' || (p[1] != '"' && p[1] != '\''))
                return -1;
            char q = p[1];
            const char *v = p + 2, *ve = strchr(v, q);
            if (!ve || !check_text(v, ve))
                return -1;
            p = ve + 1;
            if (!isspace((unsigned char)*p) && *p != '>' && *p != '/')
                return -1;
        }
        if (depth == 0) {
            roots++;
            if (strcmp(name, root))
                return -1;
        }
        elements++;
        if (*p == '/') {
            p += 2;
        } else {
            if (depth == 64)
                return -1;
            strcpy(stack[depth++], name);
            p++;
        }
    }
    return depth == 0 && roots == 1 ? elements : -1;
}

/* Reads an SVG file back: well-formed, one <svg> root with width, height
 * and viewBox, no NaN or infinity anywhere, no external reference. */
static char *check_svg(const char *path)
{
    char *s = slurp(path);
    int elements = xml_check(s, "svg");
    if (elements < 0)
        print_error("%s is not well-formed:\n%.2000s\n", path, s);
    assert_true(elements > 3);
    assert_non_null(strstr(s, "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\""));
    assert_non_null(strstr(s, "viewBox=\"0 0 "));
    assert_non_null(strstr(s, "height=\""));
    for (const char *p = s; *p; p++) {
        assert_true(strncasecmp(p, "nan", 3) != 0 || isalpha((unsigned char)p[3]) ||
                    (p > s && isalpha((unsigned char)p[-1])));
        assert_true(strncasecmp(p, "inf", 3) != 0 || (p > s && isalpha((unsigned char)p[-1])) ||
                    isalpha((unsigned char)p[3]));
    }
    /* The one URL: the namespace. No href, no scripts, no foreign objects. */
    const char *ns = strstr(s, "http://www.w3.org/2000/svg");
    assert_non_null(ns);
    assert_null(strstr(ns + 1, "http:"));
    assert_null(strstr(s, "https:"));
    assert_null(strstr(s, "href"));
    assert_null(strstr(s, "<script"));
    assert_null(strstr(s, "<foreignObject"));
    assert_null(strstr(s, "@import"));
    return s;
}

static int count(const char *s, const char *what)
{
    int n = 0;
    for (const char *p = s; (p = strstr(p, what)); p += strlen(what))
        n++;
    return n;
}

/* ------------------------------------------------------------ heat map */

static char **direction_labels(int n)
{
    char **l = calloc((size_t)n, sizeof *l);
    assert_non_null(l);
    for (int i = 0; i < n; i++) {
        l[i] = malloc(32);
        assert_non_null(l[i]);
        snprintf(l[i], 32, "\xCE\xB8 %d \xCF\x86 %d", 15 * (i / 12), 30 * (i % 12)); /* θ, φ */
    }
    return l;
}

static void free_labels(char **l, int n)
{
    for (int i = 0; i < n; i++)
        free(l[i]);
    free(l);
}

static void heatmap_81x81(void **state)
{
    (void)state;
    enum { N = 81 };
    double *v = malloc(sizeof(double) * N * N);
    assert_non_null(v);
    for (int r = 0; r < N; r++)
        for (int c = 0; c < N; c++)
            v[r * N + c] = (r + c) % 17 == 3 ? NAN : 0.5 + sin(r * 0.2) * cos(c * 0.13) + r * 0.01;
    char **labels = direction_labels(N);
    btf_svg_cell worst[3] = {{0, 0}, {40, 41}, {80, 80}};
    btf_heatmap h = {0};
    h.rows = h.cols = N;
    h.values = v;
    h.title = "Colour difference per (view, light) pair";
    h.x_title = "light (\xCE\xB8, \xCF\x86)";
    h.y_title = "view (\xCE\xB8, \xCF\x86)";
    h.legend_label = "\xCE\x94" "E";
    h.row_labels = (const char *const *)labels;
    h.col_labels = (const char *const *)labels;
    h.marked = worst;
    h.n_marked = 3;
    h.marked_label = "3 worst pairs";
    const char *path = tu_fmt("%s/heat81.svg", tu_dir);
    btf_error e = {0};
    TU_OK(btf__svg_heatmap_write(path, &h, &e), &e);
    char *s = check_svg(path);
    /* Labels thinned out: 81 rows of 7 px cells, one label per 2 rows. */
    int shown = count(s, "\xCE\xB8 ");
    assert_true(shown >= 2 * 30 && shown <= 2 * 45);
    assert_non_null(strstr(s, "3 worst pairs"));
    assert_non_null(strstr(s, "not measured"));
    assert_non_null(strstr(s, "url(#btf-hatch)"));
    assert_true(count(s, "stroke=\"#ff1a1a\"") >= 1);
    assert_true(strlen(s) < 600000);
    free(s);

    /* With a tooltip per cell: one <title> for every measured cell. */
    h.tooltips = 1;
    btf_buf b = {0};
    TU_OK(btf__svg_heatmap(&h, &b, &e), &e);
    int measured = 0;
    for (int i = 0; i < N * N; i++)
        measured += isfinite(v[i]);
    assert_int_equal(count(b.data, "<title>"), measured);
    assert_true(xml_check(b.data, "svg") > measured);
    btf__buf_free(&b);
    free_labels(labels, N);
    free(v);
}

static void heatmap_degenerate(void **state)
{
    (void)state;
    btf_error e = {0};
    const char *path = tu_fmt("%s/heat-deg.svg", tu_dir);
    /* One cell; all equal; all NaN; infinities; nasty labels. */
    double one = 3.25;
    btf_heatmap h = {.rows = 1, .cols = 1, .values = &one};
    TU_OK(btf__svg_heatmap_write(path, &h, &e), &e);
    free(check_svg(path));

    double eq[6] = {2, 2, 2, 2, 2, 2};
    h = (btf_heatmap){.rows = 2, .cols = 3, .values = eq, .legend_label = "equal"};
    TU_OK(btf__svg_heatmap_write(path, &h, &e), &e);
    free(check_svg(path));

    double nan4[4] = {NAN, NAN, NAN, NAN};
    h = (btf_heatmap){.rows = 2, .cols = 2, .values = nan4, .title = "nothing measured"};
    TU_OK(btf__svg_heatmap_write(path, &h, &e), &e);
    char *s = check_svg(path);
    assert_non_null(strstr(s, "no measured values"));
    free(s);

    double inf[4] = {INFINITY, -INFINITY, 1, NAN};
    const char *rl[2] = {"<b>&\"'", "bad \xff\xfe utf-8 \x01"};
    const char *cl[2] = {NULL, "a]]>b"};
    btf_svg_cell mk = {1, 1};
    h = (btf_heatmap){.rows = 2, .cols = 2, .values = inf, .row_labels = rl, .col_labels = cl,
                      .marked = &mk, .n_marked = 1, .marked_label = "x < y & z", .reverse = 1,
                      .vmin = 5, .vmax = 5, .tooltips = 1};
    TU_OK(btf__svg_heatmap_write(path, &h, &e), &e);
    s = check_svg(path);
    assert_non_null(strstr(s, "&lt;b&gt;&amp;&quot;&#39;"));
    assert_non_null(strstr(s, "bad \xEF\xBF\xBD\xEF\xBF\xBD utf-8 \xEF\xBF\xBD"));
    assert_non_null(strstr(s, "x &lt; y &amp; z"));
    free(s);

    /* Given range: values outside it are clamped to the scale's ends. */
    double two[2] = {-100, 100};
    h = (btf_heatmap){.rows = 1, .cols = 2, .values = two, .vmin = 0, .vmax = 1, .cell_px = 30};
    TU_OK(btf__svg_heatmap_write(path, &h, &e), &e);
    free(check_svg(path));
}

static void heatmap_bad_arguments(void **state)
{
    (void)state;
    btf_error e = {0};
    double v[4] = {1, 2, 3, 4};
    const char *path = tu_fmt("%s/heat-bad.svg", tu_dir);
    btf_heatmap h = {.rows = 0, .cols = 2, .values = v};
    assert_int_equal(btf__svg_heatmap_write(path, &h, &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, path));
    h = (btf_heatmap){.rows = 2, .cols = 2};
    assert_int_equal(btf__svg_heatmap_write(path, &h, &e), BTF_E_ARG);
    btf_svg_cell out = {2, 0};
    h = (btf_heatmap){.rows = 2, .cols = 2, .values = v, .marked = &out, .n_marked = 1};
    assert_int_equal(btf__svg_heatmap_write(path, &h, &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, "outside"));
    FILE *f = fopen(path, "r");
    assert_null(f); /* nothing written */
}

/* ------------------------------------------------------------ scatter */

static void scatter_sweep(void **state)
{
    (void)state;
    /* Time (s) against error: a front of 4, the default among the others. */
    double x[9] = {0.02, 0.05, 0.1, 0.4, 1.5, 0.08, 0.3, 2.0, 0.6};
    double y[9] = {9.0, 6.0, 4.0, 3.0, 2.5, 7.0, 5.0, 2.7, 3.5};
    const char *l[9] = {"L1 N4", "L2 N4", "L3 N4", "L3 N8", "L4 N14",
                        "L1 N8", "L2 N8", "L4 N8", "L3 auto"};
    btf_scatter s = {.n = 9, .x = x, .y = y, .labels = l, .title = "Speed against accuracy",
                     .x_title = "synthesis time (s)", .y_title = "\xCE\x94" "E", .log_x = 1,
                     .marked_label = "default", .marked = 8};
    const char *path = tu_fmt("%s/scatter.svg", tu_dir);
    btf_error e = {0};
    TU_OK(btf__svg_scatter_write(path, &s, &e), &e);
    char *t = check_svg(path);
    /* The front's labels are shown (and the default's); the others are
     * tooltips only. */
    const char *front[5] = {"L1 N4", "L2 N4", "L3 N4", "L3 N8", "L4 N14"};
    for (int i = 0; i < 5; i++)
        assert_non_null(strstr(t, tu_fmt(">%s</text>", front[i])));
    assert_non_null(strstr(t, ">L3 auto</text>"));
    assert_null(strstr(t, ">L1 N8</text>"));
    assert_non_null(strstr(t, "<title>L1 N8: "));
    assert_non_null(strstr(t, ">default</text>"));
    assert_non_null(strstr(t, ">Pareto-optimal</text>"));
    assert_non_null(strstr(t, "(log scale)"));
    assert_int_equal(count(t, "r=\"4.5\""), 5 + 1); /* 5 on the front, 1 in the legend */
    /* Ticks of a log axis over 2 decades: 1-2-5 multiples. */
    assert_non_null(strstr(t, ">0.02</text>"));
    assert_non_null(strstr(t, ">0.1</text>"));
    assert_non_null(strstr(t, ">1</text>"));
    free(t);

    /* Linear, every label, higher-is-better on y: the front changes. */
    s.log_x = 0;
    s.all_labels = 1;
    s.y_higher_better = 1;
    btf_buf b = {0};
    TU_OK(btf__svg_scatter(&s, &b, &e), &e);
    assert_true(xml_check(b.data, "svg") > 0);
    assert_non_null(strstr(b.data, ">L1 N8</text>"));
    btf__buf_free(&b);
}

static void scatter_degenerate(void **state)
{
    (void)state;
    btf_error e = {0};
    const char *path = tu_fmt("%s/scatter-deg.svg", tu_dir);
    /* No points. */
    btf_scatter s = {.n = 0, .title = "empty", .log_x = 1};
    TU_OK(btf__svg_scatter_write(path, &s, &e), &e);
    char *t = check_svg(path);
    assert_non_null(strstr(t, "no data to plot"));
    free(t);
    /* One point, marked. */
    double x1 = 0.5, y1 = 3;
    const char *l1 = "only";
    s = (btf_scatter){.n = 1, .x = &x1, .y = &y1, .labels = &l1, .marked_label = "default"};
    TU_OK(btf__svg_scatter_write(path, &s, &e), &e);
    free(check_svg(path));
    s.log_x = 1;
    TU_OK(btf__svg_scatter_write(path, &s, &e), &e);
    free(check_svg(path));
    /* All equal x; all equal y; all the same point. */
    double xe[4] = {2, 2, 2, 2}, ye[4] = {1, 2, 3, 4}, yq[4] = {7, 7, 7, 7};
    s = (btf_scatter){.n = 4, .x = xe, .y = ye};
    TU_OK(btf__svg_scatter_write(path, &s, &e), &e);
    free(check_svg(path));
    s = (btf_scatter){.n = 4, .x = xe, .y = yq, .log_x = 1};
    TU_OK(btf__svg_scatter_write(path, &s, &e), &e);
    free(check_svg(path));
    /* Zero and negative on a log axis, NaN and infinities, a marked point
     * that cannot be drawn. */
    double xb[6] = {0, -1, NAN, INFINITY, 0.3, 3};
    double yb[6] = {1, 2, 3, 4, NAN, -INFINITY};
    s = (btf_scatter){.n = 6, .x = xb, .y = yb, .log_x = 1, .marked_label = "default", .marked = 0,
                      .x_title = "time", .y_title = "error"};
    TU_OK(btf__svg_scatter_write(path, &s, &e), &e);
    t = check_svg(path);
    assert_non_null(strstr(t, "6 of 6 not drawn"));
    free(t);
    /* Huge and tiny values. */
    double xh[3] = {1e-300, 1e300, 1}, yh[3] = {-1e308, 1e308, 0};
    s = (btf_scatter){.n = 3, .x = xh, .y = yh, .log_x = 1};
    TU_OK(btf__svg_scatter_write(path, &s, &e), &e);
    free(check_svg(path));
    s.log_x = 0;
    TU_OK(btf__svg_scatter_write(path, &s, &e), &e);
    free(check_svg(path));
    /* Bad arguments. */
    s = (btf_scatter){.n = 2, .x = xh};
    assert_int_equal(btf__svg_scatter_write(path, &s, &e), BTF_E_ARG);
    s = (btf_scatter){.n = 2, .x = xh, .y = yh, .marked_label = "d", .marked = 2};
    assert_int_equal(btf__svg_scatter_write(path, &s, &e), BTF_E_ARG);
    s = (btf_scatter){.n = -1};
    assert_int_equal(btf__svg_scatter_write(path, &s, &e), BTF_E_ARG);
}

/* ------------------------------------------------------------ Pareto */

static void pareto_known_sets(void **state)
{
    (void)state;
    int idx[16];
    /* Minimise both: (1,5) (2,3) (4,1) optimal; (3,4) (5,5) (4,2) not. */
    double x[6] = {3, 1, 5, 4, 2, 4}, y[6] = {4, 5, 5, 1, 3, 2};
    int k = btf__pareto_front(x, y, 6, 0, 0, idx);
    assert_int_equal(k, 3);
    assert_int_equal(idx[0], 1);
    assert_int_equal(idx[1], 4);
    assert_int_equal(idx[2], 3);
    /* Maximise y: (1,5) dominates all with x >= 1 and y <= 5 except (5,5)? (1,5)
     * beats (5,5) (smaller x, equal y): the front is (1,5) alone. */
    k = btf__pareto_front(x, y, 6, 0, 1, idx);
    assert_int_equal(k, 1);
    assert_int_equal(idx[0], 1);
    /* Maximise both: (5,5) alone. */
    k = btf__pareto_front(x, y, 6, 1, 1, idx);
    assert_int_equal(k, 1);
    assert_int_equal(idx[0], 2);
    /* Maximise x, minimise y: (4,1) and (5,5)? (4,1) vs (5,5): neither. */
    k = btf__pareto_front(x, y, 6, 1, 0, idx);
    assert_int_equal(k, 2);
    assert_int_equal(idx[0], 3);
    assert_int_equal(idx[1], 2);
    /* Duplicates are all optimal; NaN and Inf take no part. */
    double xd[5] = {1, 1, NAN, 0, INFINITY}, yd[5] = {1, 1, 0, NAN, -INFINITY};
    k = btf__pareto_front(xd, yd, 5, 0, 0, idx);
    assert_int_equal(k, 2);
    assert_int_equal(idx[0], 0);
    assert_int_equal(idx[1], 1);
    /* Equal x: only the smaller y; a chain: every point. */
    double xq[3] = {2, 2, 2}, yq[3] = {3, 1, 2};
    k = btf__pareto_front(xq, yq, 3, 0, 0, idx);
    assert_int_equal(k, 1);
    assert_int_equal(idx[0], 1);
    double xc[4] = {4, 3, 2, 1}, yc[4] = {1, 2, 3, 4};
    k = btf__pareto_front(xc, yc, 4, 0, 0, idx);
    assert_int_equal(k, 4);
    for (int i = 0; i < 4; i++)
        assert_int_equal(idx[i], 3 - i);
    assert_int_equal(btf__pareto_front(xc, yc, 0, 0, 0, idx), 0);
    assert_int_equal(btf__pareto_front(NULL, yc, 4, 0, 0, idx), 0);
    /* Against brute force on random sets. */
    unsigned seed = 12345;
    for (int round = 0; round < 50; round++) {
        double rx[12], ry[12];
        for (int i = 0; i < 12; i++) {
            seed = seed * 1103515245u + 12345u;
            rx[i] = (seed >> 16) % 7;
            seed = seed * 1103515245u + 12345u;
            ry[i] = (seed >> 16) % 7;
        }
        k = btf__pareto_front(rx, ry, 12, 0, 0, idx);
        int expect = 0;
        for (int i = 0; i < 12; i++) {
            int beaten = 0;
            for (int j = 0; j < 12; j++)
                beaten |= rx[j] <= rx[i] && ry[j] <= ry[i] && (rx[j] < rx[i] || ry[j] < ry[i]);
            expect += !beaten;
        }
        assert_int_equal(k, expect);
        for (int a = 1; a < k; a++) {
            assert_true(rx[idx[a - 1]] <= rx[idx[a]]);
            assert_true(ry[idx[a - 1]] >= ry[idx[a]]);
        }
    }
}

/* ------------------------------------------------------------ text */

static void html_escaping(void **state)
{
    (void)state;
    btf_buf b = {0};
    assert_int_equal(btf__buf_html(&b, "a<b>&\"c'd"), 0);
    assert_string_equal(b.data, "a&lt;b&gt;&amp;&quot;c&#39;d");
    btf__buf_free(&b);
    btf__buf_html(&b, "\xCE\xB8 30 \xCF\x86 60 \xF0\x9F\x98\x80"); /* valid UTF-8 stays */
    assert_string_equal(b.data, "\xCE\xB8 30 \xCF\x86 60 \xF0\x9F\x98\x80");
    btf__buf_free(&b);
    /* Invalid UTF-8 (a lone continuation, an overlong '/', a surrogate, a
     * truncated sequence) and control characters become U+FFFD. */
    btf__buf_html(&b, "\x80|\xC0\xAF|\xED\xA0\x80|\xE2\x82|\x07|\t\n");
    assert_string_equal(b.data, "\xEF\xBF\xBD|\xEF\xBF\xBD\xEF\xBF\xBD|"
                                "\xEF\xBF\xBD\xEF\xBF\xBD\xEF\xBF\xBD|\xEF\xBF\xBD\xEF\xBF\xBD|"
                                "\xEF\xBF\xBD|\t\n");
    btf__buf_free(&b);
    assert_int_equal(btf__buf_html(&b, NULL), 0);
    assert_int_equal(btf__buf_printf(&b, "%d %s %.1f", 7, "x", 2.5), 0);
    assert_string_equal(b.data, "7 x 2.5");
    /* A long printf (past the small buffer). */
    char big[1000];
    memset(big, 'z', sizeof big - 1);
    big[sizeof big - 1] = '\0';
    assert_int_equal(btf__buf_printf(&b, "[%s]", big), 0);
    assert_int_equal(b.len, 7 + 1001);
    btf_error e = {0};
    assert_int_equal(btf__buf_check(&b, "page", &e), BTF_OK);
    b.failed = 1; /* a failure is sticky and reported */
    assert_int_equal(btf__buf_puts(&b, "more"), -1);
    assert_int_equal(btf__buf_check(&b, "page", &e), BTF_E_NOMEM);
    assert_non_null(strstr(e.msg, "page"));
    btf__buf_free(&b);

    /* The FILE form gives the same bytes. */
    const char *path = tu_fmt("%s/esc.html", tu_dir);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(btf__html_fputs(f, "<p class=\"x\">R&D \xff</p>"), 0);
    fclose(f);
    char *s = slurp(path);
    assert_string_equal(s, "&lt;p class=&quot;x&quot;&gt;R&amp;D \xEF\xBF\xBD&lt;/p&gt;");
    free(s);
    /* The whole buffer written atomically. */
    btf__buf_puts(&b, "<!doctype html>");
    TU_OK(btf__buf_write(&b, path, &e), &e);
    s = slurp(path);
    assert_string_equal(s, "<!doctype html>");
    free(s);
    btf__buf_free(&b);
    btf__buf_free(&b); /* twice is harmless */
    btf__buf_free(NULL);
}

/* ------------------------------------------------------------ scale, axes */

static double srgb_to_linear(unsigned char c)
{
    double v = c / 255.0;
    return v <= 0.04045 ? v / 12.92 : pow((v + 0.055) / 1.055, 2.4);
}

static void colour_scale_is_monotone(void **state)
{
    (void)state;
    double prev = -1;
    for (int i = 0; i <= 64; i++) {
        unsigned char c[3];
        btf__colour_scale(i / 64.0, c);
        double Y = 0.2126 * srgb_to_linear(c[0]) + 0.7152 * srgb_to_linear(c[1]) +
                   0.0722 * srgb_to_linear(c[2]);
        assert_true(Y > prev); /* brighter with every step */
        prev = Y;
    }
    unsigned char lo[3], hi[3], n[3], below[3], above[3];
    btf__colour_scale(0, lo);
    btf__colour_scale(1, hi);
    btf__colour_scale(NAN, n);
    btf__colour_scale(-5, below);
    btf__colour_scale(5, above);
    assert_memory_equal(lo, n, 3);
    assert_memory_equal(lo, below, 3);
    assert_memory_equal(hi, above, 3);
    assert_true(lo[2] > lo[1]);              /* dark violet-blue */
    assert_true(hi[0] > 200 && hi[1] > 200 && hi[2] < 100); /* bright yellow */
}

static void axes_ticks(void **state)
{
    (void)state;
    const double cases[][3] = {
        {0, 1, 0},    {0.013, 0.97, 0}, {-3, 7, 0},     {5, 5, 0},      {0, 0, 0},
        {NAN, NAN, 0}, {1e-9, 2e-9, 0}, {-1e300, 1e300, 0}, {0.02, 2, 1}, {1, 1, 1},
        {0.001, 1e6, 1}, {-5, 0, 1},    {0, 3, 1},      {1e-300, 1e300, 1}, {1.1, 1.9, 1},
        {INFINITY, -INFINITY, 0}, {NAN, 4, 1},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        btf_axis a;
        btf__axis_make(&a, cases[i][0], cases[i][1], (int)cases[i][2]);
        assert_true(isfinite(a.lo) && isfinite(a.hi) && a.lo < a.hi);
        if (a.log)
            assert_true(a.lo > 0);
        assert_true(a.nticks >= 2 && a.nticks <= BTF_AXIS_MAX_TICKS);
        for (int k = 0; k < a.nticks; k++) {
            assert_true(isfinite(a.ticks[k]));
            assert_true(a.ticks[k] >= a.lo * (a.lo > 0 ? 1 - 1e-9 : 1 + 1e-9) - 1e-300);
            assert_true(a.ticks[k] <= a.hi * (a.hi > 0 ? 1 + 1e-9 : 1 - 1e-9) + 1e-300);
            if (k)
                assert_true(a.ticks[k] > a.ticks[k - 1]);
            double p = btf__axis_pos(&a, a.ticks[k]);
            assert_true(p >= -1e-9 && p <= 1 + 1e-9);
        }
        /* Mantissas 1, 2 or 5 for the plain cases. */
        if (i < 3 || i == 8)
            for (int k = 0; k < a.nticks; k++) {
                double t = fabs(a.ticks[k]);
                if (t == 0)
                    continue;
                double m = t / pow(10, floor(log10(t) + 1e-9));
                assert_true(fabs(m - 1) < 1e-6 || fabs(m - 2) < 1e-6 || fabs(m - 5) < 1e-6 ||
                            (i != 8 && (fabs(m - 4) < 1e-6 || fabs(m - 6) < 1e-6 ||
                                        fabs(m - 8) < 1e-6 || fabs(m - 3) < 1e-6 ||
                                        fabs(m - 7) < 1e-6 || fabs(m - 9) < 1e-6)));
            }
    }
    char s[32];
    assert_string_equal(btf__svg_num(s, NAN), "0");
    assert_string_equal(btf__svg_num(s, -0.001), "0");
    assert_string_equal(btf__svg_num(s, 12.5), "12.5");
    assert_string_equal(btf__svg_num(s, 3.0), "3");
    assert_string_equal(btf__svg_label(s, 0.30000000000000004), "0.3");
    assert_string_equal(btf__svg_label(s, -0.0), "0");
    assert_string_equal(btf__svg_label(s, INFINITY), "\xE2\x80\x93");
    assert_string_equal(btf__svg_label(s, 1e-7), "1e-07");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(heatmap_81x81),
        cmocka_unit_test(heatmap_degenerate),
        cmocka_unit_test(heatmap_bad_arguments),
        cmocka_unit_test(scatter_sweep),
        cmocka_unit_test(scatter_degenerate),
        cmocka_unit_test(pareto_known_sets),
        cmocka_unit_test(html_escaping),
        cmocka_unit_test(colour_scale_is_monotone),
        cmocka_unit_test(axes_ticks),
    };
    return cmocka_run_group_tests(tests, tu_setup_dir, tu_teardown_dir);
}
