/* options.c — the option-table parser and --help writer (see options.h). */
#include "cli.h"

#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define HELP_COLUMN 26
#define USAGE_WIDTH 79

static int is_end(const cli_opt *o)
{
    return o->name == NULL;
}

static cli_opt *find_option(cli_spec *s, const char *name, size_t len)
{
    for (cli_opt *o = s->opts; !is_end(o); o++) {
        if (strlen(o->name) == len && !strncmp(o->name, name, len))
            return o;
        if (o->short_name && strlen(o->short_name) == len && !strncmp(o->short_name, name, len))
            return o;
    }
    return NULL;
}

static int parse_double(const char *s, double *out)
{
    return cli_parse_decimal(s, 1, out);
}

/* "a, b or c" */
static void list_choices(const char *const *choices, char *buf, size_t n)
{
    buf[0] = '\0';
    int count = 0;
    while (choices[count])
        count++;
    for (int i = 0; i < count; i++) {
        size_t used = strlen(buf);
        snprintf(buf + used, n - used, "%s%s", i == 0 ? "" : i == count - 1 ? " or " : ", ",
                 choices[i]);
    }
}

/* What a value of this option must look like, for usage errors. */
static void describe_value(const cli_opt *o, char *buf, size_t n)
{
    char choices[512];
    switch (o->kind) {
    case CLI_INT:
        if (o->word)
            snprintf(buf, n, "a whole number %.0f..%.0f or %s", o->lo, o->hi, o->word);
        else
            snprintf(buf, n, "a whole number %.0f..%.0f", o->lo, o->hi);
        break;
    case CLI_U64: snprintf(buf, n, "a non-negative whole number"); break;
    case CLI_DOUBLE: snprintf(buf, n, "a number in [%g, %g]", o->lo, o->hi); break;
    case CLI_SIZE: snprintf(buf, n, "WxH, each side %.0f..%.0f", o->lo, o->hi); break;
    case CLI_CHOICE:
        list_choices(o->choices, choices, sizeof choices);
        snprintf(buf, n, "%s", choices);
        break;
    default: snprintf(buf, n, "%s", o->meta ? o->meta : "a value"); break;
    }
}

static int parse_size(const char *v, double lo, double hi, int *wh)
{
    const char *x = strchr(v, 'x');
    char buf[64];
    if (!x || (size_t)(x - v) >= sizeof buf)
        return -1;
    memcpy(buf, v, (size_t)(x - v));
    buf[x - v] = '\0';
    long a, b;
    if (cli_parse_int(buf, (long)lo, (long)hi, &a) || cli_parse_int(x + 1, (long)lo, (long)hi, &b))
        return -1;
    wh[0] = (int)a;
    wh[1] = (int)b;
    return 0;
}

/* Stores v into o's destination; 0, or -1 with why filled in. */
static int store_value(cli_opt *o, const char *v, char *why, size_t n)
{
    long i;
    double d;
    switch (o->kind) {
    case CLI_INT:
        if (o->word && !strcmp(v, o->word)) {
            *(int *)o->dest = o->word_value;
            return 0;
        }
        if (cli_parse_int(v, (long)o->lo, (long)o->hi, &i))
            break;
        *(int *)o->dest = (int)i;
        return 0;
    case CLI_U64:
        if (cli_parse_u64(v, (uint64_t *)o->dest))
            break;
        return 0;
    case CLI_DOUBLE:
        if (parse_double(v, &d) || d < o->lo || d > o->hi)
            break;
        *(double *)o->dest = d;
        return 0;
    case CLI_STRING:
        *(const char **)o->dest = v;
        return 0;
    case CLI_CHOICE:
        for (int k = 0; o->choices[k]; k++)
            if (!strcmp(o->choices[k], v)) {
                *(int *)o->dest = o->values ? o->values[k] : k;
                return 0;
            }
        break;
    case CLI_SIZE:
        if (parse_size(v, o->lo, o->hi, (int *)o->dest))
            break;
        return 0;
    case CLI_CUSTOM:
        return o->parse(v, o->dest, why, n) ? -1 : 0;
    case CLI_FLAG:
        return 0;
    }
    describe_value(o, why, n);
    return -1;
}

