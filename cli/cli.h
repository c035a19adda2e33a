/*
 * cli.h — shared pieces of the btfcar command: option parsing helpers,
 * the progress bar and error reporting. Each subcommand is one file.
 */
#ifndef BTF_CLI_H
#define BTF_CLI_H

#include "btfcar.h"
#include "options.h"

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
/* Whether s starts as a plain decimal number does: a digit, or '.' and a
 * digit, after at most one '-' when allow_minus (no spaces, no '+'; the
 * strict start every number option has, since strtol and strtod skip
 * spaces and take signs). */
int cli_plain_number(const char *s, int allow_minus);
int cli_parse_int(const char *s, long lo, long hi, long *out);
int cli_parse_u64(const char *s, uint64_t *out);
/* A plain decimal number (cli_plain_number; no hexadecimal, no inf or
 * nan), any finite value, subnormals included: 0, or -1. */
int cli_parse_decimal(const char *s, int allow_minus, double *out);
/* The length of the well-formed UTF-8 sequence s starts with (1 for ASCII,
 * 1 for the terminating NUL), or 0 when its first byte starts none: file
 * names are bytes, JSON text is UTF-8. */
int cli_utf8_length(const char *s);
/* A malloc'd copy of s with each byte that starts no well-formed UTF-8
 * sequence replaced by U+FFFD, for JSON writers (cJSON copies bytes as they
 * are); NULL when out of memory. */
char *cli_utf8_copy(const char *s);
/* Whether s ends in suffix, ignoring case (".png", ".exr"). */
int cli_has_suffix(const char *s, const char *suffix);
/* The first bytes of a file, to tell what it is: at most n into buf, their
 * number; 0 when path is no regular file or cannot be read. A FIFO is never
 * opened blocking (it would wait for a writer); the reader that follows
 * names what is wrong with the file. */
size_t cli_read_head(const char *path, unsigned char *buf, size_t n);
/* An output image by its name: .exr as linear 32-bit float, anything else
 * as 8-bit sRGB PNG (the commands check the suffix first). */
btf_status cli_write_image(const char *path, const btf_image *img, btf_error *err);
/* "A,B": two plain non-negative decimal numbers (cli_plain_number): 0, or -1. */
int cli_parse_pair(const char *s, double *a, double *b);
/* "THETA,PHI" in degrees (theta 0..90, phi 0..360; 360 becomes 0): 0, or
 * -1 with what was expected in why. */
int cli_parse_dir(const char *s, btf_dir *d, char *why, size_t n);
/* A --view/--light style option: the direction and whether it was given;
 * cli_parse_dir_arg is its CLI_CUSTOM parser. */
typedef struct cli_dir_arg {
    btf_dir dir;
    int given;
} cli_dir_arg;
int cli_parse_dir_arg(const char *s, void *dest, char *why, size_t n);
/* "WxH" */
int cli_parse_size(const char *s, int *w, int *h);

/* A progress callback drawing a bar on stderr when it is a terminal. */
void cli_progress(void *user, double fraction, const char *what);
/* The progress callback to use (NULL when quiet or not a terminal). */
btf_progress_fn cli_progress_fn(const cli_ctx *c);
/* Ends a progress line (newline) if one was drawn. */
void cli_progress_done(void);

/* Before any work: checks that an output path can be written (a file or a
 * folder of files, btf_output_check) and removes stale temporaries of dead
 * btfcar runs beside it (and in it, for a folder). 0, or prints one line
 * naming the path and returns 1. */
int cli_check_output(const cli_ctx *c, const char *path, btf_output_kind kind);
/* SIGINT, SIGTERM and SIGHUP remove the run's temporaries
 * (btf_remove_temporaries) and exit with 128 + the signal. */
void cli_install_signal_cleanup(void);

/* The GPU for --backend cpu|gpu|auto and --device N (-1: none named;
 * BTF_VK_DEVICE and BTF_VK_VALIDATION read here): NULL for cpu, and for
 * auto when no real GPU is present (err says why; not a failure); for gpu
 * or a named device NULL is a failure, with err set. */
