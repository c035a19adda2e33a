/* model_opts.c — the model options shared by analyse and texture-fit:
 * --levels L|auto, --neighbourhood SPEC|auto and --max-neighbours N. */
#include "cli.h"

#include <string.h>

int cli_model_option(const cli_ctx *c, int argc, char **argv, int *i, btf_fit_opts *fo, int *rc)
{
    const char *a = argv[*i];
    const char *v = *i + 1 < argc ? argv[*i + 1] : NULL;
    *rc = 0;
    if (!strcmp(a, "--levels")) {
        long n;
        if (!v)
            return *rc = cli_usage_error(c, "--levels needs L or auto"), 1;
        if (!strcmp(v, "auto"))
            fo->levels = 0;
        else if (cli_parse_int(v, 1, BTF_MAX_LEVELS, &n))
            return *rc = cli_usage_error(c, "--levels needs 1..%d or auto", BTF_MAX_LEVELS), 1;
        else
            fo->levels = (int)n;
        (*i)++;
        return 1;
    }
    if (!strcmp(a, "--max-neighbours")) {
        long n;
        if (!v || cli_parse_int(v, 1, 14, &n))
            return *rc = cli_usage_error(c, "--max-neighbours needs a whole number 1..14"), 1;
        fo->car.max_neighbours = (int)n;
        (*i)++;
        return 1;
    }
    if (!strcmp(a, "--neighbourhood") || !strcmp(a, "--neighborhood")) {
        if (!v)
            return *rc = cli_usage_error(c, "--neighbourhood needs SPEC or auto"), 1;
        if (!strcmp(v, "auto")) {
            fo->car.n_fixed = 0;
        } else {
            btf_error err = {0};
            if (btf_neighbourhood_parse(v, fo->car.fixed, &fo->car.n_fixed, &err) != 0)
                return *rc = cli_usage_error(c, "%s", err.msg), 1;
        }
        (*i)++;
        return 1;
    }
    return 0;
}

void cli_warning(void *user, const char *message)
{
    const cli_ctx *c = user;
    cli_progress_done();
    fprintf(stderr, "btfcar %s: warning: %s\n", c->cmd, message);
}

void cli_print_subspace(const btf_subspace_model *s, int index)
{
    printf("subspace %d: %dx%d, %d level%s, mean RGB (%.4g, %.4g, %.4g)\n", index, s->width,
           s->height, s->levels, s->levels == 1 ? "" : "s", s->mean[0], s->mean[1], s->mean[2]);
    for (int b = 0; b < 3; b++)
        for (int l = 0; l < s->levels; l++) {
            const btf_car_band *cb = &s->bands[b][l];
            char spec[256];
            btf_neighbourhood_format(cb->offsets, cb->n, spec, sizeof spec);
            printf("  band %d level %d: %2d neighbours %-28s sigma %.4g mean %.4g\n", b, l, cb->n,
                   cb->n ? spec : "(white noise)", cb->sigma, cb->mean);
        }
}
