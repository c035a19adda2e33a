/*
 * range_periodic.c — the range tile made periodic: the periodic component
 * of Moisan's periodic-plus-smooth decomposition (L. Moisan, "Periodic plus
 * smooth image decomposition", J. Math. Imaging Vis. 39(2), 2011), u = p + s.
 *
 * Why this one (docs/render.md, "Range and normal map"): the photometric-
 * stereo height map of paper section II.B is not periodic; its periodic
 * extension jumps at the tile's edges, and integration drift adds a slow
 * bend that makes the jumps large. s is the smoothest image that carries
 * exactly those jumps (a harmonic field, no texture in it) and p = u - s
 * keeps all the surface detail (p has u's discrete Laplacian everywhere
 * inside, and u's mean) while its periodic extension has no jump beyond
 * the surface's own slope. Blending or quilting a tile would instead lose
 * or repeat detail near the edges, and the tile is small (64 texels).
 *
 * First the tile's mean slope is removed (a plane through its centre, so
 * the mean stays): a periodic surface has none (its steps around a period
 * sum to zero), a flat material sample has none either (a tilt is the
 * sample's mounting or integration bias), and Moisan's p alone would keep
 * most of it as a cliff at the wrap (for a ramp of slope a over w texels,
 * p's steps are a / w inside and a (1 - w) / w across the wrap: p is the
 * least-squares fit to u's steps, and a ramp's steps cannot be periodic).
 *
 * Computation (Moisan, section 2): the boundary image v holds the jumps of
 * u across opposite edges, v(x, 0) = u(x, h-1) - u(x, 0), v(x, h-1) =
 * u(x, 0) - u(x, h-1), the same along columns (summed at the corners);
 * s solves the periodic Poisson equation (sum of the 4 neighbours - 4 s) = v,
 * diagonal in the DFT: S(q, r) = V(q, r) / (2 cos(2 pi q / h) + 2 cos(2 pi
 * r / w) - 4), S(0, 0) = 0 (s has zero mean, so p keeps u's).
 */
#include "io/io.h"
#include "model/model.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define RP_PI 3.14159265358979323846

/* The boundary image v of Moisan's decomposition of u into re (zeroed
 * first). */
static void boundary_image(const double *u, int w, int h, double *re)
{
    memset(re, 0, (size_t)w * h * sizeof *re);
    for (int y = 0; y < h; y++) {
        const double *row = u + (size_t)y * w;
        double jump = row[w - 1] - row[0];
        re[(size_t)y * w] += jump;
        re[(size_t)y * w + w - 1] -= jump;
    }
    const double *top = u, *bottom = u + (size_t)(h - 1) * w;
    for (int x = 0; x < w; x++) {
        double jump = bottom[x] - top[x];
        re[x] += jump;
        re[(size_t)(h - 1) * w + x] -= jump;
    }
}

/* Removes the tile's mean slope: the mean of its steps along each axis,
 * times the distance from the centre (a plane of zero mean). */
static void remove_mean_slope(double *u, int w, int h)
{
    double gx = 0.0, gy = 0.0;
    for (int y = 0; y < h && w > 1; y++)
        gx += (u[(size_t)y * w + w - 1] - u[(size_t)y * w]) / (w - 1);
    for (int x = 0; x < w && h > 1; x++)
        gy += (u[(size_t)(h - 1) * w + x] - u[x]) / (h - 1);
    gx /= h, gy /= w;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            u[(size_t)y * w + x] -= gx * (x - 0.5 * (w - 1)) + gy * (y - 0.5 * (h - 1));
}

/* The float nearest v within the finite range: heights near FLT_MAX may
 * move past it by the decomposition's rounding. */
static float finite_float(double v)
{
    return v > FLT_MAX ? FLT_MAX : v < -FLT_MAX ? -FLT_MAX : (float)v;
}

btf_status btf_range_make_periodic(float *heights, int width, int height, btf_error *err)
{
    if (!heights || width < 1 || height < 1)
        return btf_fail(err, BTF_E_ARG, "range tile: %d x %d heights%s (expected at least 1 x 1)",
                        width, height, heights ? "" : " at NULL");
    size_t n = (size_t)width * height;
    for (size_t i = 0; i < n; i++)
        if (!isfinite(heights[i]))
            return btf_fail(err, BTF_E_DATA, "range tile: height %g at (%zu, %zu) (expected finite "
                            "heights)", heights[i], i % (size_t)width, i / (size_t)width);
    if (n == 1)
        return BTF_OK; /* a single sample is periodic */
    double *u = btf_alloc(n * 3, sizeof(double), err);
    if (!u)
        return BTF_E_NOMEM;
    double *re = u + n, *im = re + n;
    for (size_t i = 0; i < n; i++)
        u[i] = heights[i];
    remove_mean_slope(u, width, height);
    boundary_image(u, width, height, re);
    memset(im, 0, n * sizeof *im);
    char msg[256];
    if (btfcv_dft2(re, im, width, height, 0, msg, sizeof msg) != 0) {
        free(u);
        return btf_fail(err, BTF_E_NUMERIC, "range tile: DFT failed: %s", msg);
    }
    for (int q = 0; q < height; q++) {
        double cq = 2.0 * cos(2.0 * RP_PI * q / height);
        for (int r = 0; r < width; r++) {
            size_t k = (size_t)q * width + r;
            double den = cq + 2.0 * cos(2.0 * RP_PI * r / width) - 4.0;
            /* den < 0 off the origin: at least 2 - 2 cos(2 pi / side). */
            double f = (q == 0 && r == 0) ? 0.0 : 1.0 / den;
            re[k] *= f;
            im[k] *= f;
        }
    }
    if (btfcv_dft2(re, im, width, height, 1, msg, sizeof msg) != 0) {
        free(u);
        return btf_fail(err, BTF_E_NUMERIC, "range tile: inverse DFT failed: %s", msg);
    }
    for (size_t i = 0; i < n; i++)
        heights[i] = finite_float(u[i] - re[i]);
    free(u);
    return BTF_OK;
}
