/*
 * cmd_info.c — btfcar info: what a dataset or a model file holds, as text
 * for people or (--json) as a stable JSON document for programs. The JSON
 * schemas are documented in docs/model-format.md ("btfcar info --json").
 */
#include "cli.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static const char ABOUT[] =
    "Describes a BTF dataset or a model file (MODEL.btfcar, recognised by its\n"
    "signature), or with --devices the Vulkan devices.\n\n"
    "A dataset: its layout (UBO2003, UTIA or a manifest .tsv), the number of\n"
    "images, views and lights, the image size, the direction sets and the bytes on\n"
    "disk. Every image's header and structure is checked (a missing or duplicated\n"
    "(light, view) pair, mixed sizes or a truncated file is an error).\n\n"
    "A model: its direction sets, the index table, every subspace (representative\n"
    "(view, light) pair, analysed size, mean colour, spectral basis, pyramid levels,\n"
    "and per band and level the CAR neighbourhood as row:col offsets, gamma, sigma\n"
    "and mean), the range map and the file size. The whole file is checked (CRC-32\n"
    "and every field) before anything is printed.\n";

/* --------------------------------------------------------------- shared */

/* The synthesis margin of a band (-1 should the library run out of memory). */
static int band_margin(const btf_model *m, int s, int b, int l)
{
    int margin = -1;
    btf_error err = {0};
    btf_synth_margin(m, s, b, l, &margin, &err);
    return margin;
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

/* A JSON string literal: quotes, backslashes and control bytes escaped. */
static void json_string(FILE *f, const char *s)
{
    fputc('"', f);
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        if (*p == '"' || *p == '\\')
            fprintf(f, "\\%c", *p);
        else if (*p < 0x20 || *p == 0x7f)
            fprintf(f, "\\u%04x", *p);
        else
            fputc(*p, f);
    }
    fputc('"', f);
}

/* float32 values with 9 significant digits (enough to round-trip) and
 * doubles with 17; the model reader has rejected NaN and Inf already. */
static void json_f32(FILE *f, float v)
{
    fprintf(f, "%.9g", (double)v);
}

static void json_f32s(FILE *f, const float *v, int n)
{
    fputc('[', f);
    for (int i = 0; i < n; i++) {
        if (i)
            fputs(", ", f);
        json_f32(f, v[i]);
    }
    fputc(']', f);
}

/* {"name": "ubo81", "count": 81, "directions": [[theta, phi], ...]} or null */
static void json_dirset(FILE *f, const btf_dirset *s)
{
    if (!s || s->count == 0) {
        fputs("null", f);
        return;
    }
    fputs("{\"name\": ", f);
    json_string(f, s->name);
    fprintf(f, ", \"count\": %d, \"directions\": [", s->count);
    for (int i = 0; i < s->count; i++)
        fprintf(f, "%s[%.17g, %.17g]", i ? ", " : "", s->dirs[i].theta, s->dirs[i].phi);
    fputs("]}", f);
}

/* ------------------------------------------------------------ datasets */

static int dataset_text(const btf_dataset_info *in, int verify)
{
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
    return 0;
}

static int dataset_json(const btf_dataset_info *in, int verify)
{
    FILE *f = stdout;
    fputs("{\"format\": \"btfcar-dataset\", \"path\": ", f);
    json_string(f, in->root);
    fputs(", \"layout\": ", f);
    json_string(f, btf_layout_name(in->layout));
    fprintf(f, ",\n \"images\": %d, \"width\": %d, \"height\": %d, \"channels\": %d, "
               "\"file_format\": \"%s\", \"bytes_on_disk\": %llu, \"verified\": %s,\n \"views\": ",
            in->n_views * in->n_lights, in->width, in->height, in->channels,
            format_name(in->format), (unsigned long long)in->bytes_on_disk,
            verify ? "true" : "false");
    json_dirset(f, in->views);
    fputs(",\n \"lights\": ", f);
    json_dirset(f, in->lights);
    fputs("}\n", f);
    return 0;
}

static int info_dataset(cli_ctx *c, const char *path, int verify, int json, uint64_t max_px)
{
    btf_error err = {0};
    btf_dataset_opts o = {.progress = cli_progress_fn(c), .max_pixels = max_px};
    btf_dataset *ds;
    if (btf_dataset_open(path, &o, &ds, &err) != 0)
        return cli_lib_error(c, &err);
    if (verify && btf_dataset_verify_pixels(ds, cli_progress_fn(c), NULL, &err) != 0) {
        btf_dataset_close(ds);
        return cli_lib_error(c, &err);
    }
    cli_progress_done();
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    int rc = json ? dataset_json(in, verify) : dataset_text(in, verify);
    btf_dataset_close(ds);
    return rc;
}

