/*
 * cmd_info.c — btfcar info: what a dataset or a model file holds, as text
 * for people or (--json) as a stable JSON document for programs. The JSON
 * schemas are documented in docs/model-format.md ("btfcar info --json").
 * Here: the options, telling a model file from a dataset, the dataset
 * report and the Vulkan device list; the model report is info_model.c's.
 */
#include "cli.h"
#include "core/describe.h"

#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static const char ABOUT[] =
    "Describes a BTF dataset or a model file (MODEL.btfcar, or a reflectance-field\n"
    "model of analyse --family rf, recognised by its signature), or with --devices\n"
    "the Vulkan devices.\n\n"
    "A dataset: its layout (UBO2003, UTIA, a manifest .tsv or an RTI light file\n"
    ".lp), the number of images, views and lights, the image size, the direction\n"
    "sets and the bytes on disk. Every image's header and structure is checked (a\n"
    "missing or duplicated (light, view) pair, mixed sizes or a truncated file is\n"
    "an error). A Bonn .btf file (DFMF, FMF, PVF, BDIF) is a dataset too: also its\n"
    "variant, components per channel, colour model and the bytes of its factors.\n\n"
    "A model: its direction sets, the index table, every subspace (representative\n"
    "(view, light) pair, analysed size, mean colour, spectral basis, pyramid levels,\n"
    "and per band and level the CAR neighbourhood as row:col offsets, gamma, sigma\n"
    "and mean), the range map and the file size. The whole file is checked (CRC-32\n"
    "and every field) before anything is printed.\n";

/* ------------------------------------------------------------ datasets */

static const char *format_name(btf_file_format f)
{
    switch (f) {
    case BTF_FILE_PNG: return "PNG";
    case BTF_FILE_JPEG: return "JPEG";
    case BTF_FILE_EXR: return "EXR";
    default: return "?";
    }
}

/* A Bonn .btf file's own fields (layout UBO2014). */
static void ubo_text(const btf_ubo2014_info *u)
{
    printf("btf file    %s (%s), meta version %d\n", u->variant, u->signature, u->meta_version);
    if (u->components[1] || u->components[2])
        printf("components  R %d, G %d, B %d (per channel)\n", u->components[0],
               u->components[1], u->components[2]);
    else if (u->components[0])
        printf("components  %d (shared by the channels)\n", u->components[0]);
    if (u->colour_model >= 0)
        printf("colour      model %d\n", u->colour_model);
    printf("scalars     %d bytes%s%s\n", u->scalar_size, u->scalar_size == 2 ? " (half)" : "",
           u->transposed ? ", transposed layout" : "");
    char b[64];
    cli_format_bytes(u->data_bytes, b, sizeof b);
    printf("data        %s mapped (%llu bytes)\n", b, (unsigned long long)u->data_bytes);
    printf("cosine      %s\n", u->cosine_flag ? "flag set: divided by cos(theta_l)" : "flag 0");
    printf("rgb scale   %g %g %g (stored; not applied)\n", u->rgb_scale[0], u->rgb_scale[1],
           u->rgb_scale[2]);
    if (u->dynamic_range)
        printf("range       stored as ln(value + 1e-5)\n");
    if (u->rotations)
        printf("rotations   %d (skipped)\n", u->rotations);
    if (u->measurement_setup[0])
        printf("setup       %s\n", u->measurement_setup);
}

static int dataset_text(const btf_dataset_info *in, int verify, const btf_ubo2014_info *u)
{
    char views[128], lights[128], bytes[64];
    txt_describe_set(in->views, views, sizeof views);
    txt_describe_set(in->lights, lights, sizeof lights);
    cli_format_bytes(in->bytes_on_disk, bytes, sizeof bytes);
    printf("dataset     %s\n", in->root);
    printf("layout      %s\n", btf_layout_name(in->layout));
    if (in->n_pairs < in->n_views * in->n_lights)
        printf("images      %d: a sparse set of %d of the %d (%d views x %d lights) pairs\n",
               in->n_pairs, in->n_pairs, in->n_views * in->n_lights, in->n_views, in->n_lights);
    else
        printf("images      %d (%d views x %d lights)\n", in->n_pairs, in->n_views,
               in->n_lights);
    if (u)
        printf("image size  %d x %d, %d channels, reconstructed from the file\n", in->width,
               in->height, in->channels);
    else
        printf("image size  %d x %d, %d channel%s, %s\n", in->width, in->height, in->channels,
               in->channels == 1 ? "" : "s", format_name(in->format));
    printf("views       %s\n", views);
    printf("lights      %s\n", lights);
    printf("on disk     %s\n", bytes);
    if (in->near_field)
        printf("near field  camera and light positions: each image is read with the light's "
               "fall-off made its centre's, at its centre's directions\n");
    if (u)
        ubo_text(u);
    if (verify)
        printf("verified    every image decoded\n");
    return 0;
}

