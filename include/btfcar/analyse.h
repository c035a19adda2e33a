/*
 * btfcar/analyse.h — analysis, from a dataset to a model: segmentation into
 * subspace images, photometric stereo, the CAR fit, the whole analysis and
 * its presets; the reflectance-field fit.
 * Part of the public C API of btfcar; include/btfcar.h includes every
 * topical header, and its conventions (docs/api.md) hold here too.
 */
#ifndef BTFCAR_ANALYSE_H
#define BTFCAR_ANALYSE_H

#include "base.h"
#include "image.h"
#include "dataset.h"
#include "model.h"

#include <stdint.h>

/* What this header declares is part of the ABI of libbtfcar.so: the library
 * is compiled with -fvisibility=hidden, and the declarations of the public
 * headers alone are exported (docs/install.md, "Shared library and soname"). */
#pragma GCC visibility push(default)

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------ analyse, stage 1: segmentation */
/* Paper section II.A: the (view, light) images are clustered by k-means on
 * their CIE Lab cumulative histograms; each cluster is represented by the
 * member image closest to its centre (a real measured image). */

typedef struct btf_feature_opts {
    size_t struct_size; /* sizeof the struct (set by the defaults); 0: this header's */
    int bins;                 /* per channel; 0: 32 */
    int threads;              /* 0: all CPUs */
    btf_progress_fn progress;
    void *progress_user;
    /* NULL, or the caller's (views x lights) x 3 floats that get each
     * image's mean linear RGB, read in the same pass (the pair gains of
     * btf_analyse, docs/model.md "Pair gains") */
    float *means;
} btf_feature_opts;
/* The defaults: 32 bins, threads 0 (all CPUs), no progress. */
btf_feature_opts btf_feature_defaults(void);

typedef struct btf_kmeans_opts {
    size_t struct_size; /* sizeof the struct (set by the defaults); 0: this header's */
    int restarts;             /* 0: 5; the best run by distortion is kept */
    int max_iter;             /* 0: 100 Lloyd iterations per run */
    uint64_t seed;            /* 0 is a valid seed */
} btf_kmeans_opts;
/* The defaults: 5 restarts, 100 iterations, seed 0. */
btf_kmeans_opts btf_kmeans_defaults(void);

typedef struct btf_segment_opts {
    size_t struct_size; /* sizeof the struct (set by the defaults); 0: this header's */
    int subspaces;            /* K; 0: auto */
    int max_subspaces;        /* cap for auto; 0: 20 (the paper's bound) */
    double auto_threshold;    /* auto: smallest K whose distortion is at most
                                 this fraction of the K = 1 distortion; 0: 0.10 */
    double split_gain;        /* auto, past the threshold: K grows while one
                                 more subspace removes at least this fraction
                                 of the distortion left; 0: 0.12, < 0: off */
    btf_feature_opts features;
    btf_kmeans_opts kmeans;
    /* Segmenting features computed before (inside the library) only: NULL
     * (every pair measured), or [view * n_lights + light] non-zero for the
     * pairs a sparse set holds; the others' feature rows are ignored and
     * their index is BTF_PAIR_NONE. btf_segment sets it from the dataset. */
    const unsigned char *present;
} btf_segment_opts;
/* The defaults: K auto, at most 20, threshold 0.10, split gain 0.12, and
 * the defaults of features and k-means. */
btf_segment_opts btf_segment_defaults(void);

/* The index table's entry of a pair that was not measured (a sparse set). */
#define BTF_PAIR_NONE 255

typedef struct btf_segmentation {
    int n_views, n_lights;
    int k;                    /* subspaces */
    uint8_t *index;           /* [view * n_lights + light] -> subspace id;
                                 BTF_PAIR_NONE: a pair the set does not hold */
    int *rep_view, *rep_light;/* per subspace: its representative image */
    int *members;             /* per subspace: number of images */
    double distortion;        /* of the chosen clustering */
    double *distortion_by_k;  /* [0..max_k]: distortions tried (0: not tried) */
    int max_k;
    char reason[256];         /* why this K (one line) */
    float *means;             /* [(view * n_lights + light) * 3]: each image's mean
                                 linear RGB (btf_segment; NULL when segmented
                                 from features computed before) */
} btf_segmentation;

