/*
 * io.h — file formats below the public readers (src/io/): tab-separated
 * manifests, OpenEXR through its core C API, and the C interface of the
 * OpenCV bridge. Private to the library.
 */
#ifndef BTF_IO_H
#define BTF_IO_H

#include "btfcar.h"

#include <stddef.h>

/* Tab-separated manifests: io/tsv.c */
typedef struct btf_tsv {
    char *text;          /* the file, split in place */
    int ncols, nrows;
    const char *names[64];
    char **cells;        /* nrows * ncols */
    int *line_no;        /* file line of each row, for messages */
} btf_tsv;
int btf_tsv_read(const char *path, btf_tsv *t, btf_error *err);
void btf_tsv_free(btf_tsv *t);
int btf_tsv_column(const btf_tsv *t, const char *name); /* -1 if absent */
const char *btf_tsv_cell(const btf_tsv *t, int row, int col);
int btf_tsv_number(const btf_tsv *t, const char *path, int row, int col, double *out,
                   btf_error *err);

/* EXR (OpenEXR core C API): io/exr.c */
int btf_exr_probe(const char *path, btf_image_header *hdr, btf_error *err);
int btf_exr_read(const char *path, int channels, btf_image *out, btf_error *err);
int btf_exr_write(const char *path, const btf_image *img, int half, btf_error *err);

/* The OpenCV bridge (io/cv_bridge.cpp), a C interface. Error text goes to
 * errbuf; return 0 on success. */
int btfcv_read(const char *path, int *w, int *h, int *c, int *depth16,
               void **pixels, char *errbuf, size_t errlen);
int btfcv_encode(const char *ext, int w, int h, int c, const unsigned char *pixels,
                 int jpeg_quality, unsigned char **out, size_t *outlen,
                 char *errbuf, size_t errlen);
int btfcv_rgb_to_lab(const float *rgb, size_t n, float *lab, char *errbuf, size_t errlen);
int btfcv_dft2(double *re, double *im, int w, int h, int inverse, char *errbuf, size_t errlen);
int btfcv_dct2(double *a, int w, int h, int inverse, char *errbuf, size_t errlen);

#endif