/* One argument that starts with '-': the option, and its value from
 * "--name=value" or the next argument. */
static int take_option(cli_ctx *c, cli_spec *s, int argc, char **argv, int *i, int *order)
{
    const char *a = argv[*i];
    const char *eq = a[1] == '-' ? strchr(a, '=') : NULL;
    size_t len = eq ? (size_t)(eq - a) : strlen(a);
    cli_opt *o = find_option(s, a, len);
    if (!o) {
        if ((len == 7 && !strncmp(a, "--quiet", 7)) || !strcmp(a, "-q")) {
            if (eq)
                return cli_usage_error(c, "--quiet takes no value");
            c->quiet = 1;
            return -1;
        }
        return cli_usage_error(c, "unknown option '%.*s'", (int)len, a);
    }
    o->seen = ++*order;
    if (o->kind == CLI_FLAG) {
        if (eq)
            return cli_usage_error(c, "%s takes no value", o->name);
        *(int *)o->dest = 1;
        return -1;
    }
    const char *v = eq ? eq + 1 : (*i + 1 < argc ? argv[++*i] : NULL);
    char why[512];
    if (!v) {
        describe_value(o, why, sizeof why);
        return cli_usage_error(c, "%s needs %s", o->name, why);
    }
    if (store_value(o, v, why, sizeof why) != 0)
        return cli_usage_error(c, "%s '%s': expected %s", o->name, v, why);
    return -1;
}

int cli_parse(cli_ctx *c, cli_spec *s, int argc, char **argv, const char **args, int *nargs)
{
    int order = 0, options_end = 0;
    *nargs = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!options_end && (!strcmp(a, "--help") || !strcmp(a, "-h"))) {
            cli_help(s);
            return 0;
        }
        if (!options_end && !strcmp(a, "--")) {
            options_end = 1;
            continue;
        }
        if (!options_end && a[0] == '-' && a[1]) {
            int rc = take_option(c, s, argc, argv, &i, &order);
            if (rc >= 0)
                return rc;
            continue;
        }
        if (*nargs >= s->max_args)
            return cli_usage_error(c, "unexpected argument '%s'", a);
        args[(*nargs)++] = a;
    }
    for (cli_opt *o = s->opts; !is_end(o); o++)
        if (o->required && !o->seen)
            return cli_usage_error(c, "%s %s is required", o->short_name ? o->short_name : o->name,
                                   o->meta ? o->meta : "");
    if (*nargs < s->min_args)
        return cli_usage_error(c, "%s %s required", s->args, s->min_args > 1 ? "are" : "is");
    return -1;
}

const char *cli_first_seen(const cli_spec *s, int tag)
{
    const cli_opt *first = NULL;
    for (const cli_opt *o = s->opts; !is_end(o); o++)
        if (o->tag == tag && o->seen && (!first || o->seen < first->seen))
            first = o;
    return first ? first->name : NULL;
}

/* ------------------------------------------------------------------ help */

/* "--size WxH" or "-o, --output DIR" */
static void option_label(const cli_opt *o, char *buf, size_t n)
{
    const char *meta = o->kind == CLI_FLAG ? "" : o->meta ? o->meta : "VALUE";
    if (o->short_name)
        snprintf(buf, n, "%s, %s%s%s", o->short_name, o->name, *meta ? " " : "", meta);
    else
        snprintf(buf, n, "%s%s%s", o->name, *meta ? " " : "", meta);
}

