/*
 * btfcar/base.h — version, status codes and errors, progress and warning
 * callbacks, atomic files and output folders, directions.
 * Part of the public C API of btfcar; include/btfcar.h includes every
 * topical header, and its conventions (docs/api.md) hold here too.
 */
#ifndef BTFCAR_BASE_H
#define BTFCAR_BASE_H

#include <stddef.h>
#include <stdint.h>

/* What this header declares is part of the ABI of libbtfcar.so: the library
 * is compiled with -fvisibility=hidden, and the declarations of the public
 * headers alone are exported (docs/install.md, "Shared library and soname"). */
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

/* Warnings from a long computation (e.g. a model made stable by force). */
typedef void (*btf_warning_fn)(void *user, const char *message);

/* ------------------------------------------------------------------- files */

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
 * caller gave it (so that "disk full" names the caller's file, not the
 * temporary). */
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
/* A custom set from a list; sorted ring by ring, phi ascending, duplicates
 * (within 1e-6 degree) merged. If the list equals a known set it is named so. */
btf_status btf_dirset_from_list(btf_dirset *set, const btf_dir *dirs, int count,
                                btf_error *err);
void btf_dirset_free(btf_dirset *set);
/* Index of the direction within tol degrees (angle between unit vectors) or -1. */
int btf_dirset_find(const btf_dirset *set, btf_dir d, double tol_deg);

/* (theta, phi) in degrees <-> unit vector; z is the surface normal. A vector
 * on the pole gets phi = 0; phi is normalised to [0, 360). */
void btf_dir_to_vec(btf_dir d, double v[3]);
btf_dir btf_vec_to_dir(const double v[3]);
/* Angle in degrees between two directions. */
double btf_dir_angle(btf_dir a, btf_dir b);

#ifdef __cplusplus
}
#endif

#pragma GCC visibility pop
#endif /* BTFCAR_BASE_H */
