/*
 * image_file.c — image files: format detection by signature, a cheap
 * structural probe of PNG and JPEG (catches truncation without decoding),
 * decoding into linear float through libpng/libjpeg (io/png_jpeg.c) or
 * OpenEXR (io/exr_read.c), the decoding cap (btf_read_opts.max_pixels),
 * checked from the header, and the PNG and JPEG writers (OpenCV,
 * io/cv_bridge.cpp).
 *
 * Every reader works on a byte source (io/source.c), so decoding from
 * memory and from a file is one code path: btf_image_decode wraps a buffer,
 * btf_image_read opens the file, and both call decode_source.
 */
#include <stdio.h>
#include "core/core.h"
#include "io/io.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

btf_read_opts btf_read_defaults(void)
{
    return (btf_read_opts){.struct_size = sizeof(btf_read_opts),
                           .channels = 0, .linear_8bit = 0, .srgb_16bit = 0,
                           .max_pixels = BTF_DEFAULT_MAX_PIXELS};
}

static btf_file_format format_of_signature(const unsigned char *sig, size_t n)
{
    if (n >= 4 && sig[0] == 0x89 && sig[1] == 'P' && sig[2] == 'N' && sig[3] == 'G')
        return BTF_FILE_PNG;
    if (n >= 3 && sig[0] == 0xFF && sig[1] == 0xD8 && sig[2] == 0xFF)
        return BTF_FILE_JPEG;
    if (n >= 4 && sig[0] == 0x76 && sig[1] == 0x2F && sig[2] == 0x31 && sig[3] == 0x01)
        return BTF_FILE_EXR;
    return BTF_FILE_UNKNOWN;
}

static btf_file_format format_of_source(btf_source *src)
{
    unsigned char sig[4] = {0};
    int64_t n = btf__source_read(src, sig, 4, 0);
    return format_of_signature(sig, n > 0 ? (size_t)n : 0);
}

btf_file_format btf__file_format_of(const char *path)
{
    unsigned char sig[4] = {0};
    int fd = btf__open_regular(path, NULL, NULL); /* a FIFO would block */
    if (fd < 0)
        return BTF_FILE_UNKNOWN;
    ssize_t n = read(fd, sig, 4);
    close(fd);
    return format_of_signature(sig, n > 0 ? (size_t)n : 0);
}

