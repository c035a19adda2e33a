/*
 * alloc.c — malloc and calloc that report BTF_E_NOMEM through btf_error and
 * check the size product for overflow; the memory this process can still
 * get, for refusing work that cannot fit before doing it.
 */
#include "core/core.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

void *btf__alloc(size_t count, size_t size, btf_error *err)
{
    if (size && count > SIZE_MAX / size) {
        btf__fail(err, BTF_E_NOMEM, "allocation of %zu x %zu bytes overflows", count, size);
        return NULL;
    }
    size_t bytes = count * size;
    void *p = malloc(bytes > 0 ? bytes : 1);
    if (!p)
        btf__fail(err, BTF_E_NOMEM, "out of memory allocating %zu bytes", count * size);
    return p;
}

void *btf__calloc(size_t count, size_t size, btf_error *err)
{
    void *p = calloc(count ? count : 1, size ? size : 1);
    if (!p)
        btf__fail(err, BTF_E_NOMEM, "out of memory allocating %zu x %zu bytes", count, size);
    return p;
}

void btf__free_list(void *const *ptrs, size_t n)
{
    for (size_t i = 0; i < n; i++)
        free(ptrs[i]);
}

btf_status btf__opts_take(void *dst, size_t dst_size, const void *src, const void *defaults,
                          const char *what, btf_error *err)
{
    if (!src) {
        memcpy(dst, defaults, dst_size);
        return BTF_OK;
    }
    size_t n;
    memcpy(&n, src, sizeof n); /* struct_size, the first member of every options struct */
    if (n == 0)
        n = dst_size;
    if (n < sizeof n || n > dst_size)
        return btf__fail(err, BTF_E_ARG,
                         "%s: options struct of %zu bytes, this library's has %zu (built against "
                         "another btfcar header?)",
                         what, n, dst_size);
    memset(dst, 0, dst_size);
    memcpy(dst, src, n);
    memcpy(dst, &dst_size, sizeof dst_size);
    return BTF_OK;
}

/* A "Key:   N kB" line of /proc/meminfo, in bytes; 0 when absent. */
static uint64_t meminfo_bytes(const char *text, const char *key)
{
    const char *p = strstr(text, key);
    unsigned long long kb = 0;
    if (!p || sscanf(p + strlen(key), " %llu kB", &kb) != 1)
        return 0;
    return (uint64_t)kb * 1024u;
}

/* The first number in a small file (a cgroup's memory.max reads "max" when
 * unlimited: UINT64_MAX then, as when the file is absent). */
static uint64_t file_number(const char *path)
{
    FILE *f = fopen(path, "r");
    unsigned long long v = 0;
    int ok = f && fscanf(f, "%llu", &v) == 1;
    if (f)
        fclose(f);
    return ok ? (uint64_t)v : UINT64_MAX;
}

static uint64_t min_u64(uint64_t a, uint64_t b)
{
    return a < b ? a : b;
}

uint64_t btf__memory_available(void)
{
    /* The kernel's estimate of what can be allocated without swapping out
     * (MemAvailable counts reclaimable caches), plus free swap; without
     * /proc, the physical memory. */
    char text[4096];
    FILE *f = fopen("/proc/meminfo", "r");
    size_t n = f ? fread(text, 1, sizeof text - 1, f) : 0;
    if (f)
        fclose(f);
    text[n] = '\0';
    uint64_t avail = meminfo_bytes(text, "MemAvailable:");
    if (avail)
        avail += meminfo_bytes(text, "SwapFree:");
    else {
        long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
        avail = pages > 0 && page > 0 ? (uint64_t)pages * (uint64_t)page : UINT64_MAX;
    }
    /* A container's limit (cgroup v2) and this process's address space
     * limit (ulimit -v) bound it too. */
    uint64_t max = file_number("/sys/fs/cgroup/memory.max");
    uint64_t used = file_number("/sys/fs/cgroup/memory.current");
    if (max != UINT64_MAX && used != UINT64_MAX)
        avail = min_u64(avail, max > used ? max - used : 0);
    struct rlimit rl;
    if (getrlimit(RLIMIT_AS, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY)
        avail = min_u64(avail, (uint64_t)rl.rlim_cur);
    return avail;
}
