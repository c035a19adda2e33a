/*
 * testutil.h — shared helpers for the cmocka test programs.
 * Each tests/test_*.c is its own program, linked with testutil.o and
 * libbtfcar.a; tests/run.sh runs them all and prints the total.
 */
#ifndef BTF_TESTUTIL_H
#define BTF_TESTUTIL_H

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "btfcar.h"

/* A fresh temporary folder (under $TMPDIR or /tmp), removed by tu_rmtree. */
char *tu_tmpdir(void);
void tu_rmtree(const char *path);
/* printf into a static rotating buffer (8 slots): for building paths that
 * are used at once; copy a path that must outlive 8 more calls. */
const char *tu_fmt(const char *fmt, ...);
/* Runs a shell command line, returns its exit status; its stderr is captured
 * into *stderr_text (malloc'd; may be NULL) when non-NULL. */
int tu_run(const char *cmdline, char **stderr_text);
/* The btfcar command under test ($BTF_CLI, else build/btfcar). */
const char *tu_cli(void);
/* Writes bytes to a file; asserts success. */
void tu_write_file(const char *path, const void *data, size_t n);
/* Number of regular files under a folder, recursively. */
int tu_count_files(const char *path);
/* Asserts a btfcar call succeeded, printing the error message if not. */
#define TU_OK(call, errp)                                                      \
    do {                                                                       \
        int tu_rc_ = (call);                                                   \
        if (tu_rc_ != 0)                                                       \
            print_error("%s failed: %s\n", #call, (errp)->msg);                \
        assert_int_equal(tu_rc_, 0);                                           \
    } while (0)

#endif
