/* cmd_analyse.c — btfcar analyse: the analysis stages on a dataset (Haindl &
 * Filip 2007, section II: II.A segmentation, II.B range map, II.C CAR
 * models; library: src/analyse/analyse.c), or stage 1 alone with its
 * pictures and tables (--stage segment). */
#include "cli.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>


static const char ABOUT[] =
    "Analyses a BTF dataset (paper section II) into one model file:\n"
    "  1. segment  k-means on CIE Lab cumulative histograms of the (view, light)\n"
    "              images gives K subspace images and the index table;\n"
    "  2. range    robust photometric stereo on the view closest to the normal\n"
    "              gives the range map, kept at the analysed resolution, and the\n"
    "              albedo's pattern (the structure layer, docs/model.md);\n"
    "  3. model    each subspace image, divided by what the relief and albedo\n"
    "              explain under its light: spectral PCA, Gaussian-Laplacian\n"
    "              pyramid, one 2D CAR model per band and level (docs/model.md).\n"
    "With --stage segment it stops after stage 1 and writes to the folder OUT:\n"
    "index.png (x = view, y = light, one colour per subspace), index.tsv,\n"
    "subspaces.tsv, and each subspace image as subspace_NN.exr + .png preview;\n"
    "the options of the later stages (--levels, --neighbourhood, --max-neighbours,\n"
    "--no-range, --range-size, --no-structure) are then a usage error.\n"
    "With --family rf it fits per-view reflectance fields instead (Meseth, Mueller\n"
    "& Klein 2003; docs/rf.md): per measured view and texel a PTM or K lobes over\n"
    "the lights, on luminance, with the view's average colour per texel; render\n"
    "and info take the file it writes. With --sample N it fits only an N x N\n"
    "sample and stores a map of texture coordinates into it from an image\n"
    "quilting of the sample (the paper's section 6, memory reduction): the file\n"
    "is the sample's coefficients plus the map, whatever the surface's size, and\n"
    "outside the sample's own place the surface no longer corresponds texel for\n"
    "texel to the data.\n";

/* Options only the stages after the segmentation use; options of the
 * reflectance-field family only. */
enum { TAG_LATER = 1, TAG_RF = 2 };

/* The CAR family's options, which --family rf does not use. */
static const char *const CAR_ONLY[] = {"--preset", "--stage", "--subspaces", "--bins",
                                       "--restarts", "--levels", "--neighbourhood",
                                       "--neighborhood", "--max-neighbours", "--no-range",
                                       "--range-size", "--no-structure", "--no-shadows",
                                       "--no-gains", "--saturation", NULL};

/* Writes text that was built in memory (open_memstream) to path atomically:
 * the whole file appears or none does. Frees the text. */
static int write_text(const char *path, FILE *mem, char **text, size_t *len, btf_error *err)
{
    int bad = ferror(mem);
    bad |= fclose(mem) != 0;
    int rc = bad ? cli_set_error(err, BTF_E_NOMEM, "%s: out of memory formatting it", path)
                 : btf_write_file_atomic(path, *text, *len, err);
    free(*text);
    *text = NULL;
    return rc;
}

/* A table built in memory, its header line first, then written by
 * write_text. */
static FILE *text_begin(char **text, size_t *len, const char *path, const char *header,
                        btf_error *err)
{
    FILE *f = open_memstream(text, len);
    if (!f)
        cli_set_error(err, BTF_E_NOMEM, "%s: out of memory formatting it", path);
    else
        fputs(header, f);
    return f;
}

static int write_index_tsv(const btf_segmentation *s, const btf_dataset_info *in,
                           const char *path, btf_error *err)
{
    char *text = NULL;
    size_t len = 0;
    FILE *f = text_begin(&text, &len, path,
                         "view\tlight\ttheta_v\tphi_v\ttheta_l\tphi_l\tsubspace\n", err);
    if (!f)
        return BTF_E_NOMEM;
    for (int v = 0; v < s->n_views; v++)
        for (int l = 0; l < s->n_lights; l++)
            if (s->index[v * s->n_lights + l] != BTF_PAIR_NONE) /* a sparse set's pairs only */
            fprintf(f, "%d\t%d\t%g\t%g\t%g\t%g\t%d\n", v, l, in->views->dirs[v].theta,
                    in->views->dirs[v].phi, in->lights->dirs[l].theta, in->lights->dirs[l].phi,
                    s->index[v * s->n_lights + l]);
    return write_text(path, f, &text, &len, err);
}

