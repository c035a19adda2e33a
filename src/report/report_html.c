/*
 * report_html.c — the report page (issue 18, docs/report.md): one HTML
 * file that needs nothing but the PNG and SVG files beside it — no script,
 * no font or style sheet fetched — so that it reads the same from a disk,
 * an archive or a web server. The plots are drawn by svg_heatmap.c and
 * svg_scatter.c; the numbers are those of report.json.
 */
#include "core/core.h"
#include "report/report.h"
#include "report/report_data.h"

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
    "th{background:#f3f3f5}td.l,th.l{text-align:left}tr.def td{background:#fff7d6}"
    "tr.front td:first-child{font-weight:bold}figure{margin:6px 0}"
    "figcaption{font-size:12px;color:#444}.pairs{display:flex;flex-wrap:wrap;gap:10px}"
    ".pair{border:1px solid #ddd;padding:4px;font-size:11px}"
    ".pair img{image-rendering:pixelated;display:block}.note{font-size:13px;color:#444}"
    "img.plot{max-width:100%;height:auto}";

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

static const char *ratio_text(double r, char *buf, size_t n)
{
    if (!(r > 0) || !isfinite(r))
        snprintf(buf, n, "–");
    else if (r >= 100)
        snprintf(buf, n, "1 : %.0f", r);
    else
        snprintf(buf, n, "1 : %.1f", r);
    return buf;
}

static double ratio_of(uint64_t raw, uint64_t bytes)
{
    return bytes ? (double)raw / (double)bytes : 0.0;
}

static void dir_text(btf_dir d, char *buf, size_t n)
{
    snprintf(buf, n, "θ %g φ %g", d.theta, d.phi);
}

static void head(btf_buf *b, const btf_report_data *d)
{
    btf_buf_puts(b, "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
                    "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
                    "<title>btfcar report: ");
    btf_buf_html(b, d->dataset_name);
    btf_buf_printf(b, "</title>\n<style>%s</style>\n</head>\n<body>\n", STYLE);
    btf_buf_puts(b, "<h1>btfcar report: ");
    btf_buf_html(b, d->dataset_name);
    btf_buf_puts(b, "</h1>\n<p class=\"meta\">model ");
    btf_buf_html(b, d->model_name);
    btf_buf_printf(b, " · %d views × %d lights of %d×%d pixels · %d subspace images · "
                      "btfcar %s · " BTF_HTML_TIME("%s") " · measured in " BTF_HTML_TIME("%.1f s") "</p>\n",
                   d->in->n_views, d->in->n_lights, d->in->width, d->in->height,
                   d->m->n_subspaces, BTF_VERSION_STRING, d->date, d->seconds);
}

static void top(btf_buf *b, const btf_report_data *d)
{
    char t[64], r[64], l[64];
    dir_text(d->o->sphere_light, l, sizeof l);
    btf_buf_printf(b, "<div class=\"top\">\n<figure><img src=\"sphere.png\" width=\"%d\" "
                      "height=\"%d\" alt=\"the material on a sphere\">\n<figcaption>The "
                      "model on a sphere, one directional light from %s (camera frame), "
                      "%d of %d subspace images needed, rendered in " BTF_HTML_TIME("%.2f s") ".</figcaption>"
                      "</figure>\n<div class=\"cards\">\n",
                   d->o->sphere_size, d->o->sphere_size, l, d->sphere_info.needed,
                   d->sphere_info.total, d->sphere_s);
    btf_buf_printf(b, "<div class=\"card\"><b>%s</b><span>the model file</span></div>\n",
                   hr_bytes(d->bytes.total, t, sizeof t));
    btf_buf_printf(b, "<div class=\"card\"><b>%s</b><span>against the raw BTF (%s)"
                      "</span></div>\n",
                   ratio_text(ratio_of(d->raw.raw, d->bytes.total), r, sizeof r),
                   hr_bytes(d->raw.raw, t, sizeof t));
    btf_buf_printf(b, "<div class=\"card\"><b>%.2f</b><span>mean combined distance over %d "
                      "pairs (1.0: as close as the material is to itself)</span></div>\n",
                   d->q.mean_combined, d->q.n_pairs - d->q.n_held_out);
    if (d->q.n_held_out)
        btf_buf_printf(b, "<div class=\"card\"><b>%.2f</b><span>mean combined distance over "
                          "%d pair%s held out of the analysis (rendered by interpolation)"
                          "</span></div>\n", d->q.mean_held_out, d->q.n_held_out,
                       d->q.n_held_out == 1 ? "" : "s");
    const btf_pair_quality *w = &d->q.pairs[d->q.worst];
    char vd[48], ld[48];
    dir_text(d->in->views->dirs[w->view], vd, sizeof vd);
    dir_text(d->in->lights->dirs[w->light], ld, sizeof ld);
    btf_buf_printf(b, "<div class=\"card\"><b>%.2f</b><span>worst pair: view %s, light %s"
                      "</span></div>\n</div>\n</div>\n", w->d.combined, vd, ld);
}

