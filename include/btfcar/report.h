/*
 * btfcar/report.h — measuring a model: texture distances and the
 * phase-randomisation baseline, the report page with its compression and
 * quality accounting, the speed/accuracy sweep, the library page.
 * Part of the public C API of btfcar; include/btfcar.h includes every
 * topical header, and its conventions (docs/api.md) hold here too.
 */
#ifndef BTFCAR_REPORT_H
#define BTFCAR_REPORT_H

#include "base.h"
#include "image.h"
#include "dataset.h"
#include "model.h"
#include "analyse.h"
#include "gpu.h"

#include <stdint.h>

/* What this header declares is part of the ABI of libbtfcar.so: the library
 * is compiled with -fvisibility=hidden, and the declarations of the public
 * headers alone are exported (docs/install.md, "Shared library and soname"). */
#pragma GCC visibility push(default)

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------- texture distances */

/* Distances between two colour textures without pixel correspondence
 * (src/measure/, docs/measure.md): any two sizes, each side at least 16.
 * Both images are measured in CIE Lab (linear RGB converted by OpenCV;
 * values above 1 scaled by one exposure the reference fixes, 1 / its
 * largest value, the same for both; negative values count as 0). */
typedef struct btf_texture_distance_opts {
    size_t struct_size; /* sizeof the struct (set by the defaults); 0: this header's */
    int levels;                 /* structure: pyramid levels; 0: as many as
                                   the smallest view compared allows (bands of
                                   at least 8 pixels), at most 6 */
    const char *reference_name; /* start the error messages (NULL: "reference") */
    const char *image_name;     /* (NULL: "image") */
} btf_texture_distance_opts;
/* levels 0, both names NULL (a zeroed struct behaves the same). */
btf_texture_distance_opts btf_texture_distance_defaults(void);

/* One component: raw (its own unit, docs/measure.md), self (the same
 * distance between disjoint crops of the reference: the mean over the six
 * pairs of its four quadrants, times sqrt((1/Nref + 1/Nimg) / (2/Nquadrant))
 * for the sample sizes, N the pixels; 1/2 for equal sizes) and normalised
 * = raw / max(self, floor) (1.0: as close as the material is to itself;
 * floor, per component, keeps a constant reference finite). */
typedef struct btf_distance_component {
    double raw, self, normalised;
} btf_distance_component;

typedef struct btf_texture_distances {
    btf_distance_component spectrum;    /* (a) radially binned log power
                                           spectrum of luminance Y, weighted
                                           RMS, dB */
    btf_distance_component first_order; /* (b) earth mover's distance of each
                                           Lab channel's values, mean of 3 */
    btf_distance_component structure;   /* (c) Laplacian-pyramid band
                                           statistics, mean absolute difference */
    double combined;                    /* mean of the three normalised values */
    double first_order_lab[3];          /* raw EMD of L*, a*, b* alone */
    int spectrum_bins;                  /* rings of width 1/s cycles/pixel, s the
                                           smallest side compared; s / 2 rings */
    int levels;                         /* pyramid levels compared */
    double exposure;                    /* the scale applied before Lab */
} btf_texture_distances;

/* ref: the material (1 or 3 channels); img: what is compared with it.
 * Deterministic; every value finite. BTF_E_ARG for a side below 16 (naming
 * the image and its size), BTF_E_DATA for a non-finite pixel. */
btf_status btf_texture_distance(const btf_image *ref, const btf_image *img,
                                const btf_texture_distance_opts *opts,
                                btf_texture_distances *out, btf_error *err);

/* The baseline to beat (src/measure/phase_randomise.c, docs/measure.md,
 * "Phase-randomisation baseline"): a Gaussian texture with the exemplar's
 * power spectrum. The colours are decorrelated as the model does (mean,
 * PCA basis); each decorrelated channel's periodic component (Moisan's
 * periodic + smooth decomposition, which removes the border cross from
 * the spectrum) keeps its DFT amplitude and gets independent random
 * phases, Hermitian-symmetric so that the result is real; the
 * decorrelation is undone. The texture is made at the exemplar's size and
 * is periodic: other sizes wrap it (tile it, or crop it). seed chooses the
 * phases; the same seed gives the same image. out: width x height, the
 * exemplar's channel count (1 or 3). */
btf_status btf_phase_randomise(const btf_image *exemplar, int width, int height, uint64_t seed,
                               btf_image *out, btf_error *err);
/* The storage the baseline needs for a width x height exemplar: per colour
 * channel the non-redundant half of the amplitude spectrum, height x
 * (width / 2 + 1) float32 (about width x height / 2), for 3 channels, plus
 * the mean colour and the 3 x 3 basis (12 float32). */
