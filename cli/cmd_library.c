/*
 * cmd_library.c — btfcar library: the library report from the report
 * folders of many materials (btf_library_write; docs/cluster.md).
 */
#include "cli.h"
#include "options.h"

#include <stdio.h>

static const char ABOUT[] =
    "One page and one JSON (library.json) with a row per material, built from\n"
    "the folders `btfcar report` wrote for each: model bytes, compression\n"
    "ratio, mean and worst combined distance, the report's time, the preview\n"
    "and a link to each report. Nothing is measured again; a missing or\n"
    "unreadable report is an error naming it, and nothing is written. On a\n"
    "cluster each material's analyse + report is one task and this the last\n"
    "(docs/cluster.md, examples/slurm/).";

int cmd_library(int argc, char **argv)
{
    cli_ctx c = {"library", 0};
    const char *out = NULL;
    cli_opt opts[] = {
        {.name = "--output", .short_name = "-o", .kind = CLI_STRING, .dest = &out,
         .meta = "DIR", .help = "the library report's folder (index.html, library.json)",
         .required = 1},
        {0}};
    cli_spec spec = {.cmd = "library", .args = "REPORT_DIR...", .about = ABOUT, .min_args = 1,
                     .max_args = 4096, .opts = opts};
    const char *args[4096];
    int nargs, prc = cli_parse(&c, &spec, argc, argv, args, &nargs);
    if (prc >= 0)
        return prc;
    if (cli_check_output(&c, out, BTF_OUTPUT_FOLDER))
        return 1;
    btf_error err = {0};
    int rows = 0;
    if (btf_library_write(args, nargs, out, &rows, &err))
        return cli_lib_error(&c, &err);
    if (!c.quiet)
        printf("library       %s/index.html (and library.json): %d material%s\n", out, rows,
               rows == 1 ? "" : "s");
    return 0;
}
