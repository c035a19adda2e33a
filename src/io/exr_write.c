/*
 * exr_write.c — writing OpenEXR through the OpenEXR core C API: a streaming
 * scanline writer, and the one-shot writer built on it.
 *
 * Channel "Y", or "B", "G", "R" (EXR stores channels sorted by name), HALF
 * or FLOAT, scanlines in increasing y, ZIP compression: lossless deflate
 * (zlib level 4, see writer_header) over 16-scanline chunks, read by every
 * EXR implementation, good on smooth data and deterministic (the same
 * pixels give the same bytes). Non-finite input is refused (BTF_E_ARG)
 * because such a file could not be read back; half output is clamped to
 * +-65504 so it never holds Inf. A chunk that does not shrink is stored raw
 * (see compress_or_store: works around OpenEXRCore 3.1.5 writing unreadable
 * chunks).
 *
 * We do the file I/O ourselves (pwrite on our own descriptor), so a failing
 * system call is reported as such, and so the writer writes to the
 * temporary file from btf_tmp_create() (O_EXCL | O_NOFOLLOW), fsync'd, and
 * the file appears only through btf_commit_file().
 *
 * Provenance (btf_exr_meta): string attributes btfcarVersion, and with a
 * model btfcarModel, btfcarSeed, btfcarSubspace, and with directions
 * btfcarView, btfcarLight ("THETA PHI" in degrees), plus the standard
 * chromaticities attribute: the primaries and white point of linear sRGB
 * (Rec. 709, D65), which is what btfcar's linear RGB is. They change the
 * header only; the pixels are the same with or without them.
 */
#include <stdio.h>
#include "core/core.h"
#include "io/exr.h"

#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define HALF_MAX_VALUE 65504.0f

