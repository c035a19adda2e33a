/*
 * rf_report_page.c — the page and report.json of a reflectance-field
 * model's report (issue 19, point 4; docs/report.md, "Reflectance-field
 * models"): the CAR report's layout (report_html.c, report_json.c) with
 * what this family has — the file against the raw BTF, the texture
 * distances per pair and, since it keeps every texel, the pixel-wise
 * luminance error per pair and over every image. One HTML file that needs
 * nothing but the PNG and SVG files beside it.
 */
#include "core/core.h"
#include "report/report.h"
#include "report/rf_report_data.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char STYLE[] =
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
    "th{background:#f3f3f5}td.l,th.l{text-align:left}figure{margin:6px 0}"
    "figcaption{font-size:12px;color:#444}.pairs{display:flex;flex-wrap:wrap;gap:10px}"
    ".pair{border:1px solid #ddd;padding:4px;font-size:11px}"
    ".pair img{image-rendering:pixelated;display:block}.note{font-size:13px;color:#444}"
    "img.plot{max-width:100%;height:auto}";

void btf_rf_report_pair_file(const btf_rf_report_data *d, int i, char *buf, size_t n)
{
    snprintf(buf, n, "pair-v%02d-l%02d.png", d->pairs[i].view, d->pairs[i].light);
}

static const char *hr_bytes(uint64_t b, char *buf, size_t n)
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

static const char *ratio_text(uint64_t raw, uint64_t bytes, char *buf, size_t n)
{
    double r = bytes ? (double)raw / (double)bytes : 0.0;
    if (!(r > 0) || !isfinite(r))
        snprintf(buf, n, "–");
    else if (r >= 100)
        snprintf(buf, n, "1 : %.0f", r);
    else
        snprintf(buf, n, "1 : %.1f", r);
    return buf;
}

static void dir_text(btf_dir d, char *buf, size_t n)
{
    snprintf(buf, n, "θ %g φ %g", d.theta, d.phi);
}

static double percent(double a, double b)
{
    return b > 0.0 ? 100.0 * a / b : 0.0;
}

/* The heat map of the pixel-wise error over views x lights. */
static btf_status heat_map(const btf_rf_report_data *d, const char *dir, btf_error *err)
{
    int nv = d->in->n_views, nl = d->in->n_lights;
    double *v = btf_alloc((size_t)nv * nl, sizeof(double), err);
    char **rows = btf_calloc((size_t)nv + nl, sizeof(char *), err);
    btf_svg_cell *marked = btf_calloc((size_t)d->n_worst + 1, sizeof *marked, err);
    btf_status rc = v && rows && marked ? BTF_OK : BTF_E_NOMEM;
    for (int i = 0; rc == BTF_OK && i < nv * nl; i++)
        v[i] = NAN;
    for (int i = 0; rc == BTF_OK && i < d->n_pairs; i++)
        v[(size_t)d->pairs[i].view * nl + d->pairs[i].light] = d->pairs[i].mean_abs_dy;
    for (int i = 0; rc == BTF_OK && i < nv + nl; i++) {
        btf_dir dd = i < nv ? d->in->views->dirs[i] : d->in->lights->dirs[i - nv];
        if (!(rows[i] = btf_alloc(32, 1, err)))
            rc = BTF_E_NOMEM;
        else
            snprintf(rows[i], 32, "%g, %g", dd.theta, dd.phi);
    }
    for (int k = 0; rc == BTF_OK && k < d->n_worst; k++) {
        marked[k].row = d->pairs[d->worst[k]].view;
        marked[k].col = d->pairs[d->worst[k]].light;
    }
    if (rc == BTF_OK) {
        btf_heatmap h;
        memset(&h, 0, sizeof h);
        h.rows = nv;
        h.cols = nl;
        h.values = v;
        h.title = "Pixel-wise mean |ΔY| per (view, light) pair";
        h.x_title = "light (θ, φ)";
        h.y_title = "view (θ, φ)";
        h.legend_label = "|ΔY|";
        h.row_labels = (const char *const *)rows;
        h.col_labels = (const char *const *)(rows + nv);
        h.marked = marked;
        h.n_marked = d->n_worst;
        h.marked_label = "the worst pairs";
        h.tooltips = 1;
        char path[4096];
        rc = btf_path_join(path, sizeof path, dir, "heatmap.svg", err);
        if (rc == BTF_OK)
            rc = btf_svg_heatmap_write(path, &h, err);
    }
    for (int i = 0; rows && i < nv + nl; i++)
        free(rows[i]);
    free(rows);
    free(v);
    free(marked);
    return rc;
}

