/*
 * fuzz_library.c — libFuzzer target for the library report's reader of
 * report.json (src/report/library.c through cJSON): any input is a row or
 * a refusal, never a crash, and an accepted row holds only finite,
 * non-negative figures and a preview that names a file in the report's
 * folder. `make fuzz` builds and runs it.
 */
#include "btfcar.h"
#include "report/report.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    btf_library_row r;
    memset(&r, 0, sizeof r);
    if (!btf__library_row_parse((const char *)data, size, &r))
        return 0;
    double v[6] = {r.model_bytes, r.raw_bytes, r.ratio, r.mean, r.worst, r.seconds};
    for (int i = 0; i < 6; i++)
        if (!isfinite(v[i]) || v[i] < 0)
            abort();
    if (r.pairs < 0 || strchr(r.preview, '/') || strstr(r.preview, ".."))
        abort();
    return 0;
}
