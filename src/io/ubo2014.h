/*
 * ubo2014.h — the Bonn BTF database's binary .btf files (DFMF, FMF, PVF,
 * BDIF), private to src/io/. The format notes are
 * /work/shared/formats/ubo2014-btf.md ("the notes" below, section numbers
 * §N); docs/datasets.md ("UBO2014 .btf files") states the rules btfcar
 * follows where the notes leave a doubt.
 *
 *   ubo_parse.c    signature, meta block, sampling, size, rotations and the
 *                  variant's body: offsets into the bytes, every size checked
 *   ubo_decode.c   one (view, light) image from the factors or the values,
 *                  colour models, the cosine rule
 *   ubo_open.c     a file mapped with mmap, its direction sets
 *   ubo_svd.c      the truncated SVD of the writer (Gram matrix, eigenpairs)
 *   ubo_write.c    the DFMF and BDIF writers
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

#endif
