/*
 * car_report_data.h — what the report of a CAR model measured, handed from
 * its measurement (car_report.c) to its sections (car_report_page.c): the
 * shared part (report_base.h) and what only this family has. Private to
 * the library.
 */
#ifndef BTF_CAR_REPORT_DATA_H
#define BTF_CAR_REPORT_DATA_H

#include "btfcar.h"
#include "report/report_base.h"

/* The paper's claim (Haindl & Filip 2007, abstract and section V): about
 * 1 : 10^5 against the measured BTF. */
#define BTF_REPORT_PAPER_RATIO 1e5

typedef struct btf_car_report {
    btf_report_base r;            /* first: a section's base pointer is this */
    const btf_model *m;
    /* compression */
    btf_model_bytes bytes;
    btf_pca_result pca;
    btf_jpeg_contrast jpeg;
    /* quality */
    btf_quality q;
    /* the preview */
    btf_render_info sphere_info;
    /* the trade */
    btf_sweep sweep;
    int have_sweep;
} btf_car_report;

/* The CAR report's sections: the model under the title, the top (the
 * preview and the cards), the compression, the quality per direction, the
 * preview's keys (car_report_page.c), the speed/accuracy trade
 * (car_report_trade.c). */
extern const btf_report_section btf__car_about, btf__car_top, btf__car_compression,
    btf__car_quality, btf__car_preview, btf__car_trade;

#endif
