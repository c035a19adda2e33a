/*
 * describe.h — what every description of a file writes values with
 * (describe.c): btfcar info's text and JSON on datasets and on models of
 * either family. Private to the library (and its command line).
 */
#ifndef BTF_CORE_DESCRIBE_H
#define BTF_CORE_DESCRIBE_H

#include "btfcar.h"

#include <stdio.h>

/* A model file as its description names it: its path, format version and
 * size in bytes (-1 if unknown). */
typedef struct describe_file {
    const char *path;
    unsigned major, minor;
    long long bytes;
} describe_file;

/* The length of the valid UTF-8 sequence at s (1..4), 0 when the bytes there
 * are not UTF-8. */
int txt_utf8_length(const char *s);
/* "ubo81: 81 directions, theta 0..75 deg in 6 rings" */
void txt_describe_set(const btf_dirset *s, char *buf, size_t n);
/* A JSON string literal: quotes, backslashes and control bytes escaped,
 * bytes that are not UTF-8 written as U+FFFD. */
void txt_json_string(FILE *f, const char *s);
/* float32 values with 9 significant digits (enough to round-trip). */
void txt_json_f32(FILE *f, float v);
void txt_json_f32s(FILE *f, const float *v, int n);
/* {"name": "ubo81", "count": 81, "directions": [[theta, phi], ...]} or null */
void txt_json_dirset(FILE *f, const btf_dirset *s);

#endif
