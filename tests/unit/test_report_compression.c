/*
 * test_report_compression.c — the report's compression accounting
 * (src/report/, docs/report.md): the model file's byte breakdown adds up to the
 * file exactly and each part holds what it says; the deflate bit
 * attribution accounts for every bit of a zlib stream; the per-view PCA
 * finds the rank of data of known rank with no error, stays finite on
 * constant and saturated images and does not depend on the thread count;
 * the JPEG contrast and the raw bytes; bad arguments.
 */
#include "testutil.h"

#include "report/report.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <zlib.h>

static char *dir;
static char gen_dir[4096];
static btf_dataset *gen_ds;
static btf_model gen_model;

/* A generated 81 x 81 leather of 16 x 16 images and a quick model of it. */
static int setup(void **state)
{
    (void)state;
    dir = tu_tmpdir();
    btf_error e = {0};
    btf_generate_opts g = {.size = 16, .seed = 4};
    snprintf(gen_dir, sizeof gen_dir, "%s/leather", dir);
    btf_analyse_opts ao = btf_analyse_defaults();
    ao.segment.subspaces = 3;
    ao.segment.kmeans.seed = 1;
    ao.fit.levels = 2;
    ao.fit.car.max_neighbours = 4;
    ao.range_size = 8;
    if (btf_generate("leather", gen_dir, &g, &e) != 0 ||
        btf_dataset_open(gen_dir, NULL, &gen_ds, &e) != 0 ||
        btf_analyse(gen_ds, &ao, &gen_model, &e) != 0) {
        fprintf(stderr, "setup: %s\n", e.msg);
        return -1;
    }
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    btf_model_free(&gen_model);
    btf_dataset_close(gen_ds);
    tu_rmtree(dir);
    free(dir);
    return 0;
}

static uint64_t sum_parts(const uint64_t *v)
{
    uint64_t s = 0;
    for (int p = 0; p < BTF_MODEL_PART_COUNT; p++)
        s += v[p];
    return s;
}

/* The checks every breakdown passes: the parts add up to the encoder's
 * file and payload; the raw parts have the sizes the format gives them. */
/* LABQ is written when one subspace has a Lab histogram (model_file.c). */
static int has_lab_any(const btf_model *m)
{
    for (int s = 0; s < m->n_subspaces; s++)
        if (m->subspaces[s].marginal.knots && m->subspaces[s].marginal.lab_knots)
            return 1;
    return 0;
}