btf_status btf_segment(const btf_dataset *ds, const btf_segment_opts *opts,
                       btf_segmentation *out, btf_error *err);
void btf_segmentation_free(btf_segmentation *s);

/* The index table as a picture like the paper's Fig. 5: x = view index,
 * y = light index, one colour per subspace, each cell cell x cell pixels
 * (0: 6). Written atomically. */
btf_status btf_segmentation_write_png(const btf_segmentation *s, int cell, const char *path,
                                      btf_error *err);

/* ------------------------------- analyse, stage 2: photometric stereo */
/* Paper section II.B: the range map of the material is recovered by
 * photometric stereo from the images of one view under many lights. Normals
 * and albedo come from a robust Lambertian least-squares fit per pixel
 * (Woodham 1980); the normals are integrated into a height field. Directions
 * and normals share one frame: x right, y UP in the image (the row index
 * grows towards -y), z towards the camera — the frame of btf_dir_to_vec.
 * Method, robust rule and fallback: docs/photostereo.md. */

typedef enum btf_integrate_method {
    BTF_INTEGRATE_DEFAULT = 0, /* the default: BTF_INTEGRATE_POISSON */
    BTF_INTEGRATE_POISSON,     /* least squares, Neumann boundary: DCT solve
                                  (Simchony et al. 1990); conjugate gradients
                                  preconditioned by it when a mask has holes */
    BTF_INTEGRATE_FC           /* Frankot & Chellappa 1988: FFT with the
                                  central-difference derivative; treats the
                                  surface as periodic (procedural tiles are,
                                  measured patches are not) */
} btf_integrate_method;

typedef struct btf_integrate_opts {
    size_t struct_size; /* sizeof the struct (set by the defaults); 0: this header's */
    btf_integrate_method method; /* default: BTF_INTEGRATE_POISSON */
    double max_slope;   /* default 10; |dz/dx| and |dz/dy| are clamped to it,
                           so normals near the horizon (n_z -> 0) stay finite */
    double tolerance;   /* default 1e-7; relative residual at which the masked
                           Poisson solver stops */
    int max_iter;       /* default 2000 conjugate-gradient iterations at most */
} btf_integrate_opts;

/* The defaults above; a zero field of btf_integrate_opts means the same. */
btf_integrate_opts btf_integrate_defaults(void);

/* Options of photometric stereo. Each field's default is given; a zero
 * field means that default, a negative one switches a rule off where said. */
typedef struct btf_photostereo_opts {
    size_t struct_size; /* sizeof the struct (set by the defaults); 0: this header's */
    double dark;          /* default 0.1; samples below dark x the pixel's
                             reference level (its brightest after the top 5 %)
                             are shadowed and excluded; < 0: no dark rule */
    double trim_low;      /* default 0 (none); fraction of the darkest samples
                             left out of the first fit */
    double trim_high;     /* default 0.1; fraction of the brightest samples left
                             out of the first fit (highlights); < 0: none */
    double outlier;       /* default 2; samples more than this many robust
                             standard deviations below the fit (twice as
                             many above it) are excluded */
    double saturation;    /* default 0.99, at most 1: a fraction of full scale;
                             a sample with any raw channel at or above
                             saturation x full scale is excluded (clipped).
                             Full scale is 1 (the white of 8- and 16-bit
                             files) for data within it, else the images'
                             largest value (HDR or scaled linear data are
                             clipped, if at all, at their peak); < 0: no such
                             rule */
    double max_condition; /* default 1e4; largest condition number of sum l l^T
                             accepted, for the whole light set (else an error)
                             and per pixel (else the fallback) */
    double specular_cone; /* default 20; degrees: a sample brighter than the fit
                             whose half vector (of the light and the view
                             (0, 0, 1)) lies within this angle of the normal
                             is a highlight and excluded; < 0: no such rule */
    int iterations;       /* default 5 reweighting passes at most; < 0: none */
    int plain;            /* 1: plain least squares on every unsaturated sample
                             (Woodham), no robust rule: for comparison */
    const btf_image *mask; /* NULL: every pixel; else an image of the images'
                             size (1 or 3 channels) whose non-zero pixels are
                             worked on: every output is 0 elsewhere */
    btf_integrate_opts integrate; /* how the height is integrated */
    btf_read_opts read;   /* how files are decoded (manifest, dataset):
                             read.linear_8bit for linear 8-bit data; the
                             channels field is ignored (files give RGB) */
    int threads;          /* 0: all CPUs */
    btf_progress_fn progress;
    void *progress_user;
} btf_photostereo_opts;

