/*
 * btfcar.h — the public C API of btfcar, a toolkit for probabilistic modelling
 * of Bidirectional Texture Functions (Haindl & Filip, TPAMI 2007).
 *
 * Conventions (see docs/api.md):
 *  - every fallible call returns a btf_status (0 = success, negative = error) and,
 *    when given a non-NULL btf_error, fills it with one line naming the file, the
 *    value and what was expected. The library never prints and never exits.
 *  - option structs are valid when zero-initialised; zero means "default".
 *  - images are linear float, channels interleaved, row 0 at the top.
 *  - directions are in degrees: theta from the surface normal (z), phi the
 *    azimuth measured from +x towards +y.
 */
#ifndef BTFCAR_H
#define BTFCAR_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define BTF_VERSION_MAJOR 0
#define BTF_VERSION_MINOR 1
#define BTF_VERSION_PATCH 0
#define BTF_VERSION_STRING "0.1.0"

/* ------------------------------------------------------------------ errors */

typedef enum btf_status {
    BTF_OK = 0,
    BTF_E_ARG = -1,         /* invalid argument or option value */
    BTF_E_IO = -2,          /* a file could not be opened, read or written */
    BTF_E_FORMAT = -3,      /* a file is not what it claims to be, or is truncated */
    BTF_E_DATA = -4,        /* content is inconsistent (missing pair, sizes differ, NaN) */
    BTF_E_NOMEM = -5,       /* an allocation failed */
    BTF_E_UNSUPPORTED = -6, /* a valid request this build cannot serve */
    BTF_E_NUMERIC = -7      /* a computation could not produce a finite answer */
} btf_status;

typedef struct btf_error {
    int code;        /* the btf_status of the failure */
    char msg[1024];  /* one line, no trailing newline */
} btf_error;

/* A short name of a status code ("I/O error", ...). */
const char *btf_status_name(int status);

/* Progress report for long work: fraction in [0, 1]; what names the step. */
typedef void (*btf_progress_fn)(void *user, double fraction, const char *what);

/* ------------------------------------------------------------------ images */

typedef struct btf_image {
    int width, height, channels; /* channels: 1 (grey) or 3 (RGB) */
    float *data;                 /* width*height*channels floats, row-major */
} btf_image;

int btf_image_alloc(btf_image *img, int width, int height, int channels, btf_error *err);
void btf_image_free(btf_image *img);

typedef enum btf_file_format {
    BTF_FILE_UNKNOWN = 0,
    BTF_FILE_PNG,
    BTF_FILE_JPEG,
    BTF_FILE_EXR
} btf_file_format;

/* Format from the file's signature bytes (never from its name). */
btf_file_format btf_file_format_of(const char *path);

typedef struct btf_image_header {
    btf_file_format format;
    int width, height;
    int channels;       /* channels in the file (before conversion) */
    int bits;           /* 8 or 16 for PNG/JPEG, 16 (half) or 32 for EXR */
    uint64_t file_bytes;
} btf_image_header;

/* Reads the header only and checks the file's structure (a JPEG must end with
 * its end-of-image marker, a PNG with its IEND chunk): cheap, no decoding. */
int btf_image_probe(const char *path, btf_image_header *hdr, btf_error *err);

typedef struct btf_read_opts {
    int channels;       /* 0: 3 for colour files, 1 for grey; 1 or 3 forces it */
    int linear_8bit;    /* 0 (default): 8-bit files are sRGB and are linearised;
                           1: 8-bit values are taken as linear (v/255) */
    int srgb_16bit;     /* 0 (default): 16-bit PNG is linear (v/65535); 1: sRGB */
} btf_read_opts;

/* Reads PNG (8/16-bit), JPEG or EXR (half/float) into linear float. EXR values
 * that are NaN or Inf are an error (BTF_E_DATA) naming the file. */
int btf_image_read(const char *path, const btf_read_opts *opts, btf_image *out,
                   btf_error *err);

