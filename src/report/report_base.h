/*
 * report_base.h — what the reports of every model family share
 * (docs/report.md). A report is a list of sections; each section may write
 * files beside the page (plots), a part of index.html and keys of
 * report.json. A family (car_report*.c: the CAR model; rf_report*.c:
 * reflectance fields) measures its model and lists its own sections, which
 * call the shared pieces declared here: the measured pairs with their
 * pictures and the worst of them, the preview sphere, the page's skeleton,
 * its cards and tables, the heat map, the galleries of pair pictures and
 * report.json's common keys. The shared code never calls a family's
 * functions but through the family's table (btf_report_family), so a new
 * family adds files and touches none of these. Private to the library.
 */
#ifndef BTF_REPORT_BASE_H
#define BTF_REPORT_BASE_H

#include "btfcar.h"
#include "report/report.h"

#include <cjson/cJSON.h>
#include <stddef.h>

/* One measured (view, light) pair as every family's report lists it. */
typedef struct btf_report_pair {
    int view, light;                /* dataset indices */
    const btf_texture_distances *d; /* measured image (reference) against the model's
                                       flat render, held by the family's data */
    double rank;                    /* what the heat map shows and the worst pairs are
                                       ranked by, larger is worse */
} btf_report_pair;

/* The report's shared state: the first member of a family's data, so that
 * a family's section turns the pointer it gets back into its own type. */
typedef struct btf_report_base {
    const btf_dataset_info *in;
    const btf_report_opts *o;     /* resolved */
    const char *dataset_name, *model_name;
    char date[64];                /* UTC, ISO 8601 */
    double t0;                    /* btf__now() at the start */
    double seconds;               /* the whole report, up to the writing */
    /* compression */
    btf_raw_bytes raw;
    uint64_t model_bytes;         /* the model file */
    /* quality */
    int n_pairs;
    btf_report_pair *pairs;       /* view-major */
    unsigned char *pictured;      /* [pair]: pair-vVV-lLL.png written; room for every
                                     pair of the dataset, as a family may picture a
                                     pair before it knows how many it measures */
    int *worst;                   /* indices into pairs, worst first */
    int n_worst;
    /* the preview */
    double sphere_s;
} btf_report_base;

/* A part of the report; any of the three may be NULL. */
typedef struct btf_report_section {
    btf_status (*files)(const btf_report_base *r, const char *dir, btf_error *err);
    void (*html)(btf_buf *b, const btf_report_base *r);
    void (*json)(cJSON *root, const btf_report_base *r);
} btf_report_section;

/* A model family's report. */
typedef struct btf_report_family {
    const char *name;          /* report.json's "family"; NULL leaves the key out, as
                                  the CAR report's report.json always has */
    const char *style;         /* the family's own style rules, after the shared ones */
    const char *citation;      /* the method's paper, HTML, on the page's last line */
    /* Everything measured into the temporary folder tmp (dir: the report's
     * own folder, for state that must outlive an interrupted run). */
    btf_status (*measure)(btf_report_base *r, const btf_dataset *ds, const char *tmp,
                          const char *dir, btf_error *err);
    /* The model's flat render of a dataset pair (the worst pairs' pictures). */
    btf_status (*render_flat)(const btf_report_base *r, int view, int light, btf_image *out,
                              btf_error *err);
    /* The preview: the scene at side x side pixels. */
    btf_status (*render_scene)(btf_report_base *r, const btf_scene *sc, int side,
                               btf_image *out, btf_error *err);
    /* The family's figures of the summary, after the shared ones. */
    void (*summarise)(const btf_report_base *r, btf_report_summary *s);
    /* The model under the title (html: the meta line) and at the top of
     * report.json (before "seconds"). */
    const btf_report_section *about;
    const btf_report_section *const *sections; /* in the page's and the document's order */
    int n_sections;
} btf_report_family;

/* ------------------------------------------- measuring (report_run.c) */

/* The options every family takes, defaults filled in (the preview's light
 * and size, the worst pairs) and checked. */
btf_status btf__report_resolve(const btf_report_opts *in, btf_report_opts *o, btf_error *err);
/* Starts r (zeroed by the caller): the dataset, the resolved options o, the
 * names shown, the date, the clock. */
void btf__report_begin(btf_report_base *r, const btf_dataset *ds, const btf_report_opts *o);
/* Which pairs get pictures, *want [view * n_lights + light] (free it): the
 * spread of views x lights measured; with every pair measured, the default
 * spread (the worst come later). Allocates r->pictured too. */
btf_status btf__report_pictures_begin(btf_report_base *r, unsigned char **want, btf_error *err);
/* The picture of pair (its dataset view and light) into dir, marked in
 * r->pictured: measured | model side by side, a 4-pixel dark gap between,
 * as PNG (pair_file.c). */
btf_status btf__report_picture(btf_report_base *r, const char *dir, int pair, int view, int light,
                               const btf_image *measured, const btf_image *model, btf_error *err);
/* r->pairs for n pairs, zeroed, for the family to fill. */
btf_status btf__report_pairs_alloc(btf_report_base *r, int n, btf_error *err);
/* The worst pairs by rank (ties: the lower index first), then the pictures
 * of those not pictured yet, rendered again by f->render_flat, on a pool
 * of threads (1: one after the other, for a render that itself runs on
 * every thread). */