static void check_breakdown(const btf_model *m, const btf_model_bytes *b)
{
    btf_error e = {0};
    unsigned char *data;
    size_t size;
    TU_OK(btf_model_encode(m, &data, &size, &e), &e);
    free(data);
    assert_int_equal(b->total, size);
    assert_int_equal(sum_parts(b->file), b->total);
    assert_int_equal(sum_parts(b->raw), b->payload);
    assert_int_equal(b->file[BTF_MODEL_PART_CONTAINER], 26 + 4);
    assert_int_equal(b->raw[BTF_MODEL_PART_CONTAINER], 0);
    assert_int_equal(b->raw[BTF_MODEL_PART_DEFLATE], 0);
    if (!b->deflated) {
        assert_int_equal(b->file[BTF_MODEL_PART_DEFLATE], 0);
        for (int p = BTF_MODEL_PART_FRAMING; p < BTF_MODEL_PART_COUNT; p++)
            assert_int_equal(b->file[p], b->raw[p]);
    } else {
        assert_true(b->file[BTF_MODEL_PART_DEFLATE] >= 6); /* zlib header, Adler-32 */
        assert_int_equal(b->total, 30 + (b->total - 30));
    }
    int bands = 0, neighbours = 0, marginals = 0;
    for (int s = 0; s < m->n_subspaces; s++) {
        const btf_subspace_model *sm = &m->subspaces[s];
        bands += 3 * sm->levels;
        for (int k = 0; k < 3; k++)
            for (int l = 0; l < sm->levels; l++)
                neighbours += sm->bands[k][l].n;
        /* MARG: 1 + 3 x (2 + 32) x 4 + 6 x 4 bytes; LABQ: 1 + 3 x 32 x 2 */
        marginals += sm->marginal.knots ? 433 : 1;
        marginals += !has_lab_any(m) ? 0 : sm->marginal.knots && sm->marginal.lab_knots ? 193 : 1;
    }
    assert_int_equal(b->raw[BTF_MODEL_PART_SPECTRAL], 48 * m->n_subspaces);
    assert_int_equal(b->raw[BTF_MODEL_PART_LEVELS], m->n_subspaces);
    assert_int_equal(b->raw[BTF_MODEL_PART_GAMMAS], 4 * neighbours);
    assert_int_equal(b->raw[BTF_MODEL_PART_NEIGHBOURHOODS], bands + 2 * neighbours);
    assert_int_equal(b->raw[BTF_MODEL_PART_SIGMAS], 4 * bands);
    assert_int_equal(b->raw[BTF_MODEL_PART_BAND_MEANS], 4 * bands);
    assert_int_equal(b->raw[BTF_MODEL_PART_INDEX],
                     (uint64_t)m->views.count * (uint64_t)m->lights.count);
    int has_marg = 0;
    for (int s = 0; s < m->n_subspaces; s++)
        has_marg |= m->subspaces[s].marginal.knots != 0;
    assert_int_equal(b->raw[BTF_MODEL_PART_MARGINALS], has_marg ? marginals : 0);
    if (m->range)
        assert_int_equal(b->raw[BTF_MODEL_PART_RANGE],
                         2 + 2 + 4 + 2 + 4 + 2 * m->range_width * m->range_height + 1);
    else
        assert_int_equal(b->raw[BTF_MODEL_PART_RANGE], 0);
    /* Framing: the section headers, the counts, 12 bytes per subspace. */
    int has_lab = 0;
    for (int s = 0; s < m->n_subspaces; s++)
        has_lab |= m->subspaces[s].marginal.knots && m->subspaces[s].marginal.lab_knots;
    int sections = 1 + (m->views.count ? 3 : 0) + (m->range ? 1 : 0) + has_marg + has_lab +
                   (m->albedo ? 1 : 0) + (m->gain ? 1 : 0);
    /* the pair gains: one byte per pair and channel */
    assert_int_equal(b->raw[BTF_MODEL_PART_GAINS],
                     m->gain ? 3 * (uint64_t)m->views.count * (uint64_t)m->lights.count : 0);
    assert_int_equal(b->raw[BTF_MODEL_PART_FRAMING],
                     8 * sections + 2 + (has_marg ? 2 : 0) + (has_lab ? 2 : 0) +
                         12 * m->n_subspaces);
    if (m->views.count)
        assert_int_equal(b->raw[BTF_MODEL_PART_DIRECTIONS],
                         2 * 3 + strlen(m->views.name) + strlen(m->lights.name) +
                             16 * (m->views.count + m->lights.count));
}

static void breakdown_of_an_analysed_model(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_model_bytes b;
    TU_OK(btf__model_byte_breakdown(&gen_model, &b, &e), &e);
    check_breakdown(&gen_model, &b);
    assert_true(b.deflated);
    assert_non_null(gen_model.range);
    static const int present[] = {BTF_MODEL_PART_FRAMING, BTF_MODEL_PART_DIRECTIONS,
                                  BTF_MODEL_PART_INDEX,   BTF_MODEL_PART_SPECTRAL,
                                  BTF_MODEL_PART_GAMMAS,  BTF_MODEL_PART_SIGMAS,
                                  BTF_MODEL_PART_BAND_MEANS, BTF_MODEL_PART_RANGE};
    for (size_t i = 0; i < sizeof present / sizeof *present; i++)
        assert_true(b.file[present[i]] > 0);
    /* Deflate shrinks the regular parts; float32 parts stay near 4 bytes. */
    assert_true(b.file[BTF_MODEL_PART_DIRECTIONS] < b.raw[BTF_MODEL_PART_DIRECTIONS] / 2);
    assert_true(b.file[BTF_MODEL_PART_INDEX] < b.raw[BTF_MODEL_PART_INDEX]);
    for (int p = 0; p < BTF_MODEL_PART_COUNT; p++)
        print_message("%-15s %6llu of %6llu\n", btf__model_part_name(p),
                      (unsigned long long)b.file[p], (unsigned long long)b.raw[p]);
    /* float32 values do not deflate: at most a little over a byte each (a
     * literal's code can pass 8 bits where the other parts, the pair gains'
     * residuals among them, shape the literal table) */
    assert_true(b.file[BTF_MODEL_PART_SPECTRAL] <= b.raw[BTF_MODEL_PART_SPECTRAL] * 9 / 8 + 8);
    /* The same model read back from its file: the same breakdown. */
    unsigned char *data;
    size_t size;
    TU_OK(btf_model_encode(&gen_model, &data, &size, &e), &e);
    btf_model back;
    TU_OK(btf_model_decode(data, size, "m", &back, &e), &e);
    free(data);
    btf_model_bytes b2;
    TU_OK(btf__model_byte_breakdown(&back, &b2, &e), &e);
    assert_memory_equal(&b, &b2, sizeof b);
    btf_model_free(&back);
}