static int write_subspaces_tsv(const btf_segmentation *s, const btf_dataset_info *in,
                               const char *path, btf_error *err)
{
    char *text = NULL;
    size_t len = 0;
    FILE *f = text_begin(&text, &len, path,
                         "subspace\tmembers\tview\tlight\ttheta_v\tphi_v\ttheta_l\tphi_l\timage\n",
                         err);
    if (!f)
        return BTF_E_NOMEM;
    for (int c = 0; c < s->k; c++) {
        int v = s->rep_view[c], l = s->rep_light[c];
        fprintf(f, "%d\t%d\t%d\t%d\t%g\t%g\t%g\t%g\tsubspace_%02d.exr\n", c, s->members[c], v,
                l, in->views->dirs[v].theta, in->views->dirs[v].phi, in->lights->dirs[l].theta,
                in->lights->dirs[l].phi, c);
    }
    return write_text(path, f, &text, &len, err);
}

/* index.tsv and subspaces.tsv in the folder out. */
static int write_tables(const btf_segmentation *s, const btf_dataset_info *in, const char *out,
                        btf_error *err)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/index.tsv", out);
    int rc = write_index_tsv(s, in, path, err);
    if (rc)
        return rc;
    snprintf(path, sizeof path, "%s/subspaces.tsv", out);
    return write_subspaces_tsv(s, in, path, err);
}

static int write_subspace_images(const btf_segmentation *s, const btf_dataset *ds,
                                 const char *out, btf_error *err)
{
    for (int c = 0; c < s->k; c++) {
        btf_image img;
        char path[4096];
        int rc = btf_dataset_read(ds, s->rep_view[c], s->rep_light[c], &img, err);
        if (rc)
            return rc;
        snprintf(path, sizeof path, "%s/subspace_%02d.exr", out, c);
        rc = btf_image_write_exr_opts(path, &img, NULL, NULL, err);
        snprintf(path, sizeof path, "%s/subspace_%02d.png", out, c);
        if (rc == 0)
            rc = btf_image_write_png(path, &img, err);
        btf_image_free(&img);
        if (rc)
            return rc;
    }
    return 0;
}

/* The whole analysis into a model file, with a report. */
static int analyse_all(cli_ctx *c, const char *dataset, const char *out, btf_analyse_opts ao)
{
    btf_error err = {0};
    btf_dataset_opts dopts = {.progress = cli_progress_fn(c),
                              .max_pixels = ao.photostereo.read.max_pixels};
    btf_dataset *ds;
    double t0 = cli_now();
    if (btf_dataset_open(dataset, &dopts, &ds, &err) != 0)
        return cli_lib_error(c, &err);
    ao.progress = cli_progress_fn(c);
    ao.fit.car.warn = c->quiet ? NULL : cli_warning;
    ao.fit.car.warn_user = c;
    ao.photostereo.progress = cli_progress_fn(c);
    ao.photostereo.threads = ao.segment.features.threads;
    btf_analyse_report report;
    memset(&report, 0, sizeof report);
    ao.report = &report;
    btf_model m;
    int rc = btf_analyse(ds, &ao, &m, &err);
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    double raw = (double)in->n_pairs * in->width * in->height * 3.0;
    btf_dataset_close(ds);
    if (rc)
        return cli_lib_error(c, &err);
    cli_progress_done();
    rc = btf_model_write(out, &m, &err);
    unsigned char *bytes = NULL;
    size_t size = 0;
    if (rc == 0)
        rc = btf_model_encode(&m, &bytes, &size, &err);
    free(bytes);
    if (rc == 0 && !c->quiet) {
        printf("segmentation: %s\n", report.segment_reason);
        printf("structure: %s\n", report.structure_reason);
        printf("model         %s: %zu bytes, %d subspace%s, range tile %dx%d\n", out, size,
               m.n_subspaces, m.n_subspaces == 1 ? "" : "s", m.range_width, m.range_height);
        printf("compression   1 : %.0f against the raw 8-bit images (%.0f bytes)\n",
               raw / (double)size, raw);
        printf("time          %.1f s\n", cli_now() - t0);
        for (int k = 0; k < m.n_subspaces; k++)
            cli_print_subspace(&m.subspaces[k], k);
    }
    btf_model_free(&m);
    return rc ? cli_lib_error(c, &err) : 0;
}

