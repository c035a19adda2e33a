/* test_decode.c — PNG/JPEG decoding through libpng/libjpeg (src/io/png_jpeg.c):
 * the PNG layouts (palette, grey + alpha, 1-bit, 16-bit interlaced), corrupt
 * bodies as errors with nothing on stderr but btfcar's one line, and the cap
 * on decoded pixels (btf_read_opts.max_pixels, --max-pixels) checked from
 * the header before decoding. */
#include "testutil.h"
#include "core/core.h"

#include <math.h>
#include <stdio.h> /* before jpeglib.h */
#include <jpeglib.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <zlib.h>

static void put_be32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)(v >> 24), p[1] = (unsigned char)(v >> 16);
    p[2] = (unsigned char)(v >> 8), p[3] = (unsigned char)v;
}

/* Appends one chunk (length, type, data, CRC) to f. */
static void chunk(FILE *f, const char *type, const unsigned char *data, uint32_t n)
{
    unsigned char b[8];
    put_be32(b, n);
    memcpy(b + 4, type, 4);
    uLong crc = crc32(crc32(0L, Z_NULL, 0), (const Bytef *)type, 4);
    if (n)
        crc = crc32(crc, data, n);
    fwrite(b, 1, 8, f);
    if (n)
        fwrite(data, 1, n, f);
    put_be32(b, (uint32_t)crc);
    fwrite(b, 1, 4, f);
}

/* An 8-bit grey PNG of w x h: zero pixels deflated (rows = 0: a header with
 * an empty image stream, all the probe and the cap look at). */
static void grey_png(const char *path, uint32_t w, uint32_t h, uint32_t rows)
{
    static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    unsigned char ihdr[13] = {0};
    put_be32(ihdr, w);
    put_be32(ihdr + 4, h);
    ihdr[8] = 8; /* depth; colour type 0 (grey), no interlace */
    z_stream z;
    memset(&z, 0, sizeof z);
    assert_int_equal(deflateInit(&z, 1), Z_OK);
    size_t cap = 1 << 16, used = 0;
    unsigned char *out = malloc(cap), *row = calloc(1, w + 1);
    assert_true(out && row);
    for (uint32_t y = 0; y <= rows; y++) {
        z.next_in = row;
        z.avail_in = y < rows ? w + 1 : 0;
        int flush = y < rows ? Z_NO_FLUSH : Z_FINISH, rc;
        do {
            if (cap - used < 4096) {
                out = realloc(out, cap *= 2);
                assert_non_null(out);
            }
            z.next_out = out + used;
            z.avail_out = (uInt)(cap - used);
            rc = deflate(&z, flush);
            used = cap - z.avail_out;
        } while (z.avail_in > 0 || (flush == Z_FINISH && rc != Z_STREAM_END));
    }
    deflateEnd(&z);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fwrite(sig, 1, 8, f);
    chunk(f, "IHDR", ihdr, 13);
    chunk(f, "IDAT", out, (uint32_t)used);
    chunk(f, "IEND", NULL, 0);
    assert_int_equal(fclose(f), 0);
    free(out);
    free(row);
}

/* One line on stderr, naming `what`, from a failing command. */
static void one_line_error(const char *cmd, const char *what, const char *what2)
{
    char *err = NULL;
    int st = tu_run(cmd, &err);
    assert_int_not_equal(st, 0);
    assert_non_null(err);
    if (!strstr(err, what) || (what2 && !strstr(err, what2)) ||
        strchr(err, '\n') != err + strlen(err) - 1 || strncmp(err, "btfcar ", 7) != 0)
        print_error("%s: stderr was:\n%s", cmd, err);
    assert_non_null(strstr(err, what));
    if (what2)
        assert_non_null(strstr(err, what2));
    assert_true(strncmp(err, "btfcar ", 7) == 0);
    assert_true(strchr(err, '\n') == err + strlen(err) - 1);
    free(err);
}

