/*
 * cmd_export.c — btfcar export: images of a dataset written as files; made
 * for Bonn .btf files (layout UBO2014), whose images exist only as factors
 * until reconstructed (src/io/ubo_decode.c), but any dataset works. One
 * (view, light) pair to one image, or every pair in the UTIA layout.
 */
#include "cli.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char ABOUT[] =
    "Reconstructs images of a dataset, typically a Bonn .btf file (DFMF, FMF, PVF or\n"
    "BDIF; docs/datasets.md, \"UBO2014 .btf files\"), and writes them: with --view and\n"
    "--light the pair nearest to those directions (within 0.75 degree) to IMAGE (.exr:\n"
    "linear 32-bit float; otherwise 8-bit sRGB PNG); with --all every pair into the\n"
    "folder DIR in the UTIA layout, DIR/tvCCC_pvDDD/tlAAA_plBBB_tvCCC_pvDDD.exr (linear\n"
    "half float), which btfcar reads back as a dataset. Images are made one at a time.\n";

static int find_dir(const cli_ctx *c, const btf_dirset *set, btf_dir d, const char *what,
                    const char *path)
{
    int i = btf_dirset_find(set, d, 0.75);
    if (i < 0) {
        cli_error(c, "%s: no %s direction within 0.75 degree of (%g, %g) among its %d", path,
                  what, d.theta, d.phi, set->count);
        return -1;
    }
    return i;
}

static int export_all(cli_ctx *c, btf_dataset *ds, const char *dir)
{
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    btf_error err = {0};
    btf_output_dir *od = NULL;
    if (btf_output_dir_begin(dir, &od, &err) != 0)
        return cli_lib_error(c, &err);
    const char *tmp = btf_output_dir_path(od);
    btf_progress_fn progress = cli_progress_fn(c);
    int n = in->n_pairs, done = 0;
    btf_dataset_iter it;
    btf_dataset_iter_begin(&it, ds);
    int rc;
    char last_folder[64] = "";
    while ((rc = btf_dataset_iter_next(&it, &err)) == 1) {
        const btf_sample *s = &it.sample;
        int tv = (int)lround(s->view_dir.theta), pv = (int)lround(s->view_dir.phi) % 360,
            tl = (int)lround(s->light_dir.theta), pl = (int)lround(s->light_dir.phi) % 360;
        char folder[64], path[8192];
        snprintf(folder, sizeof folder, "tv%03d_pv%03d", tv, pv);
        snprintf(path, sizeof path, "%s/%s", tmp, folder);
        if (strcmp(folder, last_folder) != 0) {
            if (btf_mkdirs(path, &err) != 0) {
                rc = -1;
                break;
            }
            snprintf(last_folder, sizeof last_folder, "%s", folder);
        }
        snprintf(path, sizeof path, "%s/%s/tl%03d_pl%03d_tv%03d_pv%03d.exr", tmp, folder, tl, pl,
                 tv, pv);
        btf_exr_opts eo = btf_exr_defaults();
        eo.half = 1;
        btf_exr_meta meta = {.has_dirs = 1, .view = s->view_dir, .light = s->light_dir};
        if (btf_image_write_exr_opts(path, &s->image, &eo, &meta, &err) != 0) {
            rc = -1;
            break;
        }
        done++;
        if (progress && (done % 64 == 0 || done == n))
            progress(NULL, (double)done / n, "writing images");
    }
    btf_dataset_iter_end(&it);
    if (rc == 0 && done != n)
        rc = cli_set_error(&err, BTF_E_DATA, "%s: %d of %d images written", dir, done, n);
    if (rc == 0 && btf_output_dir_commit(od, &err) == 0) {
        cli_progress_done();
        if (!c->quiet)
            fprintf(stderr, "btfcar export: %d images (%d views x %d lights, %dx%d) in %s\n", n,
                    in->n_views, in->n_lights, in->width, in->height, dir);
        return 0;
    }
    if (rc != 0)
        btf_output_dir_fail(od, &err);
    cli_progress_done();
    return cli_lib_error(c, &err);
}

int cmd_export(int argc, char **argv)
{
    cli_ctx c = {"export", 0};
    const char *in_path = NULL, *out = NULL;
    cli_dir_arg view = {{0, 0}, 0}, light = {{0, 0}, 0};
    int all = 0;
    uint64_t max_px = BTF_DEFAULT_MAX_PIXELS;
    cli_opt opts[] = {
        {.name = "--view", .kind = CLI_CUSTOM, .dest = &view, .meta = "THETA,PHI",
         .help = "the view direction (degrees)", .parse = cli_parse_dir_arg},
        {.name = "--light", .kind = CLI_CUSTOM, .dest = &light, .meta = "THETA,PHI",
         .help = "the light direction (degrees)", .parse = cli_parse_dir_arg},
        {.name = "--all", .kind = CLI_FLAG, .dest = &all,
         .help = "every (view, light) pair, into the folder given by -o (UTIA layout)"},
        {.name = "--output", .short_name = "-o", .kind = CLI_STRING, .dest = &out,
         .meta = "IMAGE|DIR", .help = "the image (.exr or .png), or with --all the folder",
         .required = 1},
        CLI_MAX_PIXELS_OPTION(&max_px),
        {0}};
    cli_spec spec = {.cmd = "export", .args = "DATASET",
                     .alt_usage = "       btfcar export DATASET --all -o DIR", .about = ABOUT,
                     .min_args = 1, .max_args = 1, .opts = opts};
    int nargs, prc = cli_parse(&c, &spec, argc, argv, &in_path, &nargs);
    if (prc >= 0)
        return prc;
    if (all && (view.given || light.given))
        return cli_usage_error(&c, "--all takes no --view or --light");
    if (!all && (!view.given || !light.given))
        return cli_usage_error(&c, "--view and --light are required (or --all)");
    if (cli_check_output(&c, out, all ? BTF_OUTPUT_FOLDER : BTF_OUTPUT_FILE))
        return 1;
    btf_error err = {0};
    btf_dataset_opts o = {.progress = cli_progress_fn(&c), .max_pixels = max_px};
    btf_dataset *ds;
    if (btf_dataset_open(in_path, &o, &ds, &err) != 0)
        return cli_lib_error(&c, &err);
    int rc;
    if (all) {
        rc = export_all(&c, ds, out);
    } else {
        const btf_dataset_info *in = btf_dataset_get_info(ds);
        int vi = find_dir(&c, in->views, view.dir, "view", in_path);
        int li = vi < 0 ? -1 : find_dir(&c, in->lights, light.dir, "light", in_path);
        rc = 1;
        if (vi >= 0 && li >= 0) {
            btf_image img = {0};
            if (btf_dataset_read(ds, vi, li, &img, &err) != 0 ||
                cli_write_image(out, &img, &err) != 0)
                rc = cli_lib_error(&c, &err);
            else
                rc = 0;
            btf_image_free(&img);
        }
    }
    btf_dataset_close(ds);
    return rc;
}