/* "N" (N x N) or "WxH", each side 1..hi, into ((int *)dest)[0..1]. */
static int parse_sides(const char *v, int *wh, long hi, char *why, size_t n)
{
    long a, b;
    const char *x = strchr(v, 'x');
    char buf[64];
    int ok;
    if (!x) {
        ok = cli_parse_int(v, 1, hi, &a) == 0;
        b = a;
    } else {
        ok = (size_t)(x - v) < sizeof buf;
        if (ok) {
            memcpy(buf, v, (size_t)(x - v));
            buf[x - v] = '\0';
            ok = !cli_parse_int(buf, 1, hi, &a) && !cli_parse_int(x + 1, 1, hi, &b);
        }
    }
    if (!ok) {
        snprintf(why, n, "N or WxH, each side 1..%ld", hi);
        return -1;
    }
    wh[0] = (int)a, wh[1] = (int)b;
    return 0;
}
static int parse_sample(const char *v, void *dest, char *why, size_t n)
{
    return parse_sides(v, dest, 65536, why, n);
}
static int parse_surface(const char *v, void *dest, char *why, size_t n)
{
    return parse_sides(v, dest, BTF_RF_MAX_SURFACE_SIDE, why, n);
}

/* The sampled fit's own lines (paper section 6, docs/rf.md). */
static void print_sample(const btf_rf_model *m, const btf_rf_fit_info *info,
                         const btf_rf_sample_opts *so, const btf_dataset_info *in)
{
    printf("sample        %dx%d texels at (%d, %d) of the %dx%d images, chosen and the "
           "representative image made in %.1f s\n", m->width, m->height, m->sample_x,
           m->sample_y, in->width, in->height, info->sample_s);
    printf("map           %dx%d surface texels by image quilting (block %d, overlap %d, seed "
           "%llu) in %.2f s\n", m->surface_width, m->surface_height, info->quilt_block,
           info->quilt_overlap, (unsigned long long)so->seed, info->quilt_s);
    if (m->fit != BTF_RF_LAFORTUNE)
        printf("sample error  mean |Y data - Y model| %.5f on the sample's own texels\n",
               info->sample_mean_abs_error);
}

/* --family rf: the per-view reflectance fields of Meseth, Müller & Klein
 * 2003 (src/rf/, docs/rf.md) into a reflectance-field model file; with a
 * sample (so->width > 0), the memory reduction of its section 6. */
