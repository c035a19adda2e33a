/*
 * range.h — the range-map stage's internals (src/range/; Haindl & Filip
 * 2007, section II.B): robust Lambertian photometric stereo and its parts,
 * and the range map a model keeps. Private to the library.
 *
 * The files and who calls whom (no file calls back into one that calls it):
 *
 *   photostereo.c  the public entry points, options, the light set, the run
 *     -> ps_sources.c  images in memory or decoded from files; the mask
 *     -> ps_passes.c   the two passes over the images: grey samples, albedo
 *          -> ps_sources.c
 *     -> ps_solve.c    every pixel's fit, rows spread over the thread pool
 *          -> ps_fit.c     the robust fit of one pixel
 *               -> order.c   order statistics (3x3 algebra: core/linalg.c)
 *     -> core/linalg.c the conditioning of the whole light set
 *     -> integrate.c   normals to heights (public: btf__integrate)
 *   ps_manifest.c  manifest files -> photostereo.c
 *   ps_write.c     the result on disk -> ps_preview.c (previews) -> ps_sources.c
 *
 * The range map the model keeps (public calls in include/btfcar.h; none of
 * these calls the photometric stereo above):
 *
 *   range_code.c      its grid and prediction coding in the model file
 *                     (model/range_code.h; model/model_file.c's RANG
 *                     section and the analysis call it)
 *   range_periodic.c  the tile made periodic -> range_code.c
 *   range_map.c       the tile enlarged to a seamless height and normal map
 *                     of any size; a quilted model's maps come from its
 *                     structure layer (model/structure_map.c)
 */
#ifndef BTF_RANGE_H
#define BTF_RANGE_H

#include "btfcar.h"
#include "core/linalg.h" /* btf_sym3: the normal equations of every fit */

#include <stdint.h>

/* -------------------------------------------- order statistics: order.c */

/* The k-th smallest of a[0..n-1] (0-based); reorders a. */
double btf__select_kth(double *a, int n, int k);
/* Sorts a[0..n-1] ascending, in place, without allocating. */
void btf__sort_small(double *a, int n);

/* ------------------------------------------ the pixel fit: ps_fit.c */

/* The options of btf_photostereo_opts with defaults and special values
 * resolved (photostereo.c), as the fit uses them. */
typedef struct btf_ps_params {
    double dark;          /* shadow threshold, fraction of the reference level; 0: none */
    double trim_low, trim_high;
    double outlier;
    double saturation;    /* fraction of full scale (btf__ps_full_scale); INFINITY: no
                             saturation rule */
    double max_condition;
    double specular_cos;  /* cos of the specular cone; > 1: no highlight rule */
    int iterations;
    int plain;
} btf_ps_params;

/* One thread's working memory for the fits of `count` samples per pixel. */
typedef struct btf_ps_scratch {
    double *values;          /* count: sample values to sort or select in */
    double *residuals;       /* count */
    unsigned char *unshadowed; /* count flags: candidates the shadow rules keep */
    unsigned char *in_fit;   /* count flags: the samples of the current fit */
    unsigned char *next_fit; /* count flags: the set a reweighting step proposes */
    double *row_samples;     /* width x count: one image row, pixel-major */
} btf_ps_scratch;
btf_status btf__ps_scratch_alloc(btf_ps_scratch *s, int count, int width, btf_error *err);
void btf__ps_scratch_free(btf_ps_scratch *s);

/* The robust fit of one pixel: samples[i] its grey value under the unit
 * light lights[3 i..] (negative: saturated), halfway[3 i..] the unit half
 * vector of that light and the view. 1: *scaled_normal = albedo x normal
 * and s->in_fit flags the samples of the final fit; 0: no fit (fallback). */
int btf__ps_fit_pixel(const btf_ps_params *params, const double *lights, const double *halfway,
                      int count, const double *samples, btf_ps_scratch *s,
                      double scaled_normal[3]);
/* The samples from which the fallback normal (0, 0, 1) takes its albedo. */
void btf__ps_fallback_set(const double *lights, int count, const double *samples,
                          unsigned char *in_fit);

/* -------------------------------------- every pixel's fit: ps_solve.c */

/* The fit of a whole image: inputs, outputs and counts. */
typedef struct btf_ps_solve {
    int width, height, count;
    int set_words;             /* 64-bit words per pixel in fit_sets */
    const double *lights;      /* count x 3, unit */
    const double *halfway;     /* count x 3, unit half vectors with the view (0, 0, 1) */
    const float *grey;         /* count x (width x height), image-major; < 0: saturated */
    const unsigned char *inside; /* width x height flags: the mask */
    btf_ps_params params;
    float *normal;             /* width x height x 3 */
    float *lights_used, *valid; /* width x height each */
    uint64_t *fit_sets;        /* (width x height) x set_words: samples of each fit */
    int fitted, fallback;      /* pixel counts, set by btf__ps_solve_all */
} btf_ps_solve;
/* Fits every pixel inside the mask over `threads` threads (0: all CPUs);
 * progress (may be NULL) runs from `from` to `to`. */
btf_status btf__ps_solve_all(btf_ps_solve *job, int threads, btf_progress_fn progress,
                             void *progress_user, double from, double to, btf_error *err);

/* ------------------------------------------ image sources: ps_sources.c */

/* Where the images come from: memory, or files decoded on demand (once per
 * pass, so that a dataset never has all its images in memory). */
