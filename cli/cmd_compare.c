/* cmd_compare.c — btfcar compare: how far an image is from a reference
 * texture, without pixel correspondence (library: src/measure/,
 * docs/measure.md), and the phase-randomisation baseline to beat. */
#include "cli.h"

#include <cjson/cJSON.h>
#include <stdlib.h>
#include <string.h>

static const char ABOUT[] =
    "Measures how far IMAGE is from the texture REFERENCE (PNG, JPEG or EXR; any\n"
    "two sizes, each side at least 16), with no pixel correspondence: (a) spectrum,\n"
    "the radially binned log power spectrum of luminance (dB); (b) first order, the\n"
    "earth mover's distance between the CIE Lab values; (c) structure, statistics\n"
    "of Laplacian-pyramid bands of L* (variance, skewness, kurtosis, neighbour\n"
    "correlations). Each is printed raw, as the same distance between the\n"
    "reference's quadrants scaled to the images' sizes (self), and normalised\n"
    "(raw / self: 1.0 is as close as the material is to itself); the combined\n"
    "figure is the mean of the three normalised values. Definitions and the JSON\n"
    "keys: docs/measure.md.\n\n"
    "With --baseline OUT (and no IMAGE): writes the phase-randomisation baseline of\n"
    "REFERENCE (its power spectrum, random phases) at REFERENCE's size to OUT (.png\n"
    "or .exr), and measures it.\n";

static void add_component(cJSON *o, const char *key, const btf_distance_component *c,
                          const char *unit)
{
    cJSON *j = cJSON_AddObjectToObject(o, key);
    cJSON_AddNumberToObject(j, "raw", c->raw);
    cJSON_AddNumberToObject(j, "self", c->self);
    cJSON_AddNumberToObject(j, "normalised", c->normalised);
    cJSON_AddStringToObject(j, "unit", unit);
}

static void add_image(cJSON *o, const char *key, const char *path, const btf_image *img)
{
    cJSON *j = cJSON_AddObjectToObject(o, key);
    char *utf8 = cli_utf8_copy(path); /* JSON is UTF-8; a file name any bytes */
    cJSON_AddStringToObject(j, "path", utf8 ? utf8 : "");
    free(utf8);
    cJSON_AddNumberToObject(j, "width", img->width);
    cJSON_AddNumberToObject(j, "height", img->height);
}

static int print_json(const char *ref_path, const btf_image *ref, const char *img_path,
                      const btf_image *img, const btf_texture_distances *d,
                      const char *baseline, uint64_t seed)
{
    cJSON *o = cJSON_CreateObject();
    if (!o)
        return 1;
    cJSON_AddStringToObject(o, "format", "btfcar-compare");
    add_image(o, "reference", ref_path, ref);
    add_image(o, "image", img_path, img);
    add_component(o, "spectrum", &d->spectrum, "dB");
    cJSON_AddNumberToObject(cJSON_GetObjectItem(o, "spectrum"), "bins", d->spectrum_bins);
    add_component(o, "first_order", &d->first_order, "Lab");
    cJSON *fo = cJSON_GetObjectItem(o, "first_order");
    cJSON_AddNumberToObject(fo, "L", d->first_order_lab[0]);
    cJSON_AddNumberToObject(fo, "a", d->first_order_lab[1]);
    cJSON_AddNumberToObject(fo, "b", d->first_order_lab[2]);
    add_component(o, "structure", &d->structure, "");
    cJSON_AddNumberToObject(cJSON_GetObjectItem(o, "structure"), "levels", d->levels);
    cJSON_AddNumberToObject(o, "combined", d->combined);
    cJSON_AddNumberToObject(o, "exposure", d->exposure);
    if (baseline) {
        cJSON *b = cJSON_AddObjectToObject(o, "baseline");
        cJSON_AddStringToObject(b, "method", "phase-randomisation");
        cJSON_AddNumberToObject(b, "seed", (double)seed);
        cJSON_AddNumberToObject(b, "bytes",
                                (double)btf_phase_randomise_bytes(ref->width, ref->height));
    }
    char *text = cJSON_Print(o);
    cJSON_Delete(o);
    if (!text)
        return 1;
    puts(text);
    cJSON_free(text);
    return 0;
}

static void print_text(const char *ref_path, const btf_image *ref, const char *img_path,
                       const btf_image *img, const btf_texture_distances *d)
{
    printf("reference    %s (%dx%d)\n", ref_path, ref->width, ref->height);
    printf("image        %s (%dx%d)\n", img_path, img->width, img->height);
    printf("%-12s %12s %12s %11s\n", "", "raw", "self", "normalised");
    printf("%-12s %9.4f dB %9.4f dB %11.3f   (%d rings)\n", "spectrum", d->spectrum.raw,
           d->spectrum.self, d->spectrum.normalised, d->spectrum_bins);
    printf("%-12s %12.4f %12.4f %11.3f   (L* %.3f, a* %.3f, b* %.3f)\n", "first-order",
           d->first_order.raw, d->first_order.self, d->first_order.normalised,
           d->first_order_lab[0], d->first_order_lab[1], d->first_order_lab[2]);
    printf("%-12s %12.4f %12.4f %11.3f   (%d levels)\n", "structure", d->structure.raw,
           d->structure.self, d->structure.normalised, d->levels);
    printf("combined     %.3f   (mean of the normalised; 1.0: as close as the reference "
           "is to itself)\n", d->combined);
}

