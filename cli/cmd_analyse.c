/* cmd_analyse.c — btfcar analyse: the analysis stages on a dataset. */
#include "cli.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>


static void help(void)
{
    printf("usage: btfcar analyse DATASET -o MODEL.btfcar [--subspaces K|auto] [--levels L|auto]\n"
           "                      [--neighbourhood SPEC|auto] [--seed S] [--no-range]\n"
           "                      [--range-size N] [--bins B] [--restarts R] [--threads T]\n"
           "       btfcar analyse DATASET -o OUTDIR --stage segment [options]\n\n"
           "Analyses a BTF dataset (paper section II) into one model file:\n"
           "  1. segment  k-means on CIE Lab cumulative histograms of the (view, light)\n"
           "              images gives K subspace images and the index table;\n"
           "  2. range    robust photometric stereo on the view closest to the normal\n"
           "              gives the range map, kept as a small tile (--range-size, 64);\n"
           "  3. model    each subspace image: spectral PCA, Gaussian-Laplacian pyramid,\n"
           "              one 2D CAR model per band and level (docs/model.md).\n"
           "With --stage segment it stops after stage 1 and writes to the folder OUT:\n"
           "index.png (x = view, y = light, one colour per subspace), index.tsv,\n"
           "subspaces.tsv, and each subspace image as subspace_NN.exr + .png preview;\n"
           "the options of the later stages (--levels, --neighbourhood, --max-neighbours,\n"
           "--no-range, --range-size) are then a usage error.\n\n"
           "  --stage segment    stop after the segmentation\n"
           "  --levels L|auto    pyramid levels (auto: from size and correlation length, <= 3)\n"
           "  --neighbourhood SPEC|auto  causal offsets row:col,...; auto: Bayesian choice\n"
           "  --max-neighbours N   auto: the largest candidate considered, 1..14 (default 14;\n"
           "                       the paper's models have fewer than 4)\n"
           "  --no-range         leave the range map out of the model\n"
           "  --range-size N     longer side of the range tile kept in the model (default\n"
           "                     64, at most the image's); the shorter side follows the\n"
           "                     image's aspect ratio at the same scale\n"
           "  --subspaces K|auto number of subspace images, 1..255; auto (default) takes\n"
           "                     the smallest K whose k-means distortion is at most 10%% of\n"
           "                     the K = 1 distortion, at most 20 (docs/segmentation.md)\n"
           "  --bins B           histogram bins per Lab channel (default 32)\n"
           "  --seed S           k-means seed (default 1); same seed, same result\n"
           "  --restarts R       k-means restarts, the best kept (default 5)\n"
           "  --threads T        threads decoding images and solving photometric stereo\n"
           "                     (default: all CPUs)\n"
           "  --quiet            no progress bar, no report\n");
}

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

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

static int write_index_tsv(const btf_segmentation *s, const btf_dataset_info *in,
                           const char *path, btf_error *err)
{
    char *text = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&text, &len);
    if (!f)
        return cli_set_error(err, BTF_E_NOMEM, "%s: out of memory formatting it", path);
    fprintf(f, "view\tlight\ttheta_v\tphi_v\ttheta_l\tphi_l\tsubspace\n");
    for (int v = 0; v < s->n_views; v++)
        for (int l = 0; l < s->n_lights; l++)
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
    FILE *f = open_memstream(&text, &len);
    if (!f)
        return cli_set_error(err, BTF_E_NOMEM, "%s: out of memory formatting it", path);
    fprintf(f, "subspace\tmembers\tview\tlight\ttheta_v\tphi_v\ttheta_l\tphi_l\timage\n");
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
        rc = btf_image_write_exr(path, &img, 0, err);
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
static int analyse_all(cli_ctx *c, const char *dataset, const char *out, const btf_segment_opts *so,
                       const btf_fit_opts *fo, int no_range, int range_size)
{
    btf_error err = {0};
    btf_dataset_opts dopts = {.progress = cli_progress_fn(c)};
    btf_dataset *ds;
    double t0 = now();
    if (btf_dataset_open(dataset, &dopts, &ds, &err) != 0)
        return cli_lib_error(c, &err);
    btf_analyse_opts ao = {.segment = *so, .fit = *fo, .no_range = no_range,
                           .range_size = range_size, .progress = cli_progress_fn(c)};
    ao.fit.car.warn = c->quiet ? NULL : cli_warning;
    ao.fit.car.warn_user = c;
    ao.photostereo.progress = cli_progress_fn(c);
    ao.photostereo.threads = so->features.threads;
    btf_analyse_report report = {{0}};
    ao.report = &report;
    btf_model m;
    int rc = btf_analyse(ds, &ao, &m, &err);
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    double raw = (double)in->n_views * in->n_lights * in->width * in->height * 3.0;
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
        printf("model         %s: %zu bytes, %d subspace%s, range tile %dx%d\n", out, size,
               m.n_subspaces, m.n_subspaces == 1 ? "" : "s", m.range_width, m.range_height);
        printf("compression   1 : %.0f against the raw 8-bit images (%.0f bytes)\n",
               raw / (double)size, raw);
        printf("time          %.1f s\n", now() - t0);
        for (int k = 0; k < m.n_subspaces; k++)
            cli_print_subspace(&m.subspaces[k], k);
    }
    btf_model_free(&m);
    return rc ? cli_lib_error(c, &err) : 0;
}

