/*
 * btfcar/dataset.h — BTF datasets: the layouts btfcar reads (folders,
 * manifests, RTI light files, UBO2014 .btf files), reading them image by
 * image, and writing UBO2014 .btf files.
 * Part of the public C API of btfcar; include/btfcar.h includes every
 * topical header, and its conventions (docs/api.md) hold here too.
 */
#ifndef BTFCAR_DATASET_H
#define BTFCAR_DATASET_H

#include "base.h"
#include "image.h"

#include <stddef.h>
#include <stdint.h>

/* What this header declares is part of the ABI of libbtfcar.so: the library
 * is compiled with -fvisibility=hidden, and the declarations of the public
 * headers alone are exported (docs/install.md, "Shared library and soname"). */
#pragma GCC visibility push(default)

#ifdef __cplusplus
extern "C" {
#endif

/* ----------------------------------------------------------------- datasets */

typedef enum btf_layout {
    BTF_LAYOUT_UNKNOWN = 0,
    BTF_LAYOUT_UBO2003,  /* "NNNNN tlAAA plBBB tvCCC pvDDD.jpg", per-view folders or flat */
    BTF_LAYOUT_UTIA,     /* tvCCC_pvDDD/tlAAA_plBBB_tvCCC_pvDDD.(png|exr) */
    BTF_LAYOUT_MANIFEST, /* TSV: path theta_l phi_l theta_v phi_v */
    BTF_LAYOUT_UBO2014,  /* one Bonn BTFDBB .btf file: DFMF, FMF, PVF or BDIF
                            (docs/datasets.md, "UBO2014 .btf files") */
    BTF_LAYOUT_RTI       /* an RTI light file *.lp: "N", then "PATH X Y Z" per
                            image; 1 view (theta 0) x N lights */
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
    int n_pairs;                /* the measured pairs: n_views * n_lights for a
                                   full grid, fewer for a sparse set (a
                                   manifest of any pairs; docs/datasets.md) */
    int near_field;             /* 1: a manifest of camera and light positions
                                   (docs/datasets.md, "Near-field captures"):
                                   each image is read with the light's fall-off
                                   made the centre's, and stands for the
                                   directions from its centre */
} btf_dataset_info;

typedef struct btf_dataset_opts {
    size_t struct_size; /* sizeof the struct (set by the defaults); 0: this header's */
    int skip_verify;         /* 0: probe every image (size, structure); 1: only the first */
    btf_progress_fn progress;
    void *progress_user;
    uint64_t max_pixels;     /* the cap on each image's pixels, checked when the
                                headers are probed and when an image is read
                                (btf_read_opts.max_pixels); 0: the default */
} btf_dataset_opts;
/* The defaults: every field 0 (probe every image, no progress), max_pixels
 * BTF_DEFAULT_MAX_PIXELS. */
btf_dataset_opts btf_dataset_defaults(void);

/* Detects the layout of `path` (a folder, a manifest .tsv file, an RTI light
 * file *.lp or a Bonn .btf file), collects the (light, view) pairs and checks
 * that each pair is there once and that every image has one size. A folder
 * layout must hold the full grid (every light with every view); a manifest
 * may list any set of pairs (a sparse set: info->n_pairs < n_views *
 * n_lights, btf_dataset_has). */
btf_status btf_dataset_open(const char *path, const btf_dataset_opts *opts,
                            btf_dataset **out, btf_error *err);
void btf_dataset_close(btf_dataset *ds);
const btf_dataset_info *btf_dataset_get_info(const btf_dataset *ds);
/* 1 when the dataset holds an image of (view, light); 0 for a pair a sparse
 * set does not hold, or one out of range. */
int btf_dataset_has(const btf_dataset *ds, int view, int light);
/* The file holding (view, light); NULL when out of range or not held. */
const char *btf_dataset_path(const btf_dataset *ds, int view, int light);
/* Decodes one image to linear float RGB (3 channels). */
btf_status btf_dataset_read(const btf_dataset *ds, int view, int light, btf_image *out,
                            btf_error *err);

/* Streaming: hands out one (light, view) image at a time, view-major; the
 * pairs a sparse set does not hold are skipped. */
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
/* 1: a sample was produced; 0: the end; < 0: an error, a btf_status (the
 * iterator stays usable, the failing image is skipped on the next call).
 * Returns int because it counts as well as fails. */
int btf_dataset_iter_next(btf_dataset_iter *it, btf_error *err);
void btf_dataset_iter_end(btf_dataset_iter *it);

/* Reads and decodes every image once (catches corrupt data, NaN/Inf in EXR). */
btf_status btf_dataset_verify_pixels(const btf_dataset *ds, btf_progress_fn progress,
                                     void *user, btf_error *err);

/* What a UBO2014 .btf file holds (layout BTF_LAYOUT_UBO2014), beyond
 * btf_dataset_info: the format variant and its header fields. Every image is
 * reconstructed on demand from the file, which is memory-mapped, never read
 * into the heap (docs/datasets.md, "UBO2014 .btf files"). */
typedef struct btf_ubo2014_info {
    char signature[12];     /* "!DFMF08FCR", "!FMF12FCER", ... */
    const char *variant;    /* "DFMF", "FMF", "PVF" or "BDIF" */
    int meta_version;       /* the meta block's version */
    char measurement_setup[81], image_sensor[81], light_source[81];
    float ppmm;             /* pixels per millimetre, as stored */
    float rgb_scale[3];     /* rgb_scale_factor, as stored; not applied */
    int cosine_flag;        /* non-zero: the data hold cos(theta_l), divided out */
    int n_channels;         /* stored channels (3) */
    int colour_model;       /* DFMF: the decorrelation (0 RGB, 11 Ylog_UdivY_VdivY, ...); else -1 */
    int scalar_size;        /* bytes per stored factor or value: 2 (half), 4, 8 */
    int components[3];      /* DFMF: per channel; FMF, PVF: [0] (shared); BDIF: 0 */
    int transposed;         /* factor layout with the pixels as rows */
    int rotations;          /* num_rotations (read and skipped) */
    int dynamic_range;      /* FMF: data stored as ln(value + 1e-5) */
    uint64_t data_bytes;    /* the factor matrices (or BDIF images) in the mapping */
    uint64_t file_bytes;
} btf_ubo2014_info;
/* The .btf details of a dataset of layout BTF_LAYOUT_UBO2014; NULL for any
 * other layout. Lives as long as the dataset. */
const btf_ubo2014_info *btf_dataset_ubo2014(const btf_dataset *ds);

/* ------------------------------------------------- writing UBO2014 files */

/* Writing UBO2014 .btf files (src/io/ubo_write.c; docs/datasets.md,
 * "UBO2014 .btf files"). The images come from a callback: image(user, view,
 * light, out, err) fills *out (linear RGB, width x height, 3 channels;
 * btf_image_alloc'd, the writer frees it) for view and light indices into
 * the given sets; it is called for each pair in view-major order, twice per
 * pair for DFMF (two passes). */
typedef btf_status (*btf_pair_image_fn)(void *user, int view, int light, btf_image *out,
                                        btf_error *err);

typedef enum btf_ubo2014_variant {
    BTF_UBO2014_DFMF = 0, /* "!DFMF08FCR": per channel U x (S V)', colour model 0 (RGB) */
    BTF_UBO2014_BDIF,     /* "!BDIF06R2!": every value as a half float, uncompressed */
    BTF_UBO2014_FMF,      /* "!FMF12FCER": one U x (S V)' for the three channels,
                             U's row (view * n_lights + light) * 3 + channel;
                             the extended header of version 2, no height map */
    BTF_UBO2014_FMF_LOG,  /* the same of ln(value + 1e-5), with the file's
                             dynamic-range flag set (the reader takes exp(x) -
                             1e-5); every value must exceed -1e-5 */
    BTF_UBO2014_FMF06R,   /* "!FMF06FCR": FMF without the extended header */
    BTF_UBO2014_FMF06,    /* "!FMF06FC": nor the rotations field */
    BTF_UBO2014_PVF,      /* "!PVF06FCR": per view, the PCA of its pixels'
                             (light, channel) values: mean, components, weights */
    BTF_UBO2014_PVF06     /* "!PVF06FC": PVF without the rotations field */
} btf_ubo2014_variant;

typedef struct btf_ubo2014_write_opts {
    size_t struct_size; /* sizeof the struct (set by the defaults); 0: this header's */
    int variant;          /* btf_ubo2014_variant; 0: DFMF */
    int components;       /* DFMF: per channel, FMF: in all, PVF: per view (at
                             most the matrix's rank); 0: 16 */
    int scalar_size;      /* all but BDIF: 2 (half) or 4 (float); 0: 2 */
    uint64_t max_bytes;   /* DFMF, FMF, PVF: the cap on the working memory of the
                             factorisation (the Gram matrices, or the images
                             when there are fewer rows than pixels); 0: 2^31 */
    btf_progress_fn progress;
    void *progress_user;
} btf_ubo2014_write_opts;
/* The defaults: DFMF, 16 components, half, 2 GiB, no progress. */
btf_ubo2014_write_opts btf_ubo2014_write_defaults(void);

/* What a written file costs and how far its values are from the images. */
typedef struct btf_ubo2014_write_stats {
    int components[3];    /* DFMF: per channel, as written; FMF: the shared
                             count, three times; PVF: the largest of a view's */
    double rms_error[3];  /* RMS of (file value - image value) per channel, over
                             every pixel of every pair (DFMF: truncation and
                             rounding; BDIF: half rounding) */
    double max_error[3];  /* the largest |file value - image value| */
    double energy[3];     /* DFMF, FMF, PVF: 1 - (sum of squared errors) / (sum of
                             squared values) */
    uint64_t bytes;       /* the file's size */
} btf_ubo2014_write_stats;

/* Writes the BTF of views x lights images of width x height to path
 * (atomically). DFMF: per channel the truncated SVD of the (view, light) x
 * pixel matrix, computed from the Gram matrix of its smaller side
 * (deterministic); FMF: the same of the (view, light, channel) x pixel
 * matrix; PVF: per view the PCA of its pixels' 3 x n_lights values. stats
 * may be NULL. */
btf_status btf_ubo2014_write(const char *path, const btf_dirset *views, const btf_dirset *lights,
                             int width, int height, btf_pair_image_fn image, void *user,
                             const btf_ubo2014_write_opts *opts, btf_ubo2014_write_stats *stats,
                             btf_error *err);

#ifdef __cplusplus
}
#endif

#pragma GCC visibility pop
#endif /* BTFCAR_DATASET_H */