/* The defaults above (no mask, all CPUs, no progress); a zeroed
 * btf_photostereo_opts gives the same results. */
btf_photostereo_opts btf_photostereo_defaults(void);

/* Images in memory for btf_photostereo: `count` >= 3 images of one size and
 * channel count (1 or 3), image i lit from lights[3 i .. 3 i + 2] (any
 * length, normalised here; not all (nearly) coplanar). */
typedef struct btf_ps_input {
    const btf_image *images;
    int count;
    const double *lights;    /* count x 3 */
    const double *intensity; /* NULL, or count x 3 positive RGB light
                                intensities that are divided out */
} btf_ps_input;

typedef struct btf_ps_result {
    btf_image normal;      /* W x H x 3: unit normals (x, y, z); 0 outside the mask */
    btf_image albedo;      /* W x H x C (C of the inputs), light intensity divided out */
    btf_image height;      /* W x H x 1: range map, pixel units, zero mean in the mask */
    btf_image lights_used; /* W x H x 1: lights in the pixel's final fit (0: fallback) */
    btf_image valid;       /* W x H x 1: 1 fitted from >= 3 lights, 0 fallback or outside */
    int pixels;            /* inside the mask */
    int fitted, fallback;  /* pixels with a fit / with the fallback normal (0, 0, 1) */
    double condition;      /* condition number of sum l l^T over all lights */
    int view;              /* dataset, manifest with views: the view used; -1 otherwise */
    btf_dir view_dir;
} btf_ps_result;

/* Photometric stereo on images in memory. opts: NULL for the defaults;
 * opts->mask restricts the work, opts->integrate the height. On failure out
 * holds nothing to free. */
btf_status btf_photostereo(const btf_ps_input *in, const btf_photostereo_opts *opts,
                           btf_ps_result *out, btf_error *err);
/* The same on a BTF dataset or from a manifest, with the view chosen.
 * A dataset: the images of one view under all its lights (btf_dir_to_vec),
 * read one at a time; in a sparse set only views with at least 3 lights
 * count, and only the lights the set holds there are used; with no such
 * view, BTF_E_DATA saying so. A manifest: a TSV file with a header line
 * naming its columns: path (relative to the manifest's folder, or
 * absolute), the light either as theta_l, phi_l (degrees) or as lx, ly, lz
 * (a vector in the frame above), optionally r, g, b (the light's
 * intensity), and optionally theta_v, phi_v (a BTF manifest of several
 * views; each (view, light) pair once). A path listed twice is an error.
 * Either uses the images of its view nearest `view` (within 5 degrees, else
 * BTF_E_ARG), or with view NULL of its view nearest the normal (smallest
 * theta_v). out->view and out->view_dir say which (view: its index in the
 * dataset, or among the manifest's distinct views in the order of first
 * appearance). */
btf_status btf_photostereo_dataset_view(const btf_dataset *ds, const btf_dir *view,
                                        const btf_photostereo_opts *opts, btf_ps_result *out,
                                        btf_error *err);
btf_status btf_photostereo_manifest_view(const char *path, const btf_dir *view,
                                         const btf_photostereo_opts *opts, btf_ps_result *out,
                                         btf_error *err);
void btf_ps_result_free(btf_ps_result *r);

