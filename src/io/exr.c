/*
 * exr_io.c — OpenEXR files through the OpenEXR core C API (OpenEXRCore, plain
 * C, no exceptions): a header probe, a reader that decodes scanline or tiled
 * HALF/FLOAT images to linear float, and a streaming scanline writer on which
 * the one-shot writer is built.
 *
 * Why these choices:
 *  - The library must never print. A custom error handler stores the
 *    library's first message for the call in progress (found through a
 *    thread-local pointer: the handler gets only the context, and asking the
 *    context for its user data from inside the handler may take a lock the
 *    library already holds). That message ends up in the one-line btf_error
 *    "PATH: what: detail".
 *  - We do the file I/O ourselves (pread/pwrite on our own descriptor), so a
 *    failing system call (BTF_E_IO) can be told from a file that simply ends
 *    too early (BTF_E_FORMAT), and so the writer writes to the temporary name
 *    from btf_tmp_path() and the file appears only through btf_commit_file().
 *  - Files are untrusted: image sides are limited to 65536, the chunk offset
 *    table must fit in the file, every chunk must lie inside the file and
 *    inside the image (all are checked before the image is allocated), and
 *    one chunk may not unpack to more than BTF_EXR_MAX_CHUNK_BYTES. The
 *    library's chunk-table "reconstruction" is switched off: a damaged table
 *    is an error, not a guess.
 *
 * Reading: part 0 only (other parts are ignored). Channels R, G, B give a
 * colour image; else Y, else a lone channel of any name gives grey. Other
 * channels (A, Z, ...) are skipped. Deep parts, UINT or subsampled image
 * channels and luminance/chroma files (Y with RY/BY) are BTF_E_UNSUPPORTED.
 * Tiled parts are read at their full-resolution level. All compressions of
 * OpenEXRCore 3.1 are read; it has no DWAA/DWAB codec, so those files are
 * BTF_E_UNSUPPORTED too. Decoding goes chunk by chunk through one scratch
 * buffer, so memory is the image plus one chunk. Any NaN or Inf sample is
 * BTF_E_DATA naming the pixel.
 *
 * Writing: channel "Y", or "B", "G", "R" (EXR stores channels sorted by
 * name), HALF or FLOAT, scanlines in increasing y, ZIP compression:
 * lossless deflate (zlib level 4, see writer_header) over 16-scanline
 * chunks, read by every EXR implementation, good on smooth data and
 * deterministic (the same pixels give the same bytes).
 * Non-finite input is refused (BTF_E_ARG) because such a file could not be
 * read back; half output is clamped to +-65504 so it never holds Inf. A
 * chunk that does not shrink is stored raw (see compress_or_store: works
 * around OpenEXRCore 3.1.5 writing unreadable chunks).
 */
#include <stdio.h>
#include "core/core.h"
#include "io/io.h"

#include <openexr.h>

#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* Largest image side read or written (as btf_image_alloc). */
#define EXR_MAX_SIDE 65536
/* Largest unpacked chunk we let the library allocate for: far above any sane
 * file (a 65536-wide, 32-line PIZ chunk of 4 float channels is 32 MiB), far
 * below what a hostile header could ask for. A fuzzing build may lower it. */
#ifndef BTF_EXR_MAX_CHUNK_BYTES
#define BTF_EXR_MAX_CHUNK_BYTES ((uint64_t)1 << 30)
#endif
#define HALF_MAX_VALUE 65504.0f

/* ------------------------------------------------------ I/O and errors */

/* One open file: our descriptor, its size when reading, and the first error
 * the library or a system call reported during the current call. */
typedef struct exr_io {
    const char *path;   /* the name in messages (the final name when writing) */
    int fd;
    int64_t size;       /* file size when reading */
    int sys_errno;      /* errno of a failed pread/pwrite, 0 if none */
    char msg[512];      /* the library's first message, "" if none */
} exr_io;

/* The exr_io of the call in progress on this thread (see the top comment). */
static _Thread_local exr_io *tl_sink;

static void on_exr_error(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    (void)ctxt;
    exr_io *io = tl_sink;
    /* The first message is the most specific; later ones are consequences. */
    if (!io || io->msg[0])
        return;
    snprintf(io->msg, sizeof io->msg, "%s",
             msg && *msg ? msg : exr_get_default_error_message(code));
}

/* Routes library messages to io until sink_leave; returns the previous sink
 * so calls may nest (btf_exr_write runs the writer's entry points). */
static exr_io *sink_enter(exr_io *io)
{
    exr_io *prev = tl_sink;
    io->msg[0] = '\0';
    io->sys_errno = 0;
    tl_sink = io;
    return prev;
}

static void sink_leave(exr_io *prev)
{
    tl_sink = prev;
}

/* pread in a loop. Offsets come from the file and may be anything: a request
 * past the end returns what exists, and the library reports the short read
 * as a damaged file. */
static int64_t io_read(exr_const_context_t ctxt, void *user, void *buffer, uint64_t sz,
                       uint64_t offset, exr_stream_error_func_ptr_t error_cb)
{
    (void)ctxt;
    (void)error_cb;
    exr_io *io = user;
    if (offset >= (uint64_t)io->size)
        return 0;
    if (sz > (uint64_t)io->size - offset)
        sz = (uint64_t)io->size - offset;
    uint64_t done = 0;
    while (done < sz) {
        uint64_t left = sz - done;
        size_t want = left > ((uint64_t)1 << 30) ? (size_t)1 << 30 : (size_t)left;
        ssize_t r = pread(io->fd, (char *)buffer + done, want, (off_t)(offset + done));
        if (r < 0) {
            if (errno == EINTR)
                continue;
            io->sys_errno = errno;
            return -1;
        }
        if (r == 0)
            break;
        done += (uint64_t)r;
    }
    return (int64_t)done;
}

