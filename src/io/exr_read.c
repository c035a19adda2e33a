/*
 * exr_read.c — reading OpenEXR through the OpenEXR core C API (OpenEXRCore:
 * plain C, no exceptions) from a byte source (io/source.c: a file read with
 * pread, or a memory buffer): a header probe, and a decoder of scanline or
 * tiled HALF/FLOAT images to linear float.
 *
 * Why these choices:
 *  - The bytes come through our read callback, so a failing system call
 *    (BTF_E_IO) can be told from a file that simply ends too early
 *    (BTF_E_FORMAT), and a buffer in memory is read exactly like a file.
 *  - Files are untrusted: image sides are limited to 65536, the chunk offset
 *    table must fit in the file, every chunk must lie inside the file and
 *    inside the image (all are checked before the image is allocated), and
 *    one chunk may not unpack to more than BTF_EXR_MAX_CHUNK_BYTES. The
 *    library's chunk-table "reconstruction" is switched off: a damaged table
 *    is an error, not a guess.
 *
 * What is read: part 0 only (other parts are ignored). Channels R, G, B give
 * a colour image; else Y, else a lone channel of any name gives grey. Other
 * channels (A, Z, ...) are skipped. Deep parts, UINT or subsampled image
 * channels and luminance/chroma files (Y with RY/BY) are BTF_E_UNSUPPORTED.
 * Tiled parts are read at their full-resolution level. All compressions of
 * OpenEXRCore 3.1 are read; it has no DWAA/DWAB codec, so those files are
 * BTF_E_UNSUPPORTED too. Decoding goes chunk by chunk through one scratch
 * buffer, so memory is the image plus one chunk. Any NaN or Inf sample is
 * BTF_E_DATA naming the pixel.
 */
#include <stdio.h>
#include "core/core.h"
#include "io/exr.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* Largest unpacked chunk we let the library allocate for: far above any sane
 * file (a 65536-wide, 32-line PIZ chunk of 4 float channels is 32 MiB), far
 * below what a hostile header could ask for. A fuzzing build may lower it. */
#ifndef BTF_EXR_MAX_CHUNK_BYTES
#define BTF_EXR_MAX_CHUNK_BYTES ((uint64_t)1 << 30)
#endif

/* The library's read callback: the bytes of the source. */
static int64_t io_read(exr_const_context_t ctxt, void *user, void *buffer, uint64_t sz,
                       uint64_t offset, exr_stream_error_func_ptr_t error_cb)
{
    (void)ctxt;
    (void)error_cb;
    btf_exr_io *io = user;
    int64_t r = btf__source_read(io->src, buffer, sz, offset);
    if (r < 0)
        io->sys_errno = io->src->sys_errno;
    return r;
}

static int64_t io_size(exr_const_context_t ctxt, void *user)
{
    (void)ctxt;
    return (int64_t)((btf_exr_io *)user)->src->size;
}

typedef struct exr_in {
    btf_exr_io io;
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
}

