/*
 * fuzzutil.h — what the libFuzzer targets share: for the readers that work
 * on paths (a dataset manifest names files beside it), the input is written
 * to a per-process temporary file first; the parsers take it from memory.
 * Header-only, because `make fuzz` builds every tests/fuzz/fuzz_*.c on its own.
 */
#ifndef BTF_FUZZUTIL_H
#define BTF_FUZZUTIL_H

#include <fcntl.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

static char fuzz_path[512];

static void fuzz_remove_file(void)
{
    if (fuzz_path[0])
        unlink(fuzz_path);
}

/* A temporary file name for this process, removed at exit. */
static const char *fuzz_input_path(const char *ext)
{
    if (!fuzz_path[0]) {
        const char *tmp = getenv("TMPDIR");
        snprintf(fuzz_path, sizeof fuzz_path, "%s/fuzz_input.%ld.%s",
                 tmp && *tmp ? tmp : "/tmp", (long)getpid(), ext);
        atexit(fuzz_remove_file);
    }
    return fuzz_path;
}

static void fuzz_write_input(const char *path, const uint8_t *data, size_t size)
{
    int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    if (fd < 0)
        abort();
    size_t done = 0;
    while (done < size) {
        ssize_t w = write(fd, data + done, size - done);
        if (w <= 0)
            abort();
        done += (size_t)w;
    }
    close(fd);
}

#endif