/* Writes normals.exr, albedo.exr, height.exr (float) and normals.png,
 * albedo.png, height.png into outdir (created if missing), each file
 * atomically. The PNGs are previews for people: normals as RGB (n + 1) / 2
 * (the usual normal-map colours), the range map as a shaded relief (lit
 * from the top left, exaggerated to a fixed mean slope, tinted by height;
 * mask: NULL or the mask of the run, outside which it is black). */
btf_status btf_ps_write(const btf_ps_result *r, const btf_image *mask, const char *outdir,
                        btf_error *err);

/* ------------------------------------------- analyse, stage 3: the CAR fit */

/* A CAR fit warns "... the model misses N% of the band's variance ..." when
 * synthesis would give at least this fraction less than the band's variance
 * (a periodic pattern; `btfcar info` reports it too, so a quiet caller that
 * drops warnings still finds it there). */
#define BTF_CAR_MISSED_LOUD 0.2
#define BTF_CAR_MISSED_TEXT "the model misses"

typedef struct btf_car_fit_opts {
    size_t struct_size; /* sizeof the struct (set by the defaults); 0: this header's */
    int n_fixed;                          /* 0: choose by the Bayesian rule */
    btf_offset fixed[BTF_CAR_MAX_NEIGHBOURS];
    int max_neighbours;                   /* auto: largest candidate; 0: 24 */
    double coefficient_bits;              /* auto: prior odds 2^-bits per
                                             coefficient (what the file pays
                                             for it); 0: equal odds */
    btf_warning_fn warn;
    void *warn_user;
    const char *what;                     /* names the sub-band in warnings */
} btf_car_fit_opts;
/* The defaults: the Bayesian choice among candidates of at most 24
 * neighbours at equal prior odds, no warnings callback. */
btf_car_fit_opts btf_car_fit_defaults(void);

typedef struct btf_fit_opts {
    size_t struct_size; /* sizeof the struct (set by the defaults); 0: this header's */
    int levels;               /* pyramid levels 1..BTF_MAX_LEVELS; 0: auto (docs/model.md) */
    int max_auto_levels;      /* auto: at most this many; 0: 3 (the paper's bound) */
    const float *masking;     /* auto: NULL, or (the image's size) the factor the
                                 render multiplies this image's luminance by
                                 (its structure layer); the levels are then
                                 chosen for the product (docs/model.md) */
    btf_car_fit_opts car;     /* neighbourhood (fixed or auto), warnings */
} btf_fit_opts;
/* The defaults: levels 0 (auto, at most 3), car = btf_car_fit_defaults(). */
btf_fit_opts btf_fit_defaults(void);

/* A model of one ordinary colour texture: one subspace, no directions, no
 * index table, no range map. */
btf_status btf_texture_fit(const btf_image *img, const btf_fit_opts *opts, btf_model *out,
                           btf_error *err);

/* What btf_analyse decided on the way, for reports to people; the model
 * itself holds the results. (A new field is an ABI change: docs/install.md.) */
typedef struct btf_analyse_report {
    char segment_reason[256]; /* why this number of subspaces (one line, as
                                 btf_segmentation.reason) */
    char structure_reason[384]; /* which structure layers were kept and why
                                   (one line, docs/model.md "Structure") */
} btf_analyse_report;

