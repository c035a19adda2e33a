/*
 * fuzz_image.c — libFuzzer target for the PNG and JPEG paths of the image
 * decoder (src/io/image_file.c), fed from memory: the structural probe (PNG
 * IHDR and IEND, JPEG marker walk to the frame header and the end-of-image
 * marker) and, for inputs the probe accepts with a modest size, the decode
 * through OpenCV and the conversion to linear float. OpenCV's decoders are
 * not instrumented; the target checks that btfcar's own code never crashes,
 * leaks or returns a half-filled image, and that failures are one line
 * naming the input. `make fuzz` builds and runs it.
 */
#include "btfcar.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define NAME "fuzz"

static void check_error(int rc, const btf_error *e)
{
    if (rc > 0 || (rc < 0 && (e->code != rc || strncmp(e->msg, NAME ": ", 6) != 0 ||
                              strchr(e->msg, '\n'))))
        abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* A copy of exactly size bytes, so that ASan sees any over-read. */
    unsigned char *copy = malloc(size ? size : 1);
    if (!copy)
        abort();
    if (size)
        memcpy(copy, data, size);
    btf_image_header h;
    btf_error e = {0};
    int rc = btf_image_probe_memory(copy, size, NAME, &h, &e);
    check_error(rc, &e);
    if (rc == 0 && h.format != BTF_FILE_EXR && (uint64_t)h.width * h.height <= (1u << 20)) {
        static const btf_read_opts opts[2] = {{0}, {.channels = 1, .linear_8bit = 1}};
        for (int k = 0; k < 2; k++) {
            btf_image img;
            rc = btf_image_decode(copy, size, NAME, &opts[k], &img, &e);
            check_error(rc, &e);
            if (rc == 0) {
                if (!img.data || img.width != h.width || img.height != h.height)
                    abort();
                btf_image_free(&img);
            } else if (img.data) {
                abort();
            }
        }
    }
    free(copy);
    return 0;
}
