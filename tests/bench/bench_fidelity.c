/*
 * bench_fidelity.c — the fidelity bench (docs/fidelity.md):
 * for each exemplar, the texture distances (src/measure/, docs/measure.md)
 * between the exemplar and a synthesis of the same size by
 *   - btfcar's default model (auto levels, auto neighbourhoods) and its
 *     default synthesis (colour-matched, btf_synth_opts.match_colours),
 *   - the same without colour matching,
 *   - 1, 2 and 3 pyramid levels (auto neighbourhoods),
 *   - fixed neighbourhoods of 4, 8 and 12 causal offsets (auto levels),
 *   - the phase-randomisation baseline (btf_phase_randomise),
 * with the model's bytes (the model file's encoding) against the baseline's
 * stored spectrum, and the synthesis time. Prints one markdown table row
 * per (exemplar, variant) and a summary; with --sheet PATH, writes the
 * first exemplar, its default synthesis, the same without colour matching
 * and its baseline side by side.
 *
 *   bench_fidelity [--sheet PATH] IMAGE...   (sheet: exemplar | default |
 *                                             no colour match | baseline)
 * IMAGE: PNG, JPEG or EXR (btf_image_read), or a GIMP pattern (.pat: the
 * photographs tools/fetch-textures.sh extracts from Debian's gimp-data).
 * Without arguments (make bench runs every bench program so) it says how
 * to call it and exits 0. Never fails on quality or time.
 */
#include "btfcar.h"
#include "testutil.h"
#include "core/core.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A GIMP pattern: header (big-endian header size, version 1, width, height,
 * bytes per pixel, "GPAT", name), then 8-bit pixels; grey is spread to RGB.
 * sRGB values, linearised as the image reader does. 0 on success. */
static int read_pat(const char *path, btf_image *out)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return -1;
    unsigned char h[24];
    int rc = -1;
    if (fread(h, 1, 24, f) == 24 && !memcmp(h + 20, "GPAT", 4)) {
        uint32_t v[5];
        for (int i = 0; i < 5; i++)
            v[i] = (uint32_t)h[4 * i] << 24 | (uint32_t)h[4 * i + 1] << 16 |
                   (uint32_t)h[4 * i + 2] << 8 | h[4 * i + 3];
        uint32_t hs = v[0], w = v[2], ht = v[3], b = v[4];
        size_t n = (size_t)w * ht * b;
        unsigned char *px = w && ht && w <= 4096 && ht <= 4096 && b >= 1 && b <= 4 && hs >= 24
                                ? malloc(n) : NULL;
        btf_error e = {0};
        if (px && fseek(f, (long)hs, SEEK_SET) == 0 && fread(px, 1, n, f) == n &&
            btf_image_alloc(out, (int)w, (int)ht, 3, &e) == 0) {
            for (size_t p = 0; p < (size_t)w * ht; p++)
                for (int c = 0; c < 3; c++) {
                    unsigned char s = px[p * b + (b >= 3 ? (uint32_t)c : 0)];
                    out->data[3 * p + c] = btf__srgb_to_linear((float)s / 255.0f);
                }
            rc = 0;
        }
        free(px);
    }
    fclose(f);
    return rc;
}

static int read_any(const char *path, btf_image *img, btf_error *e)
{
    size_t n = strlen(path);
    if (n > 4 && !strcmp(path + n - 4, ".pat")) {
        if (read_pat(path, img) == 0)
            return 0;
        snprintf(e->msg, sizeof e->msg, "%s: not a GIMP pattern", path);
        return -1;
    }
    return btf_image_read(path, NULL, img, e);
}

typedef struct variant {
    const char *name;
    int levels;          /* 0: auto */
    const char *fixed;   /* NULL: the Bayesian choice */
    int baseline;
    int match;           /* btf_synth_opts.match_colours: 0 the default (on), -1 off */
} variant;

