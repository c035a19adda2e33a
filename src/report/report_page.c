/*
 * report_page.c — the report page's shared pieces (report_base.h,
 * docs/report.md): one HTML file that needs nothing but the PNG and SVG
 * files beside it — no script, no font or style sheet fetched — so that it
 * reads the same from a disk, an archive or a web server. Here: the
 * skeleton and its styles, the top with the preview and the cards, table
 * rows, the heat map, the galleries of pair pictures and the table of
 * every pair; a family's sections fill in what they measured.
 */
#include "core/core.h"
#include "report/report_base.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The styles every page has; a family's own rules (btf_report_family.style)
 * go between the two halves, after the generic table rules they refine. */
static const char STYLE_TOP[] =
    "body{font-family:DejaVu Sans,Liberation Sans,Arial,sans-serif;margin:0 auto;"
    "max-width:1180px;padding:16px 24px;color:#1d1d1f;background:#fff;line-height:1.4}"
    "h1{font-size:24px;margin:8px 0 4px}h2{font-size:19px;margin:28px 0 8px;"
    "border-bottom:1px solid #ccc;padding-bottom:4px}h3{font-size:15px;margin:18px 0 6px}"
    ".meta{color:#555;font-size:13px}.top{display:flex;gap:24px;flex-wrap:wrap;"
    "align-items:flex-start}.cards{display:flex;flex-wrap:wrap;gap:12px;flex:1}"
    ".card{border:1px solid #ddd;border-radius:6px;padding:10px 14px;min-width:170px}"
    ".card b{display:block;font-size:22px}.card span{color:#555;font-size:12px}"
    "table{border-collapse:collapse;font-size:13px;margin:6px 0}"
    "th,td{border:1px solid #ddd;padding:3px 8px;text-align:right}"
    "th{background:#f3f3f5}td.l,th.l{text-align:left}";
static const char STYLE_END[] =
    "figure{margin:6px 0}"
    "figcaption{font-size:12px;color:#444}.pairs{display:flex;flex-wrap:wrap;gap:10px}"
    ".pair{border:1px solid #ddd;padding:4px;font-size:11px}"
    ".pair img{image-rendering:pixelated;display:block}.note{font-size:13px;color:#444}"
    "img.plot{max-width:100%;height:auto}";

const char *btf__report_bytes_text(uint64_t b, char *buf, size_t n)
{
    if (b < 10000)
        snprintf(buf, n, "%llu B", (unsigned long long)b);
    else if (b < 10000000)
        snprintf(buf, n, "%.1f KB", b / 1e3);
    else if (b < 10000000000ULL)
        snprintf(buf, n, "%.1f MB", b / 1e6);
    else
        snprintf(buf, n, "%.2f GB", b / 1e9);
    return buf;
}

const char *btf__report_ratio_text(double r, char *buf, size_t n)
{
    if (!(r > 0) || !isfinite(r))
        snprintf(buf, n, "–");
    else if (r >= 100)
        snprintf(buf, n, "1 : %.0f", r);
    else
        snprintf(buf, n, "1 : %.1f", r);
    return buf;
}

double btf__report_ratio(uint64_t raw, uint64_t bytes)
{
    return bytes ? (double)raw / (double)bytes : 0.0;
}

const char *btf__report_dir_text(btf_dir d, char *buf, size_t n)
{
    snprintf(buf, n, "θ %g φ %g", d.theta, d.phi);
    return buf;
}

void btf__report_top_begin(btf_buf *b, const btf_report_base *r, const char *note)
{
    char t[64], q[64], l[64];
    btf__report_dir_text(r->o->sphere_light, l, sizeof l);
    btf__buf_printf(b, "<div class=\"top\">\n<figure><img src=\"sphere.png\" width=\"%d\" "
                      "height=\"%d\" alt=\"the material on a sphere\">\n<figcaption>The "
                      "model on a sphere, one directional light from %s (camera frame), "
                      "%srendered in " BTF_HTML_TIME("%.2f s") ".</figcaption></figure>\n"
                      "<div class=\"cards\">\n",
                   r->o->sphere_size, r->o->sphere_size, l, note ? note : "", r->sphere_s);
    btf__buf_printf(b, BTF_HTML_CARD("%s", "the model file"),
                    btf__report_bytes_text(r->model_bytes, t, sizeof t));
    btf__buf_printf(b, BTF_HTML_CARD("%s", "against the raw BTF (%s)"),
                    btf__report_ratio_text(btf__report_ratio(r->raw.raw, r->model_bytes), q,
                                         sizeof q),
                   btf__report_bytes_text(r->raw.raw, t, sizeof t));
}