uint64_t btf_phase_randomise_bytes(int width, int height);

/* ---------------------------------------- report: compression accounting */
/* What a model file costs, section by section, and what two plain codecs
 * would store for the same data (src/report/, docs/report.md): the
 * report's options of its per-view PCA contrast. */

/* The pixel-wise contrast: per view, a PCA of its n_lights images. Values
 * are the images' sRGB encoding clamped to [0, 1] and scaled to 0..255 (for
 * 8-bit files exactly the stored values). c is the smallest number of
 * components whose RMS error over the view's values (from the discarded
 * eigenvalues) is at most max_rms; stored: the mean image, c eigen-images and
 * n_lights x c weights, each value in `bits` bits (docs/report-compression.md). */
typedef struct btf_pca_opts {
    size_t struct_size; /* sizeof the struct (set by the defaults); 0: this header's */
    double max_rms;         /* 0: 2.0, in 8-bit sRGB levels */
    int bits;               /* bits per stored value, 1..32; 0: 16 */
    int max_components;     /* cap on c per view, 1..n_lights; 0: n_lights */
    int threads;            /* 0: the number of online CPUs */
    btf_progress_fn progress;
    void *progress_user;
} btf_pca_opts;
/* The defaults: max_rms 2.0, bits 16, max_components 0 (no cap: n_lights),
 * threads 0 (all CPUs), no progress. */
btf_pca_opts btf_pca_defaults(void);

/* ---------------------------------------- report: quality per direction */
/* How close the model comes to the measurement, pair by pair, measured by
 * the texture distances above (src/report/, docs/report.md). */

typedef struct btf_quality_opts {
    size_t struct_size; /* sizeof the struct (set by the defaults); 0: this header's */
    int all;                  /* 1: every (view, light) pair of the dataset */
    int views, lights;        /* the spread measured when not all: this many views and
                                 lights, evenly strided through each set's order
                                 (docs/report.md; 0: 9 each; more than the
                                 dataset has: all of them) */
    uint64_t seed;            /* synthesis seed of the flat renders (0 is a seed) */
    double relief;            /* range map height scale of the flat renders, as
                                 btf_render_opts.relief (< 0: 1; 0: off) */
    int threads;              /* 0: all CPUs */
    btf_progress_fn progress;
    void *progress_user;
    /* Called once per measured pair with the measured image and the model's
     * flat render of it (both linear RGB, the dataset's size), from worker
     * threads and so possibly at the same time for different pairs; a
     * non-zero btf_status return (with err filled) stops the measurement.
     * NULL: none. */
    btf_status (*on_pair)(void *user, int pair, int view, int light, const btf_image *measured,
                          const btf_image *model, btf_error *err);
    void *on_pair_user;
} btf_quality_opts;
/* The defaults: the 9 x 9 spread, seed 0, relief 1, all CPUs, no callbacks. */
btf_quality_opts btf_quality_defaults(void);

/* ---------------------------------------------- report: sweep, the page */
/* The speed/accuracy trade measured over a grid of settings (the presets
 * of btfcar/analyse.h were chosen from it), and the report page
 * (src/report/, docs/report.md). */

/* One setting of the trade: the analysis options a sweep varies (0: the
 * analysis's automatic choice). */
typedef struct btf_sweep_setting {
    int subspaces;            /* K; 0: auto */
    int levels;               /* pyramid levels; 0: auto */
    int neighbours;           /* a fixed neighbourhood of the first n candidate
                                 offsets (the Bayesian choice's candidate
                                 family, nearest first; docs/model.md); 0: the
                                 Bayesian choice */
    int plain;                /* 1: no structure layer and no pair gains (a
                                 64-texel range tile: format 1.3's model,
                                 docs/model.md); 0: the analysis's layers */
    int range_size;           /* the range map's longer side (analyse
                                 --range-size); 0: the analysed resolution
                                 (with the structure layer). Plain points: 0 */
} btf_sweep_setting;