/* --------------------------------------------------------------- models */

/* The model signature's first bytes (docs/model-format.md). Only these are
 * compared, so that a file whose line endings a text-mode transfer mangled
 * still goes to the model reader, which says so. */
static const unsigned char MODEL_STEM[7] = {0x89, 'B', 'T', 'F', 'C', 'A', 'R'};

typedef struct model_file {
    const char *path;
    unsigned major, minor;
    long long bytes;
} model_file;

/* 1 when path is a file that starts like a model; its version and size. */
static int sniff_model(const char *path, model_file *mf)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return 0;
    unsigned char head[15] = {0};
    size_t n = fread(head, 1, sizeof head, f);
    fclose(f);
    if (n < sizeof MODEL_STEM || memcmp(head, MODEL_STEM, sizeof MODEL_STEM) != 0)
        return 0;
    struct stat st;
    mf->path = path;
    mf->major = head[11] | head[12] << 8;
    mf->minor = head[13] | head[14] << 8;
    mf->bytes = stat(path, &st) == 0 ? (long long)st.st_size : -1;
    return 1;
}

/* "0:-1,-1:0", the neighbourhood SPEC syntax of the command line. */
static void format_neighbourhood(const btf_car_band *b, char *buf, size_t n)
{
    size_t k = 0;
    buf[0] = '\0';
    for (int i = 0; i < b->n && k < n; i++)
        k += (size_t)snprintf(buf + k, n - k, "%s%d:%d", i ? "," : "", b->offsets[i].row,
                              b->offsets[i].col);
}

static void range_bounds(const btf_model *m, float *lo, float *hi)
{
    size_t n = (size_t)m->range_width * m->range_height;
    *lo = *hi = m->range[0];
    for (size_t i = 1; i < n; i++) {
        *lo = fminf(*lo, m->range[i]);
        *hi = fmaxf(*hi, m->range[i]);
    }
}

/* Index table cells per subspace (how many (view, light) pairs it serves). */
static int members(const btf_model *m, int s)
{
    int n = 0;
    for (int i = 0; i < m->views.count * m->lights.count; i++)
        n += m->index[i] == s;
    return n;
}

static void text_subspace(const btf_model *m, int s)
{
    const btf_subspace_model *sm = &m->subspaces[s];
    printf("subspace %d  ", s);
    if (sm->view >= 0)
        printf("view %d (theta %g, phi %g), light %d (theta %g, phi %g), %d images; ", sm->view,
               m->views.dirs[sm->view].theta, m->views.dirs[sm->view].phi, sm->light,
               m->lights.dirs[sm->light].theta, m->lights.dirs[sm->light].phi, members(m, s));
    printf("%d x %d, %d level%s\n", sm->width, sm->height, sm->levels, sm->levels == 1 ? "" : "s");
    printf("  mean      %.6g %.6g %.6g\n", sm->mean[0], sm->mean[1], sm->mean[2]);
    printf("  basis     [%.6g %.6g %.6g] [%.6g %.6g %.6g] [%.6g %.6g %.6g]\n", sm->basis[0],
           sm->basis[1], sm->basis[2], sm->basis[3], sm->basis[4], sm->basis[5], sm->basis[6],
           sm->basis[7], sm->basis[8]);
    for (int b = 0; b < 3; b++)
        for (int l = 0; l < sm->levels; l++) {
            const btf_car_band *cb = &sm->bands[b][l];
            char nb[BTF_CAR_MAX_NEIGHBOURS * 10 + 1];
            format_neighbourhood(cb, nb, sizeof nb);
            printf("  band %d level %d: %s  gamma", b, l, cb->n ? nb : "(none)");
            for (int i = 0; i < cb->n; i++)
                printf(" %.6g", cb->gamma[i]);
            printf("  sigma %.6g  mean %.6g  margin %d\n", cb->sigma, cb->mean,
                   band_margin(m, s, b, l));
        }
}

