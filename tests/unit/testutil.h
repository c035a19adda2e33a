/*
 * testutil.h — shared helpers for the cmocka test programs.
 * Each tests/unit/test_*.c is its own program, linked with testutil.o and
 * libbtfcar.a; tests/unit/run.sh runs them all and prints the total.
 */
#ifndef BTF_TESTUTIL_H
#define BTF_TESTUTIL_H

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "btfcar.h"

#include <openexr.h>

/* A scratch folder for a whole group of tests: tu_setup_dir and
 * tu_teardown_dir are cmocka group fixtures that make and remove tu_dir. */
extern char *tu_dir;
int tu_setup_dir(void **state);
int tu_teardown_dir(void **state);

/* A fresh temporary folder (under $TMPDIR or /tmp), removed by tu_rmtree. */
char *tu_tmpdir(void);
void tu_rmtree(const char *path);
/* printf into a static rotating buffer (8 slots): for building paths that
 * are used at once; copy a path that must outlive 8 more calls. */
const char *tu_fmt(const char *fmt, ...);
/* Runs a shell command line, returns its exit status; its stderr is captured
 * into *stderr_text (malloc'd; may be NULL) when non-NULL. */
int tu_run(const char *cmdline, char **stderr_text);
/* The btfcar command under test ($BTF_CLI, else build/btfcar). */
const char *tu_cli(void);
/* Writes bytes to a file; asserts success. */
void tu_write_file(const char *path, const void *data, size_t n);
/* Number of regular files under a folder, recursively. */
int tu_count_files(const char *path);
/* Writes an EXR file directly with the core API (tu_exr_write_raw), for
 * layouts and values btf_image_write_exr_opts never produces (NaN, Inf, UINT, tiles). Channel c of pixel (x, y) (data-window relative) is
 * value(c, x, y); UINT channels store it truncated. */
typedef struct tu_exr_spec {
    exr_storage_t storage;         /* SCANLINE or TILED */
    exr_compression_t compression;
    int tile;                      /* tile side when TILED */
    int x0, y0;                    /* data window origin */
    int width, height;
    int nch;
    const char *names[4];          /* sorted by name, as EXR requires */
    exr_pixel_type_t types[4];
} tu_exr_spec;

typedef float (*tu_exr_value_fn)(int c, int x, int y);
/* The string attribute `name` of part 0 of an open EXR, or NULL when absent
 * (asserts the stored length matches the text). */
const char *tu_exr_string(exr_const_context_t ctx, const char *name);
void tu_exr_write_raw(const char *path, const tu_exr_spec *s, tu_exr_value_fn value);

/* Under ASan, keeps the Vulkan validation layer loaded after the loader lets
 * it go, so that LeakSanitizer can name its frames and the suppression of its
 * known leak (tests/unit/lsan.supp) matches. A no-op otherwise. */
void tu_vk_keep_layer_loaded(void);
/* The GPU tests' device: lavapipe unless VK_DRIVER_FILES names another
 * driver, CPU devices allowed, the Khronos validation layer on. 0, or -1
 * with the reason printed under the test's name. */
int tu_gpu_open(btf_gpu **g, const char *test);
/* Fails the test on any validation message of g (printing the first). */
void tu_gpu_no_validation_messages(btf_gpu *g);

/* Wall-clock seconds (CLOCK_MONOTONIC), and the median of n values (sorts
 * them): for the benchmark programs. */
double tu_now(void);
/* Runs a command line and returns its stdout (malloc'd, up to 64 KiB), its
 * exit status in *status. */
char *tu_capture(const char *cmd, int *status);
/* One rendered image of a procedural material (btf_procedural_make/render):
 * the test textures of several programs. */
void tu_material_image(const char *name, int size, unsigned seed, btf_dir view, btf_dir light,
                       btf_image *img);
double tu_median(double *v, int n);

/* Reads a whole file (asserts success) into a malloc'd buffer of its *n
 * bytes and one more (an empty file gets a buffer too); no more than that,
 * as tests hand the bytes to readers that ASan should catch running past
 * their end. */
unsigned char *tu_slurp(const char *path, size_t *n);

