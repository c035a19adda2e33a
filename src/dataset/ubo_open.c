/*
 * ubo_open.c — a Bonn .btf file opened for the dataset interface: the file
 * is memory-mapped (read-only, shared), never read into the heap, so memory
 * stays bounded by the factor matrices the kernel pages in; the parse
 * (dataset/ubo_parse.c) points into the mapping. The file's view and light lists
 * (radians, notes §2b) become btfcar direction sets (degrees, ring by ring),
 * with the file's index of each direction; a list with a direction twice is
 * refused, since a (view, light) pair would then be ambiguous.
 */
#include <stdio.h>
#include "core/core.h"
#include "dataset/ubo2014.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

int ubo_sniff(const char *path)
{
    int fd = btf__open_regular(path, NULL, NULL); /* no FIFO, device or folder */
    if (fd < 0)
        return 0;
    unsigned char head[8] = {0};
    int ok = read(fd, head, 8) == 8;
    close(fd);
    if (!ok || head[0] != '!')
        return 0;
    return !memcmp(head + 1, "DFMF", 4) || !memcmp(head + 1, "FMF", 3) ||
           !memcmp(head + 1, "PVF", 3) || !memcmp(head + 1, "BDIF", 4);
}

/* The set of the file's directions and, per set index, the file's index. */
static btf_status make_set(const ubo_file *f, const float *rad, uint32_t n, const char *what,
                           btf_dirset *set, uint32_t **index, btf_error *err)
{
    btf_dir *d = btf__alloc(n, sizeof *d, err);
    if (!d)
        return BTF_E_NOMEM;
    for (uint32_t i = 0; i < n; i++) {
        double t = rad[2 * i] * (180.0 / 3.14159265358979323846);
        d[i].theta = t > 90.0 ? 90.0 : t; /* float rounding of pi/2 */
        d[i].phi = rad[2 * i + 1] * (180.0 / 3.14159265358979323846);
    }
    btf_status rc = btf_dirset_from_list(set, d, (int)n, err);
    if (rc == BTF_OK && (uint32_t)set->count != n)
        rc = btf__fail(err, BTF_E_FORMAT, "%s: the %s list names a direction twice (%u entries, "
                       "%d distinct)", f->name, what, n, set->count);
    if (rc == BTF_OK) {
        *index = btf__alloc(n, sizeof **index, err);
        rc = *index ? BTF_OK : BTF_E_NOMEM;
        for (uint32_t i = 0; rc == BTF_OK && i < n; i++)
            (*index)[i] = UINT32_MAX;
        for (uint32_t i = 0; rc == BTF_OK && i < n; i++) {
            /* A known set's exact values replace the file's (within 0.75
             * degree); the nearest one is the file's direction. */
            int j = btf_dirset_find(set, d[i], BTF_DIR_NAME_TOLERANCE);
            if (j < 0 || (*index)[j] != UINT32_MAX)
                rc = btf__fail(err, BTF_E_FORMAT,
                               "%s: %s %u (theta %g, phi %g degrees) cannot be told from another",
                               f->name, what, i, d[i].theta, d[i].phi);
            else
                (*index)[j] = i;
        }
    }
    free(d);
    return rc;
}

void ubo_close(ubo_open_file *o)
{
    if (!o)
        return;
    ubo_free(&o->f);
    if (o->map)
        munmap(o->map, o->map_size);
    btf_dirset_free(&o->views);
    btf_dirset_free(&o->lights);
    BTF_FREE_ALL(o->view_index, o->light_index, o);
}

btf_status ubo_open(const char *path, ubo_open_file **out, btf_error *err)
{
    *out = NULL;
    ubo_open_file *o = btf__calloc(1, sizeof *o, err);
    if (!o)
        return BTF_E_NOMEM;
    uint64_t size;
    int fd = btf__open_regular(path, &size, err);
    if (fd < 0) {
        free(o);
        return BTF_E_IO;
    }
    btf_status rc = BTF_OK;
    if (size == 0)
        rc = btf__fail(err, BTF_E_FORMAT, "%s: empty file", path);
    if (rc == BTF_OK) {
        o->map_size = (size_t)size;
        o->map = mmap(NULL, o->map_size, PROT_READ, MAP_SHARED, fd, 0);
        if (o->map == MAP_FAILED) {
            o->map = NULL;
            rc = btf__fail(err, BTF_E_IO, "%s: cannot map %llu bytes: %s", path,
                           (unsigned long long)size, strerror(errno));
        }
    }
    close(fd);
    if (rc == BTF_OK)
        rc = ubo_parse(o->map, o->map_size, path, 0, &o->f, err);
    if (rc == BTF_OK)
        rc = make_set(&o->f, o->f.view_rad, o->f.nv, "view", &o->views, &o->view_index, err);
    if (rc == BTF_OK)
        rc = make_set(&o->f, o->f.light_rad, o->f.nl, "light", &o->lights, &o->light_index, err);
    if (rc) {
        ubo_close(o);
        return rc;
    }
    *out = o;
    return BTF_OK;
}
