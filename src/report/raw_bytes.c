/*
 * raw_bytes.c — the raw BTF a dataset holds, the denominator of the
 * report's compression ratios: the measured images (views x lights of a
 * full grid, a sparse set's pairs) of width x height RGB
 * at 8 bits per value, and the bytes its files take on disk
 * (docs/report-compression.md).
 */
#include "report/report.h"

#include <string.h>

void btf__raw_bytes_of(const btf_dataset_info *info, btf_raw_bytes *out)
{
    memset(out, 0, sizeof *out);
    out->views = info->n_views;
    out->lights = info->n_lights;
    out->width = info->width;
    out->height = info->height;
    /* the images measured: every pair of a full grid, a sparse set's own */
    out->raw = (uint64_t)info->n_pairs * (uint64_t)info->width * (uint64_t)info->height * 3u;
    out->on_disk = info->bytes_on_disk;
}

btf_status btf__dataset_raw_bytes(const btf_dataset *ds, btf_raw_bytes *out, btf_error *err)
{
    if (!out)
        return btf__fail(err, BTF_E_ARG, "dataset: no raw-bytes result to fill");
    memset(out, 0, sizeof *out);
    if (!ds)
        return btf__fail(err, BTF_E_ARG, "dataset: no dataset to account for");
    btf__raw_bytes_of(btf_dataset_get_info(ds), out);
    return BTF_OK;
}
