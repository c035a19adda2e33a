/*
 * bench_btf.c — reconstructing every image of a Bonn DFMF .btf file of
 * UBO2014's shape (src/io/ubo_decode.c) through the dataset iterator: images
 * per second and peak memory.
 *
 * The file holds 151 views x 151 lights, K half-float components per
 * channel, colour model 11 (Ylog_UdivY_VdivY, UBO2014's), written by
 * btf_ubo2014_write_factors. Its factors come from a real material, made
 * cheaply: the procedural leather is rendered for all 22,801 pairs at a small
 * side SRC, mapped to model 11's (log Y, U/Y, V/Y) and factorised by the
 * writer (btf_ubo2014_write, K components per channel); the file's U is that
 * U, and its S x V is the small S x V tiled to SIZE x SIZE (the material is
 * periodic, so the tiling is seamless). The result is a low-rank BTF with the
 * material's directional behaviour at the database's size; rendering and
 * factorising 22,801 images of 400^2 directly would take hours. The
 * database's own component count could not be established (the notes'
 * §10; docs/datasets.md, "The component count", lists what was searched):
 * K = 16, the writer's default; the reconstruction's cost is linear in K. The
 * 20-texel period of S x V is visible to the analysis (its CAR fits warn).
 *
 *   build/tests/bench_btf [SIZE [K [IMAGES [SRC [KEEP [ANALYSE]]]]]]
 *       defaults 128, 16, all 22801, 20; KEEP: write the file there and
 *       leave it ("-": a temporary file)
 *   build/tests/bench_btf analyse FILE
 *       btf_analyse on a .btf file (KEEP above) with the library's
 *       defaults, in a process of its own, as a program using the library
 *       runs it (no allocator settings of its own): time, page faults,
 *       peak memory and the model's size and hash. A process of its own:
 *       glibc raises its mmap and trim thresholds after the first large
 *       free, so the factorisation above would hide what a fresh program
 *       sees (docs/datasets.md, "UBO2014 .btf files").
 */
#include "testutil.h"
#include "io/ubo2014.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

static long status_kb(const char *key)
{
    FILE *f = fopen("/proc/self/status", "r");
    char line[256];
    long kb = -1;
    size_t n = strlen(key);
    while (f && fgets(line, sizeof line, f))
        if (!strncmp(line, key, n) && sscanf(line + n, ": %ld", &kb) == 1)
            break;
    if (f)
        fclose(f);
    return kb;
}

typedef struct src_material {
    btf_material m;
    const btf_dirset *d;
} src_material;

/* One pair of the small material in colour model 11's coordinates: the
 * inverse of §3b's decoding (BT.601 Y, U = (B - Y) / 2.03211,
 * V = (R - Y) / 1.13983; d0 = log(Y + eps), d1 = U / (Y + eps), d2 likewise). */
static btf_status render_model11(void *user, int view, int light, btf_image *out, btf_error *err)
{
    src_material *s = user;
    btf_status rc = btf_material_render(&s->m, s->d->dirs[view], s->d->dirs[light], out, err);
    if (rc)
        return rc;
    long n = (long)out->width * out->height;
    for (long i = 0; i < n; i++) {
        float *p = out->data + 3 * i;
        double y = 0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2];
        if (y < 0)
            y = 0;
        double u = (p[2] - y) / 2.03211, v = (p[0] - y) / 1.13983, ye = y + 1e-5;
        p[0] = (float)log(ye);
        p[1] = (float)(u / ye);
        p[2] = (float)(v / ye);
    }
    return BTF_OK;
}