/* The library's write callback: pwrite in a loop on our descriptor. */
static int64_t io_write(exr_const_context_t ctxt, void *user, const void *buffer, uint64_t sz,
                        uint64_t offset, exr_stream_error_func_ptr_t error_cb)
{
    (void)ctxt;
    (void)error_cb;
    btf_exr_io *io = user;
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

struct btf_exr_writer {
    btf_exr_io io;              /* our descriptor on the temporary file */
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

/* Linear sRGB: the Rec. 709 primaries and the D65 white point (CIE xy). */
static const exr_attr_chromaticities_t REC709_D65 = {0.64f, 0.33f, 0.30f, 0.60f,
                                                     0.15f, 0.06f, 0.3127f, 0.3290f};

static exr_result_t set_dir(exr_context_t ctx, int part, const char *name, btf_dir d)
{
    char text[64];
    snprintf(text, sizeof text, "%.10g %.10g", d.theta, d.phi);
    return exr_attr_set_string(ctx, part, name, text);
}

/* The provenance attributes of the top comment. */
static exr_result_t write_meta(exr_context_t ctx, int part, const btf_exr_meta *m)
{
    exr_result_t rv = exr_attr_set_chromaticities(ctx, part, "chromaticities", &REC709_D65);
    if (!rv)
        rv = exr_attr_set_string(ctx, part, "btfcarVersion", BTF_VERSION_STRING);
    if (!rv && m->model) {
        char num[32];
        rv = exr_attr_set_string(ctx, part, "btfcarModel", m->model);
        snprintf(num, sizeof num, "%" PRIu64, m->seed);
        if (!rv)
            rv = exr_attr_set_string(ctx, part, "btfcarSeed", num);
        snprintf(num, sizeof num, "%d", m->subspace);
        if (!rv)
            rv = exr_attr_set_string(ctx, part, "btfcarSubspace", num);
    }
    if (!rv && m->has_dirs)
        rv = set_dir(ctx, part, "btfcarView", m->view);
    if (!rv && m->has_dirs)
        rv = set_dir(ctx, part, "btfcarLight", m->light);
    return rv;
}

/* Header: one scanline part, the size, ZIP, the channels in sorted order,
 * then the provenance when there is any. */
static exr_result_t writer_header(btf_exr_writer *w, const btf_exr_meta *meta)
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
    if (!rv && meta)
        rv = write_meta(w->ctx, part, meta);
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
static btf_status writer_start(btf_exr_writer *w, const btf_exr_meta *meta, btf_error *err)
{
    int fd;
    btf_status rc = btf_tmp_create(w->path, w->tmp, sizeof w->tmp, &fd, err);
    if (rc)
        return rc;
    w->io.fd = fd;
    w->tmp_created = 1;
    exr_context_initializer_t init = btf_exr_initializer(&w->io);
    init.write_fn = io_write;
    exr_result_t rv = exr_start_write(&w->ctx, w->path, EXR_WRITE_FILE_DIRECTLY, &init);
    if (rv != EXR_ERR_SUCCESS) {
        w->ctx = NULL; /* exr_start_write frees it on failure */
        return btf_exr_fail(err, &w->io, rv, 1, "cannot start EXR file");
    }
    rv = writer_header(w, meta);
    if (rv != EXR_ERR_SUCCESS)
        return btf_exr_fail(err, &w->io, rv, 1, "cannot write EXR header");
    w->stage = btf_alloc((size_t)w->lines * (size_t)w->width * (size_t)w->channels,
                         sizeof(float), err);
    return w->stage ? BTF_OK : BTF_E_NOMEM;
}

btf_status btf_exr_writer_open_meta(const char *path, int width, int height, int channels,
                                    int half, const btf_exr_meta *meta, btf_exr_writer **out,
                                    btf_error *err)
{
    if (!out)
        return btf_fail(err, BTF_E_ARG, "btf_exr_writer_open: NULL output pointer");
    *out = NULL;
    if (!path || !*path)
        return btf_fail(err, BTF_E_ARG, "btf_exr_writer_open: no path");
    if (width < 1 || height < 1 || width > BTF_EXR_MAX_SIDE || height > BTF_EXR_MAX_SIDE)
        return btf_fail(err, BTF_E_ARG, "%s: image size %dx%d out of range 1..%d", path, width,
                        height, BTF_EXR_MAX_SIDE);
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
    btf_status rc = BTF_OK;
    {
        btf_exr_io *prev = btf_exr_sink_enter(&w->io);
        rc = writer_start(w, meta, err);
        btf_exr_sink_leave(prev);
    }
    if (rc) {
        btf_exr_writer_abort(w);
        return rc;
    }
    *out = w;
    return BTF_OK;
}

btf_status btf_exr_writer_open(const char *path, int width, int height, int channels, int half,
                               btf_exr_writer **out, btf_error *err)
{
    return btf_exr_writer_open_meta(path, width, height, channels, half, NULL, out, err);
}

/* Rows of the chunk being filled (the last chunk may be short). */
static int chunk_rows(const btf_exr_writer *w)
{
    int start = w->rows_done - w->rows_staged;
    return w->height - start < w->lines ? w->height - start : w->lines;
}

/* Copies one row into the staging buffer: refuses non-finite values, clamps
 * to the half range when writing half (the library would make them Inf). */
static btf_status stage_row(btf_exr_writer *w, const float *src, btf_error *err)
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
static btf_status bind_inputs(btf_exr_writer *w, btf_error *err)
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
static btf_status flush_chunk(btf_exr_writer *w, btf_error *err)
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
        return btf_exr_fail(err, &w->io, rv, 1, "cannot encode rows");
    btf_status rc = bind_inputs(w, err);
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
        return btf_exr_fail(err, &w->io, rv, 1, "cannot write rows");
    w->rows_staged = 0;
    return BTF_OK;
}

btf_status btf_exr_writer_put_rows(btf_exr_writer *w, const float *rows, int nrows, btf_error *err)
{
    if (!w)
        return btf_fail(err, BTF_E_ARG, "btf_exr_writer_put_rows: NULL writer");
    if (w->failed)
        return btf_fail(err, BTF_E_ARG, "%s: the EXR writer failed earlier", w->path);
    btf_status rc = BTF_OK;
    if (nrows < 0 || (nrows > 0 && !rows))
        rc = btf_fail(err, BTF_E_ARG, "%s: bad rows (%d)", w->path, nrows);
    else if (nrows > w->height - w->rows_done)
        rc = btf_fail(err, BTF_E_ARG, "%s: %d rows given, but only %d of %d remain", w->path,
                      nrows, w->height - w->rows_done, w->height);
    size_t rowlen = (size_t)w->width * (size_t)w->channels;
    btf_exr_io *prev = btf_exr_sink_enter(&w->io);
    for (int i = 0; i < nrows && !rc; i++) {
        rc = stage_row(w, rows + (size_t)i * rowlen, err);
        if (!rc && w->rows_staged == chunk_rows(w))
            rc = flush_chunk(w, err);
    }
    btf_exr_sink_leave(prev);
    /* Any error is final: a file with a hole in it must never be committed. */
    if (rc)
        w->failed = 1;
    return rc;
}

/* Writes the offset table, closes the descriptor and renames into place. */
static btf_status writer_finish(btf_exr_writer *w, btf_error *err)
{
    if (w->enc_started)
        exr_encoding_destroy(w->ctx, &w->enc);
    w->enc_started = 0;
    exr_result_t rv = exr_finish(&w->ctx);
    if (rv != EXR_ERR_SUCCESS || w->io.sys_errno)
        return btf_exr_fail(err, &w->io, rv ? rv : EXR_ERR_WRITE_IO, 1, "cannot finish EXR file");
    int fd = w->io.fd;
    w->io.fd = -1;
    int e = fsync(fd) != 0 ? errno : 0;
    if (close(fd) != 0 && !e)
        e = errno;
    if (e)
        return btf_fail(err, BTF_E_IO, "%s: write failed: %s", w->path, strerror(e));
    btf_status rc = btf_commit_file(w->tmp, w->path, err);
    w->tmp_created = 0; /* renamed, or removed by btf_commit_file */
    return rc;
}

btf_status btf_exr_writer_close(btf_exr_writer *w, btf_error *err)
{
    if (!w)
        return btf_fail(err, BTF_E_ARG, "btf_exr_writer_close: NULL writer");
    btf_status rc = BTF_OK;
    if (w->failed)
        rc = btf_fail(err, BTF_E_ARG, "%s: the EXR writer failed earlier; nothing written",
                      w->path);
    else if (w->rows_done != w->height)
        rc = btf_fail(err, BTF_E_ARG, "%s: EXR writer closed after %d of %d rows; nothing written",
                      w->path, w->rows_done, w->height);
    if (!rc) {
        btf_exr_io *prev = btf_exr_sink_enter(&w->io);
        rc = writer_finish(w, err);
        btf_exr_sink_leave(prev);
    }
    btf_exr_writer_abort(w); /* frees; removes the temporary file if it is left */
    return rc;
}

void btf_exr_writer_abort(btf_exr_writer *w)
{
    if (!w)
        return;
    /* Messages from tearing down a half-written file are of no interest. */
    btf_exr_io *prev = btf_exr_sink_enter(&w->io);
    if (w->ctx) {
        if (w->enc_started)
            exr_encoding_destroy(w->ctx, &w->enc);
        exr_finish(&w->ctx);
    }
    btf_exr_sink_leave(prev);
    if (w->io.fd >= 0)
        close(w->io.fd);
    if (w->tmp_created)
        btf_abort_file(w->tmp);
    free(w->stage);
    free(w->path);
    free(w);
}

btf_status btf_image_write_exr_meta(const char *path, const btf_image *img, int half,
                                    const btf_exr_meta *meta, btf_error *err)
{
    if (!img || !img->data)
        return btf_fail(err, BTF_E_ARG, "%s: no image to write", path ? path : "(null)");
    btf_exr_writer *w = NULL;
    btf_status rc = btf_exr_writer_open_meta(path, img->width, img->height, img->channels, half,
                                             meta, &w, err);
    if (rc)
        return rc;
    rc = btf_exr_writer_put_rows(w, img->data, img->height, err);
    if (rc) {
        btf_exr_writer_abort(w);
        return rc;
    }
    return btf_exr_writer_close(w, err);
}

btf_status btf_image_write_exr(const char *path, const btf_image *img, int half, btf_error *err)
{
    return btf_image_write_exr_meta(path, img, half, NULL, err);
}
