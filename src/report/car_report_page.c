/*
 * car_report_page.c — the CAR report's own sections (docs/report.md),
 * each its part of the page and its keys of report.json: the model under
 * the title, the top's cards, the compression (the model file by part, the
 * per-view PCA and JPEG contrasts), the quality per direction (the texture
 * distances, the held-out pairs, the subspace of each pair) and the
 * preview's keys. The shared pieces they call are in
 * report_page.c and report_json.c; the trade is in car_report_trade.c.
 */
#include "core/core.h"
#include "report/car_report_data.h"

#include <stdio.h>
#include <string.h>

/* A section's data: the base is the first member of the family's data. */
static const btf_car_report *car(const btf_report_base *r)
{
    return (const btf_car_report *)r;
}

/* ------------------------------------------------------------ about */

static void about_html(btf_buf *b, const btf_report_base *r)
{
    btf__buf_puts(b, "model ");
    btf__buf_html(b, r->model_name);
    btf__buf_printf(b, " · %d views × %d lights of %d×%d pixels · %d subspace images · "
                      "btfcar %s · " BTF_HTML_TIME("%s") " · measured in " BTF_HTML_TIME("%.1f s"),
                   r->in->n_views, r->in->n_lights, r->in->width, r->in->height,
                   car(r)->m->n_subspaces, BTF_VERSION_STRING, r->date, r->seconds);
}

static void about_json(cJSON *root, const btf_report_base *r)
{
    cJSON_AddNumberToObject(root, "subspaces", car(r)->m->n_subspaces);
}

const btf_report_section btf__car_about = {NULL, about_html, about_json};

/* ------------------------------------------------------------ the top */

static void top_html(btf_buf *b, const btf_report_base *r)
{
    const btf_car_report *d = car(r);
    const btf_quality *q = &d->q;
    char note[96], vd[48], ld[48];
    snprintf(note, sizeof note, "%d of %d subspace images needed, ", d->sphere_info.needed,
             d->sphere_info.total);
    btf__report_top_begin(b, r, note);
    btf__buf_printf(b, BTF_HTML_CARD("%.2f", "mean combined distance over %d pairs (1.0: as "
                                            "close as the material is to itself)"),
                   q->mean_combined, q->n_pairs - q->n_held_out);
    if (q->n_held_out)
        btf__buf_printf(b, BTF_HTML_CARD("%.2f", "mean combined distance over %d pair%s held "
                                                "out of the analysis (rendered by "
                                                "interpolation)"),
                       q->mean_held_out, q->n_held_out, q->n_held_out == 1 ? "" : "s");
    const btf_pair_quality *w = &q->pairs[q->worst];
    btf__buf_printf(b, BTF_HTML_CARD("%.2f", "worst pair: view %s, light %s"), w->d.combined,
                    btf__report_dir_text(r->in->views->dirs[w->view], vd, sizeof vd),
                    btf__report_dir_text(r->in->lights->dirs[w->light], ld, sizeof ld));
    btf__report_top_end(b);
}

const btf_report_section btf__car_top = {NULL, top_html, NULL};

/* ------------------------------------------------------------ compression */

