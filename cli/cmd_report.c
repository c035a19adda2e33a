/* cmd_report.c — btfcar report: what a model costs and how close it comes,
 * as a page people can look at (library: src/report/,
 * docs/report.md). */
#include "cli.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static const char ABOUT[] =
    "Writes the report of MODEL, analysed from DATASET, into the folder DIR:\n"
    "index.html (self-contained: PNG and SVG files beside it, no scripts) and\n"
    "report.json (the same numbers; keys: docs/report.md). It holds:\n"
    "  compression  the model file by part against the raw BTF, the paper's\n"
    "               1 : 10^5, a per-view PCA and JPEG of the subspace images;\n"
    "  quality      each sampled (view, light) pair: the measured image beside\n"
    "               the model's flat render, the texture distances (docs/measure.md),\n"
    "               a heat map over views x lights, the worst pairs;\n"
    "  preview      the material on a sphere (--light);\n"
    "  the trade    with --sweep: the dataset analysed over a grid of settings\n"
    "               (subspaces, levels, neighbourhood), each timed, sized and\n"
    "               measured, with Pareto plots. Finished points are kept in\n"
    "               DIR/sweep/: an interrupted sweep resumes where it stopped.\n"
    "A reflectance-field MODEL (analyse --family rf, docs/rf.md) gets its own\n"
    "report: its file against the raw BTF, per pair the texture distances and\n"
    "the pixel-wise mean |dY| (measured against its flat render), the mean |dY|\n"
    "over every image, the worst pairs by |dY|, the preview; no --sweep, and\n"
    "--seed, --relief, --pca-error and --jpeg-quality do not apply.\n";

/* "auto,2,4" into a sweep grid: 0 for auto (or for the grid's own word). */
typedef struct grid_arg {
    int *n;
    int *values;
    int hi;
    int given;  /* set when the option was parsed */
    const char *word; /* the name of 0; NULL: auto */
    int lo;           /* the smallest number; 0: 1 */
} grid_arg;

static int parse_grid(const char *s, void *dest, char *why, size_t n)
{
    grid_arg *g = dest;
    const char *word = g->word ? g->word : "auto";
    int lo = g->lo ? g->lo : 1;
    snprintf(why, n, "a comma-separated list of at most %d values, each %s or %d..%d",
             BTF_SWEEP_MAX_VALUES, word, lo, g->hi);
    int count = 0;
    const char *p = s;
    while (*p) {
        const char *end = strchr(p, ',');
        size_t len = end ? (size_t)(end - p) : strlen(p);
        char item[32];
        if (len == 0 || len >= sizeof item || count == BTF_SWEEP_MAX_VALUES)
            return -1;
        memcpy(item, p, len);
        item[len] = '\0';
        long v;
        if (!strcmp(item, word))
            v = 0;
        else if (cli_parse_int(item, lo, g->hi, &v) != 0)
            return -1;
        g->values[count++] = (int)v;
        p = end ? end + 1 : p + len;
        if (end && !*p)
            return -1;
    }
    if (!count)
        return -1;
    *g->n = count;
    g->given = 1;
    return 0;
}

static void show_grid(const void *dest, char *buf, size_t n)
{
    const grid_arg *g = dest;
    size_t k = 0;
    buf[0] = '\0';
    for (int i = 0; i < *g->n && k < n; i++) {
        int w = g->values[i] ? snprintf(buf + k, n - k, "%s%d", i ? "," : "", g->values[i])
                             : snprintf(buf + k, n - k, "%s%s", i ? "," : "",
                                        g->word ? g->word : "auto");
        if (w < 0)
            break;
        k += (size_t)w;
    }
}

/* --sweep-structure on|off|on,off: the structure layers (btf_sweep_setting
 * .plain 0) and format 1.3's plain model (1). */
typedef struct plain_arg {
    int *n, *values;
} plain_arg;

