/*
 * svg.c — what the report's SVG plots share: the document frame, numbers
 * that are never "nan" or "inf", escaped text, text widths for layout, and
 * axes with "nice" 1-2-5 ticks (linear or log10). The plots themselves are
 * svg_heatmap.c and svg_scatter.c.
 */
#include "core/core.h"
#include "report/report.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

void btf__svg_begin(btf_buf *b, double width, double height)
{
    char w[32], h[32];
    btf__svg_num(w, width);
    btf__svg_num(h, height);
    btf__buf_printf(b,
                    "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
                    "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%s\" height=\"%s\" "
                    "viewBox=\"0 0 %s %s\" font-family=\"%s\" font-size=\"12\" fill=\"#222222\">\n"
                    "<rect x=\"0\" y=\"0\" width=\"%s\" height=\"%s\" fill=\"#ffffff\"/>\n",
                    w, h, w, h, BTF_SVG_FONT, w, h);
}

void btf__svg_end(btf_buf *b)
{
    btf__buf_puts(b, "</svg>\n");
}

btf_status btf__svg_save(const char *path, btf_buf *b, btf_status made, btf_error *err)
{
    if (made == BTF_OK)
        made = btf__buf_write(b, path, err);
    else
        btf__error_name(err, path);
    btf__buf_free(b);
    return made;
}

const char *btf__svg_num(char out[32], double v)
{
    if (!isfinite(v) || fabs(v) > 1e9)
        v = isfinite(v) ? (v > 0 ? 1e9 : -1e9) : 0;
    snprintf(out, 32, "%.2f", v);
    char *dot = strchr(out, '.');
    if (dot) {
        char *e = out + strlen(out) - 1;
        while (e > dot && *e == '0')
            *e-- = '\0';
        if (e == dot)
            *e = '\0';
    }
    if (!strcmp(out, "-0"))
        strcpy(out, "0");
    return out;
}

const char *btf__svg_label(char out[32], double v)
{
    if (!isfinite(v)) {
        strcpy(out, "\xE2\x80\x93"); /* en dash */
        return out;
    }
    if (v == 0) /* -0 too */
        v = 0;
    double a = fabs(v);
    if (a != 0 && (a < 1e-4 || a >= 1e6))
        snprintf(out, 32, "%.3g", v);
    else
        snprintf(out, 32, "%.4g", v);
    if (!strcmp(out, "-0"))
        strcpy(out, "0");
    return out;
}

void btf__svg_text(btf_buf *b, double x, double y, double size, const char *anchor,
                   double angle, const char *extra, const char *text)
{
    char xs[32], ys[32], ss[32], as[32];
    btf__svg_num(xs, x);
    btf__svg_num(ys, y);
    btf__svg_num(ss, size);
    btf__buf_printf(b, "<text x=\"%s\" y=\"%s\" font-size=\"%s\" text-anchor=\"%s\"", xs, ys, ss,
                    anchor ? anchor : "start");
    if (angle != 0 && isfinite(angle))
        btf__buf_printf(b, " transform=\"rotate(%s %s %s)\"", btf__svg_num(as, angle), xs, ys);
    if (extra)
        btf__buf_printf(b, " %s", extra);
    btf__buf_puts(b, ">");
    btf__buf_html(b, text);
    btf__buf_puts(b, "</text>\n");
}

double btf__svg_text_width(const char *text, double size)
{
    size_t n = 0;
    for (const unsigned char *s = (const unsigned char *)(text ? text : ""); *s; s++)
        n += (*s & 0xC0) != 0x80;
    return 0.6 * size * (double)n;
}

/* The smallest 1, 2 or 5 x 10^k at least x (x > 0). */
static double nice_step(double x)
{
    double p = pow(10, floor(log10(x)));
    double m = x / p;
    return (m <= 1 ? 1 : m <= 2 ? 2 : m <= 5 ? 5 : 10) * p;
}