static void pixel_cap(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image img;
    /* A header claiming 20000 x 20000 (400 M pixels): over the default cap,
     * refused from the header, naming the file, its size and the cap. */
    char huge[4096];
    snprintf(huge, sizeof huge, "%s/huge.png", tu_dir);
    grey_png(huge, 20000, 20000, 0);
    assert_int_equal(btf_image_read(huge, NULL, &img, &e), BTF_E_UNSUPPORTED);
    assert_null(img.data);
    assert_non_null(strstr(e.msg, huge));
    assert_non_null(strstr(e.msg, "20000x20000"));
    assert_non_null(strstr(e.msg, "268435456"));
    btf_read_opts zero = {0};
    assert_int_equal(btf_image_read(huge, &zero, &img, &e), BTF_E_UNSUPPORTED);

    /* A valid 16000 x 16000 PNG (about 1 MB): under the default cap, refused
     * at once with a lower one, from memory and from the file. */
    char big[4096];
    snprintf(big, sizeof big, "%s/big.png", tu_dir);
    grey_png(big, 16000, 16000, 16000);
    btf_read_opts ro = btf_read_defaults();
    ro.max_pixels = (uint64_t)1 << 26;
    double t0 = tu_now();
    assert_int_equal(btf_image_read(big, &ro, &img, &e), BTF_E_UNSUPPORTED);
    assert_non_null(strstr(e.msg, big));
    assert_non_null(strstr(e.msg, "16000x16000"));
    assert_non_null(strstr(e.msg, "256000000"));
    assert_non_null(strstr(e.msg, "67108864"));
    size_t n;
    unsigned char *bytes = tu_slurp(big, &n);
    assert_int_equal(btf_image_decode(bytes, n, "mem", &ro, &img, &e), BTF_E_UNSUPPORTED);
    assert_true(strncmp(e.msg, "mem: ", 5) == 0);
    free(bytes);
    assert_true(tu_now() - t0 < 1.0);
    /* The cap is inclusive. */
    char small[4096];
    snprintf(small, sizeof small, "%s/small.png", tu_dir);
    grey_png(small, 30, 20, 20);
    ro.max_pixels = 600;
    TU_OK(btf_image_read(small, &ro, &img, &e), &e);
    assert_int_equal(img.width * img.height, 600);
    btf_image_free(&img);
    ro.max_pixels = 599;
    assert_int_equal(btf_image_read(small, &ro, &img, &e), BTF_E_UNSUPPORTED);

    /* EXR too. */
    char exr[4096];
    snprintf(exr, sizeof exr, "%s/small.exr", tu_dir);
    TU_OK(btf_image_alloc(&img, 30, 20, 3, &e), &e);
    TU_OK(btf_image_write_exr_opts(exr, &img, &(btf_exr_opts){.half = 1}, NULL, &e), &e);
    btf_image_free(&img);
    assert_int_equal(btf_image_read(exr, &ro, &img, &e), BTF_E_UNSUPPORTED);
    assert_non_null(strstr(e.msg, "30x20"));
    ro.max_pixels = 600;
    TU_OK(btf_image_read(exr, &ro, &img, &e), &e);
    btf_image_free(&img);

    /* The command line: texture-fit refuses the file in one line, quickly. */
    t0 = tu_now();
    one_line_error(tu_fmt("%s texture-fit %s -o %s/big.btfcar --max-pixels 67108864", tu_cli(),
                          big, tu_dir),
                   big, "67108864");
    one_line_error(tu_fmt("%s texture-fit %s -o %s/huge.btfcar", tu_cli(), huge, tu_dir), huge,
                   "268435456");
    assert_true(tu_now() - t0 < 5.0);
    /* Out of memory (an address-space limit; not under ASan, which maps
     * terabytes): the message names the file, and comes before decoding. */
    if (!getenv("BTF_ASAN"))
        one_line_error(tu_fmt("ulimit -v 800000; %s texture-fit %s -o %s/big.btfcar", tu_cli(),
                              big, tu_dir),
                       tu_fmt("%s: out of memory", big), NULL);
}

static void dataset_cap(void **state)
{
    (void)state;
    char ds[4096];
    snprintf(ds, sizeof ds, "%s/ds", tu_dir); /* corrupt_bodies uses it too */
    assert_int_equal(tu_run(tu_fmt("%s generate -q --material wood --size 16 %s", tu_cli(), ds),
                            NULL), 0);
    btf_error e = {0};
    btf_dataset *d;
    btf_dataset_opts o = btf_dataset_defaults();
    TU_OK(btf_dataset_open(ds, &o, &d, &e), &e);
    btf_dataset_close(d);
    o.max_pixels = 255; /* the images are 16 x 16 */
    assert_int_equal(btf_dataset_open(ds, &o, &d, &e), BTF_E_UNSUPPORTED);
    assert_non_null(strstr(e.msg, "16x16"));
    o.skip_verify = 1;
    assert_int_equal(btf_dataset_open(ds, &o, &d, &e), BTF_E_UNSUPPORTED);
    one_line_error(tu_fmt("%s info --verify --max-pixels 255 %s", tu_cli(), ds), ds, "255");
    assert_int_equal(tu_run(tu_fmt("%s info --verify --max-pixels 256 %s >/dev/null", tu_cli(),
                                   ds), NULL), 0);
}

