/*
 * info_format.c — the pieces both reports of btfcar info (datasets in
 * cmd_info.c, models in info_model.c) write values with: a direction set
 * summarised as text, and JSON strings, float arrays and direction sets
 * (declared in info.h).
 */
#include "info.h"

/* "ubo81: 81 directions, theta 0..75 in 6 rings" */
void cli_describe_set(const btf_dirset *s, char *buf, size_t n)
{
    int rings = 0;
    double lo = 1e9, hi = -1;
    for (int i = 0; i < s->count; i++) {
        if (i == 0 || s->dirs[i].theta != s->dirs[i - 1].theta)
            rings++;
        if (s->dirs[i].theta < lo)
            lo = s->dirs[i].theta;
        if (s->dirs[i].theta > hi)
            hi = s->dirs[i].theta;
    }
    snprintf(buf, n, "%s: %d directions, theta %g..%g deg in %d rings", s->name, s->count, lo, hi,
             rings);
}

/* A JSON string literal: quotes, backslashes and control bytes escaped, and
 * each byte that is not UTF-8 (a file name is any bytes) U+FFFD, since JSON
 * text must be UTF-8. */
void cli_json_string(FILE *f, const char *s)
{
    fputc('"', f);
    for (const unsigned char *p = (const unsigned char *)s; *p;) {
        int n = cli_utf8_length((const char *)p);
        if (n == 0)
            fputs("\\ufffd", f);
        else if (*p == '"' || *p == '\\')
            fprintf(f, "\\%c", *p);
        else if (*p < 0x20 || *p == 0x7f)
            fprintf(f, "\\u%04x", *p);
        else
            fwrite(p, 1, (size_t)n, f);
        p += n ? n : 1;
    }
    fputc('"', f);
}

/* float32 values with 9 significant digits (enough to round-trip) and
 * doubles with 17; the model reader has rejected NaN and Inf already. */
void cli_json_f32(FILE *f, float v)
{
    fprintf(f, "%.9g", (double)v);
}

void cli_json_f32s(FILE *f, const float *v, int n)
{
    fputc('[', f);
    for (int i = 0; i < n; i++) {
        if (i)
            fputs(", ", f);
        cli_json_f32(f, v[i]);
    }
    fputc(']', f);
}

/* {"name": "ubo81", "count": 81, "directions": [[theta, phi], ...]} or null */
void cli_json_dirset(FILE *f, const btf_dirset *s)
{
    if (!s || s->count == 0) {
        fputs("null", f);
        return;
    }
    fputs("{\"name\": ", f);
    cli_json_string(f, s->name);
    fprintf(f, ", \"count\": %d, \"directions\": [", s->count);
    for (int i = 0; i < s->count; i++)
        fprintf(f, "%s[%.17g, %.17g]", i ? ", " : "", s->dirs[i].theta, s->dirs[i].phi);
    fputs("]}", f);
}