static void linear_ticks(btf_axis *a, double lo, double hi, int snap)
{
    double step = nice_step((hi - lo) / 5);
    while ((hi - lo) / step > BTF_AXIS_MAX_TICKS - 2)
        step = nice_step(step * 1.01);
    if (snap) {
        lo = floor(lo / step + 1e-9) * step;
        hi = ceil(hi / step - 1e-9) * step;
        a->lo = lo, a->hi = hi;
    }
    a->nticks = 0;
    for (double k = ceil(a->lo / step - 1e-9); k * step <= a->hi + step * 1e-9; k++) {
        if (a->nticks == BTF_AXIS_MAX_TICKS)
            break;
        double t = k * step;
        if (fabs(t) < step * 1e-9)
            t = 0;
        a->ticks[a->nticks++] = t;
    }
}

void btf__axis_make(btf_axis *a, double lo, double hi, int log)
{
    memset(a, 0, sizeof *a);
    a->log = log != 0;
    /* Sanitise: no data, one value, reversed or non-finite bounds. */
    if (!isfinite(lo) && !isfinite(hi))
        lo = a->log ? 1 : 0, hi = a->log ? 10 : 1;
    else if (!isfinite(lo))
        lo = hi;
    else if (!isfinite(hi))
        hi = lo;
    if (lo > hi) {
        double t = lo;
        lo = hi, hi = t;
    }
    if (a->log) {
        if (hi <= 0)
            lo = 1, hi = 10;
        else if (lo <= 0)
            lo = hi / 10;
        lo = lo < 1e-300 ? 1e-300 : lo;
        hi = hi > 1e300 ? 1e300 : hi;
        double l0 = log10(lo), l1 = log10(hi);
        if (l1 - l0 < 1e-9)
            l0 -= 0.30103, l1 += 0.30103; /* one value: half to twice it */
        double pad = 0.05 * (l1 - l0);
        l0 -= pad, l1 += pad;
        l0 = l0 < -300 ? -300 : l0; /* keep pow() finite and non-zero */
        l1 = l1 > 300 ? 300 : l1;
        a->lo = pow(10, l0), a->hi = pow(10, l1);
        double span = l1 - l0;
        a->nticks = 0;
        if (span >= 0.9) {
            static const double m125[3] = {1, 2, 5};
            int per = span <= 2.5 ? 3 : 1;             /* 1, 2, 5 x 10^k */
            int every = span <= 16 ? 1 : (int)ceil(span / 8); /* every n-th decade */
            for (double k = floor(floor(l0) / every) * every; k <= ceil(l1); k += every)
                for (int m = 0; m < per; m++) {
                    double t = m125[m] * pow(10, k);
                    if (t >= a->lo * (1 - 1e-12) && t <= a->hi * (1 + 1e-12) &&
                        a->nticks < BTF_AXIS_MAX_TICKS)
                        a->ticks[a->nticks++] = t;
                }
        }
        if (a->nticks < 2)
            linear_ticks(a, a->lo, a->hi, 0); /* a narrow range: plain nice ticks */
        if (a->nticks < 2) {
            a->nticks = 2;
            a->ticks[0] = a->lo, a->ticks[1] = a->hi;
        }
        return;
    }
    if (hi - lo < 1e-12 * (fabs(lo) + fabs(hi)) || hi == lo) {
        double d = lo == 0 ? 1 : 0.1 * fabs(lo);
        lo -= d, hi += d;
    }
    /* Far from overflow: the nice bounds and ticks stay finite. */
    lo = lo < -1e300 ? -1e300 : lo > 1e300 ? 1e300 : lo;
    hi = hi > 1e300 ? 1e300 : hi < -1e300 ? -1e300 : hi;
    if (!(hi > lo))
        hi = lo + fabs(lo) * 0.1 + 1;
    linear_ticks(a, lo, hi, 1);
    if (a->nticks < 2 || !(a->hi > a->lo)) {
        a->lo = lo, a->hi = hi, a->nticks = 2;
        a->ticks[0] = lo, a->ticks[1] = hi;
    }
}

double btf__axis_pos(const btf_axis *a, double v)
{
    if (!isfinite(v))
        return 0;
    double p;
    if (a->log)
        p = v <= 0 ? -0.05 : (log10(v) - log10(a->lo)) / (log10(a->hi) - log10(a->lo));
    else
        p = (v - a->lo) / (a->hi - a->lo);
    if (!isfinite(p))
        return 0;
    return p < -0.05 ? -0.05 : p > 1.05 ? 1.05 : p;
}
