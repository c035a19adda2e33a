/*
 * ubo2014.h — the Bonn BTF database's binary .btf files (DFMF, FMF, PVF,
 * BDIF), private to src/dataset/. The format is the one of its public
 * readers and writer (btflib, the University of Bonn's MATLAB library;
 * Velinov's C++ btf.hh; pysmtb's btf.py): docs/datasets.md ("UBO2014 .btf
 * files") describes it as "the notes" with the section numbers §N used
 * here, and states the rules btfcar follows where the sources leave a
 * doubt.
 *
 *   ubo_parse.c    signature, meta block, sampling, size, rotations and the
 *                  variant's body: offsets into the bytes, every size checked
 *   ubo_decode.c   one (view, light) image from the factors or the values,
 *                  colour models, the cosine rule
 *   ubo_open.c     a file mapped with mmap, its direction sets
 *   ubo_svd.c      the writers' eigenpairs (the Jacobi and Cholesky of
 *                  core/linalg.c beneath)
 *   ubo_out.c      what the writers share: header bytes, the output file,
 *                  stored scalars, the images of the callback
 *   ubo_factor.c   the truncated SVD of images for DFMF and FMF
 *   ubo_write.c    the DFMF, FMF and BDIF writers, btf_ubo2014_write
 *   ubo_write_pvf.c  the PVF writer (a PCA per view)
 */
#ifndef BTF_IO_UBO2014_H
#define BTF_IO_UBO2014_H

#include "btfcar.h"

#include <stddef.h>
#include <stdint.h>
#include <string.h>

enum { UBO_DFMF = 1, UBO_FMF, UBO_PVF, UBO_BDIF };

/* A row-major matrix of rows x k scalars of `scalar` bytes in the file. */
typedef struct ubo_matrix {
    const unsigned char *p;
    int scalar;          /* 2, 4 or 8 */
    uint32_t rows, k;
} ubo_matrix;

/* One PVF view slot (§5). */
typedef struct ubo_pvf_slot {
    int scalar;
    uint32_t k, num_weights, dim;
    const unsigned char *mean, *c, *w; /* Mean[dim], C[dim x K], W[num_weights x K] */
} ubo_pvf_slot;

typedef struct ubo_file {
    const char *name;               /* starts every message */
    const unsigned char *data;
    uint64_t size;
    int variant;                    /* UBO_* */
    int sig_len;
    btf_ubo2014_info info;          /* what btf_dataset_ubo2014 hands out */
    uint32_t nc;                    /* channels (3 for decoding) */
    uint32_t nv, nl, width, height;
    float *view_rad, *light_rad;    /* nv (resp. nl) x (theta, phi), radians as stored */
    /* DFMF (per channel) and FMF (channel 0 only): U and SxV */
    int transposed;
    ubo_matrix u[3], sxv[3];
    float colour_mean[3], colour_transform[9];
    /* BDIF (§6) */
    uint32_t lines_per_chunk;
    int compression;
    const unsigned char *mask;      /* W x H bytes */
    uint32_t *rank;                 /* sparse: stored index of texel y*W+x, UINT32_MAX if none */
    uint64_t stored, chunks;
    const unsigned char *chunk0;    /* the first chunk's size field */
    uint64_t chunk_stride;          /* 4 + the bytes of a full chunk */
    /* PVF (§5) */
    ubo_pvf_slot *slots;
    uint32_t num_slots;
} ubo_file;

/* Parses the whole file held in data (size bytes): BTF_E_FORMAT naming
 * name for an unknown signature, a truncated file or sizes that do not
 * fit; BTF_E_UNSUPPORTED for a valid file this reader cannot decode (colour
 * model, channel count, compression). Checks that the factors (or values)
 * are finite unless skip_finite. Free with ubo_free (also after failure). */
btf_status ubo_parse(const unsigned char *data, uint64_t size, const char *name, int skip_finite,
                     ubo_file *f, btf_error *err);