static void compression_html(btf_buf *b, const btf_report_base *r)
{
    const btf_car_report *d = car(r);
    const btf_raw_bytes *raw = &r->raw;
    char x[64], y[64], note[192];
    btf__buf_puts(b, "<h2>Compression</h2>\n<p class=\"note\">What the parameter file costs "
                    "against the measured BTF, and what two plain codecs store for the same "
                    "data (definitions: docs/report.md).</p>\n<table>\n<tr><th class=\"l\">"
                    "what</th><th>bytes</th><th>ratio to raw</th><th class=\"l\">note</th>"
                    "</tr>\n");
    if (r->in->n_pairs < raw->views * raw->lights)
        snprintf(note, sizeof note, "%d images (a sparse set of the %d × %d pairs) × %d × %d "
                 "× 3", r->in->n_pairs, raw->views, raw->lights, raw->width, raw->height);
    else
        snprintf(note, sizeof note, "%d × %d images × %d × %d × 3", raw->views, raw->lights,
                 raw->width, raw->height);
    btf__report_row(b, NULL, "raw BTF, 8 bits per value",
                    btf__report_bytes_text(raw->raw, x, sizeof x), "1 : 1", note);
    btf__report_row(b, NULL, "the dataset as stored",
                    btf__report_bytes_text(raw->on_disk, x, sizeof x),
                    btf__report_ratio_text(btf__report_ratio(raw->raw, raw->on_disk), y, sizeof y),
                    "the image files on disk");
    snprintf(note, sizeof note, "%d subspaces, CAR parameters, marginals, range tile",
             d->m->n_subspaces);
    btf__report_row(b, "def", "btfcar model", btf__report_bytes_text(r->model_bytes, x, sizeof x),
                    btf__report_ratio_text(btf__report_ratio(raw->raw, r->model_bytes), y,
                                         sizeof y), note);
    btf__report_row(b, NULL, "the paper's claim", "–",
                    btf__report_ratio_text(BTF_REPORT_PAPER_RATIO, y, sizeof y),
                    "Haindl &amp; Filip 2007: about 1 : 10<sup>5</sup>");
    if (d->pca.views == 0) {
        btf__report_row(b, NULL, "per-view PCA", "–", "–", "not measured: a sparse set holds "
                        "no view under every light");
    } else {
        snprintf(note, sizeof note, "%.1f components per view on average (%d–%d) for an RMS "
                 "error ≤ %.1f 8-bit levels (reached: %.2f), %d-bit values",
                 d->pca.mean_components, d->pca.min_components, d->pca.max_components,
                 r->o->pca.max_rms > 0 ? r->o->pca.max_rms : 2.0, d->pca.rms,
                 r->o->pca.bits > 0 ? r->o->pca.bits : 16);
        btf__report_row(b, NULL, "per-view PCA", btf__report_bytes_text(d->pca.bytes, x, sizeof x),
                        btf__report_ratio_text(d->pca.ratio, y, sizeof y), note);
    }
    snprintf(note, sizeof note, "%d images at quality %d (RMS %.2f levels) + the %llu-byte "
             "index table; no relief, no synthesis at other sizes", d->jpeg.images,
             d->jpeg.quality, d->jpeg.rms, (unsigned long long)d->jpeg.index_bytes);
    btf__report_row(b, NULL, "JPEG of the subspace images",
                    btf__report_bytes_text(d->jpeg.bytes, x, sizeof x),
                    btf__report_ratio_text(d->jpeg.ratio, y, sizeof y), note);
    btf__buf_puts(b, "</table>\n<h3>The model file by part</h3>\n<table>\n<tr><th class=\"l\">"
                    "part</th><th>bytes in the file</th><th>share</th><th>bytes before "
                    "deflate</th></tr>\n");
    const btf_model_bytes *mb = &d->bytes;
    for (int p = 0; p < BTF_MODEL_PART_COUNT; p++) {
        if (!mb->file[p] && !mb->raw[p])
            continue;
        btf__buf_printf(b, "<tr><td class=\"l\">%s</td><td>%llu</td><td>%.1f %%</td><td>%llu"
                          "</td></tr>\n", btf__model_part_name(p),
                       (unsigned long long)mb->file[p],
                       mb->total ? 100.0 * mb->file[p] / mb->total : 0.0,
                       (unsigned long long)mb->raw[p]);
    }
    btf__buf_printf(b, "<tr><th class=\"l\">total</th><th>%llu</th><th>100 %%</th><th>%llu"
                      "</th></tr>\n</table>\n", (unsigned long long)mb->total,
                   (unsigned long long)mb->payload);
}

static void compression_json(cJSON *root, const btf_report_base *r)
{
    const btf_car_report *d = car(r);
    cJSON *c = btf__report_json_compression(root, r);
    cJSON_AddNumberToObject(c, "paper_ratio", BTF_REPORT_PAPER_RATIO);
    cJSON *parts = cJSON_AddObjectToObject(c, "model_parts");
    cJSON *raw = cJSON_AddObjectToObject(c, "model_parts_before_deflate");
    for (int p = 0; p < BTF_MODEL_PART_COUNT; p++) {
        cJSON_AddNumberToObject(parts, btf__model_part_name(p), (double)d->bytes.file[p]);
        cJSON_AddNumberToObject(raw, btf__model_part_name(p), (double)d->bytes.raw[p]);
    }
    cJSON *pca = cJSON_AddObjectToObject(c, "pca");
    if (d->pca.views == 0)
        cJSON_AddStringToObject(pca, "skipped", "a sparse set: no view under every light");
    cJSON_AddNumberToObject(pca, "bytes", (double)d->pca.bytes);
    cJSON_AddNumberToObject(pca, "ratio", d->pca.ratio);
    cJSON_AddNumberToObject(pca, "max_rms", r->o->pca.max_rms > 0 ? r->o->pca.max_rms : 2.0);
    cJSON_AddNumberToObject(pca, "rms", d->pca.rms);
    cJSON_AddNumberToObject(pca, "bits", r->o->pca.bits > 0 ? r->o->pca.bits : 16);
    cJSON_AddNumberToObject(pca, "mean_components", d->pca.mean_components);
    cJSON_AddNumberToObject(pca, "min_components", d->pca.min_components);
    cJSON_AddNumberToObject(pca, "max_components", d->pca.max_components);
    cJSON_AddNumberToObject(pca, "seconds", d->pca.seconds);
    cJSON *jp = cJSON_AddObjectToObject(c, "jpeg");
    cJSON_AddNumberToObject(jp, "quality", d->jpeg.quality);
    cJSON_AddNumberToObject(jp, "images", d->jpeg.images);
    cJSON_AddNumberToObject(jp, "jpeg_bytes", (double)d->jpeg.jpeg_bytes);
    cJSON_AddNumberToObject(jp, "index_bytes", (double)d->jpeg.index_bytes);
    cJSON_AddNumberToObject(jp, "bytes", (double)d->jpeg.bytes);
    cJSON_AddNumberToObject(jp, "ratio", d->jpeg.ratio);
    cJSON_AddNumberToObject(jp, "rms", d->jpeg.rms);
}

