/* cmd_synthesise.c — btfcar synthesise: subspace images of any size. */
#include "cli.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>


static void help(void)
{
    printf("usage: btfcar synthesise MODEL --size WxH -o OUTDIR [--subspace LIST|all]\n"
           "                        [--seed S] [--backend cpu] [--preview] [--quiet]\n\n"
           "Generates subspace images of the model at any size, seamless and stationary,\n"
           "streaming rows to OUTDIR/subspace_NN.exr (linear float RGB) as they are\n"
           "produced: memory grows with the width, not the height (docs/synthesis.md).\n\n"
           "  --size WxH        output size in pixels, each side 1..65536 (EXR files)\n"
           "  --subspace LIST   comma-separated subspace numbers, or all (default)\n"
           "  --seed S          noise seed (default 1); the same seed gives the same bytes\n"
           "  --backend B       cpu: the CPU reference; gpu: Vulkan compute (any device,\n"
           "                    the CPU driver lavapipe included); auto (default): a real\n"
           "                    GPU if present, else the CPU (lavapipe is slower than the\n"
           "                    CPU path: measured, README). Same bytes on every backend.\n"
           "  --device N        Vulkan device index (btfcar info --devices)\n"
           "  --preview         also write subspace_NN.png (8-bit sRGB; up to 8192x8192)\n"
           "  --half            write half-float EXR (default: float)\n"
           "  --quiet           print nothing but errors\n");
}

typedef struct sink {
    btf_exr_writer *exr;
    btf_image *preview;
    int height;
    btf_progress_fn progress;
} sink;

static int put_rows(void *user, int y, int nrows, const float *rows, btf_error *err)
{
    sink *s = user;
    if (s->preview)
        memcpy(s->preview->data + (size_t)y * s->preview->width * 3, rows,
               (size_t)nrows * s->preview->width * 3 * sizeof(float));
    if (s->progress && ((y + nrows) % 256 == 0 || y + nrows == s->height))
        s->progress(NULL, (double)(y + nrows) / s->height, "synthesising");
    return btf_exr_writer_put_rows(s->exr, rows, nrows, err);
}

/* "0,3,5" or "all" into a 0/1 table of m->n_subspaces entries: plain
 * decimal numbers only (no sign, no spaces), each once. */