typedef struct btf_sweep_point {
    btf_sweep_setting setting;
    int k;                    /* subspaces the analysis made */
    double analyse_s;         /* this setting's analysis: segmentation of the shared
                                 features, the CAR fits and marginals (the shared
                                 features and range map: btf_sweep.shared_s) */
    double synth_s;           /* CPU synthesis of every subspace image at
                                 synth_size^2, one thread */
    double gpu_synth_s;       /* the same on the GPU; < 0: not measured */
    double render_s;          /* the sphere frame (btf_scene_sphere) at
                                 render_size^2, one thread, CPU */
    uint64_t bytes;           /* the model file */
    double mean_combined, worst_combined; /* quality per direction over the
                                             spread, the mean over the seeds */
    double seed_spread;       /* the standard deviation of mean_combined between the
                                 seeds (0 with one) */
    int is_default;           /* the setting equals the analysis defaults */
    int pareto_bytes;         /* on the front of (bytes, mean_combined) */
    int pareto_time;          /* on the front of (synth_s, mean_combined) */
    int resumed;              /* read back from the state folder, not measured now */
    int missing;              /* not measured: another share's point
                                 (btf_sweep_opts.share_count), not in the state
                                 folder; its figures are 0 and it is on no front */
} btf_sweep_point;

#define BTF_SWEEP_MAX_VALUES 8
#define BTF_SWEEP_MAX_SEEDS 128
typedef struct btf_sweep_opts {
    size_t struct_size; /* sizeof the struct (set by the defaults); 0: this header's */
    int n_subspaces, subspaces[BTF_SWEEP_MAX_VALUES];  /* values of K (0: auto);
                                                          n 0: {0, 2, 4, 8} */
    int n_levels, levels[BTF_SWEEP_MAX_VALUES];        /* n 0: {0, 1, 2, 3} */
    int n_neighbours, neighbours[BTF_SWEEP_MAX_VALUES];/* n 0: {0, 4, 8, 12} */
    int n_plain, plain[2];                             /* btf_sweep_setting.plain;
                                                          n 0: {0} */
    int n_range_sizes, range_sizes[BTF_SWEEP_MAX_VALUES]; /* btf_sweep_setting
                                                          .range_size (0, or
                                                          4..4096); n 0: {0} */
    btf_analyse_opts analyse;  /* the base settings the grid varies */
    btf_quality_opts quality;  /* the pairs measured per point (threads ignored) */
    int seeds;                 /* each point's quality measured with synthesis seeds
                                  quality.seed .. + seeds - 1 and averaged (one seed's
                                  figure moves by about 1 %: more than many of the
                                  grid's steps); 0: 3; 1..128 */
    int synth_size;            /* 0: 512 */
    int render_size;           /* 0: 256 */
    btf_gpu *gpu;              /* NULL: no GPU times */
    const char *state_dir;     /* finished points are kept here, one JSON file each,
                                  and read back by a later run (resume); NULL: none */
    int threads;               /* settings run in parallel; 0: all CPUs */
    /* Beyond one process (docs/cluster.md): with share_count N > 0 this run
     * measures only the points i with i % N == share_index (0 <= I < N; the
     * grid's order, deterministic: the N shares do not overlap and together
     * are the grid); the others are read back from state_dir where there,
     * else marked missing. resume_only 1 measures nothing: every point must
     * be in state_dir, else BTF_E_DATA naming the missing settings (the
     * merge of the shares' points). */
    int share_index, share_count;
    int resume_only;
    btf_progress_fn progress;
    void *progress_user;
} btf_sweep_opts;
/* The defaults: the grids above (4 x 4 x 4 = 64 settings), the analysis and
 * quality defaults, 3 seeds, sizes 512 and 256, no GPU, no state folder, all
 * CPUs. */
btf_sweep_opts btf_sweep_defaults(void);

/* The speed/accuracy trade (docs/report.md, "The sweep"): the dataset
 * analysed under every setting of the grid, each model timed (analysis,
 * synthesis, the sphere frame), sized and measured (quality per
 * direction); the Pareto fronts marked. The features and the range map are
 * computed once and shared. Settings run in parallel, one per thread; each
 * finished point is written to state_dir at once, so an interrupted sweep
 * resumes where it stopped (a point whose file names another dataset or
 * other sweep options is measured again). */
typedef struct btf_sweep {
    int n_points;
    btf_sweep_point *points;   /* by structure (on, off), range size, K, levels,
                                  neighbours */
    double shared_s;           /* features and photometric stereo, once */
    double seconds;            /* the whole sweep */
    int resumed;               /* points read back from state_dir */
    int n_missing;             /* points of other shares, not there yet */
    int seeds;                 /* the seeds each point was measured with */
} btf_sweep;
/* Frees a sweep's points and zeroes it; NULL and a zeroed sweep are fine. */
void btf_sweep_free(btf_sweep *s);

/* The points of a sweep whose shares wrote to separate folders, copied
 * into one state folder (created; its parent must exist) before the merge
 * (docs/cluster.md): each DIR/sweep/point-*.json (DIR a report folder) or
 * DIR/point-*.json (DIR a state folder). Files are copied as they are
 * (each carries its options' fingerprint: the merge reads back only its
 * own); a later folder's file replaces an earlier one of the same name.
 * *copied: the files copied. BTF_E_IO naming a folder that cannot be read. */