void ubo_free(ubo_file *f);

/* The image of the file's view index fv and light index fl (positions in
 * the file's lists) into out (width x height x 3 floats, linear RGB, row 0
 * = the file's first row). */
btf_status ubo_decode(const ubo_file *f, uint32_t fv, uint32_t fl, float *out, btf_error *err);

/* A file opened for the dataset interface: mapped, parsed, and its
 * direction sets in btfcar's order with the file's index of each. */
typedef struct ubo_open_file {
    ubo_file f;
    void *map;
    size_t map_size;
    btf_dirset views, lights;
    uint32_t *view_index, *light_index; /* dataset index -> file index */
} ubo_open_file;
/* 1 when the file at path starts with a UBO2014 signature (the first
 * bytes; no other check), else 0. */
int ubo_sniff(const char *path);
btf_status ubo_open(const char *path, ubo_open_file **out, btf_error *err);
void ubo_close(ubo_open_file *o);

/* The truncated SVD of the writer (ubo_svd.c): the k largest eigenpairs of
 * the symmetric n x n matrix g (row-major, destroyed), eigenvalues
 * descending into val[k], eigenvectors as the columns of vec (n x k,
 * row-major). Deterministic. BTF_E_NUMERIC if it does not converge. */
btf_status ubo_top_eigen(double *g, int n, int k, double *val, double *vec, btf_error *err);
/* How many of the k eigenpairs (val descending) are worth keeping: those
 * with sqrt(lambda) above 1e-7 of the first's; at least 1. */
int ubo_keep_components(const double *val, int k);

/* ---- writing (ubo_out.c) ---- */

/* A growable byte buffer for headers; failed is set when memory ran out. */
typedef struct ubo_bytes {
    unsigned char *p;
    size_t n, cap;
    int failed;
} ubo_bytes;
void ubo_put(ubo_bytes *b, const void *data, size_t n);
void ubo_put_u32(ubo_bytes *b, uint32_t v);
void ubo_put_u8(ubo_bytes *b, unsigned v);
void ubo_put_f32(ubo_bytes *b, float f);
/* §2b: the views, each with the whole light list (radians). */
void ubo_put_sampling(ubo_bytes *b, const btf_dirset *views, const btf_dirset *lights);
/* The signature, the meta block (§2a, version 4), the sampling, width and
 * height: everything up to the rotations (§2c). */
void ubo_common_header(ubo_bytes *b, const char *sig, const btf_dirset *views,
                       const btf_dirset *lights, int width, int height, int cosine_flag);
/* BTF_E_NOMEM naming path if the buffer ran out of memory (and frees it). */
btf_status ubo_bytes_check(ubo_bytes *b, const char *path, btf_error *err);

/* The output: a temporary file of the final size beside path, mapped for
 * writing; closing with rc 0 syncs it and renames it into place, else
 * removes it. */
typedef struct ubo_outfile {
    char tmp[4200];
    int fd;
    unsigned char *map;
    size_t size;
} ubo_outfile;
btf_status ubo_out_open(ubo_outfile *o, const char *path, uint64_t size, btf_error *err);
btf_status ubo_out_close(ubo_outfile *o, const char *path, btf_status rc, btf_error *err);
/* Opens the output of the header h (freed) and body bytes more, copies the
 * header; *p is where the body starts. */
btf_status ubo_out_header(ubo_outfile *o, const char *path, ubo_bytes *h, uint64_t body,
                          unsigned char **p, btf_error *err);

/* A float stored as a scalar of 2, 4 or 8 bytes (§0), and the value the
 * reader gets back from it. */
void ubo_store(unsigned char *p, float v, int size);
float ubo_stored(float v, int size);
/* n floats stored at *p (advanced); BTF_E_ARG naming what for a NaN or Inf. */
btf_status ubo_store_all(unsigned char **p, const float *v, uint64_t n, int size, const char *path,
                         const char *what, btf_error *err);
