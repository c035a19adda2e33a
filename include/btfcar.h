/*
 * btfcar.h — the public C API of btfcar, a toolkit for probabilistic modelling
 * of Bidirectional Texture Functions (Haindl & Filip, TPAMI 2007).
 *
 * Conventions (docs/api.md):
 *  - a fallible call returns a btf_status (BTF_OK = 0, errors negative) and,
 *    when given a non-NULL btf_error, fills it with one line naming the file,
 *    the value and what was expected. The library never prints and never exits.
 *  - options structs are valid when zero-initialised: a zero field means its
 *    default, and btf_X_defaults() returns the struct btf_X_opts with every
 *    default written out (the same results as the zeroed struct). A NULL
 *    options pointer means the defaults.
 *  - what a call allocates into a caller's struct is released by the matching
 *    *_free (or *_close) function, which accepts a zeroed struct and NULL.
 *  - parsers work on memory (btf_image_decode, btf_model_decode); the file
 *    readers (btf_image_read, btf_model_read) are thin wrappers over them.
 *  - images are linear float, channels interleaved, row 0 at the top.
 *  - directions are in degrees: theta from the surface normal (z), phi the
 *    azimuth measured from +x towards +y.
 */
#ifndef BTFCAR_H
#define BTFCAR_H

#include <stddef.h>
#include <stdint.h>

/* What this header declares is the ABI of libbtfcar.so: the library is
 * compiled with -fvisibility=hidden, and these declarations alone are
 * exported (docs/install.md, "Shared library and soname"). */
#pragma GCC visibility push(default)

#ifdef __cplusplus
extern "C" {
#endif

#define BTF_VERSION_MAJOR 0
#define BTF_VERSION_MINOR 3
#define BTF_VERSION_PATCH 0
#define BTF_VERSION_STRING "0.3.0"

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
const char *btf_status_name(btf_status status);

/* Progress report for long work: fraction in [0, 1]; what names the step. */
typedef void (*btf_progress_fn)(void *user, double fraction, const char *what);

/* ------------------------------------------------------------------ images */

typedef struct btf_image {
    int width, height, channels; /* channels: 1 (grey) or 3 (RGB) */
    float *data;                 /* width*height*channels floats, row-major */
} btf_image;

btf_status btf_image_alloc(btf_image *img, int width, int height, int channels,
                           btf_error *err);
void btf_image_free(btf_image *img);

typedef enum btf_file_format {
    BTF_FILE_UNKNOWN = 0,
    BTF_FILE_PNG,
    BTF_FILE_JPEG,
    BTF_FILE_EXR
} btf_file_format;

/* Format from the file's signature bytes (never from its name);
 * BTF_FILE_UNKNOWN for anything but a readable regular file. */
btf_file_format btf_file_format_of(const char *path);

typedef struct btf_image_header {
    btf_file_format format;
    int width, height;
    int channels;       /* channels in the file (before conversion) */
    int bits;           /* 8 or 16 for PNG/JPEG, 16 (half) or 32 for EXR */
    uint64_t file_bytes;
} btf_image_header;

/* Reads the header only and checks the structure (a JPEG must end with its
 * end-of-image marker, a PNG with its IEND chunk, an EXR's chunk table must
 * fit): cheap, no decoding. The memory form checks n bytes at data; name
 * starts its error messages, as the path does for the file form. */
btf_status btf_image_probe_memory(const void *data, size_t n, const char *name,
                                  btf_image_header *hdr, btf_error *err);
btf_status btf_image_probe(const char *path, btf_image_header *hdr, btf_error *err);

/* The default cap on the pixels of one decoded image: 2^28 (16384 x 16384,
 * 3 GiB as float RGB, about 12 GB at texture-fit's peak; docs/api.md,
 * "Resource limits"). Files over the cap are refused from their header,
 * before any pixel is decoded, so a small file cannot claim gigabytes. */
#define BTF_DEFAULT_MAX_PIXELS ((uint64_t)1 << 28)

typedef struct btf_read_opts {
    int channels;       /* 0: 3 for colour files, 1 for grey; 1 or 3 forces it */
    int linear_8bit;    /* 0 (default): 8-bit files are sRGB and are linearised;
                           1: 8-bit values are taken as linear (v/255) */
    int srgb_16bit;     /* 0 (default): 16-bit PNG is linear (v/65535); 1: sRGB */
    uint64_t max_pixels; /* width x height above this is refused (BTF_E_UNSUPPORTED,
                           naming the file, its size and the cap) from the
                           header; 0: BTF_DEFAULT_MAX_PIXELS */
} btf_read_opts;
/* The defaults: channels, linear_8bit, srgb_16bit 0 (as above), max_pixels
 * BTF_DEFAULT_MAX_PIXELS (a zeroed struct behaves the same). */
btf_read_opts btf_read_defaults(void);

/* Decodes PNG (8/16-bit), JPEG or EXR (half/float) held in memory (n bytes
 * at data; the format from its signature) into linear float. name starts
 * the error messages (NULL: "image"). EXR values that are NaN or Inf are an
 * error (BTF_E_DATA). opts NULL: btf_read_defaults(). */
btf_status btf_image_decode(const void *data, size_t n, const char *name,
                            const btf_read_opts *opts, btf_image *out, btf_error *err);
/* The same from a file, its messages naming it. EXR files are read in place,
 * chunk by chunk; PNG and JPEG files are loaded and decoded. */
btf_status btf_image_read(const char *path, const btf_read_opts *opts, btf_image *out,
                          btf_error *err);

/* Writers are atomic: a temporary file beside `path` is renamed over it. PNG
 * and JPEG encode linear values to 8-bit sRGB (clamped to [0, 1]); EXR stores
 * linear values as half (half != 0) or float, with no optional attributes
 * (btf_image_write_exr_meta below adds provenance). */
btf_status btf_image_write_png(const char *path, const btf_image *img, btf_error *err);
btf_status btf_image_write_jpeg(const char *path, const btf_image *img, int quality,
                                btf_error *err);
btf_status btf_image_write_exr(const char *path, const btf_image *img, int half,
                               btf_error *err);

/* Streaming EXR scanline writer (synthesis of images larger than memory): rows
 * arrive top to bottom in batches of any size; only one chunk (16 rows, ZIP)
 * is buffered. Like btf_image_write_exr it is atomic: the file appears at
 * path only when close succeeds. Any error is final for the writer: close
 * (which then fails) or abort frees it and removes the temporary file. */
typedef struct btf_exr_writer btf_exr_writer;
btf_status btf_exr_writer_open(const char *path, int width, int height, int channels,
                               int half, btf_exr_writer **out, btf_error *err);
/* rows: nrows*width*channels floats, interleaved channels; finite values. */
btf_status btf_exr_writer_put_rows(btf_exr_writer *w, const float *rows, int nrows,
                                   btf_error *err);
/* Finishes and renames into place; an error if not all rows were given.
 * Always frees w. */
btf_status btf_exr_writer_close(btf_exr_writer *w, btf_error *err);
/* Frees w and removes the temporary file; NULL is fine. */
void btf_exr_writer_abort(btf_exr_writer *w);

/* mkdir -p; an existing folder is fine. */
btf_status btf_mkdirs(const char *path, btf_error *err);
/* Writes n bytes to path atomically: into a new temporary file beside it
 * (PATH.btfcar-tmp-PID-N, created with O_EXCL | O_NOFOLLOW: never through a
 * planted symlink), fsync'd and renamed over path only when every byte is
 * written; on failure the temporary file is removed and path is left as it
 * was (BTF_E_IO; BTF_E_ARG for a path too long; the message names path). */
btf_status btf_write_file_atomic(const char *path, const void *data, size_t n,
                                 btf_error *err);

/* Output folders written as a whole (docs/design.md, "Writes are atomic"):
 * begin creates a temporary sibling folder DIR.btfcar-tmp-ID-PID-N (and any
 * missing folders above DIR); the caller writes every file into
 * btf_output_dir_path(d); commit moves the set into place: a missing or
 * empty DIR is replaced by one rename, an existing DIR gets the new files by
 * one rename each (files of other names stay), with SIGINT/SIGTERM/SIGHUP
 * blocked meanwhile. abort removes the temporary folder and the folders
 * begin created. Both free d. */
typedef struct btf_output_dir btf_output_dir;
btf_status btf_output_dir_begin(const char *dir, btf_output_dir **out, btf_error *err);
const char *btf_output_dir_path(const btf_output_dir *d);
btf_status btf_output_dir_commit(btf_output_dir *d, btf_error *err);
void btf_output_dir_abort(btf_output_dir *d);
/* abort after a failure: err's message, which names files under the
 * temporary folder (the writers' paths), then names them under DIR as the
 * caller gave it (issue 29: "full disk" named the temporary). */
void btf_output_dir_fail(btf_output_dir *d, btf_error *err);

/* Checks, before any work, that path can be written: a file (BTF_OUTPUT_FILE:
 * its folder exists, takes files, and path is not a folder or other
 * non-regular file) or a folder of files (BTF_OUTPUT_FOLDER: path is a folder
 * or missing, and the nearest existing folder above it takes files). It
 * proves "takes files" by creating and removing a temporary file. BTF_E_ARG
 * or BTF_E_IO, the message naming path. */
typedef enum btf_output_kind { BTF_OUTPUT_FILE = 0, BTF_OUTPUT_FOLDER = 1 } btf_output_kind;
btf_status btf_output_check(const char *path, btf_output_kind kind, btf_error *err);

/* Removes every temporary file and folder that btfcar's writers of this
 * process have created and not yet committed or removed. Async-signal-safe
 * (system calls only): for a SIGINT/SIGTERM handler, which then exits. The
 * list it walks is the library's one piece of global mutable state: a
 * fixed table of 64 paths, each slot claimed and released atomically by
 * the thread that created the temporary (a temporary beyond 64 live ones is
 * left out of the list, not refused). */
void btf_remove_temporaries(void);
/* Removes the stale temporaries in folder: entries named
 * *.btfcar-tmp-ID-PID-N owned by this user, whose ID is this process's (the
 * same host, boot and PID namespace) and whose process PID no longer exists
 * (never this process's, never another user's, never another namespace's
 * or host's, never a name without an ID). Returns how many it removed. */
int btf_remove_stale_temporaries(const char *folder);

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
btf_status btf_dirset_ubo81(btf_dirset *set, btf_error *err);
/* The UBO2014 151-direction dome (per-ring azimuth offsets). */
btf_status btf_dirset_ubo151(btf_dirset *set, btf_error *err);
/* A custom set from a list; sorted ring by ring, phi ascending, duplicates
 * (within 1e-6 degree) merged. If the list equals a known set it is named so. */
btf_status btf_dirset_from_list(btf_dirset *set, const btf_dir *dirs, int count,
                                btf_error *err);
btf_status btf_dirset_copy(btf_dirset *dst, const btf_dirset *src, btf_error *err);
void btf_dirset_free(btf_dirset *set);
/* Index of the direction within tol degrees (angle between unit vectors) or -1. */
int btf_dirset_find(const btf_dirset *set, btf_dir d, double tol_deg);

/* (theta, phi) in degrees <-> unit vector; z is the surface normal. A vector
 * on the pole gets phi = 0; phi is normalised to [0, 360). */
void btf_dir_to_vec(btf_dir d, double v[3]);
btf_dir btf_vec_to_dir(const double v[3]);
/* Angle in degrees between two directions. */
double btf_dir_angle(btf_dir a, btf_dir b);

/* ---------------------------------------------------------- EXR provenance */

/* What an output EXR says about where it came from, as header attributes
 * (docs/api.md, "EXR provenance"): btfcarVersion and the standard
 * chromaticities attribute (linear sRGB: Rec. 709 primaries, D65 white)
 * always; btfcarModel, btfcarSeed and btfcarSubspace when model is set;
 * btfcarView and btfcarLight ("THETA PHI", degrees) when has_dirs is 1.
 * The pixels are the same with or without them. */
typedef struct btf_exr_meta {
    const char *model;     /* the model file synthesised from; NULL: none */
    uint64_t seed;         /* with model: the synthesis seed */
    int subspace;          /* with model: the subspace synthesised */
    int has_dirs;          /* 1: view and light are set */
    btf_dir view, light;   /* the subspace's representative (view, light) */
} btf_exr_meta;

/* btf_image_write_exr and btf_exr_writer_open with provenance; meta NULL
 * writes none (they are those calls then). */
btf_status btf_image_write_exr_meta(const char *path, const btf_image *img, int half,
                                    const btf_exr_meta *meta, btf_error *err);
btf_status btf_exr_writer_open_meta(const char *path, int width, int height, int channels,
                                    int half, const btf_exr_meta *meta, btf_exr_writer **out,
                                    btf_error *err);

/* EXR compression (OpenEXR's methods; docs/synthesis.md, "EXR output",
 * measures them on synthesised images). ZIP is 0, the default. NONE, RLE,
 * ZIPS, ZIP and PIZ are lossless; PXR24 is lossless for half and rounds
 * float to 24 bits. B44/B44A are not offered: btfcar refuses to read them
 * (OpenEXRCore 3.1's B44 decoder crashes on damaged files), they are lossy
 * by up to 1.5 on synthesised noise, and OpenEXRCore 3.1.5 writes float B44
 * wrong. (OpenEXRCore 3.1 cannot write DWAA/DWAB.) */
typedef enum btf_exr_compression {
    BTF_EXR_ZIP = 0,  /* zlib (level 4) over 16-row chunks */
    BTF_EXR_NONE,     /* raw scanlines */
    BTF_EXR_RLE,      /* run lengths of bytes */
    BTF_EXR_ZIPS,     /* zlib (level 4) per scanline */
    BTF_EXR_PIZ,      /* wavelet + Huffman over 32-row chunks */
    BTF_EXR_PXR24
} btf_exr_compression;

/* The name ("zip", "none", ...) of a compression; NULL if out of range. */
const char *btf_exr_compression_name(int compression);

/* Seconds an EXR writer spent, added to at close (abort adds nothing): on
 * checking and staging rows (stage_s, the caller's thread), converting and
 * packing them (convert_s), compressing (compress_s), writing the header,
 * chunks and offset table (write_s), and the caller waiting for a free
 * buffer while the background thread catches up (wait_s); bytes: file
 * sizes; files: files committed. With background 1 convert, compress and
 * write run beside the caller. */
typedef struct btf_exr_times {
    double stage_s, convert_s, compress_s, write_s, wait_s;
    uint64_t bytes;
    int files;
} btf_exr_times;

typedef struct btf_exr_opts {
    int half;           /* 0 (default): 32-bit float; 1: half, clamped to +-65504 */
    int compression;    /* btf_exr_compression; 0: ZIP */
    int background;     /* 0 (default): the caller compresses and writes; 1: a
                           thread of the writer does, while the caller makes
                           the next rows (a bounded queue of a few chunks,
                           about 256 KiB or one chunk each); same bytes */
    btf_exr_times *times; /* NULL (default), or figures added to at close */
} btf_exr_opts;
/* The defaults: every field 0 (float, ZIP, no thread, no figures). */
btf_exr_opts btf_exr_defaults(void);

/* btf_exr_writer_open_meta and btf_image_write_exr_meta with options (NULL:
 * btf_exr_defaults()); the options' half replaces the half argument. */
btf_status btf_exr_writer_open_opts(const char *path, int width, int height, int channels,
                                    const btf_exr_opts *opts, const btf_exr_meta *meta,
                                    btf_exr_writer **out, btf_error *err);
btf_status btf_image_write_exr_opts(const char *path, const btf_image *img,
                                    const btf_exr_opts *opts, const btf_exr_meta *meta,
                                    btf_error *err);

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

/* ------------------------------------------------------ procedural materials */

/* A material: a periodic height field (in texel units) with an albedo and the
 * parameters of its reflectance (Lambertian + one specular lobe). */
typedef struct btf_procedural {
    char name[32];
    int size;               /* width = height = size texels */
    float *height;          /* size*size, texel units, periodic */
    float *normal;          /* size*size*3, unit vectors, z up */
    float *albedo;          /* size*size*3, linear RGB */
    float specular;         /* specular albedo */
    float shininess;        /* Blinn-Phong exponent of the lobe */
    float fresnel0;         /* reflectance of the coat at normal incidence (0: none) */
    float ambient;          /* fraction of light reaching shadowed points */
} btf_procedural;

/* Names of the built-in materials, NULL-terminated: leather, fabric, wood. */
const char *const *btf_procedural_names(void);
btf_status btf_procedural_make(const char *name, int size, uint64_t seed, btf_procedural *m,
                             btf_error *err);
void btf_procedural_free(btf_procedural *m);

/* Renders the rectified image the BTF measures for one (view, light) pair:
 * for every texel of the reference plane, the view ray finds the visible
 * surface point (masking, parallax), which is lit by the light unless the
 * height field casts a shadow on it. Output: linear RGB, size x size. */
btf_status btf_procedural_render(const btf_procedural *m, btf_dir view, btf_dir light,
                               btf_image *out, btf_error *err);

typedef struct btf_generate_opts {
    int size;               /* 0: 128 */
    uint64_t seed;          /* 0 is a valid seed */
    int jpeg_quality;       /* 0: 95 */
    int threads;            /* 0: the number of online CPUs */
    btf_progress_fn progress;
    void *progress_user;
} btf_generate_opts;
/* The defaults: size 128, seed 0, JPEG quality 95, threads 0 (all CPUs). */
btf_generate_opts btf_generate_defaults(void);

/* Writes the 81 x 81 images of a material in the UBO2003 layout under outdir
 * (per-view folders), and outdir/truth/{height,normals,albedo}.exr. */
btf_status btf_generate(const char *material, const char *outdir,
                        const btf_generate_opts *opts, btf_error *err);

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

/* Given factors, written as a DFMF file as they are: per channel c,
 * u[c] is (n_views * n_lights) x components[c] (row view * n_lights +
 * light) and sxv[c] is (width * height) x components[c] (row y * width + x),
 * both row-major. */
typedef struct btf_ubo2014_factors {
    int colour_model;     /* stored as is (0: RGB; 11: Ylog_UdivY_VdivY, ...) */
    int cosine_flag;      /* stored as is */
    int scalar_size;      /* 2 (half; 0 means this), 4 (float) or 8 (double) */
    int components[3];
    const float *u[3], *sxv[3];
} btf_ubo2014_factors;
btf_status btf_ubo2014_write_factors(const char *path, const btf_dirset *views,
                                     const btf_dirset *lights, int width, int height,
                                     const btf_ubo2014_factors *f, btf_error *err);

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
    /* NULL, or the caller's (views x lights) x 3 floats that get each
     * image's mean linear RGB, read in the same pass (the pair gains of
     * btf_analyse, docs/model.md "Pair gains") */
    float *means;
} btf_feature_opts;
/* The defaults: 32 bins, threads 0 (all CPUs), no progress. */
btf_feature_opts btf_feature_defaults(void);

