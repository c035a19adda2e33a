/*
 * near_field.c — near-field captures (docs/datasets.md, "Near-field
 * captures"): a phone photographs the sample from ~10 cm with its flash
 * beside the lens, so the view and light directions change across the
 * image (several degrees over a 2.4 cm crop at 11 cm), and so does the
 * flash's irradiance (inverse square and cosine). The analysis models one
 * (view, light) pair per image (Haindl & Filip 2007, section II: each
 * measured image is one pair); here the irradiance is made the centre's
 * at every pixel, and the directions are the centre's. What the material's
 * reflectance does with the changing directions (the flash's highlight
 * moves with the camera) stays in the image; the manifest reader refuses
 * images whose directions spread more than BTF_NEAR_FIELD_MAX_SPREAD.
 */
#include "dataset/dataset.h"
#include "core/core.h"

#include <math.h>

static double norm3(const double *v)
{
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

btf_dir btf__near_field_dir(const double *pos)
{
    double r = norm3(pos);
    double theta = acos(pos[2] / r) * 57.29577951308232;
    double phi = atan2(pos[1], pos[0]) * 57.29577951308232;
    return (btf_dir){theta, phi < 0.0 ? phi + 360.0 : phi};
}

/* The surface point of pixel (c, r) of a w x h image: x to the right, y up. */
static void pixel_point(const btf_near_field *nf, int w, int h, double c, double r, double *p)
{
    p[0] = ((c + 0.5) / w - 0.5) * nf->size_x;
    p[1] = -((r + 0.5) / h - 0.5) * nf->size_y;
    p[2] = 0.0;
}

void btf__near_field_correct(const btf_near_field *nf, btf_image *img)
{
    if (!nf->on || !img->data)
        return;
    double l0 = norm3(nf->light);
    for (int r = 0; r < img->height; r++)
        for (int c = 0; c < img->width; c++) {
            double p[3], d[3];
            pixel_point(nf, img->width, img->height, c, r, p);
            for (int k = 0; k < 3; k++)
                d[k] = nf->light[k] - p[k];
            double q = norm3(d) / l0;
            float f = (float)(q * q * q);
            float *px = img->data + ((size_t)r * img->width + c) * img->channels;
            for (int k = 0; k < img->channels; k++)
                px[k] *= f;
        }
}

static double angle_deg(const double *a, const double *b)
{
    double d = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (norm3(a) * norm3(b));
    return acos(d > 1.0 ? 1.0 : d < -1.0 ? -1.0 : d) * 57.29577951308232;
}

double btf__near_field_spread(const btf_near_field *nf)
{
    double worst = 0.0;
    for (int corner = 0; corner < 4; corner++) {
        double p[3] = {(corner & 1 ? 0.5 : -0.5) * nf->size_x, (corner & 2 ? 0.5 : -0.5) * nf->size_y,
                       0.0};
        const double *pos[2] = {nf->camera, nf->light};
        for (int k = 0; k < 2; k++) {
            double d[3] = {pos[k][0] - p[0], pos[k][1] - p[1], pos[k][2] - p[2]};
            double a = angle_deg(d, pos[k]);
            worst = a > worst ? a : worst;
        }
    }
    return worst;
}