int cmd_analyse(int argc, char **argv)
{
    cli_ctx c = {"analyse", 0};
    const char *dataset = NULL, *out = NULL, *stage = NULL;
    btf_segment_opts so = {.kmeans.seed = 1};
    btf_fit_opts fo = {0};
    int no_range = 0, range_size = 0;
    const char *later = NULL; /* the first option only the later stages use */
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        long n;
        int rc;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            help();
            return 0;
        } else if (!strcmp(a, "--quiet") || !strcmp(a, "-q")) {
            c.quiet = 1;
        } else if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
            if (!v)
                return cli_usage_error(&c, "%s needs a path", a);
            out = v, i++;
        } else if (!strcmp(a, "--stage")) {
            if (!v)
                return cli_usage_error(&c, "--stage needs a name");
            stage = v, i++;
        } else if (!strcmp(a, "--subspaces")) {
            if (!v)
                return cli_usage_error(&c, "--subspaces needs K or auto");
            if (!strcmp(v, "auto"))
                so.subspaces = 0;
            else if (cli_parse_int(v, 1, 255, &n))
                return cli_usage_error(&c, "--subspaces needs a whole number 1..255 or auto");
            else
                so.subspaces = (int)n;
            i++;
        } else if (!strcmp(a, "--bins")) {
            if (!v || cli_parse_int(v, 2, 4096, &n))
                return cli_usage_error(&c, "--bins needs a whole number 2..4096");
            so.features.bins = (int)n, i++;
        } else if (!strcmp(a, "--seed")) {
            if (!v || cli_parse_u64(v, &so.kmeans.seed))
                return cli_usage_error(&c, "--seed needs a non-negative whole number");
            i++;
        } else if (!strcmp(a, "--restarts")) {
            if (!v || cli_parse_int(v, 1, 1000, &n))
                return cli_usage_error(&c, "--restarts needs a whole number 1..1000");
            so.kmeans.restarts = (int)n, i++;
        } else if (!strcmp(a, "--no-range")) {
            no_range = 1;
            later = later ? later : a;
        } else if (!strcmp(a, "--range-size")) {
            if (!v || cli_parse_int(v, 1, 4096, &n))
                return cli_usage_error(&c, "--range-size needs a whole number 1..4096");
            range_size = (int)n, i++;
            later = later ? later : a;
        } else if (cli_model_option(&c, argc, argv, &i, &fo, &rc)) {
            if (rc)
                return rc;
            later = later ? later : a;
        } else if (!strcmp(a, "--threads")) {
            if (!v || cli_parse_int(v, 1, 64, &n))
                return cli_usage_error(&c, "--threads needs a whole number 1..64");
            so.features.threads = (int)n, i++;
        } else if (a[0] == '-' && a[1]) {
            return cli_usage_error(&c, "unknown option '%s'", a);
        } else if (!dataset) {
            dataset = a;
        } else {
            return cli_usage_error(&c, "unexpected argument '%s'", a);
        }
    }
    if (!dataset)
        return cli_usage_error(&c, "DATASET is required");
    if (!out)
        return cli_usage_error(&c, "-o OUT is required");
    if (!stage)
        return analyse_all(&c, dataset, out, &so, &fo, no_range, range_size);
    if (strcmp(stage, "segment") != 0)
        return cli_usage_error(&c, "unknown stage '%s' (available: segment)", stage);
    /* Ignoring a model option silently would let a user believe it acted. */
    if (later)
        return cli_usage_error(&c, "%s is not used by --stage segment", later);

    btf_error err = {0};
    btf_dataset_opts dopts = {.progress = cli_progress_fn(&c)};
    btf_dataset *ds;
    double t0 = now();
    if (btf_dataset_open(dataset, &dopts, &ds, &err) != 0)
        return cli_lib_error(&c, &err);
    so.features.progress = cli_progress_fn(&c);
    btf_segmentation seg;
    double t1 = now();
    if (btf_segment(ds, &so, &seg, &err) != 0) {
        btf_dataset_close(ds);
        return cli_lib_error(&c, &err);
    }
    double t2 = now();
    cli_progress_done();
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    char path[4096];
    snprintf(path, sizeof path, "%s/index.png", out);
    int rc = btf_mkdirs(out, &err);
    if (rc == 0)
        rc = btf_segmentation_write_png(&seg, 0, path, &err);
    if (rc == 0)
        rc = write_tables(&seg, in, out, &err);
    if (rc == 0)
        rc = write_subspace_images(&seg, ds, out, &err);
    if (rc) {
        btf_segmentation_free(&seg);
        btf_dataset_close(ds);
        return cli_lib_error(&c, &err);
    }
    if (!c.quiet) {
        int n = in->n_views * in->n_lights;
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
