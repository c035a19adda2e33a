/*
 * svg_heatmap.c — a heat map as a standalone SVG file: a rows x cols grid
 * of values (the report's error per (view, light) pair: 81 x 81 for a
 * UBO2003 dataset), coloured by btf__colour_scale, unmeasured cells hatched
 * grey, a colour bar with its range and label, axis titles, row and column
 * labels thinned out to one per ~13 px, and red outlines on listed cells
 * (the worst pairs).
 *
 * Layout, left to right: y title (rotated), row labels, the grid, the
 * colour bar with its numbers, the legend; column labels run upwards under
 * the grid, the x title under them. Runs of equal colour in a row are one
 * <rect> (a smooth map of 81 x 81 stays a few hundred kB at most).
 */
#include "report/report.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define TICK_FONT 11.0
#define TITLE_FONT 13.0
#define HEAD_FONT 15.0
#define LABEL_GAP 13.0 /* px between two tick labels */
#define PAD 10.0
#define BAR_W 14.0
#define MARK_COLOUR "#ff1a1a"

static int cell_value(const btf_heatmap *h, int r, int c, double *v)
{
    *v = h->values[(size_t)r * (size_t)h->cols + (size_t)c];
    return isfinite(*v);
}

/* The colour of a value on the map's scale. */
static void value_colour(double v, double lo, double hi, int reverse, unsigned char rgb[3])
{
    double t = hi > lo ? (v - lo) / (hi - lo) : 0.5;
    if (reverse)
        t = 1 - t;
    btf__colour_scale(t, rgb);
}

static double max_label_width(const char *const *labels, int n, int step, double size)
{
    double w = 0;
    for (int i = 0; labels && i < n; i += step) {
        double t = btf__svg_text_width(labels[i], size);
        w = t > w ? t : w;
    }
    return w;
}