static int dataset_json(const btf_dataset_info *in, int verify, const btf_ubo2014_info *u)
{
    FILE *f = stdout;
    fputs("{\"format\": \"btfcar-dataset\", \"path\": ", f);
    txt_json_string(f, in->root);
    fputs(", \"layout\": ", f);
    txt_json_string(f, btf_layout_name(in->layout));
    fprintf(f, ",\n \"images\": %d, \"width\": %d, \"height\": %d, \"channels\": %d, "
               "\"file_format\": \"%s\", \"bytes_on_disk\": %llu, \"verified\": %s,\n "
               "\"sparse\": %s, \"near_field\": %s, \"views\": ",
            in->n_pairs, in->width, in->height, in->channels,
            u ? "btf" : format_name(in->format), (unsigned long long)in->bytes_on_disk,
            verify ? "true" : "false", in->n_pairs < in->n_views * in->n_lights ? "true" : "false",
            in->near_field ? "true" : "false");
    txt_json_dirset(f, in->views);
    fputs(",\n \"lights\": ", f);
    txt_json_dirset(f, in->lights);
    if (u) {
        fputs(",\n \"btf\": {\"variant\": ", f);
        txt_json_string(f, u->variant);
        fputs(", \"signature\": ", f);
        txt_json_string(f, u->signature);
        fprintf(f, ", \"components\": [%d, %d, %d], \"colour_model\": %d, \"scalar_size\": %d, "
                   "\"cosine_flag\": %d, \"data_bytes\": %llu}",
                u->components[0], u->components[1], u->components[2], u->colour_model,
                u->scalar_size, u->cosine_flag, (unsigned long long)u->data_bytes);
    }
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
    const btf_ubo2014_info *u = btf_dataset_ubo2014(ds);
    int rc = json ? dataset_json(in, verify, u) : dataset_text(in, verify, u);
    btf_dataset_close(ds);
    return rc;
}

/* --------------------------------------------------------------- models */

/* 1 when path is a file that starts like a model of any family. */
static int looks_like_model(const char *path)
{
    unsigned char head[16] = {0};
    return btf_material_sniff(head, cli_read_head(path, head, sizeof head)) != BTF_FAMILY_NONE;
}

/* A model of either family: read whole and checked, then described. */
static int info_model(cli_ctx *c, const char *path, int json)
{
    btf_error err = {0};
    btf_material *m;
    if (btf_material_read(path, &m, &err) != 0)
        return cli_lib_error(c, &err);
    btf_status rc = btf_material_describe(m, stdout, json, &err);
    btf_material_free(m);
    return rc ? cli_lib_error(c, &err) : 0;
}

/* ------------------------------------------------------------ devices */

static void devices_json(const btf_gpu_device *list, int n)
{
    printf("{\"devices\": [");
    for (int i = 0; i < n; i++) {
        printf("%s\n  {\"index\": %d, \"type\": ", i ? "," : "", list[i].index);
        txt_json_string(stdout, list[i].type_name);
        printf(", \"vulkan\": ");
        txt_json_string(stdout, list[i].vulkan_version);
        printf(", \"max_storage_buffer_bytes\": %llu, \"device_local_bytes\": %llu, "
               "\"storage_16bit\": %s, \"usable\": %s, \"name\": ",
               (unsigned long long)list[i].max_buffer_bytes,
               (unsigned long long)list[i].device_local_bytes,
               list[i].storage_16bit ? "true" : "false", list[i].usable ? "true" : "false");
        txt_json_string(stdout, list[i].name);
        printf("}");
    }
    printf("%s]}\n", n ? "\n" : "");
}

/* Device sizes are powers of two or near them (4 GiB - 1 on many GPUs), so
 * binary units read as the drivers state them: "128.0 MiB", "4.0 GiB". */
static void format_mib(uint64_t bytes, char *buf, size_t n)
{
    double mib = (double)bytes / (1024.0 * 1024.0);
    if (mib >= 1024.0)
        snprintf(buf, n, "%.1f GiB", mib / 1024.0);
    else
        snprintf(buf, n, "%.1f MiB", mib);
}

static void devices_text(const btf_gpu_device *list, int n)
{
    printf("%-5s  %-14s  %-7s  %-18s  %-17s  %-14s  %s\n", "index", "type", "Vulkan",
           "max storage buffer", "device-local heap", "16-bit storage", "name");
    for (int i = 0; i < n; i++) {
        char buf[32], heap[32];
        format_mib(list[i].max_buffer_bytes, buf, sizeof buf);
        format_mib(list[i].device_local_bytes, heap, sizeof heap);
        printf("%-5d  %-14s  %-7s  %-18s  %-17s  %-14s  %s%s\n", list[i].index,
               list[i].type_name, list[i].vulkan_version, buf, heap,
               list[i].storage_16bit ? "yes" : "no", list[i].name,
               list[i].usable ? "" : " (unusable: needs Vulkan 1.1 and a compute queue)");
    }
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
                 "buffer, largest device-local memory heap, 16-bit storage, name"},
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
    if (looks_like_model(path))
        return info_model(&c, path, json);
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
    /* An image is neither: say what it is and what models it. */
    struct stat st;
    btf_image_header hdr;
    btf_error ierr = {0};
    if (stat(path, &st) == 0 && S_ISREG(st.st_mode) && btf_image_probe(path, &hdr, &ierr) == 0)
        return cli_error(&c, "%s: %s %s image of %dx%d, not a dataset or a model; to model it "
                         "as a texture run: btfcar texture-fit %s -o MODEL.btfcar", path,
                         hdr.format == BTF_FILE_EXR ? "an" : "a", format_name(hdr.format), hdr.width,
                         hdr.height, path);
    return info_dataset(&c, path, verify, json, max_px);
}
