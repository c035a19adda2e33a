/* cmd_photostereo.c — btfcar photostereo: normals, albedo and range map of a
 * BTF dataset (the view closest to theta_v = 0) or of ordinary photometric
 * stereo images listed in a manifest (library: src/range/, entry points in
 * src/range/photostereo.c and src/range/ps_manifest.c; docs/photostereo.md). */
#include "cli.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static const char ABOUT[] =
    "Robust Lambertian photometric stereo (Haindl & Filip 2007, section II.B): the\n"
    "normal and albedo of every pixel from images of one view under known lights,\n"
    "and the range map integrated from the normals. A BTF dataset uses the images\n"
    "of its view closest to theta_v = 0 under all its lights. A manifest is a TSV\n"
    "file whose header line names the columns: path (relative to the manifest's\n"
    "folder, or absolute), the light as theta_l phi_l (degrees) or as a vector\n"
    "lx ly lz (x right, y up in the image, z towards the camera), and optionally\n"
    "r g b, the light's intensity (divided out). Normals are written in the frame\n"
    "of the light directions. PNG (8/16-bit), JPEG and EXR of any size.\n\n"
    "Writes into OUTDIR (created if missing): normals.exr (x, y, z in R, G, B),\n"
    "albedo.exr, height.exr (pixel units, zero mean) and the previews normals.png,\n"
    "albedo.png, height.png (shaded relief).\n";

/* "LOW,HIGH" into the options' trim fractions. */
static int parse_trim(const char *s, void *dest, char *why, size_t n)
{
    btf_photostereo_opts *o = dest;
    double lo, hi;
    snprintf(why, n, "LOW,HIGH fractions in [0, 1) with LOW + HIGH < 1");
    if (cli_parse_pair(s, &lo, &hi) != 0 || !(lo >= 0.0 && lo <= 0.99) ||
        !(hi >= 0.0 && hi <= 0.99) || lo + hi >= 1.0)
        return -1;
    o->trim_low = lo;
    o->trim_high = hi;
    return 0;
}

static void show_trim(const void *dest, char *buf, size_t n)
{
    const btf_photostereo_opts *o = dest;
    snprintf(buf, n, "%g,%g", o->trim_low, o->trim_high > 0.0 ? o->trim_high : 0.0);
}

typedef struct ps_args {
    const char *dataset, *manifest, *outdir, *mask;
    btf_photostereo_opts o;
    btf_dir view;
    int has_view;
} ps_args;

/* "THETA,PHI" in degrees into p->view (theta 0..90, phi 0..360). */
static int parse_view(const char *s, void *dest, char *why, size_t n)
{
    ps_args *p = dest;
    if (cli_parse_dir(s, &p->view, why, n) != 0)
        return -1;
    p->has_view = 1;
    return 0;
}

static void show_view(const void *dest, char *buf, size_t n)
{
    (void)dest;
    snprintf(buf, n, "the view nearest the normal");
}

/* On the command line 0 turns a rule off; the library says so with < 0
 * (its 0 means the default). */
static void zero_means_off(double *v)
{
    if (*v == 0.0)
        *v = -1.0;
}

static int parse_args(cli_ctx *c, int argc, char **argv, ps_args *p)
{
    static const char *const methods[] = {"poisson", "fc", NULL};
    static const int method_values[] = {BTF_INTEGRATE_POISSON, BTF_INTEGRATE_FC};
    btf_photostereo_opts *o = &p->o;
    *o = btf_photostereo_defaults();
    o->read.max_pixels = BTF_DEFAULT_MAX_PIXELS;
    cli_opt opts[] = {
        {.name = "--output", .short_name = "-o", .kind = CLI_STRING, .dest = &p->outdir,
         .meta = "OUTDIR", .help = "the folder for the results", .required = 1},
        {.name = "--manifest", .kind = CLI_STRING, .dest = &p->manifest, .meta = "FILE",
         .help = "read the images and lights from a manifest"},
        {.name = "--view", .kind = CLI_CUSTOM, .dest = p, .meta = "THETA,PHI",
         .help = "use the images of the view nearest THETA,PHI (degrees; a dataset, or a\n"
                 "manifest with theta_v phi_v columns)",
         .parse = parse_view, .show = show_view},
        {.name = "--mask", .kind = CLI_STRING, .dest = &p->mask, .meta = "IMAGE",
         .help = "work on the mask's non-zero pixels only (zero elsewhere)"},
        {.name = "--integrate", .kind = CLI_CHOICE, .dest = &o->integrate.method,
         .meta = "poisson|fc",
         .help = "least squares with a free boundary, or Frankot-Chellappa\n"
                 "(periodic surfaces, e.g. generated tiles)",
         .choices = methods, .values = method_values},
        {.name = "--linear", .kind = CLI_FLAG, .dest = &o->read.linear_8bit,
         .help = "8-bit PNG/JPEG values are linear (default: sRGB)"},
        {.name = "--trim", .kind = CLI_CUSTOM, .dest = o, .meta = "LOW,HIGH",
         .help = "fractions of the darkest / brightest samples left out of the\n"
                 "first fit",
         .parse = parse_trim, .show = show_trim},
        {.name = "--dark", .kind = CLI_DOUBLE, .dest = &o->dark, .meta = "F",
         .help = "samples below F x the pixel's reference level are shadows\n"
                 "(0: no such rule)",
         .lo = 0.0, .hi = 0.99},
        {.name = "--outlier", .kind = CLI_DOUBLE, .dest = &o->outlier, .meta = "K",
         .help = "samples K robust standard deviations below the fit (2K above)\n"
                 "are outliers",
         .lo = 0.1, .hi = 1e6},
        {.name = "--specular-cone", .kind = CLI_DOUBLE, .dest = &o->specular_cone,
         .meta = "DEG", .help = "highlight cone around the mirror direction (0: no such rule)",
         .lo = 0.0, .hi = 89.0},
        {.name = "--saturation", .kind = CLI_DOUBLE, .dest = &o->saturation, .meta = "S",
         .help = "raw values >= S x full scale are clipped; full scale is 1 (8/16-bit\n"
                 "files), or the images' peak for data beyond 1 (HDR, scaled linear\n"
                 "EXR); 0: no such rule",
         .lo = 0.0, .hi = 1.0},
        {.name = "--plain", .kind = CLI_FLAG, .dest = &o->plain,
         .help = "plain least squares, no robust rule (for comparison)"},
        {.name = "--threads", .kind = CLI_INT, .dest = &o->threads, .meta = "T",
         .help = "worker threads", .lo = 1, .hi = 64, .zero_means = "all CPUs"},
        CLI_MAX_PIXELS_OPTION(&o->read.max_pixels),
        {0}};
    cli_spec spec = {.cmd = "photostereo", .args = "DATASET",
                     .alt_usage = "       btfcar photostereo --manifest FILE -o OUTDIR [options]",
                     .about = ABOUT, .min_args = 0, .max_args = 1, .opts = opts};
    int nargs, rc = cli_parse(c, &spec, argc, argv, &p->dataset, &nargs);
    if (rc >= 0)
        return rc == 0 ? -1 : rc;
    if (nargs == 0)
        p->dataset = NULL;
    if (!p->dataset == !p->manifest)
        return cli_usage_error(c, "give either DATASET or --manifest FILE");
    zero_means_off(&o->dark);
    zero_means_off(&o->specular_cone);
    zero_means_off(&o->saturation);
    zero_means_off(&o->trim_high);
    return 0;
}

