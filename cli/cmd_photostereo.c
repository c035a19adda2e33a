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

static void help(void)
{
    printf("usage: btfcar photostereo DATASET -o OUTDIR [options]\n"
           "       btfcar photostereo --manifest FILE -o OUTDIR [options]\n\n"
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
           "albedo.png, height.png (shaded relief).\n\n"
           "  -o, --output OUTDIR    the folder for the results (required)\n"
           "  --manifest FILE        read the images and lights from a manifest\n"
           "  --mask IMAGE           work on the mask's non-zero pixels only (zero elsewhere)\n"
           "  --integrate poisson|fc least squares with a free boundary (default), or\n"
           "                         Frankot-Chellappa (periodic surfaces, e.g. generated tiles)\n"
           "  --linear               8-bit PNG/JPEG values are linear (default: sRGB)\n"
           "  --trim LOW,HIGH        fractions of the darkest / brightest samples left out\n"
           "                         of the first fit (default 0,0.1)\n"
           "  --dark F               samples below F x the pixel's reference level are\n"
           "                         shadows (default 0.1; 0: no such rule)\n"
           "  --outlier K            samples K robust standard deviations below the fit\n"
           "                         (2K above) are outliers (default 2)\n"
           "  --specular-cone DEG    highlight cone around the mirror direction (default 20;\n"
           "                         0: no such rule)\n"
           "  --saturation S         raw values >= S are clipped (default 0.99; 0: none, HDR)\n"
           "  --plain                plain least squares, no robust rule (for comparison)\n"
           "  --threads T            worker threads (default: all CPUs)\n"
           "  --quiet                no progress bar, no summary\n");
}

/* The whole string must be a finite number in [lo, hi]. */
static int parse_double(const char *s, double lo, double hi, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (end == s || *end || errno || !isfinite(v) || v < lo || v > hi)
        return -1;
    *out = v;
    return 0;
}

/* "LOW,HIGH" */
static int parse_trim(const char *s, double *lo, double *hi)
{
    char buf[64];
    const char *comma = strchr(s, ',');
    if (!comma || (size_t)(comma - s) >= sizeof buf)
        return -1;
    memcpy(buf, s, (size_t)(comma - s));
    buf[comma - s] = '\0';
    if (parse_double(buf, 0.0, 0.99, lo) || parse_double(comma + 1, 0.0, 0.99, hi) ||
        *lo + *hi >= 1.0)
        return -1;
    return 0;
}

typedef struct ps_args {
    const char *dataset, *manifest, *outdir, *mask;
    btf_photostereo_opts o;
} ps_args;

/* Options that take a value; returns 0 when handled, 2 on a usage error,
 * -1 when `a` is not one of them. */
static int value_option(const cli_ctx *c, ps_args *p, const char *a, const char *v, int *i)
{
    double x, y;
    long n;
    btf_photostereo_opts *o = &p->o;
    if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
        if (!v)
            return cli_usage_error(c, "%s needs a folder", a);
        p->outdir = v;
    } else if (!strcmp(a, "--manifest")) {
        if (!v)
            return cli_usage_error(c, "--manifest needs a file");
        p->manifest = v;
    } else if (!strcmp(a, "--mask")) {
        if (!v)
            return cli_usage_error(c, "--mask needs an image");
        p->mask = v;
    } else if (!strcmp(a, "--integrate")) {
        if (!v || (strcmp(v, "poisson") && strcmp(v, "fc")))
            return cli_usage_error(c, "--integrate needs poisson or fc");
        o->integrate.method = !strcmp(v, "fc") ? BTF_INTEGRATE_FC : BTF_INTEGRATE_POISSON;
    } else if (!strcmp(a, "--trim")) {
        if (!v || parse_trim(v, &x, &y))
            return cli_usage_error(c, "--trim needs LOW,HIGH fractions in [0, 1) with LOW + HIGH < 1");
        o->trim_low = x;
        o->trim_high = y > 0.0 ? y : -1.0; /* the library's 0 means its default */
    } else if (!strcmp(a, "--dark")) {
        if (!v || parse_double(v, 0.0, 0.99, &x))
            return cli_usage_error(c, "--dark needs a fraction in [0, 1)");
        o->dark = x > 0.0 ? x : -1.0;
    } else if (!strcmp(a, "--outlier")) {
        if (!v || parse_double(v, 0.1, 1e6, &x))
            return cli_usage_error(c, "--outlier needs a number >= 0.1");
        o->outlier = x;
    } else if (!strcmp(a, "--specular-cone")) {
        if (!v || parse_double(v, 0.0, 89.0, &x))
            return cli_usage_error(c, "--specular-cone needs degrees in [0, 89]");
        o->specular_cone = x > 0.0 ? x : -1.0;
    } else if (!strcmp(a, "--saturation")) {
        if (!v || parse_double(v, 0.0, 1e30, &x))
            return cli_usage_error(c, "--saturation needs a number >= 0");
        o->saturation = x > 0.0 ? x : -1.0;
    } else if (!strcmp(a, "--threads")) {
        if (!v || cli_parse_int(v, 1, 64, &n))
            return cli_usage_error(c, "--threads needs a whole number 1..64");
        o->threads = (int)n;
    } else {
        return -1;
    }
    (*i)++;
    return 0;
}

static int parse_args(cli_ctx *c, int argc, char **argv, ps_args *p)
{
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            help();
            return -1;
        } else if (!strcmp(a, "--quiet") || !strcmp(a, "-q")) {
            c->quiet = 1;
        } else if (!strcmp(a, "--linear")) {
            p->o.read.linear_8bit = 1;
        } else if (!strcmp(a, "--plain")) {
            p->o.plain = 1;
        } else {
            int rc = value_option(c, p, a, v, &i);
            if (rc > 0)
                return rc;
            if (rc == 0)
                continue;
            if (a[0] == '-' && a[1])
                return cli_usage_error(c, "unknown option '%s'", a);
            if (p->dataset)
                return cli_usage_error(c, "unexpected argument '%s'", a);
            p->dataset = a;
        }
    }
    if (!p->outdir)
        return cli_usage_error(c, "-o OUTDIR is required");
    if (!p->dataset == !p->manifest)
        return cli_usage_error(c, "give either DATASET or --manifest FILE");
    return 0;
}

static int run(const cli_ctx *c, const ps_args *p, btf_ps_result *r, btf_error *err)
{
    if (p->manifest)
        return btf_photostereo_manifest(p->manifest, &p->o, r, err);
    btf_dataset_opts dopts = {.skip_verify = 1, .progress = cli_progress_fn(c)};
    btf_dataset *ds;
    int rc = btf_dataset_open(p->dataset, &dopts, &ds, err);
    if (rc)
        return rc;
    rc = btf_photostereo_dataset(ds, &p->o, r, err);
    btf_dataset_close(ds);
    return rc;
}

int cmd_photostereo(int argc, char **argv)
{
    cli_ctx c = {"photostereo", 0};
    ps_args p = {0};
    int rc = parse_args(&c, argc, argv, &p);
    if (rc)
        return rc < 0 ? 0 : rc;
    p.o.progress = cli_progress_fn(&c);
    btf_error err = {0};
    btf_image mask = {0};
    if (p.mask && btf_image_read(p.mask, NULL, &mask, &err) != 0)
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
