/*
 * btfcar/image.h — float images and their files: reading, probing and
 * writing PNG, JPEG and OpenEXR; EXR provenance, compression and the
 * streaming EXR writer.
 * Part of the public C API of btfcar; include/btfcar.h includes every
 * topical header, and its conventions (docs/api.md) hold here too.
 */
#ifndef BTFCAR_IMAGE_H
#define BTFCAR_IMAGE_H

#include "base.h"

#include <stddef.h>
#include <stdint.h>

/* What this header declares is part of the ABI of libbtfcar.so: the library
 * is compiled with -fvisibility=hidden, and the declarations of the public
 * headers alone are exported (docs/install.md, "Shared library and soname"). */
#pragma GCC visibility push(default)

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------ images */

typedef struct btf_image {
    int width, height, channels; /* channels: 1 (grey) or 3 (RGB) */
    float *data;                 /* width*height*channels floats, row-major */
} btf_image;

btf_status btf_image_alloc(btf_image *img, int width, int height, int channels,
                           btf_error *err);
void btf_image_free(btf_image *img);

typedef enum btf_file_format {
    BTF_FILE_UNKNOWN = 0,
    BTF_FILE_PNG,
    BTF_FILE_JPEG,
    BTF_FILE_EXR
} btf_file_format;

typedef struct btf_image_header {
    btf_file_format format;
    int width, height;
    int channels;       /* channels in the file (before conversion) */
    int bits;           /* 8 or 16 for PNG/JPEG, 16 (half) or 32 for EXR */
    uint64_t file_bytes;
} btf_image_header;

/* Reads the header only and checks the structure (a JPEG must end with its
 * end-of-image marker, a PNG with its IEND chunk, an EXR's chunk table must
 * fit): cheap, no decoding. The memory form checks n bytes at data; name
 * starts its error messages, as the path does for the file form. */
btf_status btf_image_probe_memory(const void *data, size_t n, const char *name,
                                  btf_image_header *hdr, btf_error *err);
btf_status btf_image_probe(const char *path, btf_image_header *hdr, btf_error *err);

/* The default cap on the pixels of one decoded image: 2^28 (16384 x 16384,
 * 3 GiB as float RGB, about 12 GB at texture-fit's peak; docs/api.md,
 * "Resource limits"). Files over the cap are refused from their header,
 * before any pixel is decoded, so a small file cannot claim gigabytes. */
#define BTF_DEFAULT_MAX_PIXELS ((uint64_t)1 << 28)

typedef struct btf_read_opts {
    size_t struct_size; /* sizeof the struct (set by the defaults); 0: this header's */
    int channels;       /* 0: 3 for colour files, 1 for grey; 1 or 3 forces it */
    int linear_8bit;    /* 0 (default): 8-bit files are sRGB and are linearised;
                           1: 8-bit values are taken as linear (v/255) */
    int srgb_16bit;     /* 0 (default): 16-bit PNG is linear (v/65535); 1: sRGB */
    uint64_t max_pixels; /* width x height above this is refused (BTF_E_UNSUPPORTED,
                           naming the file, its size and the cap) from the
                           header; 0: BTF_DEFAULT_MAX_PIXELS */
} btf_read_opts;
/* The defaults: channels, linear_8bit, srgb_16bit 0 (as above), max_pixels
 * BTF_DEFAULT_MAX_PIXELS (a zeroed struct behaves the same). */
btf_read_opts btf_read_defaults(void);

/* Decodes PNG (8/16-bit), JPEG or EXR (half/float) held in memory (n bytes
 * at data; the format from its signature) into linear float. name starts
 * the error messages (NULL: "image"). EXR values that are NaN or Inf are an
 * error (BTF_E_DATA). opts NULL: btf_read_defaults(). */
btf_status btf_image_decode(const void *data, size_t n, const char *name,
                            const btf_read_opts *opts, btf_image *out, btf_error *err);
/* The same from a file, its messages naming it. EXR files are read in place,
 * chunk by chunk; PNG and JPEG files are loaded and decoded. */
btf_status btf_image_read(const char *path, const btf_read_opts *opts, btf_image *out,
                          btf_error *err);

/* Writers are atomic: a temporary file beside `path` is renamed over it. PNG
 * and JPEG encode linear values to 8-bit sRGB (clamped to [0, 1]); EXR
 * (below) stores linear values as float or half. */
btf_status btf_image_write_png(const char *path, const btf_image *img, btf_error *err);
btf_status btf_image_write_jpeg(const char *path, const btf_image *img, int quality,
                                btf_error *err);

/* -------------------------------------------------------------- EXR output */