void btf__report_top_end(btf_buf *b)
{
    btf__buf_puts(b, "</div>\n</div>\n");
}

void btf__report_row(btf_buf *b, const char *tr_class, const char *what, const char *bytes,
                     const char *ratio, const char *note)
{
    btf__buf_puts(b, "<tr");
    if (tr_class)
        btf__buf_printf(b, " class=\"%s\"", tr_class);
    btf__buf_printf(b, "><td class=\"l\">%s</td><td>%s</td><td>%s</td>", what, bytes, ratio);
    if (note)
        btf__buf_printf(b, "<td class=\"l\">%s</td>", note);
    btf__buf_puts(b, "</tr>\n");
}

btf_status btf__report_heatmap(const btf_report_base *r, const char *dir, const char *title,
                               const char *legend, btf_error *err)
{
    int nv = r->in->n_views, nl = r->in->n_lights;
    double *v = btf__alloc((size_t)nv * nl, sizeof(double), err);
    char **rows = btf__calloc((size_t)nv + nl, sizeof(char *), err);
    btf_svg_cell *marked = btf__calloc((size_t)r->n_worst + 1, sizeof *marked, err);
    btf_status rc = v && rows && marked ? BTF_OK : BTF_E_NOMEM;
    for (int i = 0; rc == BTF_OK && i < nv * nl; i++)
        v[i] = NAN;
    for (int i = 0; rc == BTF_OK && i < r->n_pairs; i++)
        v[(size_t)r->pairs[i].view * nl + r->pairs[i].light] = r->pairs[i].rank;
    for (int i = 0; rc == BTF_OK && i < nv + nl; i++) {
        btf_dir dd = i < nv ? r->in->views->dirs[i] : r->in->lights->dirs[i - nv];
        if (!(rows[i] = btf__alloc(32, 1, err)))
            rc = BTF_E_NOMEM;
        else
            snprintf(rows[i], 32, "%g, %g", dd.theta, dd.phi);
    }
    for (int k = 0; rc == BTF_OK && k < r->n_worst; k++) {
        marked[k].row = r->pairs[r->worst[k]].view;
        marked[k].col = r->pairs[r->worst[k]].light;
    }
    if (rc == BTF_OK) {
        btf_heatmap h;
        memset(&h, 0, sizeof h);
        h.rows = nv;
        h.cols = nl;
        h.values = v;
        h.title = title;
        h.x_title = "light (θ, φ)";
        h.y_title = "view (θ, φ)";
        h.legend_label = legend;
        h.row_labels = (const char *const *)rows;
        h.col_labels = (const char *const *)(rows + nv);
        h.marked = marked;
        h.n_marked = r->n_worst;
        h.marked_label = "the worst pairs";
        h.tooltips = 1;
        char path[4096];
        rc = btf__path_join(path, sizeof path, dir, "heatmap.svg", err);
        if (rc == BTF_OK)
            rc = btf__svg_heatmap_write(path, &h, err);
    }
    for (int i = 0; rows && i < nv + nl; i++)
        free(rows[i]);
    BTF_FREE_ALL(rows, v, marked);
    return rc;
}

void btf__report_heatmap_figure(btf_buf *b, const char *alt, const char *caption)
{
    btf__buf_printf(b, "<figure><img class=\"plot\" src=\"heatmap.svg\" alt=\"%s\">", alt);
    if (caption)
        btf__buf_printf(b, "<figcaption>%s</figcaption>", caption);
    btf__buf_puts(b, "</figure>\n");
}

