/*
 * fuzz_exr.c — libFuzzer target for the EXR reader (src/io/exr_read.c),
 * fed from memory through a byte source: each input is probed and, when
 * the probe accepts it and the image is modest, read with each channel
 * setting (as in file, grey, RGB). The reader must never crash, leak, print
 * or return a half-filled image; failures must be one line naming the input.
 *
 * `make fuzz-build` builds it with the whole library instrumented (clang,
 * ASan + UBSan, -DBTF_EXR_MAX_CHUNK_BYTES='(64u << 20)' to keep the
 * library's per-chunk buffers well under libFuzzer's memory limit); `make
 * fuzz` runs it from the seed corpus tests/fuzz/corpus/fuzz_exr/ (small EXR
 * files: btf_image_write_exr_opts output, and files from other writers with
 * other compressions and tiles). By hand:
 *
 *   ./build-fuzz/fuzz_exr -max_total_time=60 -max_len=65536 build-fuzz/corpus/fuzz_exr \
 *       tests/fuzz/corpus/fuzz_exr
 *
 * OpenEXRCore itself is not instrumented unless rebuilt with the sanitizers,
 * so memory errors inside it show only where they reach our code.
 */
#include "core/core.h"
#include "io/io.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define NAME "fuzz"

/* Images above this many pixels are only probed, not decoded: their output
 * buffer alone could exceed libFuzzer's memory limit. */
#define FUZZ_MAX_PIXELS (1u << 20)

/* Failures are one line that starts with the input's name. */
static void check_error(int rc, const btf_error *e)
{
    if (rc >= 0 || rc < BTF_E_NUMERIC || e->code != rc)
        abort();
    if (strncmp(e->msg, NAME ": ", 6) != 0 || strchr(e->msg, '\n'))
        abort();
}

static void check_read(const unsigned char *data, size_t size, int channels,
                       const btf_image_header *h)
{
    btf_source src;
    btf__source_memory(&src, data, size, NAME);
    btf_image img;
    btf_error e = {0};
    int rc = btf__exr_read_source(&src, channels, 0, &img, &e);
    if (rc != 0) {
        check_error(rc, &e);
        if (img.data)
            abort(); /* no half-filled image on failure */
        return;
    }
    int want = channels ? channels : h->channels;
    if (img.width != h->width || img.height != h->height || img.channels != want)
        abort();
    size_t n = (size_t)img.width * img.height * img.channels;
    for (size_t i = 0; i < n; i++)
        if (!isfinite(img.data[i]))
            abort(); /* NaN/Inf must have been reported */
    btf_image_free(&img);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* A copy of exactly size bytes, so that ASan sees any over-read. */
    unsigned char *copy = malloc(size ? size : 1);
    if (!copy)
        abort();
    if (size)
        memcpy(copy, data, size);
    btf_source src;
    btf__source_memory(&src, copy, size, NAME);
    btf_image_header h;
    btf_error e = {0};
    int rc = btf__exr_probe_source(&src, &h, &e);
    if (rc != 0) {
        check_error(rc, &e);
        free(copy);
        return 0;
    }
    if (h.format != BTF_FILE_EXR || h.width < 1 || h.height < 1 ||
        (h.channels != 1 && h.channels != 3) || (h.bits != 16 && h.bits != 32) ||
        h.file_bytes != size)
        abort();
    if ((uint64_t)h.width * (uint64_t)h.height <= FUZZ_MAX_PIXELS) {
        check_read(copy, size, 0, &h);
        check_read(copy, size, 1, &h);
        check_read(copy, size, 3, &h);
    }
    free(copy);
    return 0;
}