/* Writers are atomic: a temporary file beside `path` is renamed over it. PNG
 * and JPEG encode linear values to 8-bit sRGB (clamped to [0, 1]); EXR stores
 * linear values as half (half != 0) or float. */
int btf_image_write_png(const char *path, const btf_image *img, btf_error *err);
int btf_image_write_jpeg(const char *path, const btf_image *img, int quality,
                         btf_error *err);
int btf_image_write_exr(const char *path, const btf_image *img, int half,
                        btf_error *err);

/* sRGB transfer function (IEC 61966-2-1), per value. */
float btf_srgb_to_linear(float v);
float btf_linear_to_srgb(float v);

/* -------------------------------------------------------------- directions */

typedef struct btf_dir {
    double theta; /* degrees from the normal, [0, 90] */
    double phi;   /* degrees, [0, 360) */
} btf_dir;

typedef struct btf_dirset {
    char name[32]; /* "ubo81", "ubo151" or "custom" */
    int count;
    btf_dir *dirs; /* ring by ring (theta ascending), phi ascending in a ring */
} btf_dirset;

/* The Bonn/UTIA 81-direction sampling: theta 0,15,...,75 with 1,6,12,18,20,24
 * azimuths evenly spaced from phi = 0. */
int btf_dirset_ubo81(btf_dirset *set, btf_error *err);
/* The UBO2014 151-direction dome (per-ring azimuth offsets). */
int btf_dirset_ubo151(btf_dirset *set, btf_error *err);
/* A custom set from a list; sorted ring by ring, phi ascending, duplicates
 * (within 1e-6 degree) merged. If the list equals a known set it is named so. */
int btf_dirset_from_list(btf_dirset *set, const btf_dir *dirs, int count,
                         btf_error *err);
int btf_dirset_copy(btf_dirset *dst, const btf_dirset *src, btf_error *err);
void btf_dirset_free(btf_dirset *set);
/* Index of the direction within tol degrees (angle between unit vectors) or -1. */
int btf_dirset_find(const btf_dirset *set, btf_dir d, double tol_deg);

/* (theta, phi) in degrees <-> unit vector; z is the surface normal. A vector
 * on the pole gets phi = 0; phi is normalised to [0, 360). */
void btf_dir_to_vec(btf_dir d, double v[3]);
btf_dir btf_vec_to_dir(const double v[3]);
/* Angle in degrees between two directions. */
double btf_dir_angle(btf_dir a, btf_dir b);

/* ----------------------------------------------------------------- datasets */

typedef enum btf_layout {
    BTF_LAYOUT_UNKNOWN = 0,
    BTF_LAYOUT_UBO2003,  /* "NNNNN tlAAA plBBB tvCCC pvDDD.jpg", per-view folders or flat */
    BTF_LAYOUT_UTIA,     /* tvCCC_pvDDD/tlAAA_plBBB_tvCCC_pvDDD.(png|exr) */
    BTF_LAYOUT_MANIFEST  /* TSV: path theta_l phi_l theta_v phi_v */
} btf_layout;

const char *btf_layout_name(btf_layout layout);

typedef struct btf_dataset btf_dataset; /* opaque */

typedef struct btf_dataset_info {
    btf_layout layout;
    const char *root;           /* the folder (or manifest) that was opened */
    int n_views, n_lights;      /* images = n_views * n_lights */
    int width, height;          /* of every image */
    int channels;               /* in the files */
    btf_file_format format;     /* of the first image */
    const btf_dirset *views;    /* view directions, in index order */
    const btf_dirset *lights;   /* light directions, in index order */
    uint64_t bytes_on_disk;     /* sum of all image file sizes */
} btf_dataset_info;

typedef struct btf_dataset_opts {
    int skip_verify;         /* 0: probe every image (size, structure); 1: only the first */
    btf_progress_fn progress;
    void *progress_user;
} btf_dataset_opts;

/* Detects the layout of `path` (a folder, or a manifest .tsv file), collects
 * the (light, view) pairs and checks that the set is complete (every light
 * with every view, each pair once) and that every image has one size. */
