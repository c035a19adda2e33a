/*
 * alloc.c — malloc and calloc that report BTF_E_NOMEM through btf_error and
 * check the size product for overflow.
 */
#include "core/core.h"

#include <stdint.h>
#include <stdlib.h>

void *btf_alloc(size_t count, size_t size, btf_error *err)
{
    if (size && count > SIZE_MAX / size) {
        btf_fail(err, BTF_E_NOMEM, "allocation of %zu x %zu bytes overflows", count, size);
        return NULL;
    }
    size_t bytes = count * size;
    void *p = malloc(bytes > 0 ? bytes : 1);
    if (!p)
        btf_fail(err, BTF_E_NOMEM, "out of memory allocating %zu bytes", count * size);
    return p;
}

void *btf_calloc(size_t count, size_t size, btf_error *err)
{
    void *p = calloc(count ? count : 1, size ? size : 1);
    if (!p)
        btf_fail(err, BTF_E_NOMEM, "out of memory allocating %zu x %zu bytes", count, size);
    return p;
}