static inline void ubo_wr32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)v, p[1] = (unsigned char)(v >> 8), p[2] = (unsigned char)(v >> 16),
    p[3] = (unsigned char)(v >> 24);
}
/* Non-empty sets, a size in 1..BTF_MAX_SIDE, 3 x pairs below 2^32. */
btf_status ubo_check_sets(const char *path, const btf_dirset *views, const btf_dirset *lights,
                          int width, int height, btf_error *err);

/* The images a writer stores: image(user, v, l) for v, l in the sets. */
typedef struct ubo_source {
    const char *path;
    const btf_dirset *views, *lights;
    int width, height;
    btf_pair_image_fn image;
    void *user;
    btf_progress_fn progress;
    void *progress_user;
} ubo_source;
/* Image i = view x n_lights + light, checked: width x height x 3, finite. */
btf_status ubo_get_image(const ubo_source *s, uint64_t i, btf_image *img, btf_error *err);
void ubo_report(const ubo_source *s, double frac, const char *what);

/* ---- the factorisation of DFMF and FMF (ubo_factor.c) ---- */

#define UBO_MAX_COMPONENTS 4096
/* fmf 0 (DFMF): matrix c for channel c, n rows; fmf 1: one matrix (u[0],
 * sxv[0]) of 3 n rows, row 3 i + c for image i's channel c. U is rows x
 * kc, S x V is pixels x kc, both rounded to the stored scalar. */
typedef struct ubo_factors {
    int fmf;
    int kc[3];
    float *u[3], *sxv[3];
} ubo_factors;
/* The truncated SVD of the images of src (components at most), rounded to
 * scalar bytes; log_values (FMF): of ln(value + 1e-5). st (may be NULL)
 * gets the components and the error of the values the reader decodes. */
btf_status ubo_factorise(const ubo_source *src, int fmf, int log_values, int components,
                         int scalar, uint64_t max_bytes, ubo_factors *out,
                         btf_ubo2014_write_stats *st, btf_error *err);
void ubo_factors_free(ubo_factors *f);

/* ---- FMF and PVF from given factors (ubo_write.c, ubo_write_pvf.c) ----
 * The library writes these from images through btf_ubo2014_write; the
 * tests also write every layout the reader accepts through them. */

/* An FMF file (§4). rows x cols is 3 n x pixels (U row (v nL + l) 3 + c,
 * S x V row y W + x) or, transposed, 3 pixels x n (U row (y W + x) 3 + c,
 * S x V row v nL + l). */
typedef struct ubo_fmf {
    const char *signature;   /* "!FMF12FCER", "!FMF06FCR" or "!FMF06FC" */
    int header_version;      /* !FMF12FCER: 0, 1 or 2 */
    uint32_t drr;            /* dynamic_range_reduction_method (version >= 1) */
    uint32_t hm_a, hm_b;     /* version 2: the height map's sides (0: none) */
    const float *height_map; /* hm_a x hm_b */
    int scalar_size;         /* 2, 4 or 8 */
    uint32_t k, k_file;      /* K; the num_components before the scalar size */
    uint32_t rows, cols;
    const float *s, *u, *sxv; /* s: K singular values (NULL: S x V's column norms) */
} ubo_fmf;
btf_status ubo_write_fmf(const char *path, const btf_dirset *views, const btf_dirset *lights,
                         int width, int height, const ubo_fmf *f, btf_error *err);

/* A PVF file (§5): per view, Mean[dim], C[dim x K] and W[num_weights x K]
 * with dim = 3 nL and num_weights = pixels (value = W[y W + x] . C[3 l + c]
 * + Mean[3 l + c]) or dim = 3 pixels and num_weights = nL (value =
 * C[3 (y W + x) + c] . W[l] + Mean[3 (y W + x) + c]). */