static int model_text(const btf_model *m, const model_file *mf)
{
    char views[128], lights[128];
    printf("model       %s\n", mf->path);
    /* Exact bytes: models are a few kilobytes, the figure users compare. */
    printf("format      btfcar model %u.%u, %lld bytes\n", mf->major, mf->minor, mf->bytes);
    if (m->views.count) {
        describe_set(&m->views, views, sizeof views);
        describe_set(&m->lights, lights, sizeof lights);
        printf("views       %s\n", views);
        printf("lights      %s\n", lights);
        printf("index       %d views x %d lights -> %d subspaces\n", m->views.count,
               m->lights.count, m->n_subspaces);
    } else {
        printf("views       none (a single texture)\n");
        printf("lights      none (a single texture)\n");
    }
    printf("subspaces   %d\n", m->n_subspaces);
    if (m->range) {
        float lo, hi;
        range_bounds(m, &lo, &hi);
        printf("range map   %d x %d, texel %g, heights %.6g..%.6g\n", m->range_width,
               m->range_height, m->range_texel, lo, hi);
    } else {
        printf("range map   none\n");
    }
    for (int s = 0; s < m->n_subspaces; s++)
        text_subspace(m, s);
    return 0;
}

static void json_band(FILE *f, const btf_car_band *b, int margin)
{
    char nb[BTF_CAR_MAX_NEIGHBOURS * 10 + 1];
    format_neighbourhood(b, nb, sizeof nb);
    fputs("{\"neighbourhood\": ", f);
    json_string(f, nb);
    fputs(", \"offsets\": [", f);
    for (int i = 0; i < b->n; i++)
        fprintf(f, "%s[%d, %d]", i ? ", " : "", b->offsets[i].row, b->offsets[i].col);
    fputs("], \"gamma\": ", f);
    json_f32s(f, b->gamma, b->n);
    fputs(", \"sigma\": ", f);
    json_f32(f, b->sigma);
    fputs(", \"mean\": ", f);
    json_f32(f, b->mean);
    fprintf(f, ", \"margin\": %d", margin);
    fputc('}', f);
}

static void json_subspace(FILE *f, const btf_model *m, int s)
{
    const btf_subspace_model *sm = &m->subspaces[s];
    fprintf(f, "{\"view\": %d, \"light\": %d, \"width\": %d, \"height\": %d, \"mean\": ",
            sm->view, sm->light, sm->width, sm->height);
    json_f32s(f, sm->mean, 3);
    fputs(", \"basis\": [", f);
    for (int r = 0; r < 3; r++) {
        fputs(r ? ", " : "", f);
        json_f32s(f, sm->basis + 3 * r, 3);
    }
    fprintf(f, "], \"levels\": %d,\n   \"bands\": [", sm->levels);
    for (int b = 0; b < 3; b++) {
        fputs(b ? ",\n    [" : "\n    [", f);
        for (int l = 0; l < sm->levels; l++) {
            fputs(l ? ",\n     " : "", f);
            json_band(f, &sm->bands[b][l], band_margin(m, s, b, l));
        }
        fputc(']', f);
    }
    fputs("]}", f);
}

static void json_index(FILE *f, const btf_model *m)
{
    if (!m->index) {
        fputs("null", f);
        return;
    }
    fputc('[', f);
    for (int v = 0; v < m->views.count; v++) {
        fputs(v ? ",\n   [" : "\n   [", f);
        for (int l = 0; l < m->lights.count; l++)
            fprintf(f, "%s%u", l ? ", " : "", m->index[v * m->lights.count + l]);
        fputc(']', f);
    }
    fputc(']', f);
}

static int model_json(const btf_model *m, const model_file *mf)
{
    FILE *f = stdout;
    fprintf(f, "{\"format\": \"btfcar-model\", \"version\": [%u, %u], \"file\": ", mf->major,
            mf->minor);
    json_string(f, mf->path);
    fprintf(f, ", \"file_bytes\": %lld,\n \"views\": ", mf->bytes);
    json_dirset(f, &m->views);
    fputs(",\n \"lights\": ", f);
    json_dirset(f, &m->lights);
    fputs(",\n \"index\": ", f);
    json_index(f, m);
    fprintf(f, ",\n \"subspaces\": [");
    for (int s = 0; s < m->n_subspaces; s++) {
        fputs(s ? ",\n  " : "\n  ", f);
        json_subspace(f, m, s);
    }
    fputs("],\n \"range\": ", f);
    if (m->range) {
        float lo, hi;
        range_bounds(m, &lo, &hi);
        fprintf(f, "{\"width\": %d, \"height\": %d, \"texel\": ", m->range_width,
                m->range_height);
        json_f32(f, m->range_texel);
        fputs(", \"min\": ", f);
        json_f32(f, lo);
        fputs(", \"max\": ", f);
        json_f32(f, hi);
        fputc('}', f);
    } else {
        fputs("null", f);
    }
    fputs("}\n", f);
    return 0;
}