static int analyse_rf(cli_ctx *c, const char *dataset, const char *out, btf_rf_opts ro,
                      const btf_rf_sample_opts *so, uint64_t max_pixels)
{
    btf_error err = {0};
    btf_dataset_opts dopts = {.progress = cli_progress_fn(c), .max_pixels = max_pixels};
    btf_dataset *ds;
    double t0 = cli_now();
    if (btf_dataset_open(dataset, &dopts, &ds, &err) != 0)
        return cli_lib_error(c, &err);
    btf_rf_fit_info info;
    ro.info = &info;
    ro.progress = cli_progress_fn(c);
    btf_rf_model m;
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    if (so->width > in->width || so->height > in->height) {
        int w = in->width, h = in->height;
        btf_dataset_close(ds);
        return cli_usage_error(c, "--sample %dx%d is larger than the dataset's %dx%d images",
                               so->width, so->height, w, h);
    }
    int rc = so->width ? btf_rf_fit_sampled(ds, &ro, so, &m, &err) : btf_rf_fit(ds, &ro, &m, &err);
    double raw = (double)in->n_pairs * in->width * in->height * 3.0;
    btf_dataset_info shown = *in;
    btf_dataset_close(ds);
    if (rc)
        return cli_lib_error(c, &err);
    cli_progress_done();
    unsigned char *bytes = NULL;
    size_t size = 0;
    rc = btf_rf_encode(&m, &bytes, &size, &err);
    if (rc == 0)
        rc = btf_write_file_atomic(out, bytes, size, &err);
    free(bytes);
    btf_rf_bytes b = {0};
    if (rc == 0 && m.map)
        rc = btf_rf_model_bytes(&m, &b, &err);
    if (rc == 0 && !c->quiet) {
        double texels = (double)m.width * m.height;
        printf("fit           %s", btf_rf_fit_name(m.fit));
        if (m.fit != BTF_RF_PTM)
            printf(", %d lobe%s, %lld Levenberg-Marquardt solves, %.1f steps each", m.lobes,
                   m.lobes == 1 ? "" : "s", info.lm_runs,
                   info.lm_runs ? (double)info.lm_iterations / info.lm_runs : 0.0);
        printf("\n");
        if (m.map)
            print_sample(&m, &info, so, &shown);
        printf("error         mean |Y data - Y model| %.5f (mean luminance %.5f, %.1f %%)%s\n",
               info.mean_abs_error, info.mean_luminance,
               info.mean_luminance > 0 ? 100.0 * info.mean_abs_error / info.mean_luminance : 0.0,
               m.map ? " over every image, the surface through the map" : "");
        if (m.map)
            printf("memory        %llu bytes of coefficients + %llu bytes of coordinate map = "
                   "%llu (the file: %llu, of which the map %llu)\n",
                   (unsigned long long)b.coefficients, (unsigned long long)b.map,
                   (unsigned long long)(b.coefficients + b.map), (unsigned long long)b.file,
                   (unsigned long long)b.file_map);
        printf("model         %s: %zu bytes, %.1f bytes per %stexel (%d field%s x %d slots x "
               "2 bytes before deflate)\n", out, size, size / texels, m.map ? "sample " : "",
               m.fields, m.fields == 1 ? "" : "s", m.slots);
        printf("compression   1 : %.1f against the raw 8-bit images (%.0f bytes)\n",
               raw / (double)size, raw);
        printf("time          %.1f s (reading %.1f s, fitting %.1f s", cli_now() - t0,
               info.read_s, info.fit_s);
        if (m.map)
            printf(", sample and map %.1f s, error pass %.1f s", info.sample_s + info.quilt_s,
                   info.error_s);
        printf(")\n");
    }
    btf_rf_model_free(&m);
    return rc ? cli_lib_error(c, &err) : 0;
}

static int seen(const cli_opt *opts, const char *name)
{
    for (; opts->name; opts++)
        if (!strcmp(opts->name, name))
            return opts->seen;
    return 0;
}

/* The preset's settings, except those the command line gives itself. */
static void apply_preset(const char *name, const cli_opt *opts, btf_analyse_opts *ao)
{
    btf_analyse_opts p = *ao;
    btf_error err = {0};
    if (btf_analyse_preset(name, &p, &err) != 0)
        return; /* the option table only takes the preset names */
    if (!seen(opts, "--subspaces"))
        ao->segment.subspaces = p.segment.subspaces;
    if (!seen(opts, "--levels"))
        ao->fit.levels = p.fit.levels;
    if (!seen(opts, "--neighbourhood") && !seen(opts, "--neighborhood")) {
        ao->fit.car.n_fixed = p.fit.car.n_fixed;
        memcpy(ao->fit.car.fixed, p.fit.car.fixed, sizeof p.fit.car.fixed);
    }
}

