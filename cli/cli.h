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
/* Fills a library error record from the CLI (message and code); returns code. */
int cli_set_error(btf_error *err, int code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
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
int cmd_photostereo(int argc, char **argv);
int cmd_analyse(int argc, char **argv);
int cmd_texture_fit(int argc, char **argv);
int cmd_synthesise(int argc, char **argv);

/* Model options (--levels, --neighbourhood) shared by analyse and
 * texture-fit: returns 1 if argv[*i] was one (advancing *i), with *rc the
 * exit status of a usage error (0 when fine). */
int cli_model_option(const cli_ctx *c, int argc, char **argv, int *i, btf_fit_opts *fo, int *rc);
/* A btf_warning_fn printing "btfcar CMD: warning: ..." (user: the cli_ctx). */
void cli_warning(void *user, const char *message);
/* The CAR parameters of one subspace, as text. */
void cli_print_subspace(const btf_subspace_model *s, int index);


#endif
