/* cmd_synthesise.c — btfcar synthesise: subspace images of any size from a
 * model (Haindl & Filip 2007, section II.C, model synthesis), on the CPU
 * (src/synth/) or the GPU (gpu/), written to EXR as rows arrive. Reads the
 * environment switches the library does not (BTF_VK_*, BTF_SYNTH_WAVE,
 * BTF_NOISE_PORTABLE) and passes them as options. */
#include "cli.h"
#include "synth/each_behind.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>


/* The default EXR compression (docs/synthesis.md, "EXR output"). */
#define DEFAULT_COMPRESSION BTF_EXR_NONE

static const char ABOUT[] =
    "Generates subspace images of the model at any size, seamless and stationary\n"
    "(paper section II.C), streaming rows to OUTDIR/subspace_NN.exr (linear RGB)\n"
    "as they are produced: memory grows with the width, not the height\n"
    "(docs/synthesis.md). Colour matching, the default, reads whole images:\n"
    "up to 256 MiB each is kept whole (three at a time: one written on a\n"
    "thread while the next is colour-matched beside the synthesis of the one\n"
    "after), larger ones are synthesised twice (memory by the width).\n"
    "--tileable makes images that tile without a seam (the\n"
    "same streaming with periodic noise, on either backend). The same model and\n"
    "seed give the same pixels on every backend. Environment: BTF_VK_DEVICE=N\n"
    "names the Vulkan device when --device is not given; BTF_SYNTH_WAVE=0 and\n"
    "BTF_NOISE_PORTABLE=1 select the CPU's row-by-row field generator and\n"
    "portable noise loop (same pixels, slower);\n"
    "BTF_EXR_THREAD=0 compresses and writes on the synthesising thread (same bytes).\n"
    "--range adds the model's range map enlarged to the same size, seamless, as\n"
    "OUTDIR/range.exr (heights in analysed-image texels) and OUTDIR/normal.exr\n"
    "(unit normals, x right, y up, z out), both 32-bit float (docs/render.md);\n"
    "--subspace none with --range writes only those two.\n";

/* Where the time goes (--verbose): seconds per phase of the whole run. */
typedef struct phases {
    double read, synth, rows, close, preview, exr_open;
    btf_exr_times exr;
    int behind; /* whole images, written behind the synthesis (synth_matched) */
} phases;

typedef struct sink {
    btf_exr_writer *exr;
    btf_image *preview;
    int height;
    btf_progress_fn progress;
    int write_failed; /* the error is the output's, not the model's */
    double *rows_s; /* time spent in put_rows */
} sink;

static int put_rows_timed(void *user, int y, int nrows, const float *rows, btf_error *err);

static int put_rows(void *user, int y, int nrows, const float *rows, btf_error *err)
{
    sink *s = user;
    if (s->preview)
        memcpy(s->preview->data + (size_t)y * s->preview->width * 3, rows,
               (size_t)nrows * s->preview->width * 3 * sizeof(float));
    if (s->progress && ((y + nrows) % 256 == 0 || y + nrows == s->height))
        s->progress(NULL, (double)(y + nrows) / s->height, "synthesising");
    int rc = btf_exr_writer_put_rows(s->exr, rows, nrows, err);
    s->write_failed = rc != 0;
    return rc;
}

static int put_rows_timed(void *user, int y, int nrows, const float *rows, btf_error *err)
{
    double t0 = cli_now();
    int rc = put_rows(user, y, nrows, rows, err);
    *((sink *)user)->rows_s += cli_now() - t0;
    return rc;
}

/* "0,3,5", "all" or "none" into a 0/1 table of m->n_subspaces entries:
 * plain decimal numbers only (no sign, no spaces), each once. */
static int parse_list(const char *s, int n, unsigned char *pick)
{
    memset(pick, !strcmp(s, "all"), (size_t)n);
    if (!strcmp(s, "all") || !strcmp(s, "none"))
        return 0;
    if (!*s)
        return -1;
    for (;;) {
        char *end;
        if (*s < '0' || *s > '9')
            return -1;
        long v = strtol(s, &end, 10);
        if (v >= n || (*end != ',' && *end) || pick[v])
            return -1;
        pick[v] = 1;
        if (!*end)
            return 0;
        s = end + 1; /* after a comma a number must follow */
    }
}

