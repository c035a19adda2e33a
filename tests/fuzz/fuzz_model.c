/*
 * fuzz_model.c — libFuzzer target for the model decoders: the CAR model's
 * (src/model/model_file.c, docs/model-format.md) and the reflectance-field
 * model's (src/rf/rf_file.c, docs/rf.md, "File", with the coordinate map
 * of a sampled model, RFMP, format 2). A decoder must never crash, leak or
 * read out of bounds; a failure must be BTF_E_FORMAT (or BTF_E_NOMEM) with
 * one line naming the input, and leave the model empty. Whatever it accepts
 * must re-encode, and decode(encode(m)) must be m, field for field, with
 * encode(decode(encode(m))) the same bytes; an accepted reflectance-field
 * model is also evaluated (a small flat render through its map), so that a
 * map the decoder let through cannot send a lookup out of the codes.
 *
 * Two kinds of input, told apart by the first byte:
 *  - 0x89 (how every model file starts): the input is a whole file, so the
 *    signature, version, sizes, CRC and zlib checks are exercised (a
 *    reflectance-field file, told by its signature, goes to its decoder);
 *  - anything else: the rest of the input is a payload (the sections), put
 *    in a container with a correct CRC (stored when bit 0 of the byte is
 *    clear, deflated when set; bit 1 set: a reflectance-field container, of
 *    format 2 when bit 2 is set, else 1), so that mutations reach the
 *    section parser and the validator instead of all dying at the CRC.
 *
 * Build from the repository root (`make fuzz-build` does this for every
 * tests/fuzz/fuzz_*.c, library sources instrumented too):
 *
 *   mkdir -p build-fuzz
 *   clang++ -std=c++17 -g -O1 -fsanitize=fuzzer-no-link,address,undefined \
 *       -Iinclude -Isrc -I/usr/include/opencv4 -c src/io/cv_bridge.cpp -o build-fuzz/cv_bridge.o
 *   clang -std=c11 -g -O1 -fsanitize=fuzzer,address,undefined -ffp-contract=off \
 *       -Iinclude -Isrc -Igpu -Ibuild/gen -I/usr/include/OpenEXR -D_DEFAULT_SOURCE \
 *       -c tests/fuzz/fuzz_model.c -o build-fuzz/fuzz_model.o
 *   clang -std=c11 -g -O1 -fsanitize=fuzzer-no-link,address,undefined -ffp-contract=off \
 *       -Iinclude -Isrc -Igpu -Ibuild/gen -I/usr/include/OpenEXR -D_DEFAULT_SOURCE \
 *       -c src/model/model_file.c ...   (each library source, one object each)
 *   clang++ -fsanitize=fuzzer,address,undefined -o build-fuzz/fuzz_model \
 *       build-fuzz/fuzz_model.o build-fuzz/<library objects> build-fuzz/cv_bridge.o \
 *       -lopencv_imgcodecs -lopencv_imgproc -lopencv_core -lOpenEXRCore-3_1 \
 *       -lvulkan -lz -lm -lpthread
 *
 * Run with the seed corpus as a second, read-only corpus folder (as
 * tests/fuzz/fuzz.sh does; new inputs go to the first):
 *
 *   ./build-fuzz/fuzz_model -max_total_time=60 build-fuzz/corpus/fuzz_model \
 *       tests/fuzz/corpus/fuzz_model
 *
 * Seeds: built with -DFUZZ_MODEL_SEEDS (and without -fsanitize=fuzzer) this
 * file is a program that writes small valid inputs of both kinds:
 *
 *   cc -std=c11 -DFUZZ_MODEL_SEEDS -D_DEFAULT_SOURCE -Iinclude -Isrc -o /tmp/seeds \
 *       tests/fuzz/fuzz_model.c build/libbtfcar.a <the Makefile's LDLIBS>
 *   /tmp/seeds tests/fuzz/corpus/fuzz_model
 */
