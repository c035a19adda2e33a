/*
 * report_data.h — everything one report measured, handed from the
 * orchestration (report_write.c) to the two writers of the same numbers:
 * the page (report_html.c) and the JSON document (report_json.c).
 * Private to the library.
 */
#ifndef BTF_REPORT_DATA_H
#define BTF_REPORT_DATA_H

#include "btfcar.h"

/* The paper's claim (Haindl & Filip 2007, abstract and section V): about
 * 1 : 10^5 against the measured BTF. */
#define BTF_REPORT_PAPER_RATIO 1e5

typedef struct btf_report_data {
    const btf_dataset_info *in;
    const btf_model *m;
    const btf_report_opts *o;     /* resolved */
    const char *dataset_name, *model_name;
    char date[64];                /* UTC, ISO 8601 */
    /* compression */
    btf_model_bytes bytes;
    btf_raw_bytes raw;
    btf_pca_result pca;
    btf_jpeg_contrast jpeg;
    /* quality */
    btf_quality q;
    unsigned char *pictured;      /* [pair]: 1 when pair-*.png was written */
    int *worst;                   /* indices into q.pairs, worst first */
    int n_worst;
    /* the preview */
    double sphere_s;
    btf_render_info sphere_info;
    /* the trade */
    btf_sweep sweep;
    int have_sweep;
    double seconds;               /* the whole report, up to the writing */
} btf_report_data;

/* The picture of pair i: "pair-vVV-lLL.png" (dataset indices). */
void btf_report_pair_file(const btf_report_data *d, int pair, char *buf, size_t n);

/* The page and the JSON document into the folder dir. */
btf_status btf_report_html(const btf_report_data *d, const char *dir, btf_error *err);
btf_status btf_report_json(const btf_report_data *d, const char *dir, btf_error *err);

#endif