static void breakdown_of_a_texture_model(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image img;
    tu_material_image("fabric", 32, 3, (btf_dir){0, 0}, (btf_dir){30, 40}, &img);
    btf_fit_opts fo = {.levels = 2};
    btf_model m;
    TU_OK(btf_texture_fit(&img, &fo, &m, &e), &e);
    btf_image_free(&img);
    btf_model_bytes b;
    TU_OK(btf__model_byte_breakdown(&m, &b, &e), &e);
    check_breakdown(&m, &b);
    assert_int_equal(b.file[BTF_MODEL_PART_DIRECTIONS], 0);
    assert_int_equal(b.file[BTF_MODEL_PART_INDEX], 0);
    assert_int_equal(b.file[BTF_MODEL_PART_RANGE], 0);
    assert_true(b.file[BTF_MODEL_PART_GAMMAS] > 0);
    btf_model_free(&m);
}

/* A hand-made one-band-per-level model of incompressible floats: a file
 * whose payload is stored, or nearly so; the parts add up either way. */
static void breakdown_of_a_small_model(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_model m = {0};
    btf_subspace_model sm = {0};
    sm.view = sm.light = -1;
    sm.width = sm.height = 8;
    sm.mean[0] = 0.123456f, sm.mean[1] = 0.654321f, sm.mean[2] = 0.31415926f;
    sm.basis[0] = sm.basis[4] = sm.basis[8] = 1;
    sm.levels = 1;
    uint64_t r = 99;
    for (int k = 0; k < 3; k++) {
        btf_car_band *band = &sm.bands[k][0];
        band->sigma = 0.0123f * (k + 1) + 0.000321f;
        band->mean = -0.0456f * (k + 2) + 0.000789f;
        /* Random coefficients (sum of |gamma| < 1: stable) at distinct
         * causal offsets: nothing for deflate to find. */
        band->n = 16;
        for (int i = 0; i < band->n; i++) {
            r = r * 6364136223846793005ULL + 1442695040888963407ULL;
            band->offsets[i].row = (int8_t)(-1 - i);
            band->offsets[i].col = (int8_t)((int)(r >> 60) - 8);
            band->gamma[i] = (float)((double)(r >> 11) / 9007199254740992.0 - 0.5) / 16.0f;
        }
    }
    m.n_subspaces = 1;
    m.subspaces = &sm;
    btf_model_bytes b;
    TU_OK(btf__model_byte_breakdown(&m, &b, &e), &e);
    check_breakdown(&m, &b);
    print_message("small model: %llu bytes, deflated %d\n", (unsigned long long)b.total,
                  b.deflated);
}

/* Every bit of a zlib stream is somebody's: stored, fixed and dynamic
 * blocks; a damaged stream is refused. */
