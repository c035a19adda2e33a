/* cmd_generate.c — btfcar generate: a procedural BTF on disk, a stand-in with
 * known ground truth for the measured data that the analysis of Haindl &
 * Filip 2007, section II starts from (library: src/generate/). */
#include "cli.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

static const char ABOUT[] =
    "Renders a procedural material for all 81 x 81 (view, light) directions of the\n"
    "Bonn/UTIA sampling and writes it in the UBO2003 layout: OUTDIR/tvCCC_pvDDD/\n"
    "'NNNNN tlAAA plBBB tvCCC pvDDD.jpg' (8-bit sRGB JPEG), with the ground truth in\n"
    "OUTDIR/truth/{height,normals,albedo}.exr. OUTDIR must be new or empty.\n";

int cmd_generate(int argc, char **argv)
{
    cli_ctx c = {"generate", 0};
    btf_generate_opts o = btf_generate_defaults();
    o.seed = 1; /* the command's seed; the library's default is 0 */
    int material = -1;
    cli_opt opts[] = {
        {.name = "--material", .kind = CLI_CHOICE, .dest = &material, .meta = "NAME",
         .help = "the material", .choices = btf_material_names(), .required = 1},
        {.name = "--size", .kind = CLI_INT, .dest = &o.size, .meta = "N",
         .help = "image side in pixels", .lo = 1, .hi = 8192},
        {.name = "--seed", .kind = CLI_U64, .dest = &o.seed, .meta = "S",
         .help = "random seed; same seed, same bytes"},
        {.name = "--quality", .kind = CLI_INT, .dest = &o.jpeg_quality, .meta = "Q",
         .help = "JPEG quality", .lo = 1, .hi = 100},
        {.name = "--threads", .kind = CLI_INT, .dest = &o.threads, .meta = "T",
         .help = "worker threads", .lo = 1, .hi = 64, .zero_means = "all CPUs"},
        {0}};
    cli_spec spec = {.cmd = "generate", .args = "OUTDIR", .about = ABOUT, .min_args = 1,
                     .max_args = 1, .opts = opts};
    const char *outdir;
    int nargs, rc = cli_parse(&c, &spec, argc, argv, &outdir, &nargs);
    if (rc >= 0)
        return rc;
    if (cli_check_output(&c, outdir, BTF_OUTPUT_FOLDER))
        return 1;
    const char *name = btf_material_names()[material];
    o.progress = cli_progress_fn(&c);
    btf_error err = {0};
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    if (btf_generate(name, outdir, &o, &err) != 0)
        return cli_lib_error(&c, &err);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    cli_progress_done();
    if (!c.quiet)
        fprintf(stderr, "btfcar generate: %s, %dx%d, seed %llu: 6561 images + truth in %s (%.1f s)\n",
                name, o.size, o.size,
                (unsigned long long)o.seed, outdir,
                (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec));
    return 0;
}
