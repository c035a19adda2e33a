/*
 * library.c — the library report (docs/cluster.md, "A material library";
 * docs/cluster.md): one page and one JSON with a row per material, built from the
 * report folders that `btfcar report` wrote for each (one cluster task
 * each), never re-measuring anything: bytes, ratio, distances and times
 * are read from each folder's report.json (docs/report.md), the preview
 * and the link point at the folder's own sphere.png and index.html
 * (relative paths, so the tree can be moved or served as a whole).
 */
#include "btfcar.h"
#include "core/core.h"
#include "report/report.h"

#include <cjson/cJSON.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* report.json's size limit when read back (a report of every pair of a
 * 151 x 151 material is a few MB). */
#define REPORT_JSON_MAX ((size_t)64 << 20)

typedef btf_library_row library_row;

/* A number of the report, finite and >= 0 (every figure the row shows is),
 * else 0: a damaged or foreign file cannot put NaN on the page. */
static double number(const cJSON *o, const char *key)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    double d = cJSON_IsNumber(v) ? v->valuedouble : 0.0;
    return d >= 0.0 && d <= 1e300 ? d : 0.0;
}

static void text(const cJSON *o, const char *key, char *out, size_t n)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    snprintf(out, n, "%s", cJSON_IsString(v) ? v->valuestring : "");
}

int btf__library_row_parse(const char *data, size_t n, btf_library_row *r)
{
    cJSON *j = cJSON_ParseWithLength(data, n);
    const cJSON *f = cJSON_GetObjectItemCaseSensitive(j, "format");
    if (!j || !cJSON_IsString(f) || strcmp(f->valuestring, "btfcar-report")) {
        cJSON_Delete(j);
        return 0;
    }
    text(j, "dataset", r->dataset, sizeof r->dataset);
    text(j, "model", r->model, sizeof r->model);
    const cJSON *c = cJSON_GetObjectItemCaseSensitive(j, "compression");
    const cJSON *q = cJSON_GetObjectItemCaseSensitive(j, "quality");
    const cJSON *p = cJSON_GetObjectItemCaseSensitive(j, "preview");
    r->model_bytes = number(c, "model_bytes");
    r->raw_bytes = number(c, "raw_bytes");
    r->ratio = number(c, "ratio");
    r->mean = number(q, "mean_combined");
    r->worst = number(q, "worst_combined");
    double pairs = number(q, "pairs");
    r->pairs = pairs < 1e9 ? (int)pairs : 0;
    r->seconds = number(j, "seconds");
    text(p, "picture", r->preview, sizeof r->preview);
    if (strchr(r->preview, '/') || strstr(r->preview, "..")) /* a name in the folder only */
        r->preview[0] = '\0';
    cJSON_Delete(j);
    return 1;
}

/* One report folder's row; BTF_E_IO / BTF_E_DATA naming its report.json. */
static btf_status read_row(const char *dir, library_row *r, btf_error *err)
{
    memset(r, 0, sizeof *r);
    char path[PATH_MAX];
    btf_status rc = btf__path_join(path, sizeof path, dir, "report.json", err);
    unsigned char *data = NULL;
    size_t n = 0;
    if (rc == BTF_OK && btf__read_file(path, REPORT_JSON_MAX, &data, &n, err))
        rc = BTF_E_IO;
    if (rc)
        return rc;
    int ok = btf__library_row_parse((const char *)data, n, r);
    free(data);
    if (!ok)
        return btf__fail(err, BTF_E_DATA, "%s: not a btfcar report (no \"format\": "
                         "\"btfcar-report\")", path);
    if (!realpath(dir, r->dir))
        snprintf(r->dir, sizeof r->dir, "%s", dir);
    return BTF_OK;
}

/* The path of `to` relative to the folder `from` (both absolute). */
static void relative(const char *from, const char *to, char *out, size_t n)
{
    size_t common = 0, i = 0;
    while (from[i] && from[i] == to[i]) { /* the last '/' both share */
        i++;
        if (from[i] == '/' || from[i] == '\0')
            common = (to[i] == '/' || to[i] == '\0') ? i : common;
    }
    size_t at = 0;
    out[0] = '\0';
    for (const char *s = from + common; *s; s++) /* one "../" per folder left in from */
        if (*s == '/' && at + 4 < n)
            at += (size_t)snprintf(out + at, n - at, "../");
    const char *rest = to + common + (to[common] == '/');
    snprintf(out + at, n - at, "%s", *rest ? rest : ".");
}

static void write_page(btf_buf *b, const library_row *rows, int n, const char *out_abs)
{
    btf__buf_puts(b, "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
                    "<title>btfcar library report</title><style>body{font-family:sans-serif;"
                    "margin:2em}table{border-collapse:collapse}td,th{border:1px solid #ccc;"
                    "padding:4px 8px;text-align:right}td.l,th.l{text-align:left}"
                    "img{width:96px;height:96px}</style></head><body>\n");
    btf__buf_printf(b, "<h1>Material library: %d material%s</h1>\n<p>One row per material, read "
                    "from each material's report (<code>report.json</code>); distances are "
                    "combined texture distances, 1.0 as close as the material is to itself.</p>\n",
                    n, n == 1 ? "" : "s");
    btf__buf_puts(b, "<table><tr><th>preview</th><th class=\"l\">material</th><th>model bytes"
                    "</th><th>ratio</th><th>mean distance</th><th>worst</th><th>pairs</th>"
                    "<th>report s</th></tr>\n");
    for (int i = 0; i < n; i++) {
        const library_row *r = &rows[i];
        char link[PATH_MAX];
        relative(out_abs, r->dir, link, sizeof link);
        btf__buf_puts(b, "<tr><td>");
        if (r->preview[0]) {
            btf__buf_puts(b, "<img alt=\"\" src=\"");
            btf__buf_html(b, link);
            btf__buf_puts(b, "/");
            btf__buf_html(b, r->preview);
            btf__buf_puts(b, "\">");
        }
        btf__buf_puts(b, "</td><td class=\"l\"><a href=\"");
        btf__buf_html(b, link);
        btf__buf_puts(b, "/index.html\">");
        btf__buf_html(b, r->dataset[0] ? r->dataset : r->dir);
        btf__buf_puts(b, "</a></td>");
        btf__buf_printf(b, "<td>%.0f</td><td>1 : %.0f</td><td>%.2f</td><td>%.2f</td><td>%d</td>"
                        "<td>%.1f</td></tr>\n", r->model_bytes, r->ratio, r->mean, r->worst,
                        r->pairs, r->seconds);
    }
    btf__buf_puts(b, "</table>\n</body></html>\n");
}

