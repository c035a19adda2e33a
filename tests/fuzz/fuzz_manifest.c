/*
 * fuzz_manifest.c — libFuzzer target for the tab-separated manifests btfcar
 * reads: the parser itself on the input in memory (src/io/tsv.c: fields,
 * numbers), then, from a temporary file because they resolve paths beside
 * the manifest, the dataset reader (src/dataset/dataset_scan.c: columns, directions)
 * and the photometric-stereo manifest reader (src/range/ps_manifest.c:
 * theta/phi or lx/ly/lz, r g b). Paths in a fuzzed manifest name files that
 * do not exist, so both must fail cleanly: one line, no crash, no leak.
 * `make fuzz` builds and runs it (seeds in tests/fuzz/corpus/fuzz_manifest/).
 */
#include "core/core.h"
#include "io/io.h"
#include "range/range.h"
#include "fuzzutil.h"

#include <string.h>

static void check(int rc, const btf_error *e)
{
    if (rc > 0 || (rc < 0 && (e->code != rc || strchr(e->msg, '\n'))))
        abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* A copy of exactly size bytes, so that ASan sees any over-read. */
    char *copy = malloc(size ? size : 1);
    if (!copy)
        abort();
    if (size)
        memcpy(copy, data, size);
    btf_tsv t;
    btf_error e = {0};
    int rc = btf__tsv_parse(copy, size, "fuzz", &t, &e);
    free(copy);
    check(rc, &e);
    if (rc < 0 && strncmp(e.msg, "fuzz", 4) != 0)
        abort();
    if (rc == 0) {
        for (int r = 0; r < t.nrows; r++)
            for (int c = 0; c < t.ncols; c++) {
                double v;
                btf_error e2 = {0};
                if (!btf__tsv_cell(&t, r, c))
                    abort();
                check(btf__tsv_number(&t, "fuzz", r, c, &v, &e2), &e2);
            }
        btf__tsv_free(&t);
    }
    const char *path = fuzz_input_path("tsv");
    fuzz_write_input(path, data, size);
    btf_dataset *ds = NULL;
    btf_dataset_opts o = {.skip_verify = 1};
    rc = btf_dataset_open(path, &o, &ds, &e);
    check(rc, &e);
    btf_dataset_close(ds);
    btf_ps_result ps;
    btf_photostereo_opts po = {.threads = 1};
    rc = btf__photostereo_manifest(path, &po, &ps, &e);
    check(rc, &e);
    if (rc == 0)
        btf_ps_result_free(&ps);
    return 0;
}
