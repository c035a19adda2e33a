/*
 * png_jpeg.c — PNG and JPEG decoding with libpng and libjpeg(-turbo)
 * directly, not through OpenCV: OpenCV installs the libraries' default
 * message handlers, so their warnings ("libpng warning: ...", "Corrupt JPEG
 * data: ...") went to stderr before btfcar's own error line, and a JPEG
 * whose entropy-coded data was damaged decoded "successfully" with a
 * warning. Here every message goes to a handler: nothing is printed, an
 * error becomes the one-line error text naming the file, and libjpeg's
 * data-corruption warnings (bad Huffman code, premature end of a segment or
 * of the file, extraneous bytes, lost sync) and libpng's warnings about the
 * image data (IDAT) are errors too. Benign warnings (an unknown JFIF
 * revision, a bad ICC marker, colour profiles, ancillary-chunk CRCs, which
 * libpng discards) are dropped silently.
 *
 * Output as the OpenCV bridge gave it: 8- or 16-bit (native byte order)
 * samples, 1 or 3 channels, RGB order, alpha dropped, palette expanded.
 */
#include <stdio.h> /* before jpeglib.h, which uses FILE */
#include "core/core.h"
#include "io/io.h"

#include <jpeglib.h>
#include <jerror.h>
#include <png.h>
#include <setjmp.h>
#include <stdlib.h>
#include <string.h>

/* A progressive JPEG may hold any number of scans, each a pass over the
 * whole coefficient buffer: a small file could keep the decoder busy for
 * minutes. libjpeg-turbo's own tools stop at 500. */
#define MAX_JPEG_SCANS 500

/* ------------------------------------------------------------------ PNG */

typedef struct png_state {
    const unsigned char *data;
    size_t n, pos;
    char msg[200];
    png_structp png;
    png_infop info;
    unsigned char *px;
    png_bytep *rows;
    btf_decoded *out;
} png_state;

static void png_on_error(png_structp png, png_const_charp msg)
{
    png_state *s = png_get_error_ptr(png);
    snprintf(s->msg, sizeof s->msg, "%s", msg ? msg : "decoder error");
    png_longjmp(png, 1);
}

/* Silent. libpng reports damage to the image data that it could read past
 * (a failed zlib check at the stream's end, after the last row) as an
 * "IDAT: ..." warning: that is an error here. Spare data after the image
 * (some encoders write it) and everything outside IDAT (ancillary chunks,
 * colour profiles) are not. */
static void png_on_warning(png_structp png, png_const_charp msg)
{
    if (!msg || strncmp(msg, "IDAT: ", 6) != 0 || strstr(msg, "Too much image data") ||
        strstr(msg, "Extra compressed data"))
        return;
    png_state *s = png_get_error_ptr(png);
    snprintf(s->msg, sizeof s->msg, "%s", msg);
    png_longjmp(png, 1);
}

static void png_read_mem(png_structp png, png_bytep out, png_size_t len)
{
    png_state *s = png_get_io_ptr(png);
    if (len > s->n - s->pos)
        png_error(png, "premature end of data");
    memcpy(out, s->data + s->pos, len);
    s->pos += len;
}

static int host_little_endian(void)
{
    const uint16_t one = 1;
    return *(const unsigned char *)&one == 1;
}

/* Everything between setjmp and the end lives in *s (the caller's frame), so
 * nothing here is indeterminate after a longjmp. */
