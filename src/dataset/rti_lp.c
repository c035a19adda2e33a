/*
 * rti_lp.c — RTI light files (".lp", the light-position file of
 * reflectance transformation imaging: RTIBuilder, PTMfitter, RelightLab,
 * NeuralRTI) as a dataset layout (BTF_LAYOUT_RTI): one fixed camera looking
 * straight down (one view, θ = 0) and one distant light per image.
 *
 * The file: the first line the image count N, then N lines "PATH X Y Z",
 * (X, Y, Z) the unit vector from the object towards the light, X towards
 * the image's right, Y towards its top, Z towards the camera — btfcar's frame
 * (btf_dir_to_vec; docs/photostereo.md, "Frame"), so the light's (θ, φ) is
 * btf_vec_to_dir of the vector. PATH is relative to the .lp file's folder
 * (or absolute) and may contain spaces: the last three fields are the
 * vector. Blank lines are skipped; a '\r' before the line end is dropped.
 *
 * Refused, one line naming FILE:LINE each: a count that is no positive
 * integer; fewer or more image lines than the count; a line without a path
 * and three numbers; a number that is not a finite decimal; a vector whose
 * length is off 1 by more than 1 % (within that it is normalised); Z <= 0 (a
 * light below the surface); an image that is missing or not a regular file;
 * the same image listed twice. docs/datasets.md, "Layouts".
 *
 * dataset/dataset_scan.c hands a regular file named *.lp here; both grow
 * the entry list through dataset/dataset_entries.c, so that neither calls
 * the other back (docs/design.md, no call cycles).
 */
#include "core/core.h"
#include "dataset/dataset.h"
#include "io/io.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#define RTI_LP_MAX_BYTES (64u << 20)
#define RTI_LP_MAX_COUNT 1000000

int btf__rti_lp_name(const char *path)
{
    size_t n = strlen(path);
    return n > 3 && strcasecmp(path + n - 3, ".lp") == 0 && path[n - 4] != '/';
}

/* A decimal number and nothing else (as io/tsv.c reads numbers: no "inf",
 * "nan" or hexadecimal); 0, or -1. */
static int decimal(const char *s, double *out)
{
    const char *d = s + (*s == '-' || *s == '+');
    if (!(isdigit((unsigned char)*d) || (*d == '.' && isdigit((unsigned char)d[1]))) ||
        strpbrk(s, "xX"))
        return -1;
    char *end;
    double v = strtod(s, &end);
    if (end == s || *end != '\0' || !isfinite(v))
        return -1;
    *out = v;
    return 0;
}

static int blank(char c)
{
    return c == ' ' || c == '\t';
}

/* The last three blank-separated fields of line (trimmed at both ends, not
 * empty) as numbers into v, the text before them as the path (which may
 * hold blanks). Modifies line. */
static btf_status parse_image_line(char *line, const char *name, int line_no, char **path,
                                   double v[3], btf_error *err)
{
    char *field[3];
    char *e = line + strlen(line); /* one past the current field's last character */
    for (int k = 2; k >= 0; k--) {
        char *b = e;
        while (b > line && !blank(b[-1]))
            b--;
        if (b == line) /* no path before the numbers */
            return btf__fail(err, BTF_E_FORMAT, "%s:%d: expected 'PATH X Y Z' (an image and its "
                             "light's unit vector)", name, line_no);
        *e = '\0';
        field[k] = b;
        e = b;
        while (blank(e[-1])) /* line starts with a non-blank: e stays > line */
            e--;
    }
    *e = '\0';
    static const char *axis[3] = {"X", "Y", "Z"};
    for (int k = 0; k < 3; k++)
        if (decimal(field[k], &v[k]) != 0)
            return btf__fail(err, BTF_E_FORMAT, "%s:%d: %s '%.40s' is not a finite decimal number",
                             name, line_no, axis[k], field[k]);
    *path = line;
    return BTF_OK;
}

/* The image named on line_no: relative to base unless absolute; it must be a
 * regular file when check_files. */
static btf_status image_path(const char *name, int line_no, const char *base, const char *p,
                             int check_files, char *full, size_t n, btf_error *err)
{
    int k = p[0] == '/' ? snprintf(full, n, "%s", p) : snprintf(full, n, "%s/%s", base, p);
    if (k < 0 || (size_t)k >= n)
        return btf__fail(err, BTF_E_ARG, "%s:%d: path too long (%zu bytes at most)", name, line_no,
                         n - 1);
    if (!check_files)
        return BTF_OK;
    struct stat st;
    if (stat(full, &st) != 0)
        return btf__fail(err, BTF_E_IO, "%s:%d: %s: %s", name, line_no, full, strerror(errno));
    if (!S_ISREG(st.st_mode))
        return btf__fail(err, BTF_E_IO, "%s:%d: %s: not a regular file", name, line_no, full);
    return BTF_OK;
}