/* --baseline: the phase-randomised reference, written to path. */
static int write_baseline(cli_ctx *c, const btf_image *ref, const char *path, uint64_t seed,
                          btf_image *out)
{
    btf_error err = {0};
    if (btf_phase_randomise(ref, ref->width, ref->height, seed, out, &err) != 0)
        return cli_lib_error(c, &err);
    btf_status rc = cli_write_image(path, out, &err);
    if (rc != 0) {
        btf_image_free(out);
        return cli_lib_error(c, &err);
    }
    return 0;
}

int cmd_compare(int argc, char **argv)
{
    cli_ctx c = {"compare", 0};
    int json = 0;
    const char *baseline = NULL;
    uint64_t seed = 1;
    btf_texture_distance_opts dopts = btf_texture_distance_defaults();
    btf_read_opts ro = btf_read_defaults();
    ro.channels = 3;
    cli_opt opts[] = {
        {.name = "--json", .kind = CLI_FLAG, .dest = &json,
         .help = "print the figures as one JSON document (keys: docs/measure.md)"},
        {.name = "--levels", .kind = CLI_INT, .dest = &dopts.levels, .meta = "L|auto",
         .help = "structure: Laplacian-pyramid levels; auto: as many as the smaller\n"
                 "image (and the reference's quadrants) allow, bands of at least 8\n"
                 "pixels, at most 6",
         .lo = 1, .hi = 6, .word = "auto", .word_value = 0, .zero_means = "auto"},
        {.name = "--baseline", .kind = CLI_STRING, .dest = &baseline, .meta = "OUT",
         .help = "write the phase-randomisation baseline of REFERENCE to OUT (.png\n"
                 "or .exr) and measure it instead of an IMAGE"},
        {.name = "--seed", .kind = CLI_U64, .dest = &seed, .meta = "S",
         .help = "--baseline: the seed of the random phases"},
        CLI_MAX_PIXELS_OPTION(&ro.max_pixels),
        {0}};
    cli_spec spec = {.cmd = "compare", .args = "REFERENCE IMAGE",
                     .alt_usage = "btfcar compare REFERENCE --baseline OUT [--seed S] [--json]",
                     .about = ABOUT, .min_args = 1, .max_args = 2, .opts = opts};
    const char *args[2] = {NULL, NULL};
    int nargs, prc = cli_parse(&c, &spec, argc, argv, args, &nargs);
    if (prc >= 0)
        return prc;
    if (baseline ? nargs != 1 : nargs != 2)
        return cli_usage_error(&c, baseline ? "--baseline takes REFERENCE alone, no IMAGE"
                                            : "needs REFERENCE and IMAGE");
    if (baseline && !cli_has_suffix(baseline, ".png") && !cli_has_suffix(baseline, ".exr"))
        return cli_usage_error(&c, "--baseline %s: expected a .png or .exr file", baseline);
    if (baseline && cli_check_output(&c, baseline, BTF_OUTPUT_FILE))
        return 1;
    btf_error err = {0};
    btf_image ref, img;
    if (btf_image_read(args[0], &ro, &ref, &err) != 0)
        return cli_lib_error(&c, &err);
    int rc = baseline ? write_baseline(&c, &ref, baseline, seed, &img)
                      : btf_image_read(args[1], &ro, &img, &err) ? cli_lib_error(&c, &err) : 0;
    if (rc) {
        btf_image_free(&ref);
        return rc;
    }
    const char *img_path = baseline ? baseline : args[1];
    dopts.reference_name = args[0];
    dopts.image_name = img_path;
    btf_texture_distances d;
    if (btf_texture_distance(&ref, &img, &dopts, &d, &err) != 0)
        rc = cli_lib_error(&c, &err);
    else if (json)
        rc = print_json(args[0], &ref, img_path, &img, &d, baseline, seed);
    else {
        print_text(args[0], &ref, img_path, &img, &d);
        if (baseline) {
            char bytes[64];
            cli_format_bytes(btf_phase_randomise_bytes(ref.width, ref.height), bytes,
                             sizeof bytes);
            printf("baseline     written %s (seed %llu); its storage, the amplitude spectrum: "
                   "%s\n", baseline, (unsigned long long)seed, bytes);
        }
    }
    btf_image_free(&ref);
    btf_image_free(&img);
    return rc;
}