static int png_decode_body(png_state *s)
{
    if (setjmp(png_jmpbuf(s->png)))
        return -1;
    png_set_read_fn(s->png, s, png_read_mem);
    png_set_user_limits(s->png, BTF_MAX_SIDE, BTF_MAX_SIDE);
    png_read_info(s->png, s->info);
    png_uint_32 w, h;
    int depth, ctype, interlace;
    png_get_IHDR(s->png, s->info, &w, &h, &depth, &ctype, &interlace, NULL, NULL);
    if (ctype == PNG_COLOR_TYPE_PALETTE)
        png_set_palette_to_rgb(s->png);
    if (ctype == PNG_COLOR_TYPE_GRAY && depth < 8)
        png_set_expand_gray_1_2_4_to_8(s->png);
    if (ctype & PNG_COLOR_MASK_ALPHA)
        png_set_strip_alpha(s->png);
    if (depth == 16 && host_little_endian())
        png_set_swap(s->png);
    png_set_interlace_handling(s->png);
    png_read_update_info(s->png, s->info);
    int c = png_get_channels(s->png, s->info);
    int bits = png_get_bit_depth(s->png, s->info);
    if ((c != 1 && c != 3) || (bits != 8 && bits != 16))
        png_error(s->png, "unsupported PNG layout");
    size_t rowbytes = png_get_rowbytes(s->png, s->info);
    if (rowbytes != (size_t)w * c * (bits / 8))
        png_error(s->png, "unexpected PNG row size");
    s->px = malloc((size_t)rowbytes * h + 1);
    s->rows = malloc(sizeof *s->rows * h);
    if (!s->px || !s->rows) {
        snprintf(s->msg, sizeof s->msg, "out of memory decoding a %ux%u PNG", w, h);
        return -2;
    }
    for (png_uint_32 y = 0; y < h; y++)
        s->rows[y] = s->px + (size_t)y * rowbytes;
    png_read_image(s->png, s->rows);
    /* The chunks after the image data up to IEND: their CRCs are checked. */
    png_read_end(s->png, NULL);
    s->out->width = (int)w;
    s->out->height = (int)h;
    s->out->channels = c;
    s->out->depth16 = bits == 16;
    return 0;
}

static btf_status decode_png(const unsigned char *data, size_t n, const char *name,
                             btf_decoded *out, btf_error *err)
{
    png_state s;
    memset(&s, 0, sizeof s);
    s.data = data;
    s.n = n;
    s.out = out;
    s.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &s, png_on_error, png_on_warning);
    if (s.png)
        s.info = png_create_info_struct(s.png);
    if (!s.png || !s.info) {
        png_destroy_read_struct(s.png ? &s.png : NULL, NULL, NULL);
        return btf__fail(err, BTF_E_NOMEM, "%s: out of memory starting the PNG decoder", name);
    }
    int rc = png_decode_body(&s);
    png_destroy_read_struct(&s.png, &s.info, NULL);
    free(s.rows);
    if (rc) {
        free(s.px);
        return btf__fail(err, rc == -2 ? BTF_E_NOMEM : BTF_E_FORMAT, "%s: %s%s", name,
                         rc == -2 ? "" : "corrupt PNG: ", s.msg);
    }
    out->pixels = s.px;
    return BTF_OK;
}

/* ------------------------------------------------------------------ JPEG */

typedef struct jpeg_state {
    struct jpeg_error_mgr mgr; /* first: libjpeg hands back a pointer to it */
    struct jpeg_progress_mgr progress;
    jmp_buf jump;
    char msg[JMSG_LENGTH_MAX];
    int nomem;
    struct jpeg_decompress_struct d;
    unsigned char *px, *row;
    btf_decoded *out;
} jpeg_state;

static void jpeg_on_error(j_common_ptr cinfo)
{
    jpeg_state *s = (jpeg_state *)cinfo->err;
    s->mgr.format_message(cinfo, s->msg);
    s->nomem = s->mgr.msg_code == JERR_OUT_OF_MEMORY;
    longjmp(s->jump, 1);
}

/* level < 0: a warning; the ones that mean damaged image data end the
 * decoding (a silent success would hand grey or garbled pixels on). */
static void jpeg_on_message(j_common_ptr cinfo, int level)
{
    jpeg_state *s = (jpeg_state *)cinfo->err;
    if (level >= 0)
        return; /* trace messages */
    switch (s->mgr.msg_code) {
    case JWRN_ADOBE_XFORM:
    case JWRN_JFIF_MAJOR:
    case JWRN_BOGUS_ICC:
        return;
    default:
        s->mgr.format_message(cinfo, s->msg);
        longjmp(s->jump, 1);
    }
}

static void jpeg_on_output(j_common_ptr cinfo)
{
    (void)cinfo; /* nothing on stderr */
}

static void jpeg_on_progress(j_common_ptr cinfo)
{
    jpeg_state *s = (jpeg_state *)cinfo->err;
    if (cinfo->is_decompressor &&
        ((j_decompress_ptr)cinfo)->input_scan_number > MAX_JPEG_SCANS) {
        snprintf(s->msg, sizeof s->msg, "more than %d progressive scans", MAX_JPEG_SCANS);
        longjmp(s->jump, 1);
    }
}

