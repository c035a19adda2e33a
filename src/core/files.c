/*
 * files.c — atomic file writing (a temporary name beside the target, renamed
 * into place), whole-file reads with a size bound, folders and paths.
 */
#include "core/core.h"

#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

int btf_tmp_path(const char *path, char *tmp, size_t n, btf_error *err)
{
    /* The pid and a counter make names unique across processes and threads
     * of one process (the counter is atomic). */
    static _Atomic unsigned long counter;
    unsigned long c = ++counter;
    int k = snprintf(tmp, n, "%s.tmp%ld.%lu", path, (long)getpid(), c);
    if (k < 0 || (size_t)k >= n)
        return btf_fail(err, BTF_E_ARG, "%s: path too long", path);
    return BTF_OK;
}

int btf_commit_file(const char *tmp, const char *path, btf_error *err)
{
    if (rename(tmp, path) != 0) {
        int e = errno;
        remove(tmp);
        return btf_fail(err, BTF_E_IO, "%s: cannot rename into place: %s", path, strerror(e));
    }
    return BTF_OK;
}

void btf_abort_file(const char *tmp)
{
    remove(tmp);
}

btf_status btf_write_file_atomic(const char *path, const void *data, size_t n, btf_error *err)
{
    char tmp[4096];
    int rc = btf_tmp_path(path, tmp, sizeof tmp, err);
    if (rc)
        return rc;
    FILE *f = fopen(tmp, "wb");
    if (!f)
        return btf_fail(err, BTF_E_IO, "%s: cannot create: %s", path, strerror(errno));
    size_t w = n ? fwrite(data, 1, n, f) : 0; /* data may be NULL when n is 0 */
    int bad = (w != n) | (fflush(f) != 0);
    int e = errno;
    bad |= fclose(f) != 0;
    if (bad) {
        btf_abort_file(tmp);
        return btf_fail(err, BTF_E_IO, "%s: write failed: %s", path, strerror(e));
    }
    return btf_commit_file(tmp, path, err);
}

int btf_read_file(const char *path, size_t max_bytes, unsigned char **data,
                  size_t *n, btf_error *err)
{
    *data = NULL;
    *n = 0;
    FILE *f = fopen(path, "rb");
    if (!f)
        return btf_fail(err, BTF_E_IO, "%s: cannot open: %s", path, strerror(errno));
    size_t cap = 1 << 16, len = 0;
    unsigned char *buf = malloc(cap);
    if (!buf) {
        fclose(f);
        return btf_fail(err, BTF_E_NOMEM, "%s: out of memory", path);
    }
    for (;;) {
        if (len == cap) {
            if (cap >= max_bytes) {
                free(buf);
                fclose(f);
                return btf_fail(err, BTF_E_FORMAT, "%s: larger than %zu bytes", path, max_bytes);
            }
            size_t ncap = cap * 2 > max_bytes ? max_bytes : cap * 2;
            unsigned char *nb = realloc(buf, ncap);
            if (!nb) {
                free(buf);
                fclose(f);
                return btf_fail(err, BTF_E_NOMEM, "%s: out of memory", path);
            }
            buf = nb;
            cap = ncap;
        }
        size_t r = fread(buf + len, 1, cap - len, f);
        len += r;
        if (r == 0)
            break;
    }
    int bad = ferror(f);
    fclose(f);
    if (bad) {
        free(buf);
        return btf_fail(err, BTF_E_IO, "%s: read error", path);
    }
    *data = buf;
    *n = len;
    return BTF_OK;
}

btf_status btf_mkdirs(const char *path, btf_error *err)
{
    char buf[4096];
    size_t len = strlen(path);
    if (len == 0 || len >= sizeof buf)
        return btf_fail(err, BTF_E_ARG, "'%s': bad folder name", path);
    memcpy(buf, path, len + 1);
    for (size_t i = 1; i <= len; i++) {
        if (buf[i] == '/' || buf[i] == '\0') {
            char c = buf[i];
            buf[i] = '\0';
            if (mkdir(buf, 0777) != 0 && errno != EEXIST)
                return btf_fail(err, BTF_E_IO, "%s: cannot create folder: %s", buf, strerror(errno));
            buf[i] = c;
        }
    }
    struct stat st;
    if (stat(path, &st) != 0 || !S_ISDIR(st.st_mode))
        return btf_fail(err, BTF_E_IO, "%s: exists and is not a folder", path);
    return BTF_OK;
}

int btf_path_join(char *out, size_t n, const char *dir, const char *name, btf_error *err)
{
    size_t dl = strlen(dir);
    int slash = dl > 0 && dir[dl - 1] != '/';
    int k = snprintf(out, n, "%s%s%s", dir, slash ? "/" : "", name);
    if (k < 0 || (size_t)k >= n)
        return btf_fail(err, BTF_E_ARG, "%s/%s: path too long", dir, name);
    return BTF_OK;
}

void btf_remove_tree(const char *path)
{
    DIR *d = opendir(path);
    if (d) {
        struct dirent *e;
        while ((e = readdir(d))) {
            if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
                continue;
            char sub[4096];
            snprintf(sub, sizeof sub, "%s/%s", path, e->d_name);
            struct stat st;
            if (lstat(sub, &st) == 0 && S_ISDIR(st.st_mode))
                btf_remove_tree(sub);
            else
                remove(sub);
        }
        closedir(d);
    }
    rmdir(path);
}