int btf_dataset_open(const char *path, const btf_dataset_opts *opts,
                     btf_dataset **out, btf_error *err);
void btf_dataset_close(btf_dataset *ds);
const btf_dataset_info *btf_dataset_get_info(const btf_dataset *ds);
/* The file holding (view, light); NULL when out of range. */
const char *btf_dataset_path(const btf_dataset *ds, int view, int light);
/* Decodes one image to linear float RGB (3 channels). */
int btf_dataset_read(const btf_dataset *ds, int view, int light, btf_image *out,
                     btf_error *err);

/* Streaming: hands out one (light, view) image at a time, view-major. */
typedef struct btf_sample {
    int view, light;       /* indices into info->views / info->lights */
    btf_dir view_dir, light_dir;
    const char *path;
    btf_image image;       /* owned by the iterator; valid until the next call */
} btf_sample;

typedef struct btf_dataset_iter {
    const btf_dataset *ds;
    int next;              /* running index, view * n_lights + light */
    btf_sample sample;
} btf_dataset_iter;

void btf_dataset_iter_begin(btf_dataset_iter *it, const btf_dataset *ds);
/* 1: a sample was produced; 0: the end; < 0: an error (the iterator stays
 * usable, the failing image is skipped on the next call). */
int btf_dataset_iter_next(btf_dataset_iter *it, btf_error *err);
void btf_dataset_iter_end(btf_dataset_iter *it);

/* Reads and decodes every image once (catches corrupt data, NaN/Inf in EXR). */
int btf_dataset_verify_pixels(const btf_dataset *ds, btf_progress_fn progress,
                              void *user, btf_error *err);

/* ------------------------------------------------------ procedural materials */

/* A material: a periodic height field (in texel units) with an albedo and the
 * parameters of its reflectance (Lambertian + one specular lobe). */
typedef struct btf_material {
    char name[32];
    int size;               /* width = height = size texels */
    float *height;          /* size*size, texel units, periodic */
    float *normal;          /* size*size*3, unit vectors, z up */
    float *albedo;          /* size*size*3, linear RGB */
    float specular;         /* specular albedo */
    float shininess;        /* Blinn-Phong exponent of the lobe */
    float fresnel0;         /* reflectance of the coat at normal incidence (0: none) */
    float ambient;          /* fraction of light reaching shadowed points */
} btf_material;

/* Names of the built-in materials, NULL-terminated: leather, fabric, wood. */
const char *const *btf_material_names(void);
int btf_material_make(const char *name, int size, uint64_t seed, btf_material *m,
                      btf_error *err);
void btf_material_free(btf_material *m);

/* Renders the rectified image the BTF measures for one (view, light) pair:
 * for every texel of the reference plane, the view ray finds the visible
 * surface point (masking, parallax), which is lit by the light unless the
 * height field casts a shadow on it. Output: linear RGB, size x size. */
int btf_material_render(const btf_material *m, btf_dir view, btf_dir light,
                        btf_image *out, btf_error *err);

typedef struct btf_generate_opts {
    int size;               /* 0: 128 */
    uint64_t seed;          /* 0 is a valid seed */
    int jpeg_quality;       /* 0: 95 */
    int threads;            /* 0: the number of online CPUs */
    btf_progress_fn progress;
    void *progress_user;
} btf_generate_opts;

/* Writes the 81 x 81 images of a material in the UBO2003 layout under outdir
 * (per-view folders), and outdir/truth/{height,normals,albedo}.exr. */
int btf_generate(const char *material, const char *outdir,
                 const btf_generate_opts *opts, btf_error *err);

/* ------------------------------------------ analyse, stage 1: segmentation */
/* Paper section II.A: the (view, light) images are clustered by k-means on
 * their CIE Lab cumulative histograms; each cluster is represented by the
 * member image closest to its centre (a real measured image). */