static int64_t io_size(exr_const_context_t ctxt, void *user)
{
    (void)ctxt;
    return ((exr_io *)user)->size;
}

static int64_t io_write(exr_const_context_t ctxt, void *user, const void *buffer, uint64_t sz,
                        uint64_t offset, exr_stream_error_func_ptr_t error_cb)
{
    (void)ctxt;
    (void)error_cb;
    exr_io *io = user;
    if (offset > (uint64_t)INT64_MAX - sz) {
        io->sys_errno = EFBIG;
        return -1;
    }
    uint64_t done = 0;
    while (done < sz) {
        uint64_t left = sz - done;
        size_t want = left > ((uint64_t)1 << 30) ? (size_t)1 << 30 : (size_t)left;
        ssize_t r = pwrite(io->fd, (const char *)buffer + done, want, (off_t)(offset + done));
        if (r < 0) {
            if (errno == EINTR)
                continue;
            io->sys_errno = errno;
            return -1;
        }
        if (r == 0) {
            io->sys_errno = EIO;
            return -1;
        }
        done += (uint64_t)r;
    }
    return (int64_t)done;
}

/* A context initializer wired to our handler and I/O. */
static exr_context_initializer_t exr_init_for(exr_io *io, int writing)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = on_exr_error;
    init.user_data = io;
    if (writing) {
        init.write_fn = io_write;
    } else {
        init.read_fn = io_read;
        init.size_fn = io_size;
        init.flags = EXR_CONTEXT_FLAG_DISABLE_CHUNK_RECONSTRUCTION;
    }
    init.max_image_width = init.max_image_height = EXR_MAX_SIDE;
    init.max_tile_width = init.max_tile_height = EXR_MAX_SIDE;
    return init;
}

/* btf_status for a library failure: a failed system call is I/O, anything
 * else while reading means the file is damaged. */
static int exr_status(const exr_io *io, exr_result_t rv, int writing)
{
    if (io->sys_errno)
        return BTF_E_IO;
    switch (rv) {
    case EXR_ERR_OUT_OF_MEMORY: return BTF_E_NOMEM;
    case EXR_ERR_FEATURE_NOT_IMPLEMENTED: return BTF_E_UNSUPPORTED;
    default: return writing ? BTF_E_IO : BTF_E_FORMAT;
    }
}

static int exr_fail(btf_error *err, const exr_io *io, exr_result_t rv, int writing,
                    const char *what)
{
    const char *detail = io->sys_errno ? strerror(io->sys_errno)
                         : io->msg[0]  ? io->msg
                                       : exr_get_default_error_message(rv);
    return btf_fail(err, exr_status(io, rv, writing), "%s: %s: %s", io->path, what, detail);
}

/* ------------------------------------------------------------- reading */

typedef struct exr_in {
    exr_io io;
    exr_context_t ctx;
    exr_storage_t storage;
    int x0, y0;             /* data window origin */
    int width, height;
    int nsrc;               /* channels taken from the file: 1 or 3 */
    const char *names[3];   /* their names in output order (R, G, B or one) */
    int bits;               /* 16 if all of them are HALF, else 32 */
} exr_in;

static void in_close(exr_in *in)
{
    if (in->ctx)
        exr_finish(&in->ctx);
    if (in->io.fd >= 0)
        close(in->io.fd);
    in->io.fd = -1;
}

/* Opens path and parses its header (the caller has entered in->io as sink). */
static int in_open(exr_in *in, const char *path, btf_error *err)
{
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return btf_fail(err, BTF_E_IO, "%s: cannot open: %s", path, strerror(errno));
    in->io.fd = fd;
    struct stat st;
    if (fstat(fd, &st) != 0)
        return btf_fail(err, BTF_E_IO, "%s: cannot stat: %s", path, strerror(errno));
    if (!S_ISREG(st.st_mode))
        return btf_fail(err, BTF_E_IO, "%s: not a regular file", path);
    in->io.size = (int64_t)st.st_size;
    exr_context_initializer_t init = exr_init_for(&in->io, 0);
    exr_result_t rv = exr_start_read(&in->ctx, path, &init);
    if (rv != EXR_ERR_SUCCESS) {
        in->ctx = NULL; /* exr_start_read frees it on failure */
        return exr_fail(err, &in->io, rv, 0, "not a readable EXR file");
    }
    return BTF_OK;
}

static int find_channel(const exr_attr_chlist_t *cl, const char *name)
{
    size_t n = strlen(name);
    for (int i = 0; i < cl->num_channels; i++) {
        const exr_attr_string_t *s = &cl->entries[i].name;
        if (s->str && s->length >= 0 && (size_t)s->length == n && !memcmp(s->str, name, n))
            return i;
    }
    return -1;
}

/* "A, B, C" (at most out size) for messages. */
static void list_channels(const exr_attr_chlist_t *cl, char *out, size_t n)
{
    size_t len = 0;
    out[0] = '\0';
    for (int i = 0; i < cl->num_channels && len + 1 < n; i++) {
        const char *s = cl->entries[i].name.str ? cl->entries[i].name.str : "?";
        int k = snprintf(out + len, n - len, "%s%s", i ? ", " : "", s);
        if (k < 0)
            break;
        len += (size_t)k;
    }
}

