/*
 * exr.c — what the EXR reader and writer share: OpenEXRCore's messages and
 * btfcar's one-line errors.
 *
 * The library must never print. A custom error handler stores OpenEXRCore's
 * first message for the call in progress, found through a thread-local
 * pointer: the handler gets only the context, and asking the context for
 * its user data from inside the handler may take a lock the library already
 * holds. That message ends up in the one-line btf_error "PATH: what:
 * detail". The first message is kept because it is the most specific; later
 * ones are consequences.
 */
#include <stdio.h>
#include "core/core.h"
#include "io/exr.h"

#include <string.h>

/* The btf_exr_io of the call in progress on this thread. */
static _Thread_local btf_exr_io *tl_sink;

static void on_exr_error(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    (void)ctxt;
    btf_exr_io *io = tl_sink;
    if (!io || io->msg[0])
        return;
    snprintf(io->msg, sizeof io->msg, "%s",
             msg && *msg ? msg : exr_get_default_error_message(code));
}

btf_exr_io *btf__exr_sink_enter(btf_exr_io *io)
{
    btf_exr_io *prev = tl_sink;
    io->msg[0] = '\0';
    io->sys_errno = 0;
    tl_sink = io;
    return prev;
}

void btf__exr_sink_leave(btf_exr_io *prev)
{
    tl_sink = prev;
}

exr_context_initializer_t btf__exr_initializer(btf_exr_io *io)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = on_exr_error;
    init.user_data = io;
    init.max_image_width = init.max_image_height = BTF_EXR_MAX_SIDE;
    init.max_tile_width = init.max_tile_height = BTF_EXR_MAX_SIDE;
    return init;
}

static btf_status exr_status(const btf_exr_io *io, exr_result_t rv, int writing)
{
    if (io->sys_errno)
        return BTF_E_IO;
    switch (rv) {
    case EXR_ERR_OUT_OF_MEMORY: return BTF_E_NOMEM;
    case EXR_ERR_FEATURE_NOT_IMPLEMENTED: return BTF_E_UNSUPPORTED;
    default: return writing ? BTF_E_IO : BTF_E_FORMAT;
    }
}

btf_status btf__exr_fail(btf_error *err, const btf_exr_io *io, exr_result_t rv, int writing,
                         const char *what)
{
    const char *detail = io->sys_errno ? strerror(io->sys_errno)
                         : io->msg[0]  ? io->msg
                                       : exr_get_default_error_message(rv);
    return btf__fail(err, exr_status(io, rv, writing), "%s: %s: %s", io->path, what, detail);
}