static void pair_figure(btf_buf *b, const btf_report_base *r, int i, int zoom,
                        btf_report_pair_html caption)
{
    const btf_report_pair *p = &r->pairs[i];
    char name[64], vd[48], ld[48];
    btf__report_pair_file(p->view, p->light, name, sizeof name);
    btf__report_dir_text(r->in->views->dirs[p->view], vd, sizeof vd);
    btf__report_dir_text(r->in->lights->dirs[p->light], ld, sizeof ld);
    int w = r->in->width * 2 + 4, h = r->in->height;
    /* Small measurements are shown larger where there are few. */
    int scale = zoom && w < 300 ? 2 : 1;
    btf__buf_printf(b, "<div class=\"pair\"><img src=\"%s\" width=\"%d\" height=\"%d\" "
                      "alt=\"measured and model, view %s light %s\">view %s, light %s<br>",
                   name, w * scale, h * scale, vd, ld, vd, ld);
    caption(b, r, i);
    btf__buf_puts(b, "</div>\n");
}

void btf__report_galleries(btf_buf *b, const btf_report_base *r, const char *worst_heading,
                           const char *pictured_heading, int zoom_pictured,
                           btf_report_pair_html caption)
{
    btf__buf_printf(b, "<h3>%s</h3>\n<div class=\"pairs\">\n", worst_heading);
    for (int k = 0; k < r->n_worst; k++)
        pair_figure(b, r, r->worst[k], 1, caption);
    btf__buf_printf(b, "</div>\n<h3>%s</h3>\n<div class=\"pairs\">\n", pictured_heading);
    for (int i = 0; i < r->n_pairs; i++)
        if (r->pictured[i])
            pair_figure(b, r, i, zoom_pictured, caption);
    btf__buf_puts(b, "</div>\n");
}

void btf__report_pair_table(btf_buf *b, const btf_report_base *r, const char *head,
                            btf_report_pair_html cells)
{
    btf__buf_printf(b, "<h3>Every measured pair</h3>\n<table>\n<tr><th class=\"l\">view</th>"
                      "<th class=\"l\">light</th>%s</tr>\n", head);
    for (int i = 0; i < r->n_pairs; i++) {
        const btf_report_pair *p = &r->pairs[i];
        char vd[48], ld[48];
        btf__buf_printf(b, "<tr><td class=\"l\">%s</td><td class=\"l\">%s</td>",
                        btf__report_dir_text(r->in->views->dirs[p->view], vd, sizeof vd),
                        btf__report_dir_text(r->in->lights->dirs[p->light], ld, sizeof ld));
        cells(b, r, i);
        btf__buf_puts(b, "</tr>\n");
    }
    btf__buf_puts(b, "</table>\n");
}

btf_status btf__report_page(const btf_report_base *r, const btf_report_family *f,
                            const char *dir, btf_error *err)
{
    btf_buf b = {0};
    btf__buf_puts(&b, "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
                     "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
                     "<title>btfcar report: ");
    btf__buf_html(&b, r->dataset_name);
    btf__buf_printf(&b, "</title>\n<style>%s%s%s</style>\n</head>\n<body>\n<h1>btfcar report: ",
                    STYLE_TOP, f->style, STYLE_END);
    btf__buf_html(&b, r->dataset_name);
    btf__buf_puts(&b, "</h1>\n<p class=\"meta\">");
    f->about->html(&b, r);
    btf__buf_puts(&b, "</p>\n");
    for (int i = 0; i < f->n_sections; i++)
        if (f->sections[i]->html)
            f->sections[i]->html(&b, r);
    btf__buf_printf(&b, "<p class=\"meta\">Made by btfcar " BTF_VERSION_STRING " (%s). The same "
                       "numbers: report.json.</p>\n</body>\n</html>\n", f->citation);
    char path[4096];
    btf_status rc = btf__path_join(path, sizeof path, dir, "index.html", err);
    if (rc == BTF_OK)
        rc = btf__buf_write(&b, path, err);
    btf__buf_free(&b);
    return rc;
}
