/*
 * neighbourhood.c — causal neighbourhoods of the CAR model (paper section
 * II.C): the causality rule (a neighbour lies above, or to the left on the
 * same row, so that synthesis can run the recursion row by row), and the
 * "row:col,row:col" text form the CLI and the reports use.
 */
#include <stdio.h>
#include "core/core.h"
#include "car/car.h"

#include <stdlib.h>

int btf__offset_is_causal(btf_offset o)
{
    return o.row < 0 || (o.row == 0 && o.col < 0);
}

btf_status btf_neighbourhood_parse(const char *spec, btf_offset *offsets, int *n,
                                   btf_error *err)
{
    *n = 0;
    const char *p = spec;
    while (*p) {
        char *end;
        long r = strtol(p, &end, 10);
        if (end == p || *end != ':')
            return btf__fail(err, BTF_E_ARG, "neighbourhood '%s': expected row:col at '%s'", spec, p);
        p = end + 1;
        long c = strtol(p, &end, 10);
        if (end == p || (*end != ',' && *end != '\0'))
            return btf__fail(err, BTF_E_ARG, "neighbourhood '%s': expected row:col at '%s'", spec, p);
        if (r < -64 || r > 64 || c < -64 || c > 64)
            return btf__fail(err, BTF_E_ARG, "neighbourhood '%s': offset %ld:%ld beyond 64", spec, r, c);
        btf_offset o = {(int8_t)r, (int8_t)c};
        if (!btf__offset_is_causal(o))
            return btf__fail(err, BTF_E_ARG, "neighbourhood '%s': offset %ld:%ld is not causal "
                             "(need row < 0, or row 0 and col < 0)", spec, r, c);
        for (int i = 0; i < *n; i++)
            if (offsets[i].row == o.row && offsets[i].col == o.col)
                return btf__fail(err, BTF_E_ARG, "neighbourhood '%s': offset %ld:%ld repeated", spec, r, c);
        if (*n == BTF_CAR_MAX_NEIGHBOURS)
            return btf__fail(err, BTF_E_ARG, "neighbourhood '%s': more than %d offsets", spec,
                             BTF_CAR_MAX_NEIGHBOURS);
        offsets[(*n)++] = o;
        p = *end == ',' ? end + 1 : end;
        if (*end == ',' && *p == '\0')
            return btf__fail(err, BTF_E_ARG, "neighbourhood '%s': trailing comma", spec);
    }
    if (*n == 0)
        return btf__fail(err, BTF_E_ARG, "neighbourhood '%s': empty", spec);
    return BTF_OK;
}

void btf_neighbourhood_format(const btf_offset *offsets, int n, char *buf, size_t len)
{
    size_t k = 0;
    if (len)
        buf[0] = '\0';
    for (int i = 0; i < n && k < len; i++) {
        int w = snprintf(buf + k, len - k, "%s%d:%d", i ? "," : "", offsets[i].row, offsets[i].col);
        if (w < 0)
            break;
        k += (size_t)w;
    }
}