static void compression(btf_buf *b, const btf_report_data *d)
{
    char x[64], y[64];
    btf_buf_puts(b, "<h2>Compression</h2>\n<p class=\"note\">What the parameter file costs "
                    "against the measured BTF, and what two plain codecs store for the same "
                    "data (definitions: docs/report.md).</p>\n<table>\n<tr><th class=\"l\">"
                    "what</th><th>bytes</th><th>ratio to raw</th><th class=\"l\">note</th>"
                    "</tr>\n");
    if (d->in->n_pairs < d->raw.views * d->raw.lights)
        btf_buf_printf(b, "<tr><td class=\"l\">raw BTF, 8 bits per value</td><td>%s</td><td>1 : "
                          "1</td><td class=\"l\">%d images (a sparse set of the %d × %d pairs) "
                          "× %d × %d × 3</td></tr>\n",
                       hr_bytes(d->raw.raw, x, sizeof x), d->in->n_pairs, d->raw.views,
                       d->raw.lights, d->raw.width, d->raw.height);
    else
    btf_buf_printf(b, "<tr><td class=\"l\">raw BTF, 8 bits per value</td><td>%s</td><td>1 : 1"
                      "</td><td class=\"l\">%d × %d images × %d × %d × 3</td></tr>\n",
                   hr_bytes(d->raw.raw, x, sizeof x), d->raw.views, d->raw.lights, d->raw.width,
                   d->raw.height);
    btf_buf_printf(b, "<tr><td class=\"l\">the dataset as stored</td><td>%s</td><td>%s</td>"
                      "<td class=\"l\">the image files on disk</td></tr>\n",
                   hr_bytes(d->raw.on_disk, x, sizeof x),
                   ratio_text(ratio_of(d->raw.raw, d->raw.on_disk), y, sizeof y));
    btf_buf_printf(b, "<tr class=\"def\"><td class=\"l\">btfcar model</td><td>%s</td><td>%s"
                      "</td><td class=\"l\">%d subspaces, CAR parameters, marginals, range "
                      "tile</td></tr>\n",
                   hr_bytes(d->bytes.total, x, sizeof x),
                   ratio_text(ratio_of(d->raw.raw, d->bytes.total), y, sizeof y),
                   d->m->n_subspaces);
    btf_buf_printf(b, "<tr><td class=\"l\">the paper's claim</td><td>–</td><td>%s</td>"
                      "<td class=\"l\">Haindl &amp; Filip 2007: about 1 : 10<sup>5</sup></td>"
                      "</tr>\n", ratio_text(BTF_REPORT_PAPER_RATIO, y, sizeof y));
    if (d->pca.views == 0)
        btf_buf_puts(b, "<tr><td class=\"l\">per-view PCA</td><td>–</td><td>–</td><td "
                        "class=\"l\">not measured: a sparse set holds no view under every "
                        "light</td></tr>\n");
    else
    btf_buf_printf(b, "<tr><td class=\"l\">per-view PCA</td><td>%s</td><td>%s</td><td "
                      "class=\"l\">%.1f components per view on average (%d–%d) for an RMS "
                      "error ≤ %.1f 8-bit levels (reached: %.2f), %d-bit values</td></tr>\n",
                   hr_bytes(d->pca.bytes, x, sizeof x), ratio_text(d->pca.ratio, y, sizeof y),
                   d->pca.mean_components, d->pca.min_components, d->pca.max_components,
                   d->o->pca.max_rms > 0 ? d->o->pca.max_rms : 2.0, d->pca.rms,
                   d->o->pca.bits > 0 ? d->o->pca.bits : 16);
    btf_buf_printf(b, "<tr><td class=\"l\">JPEG of the subspace images</td><td>%s</td><td>%s"
                      "</td><td class=\"l\">%d images at quality %d (RMS %.2f levels) + the "
                      "%llu-byte index table; no relief, no synthesis at other sizes</td>"
                      "</tr>\n</table>\n",
                   hr_bytes(d->jpeg.bytes, x, sizeof x), ratio_text(d->jpeg.ratio, y, sizeof y),
                   d->jpeg.images, d->jpeg.quality, d->jpeg.rms,
                   (unsigned long long)d->jpeg.index_bytes);
    btf_buf_printf(b, "<h3>The model file by part</h3>\n<table>\n<tr><th class=\"l\">part"
                      "</th><th>bytes in the file</th><th>share</th><th>bytes before "
                      "deflate</th></tr>\n");
    for (int p = 0; p < BTF_MODEL_PART_COUNT; p++) {
        if (!d->bytes.file[p] && !d->bytes.raw[p])
            continue;
        btf_buf_printf(b, "<tr><td class=\"l\">%s</td><td>%llu</td><td>%.1f %%</td><td>%llu"
                          "</td></tr>\n", btf_model_part_name(p),
                       (unsigned long long)d->bytes.file[p],
                       d->bytes.total ? 100.0 * d->bytes.file[p] / d->bytes.total : 0.0,
                       (unsigned long long)d->bytes.raw[p]);
    }
    btf_buf_printf(b, "<tr><th class=\"l\">total</th><th>%llu</th><th>100 %%</th><th>%llu"
                      "</th></tr>\n</table>\n", (unsigned long long)d->bytes.total,
                   (unsigned long long)d->bytes.payload);
}