static void deflate_cost_accounts_for_every_bit(void **state)
{
    (void)state;
    size_t n = 20000;
    unsigned char *src = malloc(n), *lab = malloc(n);
    uint64_t r = 12345;
    for (size_t i = 0; i < n; i++) {
        r = r * 6364136223846793005ULL + 1442695040888963407ULL;
        /* Stretches of text-like repetition, of zeros and of noise. */
        src[i] = i < 6000 ? "the quick brown fox "[i % 20] : i < 12000 ? 0 : (unsigned char)(r >> 56);
        lab[i] = (unsigned char)(i / 5000);
    }
    size_t lens[] = {1, 30, 5000, n};
    for (int level = 0; level <= 9; level += 3)
        for (size_t li = 0; li < sizeof lens / sizeof *lens; li++) {
            size_t len = lens[li];
            uLongf zn = compressBound(len);
            unsigned char *z = malloc(zn);
            assert_int_equal(compress2(z, &zn, src, len, level), Z_OK);
            double bits[4] = {0}, over = 0;
            btf_error e = {0};
            TU_OK(btf__deflate_cost(z, zn, src, lab, len, 4, bits, &over, "z", &e), &e);
            double sum = over;
            for (int k = 0; k < 4; k++) {
                assert_true(bits[k] >= 0);
                sum += bits[k];
            }
            assert_true(fabs(sum - 8.0 * zn) < 1e-6);
            assert_true(over >= 48); /* header and Adler-32 */
            if (level == 0)          /* stored: 8 bits a byte */
                assert_true(fabs(bits[0] - 8.0 * (len < 5000 ? len : 5000)) < 1e-9);
            /* Another payload, a damaged stream: refused. */
            unsigned char *other = malloc(len);
            memcpy(other, src, len);
            other[len / 2] ^= 1;
            assert_int_equal(btf__deflate_cost(z, zn, other, lab, len, 4, bits, &over, "z", &e),
                             BTF_E_FORMAT);
            assert_non_null(strstr(e.msg, "z: "));
            assert_int_equal(btf__deflate_cost(z, zn - 5, src, lab, len, 4, bits, &over, "z", &e),
                             BTF_E_FORMAT);
            free(other);
            free(z);
        }
    free(src);
    free(lab);
}

/* ------------------------------------------------- small manifest datasets */

/* Writes a manifest dataset of views x lights PNG images of w x h whose
 * 8-bit sRGB value of channel c at pixel p under (view, light) is
 * value(view, light, p, c) (exr: EXR files instead, see below). Returns
 * the manifest's path (static). */
typedef int (*value_fn)(int view, int light, int p, int c);
static const char *make_manifest(const char *name, int views, int lights, int w, int h,
                                 value_fn value, int exr)
{
    static char path[4096];
    char sub[4096];
    snprintf(sub, sizeof sub, "%s/%s", dir, name);
    mkdir(sub, 0777);
    snprintf(path, sizeof path, "%s/list.tsv", sub);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, "path\ttheta_l\tphi_l\ttheta_v\tphi_v\n");
    btf_error e = {0};
    for (int v = 0; v < views; v++)
        for (int l = 0; l < lights; l++) {
            btf_image img;
            TU_OK(btf_image_alloc(&img, w, h, 3, &e), &e);
            for (int p = 0; p < w * h; p++)
                for (int c = 0; c < 3; c++) {
                    int x = value(v, l, p, c);
                    /* exr 1: x / 50 linear; 2: the level x + 1/2 (not
                     * a whole level: the PCA's float path). */
                    img.data[p * 3 + c] =
                        exr == 1 ? (float)x / 50.0f
                                 : btf__srgb_to_linear(((float)x + (exr == 2 ? 0.5f : 0.0f)) / 255.0f);
                }
            const char *file = tu_fmt("v%d_l%d.%s", v, l, exr ? "exr" : "png");
            if (exr)
                TU_OK(btf_image_write_exr_opts(tu_fmt("%s/%s", sub, file), &img, NULL, NULL, &e),
                      &e);
            else
                TU_OK(btf_image_write_png(tu_fmt("%s/%s", sub, file), &img, &e), &e);
            btf_image_free(&img);
            fprintf(f, "%s\t%d\t%d\t%d\t0\n", file, 20 + 10 * (l % 5), 60 * l, 25 * v);
        }
    assert_int_equal(fclose(f), 0);
    return path;
}

/* Rank 2 after centring: 100 + a(light) P1 + b(light) P2, integers. */
static int pattern(int seed, int p, int c)
{
    unsigned x = (unsigned)(seed * 7919 + p * 31 + c * 17);
    x ^= x >> 7;
    x *= 2654435761u;
    return (int)((x >> 20) % 21) - 10;
}

static int rank2(int view, int light, int p, int c)
{
    static const int a[6] = {-4, 3, 0, 2, -1, 4}, b[6] = {1, -3, 4, 0, -4, 2};
    return 100 + a[(light + view) % 6] * pattern(1 + view, p, c) +
           b[light % 6] * pattern(5 + view, p, c);
}

