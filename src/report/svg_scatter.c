/*
 * svg_scatter.c — a scatter plot as a standalone SVG file: the settings of
 * a speed/accuracy sweep as points (x, y), an optional log10 x axis, nice
 * 1-2-5 ticks, the Pareto-optimal points (btf__pareto_front) highlighted and
 * joined by a step line along the edge of the region they dominate, with
 * their labels; one marked point (the default setting) drawn as a diamond
 * with a legend entry. Points that cannot be drawn (a NaN or infinite
 * coordinate, x <= 0 on a log axis) are counted in a note, never written:
 * the file holds no "nan" whatever the input.
 */
#include "report/report.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TICK_FONT 11.0
#define TITLE_FONT 13.0
#define HEAD_FONT 15.0
#define PAD 10.0
#define POINT_COLOUR "#8c8c8c"
#define FRONT_COLOUR "#1f5fa8"
#define MARK_COLOUR "#e0561b"

typedef struct box {
    double x0, y0, x1, y1;
} box;

static int overlaps(const box *a, const box *b)
{
    return a->x0 < b->x1 && b->x0 < a->x1 && a->y0 < b->y1 && b->y0 < a->y1;
}

/* Places a label near (px, py): the first of four spots (right-above,
 * right-below, left-above, left-below) inside the plot that hits no label
 * placed before; else the first inside the plot. */
static void place_label(btf_buf *out, double px, double py, const char *text, const box *plot,
                        box *placed, int *nplaced, int cap, const char *extra)
{
    double w = btf__svg_text_width(text, TICK_FONT), hgt = TICK_FONT;
    static const double dx[4] = {7, 7, -7, -7}, dy[4] = {-6, 6 + TICK_FONT, -6, 6 + TICK_FONT};
    int choice = -1, inside = -1;
    for (int k = 0; k < 4 && choice < 0; k++) {
        box b;
        b.x0 = dx[k] > 0 ? px + dx[k] : px + dx[k] - w;
        b.x1 = b.x0 + w;
        b.y1 = py + dy[k] + 2;
        b.y0 = b.y1 - hgt - 2;
        int in = b.x0 >= plot->x0 && b.x1 <= plot->x1 && b.y0 >= plot->y0 && b.y1 <= plot->y1;
        if (!in)
            continue;
        if (inside < 0)
            inside = k;
        int hit = 0;
        for (int i = 0; i < *nplaced && !hit; i++)
            hit = overlaps(&b, &placed[i]);
        if (!hit)
            choice = k;
    }
    int k = choice >= 0 ? choice : inside >= 0 ? inside : 0;
    double x = px + dx[k], y = py + dy[k];
    if (*nplaced < cap) {
        box b = {dx[k] > 0 ? x : x - w, y - hgt, dx[k] > 0 ? x + w : x, y + 2};
        placed[(*nplaced)++] = b;
    }
    btf__svg_text(out, x, y, TICK_FONT, dx[k] > 0 ? "start" : "end", 0, extra, text);
}

static void diamond(btf_buf *out, double x, double y, double r)
{
    char a[32], b[32], c[32], d[32], e[32], f[32], g[32];
    btf__buf_printf(out, "<path d=\"M%s %sL%s %sL%s %sL%s %sZ\" fill=\"%s\" stroke=\"#222222\" "
                        "stroke-width=\"1\"/>\n",
                   btf__svg_num(a, x), btf__svg_num(b, y - r), btf__svg_num(c, x + r), btf__svg_num(d, y),
                   btf__svg_num(e, x), btf__svg_num(f, y + r), btf__svg_num(g, x - r), d, MARK_COLOUR);
}

