/* cmd_info.c — btfcar info: what a dataset holds. */
#include "cli.h"

#include <string.h>

static void help(void)
{
    printf("usage: btfcar info [--verify] [--quiet] DATASET\n\n"
           "Describes a BTF dataset: its layout (UBO2003, UTIA or a manifest .tsv), the\n"
           "number of images, views and lights, the image size, the direction sets and\n"
           "the bytes on disk. Every image's header and structure is checked (a missing\n"
           "or duplicated (light, view) pair, mixed sizes or a truncated file is an error).\n\n"
           "  --verify   also decode every image (catches corrupt data, NaN/Inf in EXR)\n"
           "  --quiet    no progress bar\n");
}

/* "ubo81: 81 directions, theta 0..75 in 6 rings" */
static void describe_set(const btf_dirset *s, char *buf, size_t n)
{
    int rings = 0;
    double lo = 1e9, hi = -1;
    for (int i = 0; i < s->count; i++) {
        if (i == 0 || s->dirs[i].theta != s->dirs[i - 1].theta)
            rings++;
        if (s->dirs[i].theta < lo)
            lo = s->dirs[i].theta;
        if (s->dirs[i].theta > hi)
            hi = s->dirs[i].theta;
    }
    snprintf(buf, n, "%s: %d directions, theta %g..%g deg in %d rings", s->name, s->count, lo, hi,
             rings);
}

static const char *format_name(btf_file_format f)
{
    switch (f) {
    case BTF_FILE_PNG: return "PNG";
    case BTF_FILE_JPEG: return "JPEG";
    case BTF_FILE_EXR: return "EXR";
    default: return "?";
    }
}

int cmd_info(int argc, char **argv)
{
    cli_ctx c = {"info", 0};
    const char *path = NULL;
    int verify = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            help();
            return 0;
        } else if (!strcmp(a, "--quiet") || !strcmp(a, "-q")) {
            c.quiet = 1;
        } else if (!strcmp(a, "--verify")) {
            verify = 1;
        } else if (a[0] == '-' && a[1]) {
            return cli_usage_error(&c, "unknown option '%s'", a);
        } else if (!path) {
            path = a;
        } else {
            return cli_usage_error(&c, "unexpected argument '%s'", a);
        }
    }
    if (!path)
        return cli_usage_error(&c, "DATASET is required");
    btf_error err = {0};
    btf_dataset_opts o = {.progress = cli_progress_fn(&c)};
    btf_dataset *ds;
    if (btf_dataset_open(path, &o, &ds, &err) != 0)
        return cli_lib_error(&c, &err);
    if (verify && btf_dataset_verify_pixels(ds, cli_progress_fn(&c), NULL, &err) != 0) {
        btf_dataset_close(ds);
        return cli_lib_error(&c, &err);
    }
    cli_progress_done();
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    char views[128], lights[128], bytes[64];
    describe_set(in->views, views, sizeof views);
    describe_set(in->lights, lights, sizeof lights);
    cli_format_bytes(in->bytes_on_disk, bytes, sizeof bytes);
    printf("dataset     %s\n", in->root);
    printf("layout      %s\n", btf_layout_name(in->layout));
    printf("images      %d (%d views x %d lights)\n", in->n_views * in->n_lights, in->n_views,
           in->n_lights);
    printf("image size  %d x %d, %d channel%s, %s\n", in->width, in->height, in->channels,
           in->channels == 1 ? "" : "s", format_name(in->format));
    printf("views       %s\n", views);
    printf("lights      %s\n", lights);
    printf("on disk     %s\n", bytes);
    if (verify)
        printf("verified    every image decoded\n");
    btf_dataset_close(ds);
    return 0;
}