/* btf_analyse on the file as a program using the library calls it. */
static int run_analyse(const btf_dataset *ds)
{
    btf_analyse_opts ao = btf_analyse_defaults();
    btf_model m;
    btf_error err = {0};
    struct rusage r0, r1;
    getrusage(RUSAGE_SELF, &r0);
    double t0 = tu_now();
    if (btf_analyse(ds, &ao, &m, &err)) {
        fprintf(stderr, "bench_btf: %s\n", err.msg);
        return 1;
    }
    double ta = tu_now() - t0;
    getrusage(RUSAGE_SELF, &r1);
    unsigned char *bytes = NULL;
    size_t size = 0;
    if (btf_model_encode(&m, &bytes, &size, &err)) {
        fprintf(stderr, "bench_btf: %s\n", err.msg);
        return 1;
    }
    uint64_t h = 1469598103934665603ull; /* FNV-1a: the same model, the same hash */
    for (size_t i = 0; i < size; i++)
        h = (h ^ bytes[i]) * 1099511628211ull;
    printf("   btf_analyse (library defaults, no allocator settings) on it: %.1f s (user %.1f s, "
           "system %.1f s), %ld page faults, peak RSS %ld MB; model %zu bytes, %d subspaces, "
           "FNV-1a %016llx\n", ta,
           (double)(r1.ru_utime.tv_sec - r0.ru_utime.tv_sec) +
               1e-6 * (double)(r1.ru_utime.tv_usec - r0.ru_utime.tv_usec),
           (double)(r1.ru_stime.tv_sec - r0.ru_stime.tv_sec) +
               1e-6 * (double)(r1.ru_stime.tv_usec - r0.ru_stime.tv_usec),
           r1.ru_minflt - r0.ru_minflt, r1.ru_maxrss / 1024, size, m.n_subspaces,
           (unsigned long long)h);
    free(bytes);
    btf_model_free(&m);
    return 0;
}

static int analyse_file(const char *path)
{
    btf_dataset *ds;
    btf_error err = {0};
    if (btf_dataset_open(path, NULL, &ds, &err)) {
        fprintf(stderr, "bench_btf: %s\n", err.msg);
        return 1;
    }
    int rc = run_analyse(ds);
    btf_dataset_close(ds);
    return rc;
}

