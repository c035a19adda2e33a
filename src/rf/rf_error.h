/*
 * rf_error.h — the error of a reflectance-field model against its dataset
 * (rf/rf_error.c), which the fits and the RF report report. A header of its
 * own: the report includes it without the rest of rf.h. Private to the
 * library.
 */
#ifndef BTF_RF_ERROR_H
#define BTF_RF_ERROR_H

#include "btfcar.h"

/* Table 1 of the paper: the mean |Y data - Y model| over every texel and
 * (view, light) image of ds, the model evaluated at the measured directions;
 * mean_luminance: the data's. The dataset must have the model's direction
 * sets, and its size unless the model is sampled: then data texel (x, y)
 * is compared with surface texel (x, y), wrapped, as the flat render shows
 * it (no correspondence outside the sample's own place). */
btf_status btf__rf_error(const btf_dataset *ds, const btf_rf_model *m, int threads,
                         double *mean_abs_error, double *mean_luminance, btf_error *err);

/* The same over the images the model measured of a dataset that holds more
 * (some directions held out of the analysis): view_of[v] and light_of[l]
 * give the model's index of the dataset's view v and light l, or -1 for a
 * held-out one, whose images are skipped. NULL maps: btf__rf_error. */
btf_status btf__rf_error_over(const btf_dataset *ds, const btf_rf_model *m, const int *view_of,
                              const int *light_of, int threads, double *mean_abs_error,
                              double *mean_luminance, btf_error *err);

#endif
