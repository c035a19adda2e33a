/*
 * bench_btf.c — a Bonn DFMF .btf file of UBO2014's shape (src/dataset/ubo_*.c):
 * its bytes against the layout, the reader's open time, the reconstruction
 * of every image through the dataset iterator (images per second, peak
 * memory), and btf_analyse on it.
 *
 * The file holds 151 views x 151 lights of SIZE^2 texels, half-float
 * components per channel (K, or KR,KG,KB per channel), colour model 11
 * (Ylog_UdivY_VdivY, UBO2014's), written by btf__ubo2014_write_factors. The
 * database's files (docs/datasets.md, "UBO2014 .btf files") are 82.9 to
 * 84.3 MB for 400^2, which the DFMF layout makes 226 to 230 components in
 * all, about 76 per channel: make bench uses 78,76,74 (228, 83,542,344
 * bytes). The factors come from a real material, made cheaply: the
 * procedural leather is rendered for all 22,801 pairs at a small side SRC,
 * mapped to model 11's (log Y, U/Y, V/Y) and factorised by the writer
 * (btf_ubo2014_write, max K components per channel); the file's U is that
 * U (channel c's first K_c columns), and its S x V the small S x V tiled to
 * SIZE x SIZE (the material is periodic, so the tiling is seamless). The
 * result has the material's directional behaviour at the database's size
 * and component counts; rendering and factorising 22,801 images of 400^2
 * directly would take hours. The SRC-texel period of S x V is visible to
 * the analysis (its CAR fits warn). SRC^2 must be at least the largest K.
 *
 *   build/tests/bench_btf [SIZE [K [IMAGES [SRC [KEEP]]]]]
 *       write, then read in this process; defaults 128, 16, all 22801, 20;
 *       KEEP: write the file there and leave it ("-": a temporary file)
 *   build/tests/bench_btf write FILE [SIZE [K [SRC]]]
 *       only write the file (defaults 400, 78,76,74, 20)
 *   build/tests/bench_btf read FILE [IMAGES [RUNS]]
 *       in a process of its own: the file's bytes against the layout, the
 *       open (mmap, parse, finite check, direction sets; median of RUNS,
 *       default 5), every image (or the first IMAGES) reconstructed once,
 *       one thread; peak memory is the process's VmHWM, the mapped file's
 *       pages included
 *   build/tests/bench_btf analyse FILE
 *       btf_analyse on a .btf file with the library's defaults, in a
 *       process of its own, as a program using the library runs it (no
 *       allocator settings of its own): time, page faults, peak memory and
 *       the model's size and hash. A process of its own: glibc raises its
 *       mmap and trim thresholds after the first large free, so the
 *       factorisation above would hide what a fresh program sees
 *       (docs/datasets.md, "UBO2014 .btf files").
 */
#include "testutil.h"
#include "core/core.h"
#include "dataset/ubo2014.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
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

/* "K" or "KR,KG,KB": the components per channel, each 1..UBO_MAX_COMPONENTS. */
static int parse_k(const char *s, int k[3])
{
    int n = sscanf(s, "%d,%d,%d", &k[0], &k[1], &k[2]);
    if (n == 1)
        k[1] = k[2] = k[0];
    else if (n != 3)
        return 0;
    for (int c = 0; c < 3; c++)
        if (k[c] < 1 || k[c] > UBO_MAX_COMPONENTS)
            return 0;
    return 1;
}

typedef struct src_material {
    btf_procedural m;
    const btf_dirset *d;
} src_material;

/* One pair of the small material in colour model 11's coordinates: the
 * inverse of §3b's decoding (BT.601 Y, U = (B - Y) / 2.03211,
 * V = (R - Y) / 1.13983; d0 = log(Y + eps), d1 = U / (Y + eps), d2 likewise). */
