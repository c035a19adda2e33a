/*
 * fuzz_btf.c — libFuzzer target for the Bonn .btf header parser and the
 * image reconstruction (src/dataset/ubo_parse.c, src/dataset/ubo_decode.c;
 * docs/datasets.md, "UBO2014 .btf files"). Any input must be refused with one
 * line naming it (no newline) or parse into sizes that fit the input; then
 * the first and the last (view, light) images are reconstructed, which must
 * read nothing outside the input (ASan sees a copy of exactly size bytes).
 *
 * Seeds (tests/fuzz/corpus/fuzz_btf/) are small files from the writers:
 * DFMF with half and float factors, colour models 0 and 11, the cosine
 * flag, and BDIF (btf_ubo2014_write, btf__ubo2014_write_factors); FMF under
 * each signature (half, float, double; header versions 0 and 2, the
 * dynamic-range flag, a height map, the transposed layout) and PVF (both
 * orientations, the legacy header), from tests/unit/test_btf_variants.c's
 * test_fuzz_seeds (BTF_FUZZ_SEEDS=DIR writes them there).
 *
 *   make fuzz-build && build-fuzz/fuzz_btf -max_total_time=60 \
 *       build-fuzz/corpus/fuzz_btf tests/fuzz/corpus/fuzz_btf
 */
#include "dataset/ubo2014.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    unsigned char *copy = malloc(size ? size : 1);
    if (!copy)
        return 0;
    memcpy(copy, data, size);
    ubo_file f;
    btf_error err = {0};
    btf_status rc = ubo_parse(copy, size, "fuzz", 0, &f, &err);
    if (rc != BTF_OK) {
        if (!err.msg[0] || strncmp(err.msg, "fuzz", 4) != 0 || strchr(err.msg, '\n'))
            abort(); /* every failure names the input in one line */
        free(copy);
        return 0;
    }
    uint64_t px = (uint64_t)f.width * f.height;
    if (f.nv < 1 || f.nl < 1 || px < 1)
        abort();
    if (px <= (1u << 20)) {
        float *img = malloc(px * 3 * sizeof *img);
        if (img) {
            ubo_decode(&f, 0, 0, img, &err);
            ubo_decode(&f, f.nv - 1, f.nl - 1, img, &err);
            free(img);
        }
    }
    ubo_free(&f);
    free(copy);
    return 0;
}
