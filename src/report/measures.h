/*
 * measures.h — what the report measures (src/report/, docs/report.md),
 * called by the report pages, the sweep and the tests: the compression
 * accounting (the model file by part, the raw BTF, the per-view PCA and
 * subspace-JPEG contrasts), quality per direction, and the sweep itself.
 * The public entries are btf_report_write, btf_report_sweep_points and
 * btf__rf_report_write (btfcar/report.h). Private to the library.
 */
#ifndef BTF_REPORT_MEASURES_H
#define BTF_REPORT_MEASURES_H

#include "btfcar.h"
#include "model/model.h" /* btf_model_part */

#include <stdint.h>

/* -------------------------------------------------- compression accounting */

/* A short name of a part ("gammas", ...); "?" out of range. */
const char *btf__model_part_name(int part);

typedef struct btf_model_bytes {
    uint64_t total;         /* the encoded file's size (btf_model_encode) */
    uint64_t payload;       /* its payload before deflate */
    int deflated;           /* 1: the payload is stored deflated, 0: stored as is */
    /* Bytes of the file by part; they add up to total exactly. A deflated
     * payload's bits are given to the payload bytes they code: a literal's
     * code to its byte, a match's length and distance codes (with their
     * extra bits) shared evenly by the bytes it copies; the sums in bits
     * are rounded to whole bytes by largest remainder. */
    uint64_t file[BTF_MODEL_PART_COUNT];
    /* Bytes of the payload by part before deflate; they add up to payload.
     * (CONTAINER and DEFLATE are 0 here.) */
    uint64_t raw[BTF_MODEL_PART_COUNT];
} btf_model_bytes;

/* Encodes m (btf_model_encode: same bytes) and accounts for every byte of
 * the file. BTF_E_DATA when m cannot be encoded. */
btf_status btf__model_byte_breakdown(const btf_model *m, btf_model_bytes *out, btf_error *err);

/* The raw BTF a dataset holds: what the report's ratios divide (also
 * filled into the PCA and JPEG results below). */
typedef struct btf_raw_bytes {
    int views, lights, width, height;
    uint64_t raw;           /* views x lights x width x height x 3, one byte per value */
    uint64_t on_disk;       /* btf_dataset_info.bytes_on_disk: the image files' sizes */
} btf_raw_bytes;
btf_status btf__dataset_raw_bytes(const btf_dataset *ds, btf_raw_bytes *out, btf_error *err);

typedef struct btf_pca_result {
    int views, lights, width, height;
    int *components;        /* [views]: c of each view (malloc'd) */
    double *view_rms;       /* [views]: each view's RMS error, 8-bit levels (malloc'd) */
    int min_components, max_components;
    double mean_components; /* over the views */
    double rms;             /* over every value of the dataset, 8-bit levels */
    uint64_t bytes;         /* sum over views of (W H 3 (1 + c) + n_lights c) x bits / 8, rounded up per view */
    btf_raw_bytes raw;
    double ratio;           /* raw.raw / bytes */
    double seconds;         /* wall-clock time of the call */
} btf_pca_result;

/* Views in parallel (opts->threads), one view's images in memory per
 * thread; the results do not depend on the thread count. opts NULL: the
 * defaults. Free out with btf__pca_result_free (NULL and twice are fine). */
btf_status btf__pca_contrast(const btf_dataset *ds, const btf_pca_opts *opts,
                             btf_pca_result *out, btf_error *err);
void btf__pca_result_free(btf_pca_result *r);

/* The subspace-image contrast: each subspace's representative measured image
 * (m->subspaces[k].view, .light, read from ds) encoded as JPEG in memory,
 * plus the index table (views x lights bytes, one per pair, uncompressed). */
typedef struct btf_jpeg_contrast {
    int images;             /* the subspaces */
    int quality;            /* the JPEG quality used */
    uint64_t jpeg_bytes;    /* the JPEGs together */
    uint64_t index_bytes;   /* views x lights */
    uint64_t bytes;         /* jpeg_bytes + index_bytes */
    double rms;             /* the JPEGs' error against the images, 8-bit sRGB levels */
    btf_raw_bytes raw;
    double ratio;           /* raw.raw / bytes */
} btf_jpeg_contrast;