int main(int argc, char **argv)
{
    int size = argc > 1 ? atoi(argv[1]) : 128, k = argc > 2 ? atoi(argv[2]) : 16;
    long limit = argc > 3 ? atol(argv[3]) : 0;
    int src = argc > 4 ? atoi(argv[4]) : 20;
    if (argc > 2 && !strcmp(argv[1], "analyse"))
        return analyse_file(argv[2]);
    const char *keep = argc > 5 && strcmp(argv[5], "-") ? argv[5] : NULL;
    btf_dirset d;
    btf_error err = {0};
    if (btf_dirset_ubo151(&d, &err))
        return 1;
    char *dir = tu_tmpdir();
    char small[4096], path[4096];
    snprintf(small, sizeof small, "%s/small.btf", dir);
    snprintf(path, sizeof path, "%s", keep ? keep : "");
    if (!keep)
        snprintf(path, sizeof path, "%s/bench.btf", dir);

    /* 1. The small material, factorised by the writer. */
    src_material sm = {.d = &d};
    if (btf_material_make("leather", src, 1, &sm.m, &err)) {
        fprintf(stderr, "bench_btf: %s\n", err.msg);
        return 1;
    }
    btf_ubo2014_write_opts wo = btf_ubo2014_write_defaults();
    wo.components = k;
    btf_ubo2014_write_stats st;
    double t0 = tu_now();
    if (btf_ubo2014_write(small, &d, &d, src, src, render_model11, &sm, &wo, &st, &err)) {
        fprintf(stderr, "bench_btf: %s\n", err.msg);
        return 1;
    }
    double tf = tu_now() - t0;
    btf_material_free(&sm.m);

    /* 2. Its factors, S x V tiled to size x size. */
    ubo_open_file *o;
    if (ubo_open(small, &o, &err)) {
        fprintf(stderr, "bench_btf: %s\n", err.msg);
        return 1;
    }
    int same_order = 1;
    for (int i = 0; i < d.count && o->f.nv == (uint32_t)d.count && o->f.nl == (uint32_t)d.count; i++)
        same_order &= o->view_index[i] == (uint32_t)i && o->light_index[i] == (uint32_t)i;
    if (o->f.variant != UBO_DFMF || o->f.transposed || o->f.nv != (uint32_t)d.count ||
        o->f.nl != (uint32_t)d.count || !same_order) {
        fprintf(stderr, "bench_btf: the writer's file is not the expected plain DFMF\n");
        return 1;
    }
    int n = d.count * d.count;
    long px = (long)size * size;
    float *u[3], *s[3];
    int kc[3];
    for (int c = 0; c < 3; c++) {
        const ubo_matrix *mu = &o->f.u[c], *ms = &o->f.sxv[c];
        kc[c] = (int)mu->k;
        u[c] = malloc((size_t)n * kc[c] * sizeof(float));
        s[c] = malloc((size_t)px * kc[c] * sizeof(float));
        if (!u[c] || !s[c] || mu->scalar != 2 || ms->rows != (uint32_t)src * src)
            return 1;
        const uint16_t *hu = (const void *)mu->p, *hs = (const void *)ms->p;
        for (long i = 0; i < (long)n * kc[c]; i++) {
            uint16_t h;
            memcpy(&h, hu + i, 2);
            u[c][i] = ubo_half_to_float(h);
        }
        for (long y = 0; y < size; y++)
            for (long x = 0; x < size; x++)
                for (int j = 0; j < kc[c]; j++) {
                    uint16_t h;
                    memcpy(&h, hs + ((y % src) * src + x % src) * kc[c] + j, 2);
                    s[c][(y * size + x) * kc[c] + j] = ubo_half_to_float(h);
                }
    }
    ubo_close(o);

    /* 3. The full-size file. */
    btf_ubo2014_factors f = {.colour_model = 11, .components = {kc[0], kc[1], kc[2]},
                             .u = {u[0], u[1], u[2]}, .sxv = {s[0], s[1], s[2]}};
    t0 = tu_now();
    if (btf_ubo2014_write_factors(path, &d, &d, size, size, &f, &err)) {
        fprintf(stderr, "bench_btf: %s\n", err.msg);
        return 1;
    }
    double tw = tu_now() - t0;
    for (int c = 0; c < 3; c++) {
        free(u[c]);
        free(s[c]);
    }
    long anon0 = status_kb("RssAnon");
    btf_dataset *ds;
    t0 = tu_now();
    if (btf_dataset_open(path, NULL, &ds, &err)) {
        fprintf(stderr, "bench_btf: %s\n", err.msg);
        return 1;
    }
    double topen = tu_now() - t0;
    const btf_ubo2014_info *in = btf_dataset_ubo2014(ds);
    btf_dataset_iter it;
    btf_dataset_iter_begin(&it, ds);
    int rc;
    long count = 0, anon_peak = anon0;
    struct rusage ru0;
    getrusage(RUSAGE_SELF, &ru0);
    t0 = tu_now();
    while ((limit == 0 || count < limit) && (rc = btf_dataset_iter_next(&it, &err)) == 1)
        if (++count % 256 == 0) {
            long a = status_kb("RssAnon");
            anon_peak = a > anon_peak ? a : anon_peak;
        }
    double td = tu_now() - t0;
    btf_dataset_iter_end(&it);
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    long faults = ru.ru_minflt - ru0.ru_minflt;
    printf("btf DFMF %d x %d images of %dx%d, K %d %d %d (half), model 11, factors of the "
           "leather at %d^2 (factorised in %.1f s; energy kept %.4f %.4f %.4f) with S x V "
           "tiled: file %.1f MB written in %.2f s, opened (parse, finite check) in %.2f s\n",
           d.count, d.count, size, size, kc[0], kc[1], kc[2], src, tf, st.energy[0],
           st.energy[1], st.energy[2], (double)in->file_bytes / 1e6, tw, topen);
    printf("   reconstructed %ld images in %.2f s: %.1f images/s (%.1f Mpixel/s); heap (RssAnon) "
           "%ld -> %ld kB peak; peak RSS %ld MB incl. the mapped file's pages and the "
           "factorisation before; %ld page faults\n", count, td,
           count / td, count * (double)px / td / 1e6, anon0, anon_peak, ru.ru_maxrss / 1024,
           faults);
    btf_dataset_close(ds);
    btf_dirset_free(&d);
    tu_rmtree(dir);
    free(dir);
    return 0;
}