btf_status btf__svg_heatmap(const btf_heatmap *h, btf_buf *out, btf_error *err)
{
    if (!h || !out)
        return btf__fail(err, BTF_E_ARG, "heat map: no map or no output buffer");
    if (h->rows < 1 || h->cols < 1 || h->rows > 4096 || h->cols > 4096)
        return btf__fail(err, BTF_E_ARG, "heat map: %d x %d cells (expected 1..4096 each)",
                         h->rows, h->cols);
    if (!h->values)
        return btf__fail(err, BTF_E_ARG, "heat map: no values");
    if (h->n_marked < 0 || (h->n_marked > 0 && !h->marked))
        return btf__fail(err, BTF_E_ARG, "heat map: %d marked cells without a list", h->n_marked);
    for (int i = 0; i < h->n_marked; i++)
        if (h->marked[i].row < 0 || h->marked[i].row >= h->rows || h->marked[i].col < 0 ||
            h->marked[i].col >= h->cols)
            return btf__fail(err, BTF_E_ARG,
                             "heat map: marked cell %d (row %d, column %d) is outside the %d x %d grid",
                             i, h->marked[i].row, h->marked[i].col, h->rows, h->cols);
    if (h->cell_px < 0 || h->cell_px > 200)
        return btf__fail(err, BTF_E_ARG, "heat map: cell size %d px (expected 0..200)", h->cell_px);

    /* The colour range: given, or the finite values'. */
    double lo = INFINITY, hi = -INFINITY, v;
    int any_nan = 0;
    for (int r = 0; r < h->rows; r++)
        for (int c = 0; c < h->cols; c++) {
            if (!cell_value(h, r, c, &v)) {
                any_nan = 1;
                continue;
            }
            lo = v < lo ? v : lo;
            hi = v > hi ? v : hi;
        }
    int have_data = lo <= hi;
    if (isfinite(h->vmin) && isfinite(h->vmax) && h->vmin < h->vmax)
        lo = h->vmin, hi = h->vmax;
    if (!have_data)
        lo = 0, hi = 1;

    int big = h->rows > h->cols ? h->rows : h->cols;
    double cell = h->cell_px ? h->cell_px : floor(640.0 / big);
    if (!h->cell_px)
        cell = cell < 4 ? 4 : cell > 40 ? 40 : cell;
    int rstep = (int)ceil(LABEL_GAP / cell), cstep = rstep;
    double gw = cell * h->cols, gh = cell * h->rows;

    double row_w = max_label_width(h->row_labels, h->rows, rstep, TICK_FONT);
    double col_h = max_label_width(h->col_labels, h->cols, cstep, TICK_FONT);
    double gx = PAD + (h->y_title ? TITLE_FONT + 8 : 0) + (row_w > 0 ? row_w + 8 : 0);
    double gy = PAD + (h->title ? HEAD_FONT + 12 : 0) + TICK_FONT; /* room for the bar's top label */
    double below = (col_h > 0 ? col_h + 8 : 0) + (h->x_title ? TITLE_FONT + 10 : 0);

    /* The colour bar and the legend beside the grid. */
    char lo_s[32], hi_s[32], mid_s[32];
    btf__svg_label(lo_s, lo);
    btf__svg_label(hi_s, hi);
    btf__svg_label(mid_s, 0.5 * (lo + hi));
    double bar_x = gx + gw + 24;
    double bar_h = gh < 120 ? 120 : gh > 320 ? 320 : gh;
    double bar_y = gy;
    double nums_w = 0;
    const char *nums[3] = {lo_s, mid_s, hi_s};
    for (int i = 0; i < 3; i++) {
        double t = btf__svg_text_width(nums[i], TICK_FONT);
        nums_w = t > nums_w ? t : nums_w;
    }
    if (!have_data)
        nums_w = btf__svg_text_width("no measured values", TICK_FONT);
    double legend_y = bar_y + bar_h + 22;
    double legend_w = 0, legend_h = 0;
    const char *nan_text = "not measured";
    if (any_nan) {
        double t = 18 + btf__svg_text_width(nan_text, TICK_FONT);
        legend_w = t > legend_w ? t : legend_w;
        legend_h += 18;
    }
    if (h->n_marked > 0 && h->marked_label) {
        double t = 18 + btf__svg_text_width(h->marked_label, TICK_FONT);
        legend_w = t > legend_w ? t : legend_w;
        legend_h += 18;
    }
    double label_w = h->legend_label ? btf__svg_text_width(h->legend_label, TITLE_FONT) : 0;
    double right = bar_x + BAR_W + 6 + nums_w;
    if (bar_x + label_w > right)
        right = bar_x + label_w;
    if (bar_x + legend_w > right)
        right = bar_x + legend_w;
    double width = right + PAD;
    double title_w = h->title ? PAD + btf__svg_text_width(h->title, HEAD_FONT) + PAD : 0;
    width = title_w > width ? title_w : width;
    double height = gy + gh + below + PAD;
    double lbottom = legend_y + legend_h + PAD;
    height = lbottom > height ? lbottom : height;

    char a[32], b[32], c2[32], d[32];
    btf__svg_begin(out, ceil(width), ceil(height));
    /* The hatching of unmeasured cells, and the bar's gradient (bottom to
     * top: low to high values). Internal references only. */
    btf__buf_puts(out, "<defs>\n<pattern id=\"btf-hatch\" width=\"6\" height=\"6\" "
                      "patternUnits=\"userSpaceOnUse\" patternTransform=\"rotate(45)\">"
                      "<rect width=\"6\" height=\"6\" fill=\"#e4e4e4\"/>"
                      "<line x1=\"0\" y1=\"0\" x2=\"0\" y2=\"6\" stroke=\"#a8a8a8\" "
                      "stroke-width=\"2\"/></pattern>\n"
                      "<linearGradient id=\"btf-scale\" x1=\"0\" y1=\"1\" x2=\"0\" y2=\"0\">\n");
    for (int i = 0; i <= 16; i++) {
        unsigned char rgb[3];
        btf__colour_scale(h->reverse ? 1 - i / 16.0 : i / 16.0, rgb);
        btf__buf_printf(out, "<stop offset=\"%s\" stop-color=\"#%02x%02x%02x\"/>\n",
                        btf__svg_num(a, i / 16.0), rgb[0], rgb[1], rgb[2]);
    }
    btf__buf_puts(out, "</linearGradient>\n</defs>\n");

    if (h->title)
        btf__svg_text(out, PAD, PAD + HEAD_FONT, HEAD_FONT, "start", 0, "font-weight=\"bold\"",
                      h->title);

    /* The grid: hatching under everything, then the measured cells. */
    btf__buf_printf(out, "<rect x=\"%s\" y=\"%s\" width=\"%s\" height=\"%s\" fill=\"url(#btf-hatch)\"/>\n",
                    btf__svg_num(a, gx), btf__svg_num(b, gy), btf__svg_num(c2, gw), btf__svg_num(d, gh));
    btf__buf_puts(out, "<g shape-rendering=\"crispEdges\">\n");
    for (int r = 0; r < h->rows; r++) {
        int c = 0;
        while (c < h->cols) {
            if (!cell_value(h, r, c, &v)) {
                c++;
                continue;
            }
            unsigned char rgb[3], next[3];
            value_colour(v, lo, hi, h->reverse, rgb);
            int end = c + 1;
            double w;
            while (!h->tooltips && end < h->cols && cell_value(h, r, end, &w)) {
                value_colour(w, lo, hi, h->reverse, next);
                if (memcmp(rgb, next, 3))
                    break;
                end++;
            }
            btf__buf_printf(out, "<rect x=\"%s\" y=\"%s\" width=\"%s\" height=\"%s\" fill=\"#%02x%02x%02x\"",
                            btf__svg_num(a, gx + c * cell), btf__svg_num(b, gy + r * cell),
                            btf__svg_num(c2, (end - c) * cell), btf__svg_num(d, cell), rgb[0], rgb[1],
                            rgb[2]);
            if (h->tooltips) {
                char vs[32];
                btf__buf_puts(out, "><title>");
                if (h->row_labels && h->row_labels[r])
                    btf__buf_html(out, h->row_labels[r]);
                else
                    btf__buf_printf(out, "row %d", r);
                btf__buf_puts(out, ", ");
                if (h->col_labels && h->col_labels[c])
                    btf__buf_html(out, h->col_labels[c]);
                else
                    btf__buf_printf(out, "column %d", c);
                btf__buf_printf(out, ": %s</title></rect>\n", btf__svg_label(vs, v));
            } else {
                btf__buf_puts(out, "/>\n");
            }
            c = end;
        }
    }
    btf__buf_puts(out, "</g>\n");
    btf__buf_printf(out, "<rect x=\"%s\" y=\"%s\" width=\"%s\" height=\"%s\" fill=\"none\" "
                        "stroke=\"#555555\" stroke-width=\"1\"/>\n",
                   btf__svg_num(a, gx - 0.5), btf__svg_num(b, gy - 0.5), btf__svg_num(c2, gw + 1),
                   btf__svg_num(d, gh + 1));

    /* Outlines of the listed cells. */
    if (h->n_marked > 0) {
        btf__buf_printf(out, "<g fill=\"none\" stroke=\"%s\" stroke-width=\"2\">\n", MARK_COLOUR);
        for (int i = 0; i < h->n_marked; i++) {
            double inset = cell >= 6 ? 1 : 0;
            btf__buf_printf(out, "<rect x=\"%s\" y=\"%s\" width=\"%s\" height=\"%s\"/>\n",
                            btf__svg_num(a, gx + h->marked[i].col * cell + inset),
                            btf__svg_num(b, gy + h->marked[i].row * cell + inset),
                            btf__svg_num(c2, cell - 2 * inset), btf__svg_num(d, cell - 2 * inset));
        }
        btf__buf_puts(out, "</g>\n");
    }

    /* Row labels (right-aligned before the grid), column labels (upwards
     * under it), each with a short tick. */
    if (h->row_labels) {
        for (int r = 0; r < h->rows; r += rstep) {
            double y = gy + (r + 0.5) * cell;
            btf__buf_printf(out, "<line x1=\"%s\" y1=\"%s\" x2=\"%s\" y2=\"%s\" stroke=\"#555555\"/>\n",
                            btf__svg_num(a, gx - 4), btf__svg_num(b, y), btf__svg_num(c2, gx - 1),
                            btf__svg_num(d, y));
            if (h->row_labels[r])
                btf__svg_text(out, gx - 6, y + TICK_FONT * 0.35, TICK_FONT, "end", 0, NULL,
                              h->row_labels[r]);
        }
    }
    if (h->col_labels) {
        for (int c = 0; c < h->cols; c += cstep) {
            double x = gx + (c + 0.5) * cell;
            btf__buf_printf(out, "<line x1=\"%s\" y1=\"%s\" x2=\"%s\" y2=\"%s\" stroke=\"#555555\"/>\n",
                            btf__svg_num(a, x), btf__svg_num(b, gy + gh + 1), btf__svg_num(c2, x),
                            btf__svg_num(d, gy + gh + 4));
            if (h->col_labels[c])
                btf__svg_text(out, x + TICK_FONT * 0.35, gy + gh + 6, TICK_FONT, "end", -90, NULL,
                              h->col_labels[c]);
        }
    }
    if (h->y_title)
        btf__svg_text(out, PAD + TITLE_FONT, gy + gh / 2, TITLE_FONT, "middle", -90, NULL, h->y_title);
    if (h->x_title)
        btf__svg_text(out, gx + gw / 2, gy + gh + (col_h > 0 ? col_h + 8 : 0) + TITLE_FONT + 4,
                      TITLE_FONT, "middle", 0, NULL, h->x_title);

    /* The colour bar: its label above, max at the top, min at the bottom. */
    if (h->legend_label)
        btf__svg_text(out, bar_x, bar_y - 4, TITLE_FONT, "start", 0, NULL, h->legend_label);
    btf__buf_printf(out, "<rect x=\"%s\" y=\"%s\" width=\"%s\" height=\"%s\" fill=\"%s\" "
                        "stroke=\"#555555\" stroke-width=\"1\"/>\n",
                   btf__svg_num(a, bar_x), btf__svg_num(b, bar_y), btf__svg_num(c2, BAR_W),
                   btf__svg_num(d, bar_h), have_data ? "url(#btf-scale)" : "url(#btf-hatch)");
    if (have_data) {
        btf__svg_text(out, bar_x + BAR_W + 6, bar_y + TICK_FONT * 0.8, TICK_FONT, "start", 0, NULL, hi_s);
        btf__svg_text(out, bar_x + BAR_W + 6, bar_y + bar_h / 2 + TICK_FONT * 0.35, TICK_FONT, "start",
                      0, NULL, mid_s);
        btf__svg_text(out, bar_x + BAR_W + 6, bar_y + bar_h, TICK_FONT, "start", 0, NULL, lo_s);
    } else {
        btf__svg_text(out, bar_x + BAR_W + 6, bar_y + bar_h / 2, TICK_FONT, "start", 0, NULL,
                      "no measured values");
    }

    /* The legend under the bar. */
    double ly = legend_y;
    if (any_nan) {
        btf__buf_printf(out, "<rect x=\"%s\" y=\"%s\" width=\"12\" height=\"12\" fill=\"url(#btf-hatch)\" "
                            "stroke=\"#555555\"/>\n",
                       btf__svg_num(a, bar_x), btf__svg_num(b, ly - 10));
        btf__svg_text(out, bar_x + 18, ly, TICK_FONT, "start", 0, NULL, nan_text);
        ly += 18;
    }
    if (h->n_marked > 0 && h->marked_label) {
        btf__buf_printf(out, "<rect x=\"%s\" y=\"%s\" width=\"12\" height=\"12\" fill=\"none\" "
                            "stroke=\"%s\" stroke-width=\"2\"/>\n",
                       btf__svg_num(a, bar_x), btf__svg_num(b, ly - 10), MARK_COLOUR);
        btf__svg_text(out, bar_x + 18, ly, TICK_FONT, "start", 0, NULL, h->marked_label);
    }
    btf__svg_end(out);
    return btf__buf_check(out, "heat map", err);
}

btf_status btf__svg_heatmap_write(const char *path, const btf_heatmap *h, btf_error *err)
{
    btf_buf b = {0};
    return btf__svg_save(path, &b, btf__svg_heatmap(h, &b, err), err);
}