/* Where and how the images go. */
typedef struct output {
    const char *dir;
    const char *model_path; /* provenance in each EXR header */
    int preview;
    btf_exr_opts exr;       /* half, compression, background, times */
    phases *ph;
} output;

/* Writes one image already in memory as EXR (+ preview). */
static int write_image(const btf_image *img, const btf_model *m, int k, uint64_t seed,
                       const output *out, btf_error *err)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/subspace_%02d.exr", out->dir, k);
    btf_exr_meta meta = btf_model_exr_meta(m, out->model_path, k, seed);
    double t0 = cli_now();
    int rc = btf_image_write_exr_opts(path, img, &out->exr, &meta, err);
    double t1 = cli_now();
    out->ph->close += t1 - t0;
    if (rc == 0 && out->preview) {
        snprintf(path, sizeof path, "%s/subspace_%02d.png", out->dir, k);
        rc = btf_image_write_png(path, img, err);
    }
    out->ph->preview += cli_now() - t1;
    return rc;
}

/* The environment's settings (docs/cli.md); the library reads none. */

/* BTF_NOISE_PORTABLE=1 (set, not empty, not "0"): the portable noise loop;
 * BTF_SYNTH_WAVE=0: CPU fields row by row. Both give the same bytes. */
static void env_cpu_switches(btf_synth_opts *o)
{
    const char *p = getenv("BTF_NOISE_PORTABLE"), *w = getenv("BTF_SYNTH_WAVE");
    o->portable_noise = p && *p && strcmp(p, "0") != 0;
    o->row_by_row = w && !strcmp(w, "0");
}

/* A library synthesis error names the model it came from (unless it does
 * already): "MODEL: message". Returns rc. */
static int name_model(int rc, const char *model, btf_error *err)
{
    if (rc && model && !strstr(err->msg, model)) {
        char msg[sizeof err->msg];
        snprintf(msg, sizeof msg, "%s: %s", model, err->msg);
        snprintf(err->msg, sizeof err->msg, "%s", msg);
    }
    return rc;
}

/* --range: the seamless range map and its normal map at the output size
 * (btf__range_map; docs/render.md), as 32-bit float EXR whatever --half
 * says, since heights and normals are data, not colours. */
static int write_range_maps(const btf_model *m, int w, int h, uint64_t seed, const output *out,
                            btf_error *err)
{
    btf_image hm, nm;
    /* the maps of the images' own seed: with a structure layer, one
     * quilting map places them both (btf_structure_maps) */
    int rc = btf_structure_maps(m, w, h, seed, &hm, &nm, NULL, err);
    if (rc)
        return name_model(rc, out->model_path, err);
    btf_exr_opts o = out->exr;
    o.half = 0;
    char path[4096];
    snprintf(path, sizeof path, "%s/range.exr", out->dir);
    rc = btf_image_write_exr_opts(path, &hm, &o, NULL, err);
    snprintf(path, sizeof path, "%s/normal.exr", out->dir);
    if (rc == 0)
        rc = btf_image_write_exr_opts(path, &nm, &o, NULL, err);
    btf_image_free(&hm);
    btf_image_free(&nm);
    return rc;
}

/* Where whole images i = 0.. (subspaces subs[i]) are written. */
typedef struct image_sink {
    const btf_model *m;
    const output *out;
    uint64_t seed;
    const int *subs;
    int write_failed; /* the error is the output's, not the model's */
} image_sink;

static int write_each(void *user, int i, btf_image *img, btf_error *err)
{
    image_sink *s = user;
    return write_image(img, s->m, s->subs[i], s->seed, s->out, err);
}

/* The GPU path: btf_gpu_synthesise_each groups the chosen subspaces by the
 * device's memory budget (the library's policy) and hands each finished
 * image here to be written. */
static int gpu_write(void *user, int i, btf_image *img, btf_error *err)
{
    int rc = write_each(user, i, img, err);
    ((image_sink *)user)->write_failed = rc != 0;
    return rc;
}

