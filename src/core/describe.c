/*
 * describe.c — the pieces every description of a file (btfcar info on a
 * dataset or on a model of either family) writes values with: a direction
 * set summarised as text, and JSON strings, float arrays and direction sets
 * (private header core/describe.h).
 */
#include "core/describe.h"

/* The bytes a well-formed UTF-8 sequence continues with after lead byte b:
 * the range of the first continuation byte (narrower after E0, ED, F0, F4:
 * no overlong forms, no surrogates, nothing past U+10FFFF) and the count. */
static int utf8_expect(unsigned b, unsigned *lo, unsigned *hi)
{
    *lo = 0x80;
    *hi = 0xBF;
    if (b >= 0xC2 && b <= 0xDF)
        return 1;
    if (b >= 0xE0 && b <= 0xEF) {
        *lo = b == 0xE0 ? 0xA0 : 0x80;
        *hi = b == 0xED ? 0x9F : 0xBF;
        return 2;
    }
    if (b >= 0xF0 && b <= 0xF4) {
        *lo = b == 0xF0 ? 0x90 : 0x80;
        *hi = b == 0xF4 ? 0x8F : 0xBF;
        return 3;
    }
    return -1;
}

int txt_utf8_length(const char *s)
{
    const unsigned char *p = (const unsigned char *)s;
    if (*p < 0x80)
        return 1;
    unsigned lo, hi;
    int more = utf8_expect(*p, &lo, &hi);
    if (more < 0 || p[1] < lo || p[1] > hi)
        return 0;
    for (int i = 2; i <= more; i++)
        if (p[i] < 0x80 || p[i] > 0xBF)
            return 0;
    return more + 1;
}

/* "ubo81: 81 directions, theta 0..75 in 6 rings" */
void txt_describe_set(const btf_dirset *s, char *buf, size_t n)
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
void txt_json_string(FILE *f, const char *s)
{
    fputc('"', f);
    for (const unsigned char *p = (const unsigned char *)s; *p;) {
        int n = txt_utf8_length((const char *)p);
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
void txt_json_f32(FILE *f, float v)
{
    fprintf(f, "%.9g", (double)v);
}

void txt_json_f32s(FILE *f, const float *v, int n)
{
    fputc('[', f);
    for (int i = 0; i < n; i++) {
        if (i)
            fputs(", ", f);
        txt_json_f32(f, v[i]);
    }
    fputc(']', f);
}

/* {"name": "ubo81", "count": 81, "directions": [[theta, phi], ...]} or null */
void txt_json_dirset(FILE *f, const btf_dirset *s)
{
    if (!s || s->count == 0) {
        fputs("null", f);
        return;
    }
    fputs("{\"name\": ", f);
    txt_json_string(f, s->name);
    fprintf(f, ", \"count\": %d, \"directions\": [", s->count);
    for (int i = 0; i < s->count; i++)
        fprintf(f, "%s[%.17g, %.17g]", i ? ", " : "", s->dirs[i].theta, s->dirs[i].phi);
    fputs("]}", f);
}