static void pca_finds_known_rank(void **state)
{
    (void)state;
    btf_error e = {0};
    const char *mf = make_manifest("rank2", 2, 6, 8, 6, rank2, 0);
    btf_dataset *ds;
    TU_OK(btf_dataset_open(mf, NULL, &ds, &e), &e);
    btf_pca_result r, r1;
    btf_pca_opts o = {.threads = 2};
    TU_OK(btf__pca_contrast(ds, &o, &r, &e), &e);
    assert_int_equal(r.views, 2);
    assert_int_equal(r.lights, 6);
    for (int v = 0; v < 2; v++) {
        print_message("view %d: c %d, RMS %g\n", v, r.components[v], r.view_rms[v]);
        assert_int_equal(r.components[v], 2);
        assert_true(r.view_rms[v] < 1e-3);
    }
    assert_int_equal(r.min_components, 2);
    assert_int_equal(r.max_components, 2);
    assert_true(r.mean_components == 2.0);
    assert_true(r.rms < 1e-3);
    size_t d = 8 * 6 * 3;
    assert_int_equal(r.bytes, 2 * ((d * 3 + 6 * 2) * 16 / 8));
    assert_int_equal(r.raw.raw, 2 * 6 * d);
    assert_true(fabs(r.ratio - (double)r.raw.raw / (double)r.bytes) < 1e-12);
    assert_true(r.seconds >= 0 && isfinite(r.seconds));
    /* One thread: the same numbers. */
    o.threads = 1;
    TU_OK(btf__pca_contrast(ds, &o, &r1, &e), &e);
    assert_memory_equal(r.components, r1.components, 2 * sizeof *r.components);
    assert_memory_equal(r.view_rms, r1.view_rms, 2 * sizeof *r.view_rms);
    btf__pca_result_free(&r1);
    /* Capped at one component: the cap, and an error above the target. */
    o.max_components = 1;
    TU_OK(btf__pca_contrast(ds, &o, &r1, &e), &e);
    assert_int_equal(r1.components[0], 1);
    assert_true(r1.view_rms[0] > 2.0 && isfinite(r1.view_rms[0]));
    btf__pca_result_free(&r1);
    /* 8 bits a value: half the bytes (rounded up per view). */
    o = (btf_pca_opts){.bits = 8};
    TU_OK(btf__pca_contrast(ds, &o, &r1, &e), &e);
    assert_int_equal(r1.bytes, 2 * (d * 3 + 6 * 2));
    btf__pca_result_free(&r1);
    btf__pca_result_free(&r);
    btf__pca_result_free(&r); /* twice: harmless */
    btf_dataset_close(ds);

    /* Levels between whole ones (float EXR): the same rank, a float-sized error. */
    mf = make_manifest("rank2_exr", 2, 6, 8, 6, rank2, 2);
    TU_OK(btf_dataset_open(mf, NULL, &ds, &e), &e);
    TU_OK(btf__pca_contrast(ds, NULL, &r, &e), &e);
    for (int v = 0; v < 2; v++) {
        print_message("EXR view %d: c %d, RMS %g\n", v, r.components[v], r.view_rms[v]);
        assert_int_equal(r.components[v], 2);
        assert_true(r.view_rms[v] < 1e-3);
    }
    btf__pca_result_free(&r);
    btf_dataset_close(ds);
}

static int constant(int view, int light, int p, int c)
{
    (void)view, (void)light, (void)p, (void)c;
    return 77;
}

/* Half the lights far above 1 (255 once encoded), half black. */
static int saturated(int view, int light, int p, int c)
{
    (void)view, (void)p, (void)c;
    return light % 2 ? 500 : 0;
}

static void pca_constant_and_saturated_images(void **state)
{
    (void)state;
    btf_error e = {0};
    const char *names[2] = {"constant", "saturated"};
    value_fn fns[2] = {constant, saturated};
    for (int i = 0; i < 2; i++) {
        const char *mf = make_manifest(names[i], 2, 4, 5, 5, fns[i], i == 1);
        btf_dataset *ds;
        TU_OK(btf_dataset_open(mf, NULL, &ds, &e), &e);
        btf_pca_result r;
        TU_OK(btf__pca_contrast(ds, NULL, &r, &e), &e);
        for (int v = 0; v < 2; v++) {
            assert_int_equal(r.components[v], i == 0 ? 0 : 1);
            assert_true(isfinite(r.view_rms[v]) && r.view_rms[v] < 1e-3);
        }
        assert_true(isfinite(r.rms) && isfinite(r.ratio) && r.ratio > 0);
        btf__pca_result_free(&r);
        btf_dataset_close(ds);
    }
}

