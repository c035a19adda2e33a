/*
 * rf_report_page.c — the reflectance-field report's own sections
 * (docs/report.md, "Reflectance-field models"), each its part of the page
 * and its keys of report.json: the model under the title, the top's cards,
 * the file against the raw BTF (a sampled model's coefficients and map),
 * and, since this family keeps every texel, the pixel-wise luminance error
 * per pair and over every image beside the texture distances. The shared
 * pieces they call are in report_page.c and report_json.c.
 */
#include "core/core.h"
#include "report/rf_report_data.h"

#include <stdio.h>
#include <string.h>

/* A section's data: the base is the first member of the family's data. */
static const btf_rf_report *rf(const btf_report_base *r)
{
    return (const btf_rf_report *)r;
}

static double percent(double a, double b)
{
    return b > 0.0 ? 100.0 * a / b : 0.0;
}

static double bytes_per_texel(const btf_report_base *r)
{
    return (double)r->model_bytes / ((double)r->in->width * r->in->height);
}

/* ------------------------------------------------------------ about */

static void about_html(btf_buf *b, const btf_report_base *r)
{
    const btf_rf_model *m = rf(r)->m;
    btf__buf_puts(b, "reflectance-field model ");
    btf__buf_html(b, r->model_name);
    btf__buf_printf(b, " (%s", btf_rf_fit_name(m->fit));
    if (m->fit != BTF_RF_PTM)
        btf__buf_printf(b, ", %d lobe%s", m->lobes, m->lobes == 1 ? "" : "s");
    btf__buf_printf(b, "; Meseth, Müller &amp; Klein 2003) · %d views × %d lights of %d×%d "
                      "pixels · " BTF_HTML_TIME("%s") " · " BTF_HTML_TIME("%.1f s"),
                   r->in->n_views, r->in->n_lights, r->in->width, r->in->height, r->date,
                   r->seconds);
}

static void about_json(cJSON *root, const btf_report_base *r)
{
    const btf_rf_model *m = rf(r)->m;
    cJSON *o = cJSON_AddObjectToObject(root, "rf");
    cJSON_AddStringToObject(o, "fit", btf_rf_fit_name(m->fit));
    cJSON_AddNumberToObject(o, "lobes", m->lobes);
    cJSON_AddNumberToObject(o, "fields", m->fields);
    cJSON_AddNumberToObject(o, "slots", m->slots);
    if (m->map) {
        cJSON *s = cJSON_AddObjectToObject(o, "sample");
        cJSON_AddNumberToObject(s, "x", m->sample_x);
        cJSON_AddNumberToObject(s, "y", m->sample_y);
        cJSON_AddNumberToObject(s, "width", m->width);
        cJSON_AddNumberToObject(s, "height", m->height);
        cJSON_AddNumberToObject(s, "surface_width", m->surface_width);
        cJSON_AddNumberToObject(s, "surface_height", m->surface_height);
    }
}

const btf_report_section btf__rf_about = {NULL, about_html, about_json};

/* ------------------------------------------------------------ the top */

static void top_html(btf_buf *b, const btf_report_base *r)
{
    const btf_rf_report *d = rf(r);
    btf__report_top_begin(b, r, NULL);
    btf__buf_printf(b, BTF_HTML_CARD("%.5f", "mean |ΔY| over every image%s (%.1f %% of the "
                                            "mean luminance %.4f)"),
                   d->mean_abs_error, d->n_held_out ? " the model was fitted to" : "",
                   percent(d->mean_abs_error, d->mean_luminance), d->mean_luminance);
    btf__buf_printf(b, BTF_HTML_CARD("%.2f", "mean combined distance over %d pairs (1.0: as "
                                            "close as the material is to itself)"),
                   d->mean_combined, r->n_pairs - d->n_held_out);
    if (d->n_held_out)
        btf__buf_printf(b, BTF_HTML_CARD("%.2f", "mean combined distance over %d pair%s held "
                                                "out of the fit (rendered at their exact "
                                                "directions; mean |ΔY| %.5f)"),
                       d->mean_held_out, d->n_held_out, d->n_held_out == 1 ? "" : "s",
                       d->mean_held_out_dy);
    btf__report_top_end(b);
}

const btf_report_section btf__rf_top = {NULL, top_html, NULL};

/* ------------------------------------------------------------ compression */

/* A sampled model's memory (section 6): the sample's coefficients and the
 * coordinate map, in memory and in the file. */
