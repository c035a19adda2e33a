/*
 * tsv.c — a small parser for the tab-separated manifests btfcar accepts
 * (datasets, photometric stereo): a header line naming the columns, then one
 * record per line. Blank lines and lines starting with '#' are skipped. Fields
 * are separated by tabs only, so paths may contain spaces. The parser works
 * on a buffer (btf__tsv_parse); btf__tsv_read loads a file and parses it.
 */
#include "core/core.h"
#include "io/io.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define TSV_MAX_BYTES (64u << 20)

void btf__tsv_free(btf_tsv *t)
{
    if (!t)
        return;
    BTF_FREE_ALL(t->text, t->cells, t->line_no);
    memset(t, 0, sizeof *t);
}

/* Splits one line in place at tabs into at most max fields. */
static int split_line(char *line, char **fields, int max)
{
    int n = 0;
    char *p = line;
    for (;;) {
        char *tab = strchr(p, '\t');
        if (n < max)
            fields[n] = p;
        n++;
        if (!tab)
            break;
        *tab = '\0';
        p = tab + 1;
    }
    return n;
}

static int count_fields(const char *line)
{
    int n = 1;
    for (; *line; line++)
        n += *line == '\t';
    return n;
}

static char *trim(char *s)
{
    while (*s == ' ')
        s++;
    size_t n = strlen(s);
    while (n > 0 && (s[n - 1] == ' ' || s[n - 1] == '\r'))
        s[--n] = '\0';
    return s;
}

static int is_skipped(const char *line)
{
    while (*line == ' ' || *line == '\t' || *line == '\r')
        line++;
    return *line == '\0' || *line == '#';
}

/* Parses text (n bytes plus a NUL, owned by t from here on) in place. */
static btf_status parse_owned(char *text, size_t n, const char *name, btf_tsv *t,
                              btf_error *err)
{
    t->text = text;
    if (memchr(text, 0, n)) {
        btf__tsv_free(t);
        return btf__fail(err, BTF_E_FORMAT, "%s: not a text file (contains NUL bytes)", name);
    }
    text[n] = '\0';
    size_t lines = 1;
    for (size_t i = 0; i < n; i++)
        lines += text[i] == '\n';
    int have_header = 0, line = 0;
    /* A UTF-8 byte order mark, as some editors (Excel's "UTF-8 CSV") begin a
     * file with, is no part of the first column's name. */
    char *save = n >= 3 && !memcmp(text, "\xEF\xBB\xBF", 3) ? text + 3 : text;
    for (char *l = save; l; l = save) {
        char *nl = strchr(l, '\n');
        save = nl ? nl + 1 : NULL;
        if (nl)
            *nl = '\0';
        line++;
        if (is_skipped(l))
            continue;
        if (!have_header) {
            t->ncols = count_fields(l);
            if (t->ncols > 64) {
                btf__tsv_free(t);
                return btf__fail(err, BTF_E_FORMAT, "%s:%d: more than 64 columns", name, line);
            }
            char **header = btf__alloc((size_t)t->ncols, sizeof(char *), err);
            t->cells = btf__alloc(lines * (size_t)t->ncols, sizeof(char *), err);
            t->line_no = btf__alloc(lines, sizeof(int), err);
            if (!header || !t->cells || !t->line_no) {
                free(header);
                btf__tsv_free(t);
                return BTF_E_NOMEM;
            }
            split_line(l, header, t->ncols);
            for (int c = 0; c < t->ncols; c++)
                t->names[c] = trim(header[c]);
            free(header);
            have_header = 1;
            continue;
        }
        char **row = t->cells + (size_t)t->nrows * t->ncols;
        int k = split_line(l, row, t->ncols);
        if (k != t->ncols) {
            int ncols = t->ncols;
            btf__tsv_free(t);
            return btf__fail(err, BTF_E_FORMAT, "%s:%d: %d fields, the header names %d", name, line,
                             k, ncols);
        }
        for (int c = 0; c < t->ncols; c++)
            row[c] = trim(row[c]);
        t->line_no[t->nrows++] = line;
    }
    if (!have_header) {
        btf__tsv_free(t);
        return btf__fail(err, BTF_E_FORMAT, "%s: empty manifest (no header line)", name);
    }
    return BTF_OK;
}

