/*
 * main.c — the btfcar command: dispatches to one file per subcommand.
 * The command is thin: every stage is a library function (include/btfcar.h).
 */
#include "cli.h"

#include <string.h>

static const struct {
    const char *name;
    int (*run)(int, char **);
    const char *summary;
} commands[] = {
    {"generate", cmd_generate, "write a procedural BTF (81 x 81 images) in the UBO2003 layout"},
    {"info", cmd_info, "describe a dataset, a model file, or the Vulkan devices"},
    {"analyse", cmd_analyse, "analyse a dataset into a model file (or one stage: --stage segment)"},
    {"photostereo", cmd_photostereo, "normals, albedo and range map by robust photometric stereo"},
    {"texture-fit", cmd_texture_fit, "model one colour texture with the multi-scale 2D CAR model"},
    {"synthesise", cmd_synthesise, "generate subspace images of a model at any size (CPU or GPU)"},
    {"render", cmd_render, "render the material on a scene, or flat for one (view, light) pair"},
    {"compare", cmd_compare, "distances between two textures, normalised by the reference's own"},
    {"export", cmd_export, "write a dataset's images (a Bonn .btf file's, reconstructed) as files"},
    {"report", cmd_report, "a page of what a model costs, how close it comes, and the trade"},
    {"library", cmd_library, "one page of many materials' reports (a cluster run's last step)"},
};

static void usage(FILE *f)
{
    fprintf(f, "usage: btfcar COMMAND [OPTIONS] ...\n\n"
               "Probabilistic modelling of Bidirectional Texture Functions.\n\ncommands:\n");
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        fprintf(f, "  %-12s %s\n", commands[i].name, commands[i].summary);
    fprintf(f, "\n'btfcar COMMAND --help' describes a command; 'btfcar --version' (-V) prints the version.\n");
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        usage(stderr);
        return 2;
    }
    if (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") || !strcmp(argv[1], "help")) {
        usage(stdout);
        return 0;
    }
    if (!strcmp(argv[1], "--version") || !strcmp(argv[1], "-V")) {
        printf("btfcar %s\n", BTF_VERSION_STRING);
        return 0;
    }
    cli_install_signal_cleanup();
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        if (!strcmp(argv[1], commands[i].name))
            return commands[i].run(argc - 1, argv + 1);
    fprintf(stderr, "btfcar: unknown command '%s' (see 'btfcar --help')\n", argv[1]);
    return 2;
}