/* quality 1..100; 0: 90. The model must be a BTF model of ds (same view and
 * light counts, subspace pairs in range); BTF_E_DATA otherwise. */
btf_status btf__jpeg_subspace_contrast(const btf_dataset *ds, const btf_model *m, int quality,
                                       btf_jpeg_contrast *out, btf_error *err);

/* -------------------------------------------------- quality per direction */

typedef struct btf_pair_quality {
    int view, light;          /* dataset indices */
    int subspace;             /* the model's index-table entry for the pair; -1
                                 for a pair the model did not measure */
    int held_out;             /* 1: the model did not measure the pair (left out
                                 of its analysis): its render interpolates */
    btf_texture_distances d;  /* measured image (reference) against the flat render */
    double mean_abs_dy;       /* pixel by pixel: mean |Y measured - Y render| (Rec. 709
                                 luminance of linear RGB); the render is at the
                                 capture's size, its structure layer registered */
    double luminance;         /* the measured image's mean luminance */
} btf_pair_quality;

typedef struct btf_quality {
    int n_pairs;
    btf_pair_quality *pairs;  /* view-major: by view index, then light index */
    double mean_combined, median_combined, worst_combined; /* over the pairs the
                                 model measured (all, unless some are held out) */
    int worst;                /* index into pairs of the largest combined distance */
    double mean_spectrum, mean_first_order, mean_structure; /* normalised, over pairs */
    int n_held_out;           /* pairs the model did not measure, measured apart */
    double mean_held_out;     /* their mean combined distance (0 without) */
    double mean_abs_dy;       /* the pairs' mean_abs_dy over the measured pairs, */
    double mean_held_out_abs_dy; /* over the held-out ones (0 without), */
    double mean_luminance;    /* and the measured images' mean luminance */
    int texture_size;         /* side of the synthesised tileable subspace images */
    double seconds;           /* the whole measurement */
} btf_quality;

/* How close the model comes to the measurement in every sampled (view,
 * light) pair (docs/report.md, "Quality per direction"): the measured
 * image against the model's flat render of that pair (btf_render_flat:
 * the same pixels), by btf_texture_distance. The model's subspace images
 * are synthesised once, tileable, at the dataset's image size; each pair
 * is shaded and measured on the pool. The model must be of this
 * dataset's direction sets (BTF_E_ARG otherwise). */
btf_status btf__quality_measure(const btf_dataset *ds, const btf_model *m,
                                const btf_quality_opts *opts, btf_quality *out, btf_error *err);
void btf__quality_free(btf_quality *q);
/* Pixel by pixel, measured image against a render of its size (both
 * families' reports: the CAR render's structure layer is registered with
 * the capture, the reflectance field keeps every texel): the mean |dY| of
 * Rec. 709 luminance of linear RGB and the measured image's mean luminance;
 * a non-finite measured value counts as 0; both 0 when the images are not
 * two RGB images of one size. */
void btf__pixelwise_dy(const btf_image *meas, const btf_image *model, double *mean_abs_dy,
                       double *mean_y);
/* The spread: indices of n directions of set, evenly strided through the
 * set's order (ring by ring from the pole, phi ascending in a ring):
 * idx[i] = floor(i count / n), so every ring gets its share and the
 * azimuths vary. n is clamped to 1..set->count; returns the count written
 * to idx. */
int btf__spread_directions(const btf_dirset *set, int n, int *idx);

/* -------------------------------------------------------------- the sweep */

/* The speed/accuracy trade over opts' grid (btf_sweep in btfcar/report.h
 * says what it measures; quality by btf__quality_measure). Free out with
 * btf_sweep_free. */
btf_status btf__sweep_run(const btf_dataset *ds, const btf_sweep_opts *opts, btf_sweep *out,
                          btf_error *err);

#endif