typedef struct ubo_pvf_view {
    uint32_t k, num_weights, dim;
    const float *ev, *mean, *c, *w; /* ev: K eigenvalues (NULL: zeros) */
} ubo_pvf_view;
typedef struct ubo_pvf {
    const char *signature;   /* "!PVF06FCR" or "!PVF06FC" */
    int legacy;              /* the header of magic 301074, without a meta block */
    int scalar_size;
    uint32_t num_components; /* the header's (informational) */
    const ubo_pvf_view *views; /* one slot per view */
} ubo_pvf;
btf_status ubo_write_pvf(const char *path, const btf_dirset *views, const btf_dirset *lights,
                         int width, int height, const ubo_pvf *p, btf_error *err);
/* PVF from the images of src: per view, the PCA of its 3 nL (light,
 * channel) columns over the pixels, components at most, stored in the
 * first layout above. */
btf_status ubo_write_pvf_images(const ubo_source *src, const char *signature, int components,
                                int scalar, uint64_t max_bytes, btf_ubo2014_write_stats *st,
                                btf_error *err);

/* IEEE binary16 <-> binary32, round to nearest even. */
static inline float ubo_half_to_float(uint16_t h)
{
    uint32_t s = (uint32_t)(h >> 15) << 31, e = (h >> 10) & 31u, m = h & 1023u, bits;
    if (e == 0) {
        if (m == 0) {
            bits = s;
        } else { /* subnormal: normalise */
            e = 113;
            while (!(m & 1024u)) {
                m <<= 1;
                e--;
            }
            bits = s | (e << 23) | ((m & 1023u) << 13);
        }
    } else if (e == 31) {
        bits = s | 0x7f800000u | (m << 13);
    } else {
        bits = s | ((e + 112u) << 23) | (m << 13);
    }
    float f;
    memcpy(&f, &bits, 4);
    return f;
}

static inline uint16_t ubo_float_to_half(float f)
{
    uint32_t x;
    memcpy(&x, &f, 4);
    uint32_t s = (x >> 16) & 0x8000u, a = x & 0x7fffffffu;
    if (a >= 0x7f800000u)
        return (uint16_t)(s | 0x7c00u | (a > 0x7f800000u ? 0x200u : 0));
    if (a >= 0x477ff000u) /* rounds to 65520 or more: Inf */
        return (uint16_t)(s | 0x7c00u);
    if (a < 0x38800000u) { /* subnormal half or zero */
        if (a < 0x33000000u)
            return (uint16_t)s;
        uint32_t e = a >> 23, m = (a & 0x7fffffu) | 0x800000u;
        uint32_t shift = 126 - e; /* 14 .. 24 */
        uint32_t r = m >> shift, rem = m & ((1u << shift) - 1), half = 1u << (shift - 1);
        if (rem > half || (rem == half && (r & 1u)))
            r++;
        return (uint16_t)(s | r);
    }
    uint32_t r = a - 0x38000000u; /* rebias 127 -> 15 */
    uint32_t lo = r & 0x1fffu;
    r >>= 13;
    if (lo > 0x1000u || (lo == 0x1000u && (r & 1u)))
        r++;
    return (uint16_t)(s | r);
}

static inline uint32_t ubo_rd32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
static inline float ubo_rdf32(const unsigned char *p)
{
    uint32_t u = ubo_rd32(p);
    float f;
    memcpy(&f, &u, 4);
    return f;
}
/* A stored scalar of 2, 4 or 8 bytes as a float. */
static inline float ubo_scalar(const unsigned char *p, int size)
{
    if (size == 2)
        return ubo_half_to_float((uint16_t)(p[0] | p[1] << 8));
    if (size == 4)
        return ubo_rdf32(p);
    uint64_t u = ubo_rd32(p) | (uint64_t)ubo_rd32(p + 4) << 32;
    double d;
    memcpy(&d, &u, 8);
    return (float)d;
}

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
btf_status btf__ubo2014_write_factors(const char *path, const btf_dirset *views,
                                      const btf_dirset *lights, int width, int height,
                                      const btf_ubo2014_factors *f, btf_error *err);

#endif