/* Parses text, NUL-terminated at n and modified in place. */
static btf_status parse_owned(char *text, size_t n, const char *name, const char *base,
                              int check_files, btf_dataset_entries *l, int **line_of,
                              btf_error *err)
{
    const char *nul = memchr(text, '\0', n);
    if (nul) {
        int line_no = 1;
        for (const char *c = text; c < nul; c++)
            line_no += *c == '\n';
        return btf__fail(err, BTF_E_FORMAT, "%s:%d: a NUL byte: not an RTI light file (text)",
                         name, line_no);
    }
    long count = -1;
    int line_no = 0, count_line = 0;
    char *s = text;
    while (s) {
        char *line = s;
        char *nl = strchr(s, '\n');
        s = nl && nl[1] ? nl + 1 : NULL; /* no line after a final newline */
        if (nl)
            *nl = '\0';
        line_no++;
        size_t len = strlen(line);
        while (len > 0 && (line[len - 1] == '\r' || line[len - 1] == ' ' || line[len - 1] == '\t'))
            line[--len] = '\0';
        while (*line == ' ' || *line == '\t')
            line++;
        if (!*line)
            continue;
        if (count < 0) {
            /* the count: digits only, 1 .. RTI_LP_MAX_COUNT */
            char *d = line;
            while (isdigit((unsigned char)*d))
                d++;
            errno = 0;
            long c = strtol(line, NULL, 10);
            if (d == line || *d || errno || c < 1 || c > RTI_LP_MAX_COUNT)
                return btf__fail(err, BTF_E_FORMAT, "%s:%d: bad image count '%.40s' (the first "
                                 "line of an RTI light file: a whole number 1 .. %d)", name,
                                 line_no, line, RTI_LP_MAX_COUNT);
            count = c;
            count_line = line_no;
            continue;
        }
        if (l->count == count)
            return btf__fail(err, BTF_E_FORMAT, "%s:%d: more image lines than the count %ld of "
                             "line %d", name, line_no, count, count_line);
        char *p = NULL;
        double v[3];
        btf_status rc = parse_image_line(line, name, line_no, &p, v, err);
        if (rc)
            return rc;
        double r = hypot(hypot(v[0], v[1]), v[2]);
        if (!(fabs(r - 1.0) <= 0.01))
            return btf__fail(err, BTF_E_DATA, "%s:%d: light vector (%g, %g, %g) has length %g, "
                             "not 1 (within 1 %%)", name, line_no, v[0], v[1], v[2], r);
        if (!(v[2] > 0.0))
            return btf__fail(err, BTF_E_DATA, "%s:%d: light vector (%g, %g, %g) has Z <= 0: a "
                             "light below the surface (Z points to the camera)", name, line_no,
                             v[0], v[1], v[2]);
        for (int k = 0; k < 3; k++)
            v[k] /= r;
        char full[BTF_DATASET_PATH_MAX];
        rc = image_path(name, line_no, base, p, check_files, full, sizeof full, err);
        if (rc == BTF_OK)
            rc = btf__dataset_entries_add(l, full, btf_vec_to_dir(v), (btf_dir){0.0, 0.0},
                                          err); /* one view: the camera looks straight down */
        if (rc)
            return rc;
        int *grown = realloc(*line_of, (size_t)l->cap * sizeof **line_of);
        if (!grown)
            return btf__fail(err, BTF_E_NOMEM, "%s: out of memory", name);
        *line_of = grown;
        grown[l->count - 1] = line_no;
    }
    if (count < 0)
        return btf__fail(err, BTF_E_FORMAT, "%s:%d: no image count (an empty RTI light file)", name,
                         line_no > 0 ? line_no : 1);
    if (l->count < count)
        return btf__fail(err, BTF_E_FORMAT, "%s:%d: %d image lines, fewer than the count %ld of "
                         "line %d", name, line_no, l->count, count, count_line);
    int first, again;
    btf_status rc = btf__dataset_entries_repeat(l, &first, &again, err);
    if (rc == BTF_OK && first >= 0)
        rc = btf__fail(err, BTF_E_DATA, "%s:%d: %s is listed again (first on line %d); one "
                       "image per light", name, (*line_of)[again], l->items[again].path,
                       (*line_of)[first]);
    return rc;
}

/* The folder of path without its last '/' ("" for one in the root, which
 * then makes "/NAME"), or "." */
static void folder_of(const char *path, char *base, size_t n)
{
    snprintf(base, n, "%s", path);
    char *slash = strrchr(base, '/');
    if (slash)
        slash[0] = '\0';
    else
        snprintf(base, n, ".");
}

btf_status btf__rti_lp_parse(const char *text, size_t n, const char *name, const char *base,
                             int check_files, btf_dataset_entries *l, btf_error *err)
{
    memset(l, 0, sizeof *l);
    l->layout = BTF_LAYOUT_RTI;
    if (!name)
        name = "light file";
    if (!text && n)
        return btf__fail(err, BTF_E_ARG, "%s: no text", name);
    if (n > RTI_LP_MAX_BYTES)
        return btf__fail(err, BTF_E_FORMAT, "%s: larger than %u bytes", name, RTI_LP_MAX_BYTES);
    char *copy = malloc(n + 1);
    if (!copy)
        return btf__fail(err, BTF_E_NOMEM, "%s: out of memory", name);
    if (n)
        memcpy(copy, text, n);
    copy[n] = '\0';
    int *line_of = NULL;
    btf_status rc = parse_owned(copy, n, name, base ? base : ".", check_files, l, &line_of, err);
    free(line_of);
    free(copy);
    return rc;
}

btf_status btf__rti_lp_read(const char *path, btf_dataset_entries *l, btf_error *err)
{
    memset(l, 0, sizeof *l);
    l->layout = BTF_LAYOUT_RTI;
    unsigned char *data;
    size_t n;
    btf_status rc = btf__read_file(path, RTI_LP_MAX_BYTES, &data, &n, err);
    if (rc)
        return rc;
    char base[BTF_DATASET_PATH_MAX];
    folder_of(path, base, sizeof base);
    rc = btf__rti_lp_parse((const char *)data, n, path, base, 1, l, err);
    free(data);
    return rc;
}
