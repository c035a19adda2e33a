/*
 * options.h — the command line's one option table, in the manner of libvips'
 * VIPS_ARG_* declarations: each option is one row (name, value kind, where
 * the value goes, its range or choices, help text), and the parser, the
 * usage line, the --help text and every "needs ..." message are made from
 * the rows. Defaults are not written in the table: the destination is filled
 * with the library's defaults (btf_*_defaults()) before parsing, and --help
 * prints what it holds.
 *
 * Conventions every command gets: --help/-h, --quiet/-q, --name=value as
 * well as --name value, "--" ends the options, a missing or malformed value,
 * an unknown option or an unknown choice is a usage error (exit status 2).
 */
#ifndef BTF_CLI_OPTIONS_H
#define BTF_CLI_OPTIONS_H

#include <stddef.h>
#include <stdint.h>

typedef enum cli_kind {
    CLI_FLAG,   /* no value: *(int *)dest = 1 */
    CLI_INT,    /* a whole number in [lo, hi] into *(int *)dest; the word
                   `word` (e.g. "auto"), when set, stores word_value */
    CLI_U64,    /* a non-negative whole number into *(uint64_t *)dest */
    CLI_DOUBLE, /* a finite number in [lo, hi] into *(double *)dest */
    CLI_STRING, /* any text into *(const char **)dest */
    CLI_CHOICE, /* one of choices[] into *(int *)dest: values[i] if values is
                   set, else the index i */
    CLI_SIZE,   /* "WxH", each side in [lo, hi], into ((int *)dest)[0..1] */
    CLI_CUSTOM  /* parse(value, dest, why, n): 0 on success, else why says
                   what was expected */
} cli_kind;

typedef struct cli_opt {
    const char *name;          /* "--size"; NULL ends a table */
    const char *short_name;    /* "-o", or NULL */
    cli_kind kind;
    void *dest;
    const char *meta;          /* the value's name in usage and help: "WxH" */
    const char *help;          /* lines separated by '\n' */
    double lo, hi;             /* CLI_INT, CLI_DOUBLE, CLI_SIZE ranges */
    const char *const *choices;/* CLI_CHOICE: NULL-terminated names */
    const int *values;         /* CLI_CHOICE: the value of each name, or NULL */
    const char *word;          /* CLI_INT: a word accepted instead of a number */
    int word_value;
    const char *zero_means;    /* --help shows this for a default of 0 */
    int required;              /* 1: the command needs it */
    int tag;                   /* commands group options by tag (cli_first_seen) */
    int (*parse)(const char *value, void *dest, char *why, size_t n); /* CLI_CUSTOM */
    void (*show)(const void *dest, char *buf, size_t n); /* CLI_CUSTOM default, or NULL */
    int seen;                  /* set by the parser */
} cli_opt;

typedef struct cli_spec {
    const char *cmd;           /* "synthesise" */
    const char *args;          /* positional arguments in the usage line: "MODEL" */
    const char *alt_usage;     /* further usage lines (other forms), or NULL */
    const char *about;         /* the description printed by --help */
    int min_args, max_args;    /* how many positional arguments */
    cli_opt *opts;             /* the table, ended by a row with name NULL */
} cli_spec;

struct cli_ctx;

/* Parses argv[1 ..] against the table: options into their destinations,
 * positional arguments into args[0 .. max_args - 1] (*nargs of them).
 * Returns -1 when the command should go on, 0 when --help was printed, 2
 * after printing a usage error. */
int cli_parse(struct cli_ctx *c, cli_spec *s, int argc, char **argv, const char **args,
              int *nargs);
/* The usage line(s), the description and the option list with defaults. */
void cli_help(const cli_spec *s);
/* The name of the first option given with this tag, or NULL. */
const char *cli_first_seen(const cli_spec *s, int tag);

#endif
