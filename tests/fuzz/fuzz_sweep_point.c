/*
 * fuzz_sweep_point.c — libFuzzer target for the sweep's state files
 * (DIR/sweep/point-*.json, read back to resume an interrupted sweep;
 * src/report/sweep.c through cJSON): any input is a point or a refusal,
 * never a crash, and an accepted point holds only values a measurement can
 * give. `make fuzz` builds and runs it (seeds in
 * tests/fuzz/corpus/fuzz_sweep_point/).
 */
#include "btfcar.h"
#include "report/report.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    btf_sweep_point p;
    memset(&p, 0, sizeof p);
    p.setting.subspaces = 2;
    p.setting.levels = 1;
    if (!btf__sweep_point_parse((const char *)data, size, "fp", &p))
        return 0;
    if (p.k < 1 || p.k > 255 || p.bytes < 1 || !isfinite(p.mean_combined) ||
        p.worst_combined < p.mean_combined || !p.resumed)
        abort();
    return 0;
}