/* Fixed ranges of the histograms: L* [0, 100], a* and b* [-64, 64] (values
 * outside are counted in the end bins). */
#define BTF_LAB_A_RANGE 64.0f

/* The feature of one linear-RGB image: the cumulative histograms of L*, a*,
 * b* (each normalised to end at 1), concatenated: 3 * bins floats. */
btf_status btf_lab_cumhist(const btf_image *img, int bins, float *feature, btf_error *err);

/* Features of every image of a dataset, streamed (one image decoded at a time
 * per thread): features[(view * n_lights + light) * dim + i], dim = 3 * bins. */
btf_status btf_dataset_features(const btf_dataset *ds, const btf_feature_opts *opts,
                                float **features, int *dim, btf_error *err);
/* Each image's mean linear RGB alone (what btf_feature_opts.means gives in
 * the features' pass): means[(view * n_lights + light) * 3 + c], the
 * caller frees it. */
btf_status btf_dataset_means(const btf_dataset *ds, int threads, float **means, btf_error *err);

typedef struct btf_kmeans_opts {
    int restarts;             /* 0: 5; the best run by distortion is kept */
    int max_iter;             /* 0: 100 Lloyd iterations per run */
    uint64_t seed;            /* 0 is a valid seed */
} btf_kmeans_opts;
/* The defaults: 5 restarts, 100 iterations, seed 0. */
btf_kmeans_opts btf_kmeans_defaults(void);

typedef struct btf_kmeans_result {
    int k;                    /* clusters produced: min(k asked, distinct points) */
    int *labels;              /* n: cluster of each point, 0..k-1 */
    float *centres;           /* k * dim; never NaN */
    double distortion;        /* sum of squared distances to the centres */
} btf_kmeans_result;

/* k-means with k-means++ seeding and restarts. k larger than the number of
 * distinct points is reduced to it; clusters that go empty are re-seeded at
 * the point farthest from its centre. Same inputs and seed, same result. */
btf_status btf_kmeans(const float *points, int n, int dim, int k, const btf_kmeans_opts *opts,
                      btf_kmeans_result *out, btf_error *err);
void btf_kmeans_free(btf_kmeans_result *r);

typedef struct btf_segment_opts {
    int subspaces;            /* K; 0: auto */
    int max_subspaces;        /* cap for auto; 0: 20 (the paper's bound) */
    double auto_threshold;    /* auto: smallest K whose distortion is at most
                                 this fraction of the K = 1 distortion; 0: 0.10 */
    double split_gain;        /* auto, past the threshold: K grows while one
                                 more subspace removes at least this fraction
                                 of the distortion left; 0: 0.12, < 0: off */
    btf_feature_opts features;
    btf_kmeans_opts kmeans;
    /* btf_segment_features only: NULL (every pair measured), or
     * [view * n_lights + light] non-zero for the pairs a sparse set holds;
     * the others' feature rows are ignored and their index is
     * BTF_PAIR_NONE. btf_segment sets it from the dataset. */
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
                                 linear RGB (btf_segment; NULL from
                                 btf_segment_features) */
} btf_segmentation;

