/* model_opts.c — what analyse and texture-fit share: the --neighbourhood
 * value (CLI_MODEL_OPTIONS in cli.h holds the rows), warnings, and the CAR
 * parameters of a subspace as text. */
#include "cli.h"

#include <stdio.h>
#include <string.h>

int cli_parse_neighbourhood(const char *value, void *dest, char *why, size_t n)
{
    btf_car_fit_opts *car = dest;
    if (!strcmp(value, "auto")) {
        car->n_fixed = 0;
        return 0;
    }
    btf_error err = {0};
    if (btf_neighbourhood_parse(value, car->fixed, &car->n_fixed, &err) != 0) {
        snprintf(why, n, "causal row:col offsets or auto (%s)", err.msg);
        return -1;
    }
    return 0;
}

void cli_show_neighbourhood(const void *dest, char *buf, size_t n)
{
    const btf_car_fit_opts *car = dest;
    if (car->n_fixed == 0)
        snprintf(buf, n, "auto");
    else
        btf_neighbourhood_format(car->fixed, car->n_fixed, buf, n);
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