const btf_report_section btf__car_compression = {NULL, compression_html, compression_json};

/* ------------------------------------------------------------ quality */

static btf_status quality_files(const btf_report_base *r, const char *dir, btf_error *err)
{
    return btf__report_heatmap(r, dir, "Combined distance per (view, light) pair", "combined",
                               err);
}

static void pair_caption(btf_buf *b, const btf_report_base *r, int i)
{
    const btf_texture_distances *d = r->pairs[i].d;
    btf__buf_printf(b, "spectrum %.2f · first order %.2f · structure %.2f · <b>%.2f</b>",
                    d->spectrum.normalised, d->first_order.normalised, d->structure.normalised,
                    d->combined);
}

static void pair_cells(btf_buf *b, const btf_report_base *r, int i)
{
    const btf_pair_quality *p = &car(r)->q.pairs[i];
    char sub[32];
    if (p->held_out)
        snprintf(sub, sizeof sub, "held out");
    else
        snprintf(sub, sizeof sub, "%d", p->subspace);
    btf__buf_printf(b, "<td>%s</td><td>%.2f</td><td>%.2f</td><td>%.2f</td><td><b>%.2f</b></td>"
                       "<td>%.5f</td>", sub, p->d.spectrum.normalised,
                    p->d.first_order.normalised, p->d.structure.normalised, p->d.combined,
                    p->mean_abs_dy);
}

static void quality_html(btf_buf *b, const btf_report_base *r)
{
    const btf_quality *q = &car(r)->q;
    btf__buf_printf(b, "<h2>Quality per direction</h2>\n<p class=\"note\">Each measured image "
                      "against the model's flat render of the same (view, light) pair, by "
                      "texture distances that need no pixel correspondence (the model is a new "
                      "sample of the material, not a copy): the power spectrum, the first-order "
                      "(colour histogram) and the structure (pyramid band statistics) "
                      "distances, each divided by the same distance between disjoint crops of "
                      "the measured image — 1.0 is as close as the material is to itself — and "
                      "their mean, the combined distance (docs/measure.md). %s: %d pairs, "
                      "measured in " BTF_HTML_TIME("%.1f s") ".</p>\n",
                   r->o->quality.all ? "Every pair" : "A spread of views × lights over every "
                                                      "ring of the hemisphere",
                   q->n_pairs, q->seconds);
    btf__buf_printf(b, "<table>\n<tr><th class=\"l\"></th><th>spectrum</th><th>first order"
                      "</th><th>structure</th><th>combined</th></tr>\n<tr><td class=\"l\">mean"
                      "</td><td>%.2f</td><td>%.2f</td><td>%.2f</td><td><b>%.2f</b></td></tr>\n"
                      "<tr><td class=\"l\">median</td><td></td><td></td><td></td><td>%.2f</td>"
                      "</tr>\n<tr><td class=\"l\">worst</td><td></td><td></td><td></td><td>"
                      "%.2f</td></tr>\n</table>\n",
                   q->mean_spectrum, q->mean_first_order, q->mean_structure, q->mean_combined,
                   q->median_combined, q->worst_combined);
    if (q->n_held_out)
        btf__buf_printf(b, "<p>%d of these pairs were held out of the analysis (the table's "
                          "\"held out\"): the model renders them by interpolating the pairs "
                          "it measured (docs/render.md, \"Sparse pair sets\"); their mean "
                          "combined distance is <b>%.2f</b>, not counted in the mean, median "
                          "and worst above.</p>\n", q->n_held_out, q->mean_held_out);
    btf__report_heatmap_figure(b, "heat map of the combined distance over views and lights",
                               "Rows: views; columns: lights; empty cells were not measured; "
                               "outlined: the worst pairs.");
    char worst[64];
    snprintf(worst, sizeof worst, "The %d worst pairs (measured | model)", r->n_worst);
    btf__report_galleries(b, r, worst, "Pairs with pictures (measured | model)", 0,
                          pair_caption);
    btf__buf_printf(b, "<p>Pixel by pixel: mean |ΔY| <b>%.5f</b> over the pairs the model "
                      "measured (%.1f %% of their mean luminance %.4f)",
                   q->mean_abs_dy, q->mean_luminance > 0 ? 100.0 * q->mean_abs_dy /
                                                               q->mean_luminance : 0.0,
                   q->mean_luminance);
    if (q->n_held_out)
        btf__buf_printf(b, ", %.5f over the %d held out", q->mean_held_out_abs_dy,
                        q->n_held_out);
    btf__buf_printf(b, ". The render has the "
                      "capture's size and a structure layer is registered with it, so "
                      "where the layout is the appearance (an object, a mosaic: "
                      "docs/examples/rti-lion/) this figure sees what the distances above, "
                      "which need no pixel correspondence, do not; for a texture the CAR "
                      "fields are a new sample of it and the distances are the fairer "
                      "figure.</p>\n");
    btf__report_pair_table(b, r, "<th>subspace</th><th>spectrum</th><th>first order</th>"
                                "<th>structure</th><th>combined</th><th>|ΔY|</th>",
                           pair_cells);
}