static int jpeg_decode_body(jpeg_state *s, const unsigned char *data, size_t n)
{
    if (setjmp(s->jump))
        return -1;
    jpeg_create_decompress(&s->d);
    s->d.progress = &s->progress;
    jpeg_mem_src(&s->d, data, (unsigned long)n);
    jpeg_read_header(&s->d, TRUE);
    int cmyk = 0;
    if (s->d.num_components == 1) {
        s->d.out_color_space = JCS_GRAYSCALE;
    } else if (s->d.jpeg_color_space == JCS_CMYK || s->d.jpeg_color_space == JCS_YCCK) {
        s->d.out_color_space = JCS_CMYK;
        cmyk = 1;
    } else {
        s->d.out_color_space = JCS_RGB;
    }
    jpeg_start_decompress(&s->d);
    JDIMENSION w = s->d.output_width, h = s->d.output_height;
    int comps = s->d.output_components, c = comps == 1 ? 1 : 3;
    if (w < 1 || h < 1 || w > BTF_MAX_SIDE || h > BTF_MAX_SIDE ||
        comps != (cmyk ? 4 : c)) {
        snprintf(s->msg, sizeof s->msg, "unsupported JPEG layout (%ux%u, %d components)", w,
                 h, comps);
        return -1;
    }
    s->px = malloc((size_t)w * h * c);
    s->row = malloc((size_t)w * comps);
    if (!s->px || !s->row) {
        snprintf(s->msg, sizeof s->msg, "out of memory decoding a %ux%u JPEG", w, h);
        s->nomem = 1;
        return -1;
    }
    while (s->d.output_scanline < h) {
        unsigned char *dst = s->px + (size_t)s->d.output_scanline * w * c;
        JSAMPROW r = cmyk ? s->row : dst;
        if (jpeg_read_scanlines(&s->d, &r, 1) != 1) {
            snprintf(s->msg, sizeof s->msg, "premature end of JPEG data");
            return -1;
        }
        /* Adobe's inverted CMYK, as OpenCV converts it: R = C K / 255. */
        for (JDIMENSION x = 0; cmyk && x < w; x++) {
            const unsigned char *q = s->row + 4 * (size_t)x;
            for (int k = 0; k < 3; k++)
                dst[3 * (size_t)x + k] = (unsigned char)((q[k] * q[3] + 127) / 255);
        }
    }
    /* Reads on to the end-of-image marker: trailing damage warns here. */
    jpeg_finish_decompress(&s->d);
    s->out->width = (int)w;
    s->out->height = (int)h;
    s->out->channels = c;
    s->out->depth16 = 0;
    return 0;
}

static btf_status decode_jpeg(const unsigned char *data, size_t n, const char *name,
                              btf_decoded *out, btf_error *err)
{
    jpeg_state *s = calloc(1, sizeof *s);
    if (!s)
        return btf__fail(err, BTF_E_NOMEM, "%s: out of memory starting the JPEG decoder", name);
    s->d.err = jpeg_std_error(&s->mgr);
    s->mgr.error_exit = jpeg_on_error;
    s->mgr.emit_message = jpeg_on_message;
    s->mgr.output_message = jpeg_on_output;
    s->progress.progress_monitor = jpeg_on_progress;
    s->out = out;
    int rc = jpeg_decode_body(s, data, n);
    jpeg_destroy_decompress(&s->d);
    free(s->row);
    btf_status st = BTF_OK;
    if (rc) {
        free(s->px);
        static const char lead[] = "Corrupt JPEG data: "; /* said once, not twice */
        const char *m = strncmp(s->msg, lead, sizeof lead - 1) ? s->msg : s->msg + sizeof lead - 1;
        st = btf__fail(err, s->nomem ? BTF_E_NOMEM : BTF_E_FORMAT, "%s: %s%s", name,
                       s->nomem ? "" : "corrupt JPEG: ", m);
    } else {
        out->pixels = s->px;
    }
    free(s);
    return st;
}

btf_status btf__png_jpeg_decode(const void *data, size_t n, btf_file_format format,
                                const char *name, btf_decoded *out, btf_error *err)
{
    memset(out, 0, sizeof *out);
    if (format == BTF_FILE_PNG)
        return decode_png(data, n, name, out, err);
    if (format == BTF_FILE_JPEG)
        return decode_jpeg(data, n, name, out, err);
    return btf__fail(err, BTF_E_FORMAT, "%s: not a PNG or JPEG file", name);
}
