/*
 * sweep_gather.c — the points of a sweep split over tasks that wrote to
 * separate folders, gathered into one state folder before the merge
 * (docs/cluster.md): every DIR/sweep/point-*.json (DIR a report
 * folder) or DIR/point-*.json (DIR a state folder itself) copied as it is.
 * The files are self-describing (their options' fingerprint inside), so a
 * copy never mixes sweeps: the merge reads back only those of its options.
 */
#include "btfcar.h"
#include "core/core.h"

#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* A point file's name: point-*.json, nothing else (no path). */
static int is_point_file(const char *name)
{
    size_t n = strlen(name);
    return n > 11 && !strncmp(name, "point-", 6) && !strcmp(name + n - 5, ".json") &&
           !strchr(name, '/');
}

/* DIR/sweep when it is a folder, else DIR. */
static void points_folder(const char *dir, char *out, size_t n)
{
    struct stat st;
    snprintf(out, n, "%s/sweep", dir);
    if (stat(out, &st) != 0 || !S_ISDIR(st.st_mode))
        snprintf(out, n, "%s", dir);
}

static btf_status copy_point(const char *from, const char *to, btf_error *err)
{
    unsigned char *data = NULL;
    size_t n = 0;
    if (btf__read_file(from, 1 << 20, &data, &n, err))
        return BTF_E_IO;
    btf_status rc = btf_write_file_atomic(to, data, n, err);
    free(data);
    return rc;
}

static btf_status gather_one(const char *dir, const char *state_dir, int *copied, btf_error *err)
{
    char src[4096];
    points_folder(dir, src, sizeof src);
    DIR *d = opendir(src);
    if (!d)
        return btf__fail(err, BTF_E_IO, "%s: cannot read the sweep's points: %s", src,
                         strerror(errno));
    btf_status rc = BTF_OK;
    struct dirent *e;
    while (rc == BTF_OK && (e = readdir(d)) != NULL) {
        if (!is_point_file(e->d_name))
            continue;
        char from[4096], to[4096];
        rc = btf__path_join(from, sizeof from, src, e->d_name, err);
        if (rc == BTF_OK)
            rc = btf__path_join(to, sizeof to, state_dir, e->d_name, err);
        if (rc == BTF_OK && strcmp(from, to))
            rc = copy_point(from, to, err);
        *copied += rc == BTF_OK;
    }
    closedir(d);
    return rc;
}

btf_status btf_sweep_gather(const char *const *dirs, int n, const char *state_dir, int *copied,
                            btf_error *err)
{
    if (copied)
        *copied = 0;
    if (!dirs || n < 0 || !state_dir)
        return btf__fail(err, BTF_E_ARG, "sweep: no folders to gather from, or no state folder");
    if (mkdir(state_dir, 0777) != 0 && errno != EEXIST)
        return btf__fail(err, BTF_E_IO, "%s: cannot create the sweep's state folder: %s",
                         state_dir, strerror(errno));
    int count = 0;
    btf_status rc = BTF_OK;
    for (int i = 0; rc == BTF_OK && i < n; i++)
        rc = gather_one(dirs[i], state_dir, &count, err);
    if (copied)
        *copied = count;
    return rc;
}