typedef struct btf_analyse_opts {
    size_t struct_size; /* sizeof the struct (set by the defaults); 0: this header's */
    btf_segment_opts segment;         /* stage 1 */
    btf_photostereo_opts photostereo; /* stage 2 (its own threads field: 0, all CPUs) */
    btf_fit_opts fit;                 /* stage 3; fit.car.warn also gets stage 2's
                                         warning when most pixels fall back to the
                                         flat normal (BTF_RANGE_FLAT_TEXT) */
    int no_range;                     /* 1: no range map in the model */
    int range_size;                   /* longer side of the range tile; 0: the image's
                                         (texel 1, with the structure layer); a smaller
                                         tile has no structure layer; docs/photostereo.md */
    int no_structure;                 /* 1: no structure layer (the CAR fields model
                                         the whole exemplar, as before format 1.4) */
    int no_shadows;                   /* 1: the structure layer's shading casts no
                                         shadows (as format 1.4) */
    btf_progress_fn progress;         /* stage progress (features, fits) */
    void *progress_user;
    btf_analyse_report *report;       /* NULL, or filled in when btf_analyse succeeds */
    /* Work shared between analyses of one dataset (the sweep of
     * btf_report_write): features (NULL: computed) are the dataset's
     * segmentation features (each image's CIE Lab cumulative histograms of
     * segment.features.bins bins), feature_dim floats per image;
     * range_from (NULL: photometric stereo) is a model of the same dataset
     * whose range tile is copied. */
    const float *features;
    int feature_dim;
    const float *means;               /* with features: the images' mean RGB (as
                                         btf_segmentation.means); NULL: read again */
    const btf_model *range_from;
    int no_gains;                     /* 1: no pair gains (before format 1.5) */
    int no_cells;                     /* 1: no periodic cells of the remainders where
                                         the structure repeats on a lattice (before
                                         format 1.7; docs/model.md, "Periodic cells") */
} btf_analyse_opts;
/* The defaults: those of each stage's options, a range map with a 64-texel
 * tile, no progress, no report. */
btf_analyse_opts btf_analyse_defaults(void);
/* In the warning of an analysis whose photometric stereo left most pixels
 * without a fit (docs/photostereo.md, "Fallback"): a flat range map. */
#define BTF_RANGE_FLAT_TEXT "the range map is nearly flat"

/* All analysis stages on a dataset (paper section II): segmentation into
 * subspace images, the range map by photometric stereo (view closest to
 * theta_v = 0), and the CAR model of every subspace image. The range tile
 * keeps the image's aspect ratio: one scale, range_texel, for both axes. */
btf_status btf_analyse(const btf_dataset *ds, const btf_analyse_opts *opts, btf_model *out,
                       btf_error *err);

/* Named points of the trade for btfcar analyse --preset (docs/report.md,
 * "Presets"): "fast", "balanced" (the defaults) or "accurate" set the
 * subspaces, levels and neighbourhood of o; BTF_E_ARG for another name. */
btf_status btf_analyse_preset(const char *name, btf_analyse_opts *o, btf_error *err);
/* The preset names, NULL-terminated. */
const char *const *btf_analyse_preset_names(void);

/* ------------------------------------------ the reflectance-field fit */

/* Where a fit spent its time and how well it did (NULL: not wanted). */
typedef struct btf_rf_fit_info {
    double read_s, fit_s, seconds;  /* decoding the images, fitting, in all */
    double mean_abs_error;          /* mean |Y data - Y model| over every texel and
                                       image, with the quantised parameters */
    double mean_luminance;          /* the data's mean luminance */
    long long lm_runs, lm_iterations; /* Levenberg-Marquardt solves and their steps */
    /* btf_rf_fit_sampled only (paper section 6); then mean_abs_error and
     * mean_luminance are over every image and texel of the dataset through
     * the coordinate map, seconds the whole call's. */
    double sample_mean_abs_error; /* the fit's error on the sample's own texels
                                     (per-view fits; 0 for lafortune) */
    double sample_s;              /* reading the head-on view, choosing the sample */
    double quilt_s;               /* synthesising the coordinate map */
    double error_s;               /* the error pass over the dataset */
    int quilt_block, quilt_overlap; /* the block and overlap sides used */
} btf_rf_fit_info;

