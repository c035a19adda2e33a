/*
 * fuzz_synth.c — libFuzzer target for the model -> synthesis path: whatever
 * model the decoder (src/model/model_file.c) and its validator accept must
 * synthesise (src/synth/, CPU) without crashing, and every value of a
 * synthesis that reports success must be finite. A synthesis may fail, but
 * only with a one-line message and a known status.
 *
 * Input as in fuzz_model.c, told apart by the first byte:
 *  - 0x89: the input is a whole model file;
 *  - anything else: the rest is a payload (the sections), put in a container
 *    with a correct CRC (stored when the byte is even, deflated when odd),
 *    so that mutations reach the sections instead of dying at the CRC. The
 *    byte's bits 1-2 also pick the CPU path (bit 1: row by row instead of the
 *    wavefront, bit 2: the portable noise loop) and the rest the seed.
 * Each subspace is synthesised at 17 x 9 (odd, small: pyramid levels of 1 or
 * 2 pixels and a partial wavefront tile are exercised).
 *
 * `make fuzz-build` builds it (build-fuzz/fuzz_synth); `make fuzz` runs it
 * from the seeds in tests/fuzz/corpus/fuzz_synth/. Seeds: built with
 * -DFUZZ_SYNTH_SEEDS (no -fsanitize=fuzzer) this file writes them, models
 * that btf_texture_fit made of two small textures:
 *
 *   cc -std=c11 -DFUZZ_SYNTH_SEEDS -D_DEFAULT_SOURCE -Iinclude -o /tmp/seeds \
 *       tests/fuzz/fuzz_synth.c build/libbtfcar.a <the Makefile's LDLIBS>
 *   /tmp/seeds tests/fuzz/corpus/fuzz_synth
 */
#include "btfcar.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "fuzz_container.h"

static void run_one(const unsigned char *data, size_t size, unsigned mode)
{
    btf_model m;
    btf_error e = {0};
    if (btf_model_decode(data, size, "fuzz", &m, &e) != 0)
        return; /* fuzz_model checks the decoder's failures */
    btf_synth_opts o = btf_synth_defaults();
    o.width = 17;
    o.height = 9;
    o.row_by_row = (mode >> 1) & 1;
    o.portable_noise = (mode >> 2) & 1;
    o.seed = mode >> 3;
    for (int s = 0; s < m.n_subspaces; s++) {
        btf_image img;
        int rc = btf_synthesise_image(&m, s, &o, &img, &e);
        if (rc != 0) {
            if (e.code != rc || !e.msg[0] || strchr(e.msg, '\n') ||
                (rc != BTF_E_NUMERIC && rc != BTF_E_NOMEM && rc != BTF_E_ARG &&
                 rc != BTF_E_DATA && rc != BTF_E_UNSUPPORTED))
                abort();
            continue;
        }
        if (img.width != 17 || img.height != 9 || img.channels != 3 || !img.data)
            abort();
        for (size_t i = 0; i < (size_t)17 * 9 * 3; i++)
            if (!isfinite(img.data[i]))
                abort();
        btf_image_free(&img);
    }
    btf_model_free(&m);
}

#ifndef FUZZ_SYNTH_SEEDS

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size > 0 && data[0] != 0x89) {
        size_t n;
        unsigned char *f = wrap(data + 1, size - 1, data[0] & 1, &n);
        run_one(f, n, data[0]);
        free(f);
        return 0;
    }
    /* A copy of exactly size bytes, so that ASan sees any over-read. */
    unsigned char *copy = malloc(size ? size : 1);
    if (!copy)
        abort();
    if (size)
        memcpy(copy, data, size);
    run_one(copy, size, 0);
    free(copy);
    return 0;
}

#else /* the seed writer */

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

/* A small texture: stripes (kind 0) or blobs (kind 1) with a hash noise. */
static void texture(btf_image *img, int w, int h, int kind)
{
    btf_error e = {0};
    if (btf_image_alloc(img, w, h, 3, &e))
        exit(1);
    uint32_t st = 12345u + (uint32_t)kind;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            st = st * 1664525u + 1013904223u;
            float n = (float)(st >> 8) / 16777216.0f;
            float v = kind ? 0.5f + 0.3f * sinf(0.7f * x) * cosf(0.5f * y)
                           : 0.5f + 0.3f * sinf(0.9f * (x + 0.5f * y));
            for (int c = 0; c < 3; c++)
                img->data[((size_t)y * w + x) * 3 + c] = v * (0.6f + 0.2f * c) + 0.2f * n;
        }
}

/* The whole file, and (after the mode byte 2: stored, row by row) its payload. */
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
    p[0] = 2;
    if (d[17] == 1) {
        if (uncompress(p + 1, &raw, d + 26, (uLong)(n - 30)) != Z_OK)
            exit(1);
    } else {
        memcpy(p + 1, d + 26, raw);
    }
    snprintf(fname, sizeof fname, "%s.payload", name);
    write_file(dir, fname, p, raw + 1);
    run_one(d, n, 0);
    size_t wn;
    unsigned char *w = wrap(p + 1, raw, 0, &wn);
    run_one(w, wn, p[0]);
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
    for (int kind = 0; kind < 2; kind++) {
        btf_image img;
        texture(&img, kind ? 40 : 32, kind ? 24 : 32, kind);
        btf_fit_opts fo = btf_fit_defaults();
        fo.levels = kind ? 2 : 1;
        btf_model m;
        btf_error e = {0};
        if (btf_texture_fit(&img, &fo, &m, &e)) {
            fprintf(stderr, "%s\n", e.msg);
            return 1;
        }
        btf_image_free(&img);
        write_seeds(argv[1], kind ? "blobs" : "stripes", &m);
        btf_model_free(&m);
    }
    return 0;
}

#endif
