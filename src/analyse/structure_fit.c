/*
 * structure_fit.c — the structure layer of an analysis (docs/model.md,
 * "Structure"): what the measured relief and albedo explain of each
 * subspace image is divided out before the CAR fit, so that the fields
 * model only the remainder and the renderer multiplies the measured
 * structure back, registered through one quilting map.
 *
 * The paper keeps the range map and relights it with bump mapping
 * (Haindl & Filip 2007, section III) but fits the CAR models to the whole
 * subspace image, whose variance already holds that relief's shading: the
 * relief was counted twice and registered nowhere. Here each exemplar S_k
 * under light l_k is modelled as
 *     S_k(x) = R_k(x) * A(x) * (a + max(0, n(x) . l_k)) / (a + l_kz)
 * with A the albedo's luminance pattern from photometric stereo (mean 1),
 * n the range map's normals (btf_normal_map, as the renderer derives
 * them), a the ambient term fitted below, and R_k what the CAR model
 * fits. The factor is the renderer's bump factor (btf_render_shared.h).
 */
#include "core/core.h"
#include "model/model.h"
#include "model/range_code.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A shading factor below this is held there when dividing: a texel the
 * relief turns away from the light keeps its own colour, not a blow-up. */
#define SHADE_DIVIDE_MIN 0.1
/* The flat surface's l_z floor (BTF_FLAT_MIN_Z of the renderer). */
#define FLAT_MIN_Z 0.05

static double luminance(const float *p, int channels)
{
    return channels == 3 ? 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2] : p[0];
}

btf_status btf_structure_albedo_from(const btf_image *albedo, btf_model *m, btf_error *err)
{
    size_t n = (size_t)m->range_width * m->range_height;
    if (albedo->width != m->range_width || albedo->height != m->range_height)
        return btf_fail(err, BTF_E_ARG, "structure layer: albedo %dx%d, range map %dx%d",
                        albedo->width, albedo->height, m->range_width, m->range_height);
    double sum = 0.0;
    size_t count = 0;
    for (size_t i = 0; i < n; i++) {
        double y = luminance(albedo->data + i * albedo->channels, albedo->channels);
        if (y > 0.0 && isfinite(y))
            sum += y, count++;
    }
    m->albedo = btf_alloc(n, sizeof(float), err);
    if (!m->albedo)
        return BTF_E_NOMEM;
    double mean = count && sum > 0.0 ? sum / (double)count : 1.0;
    for (size_t i = 0; i < n; i++) {
        double y = luminance(albedo->data + i * albedo->channels, albedo->channels);
        float a = y > 0.0 && isfinite(y) ? (float)(y / mean) : 1.0f;
        m->albedo[i] = btf_albedo_value(btf_albedo_code(a)); /* as the file keeps it */
    }
    return BTF_OK;
}

/* The shading factor of normal nv under light l (unit, frame of
 * btf_dir_to_vec) with ambient a. */
static double shade_factor(const float *nv, const double l[3], double a)
{
    double ndotl = nv[0] * l[0] + nv[1] * l[1] + nv[2] * l[2];
    double lit = ndotl > 0.0 ? ndotl : 0.0;
    double flat = l[2] > FLAT_MIN_Z ? l[2] : FLAT_MIN_Z;
    return (a + lit) / (a + flat);
}

btf_status btf_structure_normals(const btf_model *m, btf_image *normal, btf_error *err)
{
    btf_image h = {m->range_width, m->range_height, 1, m->range};
    return btf_normal_map(&h, 1.0, normal, err);
}

/* The ambient term of one exemplar: the least-squares line of
 * luminance / A against max(0, n . l); a = intercept / slope, -1 when the
 * line says nothing (no slope). */
static double ambient_of(const btf_image *img, const btf_model *m, const btf_image *normal,
                         const double l[3])
{
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    size_t n = (size_t)img->width * img->height;
    for (size_t i = 0; i < n; i++) {
        const float *nv = normal->data + 3 * i;
        double d = nv[0] * l[0] + nv[1] * l[1] + nv[2] * l[2];
        double x = d > 0.0 ? d : 0.0;
        double y = luminance(img->data + 3 * i, 3) / m->albedo[i];
        sx += x, sy += y, sxx += x * x, sxy += x * y;
    }
    double dn = (double)n, var = sxx - sx * sx / dn, cov = sxy - sx * sy / dn;
    if (!(var > 1e-9 * dn) || !(cov > 0.0))
        return -1.0;
    double slope = cov / var, icpt = (sy - slope * sx) / dn;
    double a = icpt / slope;
    return isfinite(a) ? (a < 0.0 ? 0.0 : a > BTF_STRUCTURE_AMBIENT_MAX ? BTF_STRUCTURE_AMBIENT_MAX : a) : -1.0;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

double btf_structure_fit_ambient(const btf_image *imgs, const btf_dir *lights, int n,
                                 const btf_model *m, const btf_image *normal)
{
    double *a = malloc((size_t)(n > 0 ? n : 1) * sizeof *a);
    if (!a)
        return 0.0;
    int got = 0;
    for (int k = 0; k < n; k++) {
        double l[3];
        btf_dir_to_vec(lights[k], l);
        if (l[2] <= 0.0)
            continue;
        double v = ambient_of(&imgs[k], m, normal, l);
        if (v >= 0.0)
            a[got++] = v;
    }
    qsort(a, (size_t)got, sizeof *a, cmp_double);
    double r = got ? a[got / 2] : 0.0;
    free(a);
    return r;
}

void btf_structure_divide(btf_image *img, const btf_model *m, const btf_image *normal,
                          btf_dir light, int albedo, double *mean_shade)
{
    double l[3];
    btf_dir_to_vec(light, l);
    size_t n = (size_t)img->width * img->height;
    double s = 0.0;
    for (size_t i = 0; i < n; i++) {
        double f = l[2] > 0.0 ? shade_factor(normal->data + 3 * i, l, m->ambient) : 1.0;
        s += f;
        double e = (f > SHADE_DIVIDE_MIN ? f : SHADE_DIVIDE_MIN) * (albedo ? m->albedo[i] : 1.0f);
        for (int c = 0; c < 3; c++)
            img->data[3 * i + c] = (float)(img->data[3 * i + c] / e);
    }
    if (mean_shade)
        *mean_shade = n ? s / (double)n : 1.0;
}