static void add_component(cJSON *o, const char *key, const btf_distance_component *c)
{
    cJSON *j = cJSON_AddObjectToObject(o, key);
    cJSON_AddNumberToObject(j, "raw", c->raw);
    cJSON_AddNumberToObject(j, "self", c->self);
    cJSON_AddNumberToObject(j, "normalised", c->normalised);
}

static void pair_json(cJSON *j, const btf_report_base *r, int i)
{
    const btf_pair_quality *p = &car(r)->q.pairs[i];
    cJSON_AddNumberToObject(j, "subspace", p->subspace);
    cJSON_AddBoolToObject(j, "held_out", p->held_out);
    cJSON_AddNumberToObject(j, "mean_abs_dy", p->mean_abs_dy);
    add_component(j, "spectrum", &p->d.spectrum);
    add_component(j, "first_order", &p->d.first_order);
    add_component(j, "structure", &p->d.structure);
    cJSON_AddNumberToObject(j, "combined", p->d.combined);
}

static void quality_json(cJSON *root, const btf_report_base *r)
{
    const btf_quality *q = &car(r)->q;
    const btf_quality_opts *qo = &r->o->quality;
    cJSON *o = btf__report_json_quality(root, r, q->mean_combined);
    cJSON_AddNumberToObject(o, "held_out", q->n_held_out);
    cJSON_AddNumberToObject(o, "mean_held_out", q->mean_held_out);
    cJSON_AddNumberToObject(o, "mean_abs_dy", q->mean_abs_dy);
    cJSON_AddNumberToObject(o, "mean_held_out_abs_dy", q->mean_held_out_abs_dy);
    cJSON_AddNumberToObject(o, "mean_luminance", q->mean_luminance);
    cJSON_AddNumberToObject(o, "median_combined", q->median_combined);
    cJSON_AddNumberToObject(o, "worst_combined", q->worst_combined);
    cJSON_AddNumberToObject(o, "mean_spectrum", q->mean_spectrum);
    cJSON_AddNumberToObject(o, "mean_first_order", q->mean_first_order);
    cJSON_AddNumberToObject(o, "mean_structure", q->mean_structure);
    cJSON_AddNumberToObject(o, "texture_size", q->texture_size);
    cJSON_AddNumberToObject(o, "relief", qo->relief < 0 ? 1.0 : qo->relief);
    cJSON_AddNumberToObject(o, "seed", (double)qo->seed);
    cJSON_AddNumberToObject(o, "seconds", q->seconds);
    btf__report_json_pairs(o, r, pair_json, 1);
}

const btf_report_section btf__car_quality = {quality_files, quality_html, quality_json};

/* ------------------------------------------------------------ the preview */

static void preview_json(cJSON *root, const btf_report_base *r)
{
    cJSON *pv = btf__report_json_preview(root, r);
    cJSON_AddNumberToObject(pv, "subspaces_needed", car(r)->sphere_info.needed);
}

const btf_report_section btf__car_preview = {NULL, NULL, preview_json};