static void pca_defaults_equal_zero(void **state)
{
    (void)state;
    btf_pca_opts d = btf_pca_defaults(), z = {0};
    assert_true(d.max_rms == 2.0);
    assert_int_equal(d.bits, 16);
    assert_int_equal(d.max_components, 0);
    assert_int_equal(d.threads, 0);
    assert_null(d.progress);
    btf_error e = {0};
    btf_pca_result a, b, c;
    const char *mf = make_manifest("defaults", 1, 3, 4, 4, rank2, 0);
    btf_dataset *ds;
    TU_OK(btf_dataset_open(mf, NULL, &ds, &e), &e);
    TU_OK(btf__pca_contrast(ds, &d, &a, &e), &e);
    TU_OK(btf__pca_contrast(ds, &z, &b, &e), &e);
    TU_OK(btf__pca_contrast(ds, NULL, &c, &e), &e);
    assert_int_equal(a.components[0], b.components[0]);
    assert_int_equal(a.components[0], c.components[0]);
    assert_int_equal(a.bytes, b.bytes);
    assert_int_equal(a.bytes, c.bytes);
    btf__pca_result_free(&a);
    btf__pca_result_free(&b);
    btf__pca_result_free(&c);
    btf_dataset_close(ds);
}

static int progress_calls;
static void count_progress(void *user, double f, const char *what)
{
    (void)user;
    assert_true(f >= 0 && f <= 1 && what);
    progress_calls++;
}

static void pca_and_jpeg_on_a_generated_dataset(void **state)
{
    (void)state;
    btf_error e = {0};
    const btf_dataset_info *info = btf_dataset_get_info(gen_ds);
    btf_raw_bytes raw;
    TU_OK(btf__dataset_raw_bytes(gen_ds, &raw, &e), &e);
    assert_int_equal(raw.raw, 81ull * 81 * 16 * 16 * 3);
    assert_int_equal(raw.on_disk, info->bytes_on_disk);
    assert_int_equal(raw.views, 81);
    assert_int_equal(raw.width, 16);

    btf_pca_opts o = {.progress = count_progress};
    btf_pca_result r;
    progress_calls = 0;
    TU_OK(btf__pca_contrast(gen_ds, &o, &r, &e), &e);
    assert_true(progress_calls > 0);
    assert_true(r.min_components >= 1 && r.max_components <= 81);
    assert_true(r.rms <= 2.0 && r.rms > 0);
    for (int v = 0; v < 81; v++)
        assert_true(r.view_rms[v] <= 2.0);
    assert_memory_equal(&r.raw, &raw, sizeof raw);
    print_message("PCA: c %d..%d (mean %.2f), RMS %.3f, %llu bytes, 1 : %.2f, %.2f s\n",
                  r.min_components, r.max_components, r.mean_components, r.rms,
                  (unsigned long long)r.bytes, r.ratio, r.seconds);
    btf__pca_result_free(&r);

    btf_jpeg_contrast j;
    TU_OK(btf__jpeg_subspace_contrast(gen_ds, &gen_model, 0, &j, &e), &e);
    assert_int_equal(j.images, gen_model.n_subspaces);
    assert_int_equal(j.quality, 90);
    assert_int_equal(j.index_bytes, 81 * 81);
    assert_int_equal(j.bytes, j.jpeg_bytes + j.index_bytes);
    assert_true(j.jpeg_bytes > 100 * (uint64_t)j.images); /* headers and tables alone */
    assert_true(isfinite(j.rms) && j.rms > 0 && j.rms < 20);
    assert_true(fabs(j.ratio - (double)raw.raw / (double)j.bytes) < 1e-9);
    /* A lower quality: fewer bytes. */
    btf_jpeg_contrast j50;
    TU_OK(btf__jpeg_subspace_contrast(gen_ds, &gen_model, 50, &j50, &e), &e);
    assert_true(j50.jpeg_bytes < j.jpeg_bytes);
}