btf_gpu *cli_open_gpu(const char *backend, int device, btf_error *err);
/* The same for a work whose largest image takes image_bytes: auto without
 * a named device takes the device btf_gpu_auto_device picks, else none. */
btf_gpu *cli_open_gpu_for(const char *backend, int device, uint64_t image_bytes,
                          btf_error *err);

/* Monotonic wall-clock seconds, for the timings commands print. */
double cli_now(void);

/* "12.3 MB" */
void cli_format_bytes(uint64_t bytes, char *buf, size_t n);

int cmd_generate(int argc, char **argv);
int cmd_info(int argc, char **argv);
int cmd_photostereo(int argc, char **argv);
int cmd_analyse(int argc, char **argv);
int cmd_texture_fit(int argc, char **argv);
int cmd_synthesise(int argc, char **argv);
int cmd_render(int argc, char **argv);
int cmd_compare(int argc, char **argv);
int cmd_report(int argc, char **argv);
int cmd_library(int argc, char **argv);
int cmd_export(int argc, char **argv);

/* The model options shared by analyse and texture-fit, as option-table
 * rows over a btf_fit_opts (fo) with a tag. */
int cli_parse_neighbourhood(const char *value, void *dest, char *why, size_t n);
void cli_show_neighbourhood(const void *dest, char *buf, size_t n);
/* --max-pixels N into a uint64_t (btf_read_opts.max_pixels and
 * btf_dataset_opts.max_pixels), set to BTF_DEFAULT_MAX_PIXELS before parsing. */
#define CLI_MAX_PIXELS_OPTION(dest_)                                                       \
    {.name = "--max-pixels", .kind = CLI_U64, .dest = (dest_), .meta = "N",               \
     .help = "refuse images of more than N pixels, from the header, before\n"             \
             "decoding (docs/api.md, \"Resource limits\")"}
#define CLI_MODEL_OPTIONS(fo, tag_)                                                        \
    {.name = "--levels", .kind = CLI_INT, .dest = &(fo)->levels, .meta = "L|auto",         \
     .help = "pyramid levels; auto: from the image size and its correlation length,\n"    \
             "at most 3, 2 beside a structure layer (docs/model.md)",                      \
     .lo = 1, .hi = BTF_MAX_LEVELS, .word = "auto", .word_value = 0, .tag = (tag_)},       \
    {.name = "--neighbourhood", .kind = CLI_CUSTOM, .dest = &(fo)->car, .meta = "SPEC|auto", \
     .help = "causal offsets row:col, comma-separated, e.g. 0:-1,-1:0,-1:-1,-1:1;\n"      \
             "auto chooses per sub-band by each candidate's posterior probability\n"      \
             "(beside a structure layer each coefficient pays its 32 bits)",               \
     .parse = cli_parse_neighbourhood, .show = cli_show_neighbourhood, .tag = (tag_)},     \
    {.name = "--neighborhood", .kind = CLI_CUSTOM, .dest = &(fo)->car, .meta = "SPEC|auto", \
     .help = "the same as --neighbourhood", .parse = cli_parse_neighbourhood,              \
     .tag = (tag_)},                                                                       \
    {.name = "--max-neighbours", .kind = CLI_INT, .dest = &(fo)->car.max_neighbours,       \
     .meta = "N", .help = "auto: the largest candidate considered (the paper's models\n"  \
                          "have fewer than 4)",                                            \
     .lo = 1, .hi = BTF_CAR_MAX_NEIGHBOURS, .tag = (tag_)}

/* A btf_warning_fn printing "btfcar CMD: warning: ..." (user: the cli_ctx);
 * --quiet passes no callback: it prints nothing but errors. */
void cli_warning(void *user, const char *message);
/* The CAR parameters of one subspace, as text. */
void cli_print_subspace(const btf_subspace_model *s, int index);


#endif
