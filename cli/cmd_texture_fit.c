/* cmd_texture_fit.c — btfcar texture-fit: the CAR model of one texture. */
#include "cli.h"

#include <string.h>

static void help(void)
{
    printf("usage: btfcar texture-fit IMAGE -o MODEL.btfcar [--levels L|auto]\n"
           "                          [--neighbourhood SPEC|auto] [--quiet]\n\n"
           "Models one ordinary colour texture (PNG, JPEG or EXR) with the multi-scale\n"
           "colour 2D CAR model: spectral decorrelation, a Gaussian-Laplacian pyramid and\n"
           "one causal auto-regressive model per band and level (docs/model.md). The\n"
           "model has one subspace, no directions and no range map; 'btfcar synthesise'\n"
           "regenerates the texture at any size.\n\n"
           "  -o MODEL             the model file to write (atomically)\n"
           "  --levels L|auto      pyramid levels 1..%d; auto (default) from the image size\n"
           "                       and its correlation length, at most 3\n"
           "  --neighbourhood SPEC causal offsets row:col, comma-separated, e.g.\n"
           "                       0:-1,-1:0,-1:-1,-1:1; auto (default) chooses per sub-band\n"
           "                       by the posterior probability of each candidate model\n"
           "  --max-neighbours N   auto: the largest candidate considered, 1..14 (default 14;\n"
           "                       the paper's models have fewer than 4)\n"
           "  --quiet              print nothing but errors\n", BTF_MAX_LEVELS);
}

int cmd_texture_fit(int argc, char **argv)
{
    cli_ctx c = {"texture-fit", 0};
    const char *image = NULL, *out = NULL;
    btf_fit_opts fo = {0};
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        int rc;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            help();
            return 0;
        } else if (!strcmp(a, "--quiet") || !strcmp(a, "-q")) {
            c.quiet = 1;
        } else if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
            if (i + 1 >= argc)
                return cli_usage_error(&c, "-o needs a path");
            out = argv[++i];
        } else if (cli_model_option(&c, argc, argv, &i, &fo, &rc)) {
            if (rc)
                return rc;
        } else if (a[0] == '-' && a[1]) {
            return cli_usage_error(&c, "unknown option '%s'", a);
        } else if (!image) {
            image = a;
        } else {
            return cli_usage_error(&c, "unexpected argument '%s'", a);
        }
    }
    if (!image)
        return cli_usage_error(&c, "IMAGE is required");
    if (!out)
        return cli_usage_error(&c, "-o MODEL is required");
    btf_error err = {0};
    btf_image img;
    btf_read_opts ro = {.channels = 3};
    if (btf_image_read(image, &ro, &img, &err) != 0)
        return cli_lib_error(&c, &err);
    fo.car.warn = c.quiet ? NULL : cli_warning;
    fo.car.warn_user = &c;
    btf_model m;
    int rc = btf_texture_fit(&img, &fo, &m, &err);
    btf_image_free(&img);
    if (rc)
        return cli_lib_error(&c, &err);
    rc = btf_model_write(out, &m, &err);
    if (rc == 0 && !c.quiet) {
        cli_print_subspace(&m.subspaces[0], 0);
        printf("written %s\n", out);
    }
    btf_model_free(&m);
    return rc ? cli_lib_error(&c, &err) : 0;
}