btf_status btf__report_worst(btf_report_base *r, const btf_report_family *f,
                             const btf_dataset *ds, const char *dir, int threads,
                             btf_error *err);
/* The preview: the material on a sphere under the chosen light, dir/sphere.png.
 * A texel per pixel at the sphere's centre: the surface shows about
 * side / 2.4 texels across its radius. */
btf_status btf__report_preview(btf_report_base *r, const btf_report_family *f, const char *dir,
                               btf_error *err);
/* The whole report of family f into the folder dir: measured into a
 * temporary folder, written (files, page, report.json) and moved into place
 * as a whole; the summary (may be NULL) filled on success; progress "done". */
btf_status btf__report_run(btf_report_base *r, const btf_report_family *f,
                           const btf_dataset *ds, const char *dir, btf_report_summary *summary,
                           btf_error *err);
void btf__report_base_free(btf_report_base *r);

/* The picture of a pair: "pair-vVV-lLL.png" (dataset indices). */
void btf__report_pair_file(int view, int light, char *buf, size_t n);

/* ------------------------------------------- the page (report_page.c) */

/* dir/index.html: the skeleton (head, styles, title), the family's about
 * line, its sections, the closing line. */
btf_status btf__report_page(const btf_report_base *r, const btf_report_family *f,
                            const char *dir, btf_error *err);

/* Numbers as the page writes them, into buf (32 bytes at least): a size
 * ("12.3 KB"), a ratio ("1 : 1027", "–" when not positive and finite), a
 * direction ("θ 30 φ 60"). */
const char *btf__report_bytes_text(uint64_t bytes, char *buf, size_t n);
const char *btf__report_ratio_text(double ratio, char *buf, size_t n);
const char *btf__report_dir_text(btf_dir d, char *buf, size_t n);
/* raw / bytes, 0 without bytes. */
double btf__report_ratio(uint64_t raw, uint64_t bytes);

/* The top: the preview with its caption (note, HTML, stands before
 * "rendered in"), then the cards of the model file and its ratio to the
 * raw BTF; the family adds its cards and closes it. */
void btf__report_top_begin(btf_buf *b, const btf_report_base *r, const char *note);
void btf__report_top_end(btf_buf *b);
/* A card of the top, as a literal format piece (like BTF_HTML_TIME), so
 * that the compiler checks its arguments: a figure and what it is. */
#define BTF_HTML_CARD(value, label) \
    "<div class=\"card\"><b>" value "</b><span>" label "</span></div>\n"

/* A row of a table of sizes: what, bytes, ratio and a note (NULL: none),
 * each HTML; what and the note left-aligned. tr_class NULL: none. */
void btf__report_row(btf_buf *b, const char *tr_class, const char *what, const char *bytes,
                     const char *ratio, const char *note);

/* What a family writes of one pair: its caption under the picture, its
 * cells in the table of every pair, its keys in report.json. */
typedef void (*btf_report_pair_html)(btf_buf *b, const btf_report_base *r, int pair);
typedef void (*btf_report_pair_json)(cJSON *o, const btf_report_base *r, int pair);

/* dir/heatmap.svg: the pairs' rank over views (rows) x lights (columns),
 * the pairs not measured left empty, the worst outlined. */
btf_status btf__report_heatmap(const btf_report_base *r, const char *dir, const char *title,
                               const char *legend, btf_error *err);
/* The heat map on the page; caption NULL: none. */
void btf__report_heatmap_figure(btf_buf *b, const char *alt, const char *caption);
/* The galleries: the worst pairs (shown larger when small), then every
 * pictured pair (larger too when zoom_pictured), each with its caption. */
void btf__report_galleries(btf_buf *b, const btf_report_base *r, const char *worst_heading,
                           const char *pictured_heading, int zoom_pictured,
                           btf_report_pair_html caption);
/* "Every measured pair": view, light, then the family's columns (head:
 * their <th> cells) and cells. */
void btf__report_pair_table(btf_buf *b, const btf_report_base *r, const char *head,
                            btf_report_pair_html cells);

/* ------------------------------------------- report.json (report_json.c) */

/* dir/report.json: the format, the family, the version, the date, the
 * names and the dataset, the family's about keys, "seconds", the sections. */
btf_status btf__report_json(const btf_report_base *r, const btf_report_family *f,
                            const char *dir, btf_error *err);
/* {"theta", "phi"} under key. */
void btf__report_json_dir(cJSON *o, const char *key, btf_dir d);
/* "compression" with the raw BTF, the dataset on disk, the model file and
 * their ratio; the family adds its keys to it. */
cJSON *btf__report_json_compression(cJSON *root, const btf_report_base *r);
/* "quality" with the sample, the pair count and the mean combined
 * distance, which every family's report has first (the library page reads
 * them: library.c); the family adds its figures, then
 * btf__report_json_pairs. */
cJSON *btf__report_json_quality(cJSON *root, const btf_report_base *r, double mean_combined);
/* "worst" and "pairs_measured" under quality: each pair's indices and
 * directions, the family's keys, its picture (null_picture: null for a
 * pair without one, else the key is left out, as the RF report has it). */
void btf__report_json_pairs(cJSON *quality, const btf_report_base *r, btf_report_pair_json keys,
                            int null_picture);
/* "preview": the picture, its light, size and time; the family may add. */
cJSON *btf__report_json_preview(cJSON *root, const btf_report_base *r);

#endif
