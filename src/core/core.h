/*
 * core.h — the plumbing every stage shares (src/core/): one-line errors,
 * allocation, atomic files and paths, the CPU count, direction-name
 * tolerance. Private to the library; not installed.
 */
#ifndef BTF_CORE_H
#define BTF_CORE_H

#include "btfcar.h"

#include <stddef.h>

#if defined(__GNUC__)
#define BTF_PRINTF(a, b) __attribute__((format(printf, a, b)))
#else
#define BTF_PRINTF(a, b)
#endif

/* Image sides beyond this are refused before any allocation: 2^16 keeps
 * width*height*3 floats far from size_t overflow and matches EXR practice. */
#define BTF_MAX_SIDE 65536

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
/* btf_write_file_atomic (a whole buffer) is public: include/btfcar.h. */
/* Reads a whole file (at most max_bytes) into a malloc'd buffer. */
int btf_read_file(const char *path, size_t max_bytes, unsigned char **data,
                  size_t *n, btf_error *err);

/* rm -r: removes a folder and everything below it (links are not
 * followed); errors are ignored. For temporary output after a failure. */
void btf_remove_tree(const char *path);
/* Joins a folder and a name into out (size n); BTF_E_ARG when too long. */
int btf_path_join(char *out, size_t n, const char *dir, const char *name, btf_error *err);

/* Number of online CPUs (at least 1). */
int btf_cpu_count(void);

/* Directions named in whole degrees (file names) match a known set within
 * this many degrees (core/directions.c, io/dataset.c). */
#define BTF_DIR_NAME_TOLERANCE 0.75

#endif
