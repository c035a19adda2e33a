/*
 * rf_report_data.h — what the report of a reflectance-field model measured
 * (issue 19, point 4; docs/report.md, "Reflectance-field models"), handed
 * from the orchestration (rf_report.c) to its page and JSON writer
 * (rf_report_page.c). Private to the library.
 */
#ifndef BTF_RF_REPORT_DATA_H
#define BTF_RF_REPORT_DATA_H

#include "btfcar.h"

typedef struct btf_rf_pair {
    int view, light;           /* dataset indices */
    btf_texture_distances d;   /* measured image (reference) against the flat render */
    double mean_abs_dy;        /* mean |Y measured - Y render| over the pair's texels */
    int pictured;              /* pair-vVV-lLL.png written */
} btf_rf_pair;

typedef struct btf_rf_report_data {
    const btf_dataset_info *in;
    const btf_rf_model *m;
    const btf_report_opts *o;  /* resolved */
    const char *dataset_name, *model_name;
    char date[64];
    /* compression */
    uint64_t file_bytes;       /* btf_rf_encode: the model file */
    btf_rf_bytes bytes;        /* coefficients and coordinate map (section 6) */
    btf_raw_bytes raw;
    /* pixel-wise error over every image (btf_rf_error, the paper's Table 1) */
    double mean_abs_error, mean_luminance;
    /* quality per sampled pair */
    int n_pairs;
    btf_rf_pair *pairs;        /* view-major */
    double mean_combined, worst_combined, mean_pair_dy, worst_pair_dy;
    double mean_spectrum, mean_first_order, mean_structure;
    int *worst;                /* pair indices by mean |dY|, largest first */
    int n_worst;
    double sphere_s;
    double seconds;
} btf_rf_report_data;

/* "pair-vVV-lLL.png" of pair i (rf_report_page.c). */
void btf_rf_report_pair_file(const btf_rf_report_data *d, int i, char *buf, size_t n);
/* DIR/index.html (and heatmap.svg) and DIR/report.json. */
btf_status btf_rf_report_page(const btf_rf_report_data *d, const char *dir, btf_error *err);

#endif
