/*
 * info.h — what the files of btfcar info share: the model report
 * (info_model.c) that cmd_info.c calls, and the text and JSON pieces both
 * reports write with (info_format.c).
 */
#ifndef BTF_CLI_INFO_H
#define BTF_CLI_INFO_H

#include "cli.h"

/* A file that starts like a model: its path, format version and size in
 * bytes (-1 if unknown). */
typedef struct model_file {
    const char *path;
    unsigned major, minor;
    long long bytes;
} model_file;

/* The model report (info_model.c): reads and checks the whole file, then
 * prints it as text or one JSON document; the exit status. */
int cli_info_model(cli_ctx *c, const model_file *mf, int json);
/* The same for a reflectance-field model (info_rf.c; docs/rf.md). */
int cli_info_rf(cli_ctx *c, const model_file *mf, int json);

/* info_format.c */
/* "ubo81: 81 directions, theta 0..75 in 6 rings" */
void cli_describe_set(const btf_dirset *s, char *buf, size_t n);
/* A JSON string literal: quotes, backslashes and control bytes escaped,
 * bytes that are not UTF-8 written as U+FFFD. */
void cli_json_string(FILE *f, const char *s);
/* float32 values with 9 significant digits (enough to round-trip). */
void cli_json_f32(FILE *f, float v);
void cli_json_f32s(FILE *f, const float *v, int n);
/* {"name": "ubo81", "count": 81, "directions": [[theta, phi], ...]} or null */
void cli_json_dirset(FILE *f, const btf_dirset *s);

#endif