static int parse_plain(const char *s, void *dest, char *why, size_t n)
{
    const plain_arg *g = dest;
    int count = 0, v[2];
    if (!strcmp(s, "on"))
        v[count++] = 0;
    else if (!strcmp(s, "off"))
        v[count++] = 1;
    else if (!strcmp(s, "on,off") || !strcmp(s, "off,on"))
        v[0] = s[1] == 'n' ? 0 : 1, v[1] = 1 - v[0], count = 2;
    else {
        snprintf(why, n, "on, off or on,off");
        return -1;
    }
    *g->n = count;
    memcpy(g->values, v, (size_t)count * sizeof *v);
    return 0;
}

static void show_plain(const void *dest, char *buf, size_t n)
{
    const plain_arg *g = dest;
    snprintf(buf, n, "%s", *g->n == 2 ? (g->values[0] ? "off,on" : "on,off")
                           : *g->n == 1 && g->values[0] ? "off" : "on");
}

/* --points I/N: this task's share of the sweep's grid. */
static int parse_points(const char *s, void *dest, char *why, size_t n)
{
    btf_sweep_opts *so = dest;
    int i, k, used = 0;
    if (sscanf(s, "%d/%d%n", &i, &k, &used) != 2 || s[used] || k < 1 || k > 100000 || i < 0 ||
        i >= k) {
        snprintf(why, n, "expected I/N with 0 <= I < N (this task's share of N), e.g. 0/4");
        return -1;
    }
    so->share_index = i, so->share_count = k;
    return 0;
}

static void show_points(const void *dest, char *buf, size_t n)
{
    const btf_sweep_opts *so = dest;
    if (so->share_count)
        snprintf(buf, n, "%d/%d", so->share_index, so->share_count);
    else
        snprintf(buf, n, "all");
}

/* --merge-from DIR, any number of times: the folders a split sweep's shares
 * wrote to. */
typedef struct merge_from {
    const char *dirs[1024];
    int n;
} merge_from;

static int parse_merge_from(const char *s, void *dest, char *why, size_t n)
{
    merge_from *m = dest;
    if (m->n >= 1024) {
        snprintf(why, n, "at most 1024 folders");
        return -1;
    }
    m->dirs[m->n++] = s;
    return 0;
}

static void show_merge_from(const void *dest, char *buf, size_t n)
{
    const merge_from *m = dest;
    snprintf(buf, n, "%d folder%s", m->n, m->n == 1 ? "" : "s");
}

static int parse_light(const char *s, void *dest, char *why, size_t n)
{
    return cli_parse_dir(s, dest, why, n);
}

static void show_light(const void *dest, char *buf, size_t n)
{
    const btf_dir *d = dest;
    snprintf(buf, n, "%g,%g", d->theta, d->phi);
}

/* --merge-from: the shares' points into OUT/sweep/ (the report's state folder). */
static int gather(cli_ctx *c, const merge_from *mf, const char *out, btf_error *err)
{
    char state[4096];
    snprintf(state, sizeof state, "%s/sweep", out);
    int copied = 0;
    if (mkdir(out, 0777) != 0 && errno != EEXIST) {
        cli_set_error(err, BTF_E_IO, "%s: cannot create the report folder: %s", out,
                      strerror(errno));
        return cli_lib_error(c, err);
    }
    if (btf_sweep_gather(mf->dirs, mf->n, state, &copied, err))
        return cli_lib_error(c, err);
    if (!c->quiet)
        printf("merge         %d point files gathered from %d folder%s into %s\n", copied,
               mf->n, mf->n == 1 ? "" : "s", state);
    return 0;
}

