/* cmd_texture_fit.c — btfcar texture-fit: the multi-scale colour CAR model of
 * one ordinary texture (Haindl & Filip 2007, section II.C; library:
 * src/analyse/subspace_fit.c). */
#include "cli.h"

#include <math.h>
#include <string.h>

static const char ABOUT[] =
    "Models one ordinary colour texture (PNG, JPEG or EXR) with the multi-scale\n"
    "colour 2D CAR model: spectral decorrelation, a Gaussian-Laplacian pyramid and\n"
    "one causal auto-regressive model per band and level (docs/model.md). The\n"
    "model has one subspace, no directions and no range map; 'btfcar synthesise'\n"
    "regenerates the texture at any size. The image's values must be at most\n"
    "1e28 in magnitude (what synthesis keeps within float), and some must be\n"
    "positive when any is negative (radiance is not negative; synthesis keeps\n"
    "colours >= 0): more than a quarter negative is a warning.\n";

/* Every magnitude of the exemplar at most BTF_EXEMPLAR_MAX_VALUE, checked
 * before any fitting: beyond it the model's bands could overflow synthesis'
 * float arithmetic, and the model file refuses them (src/model/
 * model_check.c). 0, or 1 after the one-line error naming the file. */
static int check_magnitude(const cli_ctx *c, const char *image, const btf_image *img)
{
    size_t n = (size_t)img->width * img->height * img->channels;
    float big = 0.0f;
    for (size_t i = 0; i < n; i++)
        big = fabsf(img->data[i]) > big ? fabsf(img->data[i]) : big;
    if (big > BTF_EXEMPLAR_MAX_VALUE)
        return cli_error(c, "%s: values of magnitude up to %g are too large to model (expected "
                         "at most %g, which keeps synthesis within float)", image, big,
                         BTF_EXEMPLAR_MAX_VALUE);
    return 0;
}

/* Share of negative values above which the exemplar gets a warning: the
 * model's RGB box starts at 0 (no negative radiance, src/analyse/
 * marginal_fit.c), so synthesis clamps those parts to black. A few negative
 * values (noise in the dark parts of an HDR capture) pass silently. */
#define NEGATIVE_WARN_SHARE 0.25

/* The exemplar's signs: an image with negative values and none positive is
 * refused (negative radiance is not a physical texture, and clamped to the
 * non-negative box its synthesis would be all black); an all-zero image is
 * a black texture and stays valid; more than NEGATIVE_WARN_SHARE negative
 * is a warning. 0, or 1 after the one-line error naming the file. */
static int check_signs(const cli_ctx *c, const char *image, const btf_image *img)
{
    size_t n = (size_t)img->width * img->height * img->channels, negative = 0, positive = 0;
    for (size_t i = 0; i < n; i++) {
        negative += img->data[i] < 0.0f;
        positive += img->data[i] > 0.0f;
    }
    if (negative > 0 && positive == 0)
        return cli_error(c, "%s: no value is positive and %zu of %zu are negative (expected a "
                         "texture of non-negative radiance)", image, negative, n);
    if (!c->quiet && (double)negative > NEGATIVE_WARN_SHARE * (double)n) {
        char msg[4352];
        snprintf(msg, sizeof msg, "%s: %.0f%% of the values are negative; synthesis keeps "
                 "colours >= 0, so those parts come out black", image,
                 100.0 * (double)negative / (double)n);
        cli_warning((void *)c, msg);
    }
    return 0;
}

int cmd_texture_fit(int argc, char **argv)
{
    cli_ctx c = {"texture-fit", 0};
    const char *out = NULL;
    btf_fit_opts fo = btf_fit_defaults();
    btf_read_opts ro = btf_read_defaults();
    ro.channels = 3;
    cli_opt opts[] = {
        {.name = "--output", .short_name = "-o", .kind = CLI_STRING, .dest = &out,
         .meta = "MODEL", .help = "the model file to write (atomically)", .required = 1},
        CLI_MODEL_OPTIONS(&fo, 0),
        CLI_MAX_PIXELS_OPTION(&ro.max_pixels),
        {0}};
    cli_spec spec = {.cmd = "texture-fit", .args = "IMAGE", .about = ABOUT, .min_args = 1,
                     .max_args = 1, .opts = opts};
    const char *image;
    int nargs, prc = cli_parse(&c, &spec, argc, argv, &image, &nargs);
    if (prc >= 0)
        return prc;
    if (cli_check_output(&c, out, BTF_OUTPUT_FILE))
        return 1;
    btf_error err = {0};
    btf_image img;
    if (btf_image_read(image, &ro, &img, &err) != 0)
        return cli_lib_error(&c, &err);
    if (check_magnitude(&c, image, &img) || check_signs(&c, image, &img)) {
        btf_image_free(&img);
        return 1;
    }
    fo.car.warn = c.quiet ? NULL : cli_warning;
    fo.car.warn_user = &c;
    btf_model m;
    int rc = btf_texture_fit(&img, &fo, &m, &err);
    btf_image_free(&img);
    if (rc == BTF_E_NOMEM) { /* name the file: the library only saw pixels */
        char m[sizeof err.msg];
        memcpy(m, err.msg, sizeof m);
        snprintf(err.msg, sizeof err.msg, "%s: %s", image, m);
    }
    if (rc)
        return cli_lib_error(&c, &err);
    rc = btf_model_write(out, &m, &err);
    if (rc == 0 && !c.quiet) {
        cli_print_subspace(&m.subspaces[0], 0);
        printf("written %s\n", out);
    }
    btf_model_free(&m);
    return rc ? cli_lib_error(&c, &err) : 0;
}
