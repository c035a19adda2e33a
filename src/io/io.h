/*
 * io.h — file formats below the public readers (src/io/): the byte source
 * every parser reads from, tab-separated manifests, OpenEXR through its
 * core C API, PNG and JPEG, and the C interface of the OpenCV bridge.
 * Private to the library. The datasets made of such files are
 * src/dataset/ (dataset/dataset.h).
 */
#ifndef BTF_IO_H
#define BTF_IO_H

#include "btfcar.h"

#include <stddef.h>
#include <stdint.h>

/* A byte source (io/source.c): a memory buffer, or a regular file read in
 * place with pread. name is the file name or the caller's name for the
 * buffer, and starts every error message. */
typedef struct btf_source {
    const char *name;
    int fd;                    /* -1 for a memory buffer */
    const unsigned char *data; /* the buffer (memory sources) */
    uint64_t size;
    int sys_errno;             /* errno of the last failed pread, else 0 */
} btf_source;
void btf__source_memory(btf_source *s, const void *data, size_t n, const char *name);
/* Opens a regular file (BTF_E_IO naming it otherwise); close even on failure. */
btf_status btf__source_open(btf_source *s, const char *path, btf_error *err);
void btf__source_close(btf_source *s);
/* Up to n bytes at offset (fewer at the end, 0 past it); -1 when the system
 * call fails (sys_errno says why). */
int64_t btf__source_read(btf_source *s, void *buf, uint64_t n, uint64_t offset);
/* The whole content: *data points into a memory source, or into *owned (the
 * caller frees it) for a file. */
btf_status btf__source_bytes(btf_source *s, const unsigned char **data, unsigned char **owned,
                             btf_error *err);

/* Tab-separated manifests (io/tsv.c): a header line naming the columns, then
 * one record per line; blank lines and '#' lines are skipped. */
typedef struct btf_tsv {
    char *text;          /* a copy of the input, split in place */
    int ncols, nrows;
    const char *names[64];
    char **cells;        /* nrows * ncols */
    int *line_no;        /* input line of each row, for messages */
} btf_tsv;
/* Parses n bytes of text; name starts the error messages ("NAME:LINE: ..."). */
btf_status btf__tsv_parse(const char *text, size_t n, const char *name, btf_tsv *t,
                          btf_error *err);
/* The same from a file (at most 64 MiB), named by its path. */
btf_status btf__tsv_read(const char *path, btf_tsv *t, btf_error *err);
void btf__tsv_free(btf_tsv *t);
int btf__tsv_column(const btf_tsv *t, const char *name); /* -1 if absent */
const char *btf__tsv_cell(const btf_tsv *t, int row, int col);
/* The first name that appears twice among names[0 .. n-1]: *first and
 * *again get the indices of its first and of its next occurrence, both -1
 * when every name is distinct (manifests list each file once). */
btf_status btf__first_repeat(const char *const *names, int n, int *first, int *again,
                             btf_error *err);
btf_status btf__tsv_number(const btf_tsv *t, const char *path, int row, int col, double *out,
                           btf_error *err);

/* EXR reading (io/exr_read.c) from any source: the header probe and the
 * decoder (channels 0: as in the file; 1 or 3 converts; max_pixels as in
 * btf_read_opts, checked from the header). The path forms open
 * the file and call these. The writers are public (btf_image_write_exr_opts,
 * btf_exr_writer_open_opts; io/exr_write.c). */
btf_status btf__exr_probe_source(btf_source *src, btf_image_header *hdr, btf_error *err);
btf_status btf__exr_read_source(btf_source *src, int channels, uint64_t max_pixels, btf_image *out,
                                btf_error *err);
btf_status btf__exr_probe(const char *path, btf_image_header *hdr, btf_error *err);
btf_status btf__exr_read(const char *path, int channels, btf_image *out, btf_error *err);

/* PNG and JPEG decoding (io/png_jpeg.c) with libpng and libjpeg, silently:
 * errors and data-corruption warnings become BTF_E_FORMAT naming `name`.
 * pixels: width x height x channels (1 or 3, RGB) samples, 8-bit or (depth16)
 * native uint16; the caller frees them. */
typedef struct btf_decoded {
    int width, height, channels, depth16;
    void *pixels;
} btf_decoded;
btf_status btf__png_jpeg_decode(const void *data, size_t n, btf_file_format format,
                                const char *name, btf_decoded *out, btf_error *err);

/* Encodes 8-bit sRGB pixels (1 or 3 channels, RGB order) as PNG (zlib level
 * 3) or JPEG (jpeg_quality 1..100) into a malloc'd buffer; returns 0, or -1
 * with the reason in msg. Nothing is printed. */
int btf__png_jpeg_encode(btf_file_format format, int w, int h, int c,
                         const unsigned char *pixels, int jpeg_quality, unsigned char **out,
                         size_t *outlen, char *msg, size_t msglen);
/* The OpenCV bridge (io/cv_bridge.cpp), a C interface with its own small
 * convention: 0 on success, -1 with the error text in errbuf. */
int btfcv_rgb_to_lab(const float *rgb, size_t n, float *lab, char *errbuf, size_t errlen);
int btfcv_dft2(double *re, double *im, int w, int h, int inverse, char *errbuf, size_t errlen);
int btfcv_dct2(double *a, int w, int h, int inverse, char *errbuf, size_t errlen);

/* Testing (tests/unit/test_exr.c): 1 makes the EXR writer pack chunks with
 * OpenEXRCore's own packer instead of its F16C one (the same bytes). */
extern int btf__exr_library_pack;

/* Format from the file's signature bytes (never from its name);
 * BTF_FILE_UNKNOWN for anything but a readable regular file. */
btf_file_format btf__file_format_of(const char *path);

/* The name ("zip", "none", ...) of a compression; NULL if out of range. */
const char *btf__exr_compression_name(int compression);

#endif