/* Decides which channels become the image (see the top comment). */
static int pick_channels(exr_in *in, btf_error *err)
{
    const char *path = in->io.path;
    const exr_attr_chlist_t *cl = NULL;
    exr_result_t rv = exr_get_channels(in->ctx, 0, &cl);
    if (rv != EXR_ERR_SUCCESS || !cl || cl->num_channels < 1 || !cl->entries)
        return btf_fail(err, BTF_E_FORMAT, "%s: EXR part has no channels", path);
    int idx[3];
    int r = find_channel(cl, "R"), g = find_channel(cl, "G"), b = find_channel(cl, "B");
    int y = find_channel(cl, "Y");
    if (r >= 0 && g >= 0 && b >= 0) {
        in->nsrc = 3;
        idx[0] = r, idx[1] = g, idx[2] = b;
    } else if (y >= 0) {
        /* Y with RY/BY is luminance/chroma colour with subsampled chroma:
         * reading Y alone would silently drop the colour. */
        if (find_channel(cl, "RY") >= 0 || find_channel(cl, "BY") >= 0)
            return btf_fail(err, BTF_E_UNSUPPORTED,
                            "%s: luminance/chroma EXR (Y, RY, BY) is not supported", path);
        in->nsrc = 1;
        idx[0] = y;
    } else if (cl->num_channels == 1) {
        in->nsrc = 1;
        idx[0] = 0;
    } else {
        char names[256];
        list_channels(cl, names, sizeof names);
        return btf_fail(err, BTF_E_UNSUPPORTED,
                        "%s: EXR channels (%s): expected R, G, B, or Y, or a single channel",
                        path, names);
    }
    in->bits = 16;
    for (int k = 0; k < in->nsrc; k++) {
        const exr_attr_chlist_entry_t *e = &cl->entries[idx[k]];
        const char *name = e->name.str ? e->name.str : "?";
        if (e->pixel_type == EXR_PIXEL_UINT)
            return btf_fail(err, BTF_E_UNSUPPORTED,
                            "%s: EXR channel %s holds UINT samples: only HALF and FLOAT are supported",
                            path, name);
        if (e->pixel_type != EXR_PIXEL_HALF && e->pixel_type != EXR_PIXEL_FLOAT)
            return btf_fail(err, BTF_E_FORMAT, "%s: EXR channel %s has an unknown pixel type %d",
                            path, name, (int)e->pixel_type);
        if (e->x_sampling != 1 || e->y_sampling != 1)
            return btf_fail(err, BTF_E_UNSUPPORTED,
                            "%s: EXR channel %s is subsampled (%d x %d): not supported", path,
                            name, e->x_sampling, e->y_sampling);
        if (e->pixel_type == EXR_PIXEL_FLOAT)
            in->bits = 32;
        in->names[k] = e->name.str;
    }
    return BTF_OK;
}

/* Cheap sanity checks of the chunk layout before anything is allocated for
 * it: the offset table is stored in the file, so it must fit in it. */
static int check_chunk_layout(exr_in *in, btf_error *err)
{
    const char *path = in->io.path;
    int32_t count = 0;
    exr_result_t rv = exr_get_chunk_count(in->ctx, 0, &count);
    if (rv != EXR_ERR_SUCCESS || count < 1)
        return exr_fail(err, &in->io, rv ? rv : EXR_ERR_INVALID_ATTR, 0, "bad chunk count");
    if ((uint64_t)count * 8u > (uint64_t)in->io.size)
        return btf_fail(err, BTF_E_FORMAT,
                        "%s: truncated: the offsets of %d chunks do not fit in %lld bytes", path,
                        (int)count, (long long)in->io.size);
    uint64_t unpacked = 0;
    rv = exr_get_chunk_unpacked_size(in->ctx, 0, &unpacked);
    if (rv != EXR_ERR_SUCCESS)
        return exr_fail(err, &in->io, rv, 0, "bad chunk size");
    if (unpacked > BTF_EXR_MAX_CHUNK_BYTES)
        return btf_fail(err, BTF_E_UNSUPPORTED,
                        "%s: EXR chunks of %llu bytes exceed the limit of %llu", path,
                        (unsigned long long)unpacked,
                        (unsigned long long)BTF_EXR_MAX_CHUNK_BYTES);
    return BTF_OK;
}

/* Storage type, data window, channels, chunk layout of part 0. */
static int in_inspect(exr_in *in, btf_error *err)
{
    const char *path = in->io.path;
    exr_result_t rv = exr_get_storage(in->ctx, 0, &in->storage);
    if (rv != EXR_ERR_SUCCESS)
        return exr_fail(err, &in->io, rv, 0, "bad EXR part");
    if (in->storage == EXR_STORAGE_DEEP_SCANLINE || in->storage == EXR_STORAGE_DEEP_TILED)
        return btf_fail(err, BTF_E_UNSUPPORTED, "%s: deep EXR images are not supported", path);
    if (in->storage != EXR_STORAGE_SCANLINE && in->storage != EXR_STORAGE_TILED)
        return btf_fail(err, BTF_E_FORMAT, "%s: unknown EXR storage type %d", path,
                        (int)in->storage);
    exr_attr_box2i_t dw;
    rv = exr_get_data_window(in->ctx, 0, &dw);
    if (rv != EXR_ERR_SUCCESS)
        return exr_fail(err, &in->io, rv, 0, "bad data window");
    int64_t w = (int64_t)dw.max.x - dw.min.x + 1, h = (int64_t)dw.max.y - dw.min.y + 1;
    if (w < 1 || h < 1 || w > EXR_MAX_SIDE || h > EXR_MAX_SIDE)
        return btf_fail(err, BTF_E_FORMAT, "%s: EXR data window %lld x %lld out of range 1..%d",
                        path, (long long)w, (long long)h, EXR_MAX_SIDE);
    in->x0 = dw.min.x;
    in->y0 = dw.min.y;
    in->width = (int)w;
    in->height = (int)h;
    int rc = pick_channels(in, err);
    return rc ? rc : check_chunk_layout(in, err);
}

