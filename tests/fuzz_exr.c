/*
 * fuzz_exr.c — libFuzzer target for the EXR reader (src/io/exr.c). Each input
 * is written to a temporary file (the reader works on paths), probed, and,
 * when the probe accepts it and the image is modest, read with each channel
 * setting (as in file, grey, RGB). The reader must never crash, leak, print
 * or return a half-filled image; failures must be one line naming the file.
 *
 * Build from the repository root. The reader needs only exr_io.c, util.c and
 * image.c (which refers to the OpenCV bridge); `make fuzz` links the whole
 * library instead, which works as well:
 *
 *   mkdir -p build-fuzz
 *   clang++ -std=c++17 -g -O1 -fsanitize=address,undefined -fno-sanitize=vptr -fPIC \
 *       -Iinclude -Isrc -I/usr/include/opencv4 -c src/io/cv_bridge.cpp \
 *       -o build-fuzz/cv_bridge.o
 *   clang -std=c11 -g -O1 -fsanitize=fuzzer,address,undefined -ffp-contract=off \
 *       -Iinclude -Isrc -I/usr/include/OpenEXR -D_DEFAULT_SOURCE \
 *       -DBTF_EXR_MAX_CHUNK_BYTES='(64u << 20)' \
 *       -o build-fuzz/fuzz_exr tests/fuzz_exr.c src/io/exr.c src/core/files.c src/io/image_file.c \
 *       build-fuzz/cv_bridge.o -lopencv_imgcodecs -lopencv_imgproc -lopencv_core \
 *       -lOpenEXRCore-3_1 -lstdc++ -lm -lpthread
 *
 * (-DBTF_EXR_MAX_CHUNK_BYTES keeps the library's per-chunk buffers well under
 * libFuzzer's default 2 GB memory limit; -fno-sanitize=vptr because the C
 * link lacks the C++ UBSan runtime.)
 *
 * Run with a seed corpus of small EXR files (a few KB each: btf_exr_write
 * output, and files from other writers with other compressions and tiles):
 *
 *   mkdir -p build-fuzz/corpus_exr   (and copy the seed files there)
 *   ./build-fuzz/fuzz_exr -max_total_time=60 -max_len=65536 build-fuzz/corpus_exr
 *
 * OpenEXRCore itself is not instrumented unless rebuilt with the sanitizers,
 * so memory errors inside it show only where they reach our code.
 */
#include "core/core.h"
#include "io/io.h"
#include "fuzzutil.h"

#include <fcntl.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Images above this many pixels are only probed, not decoded: their output
 * buffer alone could exceed libFuzzer's memory limit. */
#define FUZZ_MAX_PIXELS (1u << 20)

/* Failures are one line that starts with the file name. */
static void check_error(const char *path, int rc, const btf_error *e)
{
    if (rc >= 0 || rc < BTF_E_NUMERIC || e->code != rc)
        abort();
    if (strncmp(e->msg, path, strlen(path)) != 0 || strchr(e->msg, '\n'))
        abort();
}

static void check_read(const char *path, int channels, const btf_image_header *h)
{
    btf_image img;
    btf_error e = {0};
    int rc = btf_exr_read(path, channels, &img, &e);
    if (rc != 0) {
        check_error(path, rc, &e);
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
    const char *path = fuzz_input_path("exr");
    fuzz_write_input(path, data, size);
    btf_image_header h;
    btf_error e = {0};
    int rc = btf_exr_probe(path, &h, &e);
    if (rc != 0) {
        check_error(path, rc, &e);
        return 0;
    }
    if (h.format != BTF_FILE_EXR || h.width < 1 || h.height < 1 ||
        (h.channels != 1 && h.channels != 3) || (h.bits != 16 && h.bits != 32) ||
        h.file_bytes != size)
        abort();
    if ((uint64_t)h.width * (uint64_t)h.height > FUZZ_MAX_PIXELS)
        return 0;
    check_read(path, 0, &h);
    check_read(path, 1, &h);
    check_read(path, 3, &h);
    return 0;
}
