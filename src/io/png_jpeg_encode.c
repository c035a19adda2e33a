/*
 * png_jpeg_encode.c — PNG and JPEG encoding with libpng and libjpeg(-turbo)
 * directly, to a memory buffer that the caller writes atomically.
 *
 * Why not OpenCV's imencode: libopencv_imgcodecs links GDAL, GDCM, HDF5,
 * Poppler and about 125 other libraries, and loading them took ~50 ms of
 * every btfcar process — more than synthesising the paper's whole workload
 * (docs/design.md, "The map"). Decoding already went through these two libraries
 * (png_jpeg.c); with encoding here too, imgcodecs is no longer linked.
 */
#include <stdio.h> /* before jpeglib.h, which uses FILE */
#include "core/core.h"
#include "io/io.h"

#include <jpeglib.h>
#include <png.h>
#include <setjmp.h>
#include <stdlib.h>
#include <string.h>

/* zlib level 3 with libpng's adaptive filters: files within a few % of
 * level 9 at a fraction of the time (the level the OpenCV path used). */
#define PNG_ZLIB_LEVEL 3

/* A growing output buffer; on allocation failure `failed` is set and the
 * encoder is stopped through its error handler. */
typedef struct out_buffer {
    unsigned char *data;
    size_t len, cap;
    int failed;
} out_buffer;

static int buffer_append(out_buffer *b, const void *src, size_t n)
{
    if (b->failed)
        return -1;
    if (n > b->cap - b->len) {
        size_t cap = b->cap ? b->cap : 65536;
        while (cap - b->len < n) {
            if (cap > SIZE_MAX / 2) {
                b->failed = 1;
                return -1;
            }
            cap *= 2;
        }
        unsigned char *grown = realloc(b->data, cap);
        if (!grown) {
            b->failed = 1;
            return -1;
        }
        b->data = grown;
        b->cap = cap;
    }
    memcpy(b->data + b->len, src, n);
    b->len += n;
    return 0;
}

/* ------------------------------------------------------------------ PNG */

typedef struct png_out {
    out_buffer buf;
    char msg[200];
} png_out;

static void png_enc_error(png_structp png, png_const_charp msg)
{
    png_out *o = png_get_error_ptr(png);
    snprintf(o->msg, sizeof o->msg, "%s", msg);
    png_longjmp(png, 1);
}

static void png_enc_warning(png_structp png, png_const_charp msg)
{
    (void)png; /* encoder warnings carry nothing a user can act on */
    (void)msg;
}

static void png_enc_write(png_structp png, png_bytep data, png_size_t len)
{
    png_out *o = png_get_io_ptr(png);
    if (buffer_append(&o->buf, data, len) != 0)
        png_error(png, "out of memory");
}

static void png_enc_flush(png_structp png)
{
    (void)png;
}

/* Writes the rows; returns 0, or -1 with o->msg set. Separate from the
 * caller so that the setjmp frame holds no variable changed after it. */
static int png_encode_body(png_structp png, png_infop info, int w, int h, int c,
                           const unsigned char *px, png_out *o)
{
    if (setjmp(png_jmpbuf(png)))
        return -1;
    png_set_write_fn(png, o, png_enc_write, png_enc_flush);
    png_set_compression_level(png, PNG_ZLIB_LEVEL);
    png_set_IHDR(png, info, (png_uint_32)w, (png_uint_32)h, 8,
                 c == 3 ? PNG_COLOR_TYPE_RGB : PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    /* The pixels are sRGB-encoded (btf__linear_to_srgb): say so, so that
     * viewers do not guess. */
    png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    png_write_info(png, info);
    size_t stride = (size_t)w * (size_t)c;
    for (int y = 0; y < h; y++)
        png_write_row(png, (png_const_bytep)(px + (size_t)y * stride));
    png_write_end(png, info);
    return 0;
}

static int encode_png(int w, int h, int c, const unsigned char *px, unsigned char **out,
                      size_t *outlen, char *msg, size_t msglen)
{
    png_out o = {0};
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &o, png_enc_error,
                                              png_enc_warning);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    if (!png || !info) {
        png_destroy_write_struct(&png, &info);
        snprintf(msg, msglen, "out of memory");
        return -1;
    }
    int bad = png_encode_body(png, info, w, h, c, px, &o);
    png_destroy_write_struct(&png, &info);
    if (bad) {
        free(o.buf.data);
        snprintf(msg, msglen, "%s", o.msg[0] ? o.msg : "PNG encoder failed");
        return -1;
    }
    *out = o.buf.data;
    *outlen = o.buf.len;
    return 0;
}

/* ----------------------------------------------------------------- JPEG */

typedef struct jpeg_out {
    struct jpeg_error_mgr err; /* first: libjpeg casts the pointer */
    struct jpeg_destination_mgr dest;
    jmp_buf jump;
    out_buffer buf;
    unsigned char chunk[65536];
    char msg[JMSG_LENGTH_MAX];
} jpeg_out;

