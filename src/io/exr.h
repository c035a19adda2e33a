/*
 * exr.h — what the EXR reader (io/exr_read.c) and writer (io/exr_write.c)
 * share (io/exr.c): OpenEXRCore's messages routed to the call in progress,
 * a context initializer with btfcar's limits, and one way to turn a library
 * failure into a btf_status and a message. Private to src/io.
 */
#ifndef BTF_IO_EXR_H
#define BTF_IO_EXR_H

#include "io/io.h"

#include <openexr.h>

/* Largest image side read or written (as btf_image_alloc). */
#define BTF_EXR_MAX_SIDE 65536

/* One file being read or written, and the first error reported during the
 * current call, by the library or by a system call. */
typedef struct btf_exr_io {
    const char *path;   /* the name in messages (the final name when writing) */
    btf_source *src;    /* reading: where the bytes come from */
    int fd;             /* writing: the temporary file */
    int sys_errno;      /* errno of a failed system call, 0 if none */
    char msg[512];      /* the library's first message, "" if none */
} btf_exr_io;

/* Routes the library's messages to io until btf__exr_sink_leave; returns the
 * previous sink so that calls may nest (the one-shot writer runs the
 * streaming writer's entry points). Clears io's message and errno. */
btf_exr_io *btf__exr_sink_enter(btf_exr_io *io);
void btf__exr_sink_leave(btf_exr_io *prev);

/* A context initializer whose error handler feeds the sink, with io as the
 * user data and the side limits set; the caller adds its I/O functions. */
exr_context_initializer_t btf__exr_initializer(btf_exr_io *io);

/* Fills err with "PATH: what: detail" and returns the status: BTF_E_IO for a
 * failed system call, BTF_E_NOMEM, BTF_E_UNSUPPORTED for a feature the
 * library lacks, else BTF_E_FORMAT when reading (the file is damaged) and
 * BTF_E_IO when writing. */
btf_status btf__exr_fail(btf_error *err, const btf_exr_io *io, exr_result_t rv, int writing,
                         const char *what);

#endif
