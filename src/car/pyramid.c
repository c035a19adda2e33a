/*
 * pyramid.c — the Gaussian-Laplacian pyramid of one band (paper section
 * II.C; Burt & Adelson 1983), with the 5-tap binomial kernel [1 4 6 4 1]/16
 * that OpenCV's pyrDown/pyrUp use. Level 0 is the finest; each level halves
 * the size (rounding up); the Laplacian level l is G_l - up(G_{l+1}) and the
 * coarsest level keeps the low-pass G_{L-1}, so collapsing (G_l = L_l +
 * up(G_{l+1})) restores the band exactly.
 *
 * The up-sampling arithmetic is written out (btf_up_even / btf_up_odd in
 * src/synth/btf_shared.h) because synthesis on the CPU and on the GPU must
 * perform the very same float operations. Analysis works in double and mirrors at the
 * borders (reflect-101, as OpenCV does); synthesis never reaches a border.
 */
#include "core/core.h"
#include "car/car.h"

#include <stdlib.h>
#include <string.h>

/* Reflect-101 index into [0, n). */
static int mirror(int i, int n)
{
    if (n == 1)
        return 0;
    while (i < 0 || i >= n) {
        if (i < 0)
            i = -i;
        if (i >= n)
            i = 2 * n - 2 - i;
    }
    return i;
}

btf_status btf__pyr_down(const double *src, int w, int h, double **dst, btf_error *err)
{
    static const double k[5] = {1.0 / 16, 4.0 / 16, 6.0 / 16, 4.0 / 16, 1.0 / 16};
    int w2 = (w + 1) / 2, h2 = (h + 1) / 2;
    double *tmp = btf__alloc((size_t)w2 * h, sizeof(double), err);
    double *out = btf__alloc((size_t)w2 * h2, sizeof(double), err);
    if (!tmp || !out) {
        free(tmp);
        free(out);
        return BTF_E_NOMEM;
    }
    for (int y = 0; y < h; y++) /* horizontal blur, keep even columns */
        for (int x = 0; x < w2; x++) {
            double s = 0.0;
            for (int t = -2; t <= 2; t++)
                s += k[t + 2] * src[(size_t)y * w + mirror(2 * x + t, w)];
            tmp[(size_t)y * w2 + x] = s;
        }
    for (int y = 0; y < h2; y++) /* vertical blur, keep even rows */
        for (int x = 0; x < w2; x++) {
            double s = 0.0;
            for (int t = -2; t <= 2; t++)
                s += k[t + 2] * tmp[(size_t)mirror(2 * y + t, h) * w2 + x];
            out[(size_t)y * w2 + x] = s;
        }
    free(tmp);
    *dst = out;
    return BTF_OK;
}

/* One dimension of pyrUp: fine sample 2i from coarse i-1, i, i+1 (weights
 * 1, 6, 1 over 8); fine sample 2i+1 from coarse i, i+1 (1/2 each). */
static double up_sample(const double *c, int stride, int n, int x)
{
    int i = x >> 1;
    if ((x & 1) == 0)
        return (c[(size_t)mirror(i - 1, n) * stride] + c[(size_t)mirror(i + 1, n) * stride] +
                6.0 * c[(size_t)mirror(i, n) * stride]) * 0.125;
    return (c[(size_t)mirror(i, n) * stride] + c[(size_t)mirror(i + 1, n) * stride]) * 0.5;
}

btf_status btf__pyr_up(const double *src, int w2, int h2, int w, int h, double **dst, btf_error *err)
{
    double *tmp = btf__alloc((size_t)w * h2, sizeof(double), err);
    double *out = btf__alloc((size_t)w * h, sizeof(double), err);
    if (!tmp || !out) {
        free(tmp);
        free(out);
        return BTF_E_NOMEM;
    }
    for (int y = 0; y < h2; y++)
        for (int x = 0; x < w; x++)
            tmp[(size_t)y * w + x] = up_sample(src + (size_t)y * w2, 1, w2, x);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            out[(size_t)y * w + x] = up_sample(tmp + x, w, h2, y);
    free(tmp);
    *dst = out;
    return BTF_OK;
}

void btf__pyramid_free(btf_pyramid *p)
{
    for (int l = 0; l < p->levels; l++)
        free(p->level[l]);
    memset(p, 0, sizeof *p);
}

btf_status btf__pyramid_build(const double *band, int w, int h, int levels, btf_pyramid *p,
                              btf_error *err)
{
    memset(p, 0, sizeof *p);
    if (levels < 1 || levels > BTF_MAX_LEVELS)
        return btf__fail(err, BTF_E_ARG, "pyramid levels %d: expected 1..%d", levels, BTF_MAX_LEVELS);
    double *g = btf__alloc((size_t)w * h, sizeof(double), err);
    if (!g)
        return BTF_E_NOMEM;
    memcpy(g, band, (size_t)w * h * sizeof(double));
    p->levels = levels;
    for (int l = 0; l < levels; l++) {
        p->width[l] = w;
        p->height[l] = h;
        if (l == levels - 1) {
            p->level[l] = g; /* the low-pass residual */
            break;
        }
        double *down, *up;
        btf_status rc = btf__pyr_down(g, w, h, &down, err);
        if (rc == 0) {
            rc = btf__pyr_up(down, (w + 1) / 2, (h + 1) / 2, w, h, &up, err);
            if (rc)
                free(down);
        }
        if (rc) {
            free(g);
            btf__pyramid_free(p);
            return rc;
        }
        for (size_t i = 0; i < (size_t)w * h; i++)
            g[i] -= up[i];
        free(up);
        p->level[l] = g;
        g = down;
        w = (w + 1) / 2;
        h = (h + 1) / 2;
    }
    return BTF_OK;
}

btf_status btf__pyramid_collapse(const btf_pyramid *p, double **out, btf_error *err)
{
    int l = p->levels - 1;
    double *g = btf__alloc((size_t)p->width[l] * p->height[l], sizeof(double), err);
    if (!g)
        return BTF_E_NOMEM;
    memcpy(g, p->level[l], (size_t)p->width[l] * p->height[l] * sizeof(double));
    for (l = p->levels - 2; l >= 0; l--) {
        double *up;
        btf_status rc = btf__pyr_up(g, p->width[l + 1], p->height[l + 1], p->width[l], p->height[l], &up, err);
        free(g);
        if (rc)
            return rc;
        for (size_t i = 0; i < (size_t)p->width[l] * p->height[l]; i++)
            up[i] += p->level[l][i];
        g = up;
    }
    *out = g;
    return BTF_OK;
}