/* A PNG written with libpng: `ctype`, `depth`, interlaced or not; sample k of
 * pixel (x, y) is value(x, y, k) (palette: the index). */
static unsigned sample(int x, int y, int k, int depth)
{
    unsigned max = (1u << depth) - 1;
    return (unsigned)(x * 7 + y * 13 + k * 101) % (max + 1);
}

static void write_png(const char *path, int w, int h, int ctype, int depth, int interlace)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png_create_info_struct(png);
    assert_true(png && info);
    assert_int_equal(setjmp(png_jmpbuf(png)), 0);
    png_init_io(png, f);
    png_set_IHDR(png, info, (png_uint_32)w, (png_uint_32)h, depth, ctype,
                 interlace ? PNG_INTERLACE_ADAM7 : PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    png_color pal[4] = {{0, 0, 0}, {255, 0, 128}, {10, 200, 30}, {255, 255, 255}};
    if (ctype == PNG_COLOR_TYPE_PALETTE)
        png_set_PLTE(png, info, pal, 4);
    png_write_info(png, info);
    int ns = ctype == PNG_COLOR_TYPE_RGB_ALPHA ? 4 : ctype == PNG_COLOR_TYPE_RGB ? 3
           : ctype == PNG_COLOR_TYPE_GRAY_ALPHA ? 2 : 1;
    size_t rowbytes = ((size_t)w * ns * depth + 7) / 8;
    unsigned char *px = calloc((size_t)h, rowbytes);
    png_bytep *rows = malloc(sizeof *rows * (size_t)h);
    for (int y = 0; y < h; y++) {
        rows[y] = px + (size_t)y * rowbytes;
        for (int x = 0; x < w; x++)
            for (int k = 0; k < ns; k++) {
                unsigned v = sample(x, y, k, ctype == PNG_COLOR_TYPE_PALETTE ? 2 : depth);
                size_t bit = ((size_t)x * ns + k) * depth;
                if (depth == 16) {
                    rows[y][bit / 8] = (unsigned char)(v >> 8);
                    rows[y][bit / 8 + 1] = (unsigned char)v;
                } else {
                    rows[y][bit / 8] |= (unsigned char)(v << (8 - depth - bit % 8));
                }
            }
    }
    png_write_image(png, rows);
    png_write_end(png, NULL);
    png_destroy_write_struct(&png, &info);
    fclose(f);
    free(rows);
    free(px);
}

static void png_layouts(void **state)
{
    (void)state;
    static const unsigned char pal[4][3] = {{0, 0, 0}, {255, 0, 128}, {10, 200, 30},
                                            {255, 255, 255}};
    struct { int ctype, depth, interlace, channels; } cases[] = {
        {PNG_COLOR_TYPE_PALETTE, 2, 0, 3},   {PNG_COLOR_TYPE_GRAY_ALPHA, 8, 0, 1},
        {PNG_COLOR_TYPE_GRAY, 1, 0, 1},      {PNG_COLOR_TYPE_RGB_ALPHA, 16, 1, 3},
        {PNG_COLOR_TYPE_RGB, 8, 1, 3},       {PNG_COLOR_TYPE_GRAY, 16, 0, 1},
    };
    const int w = 13, h = 11;
    for (size_t t = 0; t < sizeof cases / sizeof cases[0]; t++) {
        const char *p = tu_fmt("%s/layout%zu.png", tu_dir, t);
        write_png(p, w, h, cases[t].ctype, cases[t].depth, cases[t].interlace);
        btf_error e = {0};
        btf_image img;
        btf_image_header hd;
        TU_OK(btf_image_probe(p, &hd, &e), &e);
        TU_OK(btf_image_read(p, NULL, &img, &e), &e);
        assert_int_equal(img.width, w);
        assert_int_equal(img.height, h);
        assert_int_equal(img.channels, cases[t].channels);
        assert_int_equal(hd.channels, cases[t].channels);
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++)
                for (int k = 0; k < img.channels; k++) {
                    float want;
                    int d = cases[t].depth;
                    if (cases[t].ctype == PNG_COLOR_TYPE_PALETTE)
                        want = btf__srgb_to_linear(pal[sample(x, y, 0, 2)][k] / 255.0f);
                    else if (d == 16)
                        want = (float)sample(x, y, k, 16) / 65535.0f;
                    else
                        want = btf__srgb_to_linear((float)sample(x, y, k, d) /
                                                   (float)((1u << d) - 1));
                    float got = img.data[((size_t)y * w + x) * img.channels + k];
                    if (fabsf(got - want) > 1e-6f)
                        print_error("case %zu (%d, %d, %d): %g, expected %g\n", t, x, y, k,
                                    got, want);
                    assert_true(fabsf(got - want) <= 1e-6f);
                }
        btf_image_free(&img);
    }
}