static int synth_gpu(btf_gpu *g, const btf_model *m, const unsigned char *pick,
                     const btf_synth_opts *so, const output *out, btf_error *err)
{
    int n = 0, *subs = calloc((size_t)m->n_subspaces + 1, sizeof(int));
    if (!subs)
        return cli_set_error(err, BTF_E_NOMEM, "out of memory");
    for (int k = 0; k < m->n_subspaces; k++)
        if (pick[k])
            subs[n++] = k;
    image_sink s = {m, out, so->seed, subs, 0};
    int rc = btf_gpu_synthesise_each(g, m, subs, n, so, gpu_write, &s, err);
    if (!s.write_failed) /* a write's message names its file */
        name_model(rc, out->model_path, err);
    free(subs);
    return rc;
}

/* The CPU path with colour matching (docs/synthesis.md, "Colour
 * matching"), which reads whole images anyway: btf_synthesise_each matches
 * image i - 1 on the CPU that image i's fields leave idle, and
 * btf__synthesise_each_behind writes each finished image on a thread beside
 * the next one's synthesis: three images in memory at most (one written,
 * one matched, one synthesised). The bytes are those of the streaming path. */
static int synth_matched(const cli_ctx *c, const btf_model *m, const unsigned char *pick,
                         const btf_synth_opts *so, const output *out, btf_error *err)
{
    int *subs = calloc((size_t)m->n_subspaces + 1, sizeof(int)), n = 0;
    if (!subs)
        return cli_set_error(err, BTF_E_NOMEM, "out of memory");
    for (int k = 0; k < m->n_subspaces; k++)
        if (pick[k])
            subs[n++] = k;
    output wout = *out;
    wout.exr.background = 0; /* the writer is a thread already */
    image_sink s = {m, &wout, so->seed, subs, 0};
    btf_each_behind b = {.write = write_each, .user = &s, .progress = cli_progress_fn(c)};
    double t0 = cli_now();
    int rc = btf__synthesise_each_behind(m, subs, n, so, &b, err);
    if (!b.write_failed) /* a write's message names its file */
        name_model(rc, out->model_path, err);
    out->ph->synth += cli_now() - t0 - b.wait_s;
    out->ph->rows += b.hand_s;
    out->ph->exr.wait_s += b.wait_s;
    out->ph->behind = 1;
    free(subs);
    return rc;
}

/* Whether the CPU path takes synth_matched: when the streaming synthesis
 * would hold every chosen image whole anyway (colour matching on, images
 * within 256 MiB: btf_synth_holds_whole); else it streams. */
static int matched_whole(const btf_model *m, const unsigned char *pick,
                         const btf_synth_opts *so)
{
    for (int k = 0; k < m->n_subspaces; k++)
        if (pick[k] && !btf_synth_holds_whole(m, k, so))
            return 0;
    return 1;
}

/* Opens the Vulkan device the backend asks for; NULL (auto falls back to the CPU) or
 * an error (gpu) when there is none, or when one image is larger than the
 * device's memory budget (docs/gpu.md, "Choosing a backend": the GPU would
 * hold it whole on the host, where the CPU path streams it row by row). */
static btf_gpu *open_gpu(const char *backend, int device, uint64_t image_bytes, btf_error *err)
{
    btf_gpu *g = cli_open_gpu_for(backend, device, image_bytes, err);
    if (g && !btf_gpu_auto_fits(g, image_bytes)) { /* a device named, or --backend gpu */
        cli_set_error(err, BTF_E_UNSUPPORTED, "the GPU backend holds whole images and one needs "
                      "%.2f GiB, more than the device's memory budget of %.2f GiB; --backend cpu "
                      "streams", image_bytes / 1073741824.0,
                      btf_gpu_memory_budget(g) / 1073741824.0);
        btf_gpu_close(g);
        return NULL;
    }
    return g;
}

