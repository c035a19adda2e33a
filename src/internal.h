/*
 * internal.h — helpers shared by the library's source files; not installed.
 */
#ifndef BTF_INTERNAL_H
#define BTF_INTERNAL_H

#include "btfcar.h"

#include <stdarg.h>
#include <stdio.h>

#if defined(__GNUC__)
#define BTF_PRINTF(a, b) __attribute__((format(printf, a, b)))
#else
#define BTF_PRINTF(a, b)
#endif

/* Fills err (if non-NULL) with a formatted one-line message; returns code. */
int btf_fail(btf_error *err, int code, const char *fmt, ...) BTF_PRINTF(3, 4);

/* malloc/calloc that report BTF_E_NOMEM through err; size overflow checked. */
void *btf_alloc(size_t count, size_t size, btf_error *err);
void *btf_calloc(size_t count, size_t size, btf_error *err);

/* Atomic file writing: btf_tmp_path gives a unique temporary name beside
 * `path` (same folder, so rename() is atomic); btf_commit_file renames it over
 * path, btf_abort_file removes it. */
int btf_tmp_path(const char *path, char *tmp, size_t n, btf_error *err);
int btf_commit_file(const char *tmp, const char *path, btf_error *err);
void btf_abort_file(const char *tmp);
/* Writes a whole buffer atomically. */
int btf_write_file_atomic(const char *path, const void *data, size_t n, btf_error *err);
/* Reads a whole file (at most max_bytes) into a malloc'd buffer. */
int btf_read_file(const char *path, size_t max_bytes, unsigned char **data,
                  size_t *n, btf_error *err);

/* mkdir -p; an existing folder is fine. */
int btf_mkdirs(const char *path, btf_error *err);
/* Joins a folder and a name into out (size n); BTF_E_ARG when too long. */
int btf_path_join(char *out, size_t n, const char *dir, const char *name, btf_error *err);

/* Number of online CPUs (at least 1). */
int btf_cpu_count(void);

/* EXR (OpenEXR core C API): src/exr_io.c */
int btf_exr_probe(const char *path, btf_image_header *hdr, btf_error *err);
int btf_exr_read(const char *path, int channels, btf_image *out, btf_error *err);
int btf_exr_write(const char *path, const btf_image *img, int half, btf_error *err);

/* The OpenCV bridge (src/cv_bridge.cpp), a C interface. Error text goes to
 * errbuf; return 0 on success. */
int btfcv_read(const char *path, int *w, int *h, int *c, int *depth16,
               void **pixels, char *errbuf, size_t errlen);
int btfcv_encode(const char *ext, int w, int h, int c, const unsigned char *pixels,
                 int jpeg_quality, unsigned char **out, size_t *outlen,
                 char *errbuf, size_t errlen);

#endif
