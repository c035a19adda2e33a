/*
 * fuzz_rti_lp.c — libFuzzer target for RTI light files (.lp, layout
 * BTF_LAYOUT_RTI, src/dataset/rti_lp.c): the parser on the input in memory with
 * the images not looked up (so that the numbers, counts and paths are
 * reached), every light it returns a unit direction above the surface; then,
 * from a temporary file named *.lp, the dataset reader, whose images do not
 * exist: it must fail cleanly (one line, no crash, no leak).
 * `make fuzz` builds and runs it (seeds in tests/fuzz/corpus/fuzz_rti_lp/).
 */
#include "core/core.h"
#include "dataset/dataset.h"
#include "fuzzutil.h"

#include <math.h>
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
    btf_dataset_entries l;
    btf_error e = {0};
    int rc = btf__rti_lp_parse(copy, size, "fuzz", "base", 0, &l, &e);
    free(copy);
    check(rc, &e);
    if (rc < 0 && strncmp(e.msg, "fuzz", 4) != 0 && strncmp(e.msg, "base/", 5) != 0)
        abort();
    if (rc == 0) {
        if (l.count < 1 || l.layout != BTF_LAYOUT_RTI)
            abort();
        for (int i = 0; i < l.count; i++) {
            btf_dir d = l.items[i].light;
            if (!l.items[i].path || !(d.theta >= 0.0 && d.theta < 90.0) ||
                !(d.phi >= 0.0 && d.phi < 360.0) || l.items[i].view.theta != 0.0)
                abort();
        }
    }
    btf__dataset_entries_free(&l);
    const char *path = fuzz_input_path("lp");
    fuzz_write_input(path, data, size);
    btf_dataset *ds = NULL;
    btf_dataset_opts o = {.skip_verify = 1};
    rc = btf_dataset_open(path, &o, &ds, &e);
    check(rc, &e);
    btf_dataset_close(ds);
    return 0;
}