static int synth_one(const cli_ctx *c, const btf_model *m, int k, const btf_synth_opts *so,
                     const output *out, btf_error *err)
{
    int w = so->width, h = so->height, preview = out->preview;
    char path[4096];
    snprintf(path, sizeof path, "%s/subspace_%02d.exr", out->dir, k);
    sink s = {.height = h, .progress = cli_progress_fn(c), .rows_s = &out->ph->rows};
    btf_image img = {0};
    int rc = 0;
    if (preview && (rc = btf_image_alloc(&img, w, h, 3, err)))
        return rc;
    s.preview = preview ? &img : NULL;
    btf_exr_meta meta = btf_model_exr_meta(m, out->model_path, k, so->seed);
    double t0 = cli_now();
    rc = btf_exr_writer_open_opts(path, w, h, 3, &out->exr, &meta, &s.exr, err);
    double t1 = cli_now();
    out->ph->exr_open += t1 - t0;
    if (rc == 0) {
        rc = btf_synthesise(m, k, so, put_rows_timed, &s, err);
        t0 = cli_now(), out->ph->synth += t0 - t1; /* put_rows included */
        if (!s.write_failed)
            name_model(rc, out->model_path, err);
        if (rc)
            btf_exr_writer_abort(s.exr);
        else
            rc = btf_exr_writer_close(s.exr, err);
        t1 = cli_now(), out->ph->close += t1 - t0;
    }
    if (rc == 0 && preview) {
        snprintf(path, sizeof path, "%s/subspace_%02d.png", out->dir, k);
        rc = btf_image_write_png(path, &img, err);
        out->ph->preview += cli_now() - t1;
    }
    btf_image_free(&img);
    return rc;
}

/* --verbose: the phases on stderr. Synthesis and staging rows run on this
 * thread; convert, compress and write on the writer's thread beside them
 * (waiting: this thread held up by a full queue or at close). */
static void print_phases(const phases *p, int gpu, const char *comp, int half, int bg,
                         double total)
{
    const btf_exr_times *e = &p->exr;
    double synth = p->synth - p->rows;
    if (p->behind) { /* synth_matched */
        fprintf(stderr, "phases (s): model read %.4f; synthesis, colour matching beside it "
                "%.4f; handing images to the writer %.4f; waiting for it after synthesis "
                "%.4f\n", p->read, synth, p->rows, e->wait_s);
        fprintf(stderr, "writer thread, whole images (s): EXR %.4f (convert %.4f, write %.4f); "
                "previews %.4f; %d %s files, %.1f MB\n", p->close, e->convert_s, e->write_s,
                p->preview, e->files, half ? "half" : "float", (double)e->bytes / 1e6);
        fprintf(stderr, "total %.4f s from start to exit (process start not included)\n", total);
        return;
    }
    fprintf(stderr, "phases (s): model read %.4f; %s %.4f; rows staged %.4f; waiting for the "
            "writer %.4f, at close %.4f; EXR open %.4f; previews %.4f\n", p->read,
            gpu ? "GPU synthesis (+ EXR writes)" : "synthesis", gpu ? p->close : synth,
            e->stage_s, e->wait_s, gpu ? 0 : p->close, p->exr_open, p->preview);
    fprintf(stderr, "%s (s): convert %.4f; compress (%s) %.4f; write %.4f; %d %s files, "
            "%.1f MB\n", bg ? "writer thread" : "output, on this thread", e->convert_s, comp,
            e->compress_s, e->write_s, e->files,
            half ? "half" : "float", (double)e->bytes / 1e6);
    fprintf(stderr, "total %.4f s from start to exit (process start not included)\n", total);
}