btf_status btf__svg_scatter(const btf_scatter *s, btf_buf *out, btf_error *err)
{
    if (!s || !out)
        return btf__fail(err, BTF_E_ARG, "scatter plot: no plot or no output buffer");
    if (s->n < 0 || s->n > 100000)
        return btf__fail(err, BTF_E_ARG, "scatter plot: %d points (expected 0..100000)", s->n);
    if (s->n > 0 && (!s->x || !s->y))
        return btf__fail(err, BTF_E_ARG, "scatter plot: %d points without x or y values", s->n);
    if (s->marked_label && (s->marked < 0 || s->marked >= s->n))
        return btf__fail(err, BTF_E_ARG, "scatter plot: marked point %d of %d points", s->marked, s->n);
    if (s->width < 0 || s->height < 0 || s->width > 8192 || s->height > 8192 ||
        (s->width && s->width < 240) || (s->height && s->height < 180))
        return btf__fail(err, BTF_E_ARG, "scatter plot: size %d x %d px (expected 240..8192 x 180..8192)",
                         s->width, s->height);

    int n = s->n;
    int *ok = NULL, *front = NULL, *is_front = NULL;
    double *vx = NULL, *vy = NULL;
    box *placed = NULL;
    if (n > 0) {
        ok = btf__alloc((size_t)n, sizeof *ok, err);
        front = btf__alloc((size_t)n, sizeof *front, err);
        is_front = btf__calloc((size_t)n, sizeof *is_front, err);
        vx = btf__alloc((size_t)n, sizeof *vx, err);
        vy = btf__alloc((size_t)n, sizeof *vy, err);
        placed = btf__alloc(2 * (size_t)n + 1, sizeof *placed, err);
        if (!ok || !front || !is_front || !vx || !vy || !placed) {
            free(ok), free(front), free(is_front), free(vx), free(vy), free(placed);
            return BTF_E_NOMEM;
        }
    }
    /* The drawable points, and their range. */
    int nv = 0;
    double xlo = INFINITY, xhi = -INFINITY, ylo = INFINITY, yhi = -INFINITY;
    for (int i = 0; i < n; i++) {
        double x = s->x[i], y = s->y[i];
        if (!isfinite(x) || !isfinite(y) || (s->log_x && x <= 0))
            continue;
        ok[nv] = i, vx[nv] = x, vy[nv] = y, nv++;
        xlo = x < xlo ? x : xlo, xhi = x > xhi ? x : xhi;
        ylo = y < ylo ? y : ylo, yhi = y > yhi ? y : yhi;
    }
    int nfront = 0;
    if (!s->no_pareto && nv > 0) {
        nfront = btf__pareto_front(vx, vy, nv, s->x_higher_better, s->y_higher_better, front);
        for (int k = 0; k < nfront; k++) {
            front[k] = ok[front[k]];
            is_front[front[k]] = 1;
        }
    }
    btf_axis ax, ay;
    btf__axis_make(&ax, xlo, xhi, s->log_x);
    btf__axis_make(&ay, ylo, yhi, 0);

    /* Layout. */
    double W = s->width ? s->width : 720, H = s->height ? s->height : 480;
    char lab[32];
    double ytick_w = 0;
    for (int i = 0; i < ay.nticks; i++) {
        double w = btf__svg_text_width(btf__svg_label(lab, ay.ticks[i]), TICK_FONT);
        ytick_w = w > ytick_w ? w : ytick_w;
    }
    double top = PAD + (s->title ? HEAD_FONT + 14 : 6);
    double left = PAD + (s->y_title ? TITLE_FONT + 8 : 0) + ytick_w + 8;
    double legend_h = 22;
    double bottom = TICK_FONT + 10 + (s->x_title ? TITLE_FONT + 8 : 0) + legend_h + PAD;
    box plot = {left, top, W - PAD - 10, H - bottom};
    double pw = plot.x1 - plot.x0, ph = plot.y1 - plot.y0;
#define PX(v) (plot.x0 + pw * btf__axis_pos(&ax, (v)))
#define PY(v) (plot.y1 - ph * btf__axis_pos(&ay, (v)))

    char a[32], b[32], c[32], d[32];
    btf__svg_begin(out, W, H);
    if (s->title)
        btf__svg_text(out, PAD, PAD + HEAD_FONT, HEAD_FONT, "start", 0, "font-weight=\"bold\"", s->title);
    /* Frame, grid lines and ticks. */
    btf__buf_puts(out, "<g stroke=\"#e3e3e3\" stroke-width=\"1\">\n");
    for (int i = 0; i < ax.nticks; i++) {
        double x = PX(ax.ticks[i]);
        btf__buf_printf(out, "<line x1=\"%s\" y1=\"%s\" x2=\"%s\" y2=\"%s\"/>\n", btf__svg_num(a, x),
                        btf__svg_num(b, plot.y0), btf__svg_num(c, x), btf__svg_num(d, plot.y1));
    }
    for (int i = 0; i < ay.nticks; i++) {
        double y = PY(ay.ticks[i]);
        btf__buf_printf(out, "<line x1=\"%s\" y1=\"%s\" x2=\"%s\" y2=\"%s\"/>\n", btf__svg_num(a, plot.x0),
                        btf__svg_num(b, y), btf__svg_num(c, plot.x1), btf__svg_num(d, y));
    }
    btf__buf_puts(out, "</g>\n");
    btf__buf_printf(out, "<rect x=\"%s\" y=\"%s\" width=\"%s\" height=\"%s\" fill=\"none\" "
                        "stroke=\"#555555\" stroke-width=\"1\"/>\n",
                   btf__svg_num(a, plot.x0), btf__svg_num(b, plot.y0), btf__svg_num(c, pw),
                   btf__svg_num(d, ph));
    for (int i = 0; i < ax.nticks; i++)
        btf__svg_text(out, PX(ax.ticks[i]), plot.y1 + TICK_FONT + 5, TICK_FONT, "middle", 0, NULL,
                      btf__svg_label(lab, ax.ticks[i]));
    for (int i = 0; i < ay.nticks; i++)
        btf__svg_text(out, plot.x0 - 5, PY(ay.ticks[i]) + TICK_FONT * 0.35, TICK_FONT, "end", 0, NULL,
                      btf__svg_label(lab, ay.ticks[i]));
    if (s->x_title) {
        char t[64];
        snprintf(t, sizeof t, "%s", s->log_x ? " (log scale)" : "");
        btf__buf_printf(out, "<text x=\"%s\" y=\"%s\" font-size=\"%s\" text-anchor=\"middle\">",
                        btf__svg_num(a, plot.x0 + pw / 2),
                        btf__svg_num(b, plot.y1 + TICK_FONT + 10 + TITLE_FONT), btf__svg_num(c, TITLE_FONT));
        btf__buf_html(out, s->x_title);
        btf__buf_html(out, t);
        btf__buf_puts(out, "</text>\n");
    }
    if (s->y_title)
        btf__svg_text(out, PAD + TITLE_FONT, plot.y0 + ph / 2, TITLE_FONT, "middle", -90, NULL, s->y_title);

    /* The front's step line: between neighbours (in x), through the corner
     * that is worse on both axes (the edge of the dominated region). */
    if (nfront > 1) {
        btf__buf_printf(out, "<path fill=\"none\" stroke=\"%s\" stroke-width=\"1.5\" d=\"", FRONT_COLOUR);
        for (int k = 0; k < nfront; k++) {
            double x = s->x[front[k]], y = s->y[front[k]];
            if (k > 0) {
                double px = s->x[front[k - 1]], py = s->y[front[k - 1]];
                double cx = s->x_higher_better ? (x < px ? x : px) : (x > px ? x : px);
                double cy = s->y_higher_better ? (y < py ? y : py) : (y > py ? y : py);
                btf__buf_printf(out, "L%s %s", btf__svg_num(a, PX(cx)), btf__svg_num(b, PY(cy)));
            }
            btf__buf_printf(out, "%s%s %s", k ? "L" : "M", btf__svg_num(a, PX(x)), btf__svg_num(b, PY(y)));
        }
        btf__buf_puts(out, "\"/>\n");
    }
    /* The points: ordinary ones first, the front over them. */
    for (int k = 0; k < nv; k++) {
        int i = ok[k];
        if (is_front[i])
            continue;
        btf__buf_printf(out, "<circle cx=\"%s\" cy=\"%s\" r=\"3.5\" fill=\"%s\" fill-opacity=\"0.85\">",
                        btf__svg_num(a, PX(s->x[i])), btf__svg_num(b, PY(s->y[i])), POINT_COLOUR);
        btf__buf_puts(out, "<title>");
        if (s->labels && s->labels[i])
            btf__buf_html(out, s->labels[i]), btf__buf_puts(out, ": ");
        btf__buf_printf(out, "%s, ", btf__svg_label(a, s->x[i]));
        btf__buf_printf(out, "%s</title></circle>\n", btf__svg_label(a, s->y[i]));
    }
    for (int k = 0; k < nfront; k++) {
        int i = front[k];
        btf__buf_printf(out, "<circle cx=\"%s\" cy=\"%s\" r=\"4.5\" fill=\"%s\" stroke=\"#ffffff\" "
                            "stroke-width=\"1\"><title>",
                       btf__svg_num(a, PX(s->x[i])), btf__svg_num(b, PY(s->y[i])), FRONT_COLOUR);
        if (s->labels && s->labels[i])
            btf__buf_html(out, s->labels[i]), btf__buf_puts(out, ": ");
        btf__buf_printf(out, "%s, ", btf__svg_label(a, s->x[i]));
        btf__buf_printf(out, "%s</title></circle>\n", btf__svg_label(a, s->y[i]));
    }
    int mark_shown = 0;
    if (s->marked_label) {
        int i = s->marked;
        mark_shown = isfinite(s->x[i]) && isfinite(s->y[i]) && !(s->log_x && s->x[i] <= 0);
        if (mark_shown)
            diamond(out, PX(s->x[i]), PY(s->y[i]), 7);
    }
    /* Labels: the marked point's first (it matters most), then the front's,
     * then (all_labels) the rest. */
    /* Labels keep off the points too: each point is a small box first. */
    int np = 0;
    for (int k = 0; k < nv; k++) {
        double px = PX(vx[k]), py = PY(vy[k]);
        placed[np++] = (box){px - 4, py - 4, px + 4, py + 4};
    }
    if (mark_shown && s->labels && s->labels[s->marked])
        place_label(out, PX(s->x[s->marked]), PY(s->y[s->marked]), s->labels[s->marked], &plot, placed,
                    &np, 2 * n + 1, "font-weight=\"bold\"");
    for (int k = 0; s->labels && k < nfront; k++) {
        int i = front[k];
        if (s->labels[i] && !(mark_shown && i == s->marked))
            place_label(out, PX(s->x[i]), PY(s->y[i]), s->labels[i], &plot, placed, &np, 2 * n + 1, NULL);
    }
    for (int k = 0; s->labels && s->all_labels && k < nv; k++) {
        int i = ok[k];
        if (s->labels[i] && !is_front[i] && !(mark_shown && i == s->marked))
            place_label(out, PX(s->x[i]), PY(s->y[i]), s->labels[i], &plot, placed, &np, 2 * n + 1,
                        "fill=\"#666666\"");
    }
    if (nv == 0)
        btf__svg_text(out, plot.x0 + pw / 2, plot.y0 + ph / 2, TITLE_FONT, "middle", 0,
                      "fill=\"#777777\"", "no data to plot");

    /* The legend, in one row at the bottom; then the note of points left out. */
    double lx = plot.x0, ly = H - PAD - 6;
    const char *pl = s->points_label ? s->points_label : "setting";
    btf__buf_printf(out, "<circle cx=\"%s\" cy=\"%s\" r=\"3.5\" fill=\"%s\"/>\n", btf__svg_num(a, lx + 5),
                    btf__svg_num(b, ly - 4), POINT_COLOUR);
    btf__svg_text(out, lx + 14, ly, TICK_FONT, "start", 0, NULL, pl);
    lx += 14 + btf__svg_text_width(pl, TICK_FONT) + 18;
    if (!s->no_pareto) {
        const char *fl = s->pareto_label ? s->pareto_label : "Pareto-optimal";
        btf__buf_printf(out, "<line x1=\"%s\" y1=\"%s\" x2=\"%s\" y2=\"%s\" stroke=\"%s\" stroke-width=\"1.5\"/>\n",
                        btf__svg_num(a, lx - 2), btf__svg_num(b, ly - 4), btf__svg_num(c, lx + 12),
                        btf__svg_num(d, ly - 4), FRONT_COLOUR);
        btf__buf_printf(out, "<circle cx=\"%s\" cy=\"%s\" r=\"4.5\" fill=\"%s\" stroke=\"#ffffff\"/>\n",
                        btf__svg_num(a, lx + 5), btf__svg_num(b, ly - 4), FRONT_COLOUR);
        btf__svg_text(out, lx + 18, ly, TICK_FONT, "start", 0, NULL, fl);
        lx += 18 + btf__svg_text_width(fl, TICK_FONT) + 18;
    }
    if (s->marked_label) {
        diamond(out, lx + 5, ly - 4, 6);
        btf__svg_text(out, lx + 16, ly, TICK_FONT, "start", 0, NULL, s->marked_label);
        lx += 16 + btf__svg_text_width(s->marked_label, TICK_FONT) + 18;
    }
    if (nv < n) {
        char note[128];
        snprintf(note, sizeof note, "%d of %d not drawn (%s)", n - nv, n,
                 s->log_x ? "not finite, or x \xE2\x89\xA4 0 on the log axis" : "not finite");
        btf__svg_text(out, lx, ly, TICK_FONT, "start", 0, "fill=\"#777777\"", note);
    }
#undef PX
#undef PY
    btf__svg_end(out);
    free(ok), free(front), free(is_front), free(vx), free(vy), free(placed);
    return btf__buf_check(out, "scatter plot", err);
}

btf_status btf__svg_scatter_write(const char *path, const btf_scatter *s, btf_error *err)
{
    btf_buf b = {0};
    return btf__svg_save(path, &b, btf__svg_scatter(s, &b, err), err);
}