static int run(const cli_ctx *c, const ps_args *p, btf_ps_result *r, btf_error *err)
{
    const btf_dir *view = p->has_view ? &p->view : NULL;
    if (p->manifest)
        return btf_photostereo_manifest_view(p->manifest, view, &p->o, r, err);
    btf_dataset_opts dopts = {.skip_verify = 1, .progress = cli_progress_fn(c),
                              .max_pixels = p->o.read.max_pixels};
    btf_dataset *ds;
    int rc = btf_dataset_open(p->dataset, &dopts, &ds, err);
    if (rc)
        return rc;
    rc = btf_photostereo_dataset_view(ds, view, &p->o, r, err);
    btf_dataset_close(ds);
    return rc;
}

/* Most pixels without a fit give a flat height map: worth a warning even
 * when the results are written (as analyse warns, BTF_RANGE_FLAT_TEXT). */
static void warn_if_flat(cli_ctx *c, const ps_args *p, const btf_ps_result *r)
{
    if (!(2 * (long long)r->fallback > r->pixels))
        return;
    char msg[1024];
    snprintf(msg, sizeof msg, "%s: fewer than 3 usable samples at %d of %d pixels (%.0f %%), "
             "so %s: most samples are clipped (a raw value >= --saturation x full scale), "
             "shadowed or black; if the images are not clipped there, raise --saturation or "
             "turn the rule off with --saturation 0", p->manifest ? p->manifest : p->dataset,
             r->fallback, r->pixels, 100.0 * r->fallback / r->pixels, BTF_RANGE_FLAT_TEXT);
    if (!c->quiet) /* --quiet prints nothing but errors */
        cli_warning(c, msg);
}

int cmd_photostereo(int argc, char **argv)
{
    cli_ctx c = {"photostereo", 0};
    ps_args p = {0};
    int rc = parse_args(&c, argc, argv, &p);
    if (rc)
        return rc < 0 ? 0 : rc;
    if (cli_check_output(&c, p.outdir, BTF_OUTPUT_FOLDER))
        return 1;
    p.o.progress = cli_progress_fn(&c);
    btf_error err = {0};
    btf_image mask = {0};
    btf_read_opts mro = {.max_pixels = p.o.read.max_pixels};
    if (p.mask && btf_image_read(p.mask, &mro, &mask, &err) != 0)
        return cli_lib_error(&c, &err);
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    p.o.mask = p.mask ? &mask : NULL;
    btf_ps_result r;
    rc = run(&c, &p, &r, &err);
    if (rc == 0) {
        rc = btf_ps_write(&r, p.mask ? &mask : NULL, p.outdir, &err);
        if (rc)
            btf_ps_result_free(&r);
    }
    btf_image_free(&mask);
    if (rc)
        return cli_lib_error(&c, &err);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    cli_progress_done();
    warn_if_flat(&c, &p, &r);
    if (!c.quiet) {
        char view[64] = "";
        if (r.view >= 0)
            snprintf(view, sizeof view, " (view theta %g phi %g)", r.view_dir.theta,
                     r.view_dir.phi);
        fprintf(stderr, "btfcar photostereo: %dx%d%s, %d pixels: %d fitted, %d fallback; "
                "results in %s (%.2f s)\n", r.normal.width, r.normal.height, view, r.pixels,
                r.fitted, r.fallback, p.outdir,
                (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec));
    }
    btf_ps_result_free(&r);
    return 0;
}