static void pair_figure(btf_buf *b, const btf_rf_report_data *d, int i)
{
    const btf_rf_pair *p = &d->pairs[i];
    char name[64], vd[48], ld[48];
    btf_rf_report_pair_file(d, i, name, sizeof name);
    dir_text(d->in->views->dirs[p->view], vd, sizeof vd);
    dir_text(d->in->lights->dirs[p->light], ld, sizeof ld);
    int w = d->in->width * 2 + 4, h = d->in->height, scale = w < 300 ? 2 : 1;
    btf_buf_printf(b, "<div class=\"pair\"><img src=\"%s\" width=\"%d\" height=\"%d\" "
                      "alt=\"measured and model, view %s light %s\">view %s, light %s<br>"
                      "|ΔY| %.5f · combined %.2f</div>\n",
                   name, w * scale, h * scale, vd, ld, vd, ld, p->mean_abs_dy, p->d.combined);
}

/* A sampled model's memory (section 6): the sample's coefficients and the
 * coordinate map, in memory and in the file. */
static void sample_rows(btf_buf *b, const btf_rf_report_data *d)
{
    const btf_rf_model *m = d->m;
    const btf_rf_bytes *y = &d->bytes;
    char t[64], u[64], r[64];
    btf_buf_printf(b, "<tr><td class=\"l\">of which the %d×%d sample's coefficients (in "
                      "memory: %s)</td><td>%s</td><td>%s</td></tr>\n", m->width, m->height,
                   hr_bytes(y->coefficients, u, sizeof u),
                   hr_bytes(y->file - y->file_map, t, sizeof t),
                   ratio_text(d->raw.raw, y->file - y->file_map, r, sizeof r));
    btf_buf_printf(b, "<tr><td class=\"l\">and the %d×%d coordinate map (in memory: %s, 4 "
                      "bytes per texel)</td><td>%s</td><td>–</td></tr>\n", m->surface_width,
                   m->surface_height, hr_bytes(y->map, u, sizeof u),
                   hr_bytes(y->file_map, t, sizeof t));
}