static void sample_rows(btf_buf *b, const btf_rf_report *d)
{
    const btf_rf_model *m = d->m;
    const btf_rf_bytes *y = &d->bytes;
    char what[160], t[64], u[64], q[64];
    snprintf(what, sizeof what, "of which the %d×%d sample's coefficients (in memory: %s)",
             m->width, m->height, btf__report_bytes_text(y->coefficients, u, sizeof u));
    btf__report_row(b, NULL, what, btf__report_bytes_text(y->file - y->file_map, t, sizeof t),
                    btf__report_ratio_text(btf__report_ratio(d->r.raw.raw, y->file - y->file_map),
                                         q, sizeof q), NULL);
    snprintf(what, sizeof what, "and the %d×%d coordinate map (in memory: %s, 4 bytes per "
             "texel)", m->surface_width, m->surface_height,
             btf__report_bytes_text(y->map, u, sizeof u));
    btf__report_row(b, NULL, what, btf__report_bytes_text(y->file_map, t, sizeof t), "–", NULL);
}

static void compression_html(btf_buf *b, const btf_report_base *r)
{
    const btf_dataset_info *in = r->in;
    const btf_rf_model *m = rf(r)->m;
    char what[160], t[64], q[64], bq[80];
    btf__buf_puts(b, "<h2>Compression</h2>\n<table>\n<tr><th class=\"l\">what</th><th>bytes"
                    "</th><th>against raw</th></tr>\n");
    snprintf(what, sizeof what, "raw BTF (%d × %d × %d × %d × 3 bytes)", in->n_views,
             in->n_lights, in->width, in->height);
    btf__report_row(b, NULL, what, btf__report_bytes_text(r->raw.raw, t, sizeof t), "1 : 1", NULL);
    btf__report_row(b, NULL, "the dataset as stored",
                    btf__report_bytes_text(r->raw.on_disk, t, sizeof t),
                    btf__report_ratio_text(btf__report_ratio(r->raw.raw, r->raw.on_disk), q,
                                         sizeof q), NULL);
    snprintf(what, sizeof what, "reflectance-field model file (%d fields × %d slots × 16 bits "
             "per texel, deflated)", m->fields, m->slots);
    snprintf(bq, sizeof bq, "<b>%s</b>",
             btf__report_ratio_text(btf__report_ratio(r->raw.raw, r->model_bytes), q, sizeof q));
    btf__report_row(b, NULL, what, btf__report_bytes_text(r->model_bytes, t, sizeof t), bq, NULL);
    if (m->map)
        sample_rows(b, rf(r));
    btf__buf_puts(b, "</table>\n");
    if (m->map)
        btf__buf_printf(b, "<p class=\"note\">%.1f bytes of the file per texel. Memory "
                          "reduction (paper section 6, docs/rf.md): the fields are fitted on a "
                          "%d×%d sample at (%d, %d) only, and a %d×%d map of texture "
                          "coordinates from an image quilting of the sample says which sample "
                          "texel each texel of the surface shows. The data's pixel "
                          "correspondence holds on the sample's own place only; elsewhere the "
                          "pixel-wise error measures a new arrangement of the material, and "
                          "the texture distances are the fairer figure.</p>\n",
                       bytes_per_texel(r), m->width, m->height, m->sample_x, m->sample_y,
                       m->surface_width, m->surface_height);
    else
        btf__buf_printf(b, "<p class=\"note\">%.1f bytes of the file per texel. The model "
                          "keeps every texel (docs/rf.md), so it is judged pixel by pixel as "
                          "well as by the texture distances.</p>\n",
                       bytes_per_texel(r));
}

static void compression_json(cJSON *root, const btf_report_base *r)
{
    const btf_rf_bytes *y = &rf(r)->bytes;
    cJSON *c = btf__report_json_compression(root, r);
    cJSON_AddNumberToObject(c, "bytes_per_texel", bytes_per_texel(r));
    cJSON_AddNumberToObject(c, "coefficient_bytes", (double)y->coefficients);
    cJSON_AddNumberToObject(c, "map_bytes", (double)y->map);
    cJSON_AddNumberToObject(c, "file_map_bytes", (double)y->file_map);
}

const btf_report_section btf__rf_compression = {NULL, compression_html, compression_json};

/* ------------------------------------------------------------ pixel-wise error */

static void pixelwise_json(cJSON *root, const btf_report_base *r)
{
    const btf_rf_report *d = rf(r);
    cJSON *pw = cJSON_AddObjectToObject(root, "pixelwise");
    cJSON_AddNumberToObject(pw, "mean_abs_dy", d->mean_abs_error);
    cJSON_AddNumberToObject(pw, "mean_luminance", d->mean_luminance);
    cJSON_AddNumberToObject(pw, "mean_pair_abs_dy", d->mean_pair_dy);
    cJSON_AddNumberToObject(pw, "worst_pair_abs_dy", d->worst_pair_dy);
}

const btf_report_section btf__rf_pixelwise = {NULL, NULL, pixelwise_json};

/* ------------------------------------------------------------ quality */