static const variant VARIANTS[] = {
    {"default", 0, NULL, 0, 0},
    {"no colour match", 0, NULL, 0, -1},
    {"1 level", 1, NULL, 0, 0},
    {"2 levels", 2, NULL, 0, 0},
    {"3 levels", 3, NULL, 0, 0},
    {"fixed 4", 0, "0:-1,-1:0,-1:-1,-1:1", 0, 0},
    {"fixed 8", 0, "0:-1,-1:0,-1:-1,-1:1,0:-2,-2:0,-1:-2,-1:2", 0, 0},
    {"fixed 12", 0, "0:-1,-1:0,-1:-1,-1:1,0:-2,-2:0,-1:-2,-1:2,-2:-1,-2:1,-2:-2,-2:2", 0, 0},
    {"baseline", 0, NULL, 1, 0},
};
#define N_VARIANTS (int)(sizeof VARIANTS / sizeof VARIANTS[0])

/* The synthesis of one variant at the exemplar's size, its model bytes
 * (the baseline: its spectrum's) and time. */
static int synthesise_variant(const variant *v, const btf_image *ex, btf_image *out,
                              uint64_t *bytes, double *secs, btf_error *e)
{
    double t0 = tu_now();
    if (v->baseline) {
        *bytes = btf_phase_randomise_bytes(ex->width, ex->height);
        int rc = btf_phase_randomise(ex, ex->width, ex->height, 1, out, e);
        *secs = tu_now() - t0;
        return rc;
    }
    btf_fit_opts fo = btf_fit_defaults();
    fo.levels = v->levels;
    if (v->fixed && btf_neighbourhood_parse(v->fixed, fo.car.fixed, &fo.car.n_fixed, e))
        return -1;
    btf_model m;
    if (btf_texture_fit(ex, &fo, &m, e))
        return -1;
    unsigned char *enc = NULL;
    size_t n = 0;
    if (btf_model_encode(&m, &enc, &n, e)) {
        btf_model_free(&m);
        return -1;
    }
    free(enc);
    *bytes = n;
    btf_synth_opts so = btf_synth_defaults();
    so.width = ex->width;
    so.height = ex->height;
    so.seed = 1;
    so.match_colours = v->match;
    double t1 = tu_now();
    int rc = btf_synthesise_image(&m, 0, &so, out, e);
    *secs = tu_now() - t1;
    (void)t0;
    btf_model_free(&m);
    return rc;
}

/* Counts of the output's negative channel values. */
static size_t negatives(const btf_image *img)
{
    size_t k = 0;
    for (size_t i = 0; i < (size_t)img->width * img->height * 3; i++)
        k += img->data[i] < 0.0f;
    return k;
}

/* [exemplar | default | no colour match | baseline] into one image. */
#define SHEET_PARTS 4
static void write_sheet(const char *path, const btf_image *parts[SHEET_PARTS])
{
    int w = parts[0]->width, h = parts[0]->height;
    btf_image s;
    btf_error e = {0};
    if (btf_image_alloc(&s, SHEET_PARTS * w + 4 * (SHEET_PARTS - 1), h, 3, &e))
        return;
    memset(s.data, 0, (size_t)s.width * h * 3 * sizeof(float));
    for (int k = 0; k < SHEET_PARTS; k++)
        for (int y = 0; y < h; y++)
            memcpy(s.data + ((size_t)y * s.width + (size_t)k * (w + 4)) * 3,
                   parts[k]->data + (size_t)y * w * 3, (size_t)w * 3 * sizeof(float));
    if (btf_image_write_png(path, &s, &e))
        fprintf(stderr, "bench_fidelity: %s\n", e.msg);
    btf_image_free(&s);
}