static uint32_t be32(const unsigned char *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

/* Exactly n bytes at offset, or 0 (a short read or a failed one: either
 * way the structure the probe wants is not there). */
static int read_exact(btf_source *src, void *buf, uint64_t n, uint64_t offset)
{
    return btf__source_read(src, buf, n, offset) == (int64_t)n;
}

/* PNG: signature, IHDR first, IEND chunk as the last 12 bytes. */
static btf_status probe_png(btf_source *src, btf_image_header *hdr, btf_error *err)
{
    static const unsigned char iend[12] = {0, 0, 0, 0, 'I', 'E', 'N', 'D', 0xAE, 0x42, 0x60, 0x82};
    const char *name = src->name;
    uint64_t size = src->size;
    unsigned char b[33], tail[12];
    if (size < 8 + 25 + 12 || !read_exact(src, b, 33, 0))
        return btf__fail(err, BTF_E_FORMAT, "%s: truncated PNG (%llu bytes)", name,
                         (unsigned long long)size);
    if (be32(b + 8) != 13 || memcmp(b + 12, "IHDR", 4) != 0)
        return btf__fail(err, BTF_E_FORMAT, "%s: PNG without IHDR header", name);
    uint32_t w = be32(b + 16), h = be32(b + 20);
    int depth = b[24], ctype = b[25];
    if (w < 1 || h < 1 || w > BTF_MAX_SIDE || h > BTF_MAX_SIDE)
        return btf__fail(err, BTF_E_FORMAT, "%s: PNG size %ux%u out of range", name, w, h);
    if (!read_exact(src, tail, 12, size - 12) || memcmp(tail, iend, 12) != 0)
        return btf__fail(err, BTF_E_FORMAT, "%s: truncated PNG (no IEND chunk at the end)", name);
    hdr->width = (int)w;
    hdr->height = (int)h;
    hdr->bits = depth == 16 ? 16 : 8;
    hdr->channels = (ctype == 0 || ctype == 4) ? 1 : 3;
    return BTF_OK;
}

static int is_jpeg_sof(int m)
{
    return (m >= 0xC0 && m <= 0xCF) && m != 0xC4 && m != 0xC8 && m != 0xCC;
}

/* JPEG: walk the marker segments to the frame header (SOF), then require the
 * end-of-image marker near the end (a truncated download lacks it, and
 * libjpeg would silently fill the missing part with grey). */
static btf_status probe_jpeg(btf_source *src, btf_image_header *hdr, btf_error *err)
{
    const char *name = src->name;
    uint64_t size = src->size;
    unsigned char b[10];
    uint64_t pos = 2;
    int found = 0;
    while (pos + 4 <= size && !found) {
        if (!read_exact(src, b, 4, pos))
            break;
        if (b[0] != 0xFF)
            return btf__fail(err, BTF_E_FORMAT, "%s: corrupt JPEG (bad marker at byte %llu)", name,
                             (unsigned long long)pos);
        if (b[1] == 0xFF) { /* fill byte */
            pos++;
            continue;
        }
        unsigned len = (unsigned)b[2] << 8 | b[3];
        if (is_jpeg_sof(b[1])) {
            /* precision, height, width, component count */
            if (!read_exact(src, b + 4, 6, pos + 4))
                break;
            hdr->height = b[5] << 8 | b[6];
            hdr->width = b[7] << 8 | b[8];
            hdr->channels = b[9] == 1 ? 1 : 3;
            hdr->bits = 8;
            found = 1;
        } else if (b[1] == 0xD9 || b[1] == 0xDA) {
            break; /* image data or end before any frame header */
        }
        pos += 2 + len;
    }
    if (!found)
        return btf__fail(err, BTF_E_FORMAT, "%s: truncated or corrupt JPEG (no frame header)", name);
    if (hdr->width < 1 || hdr->height < 1)
        return btf__fail(err, BTF_E_FORMAT, "%s: JPEG size %dx%d unsupported", name, hdr->width,
                         hdr->height);
    /* Encoders may pad after EOI; look for it in the last 64 bytes. */
    unsigned char tail[64];
    uint64_t start = size > 64 ? size - 64 : 0;
    int64_t got = btf__source_read(src, tail, sizeof tail, start);
    if (got < 2)
        return btf__fail(err, BTF_E_FORMAT, "%s: truncated JPEG", name);
    size_t n = (size_t)got;
    while (n > 2 && (tail[n - 1] == 0 || tail[n - 1] == '\n' || tail[n - 1] == '\r'))
        n--;
    if (tail[n - 2] == 0xFF && tail[n - 1] == 0xD9)
        return BTF_OK;
    return btf__fail(err, BTF_E_FORMAT, "%s: truncated JPEG (no end-of-image marker)", name);
}

static btf_status probe_source(btf_source *src, btf_image_header *hdr, btf_error *err)
{
    memset(hdr, 0, sizeof *hdr);
    if (src->size == 0)
        return btf__fail(err, BTF_E_FORMAT, "%s: empty file", src->name);
    btf_status rc;
    switch (format_of_source(src)) {
    case BTF_FILE_PNG:
        hdr->format = BTF_FILE_PNG;
        rc = probe_png(src, hdr, err);
        break;
    case BTF_FILE_JPEG:
        hdr->format = BTF_FILE_JPEG;
        rc = probe_jpeg(src, hdr, err);
        break;
    case BTF_FILE_EXR:
        return btf__exr_probe_source(src, hdr, err);
    default:
        rc = btf__fail(err, BTF_E_FORMAT, "%s: not a PNG, JPEG or EXR file", src->name);
    }
    hdr->file_bytes = src->size;
    return rc;
}

btf_status btf_image_probe_memory(const void *data, size_t n, const char *name,
                                  btf_image_header *hdr, btf_error *err)
{
    btf_source src;
    btf__source_memory(&src, data, n, name);
    return probe_source(&src, hdr, err);
}

btf_status btf_image_probe(const char *path, btf_image_header *hdr, btf_error *err)
{
    memset(hdr, 0, sizeof *hdr);
    btf_source src;
    btf_status rc = btf__source_open(&src, path, err);
    if (!rc)
        rc = probe_source(&src, hdr, err);
    btf__source_close(&src);
    return rc;
}

/* 8-bit to linear float through a 256-entry table built per call (no global
 * state; 256 powf calls are nothing next to a decode). */
static void convert_8bit(const unsigned char *src, size_t count, int linear, float *dst)
{
    float lut[256];
    for (int i = 0; i < 256; i++)
        lut[i] = linear ? (float)i / 255.0f : btf__srgb_to_linear((float)i / 255.0f);
    for (size_t i = 0; i < count; i++)
        dst[i] = lut[src[i]];
}

static void convert_16bit(const uint16_t *src, size_t count, int srgb, float *dst)
{
    for (size_t i = 0; i < count; i++) {
        float v = (float)src[i] / 65535.0f;
        dst[i] = srgb ? btf__srgb_to_linear(v) : v;
    }
}

/* Changes the channel count of a decoded image in place (grey <-> RGB);
 * grey from RGB is the Rec. 709 luminance of the linear values. */
static btf_status convert_channels(btf_image *img, int want, btf_error *err)
{
    if (want == 0 || want == img->channels)
        return BTF_OK;
    btf_image out;
    btf_status rc = btf_image_alloc(&out, img->width, img->height, want, err);
    if (rc)
        return rc;
    size_t n = (size_t)img->width * img->height;
    for (size_t i = 0; i < n; i++) {
        if (want == 1) {
            const float *p = img->data + 3 * i;
            out.data[i] = 0.2126f * p[0] + 0.7152f * p[1] + 0.0722f * p[2];
        } else {
            out.data[3 * i] = out.data[3 * i + 1] = out.data[3 * i + 2] = img->data[i];
        }
    }
    btf_image_free(img);
    *img = out;
    return BTF_OK;
}

/* PNG or JPEG: the probe's checks and the pixel cap from the header, then
 * libpng or libjpeg on the bytes (io/png_jpeg.c, silent). */
static btf_status decode_png_jpeg(btf_source *src, const btf_read_opts *o, btf_image *out,
                                  btf_error *err)
{
    btf_image_header hdr;
    btf_status rc = probe_source(src, &hdr, err);
    if (!rc)
        rc = btf__check_pixels(src->name, hdr.width, hdr.height, o->max_pixels, err);
    if (rc)
        return rc;
    /* The output first: a file too large for memory fails before decoding. */
    if ((rc = btf_image_alloc(out, hdr.width, hdr.height, hdr.channels, err)))
        return btf__error_name(err, src->name);
    const unsigned char *bytes;
    unsigned char *owned;
    if ((rc = btf__source_bytes(src, &bytes, &owned, err)))
        return btf__error_name(err, src->name);
    btf_decoded d;
    rc = btf__png_jpeg_decode(bytes, (size_t)src->size, hdr.format, src->name, &d, err);
    free(owned);
    if (rc)
        return rc;
    if (d.width != hdr.width || d.height != hdr.height || d.channels != hdr.channels)
        rc = btf__fail(err, BTF_E_FORMAT, "%s: decoded %dx%d, %d channels, differs from the "
                       "header's %dx%d, %d channels", src->name, d.width, d.height, d.channels,
                       hdr.width, hdr.height, hdr.channels);
    size_t count = (size_t)d.width * d.height * d.channels;
    if (rc == 0 && d.depth16)
        convert_16bit(d.pixels, count, o->srgb_16bit, out->data);
    else if (rc == 0)
        convert_8bit(d.pixels, count, o->linear_8bit, out->data);
    free(d.pixels);
    return rc;
}

/* The one decoder behind btf_image_decode and btf_image_read. */
static btf_status decode_source(btf_source *src, const btf_read_opts *o, btf_image *out,
                                btf_error *err)
{
    btf_status rc;
    switch (format_of_source(src)) {
    case BTF_FILE_EXR:
        /* The EXR reader converts the channel count while it copies. */
        return btf__exr_read_source(src, o->channels, o->max_pixels, out, err);
    case BTF_FILE_PNG:
    case BTF_FILE_JPEG:
        rc = decode_png_jpeg(src, o, out, err);
        break;
    default:
        return btf__fail(err, BTF_E_FORMAT, "%s: not a PNG, JPEG or EXR file", src->name);
    }
    if (rc == 0 && (rc = convert_channels(out, o->channels, err)))
        btf__error_name(err, src->name);
    if (rc)
        btf_image_free(out);
    return rc;
}

static btf_status check_read_opts(const btf_read_opts *o, const char *name, btf_error *err)
{
    if (o->channels != 0 && o->channels != 1 && o->channels != 3)
        return btf__fail(err, BTF_E_ARG, "%s: channels %d requested: expected 0, 1 or 3", name,
                         o->channels);
    return BTF_OK;
}

btf_status btf_image_decode(const void *data, size_t n, const char *name,
                            const btf_read_opts *opts, btf_image *out, btf_error *err)
{
    memset(out, 0, sizeof *out);
    btf_read_opts d = btf_read_defaults(), o;
    if (btf__opts_take(&o, sizeof o, opts, &d, "btf_image_decode", err))
        return BTF_E_ARG;
    btf_source src;
    btf__source_memory(&src, data, n, name);
    btf_status rc = check_read_opts(&o, src.name, err);
    return rc ? rc : decode_source(&src, &o, out, err);
}

btf_status btf_image_read(const char *path, const btf_read_opts *opts, btf_image *out,
                          btf_error *err)
{
    memset(out, 0, sizeof *out);
    btf_read_opts d = btf_read_defaults(), o;
    if (btf__opts_take(&o, sizeof o, opts, &d, "btf_image_read", err))
        return BTF_E_ARG;
    btf_status rc = check_read_opts(&o, path, err);
    if (rc)
        return rc;
    btf_source src;
    rc = btf__source_open(&src, path, err);
    if (!rc)
        rc = decode_source(&src, &o, out, err);
    btf__source_close(&src);
    return rc;
}

/* Linear float -> 8-bit sRGB, clamped; non-finite values become 0. */
static unsigned char *to_srgb8(const btf_image *img, btf_error *err)
{
    size_t n = (size_t)img->width * img->height * img->channels;
    unsigned char *b = btf__alloc(n, 1, err);
    if (!b)
        return NULL;
    for (size_t i = 0; i < n; i++) {
        float v = btf__linear_to_srgb(img->data[i]);
        b[i] = (unsigned char)lrintf(v * 255.0f);
    }
    return b;
}

static btf_status write_encoded(const char *path, btf_file_format format, const btf_image *img,
                                int quality, btf_error *err)
{
    if (!img || !img->data || (img->channels != 1 && img->channels != 3))
        return btf__fail(err, BTF_E_ARG, "%s: no image to write", path);
    unsigned char *px = to_srgb8(img, err);
    if (!px)
        return BTF_E_NOMEM;
    unsigned char *enc;
    size_t len;
    char msg[256];
    int bad = btf__png_jpeg_encode(format, img->width, img->height, img->channels, px, quality,
                                   &enc, &len, msg, sizeof msg);
    free(px);
    if (bad)
        return btf__fail(err, BTF_E_IO, "%s: cannot encode: %s", path, msg);
    btf_status rc = btf_write_file_atomic(path, enc, len, err);
    free(enc);
    return rc;
}

btf_status btf_image_write_png(const char *path, const btf_image *img, btf_error *err)
{
    return write_encoded(path, BTF_FILE_PNG, img, 0, err);
}

btf_status btf_image_write_jpeg(const char *path, const btf_image *img, int quality,
                                btf_error *err)
{
    if (quality < 1 || quality > 100)
        return btf__fail(err, BTF_E_ARG, "%s: JPEG quality %d: expected 1..100", path, quality);
    return write_encoded(path, BTF_FILE_JPEG, img, quality, err);
}