/* A CMYK JPEG (libjpeg writes Adobe's inverted convention): decoded as RGB,
 * R = C K / 255 and so on, as OpenCV did. */
static void cmyk_jpeg(void **state)
{
    (void)state;
    const char *p = tu_fmt("%s/cmyk.jpg", tu_dir);
    char path[4096];
    snprintf(path, sizeof path, "%s", p);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    struct jpeg_compress_struct c;
    struct jpeg_error_mgr jerr;
    c.err = jpeg_std_error(&jerr);
    jpeg_create_compress(&c);
    jpeg_stdio_dest(&c, f);
    c.image_width = 16;
    c.image_height = 8;
    c.input_components = 4;
    c.in_color_space = JCS_CMYK;
    jpeg_set_defaults(&c);
    jpeg_set_quality(&c, 100, TRUE);
    jpeg_start_compress(&c, TRUE);
    unsigned char row[16 * 4];
    for (int x = 0; x < 16; x++)
        row[4 * x] = 200, row[4 * x + 1] = 100, row[4 * x + 2] = 50, row[4 * x + 3] = 128;
    while (c.next_scanline < c.image_height) {
        JSAMPROW r = row;
        jpeg_write_scanlines(&c, &r, 1);
    }
    jpeg_finish_compress(&c);
    jpeg_destroy_compress(&c);
    fclose(f);
    btf_error e = {0};
    btf_image img;
    TU_OK(btf_image_read(path, NULL, &img, &e), &e);
    assert_int_equal(img.channels, 3);
    const int want[3] = {200 * 128 / 255, 100 * 128 / 255, 50 * 128 / 255};
    for (int i = 0; i < 16 * 8; i++)
        for (int k = 0; k < 3; k++) {
            float v = btf__linear_to_srgb(img.data[3 * i + k]) * 255.0f;
            if (fabsf(v - want[k]) > 2.0f)
                print_error("pixel %d channel %d: %g, expected %d\n", i, k, v, want[k]);
            assert_true(fabsf(v - want[k]) <= 2.0f);
        }
    btf_image_free(&img);
}

static void gradient_file(const char *path, int jpeg)
{
    btf_error e = {0};
    btf_image img;
    TU_OK(btf_image_alloc(&img, 32, 24, 3, &e), &e);
    for (size_t i = 0; i < (size_t)32 * 24 * 3; i++)
        img.data[i] = (float)((i * 37) % 101) / 100.0f;
    if (jpeg)
        TU_OK(btf_image_write_jpeg(path, &img, 90, &e), &e);
    else
        TU_OK(btf_image_write_png(path, &img, &e), &e);
    btf_image_free(&img);
}

/* Decoding fails with BTF_E_FORMAT naming the file and `what`; the CLI says
 * so in one line, and nothing else reaches stderr. */
static void corrupt_is_error(const char *path, const unsigned char *b, size_t n, const char *what)
{
    tu_write_file(path, b, n);
    btf_error e = {0};
    btf_image img;
    int rc = btf_image_read(path, NULL, &img, &e);
    if (rc != BTF_E_FORMAT || !strstr(e.msg, what))
        print_error("%s: status %d, %s\n", path, rc, e.msg);
    assert_int_equal(rc, BTF_E_FORMAT);
    assert_non_null(strstr(e.msg, path));
    assert_non_null(strstr(e.msg, what));
    assert_null(img.data);
    one_line_error(tu_fmt("%s texture-fit '%s' -o %s/x.btfcar", tu_cli(), path, tu_dir), path,
                   what);
}

