/* testutil.c — see testutil.h. */
#define _GNU_SOURCE
#include "testutil.h"

#include "core/core.h"

#if defined(__SANITIZE_ADDRESS__)
#define TU_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define TU_ASAN 1
#endif
#endif

#ifdef TU_ASAN
#include <dlfcn.h>
/* Leaks of libraries, not of btfcar: tests/unit/lsan.supp explains both rules.
 * The btfcar processes the tests start get the same file through
 * LSAN_OPTIONS (make asan). */
const char *__lsan_default_suppressions(void);
const char *__lsan_default_suppressions(void)
{
    return "leak:libVkLayer_khronos_validation.so\nleak:libopencv_core.so\n";
}
#endif

void tu_vk_keep_layer_loaded(void)
{
#ifdef TU_ASAN
    dlopen("libVkLayer_khronos_validation.so", RTLD_LAZY | RTLD_NODELETE);
#endif
}

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>
#include <zlib.h>

char *tu_dir;

int tu_setup_dir(void **state)
{
    (void)state;
    tu_dir = tu_tmpdir();
    return 0;
}

int tu_teardown_dir(void **state)
{
    (void)state;
    tu_rmtree(tu_dir);
    free(tu_dir);
    tu_dir = NULL;
    return 0;
}

double tu_now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double tu_median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return v[n / 2];
}

char *tu_tmpdir(void)
{
    const char *base = getenv("TMPDIR");
    char tmpl[4096];
    snprintf(tmpl, sizeof tmpl, "%s/btfcar-test-XXXXXX", base && *base ? base : "/tmp");
    char *d = mkdtemp(tmpl);
    assert_non_null(d);
    return strdup(d);
}

void tu_rmtree(const char *path)
{
    btf__remove_tree(path);
}

const char *tu_fmt(const char *fmt, ...)
{
    static char bufs[8][4096];
    static int slot;
    char *b = bufs[slot++ & 7];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(b, 4096, fmt, ap);
    va_end(ap);
    return b;
}

int tu_run(const char *cmdline, char **stderr_text)
{
    char errfile[] = "/tmp/btfcar-stderr-XXXXXX";
    int fd = mkstemp(errfile);
    assert_true(fd >= 0);
    close(fd);
    char *full = NULL;
    assert_true(asprintf(&full, "%s 2>%s", cmdline, errfile) > 0);
    int st = system(full);
    free(full);
    if (stderr_text) {
        FILE *f = fopen(errfile, "rb");
        char *text = calloc(1, 65536);
        if (f) {
            size_t n = fread(text, 1, 65535, f);
            text[n] = 0;
            fclose(f);
        }
        *stderr_text = text;
    }
    remove(errfile);
    if (st == -1)
        return -1;
    return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
}

const char *tu_cli(void)
{
    const char *c = getenv("BTF_CLI");
    return c && *c ? c : "build/btfcar";
}

void tu_write_file(const char *path, const void *data, size_t n)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, n, f), n);
    assert_int_equal(fclose(f), 0);
}

int tu_count_files(const char *path)
{
    DIR *d = opendir(path);
    if (!d)
        return 0;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
            continue;
        char sub[4096];
        snprintf(sub, sizeof sub, "%s/%s", path, e->d_name);
        struct stat st;
        if (stat(sub, &st) != 0)
            continue;
        n += S_ISDIR(st.st_mode) ? tu_count_files(sub) : 1;
    }
    closedir(d);
    return n;
}


static void raw_quiet(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    (void)ctxt, (void)code;
    print_error("openexr (test writer): %s\n", msg);
}

/* Encodes the block (bx, by, bw, bh) of the planar source buffers. */
static void raw_encode(exr_context_t ctx, exr_encode_pipeline_t *enc, int *started,
                       const exr_chunk_info_t *ci, const tu_exr_spec *s, void **planes, int bx,
                       int by)
{
    if (*started)
        assert_int_equal(exr_encoding_update(ctx, 0, ci, enc), EXR_ERR_SUCCESS);
    else
        assert_int_equal(exr_encoding_initialize(ctx, 0, ci, enc), EXR_ERR_SUCCESS);
    *started = 1;
    for (int c = 0; c < enc->channel_count; c++) {
        exr_coding_channel_info_t *ch = &enc->channels[c];
        int k = -1;
        for (int j = 0; j < s->nch; j++)
            if (!strcmp(ch->channel_name, s->names[j]))
                k = j;
        assert_true(k >= 0);
        ch->encode_from_ptr = (const uint8_t *)planes[k] + ((size_t)by * s->width + bx) * 4;
        ch->user_pixel_stride = 4;
        ch->user_line_stride = s->width * 4;
        ch->user_bytes_per_element = 4;
        ch->user_data_type = s->types[k] == EXR_PIXEL_UINT ? EXR_PIXEL_UINT : EXR_PIXEL_FLOAT;
    }
    assert_int_equal(exr_encoding_choose_default_routines(ctx, 0, enc), EXR_ERR_SUCCESS);
    assert_int_equal(exr_encoding_run(ctx, 0, enc), EXR_ERR_SUCCESS);
}

