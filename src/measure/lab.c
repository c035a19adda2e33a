/*
 * lab.c — the colour space every distance is measured in: CIE L*a*b*
 * (D65), perceptually near-uniform, so that a distance of 1 in L* means
 * about the same visible step in the dark and in the light. Images are
 * linear RGB; the OpenCV bridge converts linear values in [0, 1]. Values
 * above 1 are brought in range by one exposure fixed by the reference (the
 * same for both images, so brightness differences stay measured); negative
 * values (a synthesis can produce them) are shown as black would be.
 * Because L*, a*, b* are bounded, no later stage can overflow. The
 * spectrum uses linear luminance Y instead (measure/spectrum.c), kept
 * beside them, unclamped.
 */
#include "core/core.h"
#include "io/io.h"
#include "measure/measure.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>

double ms_exposure(const btf_image *ref)
{
    size_t n = (size_t)ref->width * ref->height * ref->channels;
    float big = 0.0f;
    for (size_t i = 0; i < n; i++)
        if (ref->data[i] > big)
            big = ref->data[i];
    return big > 1.0f ? 1.0 / (double)big : 1.0;
}

/* Rec. 709 (sRGB primaries) luminance weights. */
static const double Y_WEIGHTS[3] = {0.2126, 0.7152, 0.0722};

btf_status ms_lab(const btf_image *img, double scale, const char *name, float **lab,
                  btf_error *err)
{
    *lab = NULL;
    size_t n = (size_t)img->width * img->height;
    int c = img->channels;
    float *out = btf__alloc(n * MS_CH, sizeof(float), err);
    float *rgb = out ? btf__alloc(n * 6, sizeof(float), err) : NULL;
    if (!rgb) {
        free(out);
        return BTF_E_NOMEM;
    }
    float *lab3 = rgb + 3 * n;
    for (size_t i = 0; i < n; i++) {
        double y = 0.0;
        for (int k = 0; k < 3; k++) {
            float v = img->data[i * c + (c == 3 ? k : 0)];
            if (!isfinite(v)) {
                free(rgb);
                free(out);
                return btf__fail(err, BTF_E_DATA, "%s: pixel (%zu, %zu) is not finite", name,
                                 i % (size_t)img->width, i / (size_t)img->width);
            }
            double s = (double)v * scale;
            y += Y_WEIGHTS[k] * s;
            rgb[3 * i + k] = (float)(s < 0.0 ? 0.0 : s > 1.0 ? 1.0 : s);
        }
        /* beyond float range only when the image is far brighter than the
         * reference: clamp rather than overflow */
        out[MS_CH * i + MS_Y] = (float)(y > FLT_MAX ? FLT_MAX : y < -FLT_MAX ? -FLT_MAX : y);
    }
    char why[256];
    if (btfcv_rgb_to_lab(rgb, n, lab3, why, sizeof why) != 0) {
        free(rgb);
        free(out);
        return btf__fail(err, BTF_E_UNSUPPORTED, "%s: Lab conversion failed: %s", name, why);
    }
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            out[MS_CH * i + k] = lab3[3 * i + k];
    free(rgb);
    *lab = out;
    return BTF_OK;
}