static btf_status quality_files(const btf_report_base *r, const char *dir, btf_error *err)
{
    return btf__report_heatmap(r, dir, "Pixel-wise mean |ΔY| per (view, light) pair", "|ΔY|",
                               err);
}

static void pair_caption(btf_buf *b, const btf_report_base *r, int i)
{
    const btf_rf_pair *p = &rf(r)->pairs[i];
    btf__buf_printf(b, "|ΔY| %.5f · combined %.2f", p->mean_abs_dy, p->d.combined);
}

static void pair_cells(btf_buf *b, const btf_report_base *r, int i)
{
    const btf_rf_pair *p = &rf(r)->pairs[i];
    btf__buf_printf(b, "<td>%s</td><td><b>%.5f</b></td><td>%.2f</td><td>%.2f</td><td>%.2f</td>"
                       "<td>%.2f</td>", p->held_out ? "held out" : "fitted", p->mean_abs_dy, p->d.spectrum.normalised, p->d.first_order.normalised,
                    p->d.structure.normalised, p->d.combined);
}

static void quality_html(btf_buf *b, const btf_report_base *r)
{
    const btf_rf_report *d = rf(r);
    btf__buf_printf(b, "<h2>Quality per direction</h2>\n<p class=\"note\">%d (view, light) "
                      "pairs: each measured image against the model's flat render of that "
                      "pair (at a measured pair the fitted field itself). Pixel-wise: mean "
                      "|ΔY| %.5f over the pairs, worst %.5f; over every image the model was "
                      "fitted to %.5f. Texture distances (normalised): spectrum %.2f · first order "
                      "%.2f · structure %.2f · combined %.2f, worst %.2f.</p>\n",
                   r->n_pairs, d->mean_pair_dy, d->worst_pair_dy, d->mean_abs_error,
                   d->mean_spectrum, d->mean_first_order, d->mean_structure, d->mean_combined,
                   d->worst_combined);
    if (d->n_held_out)
        btf__buf_printf(b, "<p>%d of these pairs have a view or light held out of the fit (the "
                          "table's \"held out\"): the model renders them at their exact "
                          "directions (the fit is a function of the light; between views it "
                          "blends the closest fitted ones, docs/rf.md); their mean |ΔY| is "
                          "<b>%.5f</b> and mean combined distance <b>%.2f</b>, not counted in the "
                          "figures above, which are over the fitted pairs and images.</p>\n",
                       d->n_held_out, d->mean_held_out_dy, d->mean_held_out);
    btf__report_heatmap_figure(b, "pixel-wise error per pair", NULL);
    /* every picture larger when small: the pixel-wise error is what to look at */
    btf__report_galleries(b, r, "The worst pairs (by |ΔY|)", "The pictured pairs", 1,
                          pair_caption);
    btf__report_pair_table(b, r, "<th></th><th>|ΔY|</th><th>spectrum</th><th>first order</th>"
                                "<th>structure</th><th>combined</th>", pair_cells);
}

static void pair_json(cJSON *o, const btf_report_base *r, int i)
{
    const btf_rf_pair *p = &rf(r)->pairs[i];
    cJSON_AddBoolToObject(o, "held_out", p->held_out);
    cJSON_AddNumberToObject(o, "mean_abs_dy", p->mean_abs_dy);
    cJSON_AddNumberToObject(o, "spectrum", p->d.spectrum.normalised);
    cJSON_AddNumberToObject(o, "first_order", p->d.first_order.normalised);
    cJSON_AddNumberToObject(o, "structure", p->d.structure.normalised);
    cJSON_AddNumberToObject(o, "combined", p->d.combined);
}

static void quality_json(cJSON *root, const btf_report_base *r)
{
    const btf_rf_report *d = rf(r);
    cJSON *q = btf__report_json_quality(root, r, d->mean_combined);
    cJSON_AddNumberToObject(q, "held_out", d->n_held_out);
    cJSON_AddNumberToObject(q, "mean_held_out", d->mean_held_out);
    cJSON_AddNumberToObject(q, "mean_held_out_abs_dy", d->mean_held_out_dy);
    cJSON_AddNumberToObject(q, "worst_combined", d->worst_combined);
    cJSON_AddNumberToObject(q, "mean_spectrum", d->mean_spectrum);
    cJSON_AddNumberToObject(q, "mean_first_order", d->mean_first_order);
    cJSON_AddNumberToObject(q, "mean_structure", d->mean_structure);
    btf__report_json_pairs(q, r, pair_json, 0);
}

const btf_report_section btf__rf_quality = {quality_files, quality_html, quality_json};

/* ------------------------------------------------------------ the preview */

static void preview_json(cJSON *root, const btf_report_base *r)
{
    btf__report_json_preview(root, r);
}

const btf_report_section btf__rf_preview = {NULL, NULL, preview_json};