/* --points I/N: one share of the sweep into OUT/sweep/, nothing else. */
static int sweep_share(cli_ctx *c, const btf_dataset *ds, const char *out,
                       const btf_report_opts *ro, btf_error *err, double t0)
{
    btf_sweep s;
    int rc = btf_report_sweep_points(ds, out, ro, &s, err);
    cli_progress_done();
    if (rc)
        return cli_lib_error(c, err);
    int mine = 0;
    for (int i = 0; i < s.n_points; i++)
        mine += i % ro->sweep_opts.share_count == ro->sweep_opts.share_index;
    if (!c->quiet)
        printf("sweep share   %d/%d: %d of the %d points (%d measured now, %d already in "
               "%s/sweep/), %d of other shares still missing\n"
               "time          %.1f s\n",
               ro->sweep_opts.share_index, ro->sweep_opts.share_count, mine, s.n_points,
               s.n_points - s.resumed - s.n_missing, s.resumed - (s.n_points - mine -
               s.n_missing), out, s.n_missing, cli_now() - t0);
    btf_sweep_free(&s);
    return 0;
}

int cmd_report(int argc, char **argv)
{
    cli_ctx c = {"report", 0};
    const char *out = NULL;
    btf_report_opts ro = btf_report_defaults();
    btf_sweep_opts *so = &ro.sweep_opts;
    so->analyse.segment.kmeans.seed = 1; /* analyse's seed: the sweep's default is the command's */
    grid_arg gk = {&so->n_subspaces, so->subspaces, 255, 0, NULL, 0};
    grid_arg gl = {&so->n_levels, so->levels, BTF_MAX_LEVELS, 0, NULL, 0};
    grid_arg gn = {&so->n_neighbours, so->neighbours, BTF_CAR_MAX_NEIGHBOURS, 0, NULL, 0};
    plain_arg gp = {&so->n_plain, so->plain};
    grid_arg gr = {&so->n_range_sizes, so->range_sizes, 4096, 0, "full", 4};
    uint64_t max_pixels = BTF_DEFAULT_MAX_PIXELS;
    static merge_from mf; /* 8 KB of pointers: not on the stack */
    cli_opt opts[] = {
        {.name = "--output", .short_name = "-o", .kind = CLI_STRING, .dest = &out,
         .meta = "DIR", .help = "the report's folder (index.html, report.json, pictures)",
         .required = 1},
        {.name = "--all", .kind = CLI_FLAG, .dest = &ro.quality.all,
         .help = "measure every (view, light) pair, not a spread (pictures stay those\n"
                 "of the spread and of the worst pairs)"},
        {.name = "--views", .kind = CLI_INT, .dest = &ro.quality.views, .meta = "N",
         .help = "the spread: this many views, strided ring by ring over the hemisphere",
         .lo = 1, .hi = 100000},
        {.name = "--lights", .kind = CLI_INT, .dest = &ro.quality.lights, .meta = "N",
         .help = "the spread: this many lights", .lo = 1, .hi = 100000},
        {.name = "--worst", .kind = CLI_INT, .dest = &ro.worst, .meta = "N",
         .help = "the worst pairs shown with pictures", .lo = 1, .hi = 100},
        {.name = "--light", .kind = CLI_CUSTOM, .dest = &ro.sphere_light, .meta = "THETA,PHI",
         .help = "the preview sphere's light, in the camera's frame (theta 0: from\n"
                 "the camera)", .parse = parse_light, .show = show_light},
        {.name = "--preview-size", .kind = CLI_INT, .dest = &ro.sphere_size, .meta = "N",
         .help = "the preview's side in pixels", .lo = 16, .hi = 4096},
        {.name = "--seed", .kind = CLI_U64, .dest = &ro.quality.seed, .meta = "S",
         .help = "synthesis seed of the renders"},
        {.name = "--relief", .kind = CLI_DOUBLE, .dest = &ro.quality.relief, .meta = "R",
         .help = "range map height scale of the renders (0: flat)", .lo = 0, .hi = 1e6},
        {.name = "--pca-error", .kind = CLI_DOUBLE, .dest = &ro.pca.max_rms, .meta = "E",
         .help = "the per-view PCA's RMS error target, in 8-bit sRGB levels", .lo = 0.01,
         .hi = 255},
        {.name = "--jpeg-quality", .kind = CLI_INT, .dest = &ro.jpeg_quality, .meta = "Q",
         .help = "the JPEG contrast's quality", .lo = 1, .hi = 100},
        {.name = "--sweep", .kind = CLI_FLAG, .dest = &ro.sweep,
         .help = "measure the speed/accuracy trade over a grid of settings"},
        {.name = "--sweep-subspaces", .kind = CLI_CUSTOM, .dest = &gk, .meta = "LIST",
         .help = "--sweep: the values of K", .parse = parse_grid, .show = show_grid},
        {.name = "--sweep-levels", .kind = CLI_CUSTOM, .dest = &gl, .meta = "LIST",
         .help = "--sweep: the pyramid levels", .parse = parse_grid, .show = show_grid},
        {.name = "--sweep-neighbours", .kind = CLI_CUSTOM, .dest = &gn, .meta = "LIST",
         .help = "--sweep: fixed neighbourhoods of the first N candidate offsets\n"
                 "(auto: the Bayesian choice)", .parse = parse_grid, .show = show_grid},
        {.name = "--sweep-structure", .kind = CLI_CUSTOM, .dest = &gp, .meta = "on|off|on,off",
         .help = "--sweep: with the structure layers and pair gains (on, the default),\n"
                 "without them (off: a 64-texel range tile, format 1.3's model), or both",
         .parse = parse_plain, .show = show_plain},
        {.name = "--sweep-range-size", .kind = CLI_CUSTOM, .dest = &gr, .meta = "LIST",
         .help = "--sweep, with the layers: the range map's longer side, full (the\n"
                 "analysed resolution, with the structure layer; the default) or N (a\n"
                 "small periodic tile, no structure layer; analyse --range-size N)",
         .parse = parse_grid, .show = show_grid},
        {.name = "--points", .kind = CLI_CUSTOM, .dest = so, .meta = "I/N",
         .help = "--sweep beyond one machine: measure only share I of N of the grid\n"
                 "(point i when i mod N = I) into DIR/sweep/ and write nothing else;\n"
                 "a Slurm array task runs one share (docs/cluster.md)",
         .parse = parse_points, .show = show_points},
        {.name = "--merge", .kind = CLI_FLAG, .dest = &so->resume_only,
         .help = "--sweep: build the report from the points in DIR/sweep/ only,\n"
                 "measuring none; missing points are an error naming them"},
        {.name = "--merge-from", .kind = CLI_CUSTOM, .dest = &mf, .meta = "DIR",
         .help = "--merge, the points first copied from DIR/sweep/ (a share's report\n"
                 "folder) into DIR/sweep/ of -o; give it once per folder",
         .parse = parse_merge_from, .show = show_merge_from},
        {.name = "--sweep-seeds", .kind = CLI_INT, .dest = &so->seeds, .meta = "N",
         .help = "--sweep: each point's quality is the mean over N synthesis seeds\n"
                 "(--seed, --seed + 1, ...)", .lo = 1, .hi = BTF_SWEEP_MAX_SEEDS,
         .zero_means = "3"},
        {.name = "--threads", .kind = CLI_INT, .dest = &ro.threads, .meta = "T",
         .help = "threads (the sweep: settings run in parallel)", .lo = 1, .hi = 64,
         .zero_means = "all CPUs"},
        CLI_MAX_PIXELS_OPTION(&max_pixels),
        {0}};
    cli_spec spec = {.cmd = "report", .args = "DATASET MODEL", .about = ABOUT, .min_args = 2,
                     .max_args = 2, .opts = opts};
    const char *args[2];
    int nargs, prc = cli_parse(&c, &spec, argc, argv, args, &nargs);
    if (prc >= 0)
        return prc;
    if (cli_check_output(&c, out, BTF_OUTPUT_FOLDER))
        return 1;
    so->resume_only |= mf.n > 0;
    if ((so->share_count || so->resume_only) && !ro.sweep)
        return cli_usage_error(&c, "--points and --merge go with --sweep");
    if (so->share_count && so->resume_only)
        return cli_usage_error(&c, "--points measures a share, --merge measures nothing: "
                               "one or the other");
    btf_error err = {0};
    double t0 = cli_now();
    btf_material *m;
    if (btf_material_read(args[1], &m, &err) != 0)
        return cli_lib_error(&c, &err);
    btf_material_info mi;
    btf_material_get_info(m, &mi);
    /* the sweep varies the analysis of a model that synthesises its textures */
    if (!(mi.caps & BTF_MATERIAL_SYNTHESISES) &&
        (ro.sweep || gk.given || gl.given || gn.given || gr.given || so->n_plain)) {
        btf_material_free(m);
        return cli_usage_error(&c, "%s is a reflectance-field model: --sweep varies the CAR "
                               "analysis and does not apply", args[1]);
    }
    btf_dataset_opts dopts = {.progress = cli_progress_fn(&c), .max_pixels = max_pixels};
    btf_dataset *ds;
    if (btf_dataset_open(args[0], &dopts, &ds, &err) != 0) {
        btf_material_free(m);
        return cli_lib_error(&c, &err);
    }
    ro.dataset_name = args[0];
    ro.model_name = args[1];
    ro.progress = cli_progress_fn(&c);
    ro.progress_user = NULL;
    /* Only a real GPU is timed (--backend auto's rule): lavapipe runs on
     * these same cores and says nothing about a GPU. */
    btf_error gerr = {0};
    btf_gpu *gpu = ro.sweep ? cli_open_gpu("auto", -1, &gerr) : NULL;
    so->gpu = gpu;
    if (mf.n > 0 && gather(&c, &mf, out, &err)) {
        btf_gpu_close(gpu);
        btf_dataset_close(ds);
        btf_material_free(m);
        return 1;
    }
    if (so->share_count) {
        int rc = sweep_share(&c, ds, out, &ro, &err, t0);
        btf_gpu_close(gpu);
        btf_dataset_close(ds);
        btf_material_free(m);
        return rc;
    }
    btf_report_summary sum;
    int rc = btf_material_report_write(ds, m, out, &ro, &sum, &err);
    cli_progress_done();
    btf_gpu_close(gpu);
    btf_dataset_close(ds);
    btf_material_free(m);
    if (rc)
        return cli_lib_error(&c, &err);
    if (!c.quiet) {
        printf("report        %s/index.html (and report.json)\n", out);
        printf("compression   1 : %.0f (model %llu bytes, raw %llu bytes)\n", sum.ratio,
               (unsigned long long)sum.model_bytes, (unsigned long long)sum.raw_bytes);
        printf("quality       mean combined distance %.2f, worst %.2f over %d pairs\n",
               sum.mean_combined, sum.worst_combined, sum.pairs - sum.held_out);
        if (sum.held_out)
            printf("held out      mean combined distance %.2f over %d pair%s the model did "
                   "not measure\n", sum.mean_held_out, sum.held_out,
                   sum.held_out == 1 ? "" : "s");
        if (sum.mean_luminance > 0) /* a pixel-wise family's figure */
            printf("pixel-wise    mean |dY| %.5f over every image %s(%.1f %% of the mean "
                   "luminance %.4f)\n", sum.mean_abs_error,
                   sum.held_out ? "the model was fitted to " : "",
                   sum.mean_luminance > 0 ? 100.0 * sum.mean_abs_error / sum.mean_luminance
                                          : 0.0, sum.mean_luminance);
        if (ro.sweep)
            printf("sweep         %d settings (%d resumed from %s/sweep/)\n", sum.sweep_points,
                   sum.sweep_resumed, out);
        printf("time          %.1f s\n", cli_now() - t0);
    }
    return 0;
}