typedef struct btf_ps_source {
    const char *name;          /* for messages: "photostereo", a manifest, a dataset */
    int count;
    const btf_image *images;   /* in memory, or NULL */
    const char *const *paths;  /* files otherwise */
    const btf_dataset *ds;     /* or a dataset's images of one view (a .btf file
                                  has no file per image): read with btf_dataset_read */
    int view;
    const int *light_of;       /* with ds: image i is light light_of[i] (a sparse
                                  set's lights at that view); NULL: light i */
    btf_read_opts read;
    int width, height, channels; /* 0 x 0 for files until btf__ps_source_probe */
} btf_ps_source;
/* The size of a file source from its first image's header. */
btf_status btf__ps_source_probe(btf_ps_source *src, btf_error *err);
/* Image i: a pointer into memory, or decoded into *tmp, zero-initialised
 * or holding the previous image (a .btf file's image reuses its buffer;
 * free it after the last). */
btf_status btf__ps_source_get(const btf_ps_source *src, int i, btf_image *tmp,
                              const btf_image **img, btf_error *err);
/* inside[k] = 1 where the mask (NULL: everywhere) is non-zero and finite in
 * any channel; *pixels counts them. An error names `name` when the mask does
 * not fit a width x height image. */
btf_status btf__ps_mask_inside(const char *name, const btf_image *mask, int width, int height,
                               unsigned char *inside, int *pixels, btf_error *err);

/* The view photometric stereo uses among n distinct view directions: the
 * one nearest `want` (NULL: nearest the normal, smallest theta, the first
 * of equals, as analyse does) into *view. BTF_E_ARG naming `name` when
 * want is more than BTF_PS_VIEW_TOL degrees from every view. */
#define BTF_PS_VIEW_TOL 5.0
btf_status btf__ps_pick_view(const btf_dir *dirs, int n, const btf_dir *want, const char *name,
                             int *view, btf_error *err);

/* -------------------------------------- passes over images: ps_passes.c */

/* Pass 1: every image's grey samples into grey (count x width x height),
 * a sample with a raw channel >= clip marked saturated; progress 0 .. 0.4
 * for files. peak: NULL, or gets the largest finite raw value inside the
 * mask (0 when there is none). */
btf_status btf__ps_pass_grey(const btf_ps_source *src, const double *intensity, double clip,
                             const unsigned char *inside, float *grey, double *peak,
                             const btf_photostereo_opts *o, btf_error *err);
/* Full scale of images whose largest raw value is peak: 1, the white of
 * 8- and 16-bit files, for data within it; the peak itself for data beyond
 * it (HDR, linear data in other units), which cannot have been clipped
 * below their own maximum (docs/photostereo.md, "The robust rule"). */
double btf__ps_full_scale(double peak);
/* Pass 2: the colour albedo of every pixel with its normal fixed, over the
 * samples of its fit; progress 0.5 .. 0.9 for files. */
btf_status btf__ps_pass_albedo(const btf_ps_source *src, const double *intensity,
                               const btf_ps_solve *job, btf_image *albedo,
                               const btf_photostereo_opts *o, btf_error *err);
/* o->progress, if any. */
void btf__ps_report(const btf_photostereo_opts *o, double fraction, const char *what);

/* -------------------------------------------- the run: photostereo.c */

/* The whole stage on a source lit by lights (count x 3, any length) with
 * intensity (NULL or count x 3); a file source's size comes from its first
 * image. Fills out, which the caller has cleared. */
btf_status btf__ps_run(btf_ps_source *src, const double *lights, const double *intensity,
                       const btf_photostereo_opts *o, btf_ps_result *out, btf_error *err);
/* Clears out for a call (view -1); BTF_E_ARG when out is NULL. */
btf_status btf__ps_result_start(btf_ps_result *out, btf_error *err);

/* --------------------------- the stage's parts the library and tests share */

/* Integrates a normal map (3 channels x, y, z in the frame of
 * btfcar/analyse.h) into a height field in pixel units: dz/dcolumn =
 * -n_x/n_z, dz/drow = +n_y/n_z.
 * mask: NULL (every pixel) or an image of the same size whose non-zero
 * pixels are valid. opts: NULL for the defaults. Output: 1 channel, zero
 * mean over the valid pixels, 0 elsewhere; never NaN. A zero normal
 * (0, 0, 0) counts as flat. */
btf_status btf__integrate(const btf_image *normals, const btf_image *mask,
                          const btf_integrate_opts *opts, btf_image *height, btf_error *err);

/* btf_photostereo_dataset_view and btf_photostereo_manifest_view with view
 * NULL: the images of the view nearest the normal (smallest theta_v). */
btf_status btf__photostereo_dataset(const btf_dataset *ds, const btf_photostereo_opts *opts,
                                    btf_ps_result *out, btf_error *err);
btf_status btf__photostereo_manifest(const char *path, const btf_photostereo_opts *opts,
                                     btf_ps_result *out, btf_error *err);
/* The most lights the dataset holds at any one view (photometric stereo
 * needs 3). */
int btf__photostereo_best_lights(const btf_dataset *ds);
/* Previews for people: normals as RGB (n + 1) / 2 (the usual normal-map
 * colours once 8-bit encoded), and the range map as a shaded relief (lit
 * from the top left, exaggerated to a fixed mean slope, tinted by height;
 * mask: NULL or the mask of the run, outside which it is black). Both are
 * linear RGB for btf_image_write_png. */
btf_status btf__normals_preview(const btf_image *normals, btf_image *out, btf_error *err);
btf_status btf__height_relief(const btf_image *height, const btf_image *mask, btf_image *out,
                              btf_error *err);

#endif
