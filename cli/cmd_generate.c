/* cmd_generate.c — btfcar generate: a procedural BTF on disk. */
#include "cli.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

static void help(void)
{
    const char *const *names = btf_material_names();
    printf("usage: btfcar generate --material NAME [--size N] [--seed S] [--quality Q]\n"
           "                       [--threads T] [--quiet] OUTDIR\n\n"
           "Renders a procedural material for all 81 x 81 (view, light) directions of the\n"
           "Bonn/UTIA sampling and writes it in the UBO2003 layout: OUTDIR/tvCCC_pvDDD/\n"
           "'NNNNN tlAAA plBBB tvCCC pvDDD.jpg' (8-bit sRGB JPEG), with the ground truth in\n"
           "OUTDIR/truth/{height,normals,albedo}.exr. OUTDIR must be new or empty.\n\n"
           "  --material NAME  one of:");
    for (int i = 0; names[i]; i++)
        printf(" %s", names[i]);
    printf("\n  --size N         image side in pixels (default 128)\n"
           "  --seed S         random seed (default 1); same seed, same bytes\n"
           "  --quality Q      JPEG quality 1..100 (default 95)\n"
           "  --threads T      worker threads (default: all CPUs)\n"
           "  --quiet          no progress bar\n");
}

int cmd_generate(int argc, char **argv)
{
    cli_ctx c = {"generate", 0};
    const char *material = NULL, *outdir = NULL;
    btf_generate_opts o = {.seed = 1};
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        long n;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            help();
            return 0;
        } else if (!strcmp(a, "--quiet") || !strcmp(a, "-q")) {
            c.quiet = 1;
        } else if (!strcmp(a, "--material")) {
            if (!v)
                return cli_usage_error(&c, "--material needs a name");
            material = v, i++;
        } else if (!strcmp(a, "--size")) {
            if (!v || cli_parse_int(v, 1, 8192, &n))
                return cli_usage_error(&c, "--size needs a whole number 1..8192");
            o.size = (int)n, i++;
        } else if (!strcmp(a, "--seed")) {
            if (!v || cli_parse_u64(v, &o.seed))
                return cli_usage_error(&c, "--seed needs a non-negative whole number");
            i++;
        } else if (!strcmp(a, "--quality")) {
            if (!v || cli_parse_int(v, 1, 100, &n))
                return cli_usage_error(&c, "--quality needs a whole number 1..100");
            o.jpeg_quality = (int)n, i++;
        } else if (!strcmp(a, "--threads")) {
            if (!v || cli_parse_int(v, 1, 64, &n))
                return cli_usage_error(&c, "--threads needs a whole number 1..64");
            o.threads = (int)n, i++;
        } else if (a[0] == '-' && a[1]) {
            return cli_usage_error(&c, "unknown option '%s'", a);
        } else if (!outdir) {
            outdir = a;
        } else {
            return cli_usage_error(&c, "unexpected argument '%s'", a);
        }
    }
    if (!material)
        return cli_usage_error(&c, "--material is required");
    if (!outdir)
        return cli_usage_error(&c, "OUTDIR is required");
    o.progress = cli_progress_fn(&c);
    btf_error err = {0};
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    if (btf_generate(material, outdir, &o, &err) != 0)
        return cli_lib_error(&c, &err);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    cli_progress_done();
    if (!c.quiet)
        fprintf(stderr, "btfcar generate: %s, %dx%d, seed %llu: 6561 images + truth in %s (%.1f s)\n",
                material, o.size ? o.size : 128, o.size ? o.size : 128,
                (unsigned long long)o.seed, outdir,
                (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec));
    return 0;
}