#include "btfcar.h"
#include "model/model.h" /* the periodic cells (btf__model_cells) */
#include "rf/rf_render.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "fuzz_container.h"

static int dirsets_equal(const btf_dirset *a, const btf_dirset *b)
{
    return a->count == b->count && !memcmp(a->name, b->name, sizeof a->name) &&
           (a->count == 0 || !memcmp(a->dirs, b->dirs, sizeof *a->dirs * (size_t)a->count));
}

/* Field for field, bit for bit (the decoder zero-fills unused slots, so
 * whole structs compare). */
static int models_equal(const btf_model *a, const btf_model *b)
{
    if (!dirsets_equal(&a->views, &b->views) || !dirsets_equal(&a->lights, &b->lights))
        return 0;
    if (a->n_subspaces != b->n_subspaces || !a->index != !b->index)
        return 0;
    size_t ni = (size_t)a->views.count * a->lights.count;
    if (a->index && memcmp(a->index, b->index, ni))
        return 0;
    if (memcmp(a->subspaces, b->subspaces, sizeof *a->subspaces * (size_t)a->n_subspaces))
        return 0;
    if (a->range_width != b->range_width || a->range_height != b->range_height ||
        memcmp(&a->range_texel, &b->range_texel, sizeof a->range_texel) || !a->range != !b->range)
        return 0;
    size_t nr = (size_t)a->range_width * a->range_height;
    if (a->range && memcmp(a->range, b->range, sizeof *a->range * nr))
        return 0;
    /* the structure layer (STRC, its flags and colour layer) and the pair
     * gains (GAIN) of format 1.4 and 1.5 */
    if (!a->albedo != !b->albedo || !a->chroma != !b->chroma || !a->gain != !b->gain ||
        a->shadows != b->shadows || memcmp(&a->ambient, &b->ambient, sizeof a->ambient))
        return 0;
    if (a->albedo && memcmp(a->albedo, b->albedo, sizeof *a->albedo * nr))
        return 0;
    if (a->chroma && memcmp(a->chroma, b->chroma, sizeof *a->chroma * 3 * nr))
        return 0;
    if (a->gain && memcmp(a->gain, b->gain, sizeof *a->gain * 3 * ni))
        return 0;
    /* the periodic cells (CELL, format 1.7), kept in the private part */
    const btf_cells *ca = btf__model_cells(a), *cb = btf__model_cells(b);
    if (!ca != !cb)
        return 0;
    return !ca || (ca->w == cb->w && ca->h == cb->h && ca->shift == cb->shift &&
                   ca->n_subspaces == cb->n_subspaces &&
                   !memcmp(ca->kept, cb->kept, (size_t)ca->n_subspaces) &&
                   !memcmp(ca->value, cb->value,
                           sizeof *ca->value * 3 * (size_t)ca->w * ca->h * ca->n_subspaces));
}

static int model_empty(const btf_model *m)
{
    return !m->views.dirs && !m->lights.dirs && !m->index && !m->subspaces && !m->range &&
           !m->albedo && !m->chroma && !m->gain && m->n_subspaces == 0 && m->views.count == 0 && m->lights.count == 0;
}

/* Failures are BTF_E_FORMAT (or out of memory), one line naming the input. */
static void check_failure(int rc, const btf_error *e, const btf_model *m)
{
    if ((rc != BTF_E_FORMAT && rc != BTF_E_NOMEM) || e->code != rc)
        abort();
    if (strncmp(e->msg, "fuzz: ", 6) != 0 || strchr(e->msg, '\n') || !model_empty(m))
        abort();
    if (rc == BTF_E_FORMAT && !strstr(e->msg, "(expected"))
        abort();
}

/* What the decoder accepted must survive encode -> decode unchanged, and
 * re-encode to the same bytes. */