/* Called for each full-resolution chunk; (cx, cy) is its top-left pixel
 * relative to the data window. */
typedef int (*chunk_fn)(exr_in *in, const exr_chunk_info_t *ci, int cx, int cy, void *user,
                        btf_error *err);

/* The chunk must lie inside the image (we copy it there) and inside the file
 * (else it was cut off). */
static int check_chunk(const exr_in *in, const exr_chunk_info_t *ci, int cx, int cy,
                       btf_error *err)
{
    uint64_t size = (uint64_t)in->io.size;
    if (ci->width < 1 || ci->height < 1 || cx < 0 || cy < 0 ||
        (int64_t)cx + ci->width > in->width || (int64_t)cy + ci->height > in->height)
        return btf_fail(err, BTF_E_FORMAT, "%s: EXR chunk %d (%d x %d at %d, %d) lies outside the image",
                        in->io.path, (int)ci->idx, (int)ci->width, (int)ci->height, cx, cy);
    if (ci->data_offset > size || ci->packed_size > size - ci->data_offset)
        return btf_fail(err, BTF_E_FORMAT, "%s: truncated: EXR chunk %d ends past the end of the file",
                        in->io.path, (int)ci->idx);
    return BTF_OK;
}

static int each_scanline_chunk(exr_in *in, chunk_fn fn, void *user, btf_error *err)
{
    int32_t lines = 0;
    exr_result_t rv = exr_get_scanlines_per_chunk(in->ctx, 0, &lines);
    if (rv != EXR_ERR_SUCCESS || lines < 1)
        return exr_fail(err, &in->io, rv ? rv : EXR_ERR_INVALID_ATTR, 0, "bad scanlines per chunk");
    for (int64_t y = in->y0; y < (int64_t)in->y0 + in->height; y += lines) {
        exr_chunk_info_t ci;
        rv = exr_read_scanline_chunk_info(in->ctx, 0, (int)y, &ci);
        if (rv != EXR_ERR_SUCCESS)
            return exr_fail(err, &in->io, rv, 0, "bad EXR chunk");
        int cy = (int)((int64_t)ci.start_y - in->y0);
        int rc = check_chunk(in, &ci, 0, cy, err);
        if (!rc)
            rc = fn(in, &ci, 0, cy, user, err);
        if (rc)
            return rc;
    }
    return BTF_OK;
}

static int each_tile(exr_in *in, chunk_fn fn, void *user, btf_error *err)
{
    int32_t tw = 0, th = 0;
    exr_result_t rv = exr_get_tile_sizes(in->ctx, 0, 0, 0, &tw, &th);
    if (rv != EXR_ERR_SUCCESS || tw < 1 || th < 1)
        return exr_fail(err, &in->io, rv ? rv : EXR_ERR_INVALID_ATTR, 0, "bad tile size");
    int64_t ntx = ((int64_t)in->width + tw - 1) / tw, nty = ((int64_t)in->height + th - 1) / th;
    for (int64_t ty = 0; ty < nty; ty++) {
        for (int64_t tx = 0; tx < ntx; tx++) {
            exr_chunk_info_t ci;
            rv = exr_read_tile_chunk_info(in->ctx, 0, (int)tx, (int)ty, 0, 0, &ci);
            if (rv != EXR_ERR_SUCCESS)
                return exr_fail(err, &in->io, rv, 0, "bad EXR tile");
            /* tx < ntx, so tx * tw < width <= 65536: no overflow. */
            int cx = (int)(tx * tw), cy = (int)(ty * th);
            int rc = check_chunk(in, &ci, cx, cy, err);
            if (!rc)
                rc = fn(in, &ci, cx, cy, user, err);
            if (rc)
                return rc;
        }
    }
    return BTF_OK;
}

static int for_each_chunk(exr_in *in, chunk_fn fn, void *user, btf_error *err)
{
    return in->storage == EXR_STORAGE_TILED ? each_tile(in, fn, user, err)
                                            : each_scanline_chunk(in, fn, user, err);
}

/* The chunk-table walk's visitor: check_chunk already did the work. */
static int chunk_ok(exr_in *in, const exr_chunk_info_t *ci, int cx, int cy, void *user,
                    btf_error *err)
{
    (void)in, (void)ci, (void)cx, (void)cy, (void)user, (void)err;
    return BTF_OK;
}

/* Decoding state shared by the chunks of one image. */
typedef struct decoder {
    btf_image *out;
    exr_decode_pipeline_t dec;
    int started;
    float *buf;      /* one chunk, nsrc floats per pixel, interleaved */
    size_t cap;      /* floats in buf */
} decoder;