/* The default the destination holds now, as text; "" when none is shown. */
static void default_text(const cli_opt *o, char *buf, size_t n)
{
    buf[0] = '\0';
    int iv;
    switch (o->kind) {
    case CLI_INT:
        iv = *(const int *)o->dest;
        if (o->word && iv == o->word_value)
            snprintf(buf, n, "%s", o->word);
        else if (iv == 0 && o->zero_means)
            snprintf(buf, n, "%s", o->zero_means);
        else if (iv < o->lo && o->lo >= 0)
            buf[0] = '\0'; /* "not set", e.g. -1 for no device named */
        else
            snprintf(buf, n, "%d", iv);
        break;
    case CLI_U64:
        snprintf(buf, n, "%" PRIu64, *(const uint64_t *)o->dest);
        break;
    case CLI_DOUBLE:
        if (*(const double *)o->dest == 0.0 && o->zero_means)
            snprintf(buf, n, "%s", o->zero_means);
        else
            snprintf(buf, n, "%g", *(const double *)o->dest);
        break;
    case CLI_STRING:
        if (*(const char *const *)o->dest)
            snprintf(buf, n, "%s", *(const char *const *)o->dest);
        break;
    case CLI_CHOICE:
        iv = *(const int *)o->dest;
        for (int k = 0; o->choices[k]; k++)
            if ((o->values ? o->values[k] : k) == iv)
                snprintf(buf, n, "%s", o->choices[k]);
        break;
    case CLI_CUSTOM:
        if (o->show)
            o->show(o->dest, buf, n);
        break;
    case CLI_FLAG:
    case CLI_SIZE:
        break;
    }
}

/* Appends a word to the usage line, wrapping under the command. */
static void usage_word(const char *word, int *col, int indent)
{
    int len = (int)strlen(word);
    if (*col + 1 + len > USAGE_WIDTH) {
        printf("\n%*s", indent, "");
        *col = indent;
    } else {
        putchar(' ');
        (*col)++;
    }
    fputs(word, stdout);
    *col += len;
}

static void usage_line(const cli_spec *s)
{
    int col = printf("usage: btfcar %s", s->cmd);
    int indent = col + 1;
    if (s->args && *s->args)
        usage_word(s->args, &col, indent);
    char label[256], word[300];
    for (const cli_opt *o = s->opts; !is_end(o); o++) {
        const char *meta = o->kind == CLI_FLAG ? "" : o->meta ? o->meta : "VALUE";
        snprintf(label, sizeof label, "%s%s%s", o->short_name ? o->short_name : o->name,
                 *meta ? " " : "", meta);
        snprintf(word, sizeof word, o->required ? "%s" : "[%s]", label);
        usage_word(word, &col, indent);
    }
    usage_word("[--quiet]", &col, indent);
    putchar('\n');
    if (s->alt_usage)
        printf("%s\n", s->alt_usage);
}

/* The help text as one paragraph (its '\n' are only hints for the source),
 * with the choices and the default appended, wrapped under HELP_COLUMN. */
static void help_paragraph(const cli_opt *o, const char *dflt)
{
    char text[2048], choices[512];
    snprintf(text, sizeof text, "%s", o->help);
    for (char *p = text; *p; p++)
        if (*p == '\n')
            *p = ' ';
    size_t used = strlen(text);
    if (o->kind == CLI_CHOICE && !(o->meta && strchr(o->meta, '|'))) {
        list_choices(o->choices, choices, sizeof choices);
        used += (size_t)snprintf(text + used, sizeof text - used, ": %s", choices);
    }
    if (dflt && *dflt && used < sizeof text)
        snprintf(text + used, sizeof text - used, " (default: %s)", dflt);
    int width = USAGE_WIDTH - HELP_COLUMN, col = 0;
    for (const char *p = text; *p;) {
        while (*p == ' ')
            p++;
        int len = (int)strcspn(p, " ");
        if (len == 0)
            break;
        if (col > 0 && col + 1 + len > width) {
            printf("\n%*s", HELP_COLUMN, "");
            col = 0;
        } else if (col > 0) {
            putchar(' ');
            col++;
        }
        printf("%.*s", len, p);
        col += len;
        p += len;
    }
    putchar('\n');
}

void cli_help(const cli_spec *s)
{
    usage_line(s);
    printf("\n%s\n", s->about);
    char label[256], dflt[256];
    for (const cli_opt *o = s->opts; !is_end(o); o++) {
        option_label(o, label, sizeof label);
        default_text(o, dflt, sizeof dflt);
        int w = printf("  %s", label);
        if (w >= HELP_COLUMN - 1)
            printf("\n%*s", HELP_COLUMN, "");
        else
            printf("%*s", HELP_COLUMN - w, "");
        help_paragraph(o, o->required ? NULL : dflt);
    }
    printf("  %-*s%s\n", HELP_COLUMN - 2, "-q, --quiet", "print nothing but errors");
    printf("  %-*s%s\n", HELP_COLUMN - 2, "-h, --help", "this text");
}