static void pair_row(btf_buf *b, const btf_report_data *d, int i)
{
    const btf_pair_quality *p = &d->q.pairs[i];
    char vd[48], ld[48];
    dir_text(d->in->views->dirs[p->view], vd, sizeof vd);
    dir_text(d->in->lights->dirs[p->light], ld, sizeof ld);
    char sub[32];
    if (p->held_out)
        snprintf(sub, sizeof sub, "held out");
    else
        snprintf(sub, sizeof sub, "%d", p->subspace);
    btf_buf_printf(b, "<tr><td class=\"l\">%s</td><td class=\"l\">%s</td><td>%s</td>"
                      "<td>%.2f</td><td>%.2f</td><td>%.2f</td><td><b>%.2f</b></td></tr>\n",
                   vd, ld, sub, p->d.spectrum.normalised, p->d.first_order.normalised,
                   p->d.structure.normalised, p->d.combined);
}

static void pair_figure(btf_buf *b, const btf_report_data *d, int i, int zoom)
{
    const btf_pair_quality *p = &d->q.pairs[i];
    char name[64], vd[48], ld[48];
    btf_report_pair_file(d, i, name, sizeof name);
    dir_text(d->in->views->dirs[p->view], vd, sizeof vd);
    dir_text(d->in->lights->dirs[p->light], ld, sizeof ld);
    int w = d->in->width * 2 + 4, h = d->in->height;
    /* Small measurements are shown larger where there are few. */
    int scale = zoom && w < 300 ? 2 : 1;
    btf_buf_printf(b, "<div class=\"pair\"><img src=\"%s\" width=\"%d\" height=\"%d\" "
                      "alt=\"measured and model, view %s light %s\">view %s, light %s<br>"
                      "spectrum %.2f · first order %.2f · structure %.2f · <b>%.2f</b></div>\n",
                   name, w * scale, h * scale, vd, ld, vd, ld, p->d.spectrum.normalised,
                   p->d.first_order.normalised, p->d.structure.normalised, p->d.combined);
}

/* The heat map over views (rows) x lights (columns): all pairs of the
 * dataset, those not measured left empty. */
