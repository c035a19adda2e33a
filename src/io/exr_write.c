/*
 * exr_write.c — writing OpenEXR through the OpenEXR core C API: a streaming
 * scanline writer, and the one-shot writer built on it.
 *
 * Channel "Y", or "B", "G", "R" (EXR stores channels sorted by name), HALF
 * or FLOAT, scanlines in increasing y, compressed as btf_exr_opts says: by
 * default ZIP, lossless deflate (zlib level 4, see writer_header) over
 * 16-scanline chunks, read by every EXR implementation, good on smooth data
 * and deterministic (the same pixels give the same bytes); btfcar
 * synthesise writes half without compression (docs/synthesis.md, "EXR
 * output"). With btf_exr_opts.background a thread of the writer packs,
 * compresses and writes the staged slabs (a bounded queue, see NSLAB) while
 * the caller makes the next rows: the same bytes in the same order. Non-finite input is refused (BTF_E_ARG)
 * because such a file could not be read back; half output is clamped to
 * +-65504 so it never holds Inf. A chunk that does not shrink is stored raw
 * (see compress_or_store: works around OpenEXRCore 3.1.5 writing unreadable
 * chunks).
 *
 * We do the file I/O ourselves (pwrite on our own descriptor), so a failing
 * system call is reported as such, and so the writer writes to the
 * temporary file from btf__tmp_create() (O_EXCL | O_NOFOLLOW), fsync'd, and
 * the file appears only through btf__commit_file().
 *
 * Provenance (btf_exr_meta): string attributes btfcarVersion, and with a
 * model btfcarModel, btfcarSeed, btfcarSubspace, and with directions
 * btfcarView, btfcarLight ("THETA PHI" in degrees), plus the standard
 * chromaticities attribute: the primaries and white point of linear sRGB
 * (Rec. 709, D65), which is what btfcar's linear RGB is. They change the
 * header only; the pixels are the same with or without them.
 */
/* sync_file_range (Linux): start writing back each buffer at once, so
 * that the fsync before the rename has little left to wait for. */
#define _GNU_SOURCE
#include <stdio.h>
#include "core/behind.h"
#include "core/core.h"
#include "io/exr.h"

#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <inttypes.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* x86-64: chunks packed with F16C where the CPU has it (fast_pack). */
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__)) && \
    __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
#include <cpuid.h>
#include <immintrin.h>
#define HAVE_FAST_PACK 1
static int have_f16c(void);
#endif

#define HALF_MAX_VALUE 65504.0f