btf_status btf_segment(const btf_dataset *ds, const btf_segment_opts *opts,
                       btf_segmentation *out, btf_error *err);
/* The same from features already computed (n = n_views * n_lights). */
btf_status btf_segment_features(const float *features, int n_views, int n_lights, int dim,
                                const btf_segment_opts *opts, btf_segmentation *out,
                                btf_error *err);
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
    btf_integrate_method method; /* default: BTF_INTEGRATE_POISSON */
    double max_slope;   /* default 10; |dz/dx| and |dz/dy| are clamped to it,
                           so normals near the horizon (n_z -> 0) stay finite */
    double tolerance;   /* default 1e-7; relative residual at which the masked
                           Poisson solver stops */
    int max_iter;       /* default 2000 conjugate-gradient iterations at most */
} btf_integrate_opts;

/* The defaults above; a zero field of btf_integrate_opts means the same. */
btf_integrate_opts btf_integrate_defaults(void);

/* Integrates a normal map (3 channels x, y, z in the frame above) into a
 * height field in pixel units: dz/dcolumn = -n_x/n_z, dz/drow = +n_y/n_z.
 * mask: NULL (every pixel) or an image of the same size whose non-zero
 * pixels are valid. opts: NULL for the defaults. Output: 1 channel, zero
 * mean over the valid pixels, 0 elsewhere; never NaN. A zero normal
 * (0, 0, 0) counts as flat. */
btf_status btf_integrate(const btf_image *normals, const btf_image *mask,
                         const btf_integrate_opts *opts, btf_image *height, btf_error *err);

/* Options of photometric stereo. Each field's default is given; a zero
 * field means that default, a negative one switches a rule off where said. */