static int info_model(cli_ctx *c, const model_file *mf, int json)
{
    btf_error err = {0};
    btf_model m;
    if (btf_model_read(mf->path, &m, &err) != 0)
        return cli_lib_error(c, &err);
    int rc = json ? model_json(&m, mf) : model_text(&m, mf);
    btf_model_free(&m);
    if (fflush(stdout) != 0)
        return cli_error(c, "cannot write the output");
    return rc;
}

/* ------------------------------------------------------------ devices */

static void devices_json(const btf_gpu_device *list, int n)
{
    printf("{\"devices\": [");
    for (int i = 0; i < n; i++) {
        printf("%s\n  {\"index\": %d, \"type\": ", i ? "," : "", list[i].index);
        json_string(stdout, list[i].type_name);
        printf(", \"vulkan\": ");
        json_string(stdout, list[i].vulkan_version);
        printf(", \"max_storage_buffer_bytes\": %llu, \"usable\": %s, \"name\": ",
               (unsigned long long)list[i].max_buffer_bytes, list[i].usable ? "true" : "false");
        json_string(stdout, list[i].name);
        printf("}");
    }
    printf("%s]}\n", n ? "\n" : "");
}

static void devices_text(const btf_gpu_device *list, int n)
{
    printf("%-5s  %-14s  %-7s  %-26s  %s\n", "index", "type", "Vulkan",
           "max storage buffer (bytes)", "name");
    for (int i = 0; i < n; i++)
        printf("%-5d  %-14s  %-7s  %-26llu  %s%s\n", list[i].index, list[i].type_name,
               list[i].vulkan_version, (unsigned long long)list[i].max_buffer_bytes, list[i].name,
               list[i].usable ? "" : " (unusable: needs Vulkan 1.1 and a compute queue)");
}

/* --devices: one line per Vulkan device, or one JSON document. Without any
 * device the text form is an error (exit 1); the JSON form lists none. */
static int info_devices(cli_ctx *c, int json)
{
    btf_error err = {0};
    btf_gpu_device *list;
    int n;
    if (btf_gpu_list_devices(&list, &n, &err) != 0)
        return cli_lib_error(c, &err);
    if (n == 0 && !json) {
        free(list);
        return cli_error(c, "no Vulkan device found (install mesa-vulkan-drivers for the CPU "
                            "driver lavapipe)");
    }
    if (json)
        devices_json(list, n);
    else
        devices_text(list, n);
    free(list);
    if (fflush(stdout) != 0)
        return cli_error(c, "cannot write the output");
    return 0;
}

int cmd_info(int argc, char **argv)
{
    cli_ctx c = {"info", 0};
    const char *path = NULL;
    int verify = 0, json = 0, devices = 0;
    uint64_t max_px = BTF_DEFAULT_MAX_PIXELS;
    cli_opt opts[] = {
        {.name = "--json", .kind = CLI_FLAG, .dest = &json,
         .help = "print one JSON document instead (schema: docs/model-format.md)"},
        {.name = "--verify", .kind = CLI_FLAG, .dest = &verify,
         .help = "dataset: also decode every image (catches corrupt data, NaN/Inf\n"
                 "in EXR); a model is always verified in full"},
        {.name = "--devices", .kind = CLI_FLAG, .dest = &devices,
         .help = "list the Vulkan devices GPU synthesis can use: index (for\n"
                 "--device and BTF_VK_DEVICE), type, Vulkan version, largest storage\n"
                 "buffer, name"},
        CLI_MAX_PIXELS_OPTION(&max_px),
        {0}};
    cli_spec spec = {.cmd = "info", .args = "DATASET|MODEL",
                     .alt_usage = "       btfcar info --devices [--json]", .about = ABOUT,
                     .min_args = 0, .max_args = 1, .opts = opts};
    int nargs, prc = cli_parse(&c, &spec, argc, argv, &path, &nargs);
    if (prc >= 0)
        return prc;
    if (devices)
        return path ? cli_usage_error(&c, "--devices takes no DATASET or MODEL")
                    : info_devices(&c, json);
    if (!path)
        return cli_usage_error(&c, "DATASET or MODEL is required");
    model_file mf;
    if (sniff_model(path, &mf))
        return info_model(&c, &mf, json);
    /* A file named like a model that does not start like one: say what the
     * model reader finds, rather than trying it as a manifest. */
    size_t len = strlen(path);
    if (len > 7 && !strcmp(path + len - 7, ".btfcar")) {
        btf_model m;
        btf_error err = {0};
        if (btf_model_read(path, &m, &err) != 0)
            return cli_lib_error(&c, &err);
        btf_model_free(&m); /* cannot happen: the signature did not match */
    }
    return info_dataset(&c, path, verify, json, max_px);
}
