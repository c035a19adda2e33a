/*
 * periodic.c — the periodic component of an image (L. Moisan, "Periodic
 * plus smooth image decomposition", J. Math. Imaging Vis. 39, 2011): the
 * DFT sees an image as one tile of a periodic plane, and the jumps between
 * its opposite borders put a cross of false power along both frequency
 * axes. u = p + s, with s smooth (its discrete Laplacian is the boundary
 * image v below) and p periodic without those jumps; p's spectrum is the
 * texture's. In the DFT domain s^(q, r) = v^(q, r) / (2 cos(2 pi q / w) +
 * 2 cos(2 pi r / h) - 4), s^(0, 0) = 0, so p keeps u's mean.
 */
#include "core/core.h"
#include "io/io.h"
#include "measure/measure.h"

#include <math.h>
#include <stdlib.h>

btf_status ms_periodic_component(double *u, int w, int h, btf_error *err)
{
    size_t n = (size_t)w * h;
    double *re = btf__calloc(2 * n, sizeof(double), err);
    if (!re)
        return BTF_E_NOMEM;
    double *im = re + n;
    /* v: the jump across each border, on both sides of it. */
    for (int x = 0; x < w; x++) {
        double jump = u[(size_t)(h - 1) * w + x] - u[x];
        re[x] += jump;
        re[(size_t)(h - 1) * w + x] -= jump;
    }
    for (int y = 0; y < h; y++) {
        double jump = u[(size_t)y * w + w - 1] - u[(size_t)y * w];
        re[(size_t)y * w] += jump;
        re[(size_t)y * w + w - 1] -= jump;
    }
    char why[256];
    if (btfcv_dft2(re, im, w, h, 0, why, sizeof why) != 0) {
        free(re);
        return btf__fail(err, BTF_E_UNSUPPORTED, "periodic component: DFT failed: %s", why);
    }
    for (int r = 0; r < h; r++)
        for (int q = 0; q < w; q++) {
            size_t i = (size_t)r * w + q;
            double den = 2.0 * cos(2.0 * M_PI * q / w) + 2.0 * cos(2.0 * M_PI * r / h) - 4.0;
            if (i == 0 || den == 0.0) {
                re[i] = im[i] = 0.0;
            } else {
                re[i] /= den;
                im[i] /= den;
            }
        }
    if (btfcv_dft2(re, im, w, h, 1, why, sizeof why) != 0) {
        free(re);
        return btf__fail(err, BTF_E_UNSUPPORTED, "periodic component: DFT failed: %s", why);
    }
    for (size_t i = 0; i < n; i++)
        u[i] -= re[i];
    free(re);
    return BTF_OK;
}
