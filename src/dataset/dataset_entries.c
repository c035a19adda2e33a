/*
 * dataset_entries.c — the list of (path, light, view) entries that every
 * layout's reader fills (dataset/dataset.h): the folder scan and manifests
 * (dataset/dataset_scan.c) and RTI light files (dataset/rti_lp.c), which
 * the scan calls. In a file of its own so that both share one copy without
 * either calling the other back (docs/design.md, no call cycles).
 */
#include "core/core.h"
#include "dataset/dataset.h"
#include "io/io.h"

#include <stdlib.h>
#include <string.h>

btf_status btf__dataset_entries_add(btf_dataset_entries *l, const char *path, btf_dir light,
                                    btf_dir view, btf_error *err)
{
    if (l->count == l->cap) {
        int ncap = l->cap ? l->cap * 2 : 256;
        btf_dataset_entry *n = realloc(l->items, (size_t)ncap * sizeof *n);
        if (!n)
            return btf__fail(err, BTF_E_NOMEM, "out of memory listing the dataset");
        l->items = n;
        l->cap = ncap;
    }
    char *p = strdup(path);
    if (!p)
        return btf__fail(err, BTF_E_NOMEM, "out of memory listing the dataset");
    l->items[l->count++] = (btf_dataset_entry){p, light, view, {0}};
    return BTF_OK;
}

void btf__dataset_entries_free(btf_dataset_entries *l)
{
    for (int i = 0; i < l->count; i++)
        free(l->items[i].path);
    free(l->items);
    memset(l, 0, sizeof *l);
}

btf_status btf__dataset_entries_repeat(const btf_dataset_entries *l, int *first, int *again,
                                       btf_error *err)
{
    const char **names = btf__alloc((size_t)(l->count > 0 ? l->count : 1), sizeof *names, err);
    if (!names)
        return BTF_E_NOMEM;
    for (int i = 0; i < l->count; i++)
        names[i] = l->items[i].path;
    btf_status rc = btf__first_repeat(names, l->count, first, again, err);
    free(names);
    return rc;
}