int cmd_synthesise(int argc, char **argv)
{
    cli_ctx c = {"synthesise", 0};
    static const char *const backends[] = {"cpu", "gpu", "auto", NULL};
    const char *model = NULL, *outdir = NULL, *list = "all";
    static const char *const comps[] = {"zip", "none", "rle", "zips", "piz", "pxr24",
                                        NULL}; /* btf_exr_compression's order */
    int size[2] = {0, 0}, preview = 0, half = 0, device = -1, backend_index = 2;
    int as_float = 0, comp = DEFAULT_COMPRESSION, verbose = 0, range = 0, tileable = 0;
    int match = 0, no_match = 0;
    uint64_t seed = 1;
    double t_start = cli_now();
    cli_opt opts[] = {
        {.name = "--size", .kind = CLI_SIZE, .dest = size, .meta = "WxH",
         .help = "output size in pixels", .lo = 1, .hi = 65536, .required = 1},
        {.name = "--output", .short_name = "-o", .kind = CLI_STRING, .dest = &outdir,
         .meta = "OUTDIR", .help = "the folder for subspace_NN.exr", .required = 1},
        {.name = "--subspace", .kind = CLI_STRING, .dest = &list, .meta = "LIST",
         .help = "comma-separated subspace numbers, all, or none (with --range)"},
        {.name = "--range", .kind = CLI_FLAG, .dest = &range,
         .help = "also write range.exr and normal.exr: the range map at the same\n"
                 "size, seamless, and its normals (docs/render.md)"},
        {.name = "--seed", .kind = CLI_U64, .dest = &seed, .meta = "S",
         .help = "noise seed; the same seed gives the same pixels"},
        {.name = "--backend", .kind = CLI_CHOICE, .dest = &backend_index, .meta = "cpu|gpu|auto",
         .help = "cpu: the CPU reference; gpu: Vulkan compute on any device, the CPU\n"
                 "driver lavapipe included; auto: a real GPU if present, else the CPU",
         .choices = backends},
        {.name = "--device", .kind = CLI_INT, .dest = &device, .meta = "N",
         .help = "Vulkan device index (btfcar info --devices)", .lo = 0, .hi = 255},
        {.name = "--tileable", .kind = CLI_FLAG, .dest = &tileable,
         .help = "a tileable image: right edge continues into left, bottom into top\n"
                 "(both sides multiples of 2^(levels-1); CPU or GPU, the same pixels)"},
        {.name = "--match-colours", .kind = CLI_FLAG, .dest = &match,
         .help = "require colour matching: each image gets the exemplar's CIE Lab\n"
                 "histogram, whatever the realisation (docs/synthesis.md, \"Colour\n"
                 "matching\"). The default where the model holds that histogram (format\n"
                 "1.3 on); with this flag an older model is an error"},
        {.name = "--no-match-colours", .kind = CLI_FLAG, .dest = &no_match,
         .help = "skip colour matching: faster (a pass over each image less; images\n"
                 "over 256 MiB are not synthesised twice), the model's histograms only\n"
                 "in expectation"},
        {.name = "--preview", .kind = CLI_FLAG, .dest = &preview,
         .help = "also write subspace_NN.png (8-bit sRGB; up to 8192x8192)"},
        {.name = "--half", .kind = CLI_FLAG, .dest = &half,
         .help = "write half-float EXR (the default)"},
        {.name = "--float", .kind = CLI_FLAG, .dest = &as_float,
         .help = "write 32-bit float EXR (twice the bytes; docs/synthesis.md)"},
        {.name = "--compression", .kind = CLI_CHOICE, .dest = &comp, .meta = "NAME",
         .help = "EXR compression: none, rle, zips, zip, piz (lossless); pxr24 (lossy\n"
                 "for float); measured in docs/synthesis.md",
         .choices = comps},
        {.name = "--verbose", .short_name = "-v", .kind = CLI_FLAG, .dest = &verbose,
         .help = "print where the time went, phase by phase, at the end"},
        {0}};
    cli_spec spec = {.cmd = "synthesise", .args = "MODEL", .about = ABOUT, .min_args = 1,
                     .max_args = 1, .opts = opts};
    int nargs, prc = cli_parse(&c, &spec, argc, argv, &model, &nargs);
    if (prc >= 0)
        return prc;
    const char *backend = backends[backend_index];
    int w = size[0], h = size[1];
    if (device >= 0 && !strcmp(backend, "cpu"))
        return cli_usage_error(&c, "--device names a Vulkan device; it does not go with --backend cpu");
    if (preview && (double)w * h > 8192.0 * 8192.0)
        return cli_usage_error(&c, "--preview is limited to 8192x8192 pixels");
    if (half && as_float)
        return cli_usage_error(&c, "--half and --float exclude each other");
    if (match && no_match)
        return cli_usage_error(&c, "--match-colours and --no-match-colours exclude each other");
    if (cli_check_output(&c, outdir, BTF_OUTPUT_FOLDER))
        return 1;
    btf_error err = {0};
    btf_model m;
    phases ph = {0};
    double t_read = cli_now();
    if (btf_model_read(model, &m, &err) != 0)
        return cli_lib_error(&c, &err);
    ph.read = cli_now() - t_read;
    unsigned char *pick = calloc((size_t)m.n_subspaces, 1);
    int rc = pick ? 0 : 1;
    if (rc == 0 && parse_list(list, m.n_subspaces, pick) != 0) {
        free(pick);
        int n = m.n_subspaces;
        btf_model_free(&m);
        return cli_usage_error(&c, "--subspace '%s': expected distinct numbers 0..%d, "
                               "comma-separated, all, or none", list, n - 1);
    }
    if (rc == 0 && !strcmp(list, "none") && !range) {
        free(pick);
        btf_model_free(&m);
        return cli_usage_error(&c, "--subspace none writes nothing without --range");
    }
    if (rc == 0 && range && !m.range) {
        free(pick);
        btf_model_free(&m);
        cli_set_error(&err, BTF_E_DATA, "%s: no range map in the model (analysed with "
                      "--no-range, or a texture model); --range needs one", model);
        return cli_lib_error(&c, &err);
    }
    /* The device first: a refusal leaves no output folder behind. */
    btf_gpu *gpu = NULL;
    int picked = 0;
    for (int k = 0; k < m.n_subspaces && pick; k++)
        picked += pick[k];
    if (rc == 0 && picked) {
        gpu = open_gpu(backend, device, (uint64_t)w * h * 12, &err);
        if (!gpu && (!strcmp(backend, "gpu") || device >= 0))
            rc = 1;
        else if (!gpu)
            err = (btf_error){0}; /* the CPU takes over: the GPU's reason is spent */
    }
    btf_output_dir *od = NULL; /* all images go into place at the end, or none */
    if (rc == 0)
        rc = btf_output_dir_begin(outdir, &od, &err);
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    int done = 0;
    for (int k = 0; k < m.n_subspaces; k++)
        done += pick[k];
    btf_synth_opts so = btf_synth_defaults();
    so.width = w, so.height = h, so.seed = seed, so.tileable = tileable;
    so.match_colours = match ? 1 : no_match ? -1 : 0;
    env_cpu_switches(&so);
    output out = {.dir = btf_output_dir_path(od), .model_path = model, .preview = preview, .ph = &ph};
    out.exr = btf_exr_defaults();
    out.exr.half = !as_float;
    out.exr.compression = comp;
    /* compress and write beside synthesis; BTF_EXR_THREAD=0: on this thread */
    const char *bg = getenv("BTF_EXR_THREAD");
    out.exr.background = !(bg && !strcmp(bg, "0"));
    out.exr.times = &ph.exr;
    if (rc == 0 && gpu) {
        rc = synth_gpu(gpu, &m, pick, &so, &out, &err);
    } else if (rc == 0 && picked && matched_whole(&m, pick, &so)) {
        rc = synth_matched(&c, &m, pick, &so, &out, &err);
    } else {
        for (int k = 0; rc == 0 && k < m.n_subspaces; k++)
            if (pick[k])
                rc = synth_one(&c, &m, k, &so, &out, &err);
    }
    double range_s = cli_now();
    if (rc == 0 && range)
        rc = write_range_maps(&m, w, h, seed, &out, &err);
    range_s = cli_now() - range_s; /* not in the synthesis rate */
    if (rc == 0)
        rc = btf_output_dir_commit(od, &err);
    else
        btf_output_dir_fail(od, &err);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    int gpu_used = gpu != NULL;
    char devname[300];
    snprintf(devname, sizeof devname, "%s", gpu ? btf_gpu_device_name(gpu) : "cpu");
    btf_gpu_close(gpu);
    free(pick);
    btf_model_free(&m);
    if (rc)
        return cli_lib_error(&c, &err);
    cli_progress_done();
    double s = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec) -
               range_s;
    if (!c.quiet && done)
        printf("synthesised %d subspace image%s of %dx%d on %s in %.3f s (%.1f Mpixel/s) into %s\n",
               done, done == 1 ? "" : "s", w, h, devname, s,
               (double)w * h * done / (s > 0 ? s : 1e-9) / 1e6, outdir);
    if (!c.quiet && range)
        printf("range map and normal map of %dx%d into %s/range.exr, %s/normal.exr\n", w, h,
               outdir, outdir);
    if (verbose)
        print_phases(&ph, gpu_used, comps[comp], !as_float, out.exr.background,
                     cli_now() - t_start);
    return 0;
}
