/*
 * image_file.c — image files: format detection by signature, a cheap
 * structural probe of PNG/JPEG files (catches truncation without decoding),
 * and read/write dispatch to OpenCV (PNG, JPEG; io/cv_bridge.cpp) and
 * OpenEXR (io/exr.c).
 */
#include <stdio.h>
#include "core/core.h"
#include "io/io.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

btf_file_format btf_file_format_of(const char *path)
{
    unsigned char sig[4] = {0};
    FILE *f = fopen(path, "rb");
    if (!f)
        return BTF_FILE_UNKNOWN;
    size_t n = fread(sig, 1, 4, f);
    fclose(f);
    if (n == 4 && sig[0] == 0x89 && sig[1] == 'P' && sig[2] == 'N' && sig[3] == 'G')
        return BTF_FILE_PNG;
    if (n >= 3 && sig[0] == 0xFF && sig[1] == 0xD8 && sig[2] == 0xFF)
        return BTF_FILE_JPEG;
    if (n == 4 && sig[0] == 0x76 && sig[1] == 0x2F && sig[2] == 0x31 && sig[3] == 0x01)
        return BTF_FILE_EXR;
    return BTF_FILE_UNKNOWN;
}

static uint32_t be32(const unsigned char *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

static long file_size(FILE *f)
{
    if (fseek(f, 0, SEEK_END) != 0)
        return -1;
    long n = ftell(f);
    rewind(f);
    return n;
}

/* PNG: signature, IHDR first, IEND chunk as the last 12 bytes. */
static int probe_png(const char *path, FILE *f, long size, btf_image_header *hdr, btf_error *err)
{
    static const unsigned char iend[12] = {0, 0, 0, 0, 'I', 'E', 'N', 'D', 0xAE, 0x42, 0x60, 0x82};
    unsigned char b[33], tail[12];
    if (size < 8 + 25 + 12 || fread(b, 1, 33, f) != 33)
        return btf_fail(err, BTF_E_FORMAT, "%s: truncated PNG (%ld bytes)", path, size);
    if (be32(b + 8) != 13 || memcmp(b + 12, "IHDR", 4) != 0)
        return btf_fail(err, BTF_E_FORMAT, "%s: PNG without IHDR header", path);
    uint32_t w = be32(b + 16), h = be32(b + 20);
    int depth = b[24], ctype = b[25];
    if (w < 1 || h < 1 || w > BTF_MAX_SIDE || h > BTF_MAX_SIDE)
        return btf_fail(err, BTF_E_FORMAT, "%s: PNG size %ux%u out of range", path, w, h);
    if (fseek(f, size - 12, SEEK_SET) != 0 || fread(tail, 1, 12, f) != 12 ||
        memcmp(tail, iend, 12) != 0)
        return btf_fail(err, BTF_E_FORMAT, "%s: truncated PNG (no IEND chunk at the end)", path);
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
static int probe_jpeg(const char *path, FILE *f, long size, btf_image_header *hdr, btf_error *err)
{
    unsigned char b[9];
    long pos = 2;
    int found = 0;
    while (pos + 4 <= size && !found) {
        if (fseek(f, pos, SEEK_SET) != 0 || fread(b, 1, 4, f) != 4)
            break;
        if (b[0] != 0xFF)
            return btf_fail(err, BTF_E_FORMAT, "%s: corrupt JPEG (bad marker at byte %ld)", path, pos);
        if (b[1] == 0xFF) { /* fill byte */
            pos++;
            continue;
        }
        int len = b[2] << 8 | b[3];
        if (is_jpeg_sof(b[1])) {
            if (fread(b + 4, 1, 5, f) != 5)
                break;
            hdr->height = b[5] << 8 | b[6];
            hdr->width = b[7] << 8 | b[8];
            int comps;
            if (fseek(f, pos + 9, SEEK_SET) != 0 || (comps = fgetc(f)) == EOF)
                break;
            hdr->channels = comps == 1 ? 1 : 3;
            hdr->bits = 8;
            found = 1;
        } else if (b[1] == 0xD9 || b[1] == 0xDA) {
            break; /* image data or end before any frame header */
        }
        pos += 2 + len;
    }
    if (!found)
        return btf_fail(err, BTF_E_FORMAT, "%s: truncated or corrupt JPEG (no frame header)", path);
    if (hdr->width < 1 || hdr->height < 1)
        return btf_fail(err, BTF_E_FORMAT, "%s: JPEG size %dx%d unsupported", path, hdr->width,
                        hdr->height);
    /* Encoders may pad after EOI; look for it in the last 64 bytes. */
    unsigned char tail[64];
    long start = size > 64 ? size - 64 : 0;
    size_t n;
    if (fseek(f, start, SEEK_SET) != 0 || (n = fread(tail, 1, sizeof tail, f)) < 2)
        return btf_fail(err, BTF_E_FORMAT, "%s: truncated JPEG", path);
    while (n > 2 && (tail[n - 1] == 0 || tail[n - 1] == '\n' || tail[n - 1] == '\r'))
        n--;
    if (tail[n - 2] == 0xFF && tail[n - 1] == 0xD9)
        return BTF_OK;
    return btf_fail(err, BTF_E_FORMAT, "%s: truncated JPEG (no end-of-image marker)", path);
}

int btf_image_probe(const char *path, btf_image_header *hdr, btf_error *err)
{
    memset(hdr, 0, sizeof *hdr);
    FILE *f = fopen(path, "rb");
    if (!f)
        return btf_fail(err, BTF_E_IO, "%s: cannot open: %s", path, strerror(errno));
    long size = file_size(f);
    unsigned char sig[4] = {0};
    size_t n = size > 0 ? fread(sig, 1, 4, f) : 0;
    int rc;
    if (size <= 0) {
        rc = btf_fail(err, BTF_E_FORMAT, "%s: empty file", path);
    } else if (n == 4 && !memcmp(sig, "\x89PNG", 4)) {
        hdr->format = BTF_FILE_PNG;
        rewind(f);
        rc = probe_png(path, f, size, hdr, err);
    } else if (n >= 3 && sig[0] == 0xFF && sig[1] == 0xD8 && sig[2] == 0xFF) {
        hdr->format = BTF_FILE_JPEG;
        rc = probe_jpeg(path, f, size, hdr, err);
    } else if (n == 4 && !memcmp(sig, "\x76\x2f\x31\x01", 4)) {
        fclose(f);
        return btf_exr_probe(path, hdr, err);
    } else {
        rc = btf_fail(err, BTF_E_FORMAT, "%s: not a PNG, JPEG or EXR file", path);
    }
    fclose(f);
    hdr->file_bytes = size > 0 ? (uint64_t)size : 0;
    return rc;
}

/* 8-bit to linear float through a 256-entry table built per call (no global
 * state; 256 powf calls are nothing next to a decode). */
static void convert_8bit(const unsigned char *src, size_t count, int linear, float *dst)
{
    float lut[256];
    for (int i = 0; i < 256; i++)
        lut[i] = linear ? (float)i / 255.0f : btf_srgb_to_linear((float)i / 255.0f);
    for (size_t i = 0; i < count; i++)
        dst[i] = lut[src[i]];
}

static void convert_16bit(const uint16_t *src, size_t count, int srgb, float *dst)
{
    for (size_t i = 0; i < count; i++) {
        float v = (float)src[i] / 65535.0f;
        dst[i] = srgb ? btf_srgb_to_linear(v) : v;
    }
}

/* Changes the channel count of a decoded image in place (grey <-> RGB);
 * grey from RGB is the Rec. 709 luminance of the linear values. */
static int convert_channels(btf_image *img, int want, btf_error *err)
{
    if (want == 0 || want == img->channels)
        return BTF_OK;
    btf_image out;
    int rc = btf_image_alloc(&out, img->width, img->height, want, err);
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

static int read_cv(const char *path, const btf_read_opts *o, btf_image *out, btf_error *err)
{
    btf_image_header hdr;
    int rc = btf_image_probe(path, &hdr, err);
    if (rc)
        return rc;
    int w, h, c, d16;
    void *px;
    char msg[256];
    if (btfcv_read(path, &w, &h, &c, &d16, &px, msg, sizeof msg) != 0)
        return btf_fail(err, BTF_E_FORMAT, "%s: %s", path, msg);
    if (w != hdr.width || h != hdr.height) {
        free(px);
        return btf_fail(err, BTF_E_FORMAT, "%s: decoded size %dx%d differs from header %dx%d",
                        path, w, h, hdr.width, hdr.height);
    }
    rc = btf_image_alloc(out, w, h, c, err);
    if (rc == 0) {
        size_t count = (size_t)w * h * c;
        if (d16)
            convert_16bit(px, count, o->srgb_16bit, out->data);
        else
            convert_8bit(px, count, o->linear_8bit, out->data);
    }
    free(px);
    return rc;
}

int btf_image_read(const char *path, const btf_read_opts *opts, btf_image *out, btf_error *err)
{
    btf_read_opts o = {0};
    if (opts)
        o = *opts;
    memset(out, 0, sizeof *out);
    if (o.channels != 0 && o.channels != 1 && o.channels != 3)
        return btf_fail(err, BTF_E_ARG, "%s: channels %d requested: expected 0, 1 or 3", path,
                        o.channels);
    FILE *f = fopen(path, "rb");
    if (!f)
        return btf_fail(err, BTF_E_IO, "%s: cannot open: %s", path, strerror(errno));
    fclose(f);
    btf_file_format fmt = btf_file_format_of(path);
    int rc;
    switch (fmt) {
    case BTF_FILE_EXR:
        return btf_exr_read(path, o.channels, out, err);
    case BTF_FILE_PNG:
    case BTF_FILE_JPEG:
        rc = read_cv(path, &o, out, err);
        break;
    default:
        return btf_fail(err, BTF_E_FORMAT, "%s: not a PNG, JPEG or EXR file", path);
    }
    if (rc == 0)
        rc = convert_channels(out, o.channels, err);
    if (rc)
        btf_image_free(out);
    return rc;
}

/* Linear float -> 8-bit sRGB, clamped; non-finite values become 0. */
static unsigned char *to_srgb8(const btf_image *img, btf_error *err)
{
    size_t n = (size_t)img->width * img->height * img->channels;
    unsigned char *b = btf_alloc(n, 1, err);
    if (!b)
        return NULL;
    for (size_t i = 0; i < n; i++) {
        float v = btf_linear_to_srgb(img->data[i]);
        b[i] = (unsigned char)lrintf(v * 255.0f);
    }
    return b;
}

static int write_cv(const char *path, const char *ext, const btf_image *img, int quality,
                    btf_error *err)
{
    if (!img || !img->data || (img->channels != 1 && img->channels != 3))
        return btf_fail(err, BTF_E_ARG, "%s: no image to write", path);
    unsigned char *px = to_srgb8(img, err);
    if (!px)
        return BTF_E_NOMEM;
    unsigned char *enc;
    size_t len;
    char msg[256];
    int rc = btfcv_encode(ext, img->width, img->height, img->channels, px, quality, &enc,
                          &len, msg, sizeof msg);
    free(px);
    if (rc != 0)
        return btf_fail(err, BTF_E_IO, "%s: cannot encode: %s", path, msg);
    rc = btf_write_file_atomic(path, enc, len, err);
    free(enc);
    return rc;
}

int btf_image_write_png(const char *path, const btf_image *img, btf_error *err)
{
    return write_cv(path, ".png", img, 0, err);
}

int btf_image_write_jpeg(const char *path, const btf_image *img, int quality, btf_error *err)
{
    if (quality < 1 || quality > 100)
        return btf_fail(err, BTF_E_ARG, "%s: JPEG quality %d: expected 1..100", path, quality);
    return write_cv(path, ".jpg", img, quality, err);
}

int btf_image_write_exr(const char *path, const btf_image *img, int half, btf_error *err)
{
    if (!img || !img->data)
        return btf_fail(err, BTF_E_ARG, "%s: no image to write", path);
    return btf_exr_write(path, img, half, err);
}
