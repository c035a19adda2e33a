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
    "OUTDIR/truth/{height,normals,albedo}.exr. OUTDIR must be new or empty.\n\n"
    "With --format btf (DFMF, factorised: --components per channel), btf-fmf (one\n"
    "factorisation for the three channels), btf-pvf (a PCA per view) or btf-bdif\n"
    "(every value as a half float) the same images go into one Bonn .btf file,\n"
    "OUTDIR being the file's name, without the truth; the DFMF and FMF\n"
    "factorisations' cost grows as images x pixels x min(images, pixels), so keep\n"
    "--size small (32: about a minute). The error of the stored values is printed.\n";

static const char *const FORMATS[] = {"ubo2003", "btf", "btf-bdif", "btf-fmf", "btf-pvf", NULL};
/* The library's variant of each .btf format above (index - 1). */
static const int VARIANTS[] = {BTF_UBO2014_DFMF, BTF_UBO2014_BDIF, BTF_UBO2014_FMF,
                               BTF_UBO2014_PVF};
static const char *const VARIANT_NAMES[] = {"DFMF", "BDIF", "FMF", "FMF", "FMF", "FMF", "PVF",
                                            "PVF"};

typedef struct gen_btf {
    btf_procedural m;
    btf_dirset dirs;
} gen_btf;

static btf_status render_pair(void *user, int view, int light, btf_image *out, btf_error *err)
{
    gen_btf *g = user;
    return btf_procedural_render(&g->m, g->dirs.dirs[view], g->dirs.dirs[light], out, err);
}

/* The material's 81 x 81 images as one .btf file (src/io/ubo_write.c). */
static int generate_btf(cli_ctx *c, const char *name, const char *path,
                        const btf_generate_opts *o, int variant, int components)
{
    btf_error err = {0};
    gen_btf g;
    if (btf_procedural_make(name, o->size, o->seed, &g.m, &err) != 0)
        return cli_lib_error(c, &err);
    if (btf_dirset_ubo81(&g.dirs, &err) != 0) {
        btf_procedural_free(&g.m);
        return cli_lib_error(c, &err);
    }
    btf_ubo2014_write_opts wo = btf_ubo2014_write_defaults();
    wo.variant = variant;
    if (components)
        wo.components = components;
    wo.progress = o->progress;
    btf_ubo2014_write_stats st;
    double t0 = cli_now();
    int rc = btf_ubo2014_write(path, &g.dirs, &g.dirs, o->size, o->size, render_pair, &g, &wo,
                               &st, &err);
    btf_dirset_free(&g.dirs);
    btf_procedural_free(&g.m);
    if (rc != 0)
        return cli_lib_error(c, &err);
    cli_progress_done();
    if (!c->quiet) {
        fprintf(stderr, "btfcar generate: %s, %dx%d, seed %llu: 6561 images in %s (%s, %llu "
                        "bytes, %.1f s)\n", name, o->size, o->size, (unsigned long long)o->seed,
                path, VARIANT_NAMES[variant], (unsigned long long)st.bytes, cli_now() - t0);
        if (variant != BTF_UBO2014_BDIF)
            fprintf(stderr, "btfcar generate: components R %d G %d B %d; error of the stored "
                            "values: RMS %.3g %.3g %.3g, max %.3g %.3g %.3g; energy kept "
                            "%.6f %.6f %.6f\n",
                    st.components[0], st.components[1], st.components[2], st.rms_error[0],
                    st.rms_error[1], st.rms_error[2], st.max_error[0], st.max_error[1],
                    st.max_error[2], st.energy[0], st.energy[1], st.energy[2]);
        else
            fprintf(stderr, "btfcar generate: half rounding: max error %.3g %.3g %.3g\n",
                    st.max_error[0], st.max_error[1], st.max_error[2]);
    }
    return 0;
}

int cmd_generate(int argc, char **argv)
{
    cli_ctx c = {"generate", 0};
    btf_generate_opts o = btf_generate_defaults();
    o.seed = 1; /* the command's seed; the library's default is 0 */
    int material = -1, format = 0, components = 0;
    cli_opt opts[] = {
        {.name = "--material", .kind = CLI_CHOICE, .dest = &material, .meta = "NAME",
         .help = "the material", .choices = btf_procedural_names(), .required = 1},
        {.name = "--size", .kind = CLI_INT, .dest = &o.size, .meta = "N",
         .help = "image side in pixels", .lo = 1, .hi = 8192},
        {.name = "--seed", .kind = CLI_U64, .dest = &o.seed, .meta = "S",
         .help = "random seed; same seed, same bytes"},
        {.name = "--quality", .kind = CLI_INT, .dest = &o.jpeg_quality, .meta = "Q",
         .help = "JPEG quality", .lo = 1, .hi = 100},
        {.name = "--format", .kind = CLI_CHOICE, .dest = &format, .meta = "FORMAT",
         .help = "ubo2003: JPEG files in OUTDIR; btf: one DFMF .btf file; btf-bdif:\n"
                 "one BDIF .btf file (half floats); btf-fmf: one FMF .btf file;\n"
                 "btf-pvf: one PVF .btf file", .choices = FORMATS},
        {.name = "--components", .kind = CLI_INT, .dest = &components, .meta = "K",
         .help = "btf: components per channel (btf-fmf: in all, btf-pvf: per view)",
         .lo = 1, .hi = 4096,
         .zero_means = "16"},
        {.name = "--threads", .kind = CLI_INT, .dest = &o.threads, .meta = "T",
         .help = "worker threads", .lo = 1, .hi = 64, .zero_means = "all CPUs"},
        {0}};
    cli_spec spec = {.cmd = "generate", .args = "OUTDIR", .about = ABOUT, .min_args = 1,
                     .max_args = 1, .opts = opts};
    const char *outdir;
    int nargs, rc = cli_parse(&c, &spec, argc, argv, &outdir, &nargs);
    if (rc >= 0)
        return rc;
    if (format == 0 && components)
        return cli_usage_error(&c, "--components needs --format btf, btf-fmf or btf-pvf");
    if (cli_check_output(&c, outdir, format ? BTF_OUTPUT_FILE : BTF_OUTPUT_FOLDER))
        return 1;
    const char *name = btf_procedural_names()[material];
    o.progress = cli_progress_fn(&c);
    if (format)
        return generate_btf(&c, name, outdir, &o, VARIANTS[format - 1], components);
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