static btf_status render_model11(void *user, int view, int light, btf_image *out, btf_error *err)
{
    src_material *s = user;
    btf_status rc = btf_procedural_render(&s->m, s->d->dirs[view], s->d->dirs[light], out, err);
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

/* The file at path: 151 x 151 pairs of size^2, k[c] components per channel. */
static int write_file(const char *path, int size, const int kreq[3], int src)
{
    btf_dirset d;
    btf_error err = {0};
    if (btf__dirset_ubo151(&d, &err))
        return 1;
    int kmax = kreq[0] > kreq[1] ? kreq[0] : kreq[1];
    kmax = kreq[2] > kmax ? kreq[2] : kmax;
    if (kmax > src * src) {
        fprintf(stderr, "bench_btf: %d components need a source of at least %d texels, not %d^2\n",
                kmax, kmax, src);
        return 1;
    }
    char *dir = tu_tmpdir();
    char small[4096];
    snprintf(small, sizeof small, "%s/small.btf", dir);

    /* 1. The small material, factorised by the writer. */
    src_material sm = {.d = &d};
    if (btf_procedural_make("leather", src, 1, &sm.m, &err)) {
        fprintf(stderr, "bench_btf: %s\n", err.msg);
        return 1;
    }
    btf_ubo2014_write_opts wo = btf_ubo2014_write_defaults();
    wo.components = kmax;
    btf_ubo2014_write_stats st;
    double t0 = tu_now();
    if (btf_ubo2014_write(small, &d, &d, src, src, render_model11, &sm, &wo, &st, &err)) {
        fprintf(stderr, "bench_btf: %s\n", err.msg);
        return 1;
    }
    double tf = tu_now() - t0;
    btf_procedural_free(&sm.m);

    /* 2. Its factors: channel c's first k[c] columns, S x V tiled to size^2. */
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
    int nd = d.count, n = nd * nd;
    long px = (long)size * size;
    float *u[3], *s[3];
    int kc[3];
    for (int c = 0; c < 3; c++) {
        const ubo_matrix *mu = &o->f.u[c], *ms = &o->f.sxv[c];
        int kf = (int)mu->k; /* the writer keeps fewer for a rank-deficient channel */
        kc[c] = kreq[c] < kf ? kreq[c] : kf;
        u[c] = malloc((size_t)n * kc[c] * sizeof(float));
        s[c] = malloc((size_t)px * kc[c] * sizeof(float));
        if (!u[c] || !s[c] || mu->scalar != 2 || ms->rows != (uint32_t)src * src)
            return 1;
        const uint16_t *hu = (const void *)mu->p, *hs = (const void *)ms->p;
        for (long i = 0; i < n; i++)
            for (int j = 0; j < kc[c]; j++) {
                uint16_t h;
                memcpy(&h, hu + i * kf + j, 2);
                u[c][i * kc[c] + j] = ubo_half_to_float(h);
            }
        for (long y = 0; y < size; y++)
            for (long x = 0; x < size; x++)
                for (int j = 0; j < kc[c]; j++) {
                    uint16_t h;
                    memcpy(&h, hs + ((y % src) * src + x % src) * kf + j, 2);
                    s[c][(y * size + x) * kc[c] + j] = ubo_half_to_float(h);
                }
    }
    ubo_close(o);
    tu_rmtree(dir);
    free(dir);

    /* 3. The full-size file. */
    btf_ubo2014_factors f = {.colour_model = 11, .components = {kc[0], kc[1], kc[2]},
                             .u = {u[0], u[1], u[2]}, .sxv = {s[0], s[1], s[2]}};
    t0 = tu_now();
    int rc = btf__ubo2014_write_factors(path, &d, &d, size, size, &f, &err);
    double tw = tu_now() - t0;
    for (int c = 0; c < 3; c++) {
        free(u[c]);
        free(s[c]);
    }
    btf_dirset_free(&d);
    if (rc) {
        fprintf(stderr, "bench_btf: %s\n", err.msg);
        return 1;
    }
    struct stat sb;
    long long bytes = stat(path, &sb) == 0 ? (long long)sb.st_size : -1;
    printf("btf DFMF written: %d x %d images of %dx%d, components %d %d %d (half), model 11; "
           "factors of the leather at %d^2 (%d components factorised in %.1f s; energy kept "
           "%.4f %.4f %.4f), S x V tiled: %lld bytes written in %.2f s\n",
           nd, nd, size, size, kc[0], kc[1], kc[2], src, kmax, tf, st.energy[0],
           st.energy[1], st.energy[2], bytes, tw);
    return 0;
}

/* The open (median of runs), then every image (or the first limit) once. */
static int read_file(const char *path, long limit, int runs)
{
    btf_error err = {0};
    btf_dataset *ds = NULL;
    double t[64];
    runs = runs < 1 ? 1 : runs > 64 ? 64 : runs;
    for (int r = 0; r < runs; r++) {
        if (ds)
            btf_dataset_close(ds);
        double t0 = tu_now();
        if (btf_dataset_open(path, NULL, &ds, &err)) {
            fprintf(stderr, "bench_btf: %s\n", err.msg);
            return 1;
        }
        t[r] = tu_now() - t0;
    }
    char list[64 * 12] = "";
    for (int r = 0, at = 0; r < runs; r++)
        at += snprintf(list + at, sizeof list - at, " %.3f", t[r]);
    double topen = tu_median(t, runs);
    const btf_ubo2014_info *in = btf_dataset_ubo2014(ds);
    const btf_dataset_info *di = btf_dataset_get_info(ds);
    if (!in) {
        fprintf(stderr, "bench_btf: %s is not a .btf file\n", path);
        return 1;
    }
    uint64_t pairs = (uint64_t)di->n_views * di->n_lights, px = (uint64_t)di->width * di->height;
    int ktot = 0;
    uint64_t tail = 0; /* the channels' 13-byte headers and S */
    for (int c = 0; c < 3; c++) {
        ktot += in->components[c];
        tail += 13 + (uint64_t)in->scalar_size * in->components[c];
    }
    uint64_t header = in->file_bytes - in->data_bytes - tail;
    printf("btf %s %d x %d images of %dx%d, components %d %d %d (%d in all; %d-byte scalars), "
           "colour model %d: %llu bytes = header %llu + 3 x 13 + %d x %d x (1 + %llu + %llu)%s\n",
           in->variant, di->n_views, di->n_lights, di->width, di->height, in->components[0],
           in->components[1], in->components[2], ktot, in->scalar_size, in->colour_model,
           (unsigned long long)in->file_bytes, (unsigned long long)header, in->scalar_size,
           ktot, (unsigned long long)pairs, (unsigned long long)px,
           header + 39 + (uint64_t)in->scalar_size * ktot * (1 + pairs + px) == in->file_bytes
               ? ""
               : " (NOT the DFMF layout of equal channel shapes)");
    printf("   opened (mmap, parse, finite check of the factors, direction sets): median %.3f s "
           "of %d (runs:%s)\n", topen, runs, list);
    long anon0 = status_kb("RssAnon");
    btf_dataset_iter it;
    btf_dataset_iter_begin(&it, ds);
    int rc;
    long count = 0, anon_peak = anon0;
    struct rusage ru0, ru;
    getrusage(RUSAGE_SELF, &ru0);
    double t0 = tu_now();
    while ((limit == 0 || count < limit) && (rc = btf_dataset_iter_next(&it, &err)) == 1)
        if (++count % 256 == 0) {
            long a = status_kb("RssAnon");
            anon_peak = a > anon_peak ? a : anon_peak;
        }
    double td = tu_now() - t0;
    btf_dataset_iter_end(&it);
    getrusage(RUSAGE_SELF, &ru);
    double user = (double)(ru.ru_utime.tv_sec - ru0.ru_utime.tv_sec) +
                  1e-6 * (double)(ru.ru_utime.tv_usec - ru0.ru_utime.tv_usec);
    printf("   reconstructed %ld of %llu images in %.1f s (one thread, user %.1f s): %.1f images/s "
           "(%.1f Mpixel/s); heap (RssAnon) %ld -> %ld kB; peak RSS (VmHWM) %ld MB incl. the "
           "mapped file's pages; %ld page faults\n", count, (unsigned long long)pairs, td, user,
           count / td, count * (double)px / td / 1e6, anon0, anon_peak,
           status_kb("VmHWM") / 1024, ru.ru_minflt - ru0.ru_minflt);
    btf_dataset_close(ds);
    return 0;
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

static int usage(void)
{
    fprintf(stderr, "usage: bench_btf [SIZE [K|KR,KG,KB [IMAGES [SRC [KEEP]]]]]\n"
                    "       bench_btf write FILE [SIZE [K|KR,KG,KB [SRC]]]\n"
                    "       bench_btf read FILE [IMAGES [RUNS]]\n"
                    "       bench_btf analyse FILE\n");
    return 2;
}

int main(int argc, char **argv)
{
    int k[3] = {16, 16, 16};
    if (argc > 1 && !strcmp(argv[1], "analyse"))
        return argc == 3 ? analyse_file(argv[2]) : usage();
    if (argc > 1 && !strcmp(argv[1], "read"))
        return argc >= 3 && argc <= 5
                   ? read_file(argv[2], argc > 3 ? atol(argv[3]) : 0, argc > 4 ? atoi(argv[4]) : 5)
                   : usage();
    if (argc > 1 && !strcmp(argv[1], "write")) {
        int kb[3] = {78, 76, 74};
        if (argc < 3 || argc > 6 || (argc > 4 && !parse_k(argv[4], kb)))
            return usage();
        return write_file(argv[2], argc > 3 ? atoi(argv[3]) : 400, kb,
                          argc > 5 ? atoi(argv[5]) : 20);
    }
    int size = argc > 1 ? atoi(argv[1]) : 128;
    if (argc > 2 && !parse_k(argv[2], k))
        return usage();
    long limit = argc > 3 ? atol(argv[3]) : 0;
    int src = argc > 4 ? atoi(argv[4]) : 20;
    const char *keep = argc > 5 && strcmp(argv[5], "-") ? argv[5] : NULL;
    if (size < 1 || src < 1)
        return usage();
    char *dir = tu_tmpdir();
    char path[4096];
    snprintf(path, sizeof path, "%s", keep ? keep : "");
    if (!keep)
        snprintf(path, sizeof path, "%s/bench.btf", dir);
    int rc = write_file(path, size, k, src);
    if (rc == 0)
        rc = read_file(path, limit, 3);
    tu_rmtree(dir);
    free(dir);
    return rc;
}