btf_status btf_sweep_gather(const char *const *dirs, int n, const char *state_dir, int *copied,
                            btf_error *err);

/* The library report (docs/cluster.md, "A material library"): DIR/index.html
 * and DIR/library.json with one row per material — model bytes, ratio,
 * mean and worst combined distance, pairs, the report's time, the preview
 * and a link to the material's report — read from the n report folders
 * btf_report_write made (their report.json), measuring nothing. All
 * folders are read first: missing or unreadable ones are named together
 * (BTF_E_IO or BTF_E_DATA) and nothing is written. *rows: n on success. */
btf_status btf_library_write(const char *const *reports, int n, const char *dir, int *rows,
                             btf_error *err);

/* The report (docs/report.md): DIR/index.html, self-contained (PNG
 * pictures and SVG plots beside it, no scripts, nothing fetched), and
 * DIR/report.json with the same numbers (keys: docs/report.md). */
typedef struct btf_report_opts {
    size_t struct_size; /* sizeof the struct (set by the defaults); 0: this header's */
    const char *dataset_name;    /* shown; NULL: the dataset's root */
    const char *model_name;      /* shown; NULL: "model" */
    btf_quality_opts quality;    /* the pairs measured (all or the spread), seed, relief */
    btf_dir sphere_light;        /* the preview's light in the camera's frame; both 0 and
                                    sphere_light_set 0: theta 45, phi 135 (upper left) */
    int sphere_light_set;
    int sphere_size;             /* the preview's side in pixels; 0: 384 */
    int worst;                   /* the worst pairs shown with pictures; 0: 6 */
    btf_pca_opts pca;            /* the per-view PCA contrast */
    int jpeg_quality;            /* the JPEG contrast; 0: 90 */
    int sweep;                   /* 1: measure the trade (btf_sweep; its finished
                                    points are kept in DIR/sweep/ and resumed) */
    btf_sweep_opts sweep_opts;   /* the grid and its options (state_dir is set here) */
    int threads;                 /* 0: all CPUs */
    btf_progress_fn progress;
    void *progress_user;
} btf_report_opts;
/* The defaults: the 9 x 9 spread of pairs, the preview lit from (45, 135) at
 * 384 px, the 6 worst pairs, the PCA and sweep defaults, JPEG quality 90,
 * no sweep, all CPUs. */
btf_report_opts btf_report_defaults(void);
/* The sweep of btf_report_write alone, its points written to DIR/sweep/ and
 * nothing else (no page, no report.json): what one task of a sweep split
 * over machines runs (opts->sweep_opts.share_index, share_count:
 * docs/cluster.md); the same options give the points btf_report_write's
 * sweep would, so a later btf_report_write with sweep_opts.resume_only
 * (the merge) reads them back. Free *out with btf_sweep_free. */
btf_status btf_report_sweep_points(const btf_dataset *ds, const char *dir,
                                   const btf_report_opts *opts, btf_sweep *out,
                                   btf_error *err);

/* What a report found, for the command's summary. */
typedef struct btf_report_summary {
    uint64_t model_bytes, raw_bytes;
    double ratio;                /* raw_bytes / model_bytes */
    int pairs;                   /* measured */
    double mean_combined, worst_combined;
    int held_out;                /* pairs the model did not measure */
    double mean_held_out;        /* their mean combined distance */
    int sweep_points, sweep_resumed;
    double seconds;
    double mean_abs_error;       /* btf__rf_report_write only: mean |Y data - Y model| over
                                    every texel and image (the paper's Table 1);
                                    0 for a CAR report */
    double mean_luminance;       /* the data's mean luminance (RF reports only) */
} btf_report_summary;

/* Writes the report of model m (analysed from ds) into the folder dir:
 * compression (the model file by part, per-view PCA and JPEG contrasts),
 * quality per sampled (view, light) pair with pictures and a heat map, the
 * preview sphere, and with opts->sweep the measured trade. The report's
 * files appear as a whole (btf_output_dir_*); the sweep's state folder is
 * written as it goes, so that an interrupted report resumes its sweep.
 * summary may be NULL. */
btf_status btf_report_write(const btf_dataset *ds, const btf_model *m, const char *dir,
                            const btf_report_opts *opts, btf_report_summary *summary,
                            btf_error *err);

#ifdef __cplusplus
}
#endif

#pragma GCC visibility pop
#endif /* BTFCAR_REPORT_H */
