/*
 * measure.h — texture distances without pixel correspondence 
 * (docs/measure.md) and the phase-randomisation baseline. Private to the
 * library. Every descriptor is computed on a view: a rectangle of an image
 * already converted to CIE Lab (measure/lab.c), so that the reference, its
 * quadrants (the normalisation) and the compared image share one code path.
 */
#ifndef BTF_MEASURE_H
#define BTF_MEASURE_H

#include "btfcar.h"

#include <stddef.h>

/* Pyramid levels of the structure component: at most this many. */
#define MS_MAX_LEVELS 6
/* Neighbour offsets whose correlation each band reports: (dy, dx). */
#define MS_OFFSETS 4
/* Images smaller than this on either side are refused (BTF_E_ARG): the
 * reference's quadrants must be at least 8 x 8 for a spectrum of 4 bins and
 * one pyramid band. */
#define MS_MIN_SIDE 16

/* The floats per pixel of a measured image: L*, a*, b* (L* in [0, 100])
 * and the linear luminance Y (exposure-scaled, not clamped). */
#define MS_CH 4
#define MS_Y 3

/* A rectangle of a measured image (MS_CH floats per pixel). */
typedef struct ms_view {
    const float *lab;
    int stride;          /* pixels per row of the whole image */
    int x0, y0, w, h;
} ms_view;

/* Statistics of one band-pass band (measure/band_stats.c). */
typedef struct ms_band {
    double log_variance; /* ln(variance + MS_VARIANCE_FLOOR) */
    double skewness;     /* 0 for a band of (near) zero variance */
    double log_kurtosis; /* ln(m4 / var^2), ln 3 for a degenerate band */
    double rho[MS_OFFSETS];
} ms_band;

/* What one view holds for all three components. */
typedef struct ms_desc {
    double *spectrum;    /* bins 1..nbins at [k - 1] (10 log10 power, dB) */
    int nbins;
    float *sorted[3];    /* each Lab channel's values, ascending */
    size_t n;            /* pixels of the view */
    ms_band bands[MS_MAX_LEVELS];
    int levels;
} ms_desc;

/* measure/lab.c: the image (1 or 3 channels, linear) as MS_CH floats per
 * pixel: Lab of each value multiplied by scale and clamped to [0, 1] (the
 * OpenCV conversion's range), and Y of the scaled values. Non-finite
 * pixels are an error naming `name`. */
btf_status ms_lab(const btf_image *img, double scale, const char *name, float **lab,
                  btf_error *err);
/* The exposure the reference fixes for both images: 1 / its largest value
 * when that exceeds 1, else 1. */
double ms_exposure(const btf_image *ref);

/* measure/spectrum.c: the radially binned log power spectrum of the view's
 * luminance Y, Hann-windowed, bins of width 1/s cycles per pixel
 * (k = 1 .. nbins = s / 2). out holds nbins values. */
btf_status ms_spectrum(const ms_view *v, int s, double *out, btf_error *err);
double ms_spectrum_distance(const double *a, const double *b, int nbins);

/* measure/first_order.c: each Lab channel of the view, sorted (sorted[c]
 * holds w*h floats), and the mean over channels of the exact 1D earth
 * mover's (Wasserstein-1) distance; per_channel (may be NULL) gets each. */
void ms_sort_channels(const ms_view *v, float *sorted[3]);
double ms_emd_1d(const float *a, size_t na, const float *b, size_t nb);
double ms_first_order_distance(const ms_desc *a, const ms_desc *b, double per_channel[3]);

/* measure/band_stats.c: `levels` band-pass bands of the view's L channel
 * and their statistics. */
btf_status ms_band_stats(const ms_view *v, int levels, ms_band *out, btf_error *err);
double ms_structure_distance(const ms_band *a, const ms_band *b, int levels);
#define MS_VARIANCE_FLOOR 1e-6

/* measure/descriptor.c: all of a view's descriptors (s, the smallest side
 * of the views compared, fixes the s / 2 spectrum bins; levels the bands),
 * and their release. */
btf_status ms_describe(const ms_view *v, int s, int levels, ms_desc *d, btf_error *err);
void ms_desc_free(ms_desc *d);

/* measure/periodic.c: the periodic component of a w x h real image (Moisan
 * 2011, "Periodic plus smooth image decomposition"), in place. */
btf_status ms_periodic_component(double *u, int w, int h, btf_error *err);

#endif
