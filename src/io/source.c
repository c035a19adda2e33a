/*
 * source.c — the bytes an image reader parses: a memory buffer, or a
 * regular file read with pread. The format parsers (io/image_file.c,
 * io/exr_read.c) see only this, so every reader exists once and works on
 * both; a file is never loaded whole unless its decoder needs it in memory
 * (OpenCV's), and an EXR file is read chunk by chunk through its descriptor.
 */
#include "core/core.h"
#include "io/io.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

void btf__source_memory(btf_source *s, const void *data, size_t n, const char *name)
{
    memset(s, 0, sizeof *s);
    s->name = name ? name : "image";
    s->fd = -1;
    s->data = data ? data : (const void *)"";
    s->size = data ? (uint64_t)n : 0;
}

btf_status btf__source_open(btf_source *s, const char *path, btf_error *err)
{
    memset(s, 0, sizeof *s);
    s->name = path;
    s->fd = -1;
    /* A folder or a device has no size to check chunk offsets against, and
     * a FIFO would block the open itself: regular files only. */
    s->fd = btf__open_regular(path, &s->size, err);
    return s->fd < 0 ? BTF_E_IO : BTF_OK;
}

void btf__source_close(btf_source *s)
{
    if (s->fd >= 0)
        close(s->fd);
    s->fd = -1;
}

int64_t btf__source_read(btf_source *s, void *buf, uint64_t n, uint64_t offset)
{
    /* Offsets come from the file and may be anything: a request past the
     * end returns what exists, and the parser reports the short read. */
    if (offset >= s->size)
        return 0;
    if (n > s->size - offset)
        n = s->size - offset;
    if (s->fd < 0) {
        memcpy(buf, s->data + offset, (size_t)n);
        return (int64_t)n;
    }
    uint64_t done = 0;
    while (done < n) {
        uint64_t left = n - done;
        size_t want = left > ((uint64_t)1 << 30) ? (size_t)1 << 30 : (size_t)left;
        ssize_t r = pread(s->fd, (char *)buf + done, want, (off_t)(offset + done));
        if (r < 0) {
            if (errno == EINTR)
                continue;
            s->sys_errno = errno;
            return -1;
        }
        if (r == 0)
            break;
        done += (uint64_t)r;
    }
    return (int64_t)done;
}

btf_status btf__source_bytes(btf_source *s, const unsigned char **data, unsigned char **owned,
                             btf_error *err)
{
    *owned = NULL;
    if (s->fd < 0) {
        *data = s->data;
        return BTF_OK;
    }
    if (s->size > (uint64_t)SIZE_MAX - 1)
        return btf__fail(err, BTF_E_NOMEM, "%s: too large to load (%llu bytes)", s->name,
                         (unsigned long long)s->size);
    unsigned char *buf = malloc(s->size ? (size_t)s->size : 1);
    if (!buf)
        return btf__fail(err, BTF_E_NOMEM, "%s: out of memory", s->name);
    int64_t got = btf__source_read(s, buf, s->size, 0);
    if (got < 0 || (uint64_t)got != s->size) {
        free(buf);
        return got < 0 ? btf__fail(err, BTF_E_IO, "%s: read error: %s", s->name,
                                   strerror(s->sys_errno))
                       : btf__fail(err, BTF_E_IO, "%s: the file shrank while being read",
                                   s->name);
    }
    *data = buf;
    *owned = buf;
    return BTF_OK;
}
