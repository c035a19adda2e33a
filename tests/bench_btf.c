/*
 * bench_btf.c — reconstructing every image of a Bonn DFMF .btf file
 * (src/io/ubo_decode.c) through the dataset iterator: images per second and
 * peak memory. The file is written by btf_ubo2014_write_factors with the
 * UBO2014 shape: 151 views x 151 lights, K half-float components per
 * channel (colour model 11, as UBO2014 is expected to use).
 *
 *   build/tests/bench_btf [SIZE [K [IMAGES]]]   defaults 128, 16, all 22801
 *   (tests/bench.sh runs 128; BENCH_FULL=1 adds UBO2014's 400)
 */
#include "testutil.h"

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

int main(int argc, char **argv)
{
    int size = argc > 1 ? atoi(argv[1]) : 128, k = argc > 2 ? atoi(argv[2]) : 16;
    long limit = argc > 3 ? atol(argv[3]) : 0;
    btf_dirset d;
    btf_error err = {0};
    if (btf_dirset_ubo151(&d, &err))
        return 1;
    int n = d.count * d.count;
    long px = (long)size * size;
    float *u[3], *s[3];
    for (int c = 0; c < 3; c++) {
        u[c] = malloc((size_t)n * k * sizeof(float));
        s[c] = malloc((size_t)px * k * sizeof(float));
        if (!u[c] || !s[c])
            return 1;
        for (long i = 0; i < (long)n * k; i++)
            u[c][i] = (float)((i * 7 + c) % 31) / (31.0f * (float)(1 + i % k));
        for (long i = 0; i < px * k; i++)
            s[c][i] = (float)((i * 13 + c) % 29) / (29.0f * (float)(1 + i % k)) - 0.1f;
    }
    char *dir = tu_tmpdir();
    char path[4096];
    snprintf(path, sizeof path, "%s/bench.btf", dir);
    btf_ubo2014_factors f = {.colour_model = 11, .components = {k, k, k},
                             .u = {u[0], u[1], u[2]}, .sxv = {s[0], s[1], s[2]}};
    double t0 = tu_now();
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
    printf("btf DFMF %d x %d images of %dx%d, K %d (half), model 11: file %.1f MB written in %.2f s, "
           "opened (parse, finite check) in %.2f s\n", d.count, d.count, size, size, k,
           (double)in->file_bytes / 1e6, tw, topen);
    printf("   reconstructed %ld images in %.2f s: %.1f images/s (%.1f Mpixel/s); heap (RssAnon) "
           "%ld -> %ld kB peak; peak RSS %ld MB incl. the mapped file's pages\n", count, td,
           count / td, count * (double)px / td / 1e6, anon0, anon_peak, ru.ru_maxrss / 1024);
    btf_dataset_close(ds);
    btf_dirset_free(&d);
    tu_rmtree(dir);
    free(dir);
    return 0;
}