static void page(btf_buf *b, const btf_rf_report_data *d)
{
    const btf_dataset_info *in = d->in;
    const btf_rf_model *m = d->m;
    char t[64], r[64], l[64];
    btf_buf_puts(b, "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
                    "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
                    "<title>btfcar report: ");
    btf_buf_html(b, d->dataset_name);
    btf_buf_printf(b, "</title>\n<style>%s</style>\n</head>\n<body>\n<h1>btfcar report: ",
                   STYLE);
    btf_buf_html(b, d->dataset_name);
    btf_buf_puts(b, "</h1>\n<p class=\"meta\">reflectance-field model ");
    btf_buf_html(b, d->model_name);
    btf_buf_printf(b, " (%s", btf_rf_fit_name(m->fit));
    if (m->fit != BTF_RF_PTM)
        btf_buf_printf(b, ", %d lobe%s", m->lobes, m->lobes == 1 ? "" : "s");
    btf_buf_printf(b, "; Meseth, Müller &amp; Klein 2003) · %d views × %d lights of %d×%d "
                      "pixels · " BTF_HTML_TIME("%s") " · " BTF_HTML_TIME("%.1f s") "</p>\n", in->n_views, in->n_lights, in->width,
                   in->height, d->date, d->seconds);
    dir_text(d->o->sphere_light, l, sizeof l);
    btf_buf_printf(b, "<div class=\"top\">\n<figure><img src=\"sphere.png\" width=\"%d\" "
                      "height=\"%d\" alt=\"the material on a sphere\">\n<figcaption>The "
                      "model on a sphere, one directional light from %s (camera frame), "
                      "rendered in " BTF_HTML_TIME("%.2f s") ".</figcaption></figure>\n<div class=\"cards\">\n",
                   d->o->sphere_size, d->o->sphere_size, l, d->sphere_s);
    btf_buf_printf(b, "<div class=\"card\"><b>%s</b><span>the model file</span></div>\n",
                   hr_bytes(d->file_bytes, t, sizeof t));
    btf_buf_printf(b, "<div class=\"card\"><b>%s</b><span>against the raw BTF (%s)"
                      "</span></div>\n", ratio_text(d->raw.raw, d->file_bytes, r, sizeof r),
                   hr_bytes(d->raw.raw, t, sizeof t));
    btf_buf_printf(b, "<div class=\"card\"><b>%.5f</b><span>mean |ΔY| over every image "
                      "(%.1f %% of the mean luminance %.4f)</span></div>\n",
                   d->mean_abs_error, percent(d->mean_abs_error, d->mean_luminance),
                   d->mean_luminance);
    btf_buf_printf(b, "<div class=\"card\"><b>%.2f</b><span>mean combined distance over %d "
                      "pairs (1.0: as close as the material is to itself)</span></div>\n"
                      "</div>\n</div>\n", d->mean_combined, d->n_pairs);
    /* compression */
    btf_buf_puts(b, "<h2>Compression</h2>\n<table>\n<tr><th class=\"l\">what</th><th>bytes"
                    "</th><th>against raw</th></tr>\n");
    btf_buf_printf(b, "<tr><td class=\"l\">raw BTF (%d × %d × %d × %d × 3 bytes)</td>"
                      "<td>%s</td><td>1 : 1</td></tr>\n", in->n_views, in->n_lights,
                   in->width, in->height, hr_bytes(d->raw.raw, t, sizeof t));
    btf_buf_printf(b, "<tr><td class=\"l\">the dataset as stored</td><td>%s</td><td>%s</td>"
                      "</tr>\n", hr_bytes(d->raw.on_disk, t, sizeof t),
                   ratio_text(d->raw.raw, d->raw.on_disk, r, sizeof r));
    btf_buf_printf(b, "<tr><td class=\"l\">reflectance-field model file (%d fields × %d "
                      "slots × 16 bits per texel, deflated)</td><td>%s</td><td><b>%s</b></td>"
                      "</tr>\n", m->fields, m->slots,
                   hr_bytes(d->file_bytes, t, sizeof t),
                   ratio_text(d->raw.raw, d->file_bytes, r, sizeof r));
    if (m->map)
        sample_rows(b, d);
    btf_buf_puts(b, "</table>\n");
    if (m->map)
        btf_buf_printf(b, "<p class=\"note\">%.1f bytes of the file per texel. Memory "
                          "reduction (paper section 6, docs/rf.md): the fields are fitted on a "
                          "%d×%d sample at (%d, %d) only, and a %d×%d map of texture "
                          "coordinates from an image quilting of the sample says which sample "
                          "texel each texel of the surface shows. The data's pixel "
                          "correspondence holds on the sample's own place only; elsewhere the "
                          "pixel-wise error measures a new arrangement of the material, and "
                          "the texture distances are the fairer figure.</p>\n",
                       (double)d->file_bytes / ((double)in->width * in->height), m->width,
                       m->height, m->sample_x, m->sample_y, m->surface_width,
                       m->surface_height);
    else
        btf_buf_printf(b, "<p class=\"note\">%.1f bytes of the file per texel. The model "
                          "keeps every texel (docs/rf.md), so it is judged pixel by pixel as "
                          "well as by the texture distances.</p>\n",
                       (double)d->file_bytes / ((double)in->width * in->height));
    /* quality */
    btf_buf_printf(b, "<h2>Quality per direction</h2>\n<p class=\"note\">%d (view, light) "
                      "pairs: each measured image against the model's flat render of that "
                      "pair (at a measured pair the fitted field itself). Pixel-wise: mean "
                      "|ΔY| %.5f over the pairs, worst %.5f; over every image of the dataset "
                      "%.5f. Texture distances (normalised): spectrum %.2f · first order "
                      "%.2f · structure %.2f · combined %.2f, worst %.2f.</p>\n",
                   d->n_pairs, d->mean_pair_dy, d->worst_pair_dy, d->mean_abs_error,
                   d->mean_spectrum, d->mean_first_order, d->mean_structure, d->mean_combined,
                   d->worst_combined);
    btf_buf_puts(b, "<figure><img class=\"plot\" src=\"heatmap.svg\" alt=\"pixel-wise error "
                    "per pair\"></figure>\n<h3>The worst pairs (by |ΔY|)</h3>\n"
                    "<div class=\"pairs\">\n");
    for (int k = 0; k < d->n_worst; k++)
        pair_figure(b, d, d->worst[k]);
    btf_buf_puts(b, "</div>\n<h3>The pictured pairs</h3>\n<div class=\"pairs\">\n");
    for (int i = 0; i < d->n_pairs; i++)
        if (d->pairs[i].pictured)
            pair_figure(b, d, i);
    btf_buf_puts(b, "</div>\n<h3>Every measured pair</h3>\n<table>\n<tr><th class=\"l\">view"
                    "</th><th class=\"l\">light</th><th>|ΔY|</th><th>spectrum</th>"
                    "<th>first order</th><th>structure</th><th>combined</th></tr>\n");
    for (int i = 0; i < d->n_pairs; i++) {
        const btf_rf_pair *p = &d->pairs[i];
        char vd[48], ld[48];
        dir_text(in->views->dirs[p->view], vd, sizeof vd);
        dir_text(in->lights->dirs[p->light], ld, sizeof ld);
        btf_buf_printf(b, "<tr><td class=\"l\">%s</td><td class=\"l\">%s</td><td><b>%.5f</b>"
                          "</td><td>%.2f</td><td>%.2f</td><td>%.2f</td><td>%.2f</td></tr>\n",
                       vd, ld, p->mean_abs_dy, p->d.spectrum.normalised,
                       p->d.first_order.normalised, p->d.structure.normalised, p->d.combined);
    }
    btf_buf_puts(b, "</table>\n<p class=\"meta\">Made by btfcar " BTF_VERSION_STRING
                    " (Meseth, Müller &amp; Klein, <i>Preserving realism in real-time "
                    "rendering of bidirectional texture functions</i>, 2003). The same "
                    "numbers: report.json.</p>\n</body>\n</html>\n");
}