static btf_status heat_map(const btf_report_data *d, const char *dir, btf_error *err)
{
    int nv = d->in->n_views, nl = d->in->n_lights;
    double *v = btf_alloc((size_t)nv * nl, sizeof(double), err);
    char **rows = btf_calloc((size_t)nv + nl, sizeof(char *), err);
    btf_svg_cell *marked = btf_calloc((size_t)d->n_worst + 1, sizeof *marked, err);
    btf_status rc = v && rows && marked ? BTF_OK : BTF_E_NOMEM;
    for (int i = 0; rc == BTF_OK && i < nv * nl; i++)
        v[i] = NAN;
    for (int i = 0; rc == BTF_OK && i < d->q.n_pairs; i++)
        v[(size_t)d->q.pairs[i].view * nl + d->q.pairs[i].light] = d->q.pairs[i].d.combined;
    for (int i = 0; rc == BTF_OK && i < nv + nl; i++) {
        btf_dir dd = i < nv ? d->in->views->dirs[i] : d->in->lights->dirs[i - nv];
        if (!(rows[i] = btf_alloc(32, 1, err)))
            rc = BTF_E_NOMEM;
        else
            snprintf(rows[i], 32, "%g, %g", dd.theta, dd.phi);
    }
    for (int k = 0; rc == BTF_OK && k < d->n_worst; k++) {
        marked[k].row = d->q.pairs[d->worst[k]].view;
        marked[k].col = d->q.pairs[d->worst[k]].light;
    }
    if (rc == BTF_OK) {
        btf_heatmap h;
        memset(&h, 0, sizeof h);
        h.rows = nv;
        h.cols = nl;
        h.values = v;
        h.title = "Combined distance per (view, light) pair";
        h.x_title = "light (θ, φ)";
        h.y_title = "view (θ, φ)";
        h.legend_label = "combined";
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

static void quality(btf_buf *b, const btf_report_data *d)
{
    const btf_quality *q = &d->q;
    btf_buf_printf(b, "<h2>Quality per direction</h2>\n<p class=\"note\">Each measured image "
                      "against the model's flat render of the same (view, light) pair, by "
                      "texture distances that need no pixel correspondence (the model is a new "
                      "sample of the material, not a copy): the power spectrum, the first-order "
                      "(colour histogram) and the structure (pyramid band statistics) "
                      "distances, each divided by the same distance between disjoint crops of "
                      "the measured image — 1.0 is as close as the material is to itself — and "
                      "their mean, the combined distance (docs/measure.md). %s: %d pairs, "
                      "measured in " BTF_HTML_TIME("%.1f s") ".</p>\n",
                   d->o->quality.all ? "Every pair" : "A spread of views × lights over every "
                                                      "ring of the hemisphere",
                   q->n_pairs, q->seconds);
    btf_buf_printf(b, "<table>\n<tr><th class=\"l\"></th><th>spectrum</th><th>first order"
                      "</th><th>structure</th><th>combined</th></tr>\n<tr><td class=\"l\">mean"
                      "</td><td>%.2f</td><td>%.2f</td><td>%.2f</td><td><b>%.2f</b></td></tr>\n"
                      "<tr><td class=\"l\">median</td><td></td><td></td><td></td><td>%.2f</td>"
                      "</tr>\n<tr><td class=\"l\">worst</td><td></td><td></td><td></td><td>"
                      "%.2f</td></tr>\n</table>\n",
                   q->mean_spectrum, q->mean_first_order, q->mean_structure, q->mean_combined,
                   q->median_combined, q->worst_combined);
    if (q->n_held_out)
        btf_buf_printf(b, "<p>%d of these pairs were held out of the analysis (the table's "
                          "\"held out\"): the model renders them by interpolating the pairs "
                          "it measured (docs/render.md, \"Sparse pair sets\"); their mean "
                          "combined distance is <b>%.2f</b>, not counted in the mean, median "
                          "and worst above.</p>\n", q->n_held_out, q->mean_held_out);
    btf_buf_puts(b, "<figure><img class=\"plot\" src=\"heatmap.svg\" alt=\"heat map of the "
                    "combined distance over views and lights\"><figcaption>Rows: views; "
                    "columns: lights; empty cells were not measured; outlined: the worst "
                    "pairs.</figcaption></figure>\n");
    btf_buf_printf(b, "<h3>The %d worst pairs (measured | model)</h3>\n<div class=\"pairs\">\n",
                   d->n_worst);
    for (int k = 0; k < d->n_worst; k++)
        pair_figure(b, d, d->worst[k], 1);
    btf_buf_puts(b, "</div>\n<h3>Pairs with pictures (measured | model)</h3>\n"
                    "<div class=\"pairs\">\n");
    for (int i = 0; i < q->n_pairs; i++)
        if (d->pictured[i])
            pair_figure(b, d, i, 0);
    btf_buf_puts(b, "</div>\n<h3>Every measured pair</h3>\n<table>\n<tr><th class=\"l\">view"
                    "</th><th class=\"l\">light</th><th>subspace</th><th>spectrum</th><th>"
                    "first order</th><th>structure</th><th>combined</th></tr>\n");
    for (int i = 0; i < q->n_pairs; i++)
        pair_row(b, d, i);
    btf_buf_puts(b, "</table>\n");
}

static void setting_text(const btf_sweep_setting *s, char *buf, size_t n)
{
    char k[16], l[16], nb[16];
    snprintf(k, sizeof k, s->subspaces ? "%d" : "auto", s->subspaces);
    snprintf(l, sizeof l, s->levels ? "%d" : "auto", s->levels);
    snprintf(nb, sizeof nb, s->neighbours ? "%d" : "auto", s->neighbours);
    char r[24] = "";
    if (s->range_size)
        snprintf(r, sizeof r, ", R %d", s->range_size);
    snprintf(buf, n, "K %s, L %s, N %s%s%s", k, l, nb, r, s->plain ? ", plain" : "");
}

static btf_status pareto_plots(const btf_report_data *d, const char *dir, btf_error *err)
{
    const btf_sweep *s = &d->sweep;
    int n = s->n_points;
    double *x = btf_alloc((size_t)n * 3, sizeof(double), err);
    char (*labels)[48] = btf_alloc((size_t)n, 48, err);
    const char **lp = btf_alloc((size_t)n, sizeof(char *), err);
    btf_status rc = x && labels && lp ? BTF_OK : BTF_E_NOMEM;
    int marked = -1;
    for (int i = 0; rc == BTF_OK && i < n; i++) {
        x[i] = (double)s->points[i].bytes;
        x[n + i] = s->points[i].synth_s;
        x[2 * n + i] = s->points[i].mean_combined;
        setting_text(&s->points[i].setting, labels[i], 48);
        lp[i] = labels[i];
        if (s->points[i].is_default)
            marked = i;
    }
    for (int which = 0; rc == BTF_OK && which < 2; which++) {
        btf_scatter sc;
        memset(&sc, 0, sizeof sc);
        sc.n = n;
        sc.x = x + which * n;
        sc.y = x + 2 * n;
        sc.labels = lp;
        sc.title = which ? "Quality against synthesis time" : "Quality against model bytes";
        sc.x_title = which ? "CPU synthesis of every subspace image (s)" : "model file (bytes)";
        sc.y_title = "mean combined distance (lower is better)";
        sc.log_x = 1;
        sc.marked_label = marked >= 0 ? "default" : NULL;
        sc.marked = marked >= 0 ? marked : 0;
        char path[4096];
        rc = btf_path_join(path, sizeof path, dir, which ? "pareto-time.svg" : "pareto-bytes.svg",
                           err);
        if (rc == BTF_OK)
            rc = btf_svg_scatter_write(path, &sc, err);
    }
    free(x);
    free(labels);
    free(lp);
    return rc;
}

static void trade(btf_buf *b, const btf_report_data *d)
{
    btf_buf_puts(b, "<h2>The speed/accuracy trade</h2>\n");
    if (!d->have_sweep) {
        btf_buf_puts(b, "<p class=\"note\">Not measured: <code>btfcar report DATASET MODEL -o "
                        "DIR --sweep</code> analyses the dataset over a grid of settings and "
                        "shows here what each costs and gives. <code>btfcar analyse --preset "
                        "fast|balanced|accurate</code> picks a point measured on the "
                        "generated materials (docs/report.md).</p>\n");
        return;
    }
    const btf_sweep *s = &d->sweep;
    btf_buf_printf(b, "<p class=\"note\">The dataset analysed under %d settings: K subspace "
                      "images, L pyramid levels, N neighbours (a fixed neighbourhood of the "
                      "first N candidate offsets; auto: the Bayesian choice per band). The "
                      "features and the range map were computed once (" BTF_HTML_TIME("%.1f s") ") and shared; "
                      "settings ran in parallel, one thread each. Analysis: segmentation "
                      "and the CAR fits of that setting; synthesis: every subspace image at "
                      "%d² on the CPU, in one batch as btfcar synthesise makes them "
                      "(colour matching beside the fields); render: the sphere frame at "
                      "%d², one thread; "
                      "quality: the mean and worst combined distance over the pairs above, "
                      "each the mean over %d synthesis seeds (± : the standard deviation "
                      "of the mean between the seeds). "
                      "%d of %d points were read back from an earlier run.</p>\n",
                   s->n_points, s->shared_s, d->o->sweep_opts.synth_size,
                   d->o->sweep_opts.render_size, s->seeds, s->resumed, s->n_points);
    btf_buf_puts(b, "<figure><img class=\"plot\" src=\"pareto-bytes.svg\" alt=\"quality "
                    "against model bytes\"></figure>\n<figure><img class=\"plot\" "
                    "src=\"pareto-time.svg\" alt=\"quality against synthesis time\"></figure>"
                    "\n<p><b>Pareto-optimal</b> (no other setting is both smaller and "
                    "closer): ");
    int first = 1;
    for (int i = 0; i < s->n_points; i++)
        if (s->points[i].pareto_bytes || s->points[i].pareto_time) {
            char t[64];
            setting_text(&s->points[i].setting, t, sizeof t);
            btf_buf_printf(b, "%s%s (%s)", first ? "" : "; ", t,
                           s->points[i].pareto_bytes && s->points[i].pareto_time
                               ? "bytes and time"
                               : s->points[i].pareto_bytes ? "bytes" : "time");
            first = 0;
        }
    btf_buf_puts(b, ".</p>\n<table>\n<tr><th class=\"l\">setting</th><th>K made</th>"
                    "<th>analysis s</th><th>synthesis s</th><th>GPU s</th><th>render s</th>"
                    "<th>bytes</th><th>mean</th><th>±</th><th>worst</th>"
                    "<th class=\"l\">front</th></tr>\n");
    for (int i = 0; i < s->n_points; i++) {
        const btf_sweep_point *p = &s->points[i];
        char t[64], g[32];
        setting_text(&p->setting, t, sizeof t);
        if (p->gpu_synth_s >= 0)
            snprintf(g, sizeof g, "%.3f", p->gpu_synth_s);
        else
            snprintf(g, sizeof g, "–");
        btf_buf_printf(b, "<tr class=\"%s%s\"><td class=\"l\">%s%s</td><td>%d</td><td class=\"time\">%.2f</td>"
                          "<td class=\"time\">%.3f</td><td class=\"time\">%s</td><td class=\"time\">%.3f</td>"
                          "<td>%llu</td><td>%.3f</td>"
                          "<td>%.3f</td><td>%.2f</td><td class=\"l\">%s%s</td></tr>\n",
                       p->is_default ? "def " : "",
                       p->pareto_bytes || p->pareto_time ? "front" : "", t,
                       p->is_default ? " (default)" : "", p->k, p->analyse_s, p->synth_s, g,
                       p->render_s, (unsigned long long)p->bytes, p->mean_combined,
                       p->seed_spread, p->worst_combined, p->pareto_bytes ? "bytes " : "",
                       p->pareto_time ? "time" : "");
    }
    btf_buf_puts(b, "</table>\n<p class=\"note\">No GPU time where no GPU was present (a CPU "
                    "Vulkan driver is not timed).</p>\n");
}

btf_status btf_report_html(const btf_report_data *d, const char *dir, btf_error *err)
{
    btf_status rc = heat_map(d, dir, err);
    if (rc == BTF_OK && d->have_sweep)
        rc = pareto_plots(d, dir, err);
    if (rc)
        return rc;
    btf_buf b = {0};
    head(&b, d);
    top(&b, d);
    compression(&b, d);
    quality(&b, d);
    trade(&b, d);
    btf_buf_puts(&b, "<p class=\"meta\">Made by btfcar " BTF_VERSION_STRING " (Haindl &amp; "
                     "Filip, <i>Extreme compression and modeling of bidirectional texture "
                     "function</i>, TPAMI 2007). The same numbers: report.json.</p>\n"
                     "</body>\n</html>\n");
    char path[4096];
    rc = btf_path_join(path, sizeof path, dir, "index.html", err);
    if (rc == BTF_OK)
        rc = btf_buf_write(&b, path, err);
    btf_buf_free(&b);
    return rc;
}
