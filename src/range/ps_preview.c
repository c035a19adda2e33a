/*
 * ps_preview.c — pictures of the range-map stage's results for people
 * (Haindl & Filip 2007, section II.B): the normal map in the usual
 * normal-map colours, and the height field as a shaded relief. The EXR
 * files hold the data; these only have to be read at a glance, so the relief
 * is exaggerated to a fixed mean slope and tinted by height.
 */
#include "range/range.h"
#include "core/core.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

btf_status btf__normals_preview(const btf_image *normals, btf_image *out, btf_error *err)
{
    if (!out)
        return btf__fail(err, BTF_E_ARG, "normals preview: no output given");
    memset(out, 0, sizeof *out);
    if (!normals || !normals->data || normals->channels != 3)
        return btf__fail(err, BTF_E_ARG, "normals preview: a 3-channel normal map is needed");
    btf_status rc = btf_image_alloc(out, normals->width, normals->height, 3, err);
    if (rc)
        return rc;
    size_t count = (size_t)normals->width * normals->height;
    for (size_t k = 0; k < count; k++) {
        const float *n = normals->data + 3 * k;
        if (!(n[0] != 0.0f || n[1] != 0.0f || n[2] != 0.0f))
            continue; /* outside the mask: black */
        for (int c = 0; c < 3; c++) {
            float v = isfinite(n[c]) ? 0.5f * (n[c] + 1.0f) : 0.5f;
            /* The PNG writer encodes to sRGB; pre-linearise so the file holds
             * (n + 1) / 2 as the usual normal-map convention wants. */
            out->data[3 * k + c] = btf__srgb_to_linear(v);
        }
    }
    return BTF_OK;
}

/* Slope of the height map along columns / rows at (x, y) by central
 * differences inside the valid set, one-sided at its edge, 0 where
 * isolated. */
static double slope_at(const btf_image *height_map, const unsigned char *inside, int x, int y,
                       int dx, int dy)
{
    int width = height_map->width, rows = height_map->height;
    const float *z = height_map->data;
    int x0 = x - dx, y0 = y - dy, x1 = x + dx, y1 = y + dy;
    int has0 = x0 >= 0 && y0 >= 0 && inside[(size_t)y0 * width + x0];
    int has1 = x1 < width && y1 < rows && inside[(size_t)y1 * width + x1];
    double c = z[(size_t)y * width + x];
    if (has0 && has1)
        return 0.5 * (z[(size_t)y1 * width + x1] - z[(size_t)y0 * width + x0]);
    if (has1)
        return z[(size_t)y1 * width + x1] - c;
    if (has0)
        return c - z[(size_t)y0 * width + x0];
    return 0.0;
}

btf_status btf__height_relief(const btf_image *height, const btf_image *mask, btf_image *out,
                              btf_error *err)
{
    if (!out)
        return btf__fail(err, BTF_E_ARG, "relief: no output given");
    memset(out, 0, sizeof *out);
    if (!height || !height->data || height->channels != 1)
        return btf__fail(err, BTF_E_ARG, "relief: a 1-channel height map is needed");
    int width = height->width, rows = height->height, pixels;
    size_t count = (size_t)width * rows;
    unsigned char *inside = btf__alloc(count, 1, err);
    if (!inside)
        return BTF_E_NOMEM;
    btf_status rc = btf__ps_mask_inside("relief", mask, width, rows, inside, &pixels, err);
    if (rc == BTF_OK)
        rc = btf_image_alloc(out, width, rows, 3, err);
    if (rc) {
        free(inside);
        return rc;
    }
    /* Exaggeration: the mean slope becomes 0.5 whatever the relief's depth,
     * so a nearly flat surface still shows its shape. Tint: height from dark
     * blue-grey (low) to warm white (high) between its extremes. */
    double sum = 0.0, lo = INFINITY, hi = -INFINITY;
    int n = 0;
    for (int y = 0; y < rows; y++)
        for (int x = 0; x < width; x++) {
            size_t k = (size_t)y * width + x;
            if (!inside[k] || !isfinite(height->data[k]))
                continue;
            double gx = slope_at(height, inside, x, y, 1, 0);
            double gy = slope_at(height, inside, x, y, 0, 1);
            sum += sqrt(gx * gx + gy * gy);
            lo = fmin(lo, height->data[k]);
            hi = fmax(hi, height->data[k]);
            n++;
        }
    double mean = n > 0 ? sum / n : 0.0;
    double exaggeration = mean > 1e-12 ? 0.5 / mean : 1.0;
    double span = hi > lo ? hi - lo : 1.0;
    /* Light from the top left, 45 degrees up: (-1, 1, sqrt 2) / 2. */
    const double light[3] = {-0.5, 0.5, 0.70710678118654752};
    for (int y = 0; y < rows; y++)
        for (int x = 0; x < width; x++) {
            size_t k = (size_t)y * width + x;
            if (!inside[k] || !isfinite(height->data[k]))
                continue;
            double gx = exaggeration * slope_at(height, inside, x, y, 1, 0);
            double gy = -exaggeration * slope_at(height, inside, x, y, 0, 1); /* y up */
            double len = sqrt(gx * gx + gy * gy + 1.0);
            double shade = (-gx * light[0] - gy * light[1] + light[2]) / len;
            shade = 0.15 + 0.85 * (shade > 0.0 ? shade : 0.0);
            double t = (height->data[k] - lo) / span;
            const double low[3] = {0.55, 0.62, 0.75}, high[3] = {1.0, 0.97, 0.88};
            for (int c = 0; c < 3; c++) {
                double v = shade * (low[c] + (high[c] - low[c]) * t);
                out->data[3 * k + c] = btf__srgb_to_linear((float)(v > 1.0 ? 1.0 : v));
            }
        }
    free(inside);
    return BTF_OK;
}