void tu_exr_write_raw(const char *path, const tu_exr_spec *s, tu_exr_value_fn value)
{
    void *planes[4];
    for (int k = 0; k < s->nch; k++) {
        planes[k] = malloc((size_t)s->width * s->height * 4);
        assert_non_null(planes[k]);
        for (int y = 0; y < s->height; y++)
            for (int x = 0; x < s->width; x++) {
                size_t i = (size_t)y * s->width + x;
                float v = value(k, x, y);
                if (s->types[k] == EXR_PIXEL_UINT)
                    ((uint32_t *)planes[k])[i] = (uint32_t)v;
                else
                    ((float *)planes[k])[i] = v;
            }
    }
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = raw_quiet;
    exr_context_t ctx = NULL;
    assert_int_equal(exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, &init), EXR_ERR_SUCCESS);
    int part = -1;
    assert_int_equal(exr_add_part(ctx, NULL, s->storage, &part), EXR_ERR_SUCCESS);
    exr_attr_box2i_t box;
    box.min.x = s->x0;
    box.min.y = s->y0;
    box.max.x = s->x0 + s->width - 1;
    box.max.y = s->y0 + s->height - 1;
    exr_attr_v2f_t center;
    center.x = center.y = 0.0f;
    assert_int_equal(exr_initialize_required_attr(ctx, part, &box, &box, 1.0f, &center, 1.0f,
                                                  EXR_LINEORDER_INCREASING_Y, s->compression),
                     EXR_ERR_SUCCESS);
    if (s->storage == EXR_STORAGE_TILED)
        assert_int_equal(exr_set_tile_descriptor(ctx, part, (uint32_t)s->tile, (uint32_t)s->tile,
                                                 EXR_TILE_ONE_LEVEL, EXR_TILE_ROUND_DOWN),
                         EXR_ERR_SUCCESS);
    for (int k = 0; k < s->nch; k++)
        assert_int_equal(exr_add_channel(ctx, part, s->names[k], s->types[k],
                                         EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1),
                         EXR_ERR_SUCCESS);
    assert_int_equal(exr_write_header(ctx), EXR_ERR_SUCCESS);
    exr_encode_pipeline_t enc;
    memset(&enc, 0, sizeof enc);
    int started = 0;
    exr_chunk_info_t ci;
    if (s->storage == EXR_STORAGE_TILED) {
        int ntx = (s->width + s->tile - 1) / s->tile, nty = (s->height + s->tile - 1) / s->tile;
        for (int ty = 0; ty < nty; ty++)
            for (int tx = 0; tx < ntx; tx++) {
                assert_int_equal(exr_write_tile_chunk_info(ctx, part, tx, ty, 0, 0, &ci),
                                 EXR_ERR_SUCCESS);
                raw_encode(ctx, &enc, &started, &ci, s, planes, tx * s->tile, ty * s->tile);
            }
    } else {
        int32_t lines = 0;
        assert_int_equal(exr_get_scanlines_per_chunk(ctx, part, &lines), EXR_ERR_SUCCESS);
        for (int y = 0; y < s->height; y += lines) {
            assert_int_equal(exr_write_scanline_chunk_info(ctx, part, s->y0 + y, &ci),
                             EXR_ERR_SUCCESS);
            raw_encode(ctx, &enc, &started, &ci, s, planes, 0, y);
        }
    }
    if (started)
        exr_encoding_destroy(ctx, &enc);
    assert_int_equal(exr_finish(&ctx), EXR_ERR_SUCCESS);
    for (int k = 0; k < s->nch; k++)
        free(planes[k]);
}

char *tu_capture(const char *cmd, int *status)
{
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    char *out = calloc(1, 1 << 16);
    assert_non_null(out);
    size_t n = fread(out, 1, (1 << 16) - 1, p);
    out[n] = 0;
    int st = pclose(p);
    *status = WEXITSTATUS(st);
    return out;
}

void tu_material_image(const char *name, int size, unsigned seed, btf_dir view, btf_dir light,
                       btf_image *img)
{
    btf_error e = {0};
    btf_procedural mat;
    TU_OK(btf_procedural_make(name, size, seed, &mat, &e), &e);
    TU_OK(btf_procedural_render(&mat, view, light, img, &e), &e);
    btf_procedural_free(&mat);
}