static void jpeg_enc_error(j_common_ptr cinfo)
{
    jpeg_out *o = (jpeg_out *)cinfo->err;
    (*cinfo->err->format_message)(cinfo, o->msg);
    longjmp(o->jump, 1);
}

static void jpeg_enc_message(j_common_ptr cinfo, int level)
{
    (void)cinfo; /* nothing is printed: errors come back as text */
    (void)level;
}

static void jpeg_dest_init(j_compress_ptr cinfo)
{
    jpeg_out *o = (jpeg_out *)cinfo->err;
    o->dest.next_output_byte = o->chunk;
    o->dest.free_in_buffer = sizeof o->chunk;
}

static boolean jpeg_dest_empty(j_compress_ptr cinfo)
{
    jpeg_out *o = (jpeg_out *)cinfo->err;
    if (buffer_append(&o->buf, o->chunk, sizeof o->chunk) != 0) {
        snprintf(o->msg, sizeof o->msg, "out of memory");
        longjmp(o->jump, 1);
    }
    o->dest.next_output_byte = o->chunk;
    o->dest.free_in_buffer = sizeof o->chunk;
    return TRUE;
}

static void jpeg_dest_term(j_compress_ptr cinfo)
{
    jpeg_out *o = (jpeg_out *)cinfo->err;
    size_t used = sizeof o->chunk - o->dest.free_in_buffer;
    if (buffer_append(&o->buf, o->chunk, used) != 0) {
        snprintf(o->msg, sizeof o->msg, "out of memory");
        longjmp(o->jump, 1);
    }
}

static int jpeg_encode_body(struct jpeg_compress_struct *ci, jpeg_out *o, int w, int h, int c,
                            const unsigned char *px, int quality)
{
    if (setjmp(o->jump))
        return -1;
    jpeg_create_compress(ci);
    o->dest.init_destination = jpeg_dest_init;
    o->dest.empty_output_buffer = jpeg_dest_empty;
    o->dest.term_destination = jpeg_dest_term;
    ci->dest = &o->dest;
    ci->image_width = (JDIMENSION)w;
    ci->image_height = (JDIMENSION)h;
    ci->input_components = c;
    ci->in_color_space = c == 3 ? JCS_RGB : JCS_GRAYSCALE;
    jpeg_set_defaults(ci);
    jpeg_set_quality(ci, quality, TRUE);
    jpeg_start_compress(ci, TRUE);
    size_t stride = (size_t)w * (size_t)c;
    while (ci->next_scanline < ci->image_height) {
        JSAMPROW row = (JSAMPROW)(px + (size_t)ci->next_scanline * stride);
        jpeg_write_scanlines(ci, &row, 1);
    }
    jpeg_finish_compress(ci);
    return 0;
}

static int encode_jpeg(int w, int h, int c, const unsigned char *px, int quality,
                       unsigned char **out, size_t *outlen, char *msg, size_t msglen)
{
    jpeg_out *o = calloc(1, sizeof *o);
    if (!o) {
        snprintf(msg, msglen, "out of memory");
        return -1;
    }
    struct jpeg_compress_struct ci;
    memset(&ci, 0, sizeof ci);
    ci.err = jpeg_std_error(&o->err);
    o->err.error_exit = jpeg_enc_error;
    o->err.emit_message = jpeg_enc_message;
    int bad = jpeg_encode_body(&ci, o, w, h, c, px, quality);
    jpeg_destroy_compress(&ci);
    if (bad) {
        snprintf(msg, msglen, "%s", o->msg[0] ? o->msg : "JPEG encoder failed");
        free(o->buf.data);
        free(o);
        return -1;
    }
    *out = o->buf.data;
    *outlen = o->buf.len;
    free(o);
    return 0;
}

int btf__png_jpeg_encode(btf_file_format format, int w, int h, int c,
                         const unsigned char *pixels, int jpeg_quality, unsigned char **out,
                         size_t *outlen, char *msg, size_t msglen)
{
    *out = NULL;
    *outlen = 0;
    if (w <= 0 || h <= 0 || (c != 1 && c != 3)) {
        snprintf(msg, msglen, "cannot encode a %dx%d image of %d channels", w, h, c);
        return -1;
    }
    if (format == BTF_FILE_JPEG) {
        /* JPEG's frame header holds 16-bit sizes. */
        if (w > JPEG_MAX_DIMENSION || h > JPEG_MAX_DIMENSION) {
            snprintf(msg, msglen, "%dx%d is larger than JPEG allows (%d per side)", w, h,
                     (int)JPEG_MAX_DIMENSION);
            return -1;
        }
        return encode_jpeg(w, h, c, pixels, jpeg_quality, out, outlen, msg, msglen);
    }
    return encode_png(w, h, c, pixels, out, outlen, msg, msglen);
}
