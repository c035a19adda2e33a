/*
 * rf_report_data.h — what the report of a reflectance-field model measured
 * (docs/report.md, "Reflectance-field models"), handed from its measurement
 * (rf_report.c) to its sections (rf_report_page.c): the shared part
 * (report_base.h) and what only this family has. Private to the library.
 */
#ifndef BTF_RF_REPORT_DATA_H
#define BTF_RF_REPORT_DATA_H

#include "btfcar.h"
#include "report/report_base.h"
#include "report/measures.h"

/* A measured pair's figures; its view and light are the base's pair's. */
typedef struct btf_rf_pair {
    btf_texture_distances d;   /* measured image (reference) against the flat render */
    double mean_abs_dy;        /* mean |Y measured - Y render| over the pair's texels */
    int held_out;              /* 1: the model was not fitted to this pair's view or light
                                  (left out of its analysis): its render interpolates */
} btf_rf_pair;

typedef struct btf_rf_report {
    btf_report_base r;         /* first: a section's base pointer is this */
    const btf_rf_model *m;
    /* the dataset's view v and light l are the model's view_of[v] and
     * light_of[l], or -1: held out of the model's fit */
    int *view_of, *light_of;
    /* compression: r.model_bytes is btf_rf_encode's file */
    btf_rf_bytes bytes;        /* coefficients and coordinate map (section 6) */
    /* pixel-wise error over every image (btf__rf_error, the paper's Table 1) */
    double mean_abs_error, mean_luminance;
    /* quality per sampled pair */
    btf_rf_pair *pairs;        /* r.n_pairs, as r.pairs */
    double mean_combined, worst_combined, mean_pair_dy, worst_pair_dy;
    double mean_spectrum, mean_first_order, mean_structure;
    /* the held-out pairs, apart: the means above are over the fitted ones */
    int n_held_out;
    double mean_held_out, mean_held_out_dy;
} btf_rf_report;

/* The reflectance-field report's sections (rf_report_page.c): the model
 * under the title, the top, the compression, the pixel-wise error's keys,
 * the quality per direction, the preview's keys. */
extern const btf_report_section btf__rf_about, btf__rf_top, btf__rf_compression,
    btf__rf_pixelwise, btf__rf_quality, btf__rf_preview;

#endif