static void add_dir(cJSON *o, const char *key, btf_dir d)
{
    cJSON *j = cJSON_AddObjectToObject(o, key);
    cJSON_AddNumberToObject(j, "theta", d.theta);
    cJSON_AddNumberToObject(j, "phi", d.phi);
}

static btf_status json(const btf_rf_report_data *d, const char *dir, btf_error *err)
{
    cJSON *root = cJSON_CreateObject();
    if (!root)
        return btf_fail(err, BTF_E_NOMEM, "report.json: out of memory");
    cJSON_AddStringToObject(root, "format", "btfcar-report");
    cJSON_AddNumberToObject(root, "format_version", 1);
    cJSON_AddStringToObject(root, "family", "rf");
    cJSON_AddStringToObject(root, "btfcar", BTF_VERSION_STRING);
    cJSON_AddStringToObject(root, "date", d->date);
    cJSON_AddStringToObject(root, "dataset", d->dataset_name);
    cJSON_AddStringToObject(root, "model", d->model_name);
    cJSON *ds = cJSON_AddObjectToObject(root, "dataset_info");
    cJSON_AddStringToObject(ds, "layout", btf_layout_name(d->in->layout));
    cJSON_AddNumberToObject(ds, "views", d->in->n_views);
    cJSON_AddNumberToObject(ds, "lights", d->in->n_lights);
    cJSON_AddNumberToObject(ds, "width", d->in->width);
    cJSON_AddNumberToObject(ds, "height", d->in->height);
    cJSON *rf = cJSON_AddObjectToObject(root, "rf");
    cJSON_AddStringToObject(rf, "fit", btf_rf_fit_name(d->m->fit));
    cJSON_AddNumberToObject(rf, "lobes", d->m->lobes);
    cJSON_AddNumberToObject(rf, "fields", d->m->fields);
    cJSON_AddNumberToObject(rf, "slots", d->m->slots);
    cJSON_AddNumberToObject(root, "seconds", d->seconds);
    cJSON *c = cJSON_AddObjectToObject(root, "compression");
    cJSON_AddNumberToObject(c, "raw_bytes", (double)d->raw.raw);
    cJSON_AddNumberToObject(c, "on_disk_bytes", (double)d->raw.on_disk);
    cJSON_AddNumberToObject(c, "model_bytes", (double)d->file_bytes);
    cJSON_AddNumberToObject(c, "ratio", d->file_bytes ? (double)d->raw.raw / d->file_bytes : 0);
    cJSON_AddNumberToObject(c, "bytes_per_texel",
                            (double)d->file_bytes / ((double)d->in->width * d->in->height));
    cJSON_AddNumberToObject(c, "coefficient_bytes", (double)d->bytes.coefficients);
    cJSON_AddNumberToObject(c, "map_bytes", (double)d->bytes.map);
    cJSON_AddNumberToObject(c, "file_map_bytes", (double)d->bytes.file_map);
    if (d->m->map) {
        cJSON *s = cJSON_AddObjectToObject(rf, "sample");
        cJSON_AddNumberToObject(s, "x", d->m->sample_x);
        cJSON_AddNumberToObject(s, "y", d->m->sample_y);
        cJSON_AddNumberToObject(s, "width", d->m->width);
        cJSON_AddNumberToObject(s, "height", d->m->height);
        cJSON_AddNumberToObject(s, "surface_width", d->m->surface_width);
        cJSON_AddNumberToObject(s, "surface_height", d->m->surface_height);
    }
    cJSON *pw = cJSON_AddObjectToObject(root, "pixelwise");
    cJSON_AddNumberToObject(pw, "mean_abs_dy", d->mean_abs_error);
    cJSON_AddNumberToObject(pw, "mean_luminance", d->mean_luminance);
    cJSON_AddNumberToObject(pw, "mean_pair_abs_dy", d->mean_pair_dy);
    cJSON_AddNumberToObject(pw, "worst_pair_abs_dy", d->worst_pair_dy);
    cJSON *q = cJSON_AddObjectToObject(root, "quality");
    cJSON_AddStringToObject(q, "sample", d->o->quality.all ? "all" : "spread");
    cJSON_AddNumberToObject(q, "pairs", d->n_pairs);
    cJSON_AddNumberToObject(q, "mean_combined", d->mean_combined);
    cJSON_AddNumberToObject(q, "worst_combined", d->worst_combined);
    cJSON_AddNumberToObject(q, "mean_spectrum", d->mean_spectrum);
    cJSON_AddNumberToObject(q, "mean_first_order", d->mean_first_order);
    cJSON_AddNumberToObject(q, "mean_structure", d->mean_structure);
    cJSON *worst = cJSON_AddArrayToObject(q, "worst");
    for (int k = 0; k < d->n_worst; k++)
        cJSON_AddItemToArray(worst, cJSON_CreateNumber(d->worst[k]));
    cJSON *pairs = cJSON_AddArrayToObject(q, "pairs_measured");
    for (int i = 0; i < d->n_pairs; i++) {
        const btf_rf_pair *p = &d->pairs[i];
        cJSON *o = cJSON_CreateObject();
        cJSON_AddItemToArray(pairs, o);
        cJSON_AddNumberToObject(o, "view", p->view);
        cJSON_AddNumberToObject(o, "light", p->light);
        add_dir(o, "view_dir", d->in->views->dirs[p->view]);
        add_dir(o, "light_dir", d->in->lights->dirs[p->light]);
        cJSON_AddNumberToObject(o, "mean_abs_dy", p->mean_abs_dy);
        cJSON_AddNumberToObject(o, "spectrum", p->d.spectrum.normalised);
        cJSON_AddNumberToObject(o, "first_order", p->d.first_order.normalised);
        cJSON_AddNumberToObject(o, "structure", p->d.structure.normalised);
        cJSON_AddNumberToObject(o, "combined", p->d.combined);
        if (p->pictured) {
            char name[64];
            btf_rf_report_pair_file(d, i, name, sizeof name);
            cJSON_AddStringToObject(o, "picture", name);
        }
    }
    cJSON *pv = cJSON_AddObjectToObject(root, "preview");
    cJSON_AddStringToObject(pv, "picture", "sphere.png");
    add_dir(pv, "light", d->o->sphere_light);
    cJSON_AddNumberToObject(pv, "size", d->o->sphere_size);
    cJSON_AddNumberToObject(pv, "seconds", d->sphere_s);
    char *text = cJSON_Print(root);
    cJSON_Delete(root);
    if (!text)
        return btf_fail(err, BTF_E_NOMEM, "report.json: out of memory");
    char path[4096];
    btf_status rc = btf_path_join(path, sizeof path, dir, "report.json", err);
    if (rc == BTF_OK)
        rc = btf_write_file_atomic(path, text, strlen(text), err);
    cJSON_free(text);
    return rc;
}

btf_status btf_rf_report_page(const btf_rf_report_data *d, const char *dir, btf_error *err)
{
    btf_status rc = heat_map(d, dir, err);
    if (rc)
        return rc;
    btf_buf b = {0};
    page(&b, d);
    char path[4096];
    rc = btf_path_join(path, sizeof path, dir, "index.html", err);
    if (rc == BTF_OK)
        rc = btf_buf_write(&b, path, err);
    btf_buf_free(&b);
    if (rc == BTF_OK)
        rc = json(d, dir, err);
    return rc;
}