static void bad_arguments(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_model_bytes b;
    assert_int_equal(btf__model_byte_breakdown(NULL, &b, &e), BTF_E_ARG);
    assert_int_equal(btf__model_byte_breakdown(&gen_model, NULL, &e), BTF_E_ARG);
    btf_model empty = {0};
    assert_int_equal(btf__model_byte_breakdown(&empty, &b, &e), BTF_E_DATA);
    assert_non_null(strstr(e.msg, "model"));
    assert_null(strchr(e.msg, '\n'));

    btf_raw_bytes raw;
    assert_int_equal(btf__dataset_raw_bytes(NULL, &raw, &e), BTF_E_ARG);
    assert_int_equal(btf__dataset_raw_bytes(gen_ds, NULL, &e), BTF_E_ARG);

    btf_pca_result r;
    assert_int_equal(btf__pca_contrast(NULL, NULL, &r, &e), BTF_E_ARG);
    assert_int_equal(btf__pca_contrast(gen_ds, NULL, NULL, &e), BTF_E_ARG);
    btf_pca_opts bad[] = {{.max_rms = -1},      {.max_rms = NAN}, {.max_rms = INFINITY},
                          {.bits = 33},         {.bits = -1},     {.max_components = 82},
                          {.max_components = -1}, {.threads = -2}};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        e.msg[0] = 0;
        assert_int_equal(btf__pca_contrast(gen_ds, &bad[i], &r, &e), BTF_E_ARG);
        assert_non_null(strstr(e.msg, gen_dir));
        assert_null(r.components);
    }

    btf_jpeg_contrast j;
    assert_int_equal(btf__jpeg_subspace_contrast(gen_ds, &gen_model, 0, NULL, &e), BTF_E_ARG);
    assert_int_equal(btf__jpeg_subspace_contrast(NULL, &gen_model, 0, &j, &e), BTF_E_ARG);
    assert_int_equal(btf__jpeg_subspace_contrast(gen_ds, NULL, 0, &j, &e), BTF_E_ARG);
    assert_int_equal(btf__jpeg_subspace_contrast(gen_ds, &gen_model, 101, &j, &e), BTF_E_ARG);
    assert_int_equal(btf__jpeg_subspace_contrast(gen_ds, &gen_model, -5, &j, &e), BTF_E_ARG);
    /* A texture model, a model of another dataset: BTF_E_DATA. */
    btf_subspace_model sm = gen_model.subspaces[0];
    btf_model tex = {.n_subspaces = 1, .subspaces = &sm};
    assert_int_equal(btf__jpeg_subspace_contrast(gen_ds, &tex, 0, &j, &e), BTF_E_DATA);
    assert_non_null(strstr(e.msg, gen_dir));
    btf_model other = gen_model;
    btf_subspace_model subs[256];
    memcpy(subs, gen_model.subspaces, (size_t)gen_model.n_subspaces * sizeof *subs);
    other.subspaces = subs;
    subs[0].view = 81;
    assert_int_equal(btf__jpeg_subspace_contrast(gen_ds, &other, 0, &j, &e), BTF_E_DATA);
    assert_non_null(strstr(e.msg, "subspace 0"));

    /* Part names. */
    for (int p = 0; p < BTF_MODEL_PART_COUNT; p++) {
        assert_true(strlen(btf__model_part_name(p)) > 0);
        for (int q = 0; q < p; q++)
            assert_string_not_equal(btf__model_part_name(p), btf__model_part_name(q));
    }
    assert_string_equal(btf__model_part_name(-1), "?");
    assert_string_equal(btf__model_part_name(BTF_MODEL_PART_COUNT), "?");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(breakdown_of_an_analysed_model),
        cmocka_unit_test(breakdown_of_a_texture_model),
        cmocka_unit_test(breakdown_of_a_small_model),
        cmocka_unit_test(deflate_cost_accounts_for_every_bit),
        cmocka_unit_test(pca_finds_known_rank),
        cmocka_unit_test(pca_constant_and_saturated_images),
        cmocka_unit_test(pca_defaults_equal_zero),
        cmocka_unit_test(pca_and_jpeg_on_a_generated_dataset),
        cmocka_unit_test(bad_arguments),
    };
    return cmocka_run_group_tests_name("report_compression", tests, setup, teardown);
}