static void check_round_trip(const btf_model *m)
{
    btf_error e = {0};
    unsigned char *d1 = NULL, *d2 = NULL;
    size_t n1, n2;
    if (btf_model_encode(m, &d1, &n1, &e) != 0)
        abort();
    btf_model r;
    if (btf_model_decode(d1, n1, "fuzz", &r, &e) != 0)
        abort();
    if (!models_equal(m, &r))
        abort();
    if (btf_model_encode(&r, &d2, &n2, &e) != 0 || n1 != n2 || memcmp(d1, d2, n1))
        abort();
    btf_model_free(&r);
    free(d1);
    free(d2);
}

/* ------------------------------------------------ reflectance fields */

static const unsigned char RF_SIG[11] = {0x89, 'B', 'T', 'F', 'R', 'F', 'L', '\r', '\n', 0x1a,
                                         '\n'};

/* The reflectance-field container (major 1 or 2) around a payload. */
static unsigned char *wrap_rf(const unsigned char *payload, size_t n, int deflate, int major,
                              size_t *size)
{
    unsigned char *f = wrap(payload, n, deflate, size);
    memcpy(f, RF_SIG, 11);
    f[11] = (unsigned char)major;
    size_t end = *size - 4;
    put_u32(f + end, (uint32_t)crc32(0L, f, (uInt)end));
    return f;
}

static int rf_models_equal(const btf_rf_model *a, const btf_rf_model *b)
{
    if (!dirsets_equal(&a->views, &b->views) || !dirsets_equal(&a->lights, &b->lights) ||
        a->fit != b->fit || a->lobes != b->lobes || a->width != b->width ||
        a->height != b->height || a->params != b->params || a->slots != b->slots ||
        a->fields != b->fields || !a->map != !b->map)
        return 0;
    size_t planes = (size_t)a->fields * a->slots, texels = (size_t)a->width * a->height;
    if (memcmp(a->lo, b->lo, planes * sizeof(float)) || memcmp(a->hi, b->hi, planes * sizeof(float)) ||
        memcmp(a->codes, b->codes, planes * texels * sizeof(uint16_t)))
        return 0;
    if (!a->map)
        return 1;
    return a->surface_width == b->surface_width && a->surface_height == b->surface_height &&
           a->sample_x == b->sample_x && a->sample_y == b->sample_y &&
           !memcmp(a->map, b->map, (size_t)a->surface_width * a->surface_height * 4);
}

static int rf_model_empty(const btf_rf_model *m)
{
    return !m->views.dirs && !m->lights.dirs && !m->lo && !m->hi && !m->codes && !m->map;
}

static void run_rf_one(const unsigned char *data, size_t size)
{
    btf_rf_model m;
    btf_error e = {0};
    int rc = btf_rf_decode(data, size, "fuzz", &m, &e);
    if (rc != 0) {
        if ((rc != BTF_E_FORMAT && rc != BTF_E_NOMEM) || e.code != rc ||
            strncmp(e.msg, "fuzz: ", 6) != 0 || strchr(e.msg, '\n') || !rf_model_empty(&m) ||
            (rc == BTF_E_FORMAT && !strstr(e.msg, "(expected")))
            abort();
        return;
    }
    unsigned char *d1 = NULL, *d2 = NULL;
    size_t n1, n2;
    btf_rf_model r;
    if (btf_rf_encode(&m, &d1, &n1, &e) != 0 || btf_rf_decode(d1, n1, "fuzz", &r, &e) != 0 ||
        !rf_models_equal(&m, &r) || btf_rf_encode(&r, &d2, &n2, &e) != 0 || n1 != n2 ||
        memcmp(d1, d2, n1))
        abort();
    /* every evaluation path reads the codes through the map */
    btf_image img;
    if (btf__rf_render_flat(&m, m.views.dirs[0], m.lights.dirs[0], 5, 3, 1, &img, &e) != 0)
        abort();
    for (int i = 0; i < 5 * 3 * 3; i++)
        if (!isfinite(img.data[i]))
            abort();
    btf_image_free(&img);
    float rgb[3];
    btf__rf_eval(&m, m.views.dirs[m.views.count - 1], m.lights.dirs[0], -7, 1 << 20, rgb);
    btf_rf_model_free(&r);
    btf_rf_model_free(&m);
    free(d1);
    free(d2);
}

