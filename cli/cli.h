/*
 * cli.h — shared pieces of the btfcar command: option parsing helpers,
 * the progress bar and error reporting. Each subcommand is one file.
 */
#ifndef BTF_CLI_H
#define BTF_CLI_H

#include "btfcar.h"

#include <stdio.h>

typedef struct cli_ctx {
    const char *cmd;  /* the subcommand's name, for messages */
    int quiet;        /* --quiet: no progress bar, no notes */
} cli_ctx;

/* Prints "btfcar CMD: message" on stderr; returns the exit status 1. */
int cli_error(const cli_ctx *c, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
/* Prints the library's error message and returns 1. */
int cli_lib_error(const cli_ctx *c, const btf_error *err);
/* "Usage: ..." hint for a wrong option; returns 2. */
int cli_usage_error(const cli_ctx *c, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

/* Strict number parsing: the whole string must be a number in range. */
int cli_parse_int(const char *s, long lo, long hi, long *out);
int cli_parse_u64(const char *s, uint64_t *out);
/* "WxH" */
int cli_parse_size(const char *s, int *w, int *h);

/* A progress callback drawing a bar on stderr when it is a terminal. */
void cli_progress(void *user, double fraction, const char *what);
/* The progress callback to use (NULL when quiet or not a terminal). */
btf_progress_fn cli_progress_fn(const cli_ctx *c);
/* Ends a progress line (newline) if one was drawn. */
void cli_progress_done(void);

/* "12.3 MB" */
void cli_format_bytes(uint64_t bytes, char *buf, size_t n);

int cmd_generate(int argc, char **argv);
int cmd_info(int argc, char **argv);
int cmd_analyse(int argc, char **argv);

#endif
