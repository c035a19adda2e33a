/*
 * report.h — the report's private pieces (src/report/): a growable text
 * buffer with HTML/XML escaping, the Pareto-optimal subset of a point set,
 * a perceptual colour scale, and two plots written as standalone SVG files
 * (a heat map over (view, light) pairs, a scatter plot of a speed/accuracy
 * sweep); and what the compression accounting shares (deflate bit
 * attribution, 8-bit sRGB levels, a symmetric eigen-solver). Private to
 * the library; not installed.
 *
 * The SVG files stand alone: width, height and viewBox set, every text
 * escaped, a system sans-serif font at 11-14 px, no scripts and no
 * reference to anything outside the file (the only URL in them is the SVG
 * namespace); a non-finite number never reaches the file.
 */
#ifndef BTF_REPORT_H
#define BTF_REPORT_H

#include "btfcar.h"
#include "core/core.h"
#include "report/measures.h"

#include <stddef.h>
#include <stdio.h>

/* A figure of the page that differs run to run (the date, a time taken),
 * as a literal format piece: marked with the class "time" so that a reader
 * or a test comparing two runs can tell it from the numbers that must not
 * differ (docs/report.md, "What differs run to run"). */
#define BTF_HTML_TIME(fmt) "<span class=\"time\">" fmt "</span>"

/* ------------------------------------------------------------ text buffer */

/* A growable NUL-terminated text; zero-initialise it. An allocation failure
 * is sticky: later appends do nothing and btf__buf_check reports it, so a
 * writer appends freely and checks once. */
typedef struct btf_buf {
    char *data;   /* malloc'd, NUL-terminated (NULL while empty) */
    size_t len;   /* bytes before the NUL */
    size_t cap;
    int failed;   /* an allocation failed */
} btf_buf;

/* Appends n bytes / a C string / printf output (C locale number formats as
 * the library never calls setlocale). 0, or -1 when the buffer failed. */
int btf__buf_put(btf_buf *b, const char *s, size_t n);
int btf__buf_puts(btf_buf *b, const char *s);
int btf__buf_printf(btf_buf *b, const char *fmt, ...) BTF_PRINTF(2, 3);
/* Appends text escaped for HTML and XML, both in content and in attribute
 * values: & < > " ' become entities; control characters other than tab,
 * newline and carriage return (not allowed in XML 1.0) and bytes that are
 * not valid UTF-8 become U+FFFD. NULL appends nothing. */
int btf__buf_html(btf_buf *b, const char *text);
/* BTF_OK, or BTF_E_NOMEM ("NAME: out of memory ...") when the buffer failed. */
btf_status btf__buf_check(const btf_buf *b, const char *name, btf_error *err);
/* Writes the text to path atomically (btf_write_file_atomic); checks the
 * buffer first. */
btf_status btf__buf_write(const btf_buf *b, const char *path, btf_error *err);
void btf__buf_free(btf_buf *b);

/* The same escaping as btf__buf_html, written to f: 0, or -1 on a write error. */
int btf__html_fputs(FILE *f, const char *text);

/* ------------------------------------------------------------ library.c */

/* One material's row of the library report, from its report.json. */
typedef struct btf_library_row {
    char dir[4096];          /* the report folder, absolute */
    char dataset[512], model[512], preview[256];
    double model_bytes, raw_bytes, ratio, mean, worst, seconds; /* finite, >= 0 */
    int pairs;
} btf_library_row;
/* report.json's text into *r (whose dir is left alone): 1, or 0 when it is
 * not a btfcar report. Missing or bad figures read as 0; the preview is a
 * plain file name or empty. */
int btf__library_row_parse(const char *data, size_t n, btf_library_row *r);

/* ------------------------------------------------------------ Pareto front */

/* The Pareto-optimal points among n points (x[i], y[i]): those that no
 * other point dominates (at least as good on both axes and better on one).
 * Smaller is better on an axis unless its *_higher_better is non-zero.
 * Points with a NaN or infinite coordinate neither are optimal nor
 * dominate. Equal points are all optimal. Writes their indices into idx
 * (room for n) in increasing x, ties by increasing y then index, and
 * returns their count (0 when n <= 0). O(n^2): for sweeps of up to a few
 * thousand settings. */
int btf__pareto_front(const double *x, const double *y, int n, int x_higher_better,
                      int y_higher_better, int *idx);

/* ------------------------------------------------------------ colour scale */

/* The report's colour scale at t in [0, 1] (clamped; NaN gives t = 0) as
 * 8-bit sRGB: a viridis-like path computed in OKLCh, lightness rising
 * linearly from 0.30 to 0.93 while the hue turns from violet (310 deg)
 * through blue and green to yellow (105 deg); chroma is reduced where
 * needed to stay inside sRGB. Monotone lightness keeps it readable in grey
 * and for colour-blind readers. */
void btf__colour_scale(double t, unsigned char rgb[3]);

/* ------------------------------------------------ SVG pieces (svg.c) */

/* What the plot files share; report writers may use them for their own
 * figures. Numbers are written through btf__svg_num, which never writes
 * "nan" or "inf" (a non-finite value becomes 0). */