/* pwrite in a loop on our descriptor. */
static int64_t write_at(btf_exr_io *io, const void *buffer, uint64_t sz, uint64_t offset)
{
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

/* Background writing: the caller fills slab `fill` (whole chunks) while the
 * write-behind thread (core/behind.h) compresses and writes the queued ones,
 * oldest first. NSLAB slabs of about SLAB_BYTES (at least one chunk) bound
 * the memory: the thread holds nslab - 1 of them at most, and the caller
 * fills the one left. */
#define NSLAB 6
#define SLAB_BYTES ((size_t)1 << 18)

typedef struct slab {
    float *data;
    int y0, nrows;
} slab; /* also the thread's job: these rows, from data */

/* Chunks are written through a buffer of this many bytes: one-scanline
 * chunks (NONE, RLE, ZIPS) would otherwise cost a system call per row. */
#define WRITE_BUFFER ((size_t)1 << 20)

struct btf_exr_writer {
    btf_exr_io io;              /* our descriptor on the temporary file; first,
                                   so that the write callback finds the writer */
    unsigned char *wbuf;        /* bytes for offsets wbuf_at.. not yet written */
    size_t wbuf_len;
    uint64_t wbuf_at;
    exr_context_t ctx;
    exr_encode_pipeline_t enc;
    int enc_started;
    char *path;                 /* the final name */
    char tmp[4096];             /* the temporary name beside it */
    int tmp_created;
    int width, height, channels, half;
    exr_compression_t comp;
    int lines;                  /* scanlines per chunk */
    int rows_done;              /* rows accepted, including staged ones */
    int rows_staged;            /* rows waiting in stage for their slab */
    int slab_rows;              /* rows per slab: whole chunks */
    float *stage;               /* the slab being filled (slabs[fill].data) */
    int failed;                 /* an error happened: only abort/close remain */
    exr_result_t (*compress)(exr_encode_pipeline_t *); /* the library's */
    exr_result_t (*pack)(exr_encode_pipeline_t *);
    exr_result_t (*write)(exr_encode_pipeline_t *);
    btf_exr_times t, *times;    /* this file's figures; where they go at close */
    uint64_t bytes;             /* the file's size, once finished */
    int fast_pack;              /* pack with F16C (fast_pack), not the library */
    /* background writing (background 1) */
    int background, nslab;
    slab slabs[NSLAB];
    int fill;                   /* the slab being filled */
    btf_behind *behind;         /* the thread, until close or abort */
    int thread_failed;          /* the thread's error, in thread_err */
    btf_error thread_err;
};

/* Writes out the buffered bytes. */
static int flush_buffer(btf_exr_writer *w)
{
    if (!w->wbuf_len)
        return 0;
    int64_t r = write_at(&w->io, w->wbuf, w->wbuf_len, w->wbuf_at);
#ifdef SYNC_FILE_RANGE_WRITE
    if (r >= 0) /* a hint: an error here is found again by fsync */
        (void)sync_file_range(w->io.fd, (off_t)w->wbuf_at, (off_t)w->wbuf_len,
                              SYNC_FILE_RANGE_WRITE);
#endif
    w->wbuf_len = 0;
    return r < 0 ? -1 : 0;
}

/* The library's write callback: bytes that follow the buffered ones join
 * them; anything else (the offset table, a full buffer) flushes first.
 * The file's bytes are the same either way. */
static int64_t io_write(exr_const_context_t ctxt, void *user, const void *buffer, uint64_t sz,
                        uint64_t offset, exr_stream_error_func_ptr_t error_cb)
{
    (void)ctxt;
    (void)error_cb;
    btf_exr_writer *w = user; /* user is &w->io, its first member */
    if (w->wbuf && w->wbuf_len && offset == w->wbuf_at + w->wbuf_len &&
        sz <= WRITE_BUFFER - w->wbuf_len) {
        memcpy(w->wbuf + w->wbuf_len, buffer, (size_t)sz);
        w->wbuf_len += (size_t)sz;
        return (int64_t)sz;
    }
    if (flush_buffer(w) != 0)
        return -1;
    if (!w->wbuf || sz >= WRITE_BUFFER / 2)
        return write_at(&w->io, buffer, sz, offset);
    memcpy(w->wbuf, buffer, (size_t)sz);
    w->wbuf_len = (size_t)sz;
    w->wbuf_at = offset;
    return (int64_t)sz;
}

static const struct {
    const char *name;
    exr_compression_t exr;
} COMPRESSIONS[] = {
    [BTF_EXR_ZIP] = {"zip", EXR_COMPRESSION_ZIP},       [BTF_EXR_NONE] = {"none", EXR_COMPRESSION_NONE},
    [BTF_EXR_RLE] = {"rle", EXR_COMPRESSION_RLE},       [BTF_EXR_ZIPS] = {"zips", EXR_COMPRESSION_ZIPS},
    [BTF_EXR_PIZ] = {"piz", EXR_COMPRESSION_PIZ},       [BTF_EXR_PXR24] = {"pxr24", EXR_COMPRESSION_PXR24},
};
#define N_COMPRESSIONS ((int)(sizeof COMPRESSIONS / sizeof COMPRESSIONS[0]))

const char *btf__exr_compression_name(int compression)
{
    return compression >= 0 && compression < N_COMPRESSIONS ? COMPRESSIONS[compression].name
                                                           : NULL;
}

btf_exr_opts btf_exr_defaults(void)
{
    return (btf_exr_opts){.struct_size = sizeof(btf_exr_opts)};
}

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

/* Header: one scanline part, the size, the compression, the channels in
 * sorted order, then the provenance when there is any. */
static exr_result_t writer_header(btf_exr_writer *w, const btf_exr_meta *meta)
{
    int part = 0;
    exr_result_t rv = exr_add_part(w->ctx, NULL, EXR_STORAGE_SCANLINE, &part);
    if (!rv)
        rv = exr_initialize_required_attr_simple(w->ctx, part, w->width, w->height,
                                                 w->comp);
    static const char *const rgb[] = {"B", "G", "R"}, *const grey[] = {"Y"};
    const char *const *names = w->channels == 3 ? rgb : grey;
    exr_pixel_type_t type = w->half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT;
    for (int c = 0; c < w->channels && !rv; c++)
        rv = exr_add_channel(w->ctx, part, names[c], type, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
    /* zlib level 4, not the library's default 6: on synthesised texture
     * (noise-like, it barely compresses) a 32768 x 512 half-float image
     * took 9.0 s at 6, 3.6 s at 4 and 3.0 s at 1, for 67.8, 68.8 and 70.2
     * MB: level 6 spent 90 % of synthesis in deflate for 1.5 % of size. */
    if (!rv && (w->comp == EXR_COMPRESSION_ZIP || w->comp == EXR_COMPRESSION_ZIPS))
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

static btf_status write_slab(void *user, void *job, btf_error *err);

/* The staging buffers: one chunk, or NSLAB slabs and the thread. */
static btf_status start_slabs(btf_exr_writer *w, btf_error *err)
{
    size_t row = (size_t)w->width * (size_t)w->channels;
    size_t chunk = (size_t)w->lines * row * sizeof(float);
    int per = w->background && chunk < SLAB_BYTES ? (int)(SLAB_BYTES / chunk) : 1;
    w->slab_rows = w->lines * per < w->height ? w->lines * per : w->height;
    /* chunks of 4 MiB or more (wide rows, 16- or 32-row chunks): 3 slabs */
    w->nslab = !w->background ? 1 : chunk >= ((size_t)4 << 20) ? 3 : NSLAB;
    for (int i = 0; i < w->nslab; i++)
        if (!(w->slabs[i].data = btf__alloc((size_t)w->slab_rows * row, sizeof(float), err)))
            return BTF_E_NOMEM;
    w->stage = w->slabs[0].data;
    if (!(w->wbuf = btf__alloc(WRITE_BUFFER, 1, err)))
        return BTF_E_NOMEM;
    if (!w->background)
        return BTF_OK;
    btf_behind_spec spec = {.run = write_slab, .user = w, .job_size = sizeof(slab),
                            .depth = w->nslab - 1};
    btf_error e = {0};
    if (!(w->behind = btf__behind_start(&spec, &e))) {
        btf__error_name(&e, w->path);
        if (err)
            *err = e;
        return e.code;
    }
    return BTF_OK;
}

/* Creates the temporary file, the context and the header; allocates the
 * staging buffers (and starts the thread). */
static btf_status writer_start(btf_exr_writer *w, const btf_exr_meta *meta, btf_error *err)
{
    int fd;
    btf_status rc = btf__tmp_create(w->path, w->tmp, sizeof w->tmp, &fd, err);
    if (rc)
        return rc;
    w->io.fd = fd;
    w->tmp_created = 1;
    exr_context_initializer_t init = btf__exr_initializer(&w->io);
    init.write_fn = io_write;
    exr_result_t rv = exr_start_write(&w->ctx, w->path, EXR_WRITE_FILE_DIRECTLY, &init);
    if (rv != EXR_ERR_SUCCESS) {
        w->ctx = NULL; /* exr_start_write frees it on failure */
        return btf__exr_fail(err, &w->io, rv, 1, "cannot start EXR file");
    }
    double t0 = btf__now();
    rv = writer_header(w, meta);
    w->t.write_s += btf__now() - t0;
    if (rv != EXR_ERR_SUCCESS)
        return btf__exr_fail(err, &w->io, rv, 1, "cannot write EXR header");
    return start_slabs(w, err);
}

btf_status btf_exr_writer_open_opts(const char *path, int width, int height, int channels,
                                    const btf_exr_opts *opts, const btf_exr_meta *meta,
                                    btf_exr_writer **out, btf_error *err)
{
    if (!out)
        return btf__fail(err, BTF_E_ARG, "btf_exr_writer_open: NULL output pointer");
    *out = NULL;
    btf_exr_opts d = btf_exr_defaults(), o;
    if (btf__opts_take(&o, sizeof o, opts, &d, "btf_exr_writer_open", err))
        return BTF_E_ARG;
    if (!path || !*path)
        return btf__fail(err, BTF_E_ARG, "btf_exr_writer_open: no path");
    if (width < 1 || height < 1 || width > BTF_EXR_MAX_SIDE || height > BTF_EXR_MAX_SIDE)
        return btf__fail(err, BTF_E_ARG, "%s: image size %dx%d out of range 1..%d", path, width,
                         height, BTF_EXR_MAX_SIDE);
    if (channels != 1 && channels != 3)
        return btf__fail(err, BTF_E_ARG, "%s: channels %d: expected 1 or 3", path, channels);
    if (o.compression < 0 || o.compression >= N_COMPRESSIONS)
        return btf__fail(err, BTF_E_ARG, "%s: unknown EXR compression %d", path, o.compression);
    btf_exr_writer *w = btf__calloc(1, sizeof *w, err);
    if (!w)
        return BTF_E_NOMEM;
    w->io.fd = -1;
    w->width = width;
    w->height = height;
    w->channels = channels;
    w->half = o.half != 0;
    w->comp = COMPRESSIONS[o.compression].exr;
    w->background = o.background != 0;
    w->times = o.times;
#ifdef HAVE_FAST_PACK
    w->fast_pack = !btf__exr_library_pack && have_f16c();
#endif
    w->path = strdup(path);
    if (!w->path) {
        free(w);
        return btf__fail(err, BTF_E_NOMEM, "%s: out of memory", path);
    }
    w->io.path = w->path;
    btf_status rc = BTF_OK;
    {
        btf_exr_io *prev = btf__exr_sink_enter(&w->io);
        rc = writer_start(w, meta, err);
        btf__exr_sink_leave(prev);
    }
    if (rc) {
        btf_exr_writer_abort(w);
        return rc;
    }
    *out = w;
    return BTF_OK;
}

/* The copy loops of stage_row, written to be vectorised (GCC does at -O3;
 * -O2 leaves them scalar, a third of the caller's output work). */
#if defined(__GNUC__) && !defined(__clang__)
#define VECTORISE __attribute__((optimize("O3")))
#else
#define VECTORISE
#endif

VECTORISE static int copy_clamped(float *dst, const float *src, size_t n)
{
    int bad = 0;
    for (size_t i = 0; i < n; i++) {
        float v = src[i];
        bad |= !(fabsf(v) <= FLT_MAX);
        v = v > HALF_MAX_VALUE ? HALF_MAX_VALUE : v;
        dst[i] = v < -HALF_MAX_VALUE ? -HALF_MAX_VALUE : v;
    }
    return bad;
}

VECTORISE static int copy_checked(float *dst, const float *src, size_t n)
{
    int bad = 0;
    for (size_t i = 0; i < n; i++) {
        bad |= !(fabsf(src[i]) <= FLT_MAX);
        dst[i] = src[i];
    }
    return bad;
}

/* Copies one row into the staging buffer: refuses non-finite values, clamps
 * to the half range when writing half (the library would make them Inf). */
static btf_status stage_row(btf_exr_writer *w, const float *src, btf_error *err)
{
    size_t n = (size_t)w->width * (size_t)w->channels;
    float *dst = w->stage + (size_t)w->rows_staged * n;
    int bad = w->half ? copy_clamped(dst, src, n) : copy_checked(dst, src, n);
    for (size_t i = 0; bad && i < n; i++)
        if (!isfinite(src[i]))
            return btf__fail(err, BTF_E_ARG, "%s: %s at pixel (%d, %d): EXR output must be finite",
                             w->path, isnan(src[i]) ? "NaN" : "Inf",
                             (int)(i / (size_t)w->channels), w->rows_done);
    w->rows_staged++;
    w->rows_done++;
    return BTF_OK;
}

/* Points the encoder's channels at one chunk of interleaved rows. */
static btf_status bind_inputs(btf_exr_writer *w, const float *rows, btf_error *err)
{
    for (int c = 0; c < w->enc.channel_count; c++) {
        exr_coding_channel_info_t *ch = &w->enc.channels[c];
        int k = channel_slot(ch->channel_name);
        if (k < 0 || k >= w->channels)
            return btf__fail(err, BTF_E_IO, "%s: unexpected EXR channel %s", w->path,
                             ch->channel_name ? ch->channel_name : "?");
        ch->encode_from_ptr = (const uint8_t *)(rows + k);
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
    double t0 = btf__now();
    exr_result_t rv = w->compress(enc);
    if (rv == EXR_ERR_SUCCESS && enc->compressed_bytes >= enc->packed_bytes) {
        if (enc->compressed_buffer != enc->packed_buffer) {
            /* The compressed buffer is allocated for the worst case, which is
             * never smaller than the packed data; checked all the same. */
            if (!enc->compressed_buffer || enc->compressed_alloc_size < enc->packed_bytes)
                rv = EXR_ERR_OUT_OF_MEMORY;
            else
                memcpy(enc->compressed_buffer, enc->packed_buffer, enc->packed_bytes);
        }
        enc->compressed_bytes = enc->packed_bytes;
    }
    w->t.compress_s += btf__now() - t0;
    return rv;
}

int btf__exr_library_pack = 0;

#ifdef HAVE_FAST_PACK

/* n floats to half with F16C, round to nearest even: what Imath's
 * imath_float_to_half (the library's conversion) computes, which itself
 * uses this instruction where the compiler may. */
__attribute__((target("f16c,avx"))) static void halves_f16c(uint16_t *dst, const float *src,
                                                            size_t n)
{
    size_t i = 0;
    for (; i + 8 <= n; i += 8)
        _mm_storeu_si128((__m128i *)(dst + i),
                         _mm256_cvtps_ph(_mm256_loadu_ps(src + i), _MM_FROUND_TO_NEAREST_INT));
    for (; i < n; i++)
        dst[i] = (uint16_t)_mm_extract_epi16(
            _mm_cvtps_ph(_mm_set_ss(src[i]), _MM_FROUND_TO_NEAREST_INT), 0);
}

/* Whether the CPU (and the OS, for the AVX registers) has F16C and AVX:
 * CPUID leaf 1, ECX bits 29 (F16C), 28 (AVX), 27 (OSXSAVE), and XCR0's
 * SSE and AVX state bits. (Not __builtin_cpu_supports: clang's knows no
 * "f16c".) */
static int have_f16c(void)
{
    unsigned a, b, c, d;
    if (!__get_cpuid(1, &a, &b, &c, &d) || (c & 0x38000000u) != 0x38000000u)
        return 0;
    unsigned lo, hi;
    __asm__("xgetbv" : "=a"(lo), "=d"(hi) : "c"(0));
    return (lo & 6u) == 6u;
}

/* The chunk's rows from the interleaved stage into the file's layout (per
 * scanline, each channel's samples in the file's channel order, little
 * endian), as the library's packer does, converting a row at a time. */
static exr_result_t fast_pack(exr_encode_pipeline_t *enc)
{
    btf_exr_writer *w = enc->encoding_user_data;
    int width = enc->chunk.width, lines = enc->chunk.height, nc = enc->channel_count;
    size_t row = (size_t)width * (size_t)w->channels, esize = w->half ? 2 : 4;
    uint64_t bytes = (uint64_t)lines * (uint64_t)width * (uint64_t)nc * esize;
    if (bytes > enc->packed_alloc_size || !enc->packed_buffer || nc != w->channels)
        return EXR_ERR_OUT_OF_MEMORY;
    uint16_t tmp[1024 * 3];
    unsigned char *out = enc->packed_buffer;
    const float *src = (const float *)enc->channels[0].encode_from_ptr;
    int slot[3];
    for (int c = 0; c < nc; c++) {
        slot[c] = channel_slot(enc->channels[c].channel_name);
        src = slot[c] == 0 ? (const float *)enc->channels[c].encode_from_ptr : src;
    }
    for (int y = 0; y < lines; y++, src += row, out += row * esize) {
        if (!w->half) {
            for (int c = 0; c < nc; c++) {
                float *o = (float *)(void *)out + (size_t)c * width;
                for (int x = 0; x < width; x++)
                    o[x] = src[(size_t)x * nc + slot[c]];
            }
            continue;
        }
        /* half: 1024 pixels at a time through tmp, then to each plane */
        for (int x0 = 0; x0 < width; x0 += 1024) {
            int n = width - x0 < 1024 ? width - x0 : 1024;
            halves_f16c(tmp, src + (size_t)x0 * nc, (size_t)n * nc);
            for (int c = 0; c < nc; c++) {
                uint16_t *o = (uint16_t *)(void *)out + (size_t)c * width + x0;
                for (int x = 0; x < n; x++)
                    o[x] = tmp[x * nc + slot[c]];
            }
        }
    }
    enc->packed_bytes = bytes;
    return EXR_ERR_SUCCESS;
}
#endif

/* The library's packing (float to the file's type, channels planar), or
 * ours where the CPU has F16C (the same bytes, a few times faster); timed,
 * as is the chunk writing. */
static exr_result_t timed_pack(exr_encode_pipeline_t *enc)
{
    btf_exr_writer *w = enc->encoding_user_data;
    double t0 = btf__now();
    exr_result_t rv;
#ifdef HAVE_FAST_PACK
    if (w->fast_pack)
        rv = fast_pack(enc);
    else
#endif
        rv = w->pack(enc);
    w->t.convert_s += btf__now() - t0;
    return rv;
}

static exr_result_t timed_write(exr_encode_pipeline_t *enc)
{
    btf_exr_writer *w = enc->encoding_user_data;
    double t0 = btf__now();
    exr_result_t rv = w->write(enc);
    w->t.write_s += btf__now() - t0;
    return rv;
}

/* Compresses and writes nrows rows at data, starting at row y0 (a chunk
 * boundary), chunk by chunk. The caller's thread or the writer's. */
static btf_status write_rows(btf_exr_writer *w, const float *data, int y0, int nrows,
                             btf_error *err)
{
    size_t row = (size_t)w->width * (size_t)w->channels;
    for (int r = 0; r < nrows; r += w->lines) {
        exr_chunk_info_t ci;
        exr_result_t rv = exr_write_scanline_chunk_info(w->ctx, 0, y0 + r, &ci);
        if (!rv) {
            rv = w->enc_started ? exr_encoding_update(w->ctx, 0, &ci, &w->enc)
                                : exr_encoding_initialize(w->ctx, 0, &ci, &w->enc);
            w->enc_started = 1;
        }
        if (rv)
            return btf__exr_fail(err, &w->io, rv, 1, "cannot encode rows");
        btf_status rc = bind_inputs(w, data + (size_t)r * row, err);
        if (rc)
            return rc;
        rv = exr_encoding_choose_default_routines(w->ctx, 0, &w->enc);
        if (!rv) {
            w->enc.encoding_user_data = w;
            if (w->enc.compress_fn) {
                w->compress = w->enc.compress_fn;
                w->enc.compress_fn = compress_or_store;
            }
            if (w->enc.convert_and_pack_fn) {
                w->pack = w->enc.convert_and_pack_fn;
                w->enc.convert_and_pack_fn = timed_pack;
            }
            if (w->enc.write_fn) {
                w->write = w->enc.write_fn;
                w->enc.write_fn = timed_write;
            }
        }
        if (!rv)
            rv = exr_encoding_run(w->ctx, 0, &w->enc);
        if (rv)
            return btf__exr_fail(err, &w->io, rv, 1, "cannot write rows");
    }
    return BTF_OK;
}

/* The thread's job: one slab's rows. The sink is the thread's while it
 * writes (the caller calls no library function meanwhile). */
static btf_status write_slab(void *user, void *job, btf_error *err)
{
    btf_exr_writer *w = user;
    const slab *s = job;
    btf_exr_io *prev = btf__exr_sink_enter(&w->io);
    btf_status rc = write_rows(w, s->data, s->y0, s->nrows, err);
    btf__exr_sink_leave(prev);
    return rc;
}

/* The staged rows (whole chunks, or the image's last rows) go out: written
 * here, or queued for the thread, which holds nslab - 1 slabs at most, so
 * the next slab is free to fill when the put returns. */
static btf_status flush_slab(btf_exr_writer *w, btf_error *err)
{
    int y0 = w->rows_done - w->rows_staged, n = w->rows_staged;
    w->rows_staged = 0;
    if (!w->behind)
        return write_rows(w, w->stage, y0, n, err);
    double t0 = btf__now();
    slab job = {w->stage, y0, n};
    btf_status rc = btf__behind_put(w->behind, &job, err);
    if (!rc)
        w->fill = (w->fill + 1) % w->nslab;
    w->stage = w->slabs[w->fill].data;
    w->t.wait_s += btf__now() - t0;
    return rc;
}

/* Stops the thread after the queued slabs, keeping its error
 * (WRITE_QUEUED), or at once, dropping them (DROP_QUEUED: an abort), and
 * waits for it. */
enum { WRITE_QUEUED, DROP_QUEUED };

static void stop_thread(btf_exr_writer *w, int how)
{
    if (!w->behind)
        return;
    if (how == DROP_QUEUED)
        btf__behind_abort(w->behind);
    else if (btf__behind_finish(w->behind, &w->thread_err) != BTF_OK)
        w->thread_failed = 1;
    w->behind = NULL;
}

btf_status btf_exr_writer_put_rows(btf_exr_writer *w, const float *rows, int nrows, btf_error *err)
{
    if (!w)
        return btf__fail(err, BTF_E_ARG, "btf_exr_writer_put_rows: NULL writer");
    if (w->failed)
        return btf__fail(err, BTF_E_ARG, "%s: the EXR writer failed earlier", w->path);
    btf_status rc = BTF_OK;
    if (nrows < 0 || (nrows > 0 && !rows))
        rc = btf__fail(err, BTF_E_ARG, "%s: bad rows (%d)", w->path, nrows);
    else if (nrows > w->height - w->rows_done)
        rc = btf__fail(err, BTF_E_ARG, "%s: %d rows given, but only %d of %d remain", w->path,
                       nrows, w->height - w->rows_done, w->height);
    size_t rowlen = (size_t)w->width * (size_t)w->channels;
    /* With the thread, this thread calls no library function: the sink
     * (and w->io) belong to the thread. */
    btf_exr_io *prev = w->behind ? NULL : btf__exr_sink_enter(&w->io);
    for (int i = 0; i < nrows && !rc; i++) {
        double t0 = btf__now();
        rc = stage_row(w, rows + (size_t)i * rowlen, err);
        w->t.stage_s += btf__now() - t0;
        if (!rc && (w->rows_staged == w->slab_rows || w->rows_done == w->height))
            rc = flush_slab(w, err);
    }
    if (!w->behind)
        btf__exr_sink_leave(prev);
    /* Any error is final: a file with a hole in it must never be committed. */
    if (rc)
        w->failed = 1;
    return rc;
}

/* Writes the offset table, closes the descriptor and renames into place. */
static btf_status writer_finish(btf_exr_writer *w, btf_error *err)
{
    stop_thread(w, WRITE_QUEUED);
    if (w->thread_failed) {
        if (err)
            *err = w->thread_err;
        return w->thread_err.code ? (btf_status)w->thread_err.code : BTF_E_IO;
    }
    double t0 = btf__now();
    if (w->enc_started)
        exr_encoding_destroy(w->ctx, &w->enc);
    w->enc_started = 0;
    exr_result_t rv = exr_finish(&w->ctx);
    if (flush_buffer(w) != 0 && rv == EXR_ERR_SUCCESS)
        rv = EXR_ERR_WRITE_IO;
    if (rv != EXR_ERR_SUCCESS || w->io.sys_errno)
        return btf__exr_fail(err, &w->io, rv ? rv : EXR_ERR_WRITE_IO, 1, "cannot finish EXR file");
    off_t end = lseek(w->io.fd, 0, SEEK_END);
    w->bytes = end > 0 ? (uint64_t)end : 0;
    int fd = w->io.fd;
    w->io.fd = -1;
    int e = fsync(fd) != 0 ? errno : 0;
    if (close(fd) != 0 && !e)
        e = errno;
    if (e)
        return btf__fail(err, BTF_E_IO, "%s: write failed: %s", w->path, strerror(e));
    btf_status rc = btf__commit_file(w->tmp, w->path, err);
    w->tmp_created = 0; /* renamed, or removed by btf__commit_file */
    w->t.write_s += btf__now() - t0;
    return rc;
}

btf_status btf_exr_writer_close(btf_exr_writer *w, btf_error *err)
{
    if (!w)
        return btf__fail(err, BTF_E_ARG, "btf_exr_writer_close: NULL writer");
    btf_status rc = BTF_OK;
    if (w->failed)
        rc = btf__fail(err, BTF_E_ARG, "%s: the EXR writer failed earlier; nothing written",
                       w->path);
    else if (w->rows_done != w->height)
        rc = btf__fail(err, BTF_E_ARG, "%s: EXR writer closed after %d of %d rows; nothing written",
                       w->path, w->rows_done, w->height);
    if (!rc) {
        stop_thread(w, WRITE_QUEUED); /* the queued rows first: then the sink is ours */
        btf_exr_io *prev = btf__exr_sink_enter(&w->io);
        rc = writer_finish(w, err);
        btf__exr_sink_leave(prev);
    }
    if (!rc && w->times) {
        w->t.files = 1;
        w->t.bytes = w->bytes;
        btf_exr_times *t = w->times;
        t->stage_s += w->t.stage_s, t->convert_s += w->t.convert_s;
        t->compress_s += w->t.compress_s, t->write_s += w->t.write_s, t->wait_s += w->t.wait_s;
        t->bytes += w->t.bytes, t->files += w->t.files;
    }
    btf_exr_writer_abort(w); /* frees; removes the temporary file if it is left */
    return rc;
}

void btf_exr_writer_abort(btf_exr_writer *w)
{
    if (!w)
        return;
    stop_thread(w, DROP_QUEUED);
    /* Messages from tearing down a half-written file are of no interest. */
    btf_exr_io *prev = btf__exr_sink_enter(&w->io);
    if (w->ctx) {
        if (w->enc_started)
            exr_encoding_destroy(w->ctx, &w->enc);
        exr_finish(&w->ctx);
    }
    btf__exr_sink_leave(prev);
    if (w->io.fd >= 0)
        close(w->io.fd);
    if (w->tmp_created)
        btf__abort_file(w->tmp);
    for (int i = 0; i < NSLAB; i++)
        free(w->slabs[i].data);
    free(w->wbuf);
    free(w->path);
    free(w);
}

btf_status btf_image_write_exr_opts(const char *path, const btf_image *img,
                                    const btf_exr_opts *opts, const btf_exr_meta *meta,
                                    btf_error *err)
{
    if (!img || !img->data)
        return btf__fail(err, BTF_E_ARG, "%s: no image to write", path ? path : "(null)");
    btf_exr_writer *w = NULL;
    btf_status rc = btf_exr_writer_open_opts(path, img->width, img->height, img->channels, opts,
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