/* A deterministic random stream (splitmix64) for seeded choices. */
typedef struct btf_rng {
    uint64_t state;
} btf_rng;
void btf_rng_seed(btf_rng *r, uint64_t seed);
uint64_t btf_rng_next(btf_rng *r);
double btf_rng_uniform(btf_rng *r); /* [0, 1), 53 bits */

typedef struct btf_feature_opts {
    int bins;                 /* per channel; 0: 32 */
    int threads;              /* 0: all CPUs */
    btf_progress_fn progress;
    void *progress_user;
} btf_feature_opts;

/* Fixed ranges of the histograms: L* [0, 100], a* and b* [-64, 64] (values
 * outside are counted in the end bins). */
#define BTF_LAB_A_RANGE 64.0f

/* The feature of one linear-RGB image: the cumulative histograms of L*, a*,
 * b* (each normalised to end at 1), concatenated: 3 * bins floats. */
int btf_lab_cumhist(const btf_image *img, int bins, float *feature, btf_error *err);

/* Features of every image of a dataset, streamed (one image decoded at a time
 * per thread): features[(view * n_lights + light) * dim + i], dim = 3 * bins. */
int btf_dataset_features(const btf_dataset *ds, const btf_feature_opts *opts,
                         float **features, int *dim, btf_error *err);

typedef struct btf_kmeans_opts {
    int restarts;             /* 0: 5; the best run by distortion is kept */
    int max_iter;             /* 0: 100 Lloyd iterations per run */
    uint64_t seed;            /* 0 is a valid seed */
} btf_kmeans_opts;

typedef struct btf_kmeans_result {
    int k;                    /* clusters produced: min(k asked, distinct points) */
    int *labels;              /* n: cluster of each point, 0..k-1 */
    float *centres;           /* k * dim; never NaN */
    double distortion;        /* sum of squared distances to the centres */
} btf_kmeans_result;

/* k-means with k-means++ seeding and restarts. k larger than the number of
 * distinct points is reduced to it; clusters that go empty are re-seeded at
 * the point farthest from its centre. Same inputs and seed, same result. */
int btf_kmeans(const float *points, int n, int dim, int k, const btf_kmeans_opts *opts,
               btf_kmeans_result *out, btf_error *err);
void btf_kmeans_free(btf_kmeans_result *r);

typedef struct btf_segment_opts {
    int subspaces;            /* K; 0: auto */
    int max_subspaces;        /* cap for auto; 0: 20 (the paper's bound) */
    double auto_threshold;    /* auto: smallest K whose distortion is at most
                                 this fraction of the K = 1 distortion; 0: 0.10 */
    btf_feature_opts features;
    btf_kmeans_opts kmeans;
} btf_segment_opts;

typedef struct btf_segmentation {
    int n_views, n_lights;
    int k;                    /* subspaces */
    uint8_t *index;           /* [view * n_lights + light] -> subspace id */
    int *rep_view, *rep_light;/* per subspace: its representative image */
    int *members;             /* per subspace: number of images */
    double distortion;        /* of the chosen clustering */
    double *distortion_by_k;  /* [0..max_k]: distortions tried (0: not tried) */
    int max_k;
    char reason[256];         /* why this K (one line) */
} btf_segmentation;

int btf_segment(const btf_dataset *ds, const btf_segment_opts *opts, btf_segmentation *out,
                btf_error *err);
/* The same from features already computed (n = n_views * n_lights). */
int btf_segment_features(const float *features, int n_views, int n_lights, int dim,
                         const btf_segment_opts *opts, btf_segmentation *out, btf_error *err);
void btf_segmentation_free(btf_segmentation *s);

/* The index table as a picture like the paper's Fig. 5: x = view index,
 * y = light index, one colour per subspace, each cell cell x cell pixels
 * (0: 6). Written atomically. */
int btf_segmentation_write_png(const btf_segmentation *s, int cell, const char *path,
                               btf_error *err);


/* ------------------------------- analyse, stage 2: photometric stereo */
/* (photometric stereo API: src/photostereo.c, src/integrate.c) */

#ifdef __cplusplus
}
#endif
#endif /* BTFCAR_H */
