/*
 * report.h — what the files of src/report/ (the report's compression
 * accounting, issue 18) share. Private to the library.
 */
#ifndef BTF_REPORT_H
#define BTF_REPORT_H

#include "core/core.h"

/* Decodes the zlib stream z (zn bytes: header, deflate data, Adler-32),
 * which must inflate to exactly the n bytes at expect, and gives every bit
 * of it to what it codes: a literal's code to its byte, a match's length
 * and distance codes with their extra bits in equal shares to the bytes it
 * copies, a stored block's bytes to themselves. bits[label[i]] receives
 * the bits of payload byte i (labels < nlabels; bits has nlabels entries,
 * added to); *overhead_bits the rest (zlib header and Adler-32, block
 * headers, code tables, end-of-block codes, padding), so that the sum of
 * bits and overhead is 8 zn. name starts error messages; BTF_E_FORMAT when
 * the stream is not valid or does not inflate to expect
 * (report/deflate_cost.c). */
btf_status btf_deflate_cost(const unsigned char *z, size_t zn, const unsigned char *expect,
                            const unsigned char *label, size_t n, int nlabels, double *bits,
                            double *overhead_bits, const char *name, btf_error *err);

/* An image's linear float values as the report's 8-bit sRGB levels, 0..255
 * and not rounded: btf_linear_to_srgb (which clamps to [0, 1]) x 255; a
 * value decoded from an 8-bit sRGB file gives back its stored code exactly
 * (report/srgb_levels.c). The table makes that exact path cheap: fill it
 * once with btf_srgb_levels_init. */
typedef struct btf_srgb_levels_table {
    float lut[256];              /* the linear value of each 8-bit code */
    unsigned char start[4097];   /* the first code whose value is >= k / 4096 */
} btf_srgb_levels_table;
void btf_srgb_levels_init(btf_srgb_levels_table *t);
void btf_srgb_levels(const btf_srgb_levels_table *t, const float *linear, size_t n, float *out);

/* The eigenvalues (descending) and unit eigenvectors (columns of vec, n x n
 * row-major: vec[i * n + k] is component i of eigenvector k) of the
 * symmetric n x n matrix a (overwritten), by cyclic Jacobi rotations until
 * the off-diagonal part vanishes: deterministic. -1 when out of memory
 * (report/jacobi.c). */
int btf_sym_eigen(double *a, int n, double *val, double *vec);

/* The raw BTF of a dataset (report/raw_bytes.c): btf_dataset_raw_bytes
 * without the argument checks. */
void btf_raw_bytes_of(const btf_dataset_info *info, btf_raw_bytes *out);

#endif