btf_status btf__tsv_parse(const char *text, size_t n, const char *name, btf_tsv *t,
                          btf_error *err)
{
    memset(t, 0, sizeof *t);
    if (!name)
        name = "manifest";
    if (!text && n)
        return btf__fail(err, BTF_E_ARG, "%s: no text", name);
    if (n > TSV_MAX_BYTES)
        return btf__fail(err, BTF_E_FORMAT, "%s: larger than %u bytes", name, TSV_MAX_BYTES);
    char *copy = malloc(n + 1);
    if (!copy)
        return btf__fail(err, BTF_E_NOMEM, "%s: out of memory", name);
    if (n)
        memcpy(copy, text, n);
    return parse_owned(copy, n, name, t, err);
}

btf_status btf__tsv_read(const char *path, btf_tsv *t, btf_error *err)
{
    memset(t, 0, sizeof *t);
    unsigned char *data;
    size_t n;
    btf_status rc = btf__read_file(path, TSV_MAX_BYTES, &data, &n, err);
    if (rc)
        return rc;
    /* Room for the terminating NUL; the bytes are parsed where they are. */
    char *text = realloc(data, n + 1);
    if (!text) {
        free(data);
        return btf__fail(err, BTF_E_NOMEM, "%s: out of memory", path);
    }
    return parse_owned(text, n, path, t, err);
}

int btf__tsv_column(const btf_tsv *t, const char *name)
{
    for (int c = 0; c < t->ncols; c++)
        if (strcmp(t->names[c], name) == 0)
            return c;
    return -1;
}

const char *btf__tsv_cell(const btf_tsv *t, int row, int col)
{
    return t->cells[(size_t)row * t->ncols + col];
}

/* A sign at most, then a digit, or '.' and a digit: what a decimal number
 * starts with (not "inf", "nan" or a space). */
static int is_decimal_start(const char *s)
{
    if (*s == '-' || *s == '+')
        s++;
    return (*s >= '0' && *s <= '9') || (*s == '.' && s[1] >= '0' && s[1] <= '9');
}

btf_status btf__tsv_number(const btf_tsv *t, const char *path, int row, int col, double *out,
                           btf_error *err)
{
    const char *s = btf__tsv_cell(t, row, col);
    char *end;
    double v = 0.0;
    /* Decimal only: strtod would also read "0x1e" as thirty and "inf" or
     * "nan"; a subnormal ("1e-320", ERANGE) is a finite value and kept. */
    int decimal = is_decimal_start(s) && !strpbrk(s, "xX");
    if (decimal)
        v = strtod(s, &end);
    if (!decimal || end == s || *end != '\0' || !isfinite(v))
        return btf__fail(err, BTF_E_FORMAT, "%s:%d: %s '%s' is not a finite decimal number", path,
                         t->line_no[row], t->names[col], s);
    *out = v;
    return BTF_OK;
}

typedef struct name_index {
    const char *name;
    int index;
} name_index;

static int by_name_then_index(const void *a, const void *b)
{
    const name_index *x = a, *y = b;
    int c = strcmp(x->name, y->name);
    return c ? c : (x->index > y->index) - (x->index < y->index);
}

btf_status btf__first_repeat(const char *const *names, int n, int *first, int *again,
                             btf_error *err)
{
    *first = *again = -1;
    if (n < 2)
        return BTF_OK;
    name_index *order = btf__alloc((size_t)n, sizeof *order, err);
    if (!order)
        return BTF_E_NOMEM;
    for (int i = 0; i < n; i++)
        order[i] = (name_index){names[i], i};
    qsort(order, (size_t)n, sizeof *order, by_name_then_index);
    /* Sorted by name, then index: the repeat with the smallest index pair
     * in sort order is the one reported (deterministic). */
    for (int i = 1; i < n; i++)
        if (!strcmp(order[i - 1].name, order[i].name)) {
            *first = order[i - 1].index;
            *again = order[i].index;
            break;
        }
    free(order);
    return BTF_OK;
}