static int slot_of(const exr_in *in, const char *name)
{
    for (int k = 0; k < in->nsrc; k++)
        if (name && in->names[k] && !strcmp(name, in->names[k]))
            return k;
    return -1;
}

/* Points the pipeline's wanted channels into the scratch buffer as
 * interleaved floats (the library converts HALF); others are skipped. */
static int bind_outputs(exr_in *in, decoder *d, const exr_chunk_info_t *ci, btf_error *err)
{
    int bound = 0;
    for (int c = 0; c < d->dec.channel_count; c++) {
        exr_coding_channel_info_t *ch = &d->dec.channels[c];
        int k = slot_of(in, ch->channel_name);
        if (k < 0) {
            ch->decode_to_ptr = NULL;
            continue;
        }
        /* Our channels are not subsampled, so each must cover the chunk:
         * anything else would write past the scratch buffer. */
        if (ch->width != ci->width || ch->height != ci->height)
            return btf_fail(err, BTF_E_FORMAT, "%s: EXR channel %s does not cover its chunk",
                            in->io.path, in->names[k]);
        ch->decode_to_ptr = (uint8_t *)(d->buf + k);
        ch->user_pixel_stride = (int32_t)(in->nsrc * sizeof(float));
        ch->user_line_stride = (int32_t)((size_t)ci->width * in->nsrc * sizeof(float));
        ch->user_data_type = EXR_PIXEL_FLOAT;
        ch->user_bytes_per_element = (int16_t)sizeof(float);
        bound++;
    }
    if (bound != in->nsrc)
        return btf_fail(err, BTF_E_FORMAT, "%s: EXR chunk lacks some of its channels", in->io.path);
    return BTF_OK;
}

/* Luminance with Rec. 709 weights, in double so FLT_MAX inputs cannot
 * overflow on the way, clamped so the cast to float is defined. */
static float luminance(const float *p)
{
    double l = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    if (l > FLT_MAX)
        l = FLT_MAX;
    if (l < -FLT_MAX)
        l = -FLT_MAX;
    return (float)l;
}

/* Checks a decoded chunk for NaN/Inf and copies it into the image,
 * converting the channel count. */
static int store_chunk(const exr_in *in, const float *buf, const exr_chunk_info_t *ci, int cx,
                       int cy, btf_image *out, btf_error *err)
{
    int nsrc = in->nsrc, want = out->channels;
    for (int r = 0; r < ci->height; r++) {
        const float *p = buf + (size_t)r * ci->width * nsrc;
        float *o = out->data + ((size_t)(cy + r) * out->width + cx) * want;
        for (int x = 0; x < ci->width; x++, p += nsrc, o += want) {
            for (int k = 0; k < nsrc; k++)
                if (!isfinite(p[k]))
                    return btf_fail(err, BTF_E_DATA, "%s: NaN or Inf at pixel (%d, %d)",
                                    in->io.path, cx + x, cy + r);
            if (want == nsrc)
                memcpy(o, p, (size_t)nsrc * sizeof(float));
            else if (want == 1)
                o[0] = luminance(p);
            else
                o[0] = o[1] = o[2] = p[0];
        }
    }
    return BTF_OK;
}

static int decode_chunk(exr_in *in, const exr_chunk_info_t *ci, int cx, int cy, void *user,
                        btf_error *err)
{
    decoder *d = user;
    size_t n = (size_t)ci->width * (size_t)ci->height * (size_t)in->nsrc;
    if (n > d->cap) {
        free(d->buf);
        d->cap = 0;
        d->buf = btf_alloc(n, sizeof(float), err);
        if (!d->buf)
            return BTF_E_NOMEM;
        d->cap = n;
    }
    /* Defined contents even if a corrupt chunk decodes short. */
    memset(d->buf, 0, n * sizeof(float));
    exr_result_t rv = d->started ? exr_decoding_update(in->ctx, 0, ci, &d->dec)
                                 : exr_decoding_initialize(in->ctx, 0, ci, &d->dec);
    d->started = 1;
    if (rv != EXR_ERR_SUCCESS)
        return exr_fail(err, &in->io, rv, 0, "cannot decode EXR chunk");
    int rc = bind_outputs(in, d, ci, err);
    if (rc)
        return rc;
    /* Chosen again per chunk: the unpacker depends on the chunk's shape. */
    rv = exr_decoding_choose_default_routines(in->ctx, 0, &d->dec);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_decoding_run(in->ctx, 0, &d->dec);
    if (rv != EXR_ERR_SUCCESS)
        return exr_fail(err, &in->io, rv, 0, "corrupt EXR chunk");
    return store_chunk(in, d->buf, ci, cx, cy, d->out, err);
}

static int read_pixels(exr_in *in, int channels, btf_image *out, btf_error *err)
{
    int want = channels ? channels : in->nsrc;
    int rc = btf_image_alloc(out, in->width, in->height, want, err);
    if (rc) {
        if (err) {
            char m[sizeof err->msg];
            memcpy(m, err->msg, sizeof m);
            btf_fail(err, rc, "%s: %s", in->io.path, m);
        }
        return rc;
    }
    decoder d;
    memset(&d, 0, sizeof d);
    d.out = out;
    rc = for_each_chunk(in, decode_chunk, &d, err);
    if (d.started)
        exr_decoding_destroy(in->ctx, &d.dec);
    free(d.buf);
    return rc;
}