typedef struct btf_rf_opts {
    size_t struct_size; /* sizeof the struct (set by the defaults); 0: this header's */
    int fit;            /* btf_rf_fit_kind; 0: PTM */
    int lobes;          /* k for lobes and lafortune, 1..BTF_RF_MAX_LOBES; 0: 2 */
    int iterations;     /* Levenberg-Marquardt steps per texel at most; 0: 40 */
    int threads;        /* 0: all CPUs */
    size_t memory;      /* lafortune: bytes of luminance held at once (texel rows
                           are fitted in passes over the dataset); 0: 256 MiB */
    btf_rf_fit_info *info; /* NULL, or filled */
    btf_progress_fn progress;
    void *progress_user;
    /* Fit only the window of crop_width x crop_height texels at (crop_x,
     * crop_y) of the dataset's images (crop_width and crop_height 0: every
     * texel); the model has the window's size. A texel's fit depends only on
     * its data, so a window's codes are the whole fit's texels requantised
     * over the window. btf_rf_fit_sampled fits its sample so. */
    int crop_x, crop_y, crop_width, crop_height;
} btf_rf_opts;
/* The defaults: PTM, 2 lobes, 40 iterations, all CPUs, 256 MiB, no crop. */
btf_rf_opts btf_rf_defaults(void);

/* Fits the dataset: per view, the n_lights images are read (one view's
 * lights at a time; lafortune: every image, texel rows in passes bounded by
 * opts->memory), converted to luminance Y = 0.2126 R + 0.7152 G + 0.0722 B,
 * and every texel fitted in parallel (the result does not depend on the
 * thread count). Dark, saturated and constant texels give finite fits. A
 * sparse set is BTF_E_DATA (the family fits every light at each view). */
btf_status btf_rf_fit(const btf_dataset *ds, const btf_rf_opts *opts, btf_rf_model *out,
                      btf_error *err);

/* Memory reduction as in the paper's section 6: the fields are fitted on a
 * small sample of the material only, and a coordinate map from a texture
 * synthesis of the sample (image quilting, Efros & Freeman 2001, the
 * paper's reference 6, with the minimum-error boundary cut) says which
 * sample texel every texel of the surface shows, so that the model's size
 * is the sample's coefficients plus the map (docs/rf.md, "Memory
 * reduction"). The synthesis runs on one representative image, the
 * head-on view's Lambertian fit b = rho n over its lights (albedo and
 * relief orientation), so that one map serves every view and light. The
 * sample keeps its place: the surface's texels under it map to themselves
 * (the data's pixel correspondence holds there, and only there). */
typedef struct btf_rf_sample_opts {
    size_t struct_size; /* sizeof the struct (set by the defaults); 0: this header's */
    int width, height;          /* the sample's texels, 1..the images' sides (required) */
    int placed;                 /* 1: the sample's window is at (x, y); 0: the window
                                   whose statistics (mean and spread of the
                                   representative image's channels) are closest to
                                   the whole image's (the first on ties) */
    int x, y;
    int surface_width, surface_height; /* the map's size, 1..BTF_RF_MAX_SURFACE_SIDE;
                                   0: the dataset's */
    int block;                  /* the quilting block's side; 0: half the sample's
                                   shorter side, at most 32 (at least 1) */
    int overlap;                /* the blocks' overlap, 1..block / 2; 0: block / 4
                                   (0 for blocks under 4: a plain random tiling) */
    double tolerance;           /* candidates within (1 + tolerance) of the best
                                   overlap error are drawn from; 0: 0.1 */
    uint64_t seed;              /* the quilting's draws; same seed, same map */
} btf_rf_sample_opts;
#define BTF_RF_MAX_SURFACE_SIDE 8192
/* The defaults: every field 0 (an unset size is BTF_E_ARG). */
btf_rf_sample_opts btf_rf_sample_defaults(void);
/* Fits the dataset's sample (btf_rf_fit with the crop of so's window; opts
 * as btf_rf_fit's, its crop ignored) and synthesises the coordinate map of
 * the surface; opts->info (NULL: not wanted) gets the fit's figures, the
 * sample's and the map's, and the error over the whole dataset through the
 * map (one more pass over the images). A sample of the whole image on a
 * surface of the image's size gives the identity map and the whole fit's
 * codes. Deterministic for a seed, for any thread count. */
btf_status btf_rf_fit_sampled(const btf_dataset *ds, const btf_rf_opts *opts,
                              const btf_rf_sample_opts *so, btf_rf_model *out,
                              btf_error *err);

#ifdef __cplusplus
}
#endif

#pragma GCC visibility pop
#endif /* BTFCAR_ANALYSE_H */