static void run_one(const unsigned char *data, size_t size)
{
    btf_model m;
    btf_error e = {0};
    int rc = btf_model_decode(data, size, "fuzz", &m, &e);
    if (rc != 0) {
        check_failure(rc, &e, &m);
        return;
    }
    check_round_trip(&m);
    btf_model_free(&m);
}

#ifndef FUZZ_MODEL_SEEDS

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size > 0 && data[0] != 0x89) {
        size_t n;
        int rf = data[0] & 2;
        unsigned char *f = rf ? wrap_rf(data + 1, size - 1, data[0] & 1, data[0] & 4 ? 2 : 1, &n)
                              : wrap(data + 1, size - 1, data[0] & 1, &n);
        if (rf)
            run_rf_one(f, n);
        else
            run_one(f, n);
        free(f);
        return 0;
    }
    /* A copy of exactly size bytes, so that ASan sees any over-read. */
    unsigned char *copy = malloc(size ? size : 1);
    if (!copy)
        abort();
    if (size)
        memcpy(copy, data, size);
    if (btf__rf_sniff(copy, size))
        run_rf_one(copy, size);
    else
        run_one(copy, size);
    free(copy);
    return 0;
}

#else /* the seed writer */

static btf_offset causal[] = {{0, -1}, {-1, 0}, {-1, -1}, {-1, 1}, {0, -2}, {-2, 0}};

static void small_model(btf_model *m, int directions, int range)
{
    btf_error e = {0};
    memset(m, 0, sizeof *m);
    if (directions) {
        btf_dir v[3] = {{0, 0}, {30, 0}, {30, 180}}, l[2] = {{0, 0}, {45, 90}};
        if (btf_dirset_from_list(&m->views, v, 3, &e) || btf_dirset_from_list(&m->lights, l, 2, &e))
            exit(1);
    }
    m->n_subspaces = 2;
    if (directions) {
        m->index = malloc(6);
        for (int i = 0; i < 6; i++)
            m->index[i] = (uint8_t)(i & 1);
    }
    m->subspaces = calloc(2, sizeof *m->subspaces);
    for (int s = 0; s < 2; s++) {
        btf_subspace_model *sm = &m->subspaces[s];
        sm->view = directions ? s : -1;
        sm->light = directions ? 1 - s : -1;
        sm->width = 64;
        sm->height = 48;
        sm->mean[0] = 0.25f, sm->mean[1] = 0.5f, sm->mean[2] = 0.125f;
        /* An orthonormal basis: a rotation about z by 90 degrees. */
        sm->basis[1] = 1.0f, sm->basis[3] = -1.0f, sm->basis[8] = 1.0f;
        sm->levels = 2;
        for (int b = 0; b < 3; b++)
            for (int l = 0; l < 2; l++) {
                btf_car_band *cb = &sm->bands[b][l];
                cb->n = 1 + (b + l + s) % 6;
                for (int i = 0; i < cb->n; i++) {
                    cb->offsets[i] = causal[i];
                    cb->gamma[i] = 0.1f * (float)(i + 1) - 0.2f;
                }
                cb->sigma = 0.01f * (float)(b + 1);
                cb->mean = b == 0 ? 0.002f : 0.0f;
            }
    }
    if (range) {
        m->range_width = 5;
        m->range_height = 4;
        m->range_texel = 2.0f;
        m->range = malloc(20 * sizeof(float));
        for (int i = 0; i < 20; i++)
            m->range[i] = 0.3f * (float)(i % 5) - 0.1f * (float)(i / 5);
    }
}

static void write_file(const char *dir, const char *name, const unsigned char *p, size_t n)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(p, 1, n, f) != n || fclose(f) != 0) {
        fprintf(stderr, "%s: cannot write\n", path);
        exit(1);
    }
}