const char *tu_exr_string(exr_const_context_t ctx, const char *name)
{
    int32_t len = 0;
    const char *s = NULL;
    if (exr_attr_get_string(ctx, 0, name, &len, &s) != EXR_ERR_SUCCESS)
        return NULL;
    assert_int_equal((int)strlen(s), len);
    return s;
}

int tu_gpu_open(btf_gpu **g, const char *test)
{
    const char *icd = "/usr/share/vulkan/icd.d/lvp_icd.x86_64.json";
    if (!getenv("VK_DRIVER_FILES"))
        setenv("VK_DRIVER_FILES", icd, 1);
    if (!getenv("VK_ICD_FILENAMES"))
        setenv("VK_ICD_FILENAMES", icd, 1);
    tu_vk_keep_layer_loaded();
    btf_gpu_opts o = {.allow_cpu = 1, .validation = 1};
    btf_error e = {0};
    if (btf_gpu_open(&o, g, &e) != 0) {
        fprintf(stderr, "%s: %s\n", test, e.msg);
        return -1;
    }
    return 0;
}

void tu_gpu_no_validation_messages(btf_gpu *g)
{
    unsigned n = btf_gpu_validation_errors(g);
    if (n)
        print_error("validation: %u message(s), first: %s\n", n,
                    btf_gpu_first_validation_message(g));
    assert_int_equal(n, 0);
}

unsigned char *tu_slurp(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *d = malloc((size_t)len + 1);
    assert_non_null(d);
    assert_int_equal(fread(d, 1, (size_t)len, f), (size_t)len);
    fclose(f);
    *n = (size_t)len;
    return d;
}

btf_dirset tu_small_views, tu_small_lights;

int tu_setup_small(void **state)
{
    btf_dir vd[TU_SMALL_NV] = {{0, 0}, {30, 90}, {60, 200}};
    btf_dir ld[TU_SMALL_NL] = {{0, 0}, {20, 10}, {45, 180}, {75, 300}};
    if (btf_dirset_from_list(&tu_small_views, vd, TU_SMALL_NV, NULL) ||
        btf_dirset_from_list(&tu_small_lights, ld, TU_SMALL_NL, NULL))
        return -1;
    return tu_setup_dir(state);
}

int tu_teardown_small(void **state)
{
    btf_dirset_free(&tu_small_views);
    btf_dirset_free(&tu_small_lights);
    return tu_teardown_dir(state);
}

float tu_small_value(int v, int l, int x, int y, int c)
{
    return 0.2f + 0.1f * (float)v + 0.05f * (float)l * (float)(c + 1) +
           0.01f * (float)(x * (c + 1)) - 0.015f * (float)y + 0.002f * (float)(x * y * l);
}

btf_status tu_small_image(void *user, int v, int l, btf_image *out, btf_error *err)
{
    (void)user;
    const int w = TU_SMALL_W, h = TU_SMALL_H;
    btf_status rc = btf_image_alloc(out, w, h, 3, err);
    for (int y = 0; rc == BTF_OK && y < h; y++)
        for (int x = 0; x < w; x++)
            for (int c = 0; c < 3; c++)
                out->data[(y * w + x) * 3 + c] = tu_small_value(v, l, x, y, c);
    return rc;
}

void tu_expect_open_fails(const unsigned char *d, size_t n, const char *what, int code)
{
    const char *p = tu_fmt("%s/bad.btf", tu_dir);
    tu_write_file(p, d, n);
    btf_error err = {0};
    btf_dataset *ds = NULL;
    int rc = btf_dataset_open(p, NULL, &ds, &err);
    if (rc == 0)
        print_error("opened although %s\n", what ? what : "bad");
    assert_int_not_equal(rc, 0);
    assert_null(ds);
    if (code)
        assert_int_equal(rc, code);
    assert_non_null(strstr(err.msg, p));
    assert_null(strchr(err.msg, '\n'));
    if (what && !strstr(err.msg, what))
        print_error("message \"%s\" lacks \"%s\"\n", err.msg, what);
    if (what)
        assert_non_null(strstr(err.msg, what));
}

int tu_generate_dataset(const char *material, int size, uint64_t seed, char *path,
                        size_t path_size, btf_dataset **ds)
{
    btf_error e = {0};
    btf_generate_opts g = {.size = size, .seed = seed};
    snprintf(path, path_size, "%s/%s", tu_dir, material);
    if (btf_generate(material, path, &g, &e) != 0 || btf_dataset_open(path, NULL, ds, &e) != 0) {
        fprintf(stderr, "setup: %s\n", e.msg);
        return -1;
    }
    return 0;
}