/* What an output EXR says about where it came from, as header attributes
 * (docs/api.md, "EXR provenance"): btfcarVersion and the standard
 * chromaticities attribute (linear sRGB: Rec. 709 primaries, D65 white)
 * always; btfcarModel, btfcarSeed and btfcarSubspace when model is set;
 * btfcarView and btfcarLight ("THETA PHI", degrees) when has_dirs is 1.
 * The pixels are the same with or without them. */
typedef struct btf_exr_meta {
    const char *model;     /* the model file synthesised from; NULL: none */
    uint64_t seed;         /* with model: the synthesis seed */
    int subspace;          /* with model: the subspace synthesised */
    int has_dirs;          /* 1: view and light are set */
    btf_dir view, light;   /* the subspace's representative (view, light) */
} btf_exr_meta;

/* EXR compression (OpenEXR's methods; docs/synthesis.md, "EXR output",
 * measures them on synthesised images). ZIP is 0, the default. NONE, RLE,
 * ZIPS, ZIP and PIZ are lossless; PXR24 is lossless for half and rounds
 * float to 24 bits. B44/B44A are not offered: btfcar refuses to read them
 * (OpenEXRCore 3.1's B44 decoder crashes on damaged files), they are lossy
 * by up to 1.5 on synthesised noise, and OpenEXRCore 3.1.5 writes float B44
 * wrong. (OpenEXRCore 3.1 cannot write DWAA/DWAB.) */
typedef enum btf_exr_compression {
    BTF_EXR_ZIP = 0,  /* zlib (level 4) over 16-row chunks */
    BTF_EXR_NONE,     /* raw scanlines */
    BTF_EXR_RLE,      /* run lengths of bytes */
    BTF_EXR_ZIPS,     /* zlib (level 4) per scanline */
    BTF_EXR_PIZ,      /* wavelet + Huffman over 32-row chunks */
    BTF_EXR_PXR24
} btf_exr_compression;

/* Seconds an EXR writer spent, added to at close (abort adds nothing): on
 * checking and staging rows (stage_s, the caller's thread), converting and
 * packing them (convert_s), compressing (compress_s), writing the header,
 * chunks and offset table (write_s), and the caller waiting for a free
 * buffer while the background thread catches up (wait_s); bytes: file
 * sizes; files: files committed. With background 1 convert, compress and
 * write run beside the caller. */
typedef struct btf_exr_times {
    double stage_s, convert_s, compress_s, write_s, wait_s;
    uint64_t bytes;
    int files;
} btf_exr_times;

typedef struct btf_exr_opts {
    size_t struct_size; /* sizeof the struct (set by the defaults); 0: this header's */
    int half;           /* 0 (default): 32-bit float; 1: half, clamped to +-65504 */
    int compression;    /* btf_exr_compression; 0: ZIP */
    int background;     /* 0 (default): the caller compresses and writes; 1: a
                           thread of the writer does, while the caller makes
                           the next rows (a bounded queue of a few chunks,
                           about 256 KiB or one chunk each); same bytes */
    btf_exr_times *times; /* NULL (default), or figures added to at close */
} btf_exr_opts;
/* The defaults: every field 0 (float, ZIP, no thread, no figures). */
btf_exr_opts btf_exr_defaults(void);

/* Writes img to path as an EXR file (atomically) with the options (NULL:
 * btf_exr_defaults(): float, ZIP) and the provenance attributes of meta
 * (NULL: none, no optional attributes). */
btf_status btf_image_write_exr_opts(const char *path, const btf_image *img,
                                    const btf_exr_opts *opts, const btf_exr_meta *meta,
                                    btf_error *err);

/* Streaming EXR scanline writer (synthesis of images larger than memory): rows
 * arrive top to bottom in batches of any size; only one chunk (16 rows, ZIP)
 * is buffered. Like btf_image_write_exr_opts it is atomic: the file appears
 * at path only when close succeeds. Any error is final for the writer: close
 * (which then fails) or abort frees it and removes the temporary file. */
typedef struct btf_exr_writer btf_exr_writer;
/* Opens a writer of a width x height image of `channels` channels (1 or 3),
 * with options and provenance as btf_image_write_exr_opts takes them. */
btf_status btf_exr_writer_open_opts(const char *path, int width, int height, int channels,
                                    const btf_exr_opts *opts, const btf_exr_meta *meta,
                                    btf_exr_writer **out, btf_error *err);
/* rows: nrows*width*channels floats, interleaved channels; finite values. */
btf_status btf_exr_writer_put_rows(btf_exr_writer *w, const float *rows, int nrows,
                                   btf_error *err);
/* Finishes and renames into place; an error if not all rows were given.
 * Always frees w. */
btf_status btf_exr_writer_close(btf_exr_writer *w, btf_error *err);
/* Frees w and removes the temporary file; NULL is fine. */
void btf_exr_writer_abort(btf_exr_writer *w);

#ifdef __cplusplus
}
#endif

#pragma GCC visibility pop
#endif /* BTFCAR_IMAGE_H */