int btf_exr_probe(const char *path, btf_image_header *hdr, btf_error *err)
{
    if (!path || !hdr)
        return btf_fail(err, BTF_E_ARG, "btf_exr_probe: NULL argument");
    memset(hdr, 0, sizeof *hdr);
    exr_in in;
    memset(&in, 0, sizeof in);
    in.io.path = path;
    in.io.fd = -1;
    exr_io *prev = sink_enter(&in.io);
    int rc = in_open(&in, path, err);
    if (!rc)
        rc = in_inspect(&in, err);
    /* Walking the chunk table catches truncation without decoding. */
    if (!rc)
        rc = for_each_chunk(&in, chunk_ok, NULL, err);
    if (!rc) {
        hdr->format = BTF_FILE_EXR;
        hdr->width = in.width;
        hdr->height = in.height;
        hdr->channels = in.nsrc;
        hdr->bits = in.bits;
        hdr->file_bytes = (uint64_t)in.io.size;
    }
    in_close(&in);
    sink_leave(prev);
    return rc;
}

int btf_exr_read(const char *path, int channels, btf_image *out, btf_error *err)
{
    if (!path || !out)
        return btf_fail(err, BTF_E_ARG, "btf_exr_read: NULL argument");
    memset(out, 0, sizeof *out);
    if (channels != 0 && channels != 1 && channels != 3)
        return btf_fail(err, BTF_E_ARG, "%s: channels %d: expected 0, 1 or 3", path, channels);
    exr_in in;
    memset(&in, 0, sizeof in);
    in.io.path = path;
    in.io.fd = -1;
    exr_io *prev = sink_enter(&in.io);
    int rc = in_open(&in, path, err);
    if (!rc)
        rc = in_inspect(&in, err);
    /* A cut-off or damaged chunk table fails here, before the image is
     * allocated (a header may claim 65536 x 65536 in a few kilobytes). */
    if (!rc)
        rc = for_each_chunk(&in, chunk_ok, NULL, err);
    if (!rc)
        rc = read_pixels(&in, channels, out, err);
    in_close(&in);
    sink_leave(prev);
    if (rc)
        btf_image_free(out);
    return rc;
}

/* ------------------------------------------------------------- writing */

struct btf_exr_writer {
    exr_io io;                  /* our descriptor on the temporary file */
    exr_context_t ctx;
    exr_encode_pipeline_t enc;
    int enc_started;
    char *path;                 /* the final name */
    char tmp[4096];             /* the temporary name beside it */
    int tmp_created;
    int width, height, channels, half;
    int lines;                  /* scanlines per chunk */
    int rows_done;              /* rows accepted, including staged ones */
    int rows_staged;            /* rows waiting in stage for their chunk */
    float *stage;               /* lines * width * channels floats */
    int failed;                 /* an error happened: only abort/close remain */
    exr_result_t (*compress)(exr_encode_pipeline_t *); /* the library's */
};

/* Where a file channel's samples sit in an interleaved pixel. */
static int channel_slot(const char *name)
{
    if (!name)
        return -1;
    if (!strcmp(name, "R") || !strcmp(name, "Y"))
        return 0;
    if (!strcmp(name, "G"))
        return 1;
    if (!strcmp(name, "B"))
        return 2;
    return -1;
}