void tu_rf_tiny_model(btf_rf_model *m, int width, int height)
{
    btf_error e = {0};
    memset(m, 0, sizeof *m);
    btf_dir v[2] = {{0, 0}, {30, 90}}, l[1] = {{45, 0}};
    TU_OK(btf_dirset_from_list(&m->views, v, 2, &e), &e);
    TU_OK(btf_dirset_from_list(&m->lights, l, 1, &e), &e);
    m->fit = BTF_RF_PTM, m->params = 6, m->slots = 9, m->fields = 2;
    m->width = width, m->height = height;
    int planes = m->fields * m->slots, codes = planes * width * height;
    m->lo = calloc((size_t)planes, sizeof(float));
    m->hi = calloc((size_t)planes, sizeof(float));
    m->codes = calloc((size_t)codes, sizeof(uint16_t));
    for (int i = 0; i < planes; i++)
        m->hi[i] = 1.0f;
    for (int i = 0; i < codes; i++)
        m->codes[i] = (uint16_t)(i * 1000);
}

size_t tu_rf_payload(const unsigned char *d, unsigned char *payload, size_t cap)
{
    uLongf plen = cap;
    uint32_t stored = d[22] | d[23] << 8 | d[24] << 16 | (uint32_t)d[25] << 24;
    if (d[17] == 1)
        assert_int_equal(uncompress(payload, &plen, d + 26, stored), Z_OK);
    else
        memcpy(payload, d + 26, stored), plen = stored;
    return plen;
}

unsigned char *tu_model_payload(const unsigned char *d, size_t *n)
{
    size_t raw = d[18] | d[19] << 8 | d[20] << 16 | (size_t)d[21] << 24;
    unsigned char *p = malloc(raw ? raw : 1);
    assert_non_null(p);
    *n = tu_rf_payload(d, p, raw);
    return p;
}

size_t tu_rf_section(const unsigned char *payload, size_t n, const char *tag)
{
    size_t at = 0, found = 0;
    while (at + 8 <= n) {
        size_t len = payload[at + 4] | payload[at + 5] << 8 | payload[at + 6] << 16;
        if (!memcmp(payload + at, tag, 4))
            found = at + 8;
        at += 8 + len;
    }
    return found;
}

/* A stored (not deflated) container of signature sig around a payload,
 * with a correct CRC-32. */
static unsigned char *rewrap(const char *sig, const unsigned char *payload, size_t n, int major,
                             int minor, size_t *size)
{
    unsigned char *out = malloc(26 + n + 4);
    memcpy(out, sig, 11);
    out[11] = (unsigned char)major, out[12] = 0, out[13] = (unsigned char)minor, out[14] = 0,
    out[15] = 26, out[16] = 0, out[17] = 0;
    for (int i = 0; i < 4; i++)
        out[18 + i] = out[22 + i] = (unsigned char)(n >> (8 * i));
    memcpy(out + 26, payload, n);
    uint32_t crc = (uint32_t)crc32(0L, out, (uInt)(26 + n));
    for (int i = 0; i < 4; i++)
        out[26 + n + i] = (unsigned char)(crc >> (8 * i));
    *size = 26 + n + 4;
    return out;
}

unsigned char *tu_rf_rewrap(const unsigned char *payload, size_t n, int major, size_t *size)
{
    return rewrap("\x89" "BTFRFL\r\n\x1a\n", payload, n, major, 0, size);
}

unsigned char *tu_model_rewrap(const unsigned char *payload, size_t n, int minor, size_t *size)
{
    return rewrap("\x89" "BTFCAR\r\n\x1a\n", payload, n, 1, minor, size);
}

void tu_rf_expect_format_error(const unsigned char *d, size_t n, const char *what,
                               btf_rf_model *m, btf_error *e)
{
    int rc = btf_rf_decode(d, n, "bad.rf", m, e);
    if (rc != BTF_E_FORMAT)
        print_error("%s: rc %d, %s\n", what, rc, e->msg);
    assert_int_equal(rc, BTF_E_FORMAT);
    assert_true(strncmp(e->msg, "bad.rf: ", 8) == 0);
    assert_null(m->codes);
}

void tu_rf_expect_damage_fails(unsigned char *d, size_t n, tu_rf_expect_fn expect)
{
    for (size_t k = 0; k < n; k++)
        expect(d, k, "truncated");
    for (size_t k = 0; k < n; k++) {
        d[k] ^= 0x10;
        expect(d, n, "flipped");
        d[k] ^= 0x10;
    }
}