/* The file itself, and (prefixed by the mode byte 0) its payload. */
static void write_seeds(const char *dir, const char *name, const btf_model *m)
{
    btf_error e = {0};
    unsigned char *d;
    size_t n;
    if (btf_model_encode(m, &d, &n, &e)) {
        fprintf(stderr, "%s\n", e.msg);
        exit(1);
    }
    char fname[256];
    snprintf(fname, sizeof fname, "%s.btfcar", name);
    write_file(dir, fname, d, n);
    uLongf raw = d[18] | d[19] << 8 | d[20] << 16 | (uLongf)d[21] << 24;
    unsigned char *p = malloc(raw + 1);
    p[0] = 0;
    if (d[17] == 1) {
        if (uncompress(p + 1, &raw, d + 26, (uLong)(n - 30)) != Z_OK)
            exit(1);
    } else {
        memcpy(p + 1, d + 26, raw);
    }
    snprintf(fname, sizeof fname, "%s.payload", name);
    write_file(dir, fname, p, raw + 1);
    /* Both seeds must pass the target's own checks. */
    size_t wn;
    unsigned char *w = wrap(p + 1, raw, 0, &wn);
    btf_model r;
    if (btf_model_decode(w, wn, "seed", &r, &e)) {
        fprintf(stderr, "%s\n", e.msg);
        exit(1);
    }
    btf_model_free(&r);
    run_one(w, wn);
    run_one(d, n);
    free(w);
    free(p);
    free(d);
}

/* A small reflectance-field model: 2 views, 2 lights, a 3 x 2 sample of
 * lobes; with a 5 x 4 coordinate map when sampled (format 2). */
static void small_rf(btf_rf_model *m, int sampled)
{
    btf_error e = {0};
    memset(m, 0, sizeof *m);
    btf_dir v[2] = {{0, 0}, {30, 90}}, l[2] = {{0, 0}, {45, 90}};
    if (btf_dirset_from_list(&m->views, v, 2, &e) || btf_dirset_from_list(&m->lights, l, 2, &e))
        exit(1);
    m->fit = BTF_RF_LOBES, m->lobes = 1, m->params = 4, m->slots = 7, m->fields = 2;
    m->width = 3, m->height = 2;
    m->lo = calloc(14, sizeof(float));
    m->hi = calloc(14, sizeof(float));
    m->codes = calloc(2 * 6 * 7, sizeof(uint16_t));
    for (int i = 0; i < 14; i++)
        m->lo[i] = -0.5f * (float)(i % 3), m->hi[i] = 1.0f + (float)(i % 4);
    for (int i = 0; i < 2 * 6 * 7; i++)
        m->codes[i] = (uint16_t)(i * 777);
    if (sampled) {
        m->surface_width = 5, m->surface_height = 4, m->sample_x = 1, m->sample_y = 2;
        m->map = malloc(5 * 4 * 2 * sizeof(uint16_t));
        for (int t = 0; t < 20; t++)
            m->map[2 * t] = (uint16_t)((t * 7) % 3), m->map[2 * t + 1] = (uint16_t)((t / 5) % 2);
    }
}