typedef struct btf_photostereo_opts {
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
/* The same on a BTF dataset: the images of the view closest to theta_v = 0
 * under all its lights (btf_dir_to_vec), read one at a time. In a sparse
 * set only views with at least 3 lights count, and only the lights the set
 * holds there are used; with no such view, BTF_E_DATA saying so. */
btf_status btf_photostereo_dataset(const btf_dataset *ds, const btf_photostereo_opts *opts,
                                   btf_ps_result *out, btf_error *err);
/* The same from a manifest: a TSV file with a header line naming its columns:
 * path (relative to the manifest's folder, or absolute), the light either as
 * theta_l, phi_l (degrees) or as lx, ly, lz (a vector in the frame above),
 * optionally r, g, b (the light's intensity), and optionally theta_v, phi_v
 * (the view: only the images of the view nearest the normal are used, see
 * btf_photostereo_manifest_view). A path listed twice is an error. */
btf_status btf_photostereo_manifest(const char *path, const btf_photostereo_opts *opts,
                                    btf_ps_result *out, btf_error *err);
/* The same with the view chosen: a dataset, or a manifest with theta_v and
 * phi_v columns (a BTF manifest of several views; each (view, light) pair
 * once), uses the images of its view nearest `view` (within 5 degrees, else
 * BTF_E_ARG), or with view NULL of its view nearest the normal (smallest
 * theta_v, as btf_photostereo_dataset and btf_photostereo_manifest do).
 * out->view and out->view_dir say which (view: its index in the dataset, or
 * among the manifest's distinct views in the order of first appearance). */
/* The most lights the dataset holds at any one view (photometric stereo
 * needs 3). */
int btf_photostereo_best_lights(const btf_dataset *ds);
btf_status btf_photostereo_dataset_view(const btf_dataset *ds, const btf_dir *view,
                                        const btf_photostereo_opts *opts, btf_ps_result *out,
                                        btf_error *err);
btf_status btf_photostereo_manifest_view(const char *path, const btf_dir *view,
                                         const btf_photostereo_opts *opts, btf_ps_result *out,
                                         btf_error *err);
void btf_ps_result_free(btf_ps_result *r);

/* Previews for people: normals as RGB (n + 1) / 2 (the usual normal-map
 * colours once 8-bit encoded), and the range map as a shaded relief (lit
 * from the top left, exaggerated to a fixed mean slope, tinted by height;
 * mask: NULL or the mask of the run, outside which it is black). Both are
 * linear RGB for btf_image_write_png. */
btf_status btf_normals_preview(const btf_image *normals, btf_image *out, btf_error *err);
btf_status btf_height_relief(const btf_image *height, const btf_image *mask, btf_image *out,
                             btf_error *err);
/* Writes normals.exr, albedo.exr, height.exr (float) and normals.png,
 * albedo.png, height.png into outdir (created if missing), each file
 * atomically; mask as for btf_height_relief. */
btf_status btf_ps_write(const btf_ps_result *r, const btf_image *mask, const char *outdir,
                        btf_error *err);

/* ------------------------------ analyse, stage 3: the CAR model; the model */

/* Paper section II.C. Each subspace image is decorrelated into 3 mono-spectral
 * bands (PCA, Karhunen-Loeve), each band decomposed into a Gaussian-Laplacian
 * pyramid, and each sub-band (band, level) modelled by a 2D causal
 * auto-regressive field  Y_r = gamma X_r + e_r,  e_r ~ N(0, sigma^2),  where
 * X_r holds the sub-band's values at the causal neighbourhood offsets. */

#define BTF_CAR_MAX_NEIGHBOURS 24
#define BTF_MAX_LEVELS 8

/* A causal offset: row < 0, or row == 0 and col < 0. */
typedef struct btf_offset {
    int8_t row, col;
} btf_offset;

typedef struct btf_car_band {
    int n;                                   /* neighbours, 0..BTF_CAR_MAX_NEIGHBOURS */
    btf_offset offsets[BTF_CAR_MAX_NEIGHBOURS];
    float gamma[BTF_CAR_MAX_NEIGHBOURS];     /* coefficients, one per offset */
    float sigma;                             /* noise standard deviation, >= 0 */
    float mean;                              /* mean of the sub-band */
} btf_car_band;

/* Marginal transfer of a subspace (docs/synthesis.md, "Marginals"): the CAR
 * fields' collapsed bands are Gaussian, the material's decorrelated channels
 * are not; synthesis sends each band v through the monotone piecewise-linear
 * map with knots z_j = synth_mean + synth_sd * N_j (N_j the standard normal
 * quantiles of the documented probabilities) onto the exemplar's quantiles
 * quantile[j], clamped to [quantile[0], quantile[last]] (the exemplar's
 * range), and the RGB result to [rgb_lo, rgb_hi] (the exemplar's RGB box,
 * rgb_lo >= 0). knots 0: no transfer (identity, no clamp), as in a model
 * file of format 1.0 or 1.1. */
#define BTF_MARGIN_KNOTS 32
typedef struct btf_marginal {
    int knots;                            /* 0 or BTF_MARGIN_KNOTS */
    float synth_mean[3], synth_sd[3];     /* per band: the synthesised band's mean and
                                             standard deviation (sd >= 0) */
    float quantile[3][BTF_MARGIN_KNOTS];  /* per band: the exemplar's quantiles, nondecreasing;
                                             [0] its minimum, [last] its maximum */
    float rgb_lo[3], rgb_hi[3];           /* the exemplar's linear RGB range, 0 <= lo <= hi */
    /* The exemplar's CIE Lab histogram (format 1.3, docs/synthesis.md,
     * "Colour matching"): L*, a*, b* of its RGB times the distances'
     * exposure (1, or 1 / the largest rgb_hi when that is above 1) at
     * probabilities j / 31, [0] the
     * minimum, [last] the maximum; nondecreasing, L* in [0, 100], a*, b* in
     * [-128, 128]. lab_knots 0: none (a file of format 1.2 or older), and
     * btf_colour_match refuses the subspace. Only with knots. */
    int lab_knots;                        /* 0 or BTF_MARGIN_KNOTS */
    float lab_quantile[3][BTF_MARGIN_KNOTS];
} btf_marginal;

typedef struct btf_subspace_model {
    int view, light;           /* the representative image's pair; -1 for a texture */
    int width, height;         /* size of the analysed image */
    float mean[3];             /* mean linear RGB */
    float basis[9];            /* row-major 3x3: band_i = sum_j basis[3i+j] (rgb_j - mean_j);
                                  orthonormal, so rgb = mean + basis^T band */
    int levels;                /* pyramid levels, 1..BTF_MAX_LEVELS; level 0 is the finest */
    btf_car_band bands[3][BTF_MAX_LEVELS]; /* [spectral band][level] */
    btf_marginal marginal;     /* knots 0: none (btf_fit_subspace leaves it so;
                                  btf_fit_marginals fills it) */
} btf_subspace_model;

typedef struct btf_model {
    btf_dirset views, lights;  /* count 0 for a single texture */
    int n_subspaces;
    uint8_t *index;            /* [view * lights.count + light] -> subspace; NULL for a texture */
    btf_subspace_model *subspaces;
    /* The range map (paper section II.B) as a small periodic tile: heights in
     * texel units of the analysed images; NULL when absent. Normals follow
     * from it. */
    int range_width, range_height;
    float *range;
    float range_texel;         /* analysed-image texels per range-tile texel,
                                  along both axes (the tile keeps the image's
                                  aspect ratio) */
    /* The structure layer (docs/model.md, "Structure"): on the range map's
     * grid (texel 1 only), the albedo's luminance pattern (mean 1) that the
     * photometric stereo recovered. When present, every subspace's CAR
     * fields model the remainder: the exemplar divided by this pattern and
     * by the range map's relit shading (a + max(0, n.l)) / (a + l_z) under
     * the subspace's light, a = ambient. Synthesis multiplies the pattern
     * back, the renderer the shading; both through one quilting map of the
     * range map and the pattern (btf_structure_maps). NULL: none. */
    float *albedo;
    /* The colour of that pattern (docs/model.md, "Colour layer"): per texel
     * of the range map's grid three factors (R, G, B; each of mean 1 over
     * the grid) of the albedo's colour over its luminance, which multiply
     * the pattern channel by channel. Kept only where the colour varies
     * across the sample (a weave of two yarns); NULL: the pattern is grey. */
    float *chroma;
    float ambient;             /* a >= 0 of the shading above (0 without structure) */
    int shadows;               /* 1: that shading holds the relief's cast shadows,
                                  a + vis max(0, n.l) with vis from the range
                                  map's horizons (docs/model.md, "Shadows");
                                  0 before format 1.5 */
    /* The pair gains (docs/model.md, "Pair gains"): per measured pair
     * [(view * lights.count + light) * 3 + c], the ratio of the measured
     * image's mean colour to the render's of that pair from its subspace
     * image, so that every pair keeps its own brightness and colour (the
     * first-order statistics a subspace shares); the renderer interpolates
     * them with the images' weights. NULL: 1 everywhere. */
    float *gain;
    /* The library's own data about a model it read (the synthesis margins
     * computed then, docs/synthesis.md): opaque, freed by btf_model_free;
     * NULL in a model built by hand, which is fine. */
    struct btf_model_internal *internal;
} btf_model;

/* Frees what the model owns and zeroes it; NULL and a zeroed model are fine. */
void btf_model_free(btf_model *m);
/* The provenance of a synthesis of subspace `subspace` of m, read from
 * model_path with seed: the subspace's representative (view, light) when it
 * has one (has_dirs 0 for a texture model or an out-of-range subspace). */
btf_exr_meta btf_model_exr_meta(const btf_model *m, const char *model_path, int subspace,
                                uint64_t seed);

/* Warnings from a long computation (e.g. a model made stable by force). */
typedef void (*btf_warning_fn)(void *user, const char *message);
/* A CAR fit warns "... the model misses N% of the band's variance ..." when
 * synthesis would give at least this fraction less than the band's variance
 * (a periodic pattern; `btfcar info` reports it too, so a quiet caller that
 * drops warnings still finds it there). */
#define BTF_CAR_MISSED_LOUD 0.2
#define BTF_CAR_MISSED_TEXT "the model misses"

/* Neighbourhood SPEC: comma-separated causal "row:col" offsets, e.g.
 * "0:-1,-1:0,-1:-1,-1:1". A non-causal or repeated offset is an error. */
btf_status btf_neighbourhood_parse(const char *spec, btf_offset *offsets, int *n,
                                   btf_error *err);
void btf_neighbourhood_format(const btf_offset *offsets, int n, char *buf, size_t len);

typedef struct btf_car_fit_opts {
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

#define BTF_CAR_MAX_CANDIDATES 16
typedef struct btf_car_fit_info {
    int candidates;                       /* evaluated */
    int size[BTF_CAR_MAX_CANDIDATES];     /* their neighbour counts */
    double log_evidence[BTF_CAR_MAX_CANDIDATES];
    int chosen;                           /* index into the above; -1: none fitted */
    double shrink;                        /* 1: as estimated; < 1: gamma scaled for stability */
    long pixels;                          /* equations used (t) */
} btf_car_fit_info;

/* Fits the CAR model to one sub-band (w x h doubles): Bayesian estimates
 * gamma = V_xx^-1 V_xy, sigma^2 from lambda, with the neighbourhood chosen by
 * its posterior probability among a nested family of candidates (or fixed).
 * Constant, tiny or ill-conditioned bands degrade to smaller models; an
 * unstable estimate is shrunk until stable (a warning). Output always finite. */
btf_status btf_car_fit(const double *band, int w, int h, const btf_car_fit_opts *opts,
                       btf_car_band *out, btf_car_fit_info *info, btf_error *err);
/* 1 when the recursion 1/A(z1, z2) of the band's model is stable. */
int btf_car_is_stable(const btf_car_band *b);
/* sigma^2 times the mean of 1/|A|^2 over the frequency torus: the variance of
 * the stationary field (without its mean). */
double btf_car_stationary_variance(const btf_car_band *b);

/* The model file MODEL.btfcar (docs/model-format.md): little-endian,
 * versioned, CRC-32 checked. Writing is atomic; reading a corrupt, truncated
 * or foreign file is an error naming it, never a crash. */
btf_status btf_model_write(const char *path, const btf_model *m, btf_error *err);
btf_status btf_model_read(const char *path, btf_model *m, btf_error *err);
/* The same to and from memory: encode's buffer is malloc'd (the caller
 * frees it); decode's name starts its messages (NULL: "model"). The file
 * forms are these plus the atomic write or the whole-file read. */
btf_status btf_model_encode(const btf_model *m, unsigned char **data, size_t *size,
                            btf_error *err);
btf_status btf_model_decode(const unsigned char *data, size_t size, const char *name,
                            btf_model *m, btf_error *err);

typedef struct btf_fit_opts {
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

/* The largest magnitude of a band's sigma and mean and of a subspace's
 * colour mean that a model holds: within it, synthesis stays inside the
 * float range (src/model/model_check.c derives it); the model validator
 * refuses more. */
#define BTF_MODEL_MAX_VALUE 1e30f
/* The largest pixel magnitude `btfcar texture-fit` models: the bands of
 * such an exemplar (differences of colours, projected on a unit basis,
 * split into pyramid levels) stay far inside BTF_MODEL_MAX_VALUE. */
#define BTF_EXEMPLAR_MAX_VALUE 1e28f

/* Models one subspace image (linear RGB): decorrelation, pyramid, one CAR
 * model per band and level. view and light are left -1. */
btf_status btf_fit_subspace(const btf_image *img, const btf_fit_opts *opts,
                            btf_subspace_model *out, btf_error *err);
/* A model of one ordinary colour texture: one subspace, no directions, no
 * index table, no range map. */
btf_status btf_texture_fit(const btf_image *img, const btf_fit_opts *opts, btf_model *out,
                           btf_error *err);
/* The marginal transfer of subspace `subspace` of m from its exemplar img
 * (linear RGB, the image the subspace was fitted to): the exemplar's
 * decorrelated quantiles and RGB range, and the mean and standard deviation
 * of each band of a synthesis of the subspace (512 x 512, a fixed seed, no
 * transfer). btf_texture_fit and btf_analyse call it for every subspace. */
btf_status btf_fit_marginals(const btf_image *img, btf_model *m, int subspace, btf_error *err);
/* The candidate neighbourhood family of the Bayesian choice (docs/model.md):
 * its BTF_CAR_MAX_NEIGHBOURS causal offsets in order, nearest first; a
 * "fixed order n" neighbourhood is its first n. Returns the count. */
int btf_car_candidate_offsets(btf_offset offsets[BTF_CAR_MAX_NEIGHBOURS]);
/* The automatic number of pyramid levels for a band (docs/model.md). */
int btf_auto_levels(const double *band, int w, int h);

/* What btf_analyse decided on the way, for reports to people; the model
 * itself holds the results. (A new field is an ABI change: docs/install.md.) */
typedef struct btf_analyse_report {
    char segment_reason[256]; /* why this number of subspaces (one line, as
                                 btf_segmentation.reason) */
    char structure_reason[384]; /* which structure layers were kept and why
                                   (one line, docs/model.md "Structure") */
} btf_analyse_report;

typedef struct btf_analyse_opts {
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
     * btf_sweep_run): features (NULL: computed) are the dataset's, as
     * btf_dataset_features gives them with segment.features.bins bins,
     * feature_dim floats per image; range_from (NULL: photometric stereo)
     * is a model of the same dataset whose range tile is copied. */
    const float *features;
    int feature_dim;
    const float *means;               /* with features: the images' mean RGB (as
                                         btf_segmentation.means); NULL: read again */
    const btf_model *range_from;
    int no_gains;                     /* 1: no pair gains (before format 1.5) */
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
/* Stage 2 alone: the range tile of the dataset (photometric stereo, as
 * btf_analyse makes it) into out's range fields; nothing else of out is
 * touched. For work shared between analyses (btf_analyse_opts.range_from). */
btf_status btf_analyse_range(const btf_dataset *ds, const btf_analyse_opts *opts, btf_model *out,
                             btf_error *err);

/* ------------------------------------------------------ synthesis (CPU) */
/* Paper section II.C (synthesis): per spectral band, every pyramid level is
 * a CAR field generated by its causal recursion, the pyramid is collapsed
 * and the decorrelation undone (docs/synthesis.md). */

/* Receives synthesised rows in order: rows [y, y + nrows) of width * channels
 * floats each. Return 0 to go on; to stop, a btf_status (and fill err), which
 * the synthesis returns (any other non-zero value: BTF_E_IO). */
typedef int (*btf_rows_fn)(void *user, int y, int nrows, const float *rows, btf_error *err);

/* Options of a synthesis; zero-initialised means the defaults. */
typedef struct btf_synth_opts {
    int width, height;   /* output size, each side 1..2^24; 0: the subspace's
                            analysed size (btf_subspace_model.width, height) */
    uint64_t seed;       /* noise seed; the same seed gives the same bytes */
    /* CPU only; every setting gives the same bytes, these rule out a fast
     * path when in doubt or compare the paths: */
    int portable_noise;  /* 1: the portable noise loop instead of AVX2 (and so
                            no wavefront, which draws its noise with AVX2) */
    int row_by_row;      /* 1: CAR fields row by row instead of the wavefront */
    /* 1: a tileable image (docs/synthesis.md, "Tileable synthesis"): the
     * streaming synthesis with periodic noise, level l's field driven by
     * the noise of (row mod (H >> l), column mod (W >> l)), so that each
     * window converges, within the margin, to the CAR field on its torus
     * and the pyramid collapses to an image whose right edge continues
     * into the left and the bottom into the top with the model's
     * statistics everywhere. Memory and sizes as streaming, but both sides
     * must be multiples of 2^(levels - 1) (BTF_E_ARG otherwise, naming the
     * size); the fields run row by row (no wavefront). The same seed gives
     * the same bytes on every CPU path and on the GPU (btf_gpu_synthesise). */
    int tileable;
    /* Colour matching (btf_colour_match): after synthesis each CIE Lab
     * channel of the image goes through the monotone map from its own
     * histogram onto the exemplar's, so that the image has the material's
     * first-order statistics whatever the realisation (docs/synthesis.md,
     * "Colour matching"). 0 (the default): on where the subspace holds the
     * exemplar's Lab quantiles (format 1.3 on), off for older files;
     * 1: on, BTF_E_ARG for a subspace without; -1: off (faster: no pass
     * over the image). The streaming btf_synthesise keeps the whole image
     * up to 256 MiB, and beyond synthesises it twice (first for its
     * histogram): memory by the width still, the same bytes. The GPU
     * (btf_gpu_synthesise, the GPU render) matches on the device with the
     * CPU's operations: the same bytes everywhere. */
    int match_colours;
    /* The largest image (width x height x 3 floats, in bytes) the streaming
     * btf_synthesise keeps whole to colour-match; a larger one is
     * synthesised twice. 0: 256 MiB. The bytes are the same either way, so
     * this trades memory for time only (and lets tests reach the two-pass
     * path with small images). */
    size_t match_whole_bytes;
} btf_synth_opts;

/* The defaults that a zero field of btf_synth_opts stands for. */
btf_synth_opts btf_synth_defaults(void);

/* Synthesises subspace image `subspace` of the model (opts may be NULL),
 * streaming: memory grows with the width, not the height (tileable too,
 * btf_synth_opts.tileable). Per spectral band
 * and pyramid level the CAR recursion runs with a burn-in margin
 * (docs/synthesis.md) so the field is stationary from its first pixel; the
 * pyramid is collapsed and the colour decorrelation undone. The noise is a
 * counter-based generator of (seed, subspace, band, level, row, column):
 * the same seed gives the same bytes. Rows are linear RGB. */
btf_status btf_synthesise(const btf_model *m, int subspace, const btf_synth_opts *opts,
                          btf_rows_fn fn, void *user, btf_error *err);
/* The same into an image (linear RGB), allocated here. */
btf_status btf_synthesise_image(const btf_model *m, int subspace, const btf_synth_opts *opts,
                                btf_image *out, btf_error *err);
/* Subspace images subspaces[0 .. n-1] into outs[0 .. n-1] (allocated here;
 * on failure none is left), each the bytes btf_synthesise_image gives with
 * the same opts. Faster with colour matching: image i - 1 is matched on the
 * CPU that image i's synthesis leaves idle (docs/synthesis.md, "Colour
 * matching"), so the pass costs little more than its last image's. */
btf_status btf_synthesise_images(const btf_model *m, const int *subspaces, int n,
                                 const btf_synth_opts *opts, btf_image *outs, btf_error *err);
/* 1 when btf_synthesise holds the subspace's whole image in memory anyway
 * with these opts (colour matching on, the image within 256 MiB; 0 too for
 * options the synthesis would refuse): a batch (btf_synthesise_each) then
 * costs no more memory per image than streaming. */
int btf_synth_holds_whole(const btf_model *m, int subspace, const btf_synth_opts *opts);
/* Receives image i of btf_synthesise_each, finished (linear RGB): fn may
 * keep it (take the struct and zero *img), else it is freed when fn
 * returns. Non-zero stops the batch: a btf_status with err filled, or any
 * other value (BTF_E_IO). */
typedef int (*btf_image_fn)(void *user, int i, btf_image *img, btf_error *err);
/* The same as btf_synthesise_images, each image handed to fn in order as
 * soon as it is finished (image i - 1 while image i is being synthesised,
 * when matched): at most two images in memory besides what fn keeps. */
btf_status btf_synthesise_each(const btf_model *m, const int *subspaces, int n,
                               const btf_synth_opts *opts, btf_image_fn fn, void *user,
                               btf_error *err);
/* Colour matching (src/synth/colour_match.c, docs/synthesis.md, "Colour
 * matching"): the per-band marginal transfer gives each decorrelated band
 * the exemplar's histogram, but the bands are synthesised independently
 * where the material's chroma depends on its lightness, and a small
 * synthesis' histogram strays from the model's with its realisation: both
 * show in the CIE Lab histograms (issue 17's first-order distance). This
 * pass measures img's own L*, a*, b* quantiles (every pixel up to 128 x
 * 128, a regular grid of as many beyond), sends each channel of every pixel
 * through the piecewise-linear map from them onto the model's
 * lab_quantile (resampled on 256 segments), converts back and clamps into
 * the exemplar's RGB box. Monotone per channel, deterministic, finite; a
 * tileable image stays tileable. BTF_E_ARG when the subspace holds no Lab
 * quantiles or img is not RGB or holds Inf or NaN. The synthesis calls it
 * by default (btf_synth_opts.match_colours). */
btf_status btf_colour_match(const btf_model *m, int subspace, btf_image *img, btf_error *err);
/* The synthesis margin of one band (0..2) and pyramid level of a subspace in
 * pixels: its CAR field starts this many rows above the level's window and
 * runs this many columns on either side (docs/synthesis.md). */
btf_status btf_synth_margin(const btf_model *m, int subspace, int band, int level, int *margin,
                            btf_error *err);
/* The fraction (0..1) of the band's stationary variance that synthesis
 * misses in its first rows and columns (the margin too short for a nearly
 * periodic pattern): 0 for a band whose margin is below the largest, else
 * measured on a test field (docs/synthesis.md). */
btf_status btf_synth_missed_variance(const btf_model *m, int subspace, int band, int level,
                                     double *missed, btf_error *err);

/* ------------------------------------------------------ synthesis (GPU) */

/* The Vulkan compute path (gpu/synth_gpu.c, docs/gpu.md): the same fields,
 * collapse and colour as btf_synthesise, bit for bit, computed by compute
 * shaders (a wavefront over each causal field). */
typedef struct btf_gpu btf_gpu;

typedef enum btf_gpu_device_type { /* VkPhysicalDeviceType's values */
    BTF_GPU_OTHER = 0,
    BTF_GPU_INTEGRATED = 1,
    BTF_GPU_DISCRETE = 2,
    BTF_GPU_VIRTUAL = 3,
    BTF_GPU_CPU = 4 /* a CPU driver such as lavapipe */
} btf_gpu_device_type;

typedef struct btf_gpu_device {
    int index;                 /* for btf_gpu_opts.device */
    char name[256];
    btf_gpu_device_type type;
    const char *type_name;     /* "discrete GPU", "integrated GPU", "virtual GPU",
                                  "CPU", "other" */
    char vulkan_version[32];   /* "1.3.230" */
    int usable;                /* Vulkan >= 1.1 and a compute queue */
    uint64_t max_buffer_bytes; /* largest storage buffer (maxStorageBufferRange) */
    uint64_t device_local_bytes; /* size of the largest device-local memory heap */
    int storage_16bit;         /* 1: 16-bit values in storage buffers
                                  (storageBuffer16BitAccess, Vulkan 1.1) */
} btf_gpu_device;

/* Every Vulkan device, in the driver's order (the indices of
 * btf_gpu_opts.device). *list is malloc'd: free() it; *count may be 0. No
 * Vulkan driver: BTF_E_UNSUPPORTED. */
btf_status btf_gpu_list_devices(btf_gpu_device **list, int *count, btf_error *err);

/* Options of btf_gpu_open; zero-initialised means the defaults. */
typedef struct btf_gpu_opts {
    int use_device;   /* 1: take `device` (an index of btf_gpu_list_devices);
                         0: the best device, discrete > integrated > virtual
                         GPU > CPU */
    int device;
    int allow_cpu;    /* 1: a CPU device (lavapipe) may be the best device */
    int validation;   /* 1: the Khronos validation layer, its messages counted */
} btf_gpu_opts;

/* The defaults that a zero field of btf_gpu_opts stands for. */
btf_gpu_opts btf_gpu_defaults(void);

btf_status btf_gpu_open(const btf_gpu_opts *opts, btf_gpu **out, btf_error *err);
void btf_gpu_close(btf_gpu *g);
const char *btf_gpu_device_name(const btf_gpu *g);
int btf_gpu_is_cpu(const btf_gpu *g);             /* 1 for lavapipe */
unsigned btf_gpu_validation_errors(const btf_gpu *g);
const char *btf_gpu_first_validation_message(const btf_gpu *g);

/* Synthesises n subspace images into outs[0 .. n-1] (allocated here, linear
 * RGB), as btf_synthesise with the same opts would (the CPU switches do not
 * apply). Images are grouped in batches and cut into strips of rows so that
 * every GPU buffer fits the device's limit; the causal fields carry their
 * last rows from strip to strip, so the result is the same whatever the
 * tiling. The structure layer and colour matching run on the device
 * (docs/gpu.md, "Colour matching on the device"), the CPU's bits. */
btf_status btf_gpu_synthesise(btf_gpu *g, const btf_model *m, const int *subspaces, int n,
                              const btf_synth_opts *opts, btf_image *outs, btf_error *err);
/* The bytes of images btf_gpu_synthesise_each keeps on the device at once:
 * a quarter of the device's largest device-local heap (the rest for the
 * synthesis' own buffers and other programs), at most the 4 storage
 * buffers of the device's limit that one group of images may span. */
uint64_t btf_gpu_memory_budget(const btf_gpu *g);
/* Whether the CLI's synthesis runs a work whose largest image takes
 * image_bytes on g (docs/gpu.md, "Choosing a backend": auto opens only a
 * real GPU, btf_gpu_opts.allow_cpu 0, or the device named): the image fits
 * g's memory budget; else auto takes the CPU, which streams, and --backend
 * gpu is refused. */
int btf_gpu_auto_fits(const btf_gpu *g, uint64_t image_bytes);
/* The rule of --backend auto over a device list (btf_gpu_list_devices;
 * docs/gpu.md, "Choosing a backend"): the index (btf_gpu_device.index) of
 * the device a work whose largest image takes image_bytes (0: any) runs
 * on — the best usable real GPU (discrete, then integrated, then virtual;
 * never a CPU device such as lavapipe) whose memory budget holds the
 * image — or -1 for the CPU. */
int btf_gpu_auto_device(const btf_gpu_device *list, int n, uint64_t image_bytes);
/* The same images handed to fn in order (btf_image_fn: fn may keep each),
 * synthesised in groups that fit btf_gpu_memory_budget, each group
 * finished on the device and read back one image at a time: at most one
 * image on the host besides what fn keeps, whatever n. An image larger
 * than the budget alone is synthesised in strips straight to the host and
 * finished there by the CPU's code (the same bits). */
btf_status btf_gpu_synthesise_each(btf_gpu *g, const btf_model *m, const int *subspaces, int n,
                                   const btf_synth_opts *opts, btf_image_fn fn, void *user,
                                   btf_error *err);

/* ------------------------------------------ hemisphere interpolation (render) */

/* Haindl & Filip 2007, section III and Fig. 1: a pixel's local view (or
 * light) direction is interpolated from the three measured directions that
 * enclose it, with barycentric weights, on a triangulation of the measured
 * set (src/render/hemisphere.c, docs/render.md). Local directions are in
 * the tangent frame: x along the texture's columns (phi = 0), y up the
 * image (phi = 90), z the surface normal. */
typedef struct btf_hemisphere btf_hemisphere; /* opaque */

/* Triangulates a direction set: the directions projected to the unit disk
 * (azimuthal equidistant, radius theta / 90 degrees, azimuth phi), then a
 * Delaunay triangulation of the points, ties between cocircular points
 * broken by the set's order, and a grid of cells over [-1, 1]^2 listing the
 * triangles that may cover each. Errors (BTF_E_ARG, naming the set): fewer
 * than 3 directions, more than BTF_HEMISPHERE_MAX_POINTS, a theta outside
 * [0, 90] or non-finite, two directions on the same projected point (e.g.
 * the pole twice), all directions on one line after the projection (one
 * great circle through the pole). */
#define BTF_HEMISPHERE_MAX_POINTS 1024
btf_status btf_hemisphere_build(const btf_dirset *set, btf_hemisphere **out, btf_error *err);
void btf_hemisphere_free(btf_hemisphere *h);
/* The three set indices enclosing local direction v (any non-zero vector:
 * beyond the outermost ring and below the horizon too, by the rule in
 * docs/render.md) and their weights: w >= 0, summing to 1, continuous in
 * v, 1 at a measured direction. A zero or non-finite v is taken as the
 * pole. Beyond the hull the third weight is 0 (idx[2] then names the apex
 * of the triangle on that hull edge). */
void btf_hemisphere_lookup(const btf_hemisphere *h, const float v[3], int idx[3], float w[3]);

/* The flat tables the CPU and GPU lookups both read (the lookup itself is
 * src/render/btf_hemisphere_lookup.h, the same text for C and GLSL). The
 * pointers stay owned by h. */
typedef struct btf_hemisphere_table {
    int n_points, n_triangles;
    const float *points;        /* [n_points][2]: the projected directions, set order */
    const int32_t *triangles;   /* [n_triangles][3]: point indices, counter-clockwise */
    int grid;                   /* grid x grid cells over [-1, 1]^2, row-major from (-1, -1) */
    const int32_t *cell_start;  /* [grid * grid + 1]: cell c's triangles are */
    const int32_t *cell_tris;   /*   cell_tris[cell_start[c] .. cell_start[c + 1]) */
    int n_cell_tris;
    int n_hull;                 /* the outer boundary, counter-clockwise: */
    const int32_t *hull;        /*   [n_hull] point indices (collinear ones included) */
    const int32_t *hull_apex;   /* [n_hull]: the third vertex of the triangle on edge
                                   hull[i] -> hull[(i + 1) % n_hull] */
} btf_hemisphere_table;
void btf_hemisphere_get_table(const btf_hemisphere *h, btf_hemisphere_table *t);

/* ---------------------------------------------------- range and normal map */

/* The model's range tile (paper section II.B) enlarged to a seamless
 * width x height map in analysed-image texels: the map wraps (its right
 * edge continues into its left, its bottom into its top) at any size
 * (docs/render.md says how). height: width x height x 1, heights in
 * analysed-image texels (multiply by a relief scale to exaggerate);
 * normal: width x height x 3 unit normals in the tangent frame (x right,
 * y up the image, z out), derived from the heights with wrap-around
 * differences. Either output may be NULL. A model without a range map
 * gives a flat map (heights 0, normals (0, 0, 1)). */
btf_status btf_range_map(const btf_model *m, int width, int height, btf_image *height_out,
                         btf_image *normal_out, btf_error *err);
/* The same with the structure layer (docs/model.md, "Structure"): a model
 * whose range map is at the analysed resolution gets its heights, normals
 * and albedo pattern quilted onto the width x height torus by one
 * coordinate map drawn from seed (the seed of the synthesis they go with:
 * btf_synthesise multiplies the same pattern into its images), so the
 * layers are registered with each other and the map tiles without a seam.
 * A model with a small periodic tile gets btf_range_map's heights and an
 * albedo of 1. The albedo has one channel, or three (RGB) when the model
 * has a colour layer (btf_model.chroma). Any output may be NULL. */
btf_status btf_structure_maps(const btf_model *m, int width, int height, uint64_t seed,
                              btf_image *height_out, btf_image *normal_out,
                              btf_image *albedo_out, btf_error *err);
/* The unit normals of the height map scale * h (1 channel) into normal
 * (allocated here, 3 channels, same size): n = normalize(-dh/dx, -dh/dy, 1)
 * with x right and y up the image (rows grow downwards), from wrap-around
 * central differences, so a map that wraps gives normals that wrap. Finite
 * heights give finite unit normals (scale finite; huge slopes included). */
btf_status btf_normal_map(const btf_image *height, double scale, btf_image *normal,
                          btf_error *err);
/* Makes a range tile periodic in place (analysis does, and reading a model
 * file of format 1.0 does): its mean slope removed, then a variance-
 * preserving cross-fade with itself shifted by half a period along each
 * axis (docs/render.md), which keeps the tile's mean and variance and
 * removes the jumps between opposite edges; the result lies on the model
 * file's 16-bit height grid, so writing it loses nothing. Heights must be
 * finite (BTF_E_DATA). */
btf_status btf_range_make_periodic(float *heights, int width, int height, btf_error *err);

/* ----------------------------------------------------------------- scenes */

/* A scene for btf_render_scene (src/scene/, docs/scene.md): a pinhole
 * camera, lights and objects, buildable by a program without a file.
 * World units are arbitrary; right-handed coordinates. */
typedef struct btf_camera {
    double position[3], target[3], up[3];
    double fov_deg;                 /* vertical field of view, (0, 180) */
} btf_camera;

typedef enum btf_light_kind { BTF_LIGHT_DIRECTIONAL = 0, BTF_LIGHT_POINT } btf_light_kind;

typedef struct btf_light {
    btf_light_kind kind;
    double direction[3];            /* directional: towards the light (unit) */
    double position[3];             /* point: its position; falls off as 1/d^2 */
    float rgb[3];                   /* intensity per channel */
} btf_light;

typedef enum btf_object_kind {
    BTF_OBJECT_PLANE = 0,           /* a square of side `size` around center, normal `axis` */
    BTF_OBJECT_SPHERE,              /* center, radius */
    BTF_OBJECT_CYLINDER,            /* center (of its axis), axis, radius, height; open ends */
    BTF_OBJECT_MESH                 /* triangles with UVs */
} btf_object_kind;

typedef struct btf_mesh {
    int n_vertices, n_triangles;
    float *positions;               /* [n_vertices][3] */
    float *normals;                 /* [n_vertices][3] or NULL (face normals) */
    float *uvs;                     /* [n_vertices][2]: UV channel 0, top-left origin (v down
                                       the rows), in the file's units; the trace multiplies by
                                       texture_scale and turns by rotation_deg */
    uint32_t *indices;              /* [n_triangles][3] */
} btf_mesh;

typedef struct btf_object {
    btf_object_kind kind;
    double center[3];               /* mesh: added to its vertices */
    double axis[3];                 /* plane normal, sphere pole, cylinder axis; unit */
    double radius, height, size;
    double texture_scale;           /* texels of the material per world unit (mesh: per UV unit) */
    double rotation_deg;            /* the material turned on the surface */
    btf_mesh mesh;                  /* BTF_OBJECT_MESH: owned by the scene */
} btf_object;

typedef struct btf_scene {
    btf_camera camera;
    int n_lights;
    btf_light *lights;
    int n_objects;
    btf_object *objects;
    float background[3];            /* linear RGB */
} btf_scene;

/* Reads a JSON scene file (docs/scene.md; meshes through assimp): any bad
 * key, type, value, missing or UV-less mesh is one error naming the file
 * and the key. Every file read is a regular file, and the files a mesh
 * names (mtllib, glTF buffers) lie in the mesh's folder or below. */
btf_status btf_scene_load(const char *path, btf_scene *out, btf_error *err);
/* Checks a scene built in memory (degenerate camera, zero radius, ...). */
btf_status btf_scene_check(const btf_scene *s, btf_error *err);
void btf_scene_free(btf_scene *s);
/* The material preview scene (src/scene/scene_sphere.c): a unit sphere
 * filling most of the frame, seen along -z, under one white directional
 * light given as a direction in the camera's frame (theta 0: from the
 * camera), texture_scale texels per world unit, a dark background. Free
 * it with btf_scene_free. */
btf_status btf_scene_sphere(btf_dir light, double texture_scale, btf_scene *out, btf_error *err);

/* What ray casting gives per pixel: the G-buffer the renderer shades (and
 * uploads for the GPU pass). Pixel (x, y), row y from the top; arrays are
 * row-major, p = y * width + x. frame rows: T (direction of increasing u),
 * B (decreasing v: up the texture image), N (shading normal towards the
 * eye); orthonormal, T x B = N. uv may be negative or beyond the texture
 * (the renderer wraps); a surface seen from behind has u negated so that
 * the material never reads mirrored (docs/scene.md). Background pixels:
 * object -1, uv 0, position 0, frame the identity, view still the ray's. */
typedef struct btf_gbuffer {
    int width, height;
    int32_t *object;                /* object index, -1: background */
    float *uv;                      /* [2] material texels: u along columns, v down rows */
    float *frame;                   /* [9] tangent (phi = 0), bitangent (phi = 90), normal; world */
    float *position;                /* [3] world hit point */
    float *view;                    /* [3] world unit vector from the hit towards the eye */
} btf_gbuffer;

/* Casts one ray per pixel centre (BVH over mesh triangles, built per call),
 * on `threads` threads (0: all CPUs); the result does not depend on the
 * thread count. Checks the scene first (btf_scene_check). width, height in
 * 1 .. 65536. */
btf_status btf_scene_trace(const btf_scene *s, int width, int height, int threads,
                           btf_gbuffer *out, btf_error *err);
void btf_gbuffer_free(btf_gbuffer *g);

/* ---------------------------------------------------------------- render */

/* The paper's rendering stage (Haindl & Filip 2007, section III, Fig. 1;
 * src/render/, docs/render.md): per pixel, the local view and light
 * directions select the 3 nearest measured views x 3 nearest lights; the
 * nine (view, light) pairs select subspace images through the index table,
 * which are sampled at parallax-shifted texture coordinates and blended with
 * the barycentric weights; the result is relit by the range map's normals. */
typedef struct btf_render_opts {
    int width, height;   /* frame size, 1..BTF_RENDER_MAX_SIDE; 0: 512 */
    uint64_t seed;       /* synthesis seed of the subspace images */
    int threads;         /* 0: all CPUs */
    double relief;       /* range map height scale (parallax and bump); 0: off; < 0: 1 */
    int texture_size;    /* side of the synthesised tileable subspace images and
                            range map, in analysed texels; 0: what the visible
                            surface needs (docs/render.md) */
    int all_subspaces;   /* 1: synthesise every subspace, not only the needed ones */
} btf_render_opts;
#define BTF_RENDER_MAX_SIDE 16384
btf_render_opts btf_render_defaults(void);

/* What a render did (times in seconds). */
typedef struct btf_render_info {
    int needed, total;   /* subspaces synthesised, of the model's */
    int texture_size;
    double trace_s, synth_s, shade_s;
} btf_render_info;

/* The subspaces (needed[k] = 1) that the nine pairs of any pixel of g
 * select under any of the lights, and their count. needed has
 * m->n_subspaces entries. */
btf_status btf_render_needed(const btf_model *m, const btf_gbuffer *g, const btf_light *lights,
                             int n_lights, uint8_t *needed, int *count, btf_error *err);

/* A material ready to shade with: the model's hemisphere tables, its
 * range and normal map, and the synthesised (tileable) subspace images
 * (only those with needed[k] set; needed NULL: all), all of side
 * texture_size. Kept in memory; repeated renders reuse it. */
typedef struct btf_render_material btf_render_material;
btf_status btf_render_material_build(const btf_model *m, const uint8_t *needed,
                                     int texture_size, uint64_t seed, int threads,
                                     btf_render_material **out, btf_error *err);
void btf_render_material_free(btf_render_material *rm);

/* Shades a G-buffer into out (linear RGB, g's size; allocated here). A pixel
 * that needs a subspace the material was not built with is an error. */
btf_status btf_render_shade(const btf_render_material *rm, const btf_gbuffer *g,
                            const btf_light *lights, int n_lights, const float background[3],
                            double relief, int threads, btf_image *out, btf_error *err);

/* The whole render of a scene: trace, the needed subspaces, synthesis, shade. */
btf_status btf_render_scene(const btf_model *m, const btf_scene *s, const btf_render_opts *opts,
                            btf_image *out, btf_render_info *info, btf_error *err);

/* The model's counterpart of one measured image: a flat patch seen from
 * `view` and lit (unit white directional light) from `light`,
 * orthographic, texel (x, y) of the frame at texture texel (x, y). */
btf_status btf_render_flat(const btf_model *m, btf_dir view, btf_dir light,
                           const btf_render_opts *opts, btf_image *out, btf_render_info *info,
                           btf_error *err);

/* -------------------------------------------------------- render (GPU) */

/* The GPU render pass (gpu/render_gpu.c, docs/render.md, "On the GPU"):
 * the same plan as btf_render_scene / btf_render_flat (G-buffer traced on
 * the CPU, the needed subspaces), then two compute passes on g's device:
 * the needed subspaces synthesised tileable into one device buffer, left
 * there, and a render shader running the CPU renderer's shading text
 * (src/render/btf_render_shared.h). A frame beyond the device's buffer
 * limits is rendered in bands of rows. info's synth_s and shade_s are the
 * two passes. */
btf_status btf_gpu_render_scene(btf_gpu *g, const btf_model *m, const btf_scene *s,
                                const btf_render_opts *opts, btf_image *out,
                                btf_render_info *info, btf_error *err);
btf_status btf_gpu_render_flat(btf_gpu *g, const btf_model *m, btf_dir view, btf_dir light,
                               const btf_render_opts *opts, btf_image *out,
                               btf_render_info *info, btf_error *err);

/* --------------------------------------- texture distances (issue 17) */

/* Distances between two colour textures without pixel correspondence
 * (src/measure/, docs/measure.md): any two sizes, each side at least 16.
 * Both images are measured in CIE Lab (linear RGB converted by OpenCV;
 * values above 1 scaled by one exposure the reference fixes, 1 / its
 * largest value, the same for both; negative values count as 0). */
typedef struct btf_texture_distance_opts {
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

/* ------------------------------------ report: compression accounting (issue 18) */
/* What a model file costs, section by section, and what two plain codecs
 * would store for the same data (src/report/, docs/report.md). */

/* The parts of an encoded model file (docs/report-compression.md). */
typedef enum btf_model_part {
    BTF_MODEL_PART_CONTAINER = 0, /* the 26-byte file header and the CRC-32 */
    BTF_MODEL_PART_DEFLATE,       /* zlib's header and Adler-32, deflate's block
                                     headers, code tables, end-of-block codes
                                     and final padding (0 when stored) */
    BTF_MODEL_PART_FRAMING,       /* section tags and lengths, the subspace and
                                     marginal counts, each subspace's
                                     representative pair and analysed size */
    BTF_MODEL_PART_DIRECTIONS,    /* VIEW and LGHT: names, counts, directions */
    BTF_MODEL_PART_INDEX,         /* INDX: the index table */
    BTF_MODEL_PART_SPECTRAL,      /* per subspace: the mean colour and the 3 x 3 basis */
    BTF_MODEL_PART_LEVELS,        /* per subspace: the pyramid level count */
    BTF_MODEL_PART_NEIGHBOURHOODS,/* per band: neighbour count and offsets */
    BTF_MODEL_PART_GAMMAS,        /* per band: the CAR coefficients */
    BTF_MODEL_PART_SIGMAS,        /* per band: the noise deviation */
    BTF_MODEL_PART_BAND_MEANS,    /* per band: the sub-band mean */
    BTF_MODEL_PART_MARGINALS,     /* MARG: per subspace its knot count and transfer */
    BTF_MODEL_PART_RANGE,         /* RANG: the range/normal tile, all of its body */
    BTF_MODEL_PART_STRUCTURE,     /* STRC: the albedo pattern and the shading's ambient */
    BTF_MODEL_PART_GAINS,         /* GAIN: the pair gains */
    BTF_MODEL_PART_COUNT
} btf_model_part;

/* A short name of a part ("gammas", ...); "?" out of range. */
const char *btf_model_part_name(int part);

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
btf_status btf_model_byte_breakdown(const btf_model *m, btf_model_bytes *out, btf_error *err);

/* The raw BTF a dataset holds: what the report's ratios divide (also
 * filled into the PCA and JPEG results below). */
typedef struct btf_raw_bytes {
    int views, lights, width, height;
    uint64_t raw;           /* views x lights x width x height x 3, one byte per value */
    uint64_t on_disk;       /* btf_dataset_info.bytes_on_disk: the image files' sizes */
} btf_raw_bytes;
btf_status btf_dataset_raw_bytes(const btf_dataset *ds, btf_raw_bytes *out, btf_error *err);

/* The pixel-wise contrast: per view, a PCA of its n_lights images. Values
 * are the images' sRGB encoding clamped to [0, 1] and scaled to 0..255 (for
 * 8-bit files exactly the stored values). c is the smallest number of
 * components whose RMS error over the view's values (from the discarded
 * eigenvalues) is at most max_rms; stored: the mean image, c eigen-images and
 * n_lights x c weights, each value in `bits` bits (docs/report-compression.md). */
typedef struct btf_pca_opts {
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
 * defaults. Free out with btf_pca_result_free (NULL and twice are fine). */
btf_status btf_pca_contrast(const btf_dataset *ds, const btf_pca_opts *opts,
                            btf_pca_result *out, btf_error *err);
void btf_pca_result_free(btf_pca_result *r);

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
btf_status btf_jpeg_subspace_contrast(const btf_dataset *ds, const btf_model *m, int quality,
                                      btf_jpeg_contrast *out, btf_error *err);

/* (end of compression accounting) */

/* ------------------------------------- report: quality per direction (issue 18) */
/* How close the model comes to the measurement, pair by pair, measured by
 * the texture distances above (src/report/, docs/report.md). */

typedef struct btf_quality_opts {
    int all;                  /* 1: every (view, light) pair of the dataset */
    int views, lights;        /* the spread measured when not all: this many views and
                                 lights (btf_spread_directions; 0: 9 each; more than
                                 the dataset has: all of them) */
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

typedef struct btf_pair_quality {
    int view, light;          /* dataset indices */
    int subspace;             /* the model's index-table entry for the pair; -1
                                 for a pair the model did not measure */
    int held_out;             /* 1: the model did not measure the pair (left out
                                 of its analysis): its render interpolates */
    btf_texture_distances d;  /* measured image (reference) against the flat render */
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
btf_status btf_quality_measure(const btf_dataset *ds, const btf_model *m,
                               const btf_quality_opts *opts, btf_quality *out, btf_error *err);
void btf_quality_free(btf_quality *q);
/* The spread: indices of n directions of set, evenly strided through the
 * set's order (ring by ring from the pole, phi ascending in a ring):
 * idx[i] = floor(i count / n), so every ring gets its share and the
 * azimuths vary. n is clamped to 1..set->count; returns the count written
 * to idx. */
int btf_spread_directions(const btf_dirset *set, int n, int *idx);

/* (end of quality per direction) */

/* ------------------------------------ report: sweep, presets, the page (issue 18) */
/* The speed/accuracy trade measured over a grid of settings, the presets
 * chosen from it, and the report page (src/report/, docs/report.md). */

/* One setting of the trade: the analysis options a sweep varies (0: the
 * analysis's automatic choice). */
typedef struct btf_sweep_setting {
    int subspaces;            /* K; 0: auto */
    int levels;               /* pyramid levels; 0: auto */
    int neighbours;           /* a fixed neighbourhood of the first n candidate
                                 offsets (btf_car_candidate_offsets); 0: the
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
    double mean_combined, worst_combined; /* btf_quality_measure over the spread,
                                             the mean over the seeds */
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
#define BTF_SWEEP_MAX_SEEDS 16
typedef struct btf_sweep_opts {
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
                                  grid's steps); 0: 3; 1..16 */
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

/* The speed/accuracy trade (docs/report.md, "The sweep"): the dataset
 * analysed under every setting of the grid, each model timed (analysis,
 * synthesis, the sphere frame), sized and measured (btf_quality_measure);
 * the Pareto fronts marked. The features and the range map are computed
 * once and shared. Settings run in parallel, one per thread; each finished
 * point is written to state_dir at once, so an interrupted sweep resumes
 * where it stopped (a point whose file names another dataset or other
 * sweep options is measured again). */
btf_status btf_sweep_run(const btf_dataset *ds, const btf_sweep_opts *opts, btf_sweep *out,
                         btf_error *err);
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

/* Named points of the trade for btfcar analyse --preset (docs/report.md,
 * "Presets"): "fast", "balanced" (the defaults) or "accurate" set the
 * subspaces, levels and neighbourhood of o; BTF_E_ARG for another name. */
btf_status btf_analyse_preset(const char *name, btf_analyse_opts *o, btf_error *err);
/* The preset names, NULL-terminated. */
const char *const *btf_analyse_preset_names(void);

/* The report (docs/report.md): DIR/index.html, self-contained (PNG
 * pictures and SVG plots beside it, no scripts, nothing fetched), and
 * DIR/report.json with the same numbers (keys: docs/report.md). */
typedef struct btf_report_opts {
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
    int sweep;                   /* 1: measure the trade (btf_sweep_run; its finished
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
 * (the merge) reads them back. *out as btf_sweep_run's (free it). */
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
    double mean_abs_error;       /* btf_rf_report_write only: mean |Y data - Y model| over
                                    every image (btf_rf_error); 0 for a CAR report */
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

/* (end of sweep, presets, the page) */

/* ------------------------------------- reflectance fields (issue 19) */

/* The pixel-wise alternative to the CAR model, the accuracy end of the
 * speed/accuracy trade (Meseth, Müller & Klein 2003, "Preserving realism in
 * real-time rendering of bidirectional texture functions"; docs/rf.md):
 * per measured view v and texel x a reflectance field RF_v(x, l) is fitted
 * over the light directions l (paper section 3.1), on luminance, with the
 * colour from the per-view, per-texel average chromaticity (section 4.2);
 * rendering interpolates the four closest measured views (section 5.4).
 *
 *  - BTF_RF_PTM: a biquadratic polynomial texture map in the light's (lu, lv)
 *    = (lx, ly), linear least squares: a0 lu^2 + a1 lv^2 + a2 lu lv + a3 lu
 *    + a4 lv + a5 (6 parameters).
 *  - BTF_RF_LOBES: k non-linear lobes, equation (1), <(a,b,c), l>^n, fitted
 *    by Levenberg-Marquardt, kept as rho <d, l>^n with the unit direction
 *    d = (x, y, 1) / |(x, y, 1)| and rho = |(a,b,c)|^n (the same function;
 *    this form cannot overflow): 4 parameters per lobe (rho, x, y, log2 n).
 *  - BTF_RF_LAFORTUNE: for contrast, one Lafortune model per texel over all
 *    views (Table 1's first column): rho_d l_z + sum of k lobes
 *    rho (cx lx vx + cy ly vy + cz lz vz)^n, 1 + 5k parameters, one colour
 *    per texel.
 *
 * Every parameter is kept as a 16-bit code with a per-field (per-view)
 * scale and offset per parameter slot: v = lo + code (hi - lo) / 65535, an
 * error of at most (hi - lo) / 131070 (docs/rf.md, "Quantisation").
 * Clamps keep every evaluation finite: rho in [0, BTF_RF_MAX_RHO], n in
 * [BTF_RF_MIN_EXPONENT, BTF_RF_MAX_EXPONENT], |x|, |y| <= 16 and
 * |cx|, |cy|, |cz| <= 1, so no lobe exceeds its rho. */
typedef enum btf_rf_fit_kind {
    BTF_RF_PTM = 0,       /* default */
    BTF_RF_LOBES = 1,
    BTF_RF_LAFORTUNE = 2
} btf_rf_fit_kind;
#define BTF_RF_MAX_LOBES 4
#define BTF_RF_MAX_RHO 1.0e4f
#define BTF_RF_MIN_EXPONENT 0.25f
#define BTF_RF_MAX_EXPONENT 1024.0f
/* The parameter slots of a texel in one field: its luminance parameters,
 * then 3 chromaticity factors (rgb = chroma x luminance). */
#define BTF_RF_MAX_SLOTS (1 + 5 * BTF_RF_MAX_LOBES + 3)

/* The name of a fit ("ptm", "lobes", "lafortune"); NULL if out of range. */
const char *btf_rf_fit_name(int fit);

/* Where a fit spent its time and how well it did (NULL: not wanted). */
typedef struct btf_rf_fit_info {
    double read_s, fit_s, seconds;  /* decoding the images, fitting, in all */
    double mean_abs_error;          /* mean |Y data - Y model| over every texel and
                                       image, with the quantised parameters */
    double mean_luminance;          /* the data's mean luminance */
    long long lm_runs, lm_iterations; /* Levenberg-Marquardt solves and their steps */
    /* btf_rf_fit_sampled only (paper section 6); then mean_abs_error and
     * mean_luminance are over every image and texel of the dataset through
     * the coordinate map (btf_rf_error), seconds the whole call's. */
    double sample_mean_abs_error; /* the fit's error on the sample's own texels
                                     (per-view fits; 0 for lafortune) */
    double sample_s;              /* reading the head-on view, choosing the sample */
    double quilt_s;               /* synthesising the coordinate map */
    double error_s;               /* the error pass over the dataset */
    int quilt_block, quilt_overlap; /* the block and overlap sides used */
} btf_rf_fit_info;

typedef struct btf_rf_opts {
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

/* A fitted model. codes[(field * height * width + texel) * slots + s] is
 * slot s of a texel (texel = y * width + x) in field `field` (a view, or
 * the one field of a Lafortune model); lo/hi[field * slots + s] its range. */
typedef struct btf_rf_model {
    int fit;                   /* btf_rf_fit_kind */
    int lobes;                 /* k */
    int width, height;         /* texels */
    btf_dirset views, lights;  /* the measured directions */
    int params;                /* luminance parameters per texel and field */
    int slots;                 /* params + 3 */
    int fields;                /* views.count (ptm, lobes) or 1 (lafortune) */
    float *lo, *hi;            /* [fields * slots] */
    uint16_t *codes;           /* [fields * width * height * slots] */
    /* Memory reduction (paper section 6; btf_rf_fit_sampled): map NULL (the
     * model describes its width x height texels), or the texture coordinates
     * of a surface of surface_width x surface_height texels into the fitted
     * width x height sample: surface texel (x, y) is sample texel
     * (map[2 (y surface_width + x)], map[2 (y surface_width + x) + 1]).
     * (sample_x, sample_y): where the sample lies in the dataset's images,
     * and in the surface, whose texels there map to themselves. */
    int surface_width, surface_height;
    int sample_x, sample_y;
    uint16_t *map;             /* [surface_height * surface_width * 2], or NULL */
} btf_rf_model;
void btf_rf_model_free(btf_rf_model *m);
/* The texels the model describes: the coordinate map's size when it has one,
 * else width x height. Every evaluation (flat and scene render, btf_rf_eval,
 * btf_rf_error) wraps coordinates into this surface. */
void btf_rf_surface_size(const btf_rf_model *m, int *width, int *height);
/* Luminance parameters per texel and field of a fit with k lobes. */
int btf_rf_param_count(int fit, int lobes);

/* Fits the dataset: per view, the n_lights images are read (one view's
 * lights at a time; lafortune: every image, texel rows in passes bounded by
 * opts->memory), converted to luminance Y = 0.2126 R + 0.7152 G + 0.0722 B,
 * and every texel fitted in parallel (the result does not depend on the
 * thread count). Dark, saturated and constant texels give finite fits. */
/* BTF_E_DATA with the message when ds is a sparse set (the family fits
 * every light at each view); BTF_OK for a full grid. */
btf_status btf_rf_refuse_sparse(const btf_dataset *ds, btf_error *err);
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

/* What a model costs (docs/rf.md, "Memory reduction"): in memory, the
 * coefficients (fields x slots x (2 bytes per texel + 8 for the range)) and
 * the coordinate map (4 bytes per surface texel; 0 without one), and in
 * the file (btf_rf_encode, deflated) in all and for the map alone (the
 * file's bytes less those of the same model without its map). */
typedef struct btf_rf_bytes {
    uint64_t coefficients, map;   /* in memory */
    uint64_t file, file_map;      /* the file; of which the map */
} btf_rf_bytes;
btf_status btf_rf_model_bytes(const btf_rf_model *m, btf_rf_bytes *out, btf_error *err);

/* The four closest measured views of a direction (paper section 5.4): the
 * two measured theta rings around theta (one at the pole or beyond the
 * last ring), on each the two measured azimuths around phi, bilinear weights
 * in theta and phi that sum to 1 (computed in float, as the renderers
 * blend: to 1e-6). idx[i] and w[i], i < 4 (an index may repeat, e.g. at
 * the pole; unused weights are 0). */
void btf_rf_view_weights(const btf_dirset *views, btf_dir view, int idx[4], double w[4]);

/* Linear RGB of texel (x, y) (wrapped into the surface, btf_rf_surface_size;
 * a sampled model's through its coordinate map) of field `field` (a view
 * index; 0 for lafortune) lit from `light` (view: the view direction, used
 * by lafortune only). */
void btf_rf_eval_field(const btf_rf_model *m, int field, btf_dir view, btf_dir light, int x,
                       int y, float rgb[3]);
/* The same at any view: the four closest views' fields weighted
 * (btf_rf_view_weights); lafortune evaluates its one field at the view. */
void btf_rf_eval(const btf_rf_model *m, btf_dir view, btf_dir light, int x, int y,
                 float rgb[3]);
/* The flat (view, light) render of docs/render.md with an RF model: pixel
 * (x, y) is surface texel (x mod width, y mod height) (btf_rf_surface_size;
 * a sampled model's through its map), lit by one unit light. width/height
 * 0: the surface's. threads 0: all CPUs. */
btf_status btf_rf_render_flat(const btf_rf_model *m, btf_dir view, btf_dir light, int width,
                              int height, int threads, btf_image *out, btf_error *err);

/* A scene (btf_scene_load, docs/scene.md) rendered with an RF model on the
 * CPU: traced into the CAR renderer's G-buffer (btf_scene_trace); per pixel
 * the local view and light directions in the tangent frame (as
 * btf_render_shade takes them: a light below the surface's horizon gives
 * nothing, a point light falls off as 1/d^2), the texel floor(uv) wrapped
 * into the model's surface (through a sampled model's map), the four
 * closest views' fields at the exact
 * light blended (the flat render's arithmetic), times each light's
 * intensity; background pixels the scene's background. No parallax or bump
 * mapping (the fields hold the relief). width/height 0: 512; threads 0:
 * all CPUs. info (NULL: not wanted): trace_s and shade_s, the rest 0. */
btf_status btf_rf_render_scene(const btf_rf_model *m, const btf_scene *s, int width,
                               int height, int threads, btf_image *out, btf_render_info *info,
                               btf_error *err);

/* The same two renders on g's Vulkan device (gpu/rf_render_gpu.c,
 * gpu/rf_render.comp; docs/rf.md, "Rendering on the GPU"), with the
 * formulas of the CPU renders (one text, src/rf/btf_rf_shared.h): on
 * lavapipe the pixels are the CPU's bit for bit, on other devices within
 * the rounding of sqrt and division. The flat render uploads only the (at
 * most four) fields of the view and shades each distinct texel once; the
 * scene render traces on the host (threads: 0 all CPUs) and uploads every
 * field. A model whose codes exceed 4 of the device's largest storage
 * buffers is BTF_E_UNSUPPORTED. info (NULL: not wanted): trace_s (scene),
 * synth_s the upload of the model's fields and parameters, shade_s the
 * render pass with its download. */
btf_status btf_gpu_rf_render_flat(btf_gpu *g, const btf_rf_model *m, btf_dir view,
                                  btf_dir light, int width, int height, btf_image *out,
                                  btf_render_info *info, btf_error *err);
btf_status btf_gpu_rf_render_scene(btf_gpu *g, const btf_rf_model *m, const btf_scene *s,
                                   int width, int height, int threads, btf_image *out,
                                   btf_render_info *info, btf_error *err);

/* Table 1 of the paper: the mean |Y data - Y model| over every texel and
 * (view, light) image of ds, the model evaluated at the measured directions;
 * mean_luminance: the data's. The dataset must have the model's direction
 * sets, and its size unless the model is sampled: then data texel (x, y)
 * is compared with surface texel (x, y), wrapped, as the flat render shows
 * it (no correspondence outside the sample's own place). */
btf_status btf_rf_error(const btf_dataset *ds, const btf_rf_model *m, int threads,
                        double *mean_abs_error, double *mean_luminance, btf_error *err);

/* The report of an RF model (docs/report.md, "Reflectance-field models"),
 * the counterpart of btf_report_write in the same folder layout: the model
 * file's bytes against the raw BTF; per sampled pair (opts->quality: the
 * spread or all) the measured image against btf_rf_render_flat of that
 * pair by btf_texture_distance and the pixel-wise mean |dY|; the mean |dY|
 * over every image (btf_rf_error); pictures of the sampled pairs and of the
 * opts->worst pairs by |dY|; the preview sphere (btf_rf_render_scene);
 * DIR/index.html and DIR/report.json. The model must be of ds (size and
 * direction sets; BTF_E_ARG). opts->sweep is BTF_E_ARG (no CAR settings to
 * trade); the PCA, JPEG and relief options do not apply. */
btf_status btf_rf_report_write(const btf_dataset *ds, const btf_rf_model *m, const char *dir,
                               const btf_report_opts *opts, btf_report_summary *summary,
                               btf_error *err);

/* The file (docs/rf.md, "File"): the container of MODEL.btfcar (version,
 * zlib, CRC-32) with its own signature "\x89BTFRFL\r\n\x1a\n" and sections.
 * name (NULL: "buffer") names the buffer in messages. The decoder checks
 * everything and never trusts a size it has not bounded. */
btf_status btf_rf_encode(const btf_rf_model *m, unsigned char **data, size_t *size,
                         btf_error *err);
btf_status btf_rf_decode(const unsigned char *data, size_t size, const char *name,
                         btf_rf_model *out, btf_error *err);
btf_status btf_rf_write(const char *path, const btf_rf_model *m, btf_error *err);
btf_status btf_rf_read(const char *path, btf_rf_model *out, btf_error *err);
/* 1 when the bytes start like a reflectance-field file (the signature's
 * first 7 bytes), else 0. */
int btf_rf_sniff(const unsigned char *data, size_t size);

#ifdef __cplusplus
}
#endif

#pragma GCC visibility pop

/* One interface over the model families. */
#include "btfcar/material.h"

#endif /* BTFCAR_H */