/* Header: one scanline part, the size, ZIP, the channels in sorted order. */
static exr_result_t writer_header(btf_exr_writer *w)
{
    int part = 0;
    exr_result_t rv = exr_add_part(w->ctx, NULL, EXR_STORAGE_SCANLINE, &part);
    if (!rv)
        rv = exr_initialize_required_attr_simple(w->ctx, part, w->width, w->height,
                                                 EXR_COMPRESSION_ZIP);
    static const char *const rgb[] = {"B", "G", "R"}, *const grey[] = {"Y"};
    const char *const *names = w->channels == 3 ? rgb : grey;
    exr_pixel_type_t type = w->half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT;
    for (int c = 0; c < w->channels && !rv; c++)
        rv = exr_add_channel(w->ctx, part, names[c], type, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
    /* zlib level 4, not the library's default 6: on synthesised texture
     * (noise-like, it barely compresses) a 32768 x 512 half-float image
     * took 9.0 s at 6, 3.6 s at 4 and 3.0 s at 1, for 67.8, 68.8 and 70.2
     * MB: level 6 spent 90 % of synthesis in deflate for 1.5 % of size. */
    if (!rv)
        rv = exr_set_zip_compression_level(w->ctx, part, 4);
    if (!rv)
        rv = exr_write_header(w->ctx);
    int32_t lines = 0;
    if (!rv)
        rv = exr_get_scanlines_per_chunk(w->ctx, part, &lines);
    if (!rv && lines < 1)
        rv = EXR_ERR_INVALID_ATTR;
    w->lines = lines;
    return rv;
}

/* Creates the temporary file, the context and the header; allocates the
 * one-chunk staging buffer. */
static int writer_start(btf_exr_writer *w, btf_error *err)
{
    int fd = open(w->tmp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd < 0)
        return btf_fail(err, BTF_E_IO, "%s: cannot create: %s", w->path, strerror(errno));
    w->io.fd = fd;
    w->tmp_created = 1;
    exr_context_initializer_t init = exr_init_for(&w->io, 1);
    exr_result_t rv = exr_start_write(&w->ctx, w->path, EXR_WRITE_FILE_DIRECTLY, &init);
    if (rv != EXR_ERR_SUCCESS) {
        w->ctx = NULL; /* exr_start_write frees it on failure */
        return exr_fail(err, &w->io, rv, 1, "cannot start EXR file");
    }
    rv = writer_header(w);
    if (rv != EXR_ERR_SUCCESS)
        return exr_fail(err, &w->io, rv, 1, "cannot write EXR header");
    w->stage = btf_alloc((size_t)w->lines * (size_t)w->width * (size_t)w->channels,
                         sizeof(float), err);
    return w->stage ? BTF_OK : BTF_E_NOMEM;
}

int btf_exr_writer_open(const char *path, int width, int height, int channels, int half,
                        btf_exr_writer **out, btf_error *err)
{
    if (!out)
        return btf_fail(err, BTF_E_ARG, "btf_exr_writer_open: NULL output pointer");
    *out = NULL;
    if (!path || !*path)
        return btf_fail(err, BTF_E_ARG, "btf_exr_writer_open: no path");
    if (width < 1 || height < 1 || width > EXR_MAX_SIDE || height > EXR_MAX_SIDE)
        return btf_fail(err, BTF_E_ARG, "%s: image size %dx%d out of range 1..%d", path, width,
                        height, EXR_MAX_SIDE);
    if (channels != 1 && channels != 3)
        return btf_fail(err, BTF_E_ARG, "%s: channels %d: expected 1 or 3", path, channels);
    btf_exr_writer *w = btf_calloc(1, sizeof *w, err);
    if (!w)
        return BTF_E_NOMEM;
    w->io.fd = -1;
    w->width = width;
    w->height = height;
    w->channels = channels;
    w->half = half != 0;
    w->path = strdup(path);
    if (!w->path) {
        free(w);
        return btf_fail(err, BTF_E_NOMEM, "%s: out of memory", path);
    }
    w->io.path = w->path;
    int rc = btf_tmp_path(path, w->tmp, sizeof w->tmp, err);
    if (!rc) {
        exr_io *prev = sink_enter(&w->io);
        rc = writer_start(w, err);
        sink_leave(prev);
    }
    if (rc) {
        btf_exr_writer_abort(w);
        return rc;
    }
    *out = w;
    return BTF_OK;
}

/* Rows of the chunk being filled (the last chunk may be short). */
static int chunk_rows(const btf_exr_writer *w)
{
    int start = w->rows_done - w->rows_staged;
    return w->height - start < w->lines ? w->height - start : w->lines;
}

/* Copies one row into the staging buffer: refuses non-finite values, clamps
 * to the half range when writing half (the library would make them Inf). */
static int stage_row(btf_exr_writer *w, const float *src, btf_error *err)
{
    size_t n = (size_t)w->width * (size_t)w->channels;
    float *dst = w->stage + (size_t)w->rows_staged * n;
    for (size_t i = 0; i < n; i++) {
        float v = src[i];
        if (!isfinite(v))
            return btf_fail(err, BTF_E_ARG, "%s: %s at pixel (%d, %d): EXR output must be finite",
                            w->path, isnan(v) ? "NaN" : "Inf", (int)(i / (size_t)w->channels),
                            w->rows_done);
        if (w->half)
            v = v > HALF_MAX_VALUE ? HALF_MAX_VALUE : v < -HALF_MAX_VALUE ? -HALF_MAX_VALUE : v;
        dst[i] = v;
    }
    w->rows_staged++;
    w->rows_done++;
    return BTF_OK;
}

/* Points the encoder's channels at the interleaved staging buffer. */
static int bind_inputs(btf_exr_writer *w, btf_error *err)
{
    for (int c = 0; c < w->enc.channel_count; c++) {
        exr_coding_channel_info_t *ch = &w->enc.channels[c];
        int k = channel_slot(ch->channel_name);
        if (k < 0 || k >= w->channels)
            return btf_fail(err, BTF_E_IO, "%s: unexpected EXR channel %s", w->path,
                            ch->channel_name ? ch->channel_name : "?");
        ch->encode_from_ptr = (const uint8_t *)(w->stage + k);
        ch->user_pixel_stride = (int32_t)((size_t)w->channels * sizeof(float));
        ch->user_line_stride = (int32_t)((size_t)w->width * w->channels * sizeof(float));
        ch->user_data_type = EXR_PIXEL_FLOAT;
        ch->user_bytes_per_element = (int16_t)sizeof(float);
    }
    return BTF_OK;
}

/* EXR stores a chunk raw when compression does not make it smaller, and
 * readers decide by comparing sizes: equal sizes mean raw. OpenEXRCore 3.1.5
 * keeps compressed output that is exactly as long as the raw data (seen with
 * a 16-pixel half row), which every reader then misreads. So: the library's
 * compressor, then the raw bytes whenever they are not larger. */
static exr_result_t compress_or_store(exr_encode_pipeline_t *enc)
{
    btf_exr_writer *w = enc->encoding_user_data;
    exr_result_t rv = w->compress(enc);
    if (rv != EXR_ERR_SUCCESS || enc->compressed_bytes < enc->packed_bytes)
        return rv;
    if (enc->compressed_buffer != enc->packed_buffer) {
        /* The compressed buffer is allocated for the worst case, which is
         * never smaller than the packed data; checked all the same. */
        if (!enc->compressed_buffer || enc->compressed_alloc_size < enc->packed_bytes)
            return EXR_ERR_OUT_OF_MEMORY;
        memcpy(enc->compressed_buffer, enc->packed_buffer, enc->packed_bytes);
    }
    enc->compressed_bytes = enc->packed_bytes;
    return rv;
}

/* Compresses and writes the staged rows as one chunk. */
static int flush_chunk(btf_exr_writer *w, btf_error *err)
{
    int y = w->rows_done - w->rows_staged;
    exr_chunk_info_t ci;
    exr_result_t rv = exr_write_scanline_chunk_info(w->ctx, 0, y, &ci);
    if (!rv) {
        rv = w->enc_started ? exr_encoding_update(w->ctx, 0, &ci, &w->enc)
                            : exr_encoding_initialize(w->ctx, 0, &ci, &w->enc);
        w->enc_started = 1;
    }
    if (rv)
        return exr_fail(err, &w->io, rv, 1, "cannot encode rows");
    int rc = bind_inputs(w, err);
    if (rc)
        return rc;
    rv = exr_encoding_choose_default_routines(w->ctx, 0, &w->enc);
    if (!rv && w->enc.compress_fn) {
        w->compress = w->enc.compress_fn;
        w->enc.compress_fn = compress_or_store;
        w->enc.encoding_user_data = w;
    }
    if (!rv)
        rv = exr_encoding_run(w->ctx, 0, &w->enc);
    if (rv)
        return exr_fail(err, &w->io, rv, 1, "cannot write rows");
    w->rows_staged = 0;
    return BTF_OK;
}

int btf_exr_writer_put_rows(btf_exr_writer *w, const float *rows, int nrows, btf_error *err)
{
    if (!w)
        return btf_fail(err, BTF_E_ARG, "btf_exr_writer_put_rows: NULL writer");
    if (w->failed)
        return btf_fail(err, BTF_E_ARG, "%s: the EXR writer failed earlier", w->path);
    int rc = BTF_OK;
    if (nrows < 0 || (nrows > 0 && !rows))
        rc = btf_fail(err, BTF_E_ARG, "%s: bad rows (%d)", w->path, nrows);
    else if (nrows > w->height - w->rows_done)
        rc = btf_fail(err, BTF_E_ARG, "%s: %d rows given, but only %d of %d remain", w->path,
                      nrows, w->height - w->rows_done, w->height);
    size_t rowlen = (size_t)w->width * (size_t)w->channels;
    exr_io *prev = sink_enter(&w->io);
    for (int i = 0; i < nrows && !rc; i++) {
        rc = stage_row(w, rows + (size_t)i * rowlen, err);
        if (!rc && w->rows_staged == chunk_rows(w))
            rc = flush_chunk(w, err);
    }
    sink_leave(prev);
    /* Any error is final: a file with a hole in it must never be committed. */
    if (rc)
        w->failed = 1;
    return rc;
}

/* Writes the offset table, closes the descriptor and renames into place. */
static int writer_finish(btf_exr_writer *w, btf_error *err)
{
    if (w->enc_started)
        exr_encoding_destroy(w->ctx, &w->enc);
    w->enc_started = 0;
    exr_result_t rv = exr_finish(&w->ctx);
    if (rv != EXR_ERR_SUCCESS || w->io.sys_errno)
        return exr_fail(err, &w->io, rv ? rv : EXR_ERR_WRITE_IO, 1, "cannot finish EXR file");
    int fd = w->io.fd;
    w->io.fd = -1;
    if (close(fd) != 0)
        return btf_fail(err, BTF_E_IO, "%s: write failed: %s", w->path, strerror(errno));
    int rc = btf_commit_file(w->tmp, w->path, err);
    w->tmp_created = 0; /* renamed, or removed by btf_commit_file */
    return rc;
}

int btf_exr_writer_close(btf_exr_writer *w, btf_error *err)
{
    if (!w)
        return btf_fail(err, BTF_E_ARG, "btf_exr_writer_close: NULL writer");
    int rc = BTF_OK;
    if (w->failed)
        rc = btf_fail(err, BTF_E_ARG, "%s: the EXR writer failed earlier; nothing written",
                      w->path);
    else if (w->rows_done != w->height)
        rc = btf_fail(err, BTF_E_ARG, "%s: EXR writer closed after %d of %d rows; nothing written",
                      w->path, w->rows_done, w->height);
    if (!rc) {
        exr_io *prev = sink_enter(&w->io);
        rc = writer_finish(w, err);
        sink_leave(prev);
    }
    btf_exr_writer_abort(w); /* frees; removes the temporary file if it is left */
    return rc;
}

void btf_exr_writer_abort(btf_exr_writer *w)
{
    if (!w)
        return;
    /* Messages from tearing down a half-written file are of no interest. */
    exr_io *prev = sink_enter(&w->io);
    if (w->ctx) {
        if (w->enc_started)
            exr_encoding_destroy(w->ctx, &w->enc);
        exr_finish(&w->ctx);
    }
    sink_leave(prev);
    if (w->io.fd >= 0)
        close(w->io.fd);
    if (w->tmp_created)
        btf_abort_file(w->tmp);
    free(w->stage);
    free(w->path);
    free(w);
}

int btf_exr_write(const char *path, const btf_image *img, int half, btf_error *err)
{
    if (!img || !img->data)
        return btf_fail(err, BTF_E_ARG, "%s: no image to write", path ? path : "(null)");
    btf_exr_writer *w = NULL;
    int rc = btf_exr_writer_open(path, img->width, img->height, img->channels, half, &w, err);
    if (rc)
        return rc;
    rc = btf_exr_writer_put_rows(w, img->data, img->height, err);
    if (rc) {
        btf_exr_writer_abort(w);
        return rc;
    }
    return btf_exr_writer_close(w, err);
}