#define BTF_SVG_FONT "DejaVu Sans, Liberation Sans, Arial, Helvetica, sans-serif"
/* The XML declaration and the <svg> element: width, height, viewBox, the
 * font; then a white background. */
void btf__svg_begin(btf_buf *b, double width, double height);
void btf__svg_end(btf_buf *b);
/* Writes b, which a plot function filled and answered made for, to path
 * (atomically) when made is BTF_OK, else names path in err's message; frees
 * b and returns the status: the *_write of every plot. */
btf_status btf__svg_save(const char *path, btf_buf *b, btf_status made, btf_error *err);
/* v with at most 2 decimals, trailing zeros dropped, into out (32 bytes). */
const char *btf__svg_num(char out[32], double v);
/* A value for a label: 4 significant digits, no exponent between 1e-4 and
 * 1e6, "-0" as "0"; non-finite values as "–". */
const char *btf__svg_label(char out[32], double v);
/* <text x y font-size text-anchor [transform rotate(angle about x,y)]>
 * with the escaped text; anchor "start", "middle" or "end"; extra NULL or
 * more attributes (e.g. "font-weight=\"bold\""). */
void btf__svg_text(btf_buf *b, double x, double y, double size, const char *anchor,
                   double angle, const char *extra, const char *text);
/* The width of text in px at a font size (an estimate: 0.6 em per
 * character, counted in UTF-8 code points). */
double btf__svg_text_width(const char *text, double size);

/* An axis: the data range [lo, hi] widened to nice bounds (linear) or
 * padded (log), and its ticks at 1-2-5 multiples of powers of ten (log:
 * decades, with 2 and 5 when there are few). lo, hi may be anything,
 * NaN and a single value included: the result is always finite, lo < hi,
 * positive on a log axis, with 2..BTF_AXIS_MAX_TICKS ticks. */
#define BTF_AXIS_MAX_TICKS 24
typedef struct btf_axis {
    double lo, hi;        /* the drawn range (data units) */
    int log;              /* log10 scale */
    int nticks;
    double ticks[BTF_AXIS_MAX_TICKS];
} btf_axis;
void btf__axis_make(btf_axis *a, double lo, double hi, int log);
/* A value's position in [0, 1] along the axis (clamped to [-0.05, 1.05];
 * non-finite: 0). */
double btf__axis_pos(const btf_axis *a, double v);

/* ------------------------------------------------------------ heat map */

typedef struct btf_svg_cell {
    int row, col;
} btf_svg_cell;

/* A rows x cols grid of values, row 0 at the top, column 0 at the left.
 * Zero-initialise and fill in; NULL texts are left out. */
typedef struct btf_heatmap {
    int rows, cols;               /* 1..4096 each */
    const double *values;         /* rows*cols, row-major; NaN: not measured
                                     (drawn hatched grey); +-Inf as NaN */
    const char *title;            /* above the plot */
    const char *x_title;          /* under the columns, e.g. "light (θ, φ)" */
    const char *y_title;          /* beside the rows, e.g. "view (θ, φ)" */
    const char *legend_label;     /* beside the colour bar, e.g. "ΔE" */
    const char *const *row_labels; /* rows entries (entries may be NULL) or NULL */
    const char *const *col_labels; /* cols entries or NULL; thinned out to
                                     stay readable when cells are small */
    const btf_svg_cell *marked;   /* cells outlined in red (e.g. the worst pairs) */
    int n_marked;
    const char *marked_label;     /* legend entry of the outlines (NULL: none) */
    double vmin, vmax;            /* colour range; vmin >= vmax (both 0 when
                                     zeroed): the finite values' range */
    int reverse;                  /* non-zero: the scale runs from vmax (dark) to
                                     vmin (bright), when small is bad */
    int cell_px;                  /* cell side in px; 0: auto (fits ~640 px,
                                     4..40) */
    int tooltips;                 /* non-zero: a <title> per cell (row, column,
                                     value); larger files */
} btf_heatmap;

/* Appends the heat map as one SVG document to out; BTF_E_ARG for sizes out
 * of range, a NULL values pointer or a marked cell outside the grid. */
btf_status btf__svg_heatmap(const btf_heatmap *h, btf_buf *out, btf_error *err);
/* The same written to path (atomically); messages name path. */
btf_status btf__svg_heatmap_write(const char *path, const btf_heatmap *h, btf_error *err);

/* ------------------------------------------------------------ scatter plot */

/* Points (x[i], y[i]), e.g. the settings of a sweep: time against error.
 * Zero-initialise and fill in. Points with a non-finite coordinate, or
 * x <= 0 on a log axis, are not drawn (a note under the plot counts them)
 * and take no part in the Pareto front. */