/* Parses the header of src (the caller has entered in->io as sink). */
static btf_status in_open(exr_in *in, btf_source *src, btf_error *err)
{
    in->io.src = src;
    in->io.path = src->name;
    in->io.fd = -1;
    exr_context_initializer_t init = btf__exr_initializer(&in->io);
    init.read_fn = io_read;
    init.size_fn = io_size;
    init.flags = EXR_CONTEXT_FLAG_DISABLE_CHUNK_RECONSTRUCTION;
    exr_result_t rv = exr_start_read(&in->ctx, src->name, &init);
    if (rv != EXR_ERR_SUCCESS) {
        in->ctx = NULL; /* exr_start_read frees it on failure */
        return btf__exr_fail(err, &in->io, rv, 0, "not a readable EXR file");
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
static btf_status pick_channels(exr_in *in, btf_error *err)
{
    const char *path = in->io.path;
    const exr_attr_chlist_t *cl = NULL;
    exr_result_t rv = exr_get_channels(in->ctx, 0, &cl);
    if (rv != EXR_ERR_SUCCESS || !cl || cl->num_channels < 1 || !cl->entries)
        return btf__fail(err, BTF_E_FORMAT, "%s: EXR part has no channels", path);
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
            return btf__fail(err, BTF_E_UNSUPPORTED,
                             "%s: luminance/chroma EXR (Y, RY, BY) is not supported", path);
        in->nsrc = 1;
        idx[0] = y;
    } else if (cl->num_channels == 1) {
        in->nsrc = 1;
        idx[0] = 0;
    } else {
        char names[256];
        list_channels(cl, names, sizeof names);
        return btf__fail(err, BTF_E_UNSUPPORTED,
                         "%s: EXR channels (%s): expected R, G, B, or Y, or a single channel",
                         path, names);
    }
    in->bits = 16;
    for (int k = 0; k < in->nsrc; k++) {
        const exr_attr_chlist_entry_t *e = &cl->entries[idx[k]];
        const char *name = e->name.str ? e->name.str : "?";
        if (e->pixel_type == EXR_PIXEL_UINT)
            return btf__fail(err, BTF_E_UNSUPPORTED,
                             "%s: EXR channel %s holds UINT samples: only HALF and FLOAT are supported",
                             path, name);
        if (e->pixel_type != EXR_PIXEL_HALF && e->pixel_type != EXR_PIXEL_FLOAT)
            return btf__fail(err, BTF_E_FORMAT, "%s: EXR channel %s has an unknown pixel type %d",
                             path, name, (int)e->pixel_type);
        if (e->x_sampling != 1 || e->y_sampling != 1)
            return btf__fail(err, BTF_E_UNSUPPORTED,
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
static btf_status check_chunk_layout(exr_in *in, btf_error *err)
{
    const char *path = in->io.path;
    int32_t count = 0;
    exr_result_t rv = exr_get_chunk_count(in->ctx, 0, &count);
    if (rv != EXR_ERR_SUCCESS || count < 1)
        return btf__exr_fail(err, &in->io, rv ? rv : EXR_ERR_INVALID_ATTR, 0, "bad chunk count");
    if ((uint64_t)count * 8u > (uint64_t)in->io.src->size)
        return btf__fail(err, BTF_E_FORMAT,
                         "%s: truncated: the offsets of %d chunks do not fit in %lld bytes", path,
                         (int)count, (long long)in->io.src->size);
    uint64_t unpacked = 0;
    rv = exr_get_chunk_unpacked_size(in->ctx, 0, &unpacked);
    if (rv != EXR_ERR_SUCCESS)
        return btf__exr_fail(err, &in->io, rv, 0, "bad chunk size");
    if (unpacked > BTF_EXR_MAX_CHUNK_BYTES)
        return btf__fail(err, BTF_E_UNSUPPORTED,
                         "%s: EXR chunks of %llu bytes exceed the limit of %llu", path,
                         (unsigned long long)unpacked,
                         (unsigned long long)BTF_EXR_MAX_CHUNK_BYTES);
    return BTF_OK;
}

/* Storage type, data window, channels, chunk layout of part 0. */
static btf_status in_inspect(exr_in *in, btf_error *err)
{
    const char *path = in->io.path;
    exr_result_t rv = exr_get_storage(in->ctx, 0, &in->storage);
    if (rv != EXR_ERR_SUCCESS)
        return btf__exr_fail(err, &in->io, rv, 0, "bad EXR part");
    if (in->storage == EXR_STORAGE_DEEP_SCANLINE || in->storage == EXR_STORAGE_DEEP_TILED)
        return btf__fail(err, BTF_E_UNSUPPORTED, "%s: deep EXR images are not supported", path);
    if (in->storage != EXR_STORAGE_SCANLINE && in->storage != EXR_STORAGE_TILED)
        return btf__fail(err, BTF_E_FORMAT, "%s: unknown EXR storage type %d", path,
                         (int)in->storage);
    /* OpenEXR 3.1's B44/B44A decoder (Debian 12) reads out of bounds on a
     * damaged file (found by fuzz_exr); such files are refused before any
     * chunk is decoded rather than risk a crash. */
    exr_compression_t comp;
    rv = exr_get_compression(in->ctx, 0, &comp);
    if (rv != EXR_ERR_SUCCESS)
        return btf__exr_fail(err, &in->io, rv, 0, "bad compression attribute");
    if (comp == EXR_COMPRESSION_B44 || comp == EXR_COMPRESSION_B44A)
        return btf__fail(err, BTF_E_UNSUPPORTED, "%s: B44/B44A-compressed EXR is not supported "
                         "(convert it, e.g. to ZIP or PIZ)", path);
    exr_attr_box2i_t dw;
    rv = exr_get_data_window(in->ctx, 0, &dw);
    if (rv != EXR_ERR_SUCCESS)
        return btf__exr_fail(err, &in->io, rv, 0, "bad data window");
    int64_t w = (int64_t)dw.max.x - dw.min.x + 1, h = (int64_t)dw.max.y - dw.min.y + 1;
    if (w < 1 || h < 1 || w > BTF_EXR_MAX_SIDE || h > BTF_EXR_MAX_SIDE)
        return btf__fail(err, BTF_E_FORMAT, "%s: EXR data window %lld x %lld out of range 1..%d",
                         path, (long long)w, (long long)h, BTF_EXR_MAX_SIDE);
    in->x0 = dw.min.x;
    in->y0 = dw.min.y;
    in->width = (int)w;
    in->height = (int)h;
    btf_status rc = pick_channels(in, err);
    return rc ? rc : check_chunk_layout(in, err);
}

/* Called for each full-resolution chunk; (cx, cy) is its top-left pixel
 * relative to the data window. */
typedef btf_status (*chunk_fn)(exr_in *in, const exr_chunk_info_t *ci, int cx, int cy,
                    void *user, btf_error *err);

/* The chunk must lie inside the image (we copy it there) and inside the file
 * (else it was cut off). */
static btf_status check_chunk(const exr_in *in, const exr_chunk_info_t *ci, int cx, int cy,
                              btf_error *err)
{
    uint64_t size = (uint64_t)in->io.src->size;
    if (ci->width < 1 || ci->height < 1 || cx < 0 || cy < 0 ||
        (int64_t)cx + ci->width > in->width || (int64_t)cy + ci->height > in->height)
        return btf__fail(err, BTF_E_FORMAT, "%s: EXR chunk %d (%d x %d at %d, %d) lies outside the image",
                         in->io.path, (int)ci->idx, (int)ci->width, (int)ci->height, cx, cy);
    if (ci->data_offset > size || ci->packed_size > size - ci->data_offset)
        return btf__fail(err, BTF_E_FORMAT, "%s: truncated: EXR chunk %d ends past the end of the file",
                         in->io.path, (int)ci->idx);
    return BTF_OK;
}

static btf_status each_scanline_chunk(exr_in *in, chunk_fn fn, void *user, btf_error *err)
{
    int32_t lines = 0;
    exr_result_t rv = exr_get_scanlines_per_chunk(in->ctx, 0, &lines);
    if (rv != EXR_ERR_SUCCESS || lines < 1)
        return btf__exr_fail(err, &in->io, rv ? rv : EXR_ERR_INVALID_ATTR, 0, "bad scanlines per chunk");
    for (int64_t y = in->y0; y < (int64_t)in->y0 + in->height; y += lines) {
        exr_chunk_info_t ci;
        rv = exr_read_scanline_chunk_info(in->ctx, 0, (int)y, &ci);
        if (rv != EXR_ERR_SUCCESS)
            return btf__exr_fail(err, &in->io, rv, 0, "bad EXR chunk");
        int cy = (int)((int64_t)ci.start_y - in->y0);
        btf_status rc = check_chunk(in, &ci, 0, cy, err);
        if (!rc)
            rc = fn(in, &ci, 0, cy, user, err);
        if (rc)
            return rc;
    }
    return BTF_OK;
}

static btf_status each_tile(exr_in *in, chunk_fn fn, void *user, btf_error *err)
{
    int32_t tw = 0, th = 0;
    exr_result_t rv = exr_get_tile_sizes(in->ctx, 0, 0, 0, &tw, &th);
    if (rv != EXR_ERR_SUCCESS || tw < 1 || th < 1)
        return btf__exr_fail(err, &in->io, rv ? rv : EXR_ERR_INVALID_ATTR, 0, "bad tile size");
    int64_t ntx = ((int64_t)in->width + tw - 1) / tw, nty = ((int64_t)in->height + th - 1) / th;
    for (int64_t ty = 0; ty < nty; ty++) {
        for (int64_t tx = 0; tx < ntx; tx++) {
            exr_chunk_info_t ci;
            rv = exr_read_tile_chunk_info(in->ctx, 0, (int)tx, (int)ty, 0, 0, &ci);
            if (rv != EXR_ERR_SUCCESS)
                return btf__exr_fail(err, &in->io, rv, 0, "bad EXR tile");
            /* tx < ntx, so tx * tw < width <= 65536: no overflow. */
            int cx = (int)(tx * tw), cy = (int)(ty * th);
            btf_status rc = check_chunk(in, &ci, cx, cy, err);
            if (!rc)
                rc = fn(in, &ci, cx, cy, user, err);
            if (rc)
                return rc;
        }
    }
    return BTF_OK;
}

static btf_status for_each_chunk(exr_in *in, chunk_fn fn, void *user, btf_error *err)
{
    return in->storage == EXR_STORAGE_TILED ? each_tile(in, fn, user, err)
                                            : each_scanline_chunk(in, fn, user, err);
}

/* The chunk-table walk's visitor: check_chunk already did the work. */
static btf_status chunk_ok(exr_in *in, const exr_chunk_info_t *ci, int cx, int cy, void *user,
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
    float *unused;   /* one plane per channel we do not keep (see bind_outputs) */
    size_t unused_cap;
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
static btf_status bind_outputs(exr_in *in, decoder *d, const exr_chunk_info_t *ci, btf_error *err)
{
    /* Channels we do not keep are decoded too, each into a plane of its
     * own: OpenEXRCore 3.1's unpackers crash on some damaged files when a
     * channel is skipped (decode_to_ptr NULL; found by fuzz_exr). */
    size_t plane = (size_t)ci->width * (size_t)ci->height;
    size_t need = plane * (size_t)d->dec.channel_count;
    if (need > d->unused_cap) {
        free(d->unused);
        d->unused_cap = 0;
        if (!(d->unused = btf__alloc(need, sizeof(float), err)))
            return BTF_E_NOMEM;
        d->unused_cap = need;
    }
    int bound = 0;
    for (int c = 0; c < d->dec.channel_count; c++) {
        exr_coding_channel_info_t *ch = &d->dec.channels[c];
        int k = slot_of(in, ch->channel_name);
        if (k < 0) {
            if (ch->width > ci->width || ch->height > ci->height || ch->width < 0 ||
                ch->height < 0)
                return btf__fail(err, BTF_E_FORMAT, "%s: EXR channel %s is larger than its chunk",
                                 in->io.path, ch->channel_name);
            ch->decode_to_ptr = (uint8_t *)(d->unused + plane * (size_t)c);
            ch->user_pixel_stride = (int32_t)sizeof(float);
            ch->user_line_stride = (int32_t)((size_t)(ch->width > 0 ? ch->width : 1) *
                                             sizeof(float));
            ch->user_data_type = EXR_PIXEL_FLOAT;
            ch->user_bytes_per_element = (int16_t)sizeof(float);
            continue;
        }
        /* Our channels are not subsampled, so each must cover the chunk:
         * anything else would write past the scratch buffer. */
        if (ch->width != ci->width || ch->height != ci->height)
            return btf__fail(err, BTF_E_FORMAT, "%s: EXR channel %s does not cover its chunk",
                             in->io.path, in->names[k]);
        ch->decode_to_ptr = (uint8_t *)(d->buf + k);
        ch->user_pixel_stride = (int32_t)(in->nsrc * sizeof(float));
        ch->user_line_stride = (int32_t)((size_t)ci->width * in->nsrc * sizeof(float));
        ch->user_data_type = EXR_PIXEL_FLOAT;
        ch->user_bytes_per_element = (int16_t)sizeof(float);
        bound++;
    }
    if (bound != in->nsrc)
        return btf__fail(err, BTF_E_FORMAT, "%s: EXR chunk lacks some of its channels", in->io.path);
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
static btf_status store_chunk(const exr_in *in, const float *buf, const exr_chunk_info_t *ci,
                              int cx, int cy, btf_image *out, btf_error *err)
{
    int nsrc = in->nsrc, want = out->channels;
    for (int r = 0; r < ci->height; r++) {
        const float *p = buf + (size_t)r * ci->width * nsrc;
        float *o = out->data + ((size_t)(cy + r) * out->width + cx) * want;
        for (int x = 0; x < ci->width; x++, p += nsrc, o += want) {
            for (int k = 0; k < nsrc; k++)
                if (!isfinite(p[k]))
                    return btf__fail(err, BTF_E_DATA, "%s: NaN or Inf at pixel (%d, %d)",
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

static btf_status decode_chunk(exr_in *in, const exr_chunk_info_t *ci, int cx, int cy,
                               void *user, btf_error *err)
{
    decoder *d = user;
    size_t n = (size_t)ci->width * (size_t)ci->height * (size_t)in->nsrc;
    if (n > d->cap) {
        free(d->buf);
        d->cap = 0;
        d->buf = btf__alloc(n, sizeof(float), err);
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
        return btf__exr_fail(err, &in->io, rv, 0, "cannot decode EXR chunk");
    btf_status rc = bind_outputs(in, d, ci, err);
    if (rc)
        return rc;
    /* Chosen again per chunk: the unpacker depends on the chunk's shape. */
    rv = exr_decoding_choose_default_routines(in->ctx, 0, &d->dec);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_decoding_run(in->ctx, 0, &d->dec);
    if (rv != EXR_ERR_SUCCESS)
        return btf__exr_fail(err, &in->io, rv, 0, "corrupt EXR chunk");
    return store_chunk(in, d->buf, ci, cx, cy, d->out, err);
}

static btf_status read_pixels(exr_in *in, int channels, btf_image *out, btf_error *err)
{
    int want = channels ? channels : in->nsrc;
    btf_status rc = btf_image_alloc(out, in->width, in->height, want, err);
    if (rc) {
        if (err) {
            char m[sizeof err->msg];
            memcpy(m, err->msg, sizeof m);
            btf__fail(err, rc, "%s: %s", in->io.path, m);
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
    free(d.unused);
    return rc;
}

btf_status btf__exr_probe_source(btf_source *src, btf_image_header *hdr, btf_error *err)
{
    if (!src || !hdr)
        return btf__fail(err, BTF_E_ARG, "btf_exr_probe: NULL argument");
    memset(hdr, 0, sizeof *hdr);
    exr_in in;
    memset(&in, 0, sizeof in);
    btf_exr_io *prev = btf__exr_sink_enter(&in.io);
    btf_status rc = in_open(&in, src, err);
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
        hdr->file_bytes = src->size;
    }
    in_close(&in);
    btf__exr_sink_leave(prev);
    return rc;
}

btf_status btf__exr_read_source(btf_source *src, int channels, uint64_t max_pixels, btf_image *out,
                                btf_error *err)
{
    if (!src || !out)
        return btf__fail(err, BTF_E_ARG, "btf_exr_read: NULL argument");
    memset(out, 0, sizeof *out);
    if (channels != 0 && channels != 1 && channels != 3)
        return btf__fail(err, BTF_E_ARG, "%s: channels %d: expected 0, 1 or 3", src->name,
                         channels);
    exr_in in;
    memset(&in, 0, sizeof in);
    btf_exr_io *prev = btf__exr_sink_enter(&in.io);
    btf_status rc = in_open(&in, src, err);
    if (!rc)
        rc = in_inspect(&in, err);
    if (!rc)
        rc = btf__check_pixels(src->name, in.width, in.height, max_pixels, err);
    /* A cut-off or damaged chunk table fails here, before the image is
     * allocated (a header may claim 65536 x 65536 in a few kilobytes). */
    if (!rc)
        rc = for_each_chunk(&in, chunk_ok, NULL, err);
    if (!rc)
        rc = read_pixels(&in, channels, out, err);
    in_close(&in);
    btf__exr_sink_leave(prev);
    if (rc)
        btf_image_free(out);
    return rc;
}

btf_status btf__exr_probe(const char *path, btf_image_header *hdr, btf_error *err)
{
    if (!path || !hdr)
        return btf__fail(err, BTF_E_ARG, "btf_exr_probe: NULL argument");
    memset(hdr, 0, sizeof *hdr);
    btf_source src;
    btf_status rc = btf__source_open(&src, path, err);
    if (!rc)
        rc = btf__exr_probe_source(&src, hdr, err);
    btf__source_close(&src);
    return rc;
}

btf_status btf__exr_read(const char *path, int channels, btf_image *out, btf_error *err)
{
    if (!path || !out)
        return btf__fail(err, BTF_E_ARG, "btf_exr_read: NULL argument");
    memset(out, 0, sizeof *out);
    if (channels != 0 && channels != 1 && channels != 3)
        return btf__fail(err, BTF_E_ARG, "%s: channels %d: expected 0, 1 or 3", path, channels);
    btf_source src;
    btf_status rc = btf__source_open(&src, path, err);
    if (!rc)
        rc = btf__exr_read_source(&src, channels, 0, out, err);
    btf__source_close(&src);
    return rc;
}