static int parse_list(const char *s, int n, unsigned char *pick)
{
    memset(pick, !strcmp(s, "all"), (size_t)n);
    if (!strcmp(s, "all"))
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

/* Writes one image already in memory as EXR (+ preview). */
static int write_image(const btf_image *img, int k, const char *outdir, int preview, int half,
                       btf_error *err)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/subspace_%02d.exr", outdir, k);
    int rc = btf_image_write_exr(path, img, half, err);
    if (rc == 0 && preview) {
        snprintf(path, sizeof path, "%s/subspace_%02d.png", outdir, k);
        rc = btf_image_write_png(path, img, err);
    }
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

/* BTF_VK_DEVICE=N (a device index; unset or empty: none, *index -1) and
 * BTF_VK_VALIDATION=0|1 into the GPU options. */
static int env_gpu(btf_gpu_opts *o, int *index, btf_error *err)
{
    const char *d = getenv("BTF_VK_DEVICE"), *v = getenv("BTF_VK_VALIDATION");
    *index = -1;
    if (d && *d) {
        long n = 0;
        for (const char *c = d; *c; c++) {
            if (*c < '0' || *c > '9' || n > 100000)
                return cli_set_error(err, BTF_E_ARG, "BTF_VK_DEVICE='%s': expected a device "
                                     "index (see btfcar info --devices)", d);
            n = n * 10 + (*c - '0');
        }
        *index = (int)n;
    }
    if (v && *v && strcmp(v, "0") && strcmp(v, "1"))
        return cli_set_error(err, BTF_E_ARG, "BTF_VK_VALIDATION='%s': expected 0 or 1", v);
    o->validation = v && !strcmp(v, "1");
    return 0;
}

/* The GPU path returns whole images; at most this many bytes of them are
 * held at once (the CPU path streams rows instead). */
#define GPU_IMAGE_BUDGET (1ull << 30)

/* The GPU path: the chosen subspaces in groups that fit the memory budget,
 * each group in as few jobs as the device allows. */
static int synth_gpu(btf_gpu *g, const btf_model *m, const unsigned char *pick,
                     const btf_synth_opts *so, const char *outdir, int preview, int half,
                     btf_error *err)
{
    size_t count = m->n_subspaces > 0 ? (size_t)m->n_subspaces : 1;
    int n = 0, *subs = calloc(count, sizeof(int));
    btf_image *imgs = calloc(count, sizeof(btf_image));
    if (!subs || !imgs) {
        free(subs);
        free(imgs);
        return cli_set_error(err, BTF_E_NOMEM, "out of memory");
    }
    for (int k = 0; k < m->n_subspaces; k++)
        if (pick[k])
            subs[n++] = k;
    uint64_t one = (uint64_t)so->width * so->height * 12;
    int group = (int)(GPU_IMAGE_BUDGET / one);
    if (group < 1)
        group = 1;
    int rc = 0;
    for (int start = 0; rc == 0 && start < n; start += group) {
        int k = n - start < group ? n - start : group;
        rc = btf_gpu_synthesise(g, m, subs + start, k, so, imgs, err);
        for (int j = 0; rc == 0 && j < k; j++)
            rc = write_image(&imgs[j], subs[start + j], outdir, preview, half, err);
        for (int j = 0; j < k; j++)
            btf_image_free(&imgs[j]);
    }
    free(subs);
    free(imgs);
    return rc;
}

/* Opens the Vulkan device the backend asks for; NULL with a note (auto) or
 * an error (gpu) when there is none. */
static btf_gpu *open_gpu(const cli_ctx *c, const char *backend, int device, uint64_t image_bytes,
                        btf_error *err)
{
    if (!strcmp(backend, "cpu"))
        return NULL;
    /* A named device is as explicit as --backend gpu: its errors are errors. */
    int explicit_gpu = !strcmp(backend, "gpu") || device >= 0;
    if (image_bytes > GPU_IMAGE_BUDGET) {
        cli_set_error(err, BTF_E_UNSUPPORTED, "the GPU backend holds whole images in memory and one "
                 "image needs %.1f GiB, more than its %.0f GiB budget; --backend cpu streams",
                 image_bytes / 1073741824.0, GPU_IMAGE_BUDGET / 1073741824.0);
        if (!explicit_gpu && !c->quiet)
            fprintf(stderr, "btfcar synthesise: note: images this large are streamed on the CPU\n");
        return NULL;
    }
    btf_gpu_opts o = btf_gpu_defaults();
    int env_device;
    btf_gpu *g = NULL;
    int rc = env_gpu(&o, &env_device, err), from_env = device < 0 && env_device >= 0;
    if (from_env)
        device = env_device;
    o.use_device = device >= 0;
    o.device = device < 0 ? 0 : device;
    o.allow_cpu = explicit_gpu;
    if (rc == 0 && btf_gpu_open(&o, &g, err) != 0 && from_env) {
        char msg[sizeof err->msg];
        snprintf(msg, sizeof msg, "BTF_VK_DEVICE=%d: %s", device, err->msg);
        snprintf(err->msg, sizeof err->msg, "%s", msg);
    }
    if (!g) {
        if (!explicit_gpu && !c->quiet)
            fprintf(stderr, "btfcar synthesise: note: no GPU found; using the CPU (--backend gpu "
                            "runs the Vulkan path on any device, the CPU driver lavapipe "
                            "included)\n");
        return NULL;
    }
    return g;
}

static int synth_one(const cli_ctx *c, const btf_model *m, int k, const btf_synth_opts *so,
                     const char *outdir, int preview, int half, btf_error *err)
{
    int w = so->width, h = so->height;
    char path[4096];
    snprintf(path, sizeof path, "%s/subspace_%02d.exr", outdir, k);
    sink s = {.height = h, .progress = cli_progress_fn(c)};
    btf_image img = {0};
    int rc = 0;
    if (preview && (rc = btf_image_alloc(&img, w, h, 3, err)))
        return rc;
    s.preview = preview ? &img : NULL;
    rc = btf_exr_writer_open(path, w, h, 3, half, &s.exr, err);
    if (rc == 0) {
        rc = btf_synthesise(m, k, so, put_rows, &s, err);
        if (rc)
            btf_exr_writer_abort(s.exr);
        else
            rc = btf_exr_writer_close(s.exr, err);
    }
    if (rc == 0 && preview) {
        snprintf(path, sizeof path, "%s/subspace_%02d.png", outdir, k);
        rc = btf_image_write_png(path, &img, err);
    }
    btf_image_free(&img);
    return rc;
}

int cmd_synthesise(int argc, char **argv)
{
    cli_ctx c = {"synthesise", 0};
    const char *model = NULL, *outdir = NULL, *list = "all", *backend = "auto";
    int w = 0, h = 0, preview = 0, half = 0, device = -1;
    uint64_t seed = 1;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            help();
            return 0;
        } else if (!strcmp(a, "--quiet") || !strcmp(a, "-q")) {
            c.quiet = 1;
        } else if (!strcmp(a, "--preview")) {
            preview = 1;
        } else if (!strcmp(a, "--half")) {
            half = 1;
        } else if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
            if (!v)
                return cli_usage_error(&c, "-o needs a folder");
            outdir = v, i++;
        } else if (!strcmp(a, "--size")) {
            if (!v || cli_parse_size(v, &w, &h) || w > 65536 || h > 65536)
                return cli_usage_error(&c, "--size needs WxH, each 1..65536");
            i++;
        } else if (!strcmp(a, "--subspace")) {
            if (!v)
                return cli_usage_error(&c, "--subspace needs a list or all");
            list = v, i++;
        } else if (!strcmp(a, "--seed")) {
            if (!v || cli_parse_u64(v, &seed))
                return cli_usage_error(&c, "--seed needs a non-negative whole number");
            i++;
        } else if (!strcmp(a, "--backend")) {
            if (!v || (strcmp(v, "cpu") && strcmp(v, "gpu") && strcmp(v, "auto")))
                return cli_usage_error(&c, "--backend needs cpu, gpu or auto");
            backend = v, i++;
        } else if (!strcmp(a, "--device")) {
            long n;
            if (!v || cli_parse_int(v, 0, 255, &n))
                return cli_usage_error(&c, "--device needs an index 0..255");
            device = (int)n, i++;
        } else if (a[0] == '-' && a[1]) {
            return cli_usage_error(&c, "unknown option '%s'", a);
        } else if (!model) {
            model = a;
        } else {
            return cli_usage_error(&c, "unexpected argument '%s'", a);
        }
    }
    if (!model)
        return cli_usage_error(&c, "MODEL is required");
    if (!w)
        return cli_usage_error(&c, "--size WxH is required");
    if (!outdir)
        return cli_usage_error(&c, "-o OUTDIR is required");
    if (device >= 0 && !strcmp(backend, "cpu"))
        return cli_usage_error(&c, "--device names a Vulkan device; it does not go with --backend cpu");
    if (preview && (double)w * h > 8192.0 * 8192.0)
        return cli_usage_error(&c, "--preview is limited to 8192x8192 pixels");
    btf_error err = {0};
    btf_model m;
    if (btf_model_read(model, &m, &err) != 0)
        return cli_lib_error(&c, &err);
    unsigned char *pick = calloc((size_t)m.n_subspaces, 1);
    int rc = pick ? 0 : 1;
    if (rc == 0 && parse_list(list, m.n_subspaces, pick) != 0) {
        free(pick);
        int n = m.n_subspaces;
        btf_model_free(&m);
        return cli_usage_error(&c, "--subspace '%s': expected distinct numbers 0..%d, "
                               "comma-separated, or all", list, n - 1);
    }
    /* The device first: a refusal leaves no output folder behind. */
    btf_gpu *gpu = NULL;
    if (rc == 0) {
        gpu = open_gpu(&c, backend, device, (uint64_t)w * h * 12, &err);
        if (!gpu && (!strcmp(backend, "gpu") || device >= 0))
            rc = 1;
        else if (!gpu)
            err = (btf_error){0}; /* the CPU takes over: the GPU's reason is spent */
    }
    if (rc == 0)
        rc = btf_mkdirs(outdir, &err);
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    int done = 0;
    for (int k = 0; k < m.n_subspaces; k++)
        done += pick[k];
    btf_synth_opts so = btf_synth_defaults();
    so.width = w, so.height = h, so.seed = seed;
    env_cpu_switches(&so);
    if (rc == 0 && gpu) {
        rc = synth_gpu(gpu, &m, pick, &so, outdir, preview, half, &err);
    } else {
        for (int k = 0; rc == 0 && k < m.n_subspaces; k++)
            if (pick[k])
                rc = synth_one(&c, &m, k, &so, outdir, preview, half, &err);
    }
    clock_gettime(CLOCK_MONOTONIC, &t1);
    char devname[300];
    snprintf(devname, sizeof devname, "%s", gpu ? btf_gpu_device_name(gpu) : "cpu");
    btf_gpu_close(gpu);
    free(pick);
    btf_model_free(&m);
    if (rc)
        return cli_lib_error(&c, &err);
    cli_progress_done();
    double s = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    if (!c.quiet)
        printf("synthesised %d subspace image%s of %dx%d on %s in %.3f s (%.1f Mpixel/s) into %s\n",
               done, done == 1 ? "" : "s", w, h, devname, s,
               (double)w * h * done / (s > 0 ? s : 1e-9) / 1e6, outdir);
    return 0;
}