int main(int argc, char **argv)
{
    const char *sheet = NULL;
    int first = 1;
    if (argc > 2 && !strcmp(argv[1], "--sheet"))
        sheet = argv[2], first = 3;
    if (first >= argc) {
        printf("bench_fidelity: [--sheet PATH] IMAGE... (tests/bench/bench.sh runs it on the "
               "generated materials and tools/fetch-textures.sh's photographs)\n");
        return 0;
    }
    double sum_comb[N_VARIANTS] = {0}, worst_first[N_VARIANTS] = {0};
    double sum_bytes[N_VARIANTS] = {0};
    int counted = 0;
    printf("| exemplar | variant | spectrum | first order | structure | combined | bytes | "
           "synthesis ms | negative values |\n|---|---|---|---|---|---|---|---|---|\n");
    for (int a = first; a < argc; a++) {
        btf_image ex = {0};
        btf_error e = {0};
        if (read_any(argv[a], &ex, &e)) {
            fprintf(stderr, "bench_fidelity: %s\n", e.msg);
            continue;
        }
        const char *base = strrchr(argv[a], '/') ? strrchr(argv[a], '/') + 1 : argv[a];
        btf_image keep[3] = {{0}}; /* default, no colour match, baseline */
        double comb[N_VARIANTS], fo[N_VARIANTS];
        uint64_t by[N_VARIANTS];
        int ok = 1;
        for (int v = 0; v < N_VARIANTS && ok; v++) {
            btf_image out = {0};
            double secs = 0;
            btf_texture_distances d;
            btf_texture_distance_opts dopt = btf_texture_distance_defaults();
            if (synthesise_variant(&VARIANTS[v], &ex, &out, &by[v], &secs, &e) ||
                btf_texture_distance(&ex, &out, &dopt, &d, &e)) {
                fprintf(stderr, "bench_fidelity: %s, %s: %s\n", base, VARIANTS[v].name, e.msg);
                btf_image_free(&out);
                ok = 0;
                break;
            }
            comb[v] = d.combined;
            fo[v] = d.first_order.normalised;
            printf("| %s | %s | %.2f | %.2f | %.2f | %.2f | %llu | %.1f | %zu |\n", base,
                   VARIANTS[v].name, d.spectrum.normalised, d.first_order.normalised,
                   d.structure.normalised, d.combined, (unsigned long long)by[v],
                   1000.0 * secs, negatives(&out));
            if (v == 0)
                keep[0] = out;
            else if (VARIANTS[v].match < 0 && !keep[1].data)
                keep[1] = out;
            else if (VARIANTS[v].baseline)
                keep[2] = out;
            else
                btf_image_free(&out);
        }
        if (ok) {
            for (int v = 0; v < N_VARIANTS; v++) {
                sum_comb[v] += comb[v];
                sum_bytes[v] += (double)by[v];
                worst_first[v] = fo[v] > worst_first[v] ? fo[v] : worst_first[v];
            }
            counted++;
            if (sheet && a == first) {
                const btf_image *parts[SHEET_PARTS] = {&ex, &keep[0], &keep[1], &keep[2]};
                write_sheet(sheet, parts);
            }
        }
        for (int k = 0; k < 3; k++)
            btf_image_free(&keep[k]);
        btf_image_free(&ex);
    }
    if (counted == 0)
        return 0;
    printf("\nover %d exemplars: mean combined distance, worst first-order component, mean "
           "bytes\n", counted);
    for (int v = 0; v < N_VARIANTS; v++)
        printf("   %-15s combined %.2f, worst first order %.2f, %.0f bytes\n", VARIANTS[v].name,
               sum_comb[v] / counted, worst_first[v], sum_bytes[v] / counted);
    printf("   default against baseline: combined %.2f vs %.2f (%s); baseline stores %.0f x the "
           "model's bytes\n", sum_comb[0] / counted, sum_comb[N_VARIANTS - 1] / counted,
           sum_comb[0] <= sum_comb[N_VARIANTS - 1] ? "no worse" : "worse",
           sum_bytes[N_VARIANTS - 1] / sum_bytes[0]);
    printf("   default's first-order component: worst %.2f (target: <= 1.2 on every exemplar: "
           "%s)\n", worst_first[0], worst_first[0] <= 1.2 ? "met" : "not met");
    return 0;
}