typedef struct btf_scatter {
    int n;                        /* 0..100000 */
    const double *x, *y;
    const char *const *labels;    /* n entries (entries may be NULL) or NULL:
                                     shown beside the Pareto-optimal and the
                                     marked point, a tooltip for the others */
    const char *title, *x_title, *y_title;
    int log_x;                    /* non-zero: logarithmic x axis */
    int x_higher_better;          /* Pareto directions: 0, smaller is better */
    int y_higher_better;
    int no_pareto;                /* non-zero: no front drawn */
    const char *pareto_label;     /* legend; NULL: "Pareto-optimal" */
    const char *points_label;     /* legend; NULL: "setting" */
    const char *marked_label;     /* legend of the marked point, e.g.
                                     "default"; NULL: no marked point */
    int marked;                   /* its index (used when marked_label is set) */
    int all_labels;               /* non-zero: every point's label shown */
    int width, height;            /* px; 0: 720 x 480 */
} btf_scatter;

/* Appends the scatter plot as one SVG document to out; BTF_E_ARG for n
 * out of range, NULL arrays with n > 0, a marked index outside 0..n-1. */
btf_status btf__svg_scatter(const btf_scatter *s, btf_buf *out, btf_error *err);
btf_status btf__svg_scatter_write(const char *path, const btf_scatter *s, btf_error *err);

/* ---------------------------------------------- compression accounting */

/* Decodes the zlib stream z (zn bytes: header, deflate data, Adler-32),
 * which must inflate to exactly the n bytes at expect, and gives every bit
 * of it to what it codes: a literal's code to its byte, a match's length
 * and distance codes with their extra bits in equal shares to the bytes it
 * copies, a stored block's bytes to themselves. bits[label[i]] receives
 * the bits of payload byte i (labels < nlabels; bits has nlabels entries,
 * added to); *overhead_bits the rest (zlib header and Adler-32, block
 * headers, code tables, end-of-block codes, padding), so that the sum of
 * bits and overhead is 8 zn. name starts error messages; BTF_E_FORMAT when
 * the stream is not valid or does not inflate to expect
 * (report/deflate_cost.c). */
btf_status btf__deflate_cost(const unsigned char *z, size_t zn, const unsigned char *expect,
                             const unsigned char *label, size_t n, int nlabels, double *bits,
                             double *overhead_bits, const char *name, btf_error *err);

/* An image's linear float values as the report's 8-bit sRGB levels, 0..255
 * and not rounded: btf__linear_to_srgb (which clamps to [0, 1]) x 255; a
 * value decoded from an 8-bit sRGB file gives back its stored code exactly
 * (report/srgb_levels.c). The table makes that exact path cheap: fill it
 * once with btf__srgb_levels_init. */
typedef struct btf_srgb_levels_table {
    float lut[256];              /* the linear value of each 8-bit code */
    unsigned char start[4097];   /* the first code whose value is >= k / 4096 */
} btf_srgb_levels_table;
void btf__srgb_levels_init(btf_srgb_levels_table *t);
void btf__srgb_levels(const btf_srgb_levels_table *t, const float *linear, size_t n, float *out);

/* The eigenvalues (descending) and unit eigenvectors (columns of vec, n x n
 * row-major: vec[i * n + k] is component i of eigenvector k) of the
 * symmetric n x n matrix a (overwritten), by cyclic Jacobi rotations until
 * the off-diagonal part vanishes: deterministic. -1 when out of memory
 * (report/jacobi.c). */
int btf_sym_eigen(double *a, int n, double *val, double *vec);

/* The raw BTF of a dataset (report/raw_bytes.c): btf__dataset_raw_bytes
 * without the argument checks. */
void btf__raw_bytes_of(const btf_dataset_info *info, btf_raw_bytes *out);

/* ------------------------------------------------------ the sweep's state */

/* A sweep point's state file (report/sweep.c), text of n bytes: 1 when it
 * is a whole point of the setting p->setting written under fingerprint,
 * with values a measurement can give (then *p holds them, resumed set);
 * 0 for anything else (*p untouched), never a crash: the file is read back
 * from a folder anyone may have edited. */
int btf__sweep_point_parse(const char *text, size_t n, const char *fingerprint,
                           btf_sweep_point *p);

/* Reached through the material interface (btfcar/material.h) by users;
 * declared here for the library and its tests. */
/* ----------------------------------------- reflectance-field reports */

/* The report of an RF model (docs/report.md, "Reflectance-field models"),
 * the counterpart of btf_report_write in the same folder layout: the model
 * file's bytes against the raw BTF; per sampled pair (opts->quality: the
 * spread or all) the measured image against btf__rf_render_flat of that
 * pair by btf_texture_distance and the pixel-wise mean |dY|; the mean |dY|
 * over every texel and image (the paper's Table 1); pictures of the sampled
 * pairs and of the
 * opts->worst pairs by |dY|; the preview sphere (btf__rf_render_scene);
 * DIR/index.html and DIR/report.json. The model must be of ds (size and
 * direction sets; BTF_E_ARG). opts->sweep is BTF_E_ARG (no CAR settings to
 * trade); the PCA, JPEG and relief options do not apply. */
btf_status btf__rf_report_write(const btf_dataset *ds, const btf_rf_model *m, const char *dir,
                                const btf_report_opts *opts, btf_report_summary *summary,
                                btf_error *err);

#endif