static void corrupt_bodies(void **state)
{
    (void)state;
    char jpg[4096], png[4096];
    snprintf(jpg, sizeof jpg, "%s/good.jpg", tu_dir);
    snprintf(png, sizeof png, "%s/good.png", tu_dir);
    gradient_file(jpg, 1);
    gradient_file(png, 0);
    size_t n;
    unsigned char *d = tu_slurp(jpg, &n);
    /* The scan data: after the SOS segment, up to the EOI marker. */
    size_t sos = 2;
    while (sos + 4 < n && !(d[sos] == 0xFF && d[sos + 1] == 0xDA))
        sos += 2 + ((size_t)d[sos + 2] << 8 | d[sos + 3]);
    assert_true(sos + 4 < n);
    size_t body = sos + 2 + ((size_t)d[sos + 2] << 8 | d[sos + 3]), len = n - 2 - body;
    assert_true(len > 100);
    unsigned char *b = malloc(n);
    /* Entropy data cut in half, the end-of-image marker kept (the probe's
     * structure is sound): libjpeg warned and filled grey, exit 0. */
    memcpy(b, d, body + len / 2);
    b[body + len / 2] = 0xFF, b[body + len / 2 + 1] = 0xD9;
    corrupt_is_error(tu_fmt("%s/cut.jpg", tu_dir), b, body + len / 2 + 2, "corrupt JPEG");
    /* Garbled bytes in the middle of the scan. */
    memcpy(b, d, n);
    for (size_t k = body + 10; k < body + 14; k++)
        b[k] ^= 0x55;
    corrupt_is_error(tu_fmt("%s/flip.jpg", tu_dir), b, n, "corrupt JPEG");
    free(b);
    free(d);

    d = tu_slurp(png, &n);
    size_t idat = 8;
    while (idat + 8 < n && memcmp(d + idat + 4, "IDAT", 4) != 0)
        idat += 12 + ((size_t)d[idat] << 24 | (size_t)d[idat + 1] << 16 |
                      (size_t)d[idat + 2] << 8 | d[idat + 3]);
    assert_true(idat + 8 < n);
    uint32_t ilen = (uint32_t)d[idat] << 24 | (uint32_t)d[idat + 1] << 16 |
                    (uint32_t)d[idat + 2] << 8 | d[idat + 3];
    b = malloc(n);
    /* The image data's CRC does not match. */
    memcpy(b, d, n);
    b[idat + 8 + ilen] ^= 0x20;
    corrupt_is_error(tu_fmt("%s/crc.png", tu_dir), b, n, "CRC");
    /* A flipped byte in the middle of the image data. */
    memcpy(b, d, n);
    b[idat + 8 + ilen / 2] ^= 0x20;
    corrupt_is_error(tu_fmt("%s/flip.png", tu_dir), b, n, "corrupt PNG");
    /* The same with a correct CRC: the zlib stream's own check (its last
     * four bytes, after the last row) fails. */
    memcpy(b, d, n);
    b[idat + 8 + ilen - 1] ^= 0x01;
    uLong crc = crc32(crc32(0L, Z_NULL, 0), b + idat + 4, ilen + 4);
    put_be32(b + idat + 8 + ilen, (uint32_t)crc);
    corrupt_is_error(tu_fmt("%s/adler.png", tu_dir), b, n, "corrupt PNG");
    free(b);
    free(d);

    /* A dataset (dataset_cap's) with one corrupt JPEG body: info --verify
     * fails in one line naming it (plain info only probes the structure,
     * which is sound). */
    char ds[4096];
    snprintf(ds, sizeof ds, "%s/ds", tu_dir);
    const char *victim = tu_fmt("%s/tv060_pv018/02387 tl045 pl200 tv060 pv018.jpg", ds);
    char vpath[4096];
    snprintf(vpath, sizeof vpath, "%s", victim);
    d = tu_slurp(vpath, &n);
    sos = 2;
    while (sos + 4 < n && !(d[sos] == 0xFF && d[sos + 1] == 0xDA))
        sos += 2 + ((size_t)d[sos + 2] << 8 | d[sos + 3]);
    body = sos + 2 + ((size_t)d[sos + 2] << 8 | d[sos + 3]);
    len = n - 2 - body;
    d[body + len / 2] = 0xFF, d[body + len / 2 + 1] = 0xD9;
    tu_write_file(vpath, d, body + len / 2 + 2);
    free(d);
    assert_int_equal(tu_run(tu_fmt("%s info %s >/dev/null", tu_cli(), ds), NULL), 0);
    one_line_error(tu_fmt("%s info --verify %s", tu_cli(), ds), "02387 tl045 pl200 tv060 pv018.jpg",
                   "corrupt JPEG");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(pixel_cap),
        cmocka_unit_test(dataset_cap),
        cmocka_unit_test(png_layouts),
        cmocka_unit_test(cmyk_jpeg),
        cmocka_unit_test(corrupt_bodies),
    };
    return cmocka_run_group_tests_name("decode", tests, tu_setup_dir, tu_teardown_dir);
}