int cmd_analyse(int argc, char **argv)
{
    cli_ctx c = {"analyse", 0};
    static const char *const stages[] = {"segment", NULL};
    const char *out = NULL;
    int stage = -1;
    btf_analyse_opts ao = btf_analyse_defaults();
    ao.segment.kmeans.seed = 1; /* the command's seed; the library's default is 0 */
    ao.photostereo.read.max_pixels = BTF_DEFAULT_MAX_PIXELS;
    btf_segment_opts *so = &ao.segment;
    int preset = -1, family = 0;
    static const char *const families[] = {"car", "rf", NULL};
    static const char *const fits[] = {"ptm", "lobes", "lafortune", NULL};
    btf_rf_opts ro = btf_rf_defaults();
    btf_rf_sample_opts sample_opts = btf_rf_sample_defaults();
    int sample[2] = {0, 0}, surface[2] = {0, 0};
    cli_opt opts[] = {
        {.name = "--output", .short_name = "-o", .kind = CLI_STRING, .dest = &out,
         .meta = "OUT", .help = "the model file to write (a folder with --stage segment)",
         .required = 1},
        {.name = "--family", .kind = CLI_CHOICE, .dest = &family, .meta = "car|rf",
         .help = "car: the probabilistic CAR model (paper section II); rf: per-view\n"
                 "reflectance fields fitted per texel (Meseth et al. 2003, docs/rf.md),\n"
                 "the accuracy end of the trade, megabytes instead of kilobytes",
         .choices = families},
        {.name = "--fit", .kind = CLI_CHOICE, .dest = &ro.fit, .meta = "ptm|lobes|lafortune",
         .help = "--family rf: ptm, a biquadratic polynomial per view and texel; lobes,\n"
                 "K non-linear lobes per view and texel (Levenberg-Marquardt); lafortune,\n"
                 "one Lafortune model (K lobes) per texel over all views, for contrast",
         .choices = fits, .tag = TAG_RF},
        {.name = "--lobes", .kind = CLI_INT, .dest = &ro.lobes, .meta = "K",
         .help = "--family rf: lobes of the lobes and lafortune fits", .lo = 1,
         .hi = BTF_RF_MAX_LOBES, .tag = TAG_RF},
        {.name = "--iterations", .kind = CLI_INT, .dest = &ro.iterations, .meta = "N",
         .help = "--family rf: Levenberg-Marquardt steps per texel at most", .lo = 1,
         .hi = 10000, .tag = TAG_RF},
        {.name = "--sample", .kind = CLI_CUSTOM, .dest = sample, .meta = "N|WxH",
         .help = "--family rf: fit only an N x N (W x H) sample of the images, the window\n"
                 "most like the whole in statistics, and store a map of texture coordinates\n"
                 "into it from an image quilting of the sample (paper section 6, docs/rf.md)",
         .parse = parse_sample, .tag = TAG_RF},
        {.name = "--surface", .kind = CLI_CUSTOM, .dest = surface, .meta = "N|WxH",
         .help = "--family rf --sample: the texels the coordinate map covers (default:\n"
                 "the dataset's size)",
         .parse = parse_surface, .tag = TAG_RF},
        {.name = "--preset", .kind = CLI_CHOICE, .dest = &preset,
         .meta = "fast|balanced|accurate",
         .help = "a measured point of the speed/accuracy trade: fast (K 2, 1 level,\n"
                 "4 neighbours), balanced (K 4, 1 level, 4 neighbours) or accurate\n"
                 "(K 8, levels and neighbourhood auto) sets --subspaces, --levels and\n"
                 "--neighbourhood (each given explicitly wins; docs/report.md, \"Presets\")",
         .choices = btf_analyse_preset_names()},
        {.name = "--stage", .kind = CLI_CHOICE, .dest = &stage, .meta = "STAGE",
         .help = "stop after this stage", .choices = stages},
        {.name = "--subspaces", .kind = CLI_INT, .dest = &so->subspaces, .meta = "K|auto",
         .help = "number of subspace images; auto takes the smallest K whose k-means\n"
                 "distortion is at most 10% of the K = 1 distortion, then splits on\n"
                 "while one more removes 12% of what is left (up to twice that K, at\n"
                 "most 20; docs/segmentation.md)",
         .lo = 1, .hi = 255, .word = "auto", .word_value = 0},
        {.name = "--bins", .kind = CLI_INT, .dest = &so->features.bins, .meta = "B",
         .help = "histogram bins per Lab channel", .lo = 2, .hi = 4096},
        {.name = "--seed", .kind = CLI_U64, .dest = &so->kmeans.seed, .meta = "S",
         .help = "k-means seed (--family rf --sample: the quilting's); same seed, same\n"
                 "result"},
        {.name = "--restarts", .kind = CLI_INT, .dest = &so->kmeans.restarts, .meta = "R",
         .help = "k-means restarts, the best kept", .lo = 1, .hi = 1000},
        {.name = "--threads", .kind = CLI_INT, .dest = &so->features.threads, .meta = "T",
         .help = "threads decoding images and solving photometric stereo", .lo = 1,
         .hi = 64, .zero_means = "all CPUs"},
        CLI_MODEL_OPTIONS(&ao.fit, TAG_LATER),
        {.name = "--no-range", .kind = CLI_FLAG, .dest = &ao.no_range,
         .help = "leave the range map out of the model", .tag = TAG_LATER},
        {.name = "--range-size", .kind = CLI_INT, .dest = &ao.range_size, .meta = "N",
         .help = "longer side of the range map kept in the model; 0: the image's\n"
                 "own (texel 1, with the structure layer); a smaller N keeps a\n"
                 "small periodic tile and no structure layer (docs/model.md)",
         .lo = 0, .hi = 4096, .zero_means = "the image's size", .tag = TAG_LATER},
        {.name = "--saturation", .kind = CLI_DOUBLE, .dest = &ao.photostereo.saturation,
         .meta = "S",
         .help = "photometric stereo leaves out samples with a raw value >= S x full\n"
                 "scale as clipped; full scale is 1 (8/16-bit files), or the images'\n"
                 "peak for data beyond 1 (HDR, scaled linear EXR); 0: no such rule\n"
                 "(docs/photostereo.md)",
         .lo = 0.0, .hi = 1.0, .tag = TAG_LATER},
        {.name = "--no-structure", .kind = CLI_FLAG, .dest = &ao.no_structure,
         .help = "no structure layer: the CAR fields model the whole exemplar\n"
                 "(the relief and albedo are not divided out; format 1.3)",
         .tag = TAG_LATER},
        {.name = "--no-shadows", .kind = CLI_FLAG, .dest = &ao.no_shadows,
         .help = "the structure layer's shading without the relief's cast shadows\n"
                 "(nor the renderer's view march; as format 1.4)",
         .tag = TAG_LATER},
        {.name = "--no-gains", .kind = CLI_FLAG, .dest = &ao.no_gains,
         .help = "no pair gains: every pair of a subspace shares its image's mean\n"
                 "colour (as format 1.4)",
         .tag = TAG_LATER},
        {.name = "--no-cells", .kind = CLI_FLAG, .dest = &ao.no_cells,
         .help = "no periodic cells: where the structure repeats on a lattice (a\n"
                 "weave), the CAR fields model the whole remainder (as format 1.6)",
         .tag = TAG_LATER},
        CLI_MAX_PIXELS_OPTION(&ao.photostereo.read.max_pixels),
        {0}};
    cli_spec spec = {.cmd = "analyse", .args = "DATASET",
                     .alt_usage = "       btfcar analyse DATASET -o OUTDIR --stage segment "
                                  "[options]",
                     .about = ABOUT, .min_args = 1, .max_args = 1, .opts = opts};
    const char *dataset;
    int nargs, prc = cli_parse(&c, &spec, argc, argv, &dataset, &nargs);
    if (prc >= 0)
        return prc;
    if (family == 1) {
        for (int i = 0; CAR_ONLY[i]; i++)
            if (seen(opts, CAR_ONLY[i]))
                return cli_usage_error(&c, "%s is not used by --family rf", CAR_ONLY[i]);
        if (!sample[0] && (seen(opts, "--surface") || seen(opts, "--seed")))
            return cli_usage_error(&c, "%s goes with --sample", seen(opts, "--surface")
                                                                    ? "--surface" : "--seed");
        if (cli_check_output(&c, out, BTF_OUTPUT_FILE))
            return 1;
        ro.threads = so->features.threads;
        btf_rf_sample_opts *rs = &sample_opts;
        rs->width = sample[0], rs->height = sample[1];
        rs->surface_width = surface[0], rs->surface_height = surface[1];
        rs->seed = so->kmeans.seed;
        return analyse_rf(&c, dataset, out, ro, rs, ao.photostereo.read.max_pixels);
    }
    if (cli_first_seen(&spec, TAG_RF))
        return cli_usage_error(&c, "%s goes with --family rf", cli_first_seen(&spec, TAG_RF));
    if (preset >= 0)
        apply_preset(btf_analyse_preset_names()[preset], opts, &ao);
    if (ao.no_range && seen(opts, "--saturation"))
        return cli_usage_error(&c, "--saturation is not used with --no-range");
    if (ao.photostereo.saturation == 0.0)
        ao.photostereo.saturation = -1.0; /* the library's "no such rule" */
    if (cli_check_output(&c, out, stage < 0 ? BTF_OUTPUT_FILE : BTF_OUTPUT_FOLDER))
        return 1;
    if (stage < 0)
        return analyse_all(&c, dataset, out, ao);
    /* Ignoring a model option silently would let a user believe it acted. */
    const char *later = cli_first_seen(&spec, TAG_LATER);
    if (later)
        return cli_usage_error(&c, "%s is not used by --stage segment", later);

    btf_error err = {0};
    btf_dataset_opts dopts = {.progress = cli_progress_fn(&c),
                              .max_pixels = ao.photostereo.read.max_pixels};
    btf_dataset *ds;
    double t0 = cli_now();
    if (btf_dataset_open(dataset, &dopts, &ds, &err) != 0)
        return cli_lib_error(&c, &err);
    so->features.progress = cli_progress_fn(&c);
    btf_segmentation seg;
    double t1 = cli_now();
    if (btf_segment(ds, so, &seg, &err) != 0) {
        btf_dataset_close(ds);
        return cli_lib_error(&c, &err);
    }
    double t2 = cli_now();
    cli_progress_done();
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    char path[4096];
    btf_output_dir *od = NULL; /* the set goes into place as a whole */
    int rc = btf_output_dir_begin(out, &od, &err);
    const char *dir = btf_output_dir_path(od);
    if (rc == 0)
        snprintf(path, sizeof path, "%s/index.png", dir);
    if (rc == 0)
        rc = btf_segmentation_write_png(&seg, 0, path, &err);
    if (rc == 0)
        rc = write_tables(&seg, in, dir, &err);
    if (rc == 0)
        rc = write_subspace_images(&seg, ds, dir, &err);
    if (rc)
        btf_output_dir_fail(od, &err);
    else
        rc = btf_output_dir_commit(od, &err);
    if (rc) {
        btf_segmentation_free(&seg);
        btf_dataset_close(ds);
        return cli_lib_error(&c, &err);
    }
    if (!c.quiet) {
        int n = in->n_pairs;
        printf("segmentation: %s\n", seg.reason);
        printf("images        %d (%d views x %d lights), %.2f ms per image, %.1f s in all\n", n,
               in->n_views, in->n_lights, 1e3 * (t2 - t1) / n, t2 - t0);
        for (int k = 0; k < seg.k; k++) {
            int v = seg.rep_view[k], l = seg.rep_light[k];
            printf("subspace %2d   %4d images, represented by view (%g, %g) light (%g, %g)\n", k,
                   seg.members[k], in->views->dirs[v].theta, in->views->dirs[v].phi,
                   in->lights->dirs[l].theta, in->lights->dirs[l].phi);
        }
        printf("written       %s/{index.png,index.tsv,subspaces.tsv,subspace_NN.exr,.png}\n", out);
    }
    btf_segmentation_free(&seg);
    btf_dataset_close(ds);
    return 0;
}