static char *library_json(const library_row *rows, int n, const char *out_abs)
{
    cJSON *j = cJSON_CreateObject(), *arr = cJSON_AddArrayToObject(j, "materials");
    cJSON_AddStringToObject(j, "format", "btfcar-library");
    cJSON_AddNumberToObject(j, "format_version", 1);
    for (int i = 0; i < n; i++) {
        const library_row *r = &rows[i];
        char link[PATH_MAX];
        relative(out_abs, r->dir, link, sizeof link);
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "dataset", r->dataset);
        cJSON_AddStringToObject(o, "model", r->model);
        cJSON_AddStringToObject(o, "report", link);
        cJSON_AddNumberToObject(o, "model_bytes", r->model_bytes);
        cJSON_AddNumberToObject(o, "raw_bytes", r->raw_bytes);
        cJSON_AddNumberToObject(o, "ratio", r->ratio);
        cJSON_AddNumberToObject(o, "mean_combined", r->mean);
        cJSON_AddNumberToObject(o, "worst_combined", r->worst);
        cJSON_AddNumberToObject(o, "pairs", r->pairs);
        cJSON_AddNumberToObject(o, "report_seconds", r->seconds);
        cJSON_AddItemToArray(arr, o);
    }
    char *s = cJSON_Print(j);
    cJSON_Delete(j);
    return s;
}

/* Every folder read first: the missing ones named together, nothing written. */
static btf_status read_all(const char *const *dirs, int n, library_row *rows, btf_error *err)
{
    int missing = 0;
    char list[512] = "";
    size_t at = 0;
    btf_error first = {0};
    for (int i = 0; i < n; i++) {
        btf_error e = {0};
        if (read_row(dirs[i], &rows[i], &e) == BTF_OK)
            continue;
        if (!missing++)
            first = e;
        int w = snprintf(list + at, sizeof list - at, "%s%s", at ? ", " : "", dirs[i]);
        at = w > 0 && (size_t)w < sizeof list - at ? at + (size_t)w : at;
    }
    if (missing == 1 && err)
        *err = first;
    if (missing > 1)
        btf__fail(err, BTF_E_IO, "library: %d of %d material reports are missing or unreadable: "
                  "%s (first: %s)", missing, n, list, first.msg);
    return missing ? (missing == 1 ? first.code : BTF_E_IO) : BTF_OK;
}

btf_status btf_library_write(const char *const *reports, int n, const char *dir, int *rows_out,
                             btf_error *err)
{
    if (rows_out)
        *rows_out = 0;
    if (!reports || n < 1 || !dir)
        return btf__fail(err, BTF_E_ARG, "library: no report folders or no output folder");
    library_row *rows = btf__calloc((size_t)n, sizeof *rows, err);
    if (!rows)
        return BTF_E_NOMEM;
    btf_status rc = read_all(reports, n, rows, err);
    /* the output's absolute path, for the relative links: its parent exists */
    char out_abs[PATH_MAX], parent[PATH_MAX];
    snprintf(parent, sizeof parent, "%s", dir);
    char *slash = strrchr(parent, '/');
    const char *base = slash ? slash + 1 : dir;
    if (slash)
        *slash = '\0';
    char pabs[PATH_MAX];
    if (rc == BTF_OK && !realpath(slash ? (parent[0] ? parent : "/") : ".", pabs))
        rc = btf__fail(err, BTF_E_IO, "%s: its parent folder does not exist", dir);
    if (rc == BTF_OK)
        snprintf(out_abs, sizeof out_abs, "%s/%s", strcmp(pabs, "/") ? pabs : "", base);
    btf_output_dir *od = NULL;
    if (rc == BTF_OK)
        rc = btf_output_dir_begin(dir, &od, err);
    btf_buf page = {0};
    char *json = NULL;
    char path[PATH_MAX];
    if (rc == BTF_OK) {
        write_page(&page, rows, n, out_abs);
        rc = btf__path_join(path, sizeof path, btf_output_dir_path(od), "index.html", err);
    }
    if (rc == BTF_OK)
        rc = btf__buf_write(&page, path, err);
    if (rc == BTF_OK && !(json = library_json(rows, n, out_abs)))
        rc = btf__fail(err, BTF_E_NOMEM, "library: out of memory");
    if (rc == BTF_OK)
        rc = btf__path_join(path, sizeof path, btf_output_dir_path(od), "library.json", err);
    if (rc == BTF_OK)
        rc = btf_write_file_atomic(path, json, strlen(json), err);
    if (od && rc == BTF_OK)
        rc = btf_output_dir_commit(od, err);
    else if (od)
        btf_output_dir_fail(od, err);
    btf__buf_free(&page);
    cJSON_free(json);
    free(rows);
    if (rc == BTF_OK && rows_out)
        *rows_out = n;
    return rc;
}
