/*
 * fuzz_image.c — libFuzzer target for the PNG and JPEG paths of the image
 * reader (src/io/image_file.c): the structural probe (PNG IHDR and IEND, JPEG marker
 * walk to the frame header and the end-of-image marker) and, for inputs the
 * probe accepts with a modest size, the decode through OpenCV and the
 * conversion to linear float. OpenCV's decoders are not instrumented; the
 * target checks that btfcar's own code never crashes, leaks or returns a
 * half-filled image. `make fuzz` builds and runs it.
 */
#include "core/core.h"
#include "io/io.h"
#include "fuzzutil.h"

#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fuzz_input_path("img");
    fuzz_write_input(path, data, size);
    btf_image_header h;
    btf_error e = {0};
    int rc = btf_image_probe(path, &h, &e);
    if (rc > 0 || (rc < 0 && (e.code != rc || strncmp(e.msg, path, strlen(path)) != 0)))
        abort();
    if (rc == 0 && h.format != BTF_FILE_EXR && (uint64_t)h.width * h.height <= (1u << 20)) {
        btf_image img;
        rc = btf_image_read(path, NULL, &img, &e);
        if (rc == 0) {
            if (!img.data || img.width != h.width || img.height != h.height)
                abort();
            btf_image_free(&img);
        } else if (img.data) {
            abort();
        }
    }
    return 0;
}