/* The file itself, and (prefixed by its mode byte) its payload. */
static void write_rf_seeds(const char *dir, const char *name, const btf_rf_model *m)
{
    btf_error e = {0};
    unsigned char *d;
    size_t n;
    if (btf_rf_encode(m, &d, &n, &e)) {
        fprintf(stderr, "%s\n", e.msg);
        exit(1);
    }
    char fname[256];
    snprintf(fname, sizeof fname, "%s.btfcar", name);
    write_file(dir, fname, d, n);
    uLongf raw = d[18] | d[19] << 8 | d[20] << 16 | (uLongf)d[21] << 24;
    unsigned char *p = malloc(raw + 1);
    p[0] = (unsigned char)(2 | (m->map ? 4 : 0));
    if (d[17] == 1) {
        if (uncompress(p + 1, &raw, d + 26, (uLong)(n - 30)) != Z_OK)
            exit(1);
    } else {
        memcpy(p + 1, d + 26, raw);
    }
    snprintf(fname, sizeof fname, "%s.payload", name);
    write_file(dir, fname, p, raw + 1);
    size_t wn;
    unsigned char *w = wrap_rf(p + 1, raw, 0, m->map ? 2 : 1, &wn);
    btf_rf_model r;
    if (btf_rf_decode(w, wn, "seed", &r, &e)) {
        fprintf(stderr, "%s\n", e.msg);
        exit(1);
    }
    btf_rf_model_free(&r);
    run_rf_one(w, wn);
    run_rf_one(d, n);
    free(w);
    free(p);
    free(d);
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: %s DIR\n", argv[0]);
        return 2;
    }
    btf_model m;
    small_model(&m, 1, 1);
    write_seeds(argv[1], "full", &m);
    btf_model_free(&m);
    small_model(&m, 0, 0);
    write_seeds(argv[1], "texture", &m);
    btf_model_free(&m);
    small_model(&m, 0, 1);
    write_seeds(argv[1], "texture-range", &m);
    btf_model_free(&m);
    /* format 1.2: a marginal transfer on subspace 0 (MARG), none on 1 */
    small_model(&m, 1, 1);
    btf_marginal *mg = &m.subspaces[0].marginal;
    mg->knots = BTF_MARGIN_KNOTS;
    for (int b = 0; b < 3; b++) {
        mg->synth_mean[b] = 0.01f * (float)b;
        mg->synth_sd[b] = 0.1f / (float)(b + 1);
        for (int j = 0; j < BTF_MARGIN_KNOTS; j++)
            mg->quantile[b][j] = -0.2f + 0.4f * (float)(j * j) / (float)(31 * 31);
    }
    for (int k = 0; k < 3; k++)
        mg->rgb_lo[k] = 0.0f, mg->rgb_hi[k] = 0.75f;
    write_seeds(argv[1], "marginals", &m);
    /* format 1.3: and the exemplar's Lab histogram (LABQ), values a 16-bit
     * code holds exactly as the decoder computes them */
    mg->lab_knots = BTF_MARGIN_KNOTS;
    for (int c = 0; c < 3; c++)
        for (int j = 0; j < BTF_MARGIN_KNOTS; j++) {
            double low = c == 0 ? 0.0 : -128.0, span = c == 0 ? 100.0 : 256.0;
            mg->lab_quantile[c][j] = (float)(low + span * (double)(20000 + 700 * j) / 65535.0);
        }
    write_seeds(argv[1], "lab", &m);
    btf_model_free(&m);
    /* format 1.7: a structure layer (STRC) with periodic cells (CELL) for
     * subspace 1 of 2 */
    small_model(&m, 1, 1);
    m.range_width = m.range_height = 8;
    m.range_texel = 1.0f;
    free(m.range);
    m.range = calloc(64, sizeof(float));
    m.albedo = malloc(64 * sizeof(float));
    for (int i = 0; i < 64; i++)
        m.albedo[i] = btf__albedo_value(120u + (unsigned)(i % 9));
    btf_error ce = {0};
    btf_cells *cells = btf__cells_new(4, 2, 1, 2, &ce);
    if (!cells)
        exit(1);
    cells->kept[1] = 1;
    for (int i = 0; i < 24; i++)
        cells->value[24 + i] = btf__albedo_value(112u + (unsigned)((i * 7) % 33));
    if (btf__model_set_cells(&m, cells, &ce))
        exit(1);
    write_seeds(argv[1], "cells-1.7", &m);
    btf_model_free(&m);
    /* reflectance fields: format 1.0, and a sampled model (format 2.0, RFMP) */
    btf_rf_model rm;
    small_rf(&rm, 0);
    write_rf_seeds(argv[1], "rf", &rm);
    btf_rf_model_free(&rm);
    small_rf(&rm, 1);
    write_rf_seeds(argv[1], "rf-sampled", &rm);
    btf_rf_model_free(&rm);
    return 0;
}

#endif
