/*
 * horizon.c — the horizon map of a height field (btf_horizon.h; Max 1988):
 * per texel and direction the steepest rise of the relief within
 * BTF_HORIZON_REACH texels, which the shading turns into cast shadows.
 * Marched on whole texels along the eight directions (the diagonals at
 * sqrt 2 a step), so each sample is a plain lookup; a march stops as soon
 * as the highest point of the map could no longer beat the best rise.
 */
#include "model/model.h"
#include "render/btf_horizon.h"
#include "core/core.h"

#include <math.h>
#include <stdlib.h>

/* Direction d's step in world units (x right, y up) and its length. */
static const int DIR_X[BTF_HORIZON_DIRS] = {1, 1, 0, -1, -1, -1, 0, 1};
static const int DIR_Y[BTF_HORIZON_DIRS] = {0, 1, 1, 1, 0, -1, -1, -1};

typedef struct horizon_job {
    const float *h;
    int w, hh, wrap;
    float top;
    uint32_t *out;
} horizon_job;

static unsigned horizon_code(double t)
{
    double q = floor(t * BTF_HORIZON_PER_UNIT + 0.5);
    return q <= 0.0 ? 0u : q >= 255.0 ? 255u : (unsigned)q;
}

/* The steepest rise from texel (x, y) along direction d. */
static double rise(const horizon_job *j, int x, int y, int d)
{
    double h0 = j->h[(size_t)y * j->w + x], best = 0.0;
    if (!isfinite(h0))
        return 0.0;
    double step = DIR_X[d] && DIR_Y[d] ? 1.41421356237309505 : 1.0;
    for (int k = 1; k <= BTF_HORIZON_REACH; k++) {
        double dist = k * step;
        if ((j->top - h0) / dist <= best)
            break; /* nothing further can rise more steeply */
        int u = x + k * DIR_X[d], v = y - k * DIR_Y[d]; /* world y up: rows go up */
        if (j->wrap) {
            u = ((u % j->w) + j->w) % j->w;
            v = ((v % j->hh) + j->hh) % j->hh;
        } else if (u < 0 || v < 0 || u >= j->w || v >= j->hh) {
            break; /* beyond the sample: nothing known */
        }
        double t = (j->h[(size_t)v * j->w + u] - h0) / dist;
        best = t > best ? t : best;
    }
    return best;
}

static btf_status horizon_row(void *user, int y, int worker, btf_error *err)
{
    (void)worker, (void)err;
    const horizon_job *j = user;
    for (int x = 0; x < j->w; x++) {
        uint32_t w[2] = {0, 0};
        for (int d = 0; d < BTF_HORIZON_DIRS; d++)
            w[d / 4] |= (uint32_t)horizon_code(rise(j, x, y, d)) << (8 * (d % 4));
        j->out[2 * ((size_t)y * j->w + x)] = w[0];
        j->out[2 * ((size_t)y * j->w + x) + 1] = w[1];
    }
    return BTF_OK;
}

btf_status btf__horizon_map(const float *h, int w, int hh, int wrap, int threads,
                            uint32_t **out, btf_error *err)
{
    *out = NULL;
    if (!h || w < 1 || hh < 1)
        return btf__fail(err, BTF_E_ARG, "horizon map: no heights or size %dx%d", w, hh);
    size_t n = (size_t)w * hh;
    uint32_t *o = btf__alloc(n, 2 * sizeof(uint32_t), err);
    if (!o)
        return BTF_E_NOMEM;
    float top = -INFINITY;
    for (size_t i = 0; i < n; i++)
        top = isfinite(h[i]) && h[i] > top ? h[i] : top;
    if (!isfinite(top))
        top = 0.0f;
    horizon_job j = {h, w, hh, wrap, top, o};
    btf_status rc = btf__pool_run(hh, threads, horizon_row, &j, NULL, err);
    if (rc) {
        free(o);
        return rc;
    }
    *out = o;
    return BTF_OK;
}