/* The small UBO2014 set of the .btf tests (test_btf_file, test_btf_variants):
 * TU_SMALL_NV views x TU_SMALL_NL lights of TU_SMALL_W x TU_SMALL_H pixels,
 * smooth RGB images whose every value a test can compute (tu_small_value).
 * tu_setup_small and tu_teardown_small are cmocka group fixtures that make
 * and free the two direction sets, and tu_dir with them. */
enum { TU_SMALL_W = 8, TU_SMALL_H = 6, TU_SMALL_NV = 3, TU_SMALL_NL = 4 };
extern btf_dirset tu_small_views, tu_small_lights;
int tu_setup_small(void **state);
int tu_teardown_small(void **state);
/* Channel c of pixel (x, y) of the image of view v, light l. */
float tu_small_value(int v, int l, int x, int y, int c);
/* The image of (v, l): a btf_pair_image_fn for btf_ubo2014_write (user unused). */
btf_status tu_small_image(void *user, int v, int l, btf_image *out, btf_error *err);
/* Opening the n bytes d, written to tu_dir/bad.btf, as a dataset fails: with
 * code (unless 0) and one line that names the file and contains what
 * (unless NULL). */
void tu_expect_open_fails(const unsigned char *d, size_t n, const char *what, int code);

/* A generated dataset for a group fixture: btf_generate of material at
 * size x size texels and seed, written to tu_dir/material (path receives
 * that; path_size bytes) and opened into *ds. 0, or -1 with the reason
 * printed: a group fixture fails by its return value, not by asserting. */
int tu_generate_dataset(const char *material, int size, uint64_t seed, char *path,
                        size_t path_size, btf_dataset **ds);

/* The RF model file's tests (test_rf, test_rf_sample). A tiny PTM model:
 * 2 views, 1 light, 2 fields of width x height texels, every lo 0, every
 * hi 1, the codes 0, 1000, 2000, ... */
void tu_rf_tiny_model(btf_rf_model *m, int width, int height);
/* The payload of an encoded model file (after its 26-byte container head,
 * inflated when stored compressed) into payload, of cap bytes; its length. */
size_t tu_rf_payload(const unsigned char *d, unsigned char *payload, size_t cap);
/* The payload of a model file d (either family: one container), inflated
 * when deflated, malloc'd; its size in *n. */
unsigned char *tu_model_payload(const unsigned char *d, size_t *n);
/* Where the content of the payload's section tag ("RFHD", ...) starts, past
 * its 8-byte head; 0 when there is none, the last when there are several. */
size_t tu_rf_section(const unsigned char *payload, size_t n, const char *tag);
/* Wraps a (modified) payload of n bytes as a stored container of the given
 * major format version with a valid CRC, so that the decoder reaches the
 * change: malloc'd, its size in *size. */
unsigned char *tu_rf_rewrap(const unsigned char *payload, size_t n, int major, size_t *size);
/* The same for a CAR model file (docs/model-format.md): version 1.minor. */
unsigned char *tu_model_rewrap(const unsigned char *payload, size_t n, int minor, size_t *size);
/* Decoding the n bytes d as "bad.rf" is BTF_E_FORMAT with a message naming
 * it, and leaves m->codes NULL; what (the damage) is printed otherwise. m
 * and e are the caller's, for checks of its own. */
void tu_rf_expect_format_error(const unsigned char *d, size_t n, const char *what,
                               btf_rf_model *m, btf_error *e);
/* Every truncation of an encoded model file, and the file with any one byte
 * changed (bit 4 flipped, then restored), is an error by expect. */
typedef void (*tu_rf_expect_fn)(const unsigned char *d, size_t n, const char *what);
void tu_rf_expect_damage_fails(unsigned char *d, size_t n, tu_rf_expect_fn expect);

/* Asserts a btfcar call succeeded, printing the error message if not. */
#define TU_OK(call, errp)                                                      \
    do {                                                                       \
        int tu_rc_ = (call);                                                   \
        if (tu_rc_ != 0)                                                       \
            print_error("%s failed: %s\n", #call, (errp)->msg);                \
        assert_int_equal(tu_rc_, 0);                                           \
    } while (0)

#endif
