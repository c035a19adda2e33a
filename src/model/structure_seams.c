/*
 * structure_seams.c — the quilted range map's joins, relaxed in the
 * gradient domain (docs/render.md, "The structure map (texel 1)").
 *
 * Image quilting (Efros & Freeman 2001) joins blocks along a minimum-error
 * cut: the cut runs where the two blocks' features differ least, but where
 * they still differ the heights step. On the generated leather (128^2
 * measured, quilted to 256^2) 0.2 % of neighbouring texels differed by more
 * than 0.8 texel heights, up to 1.3, where the measured range map has no
 * step above 0.8: a groove's wall cut in two, a ridge ending in a ledge.
 * The normals are the heights' differences, so under grazing light each
 * step is a bright or dark line the material does not have.
 *
 * The cure is Poisson image editing's (Perez, Gangnet & Blake 2003): keep
 * every difference between two texels whose sources are neighbours in the
 * range grid (the measured difference), give each pair across a join the
 * mean of the two sources' own differences in that direction, and solve
 * for the heights that best have those differences — only near the joins
 * (within SEAM_REACH texels; the rest keeps the measured heights), by
 * successive over-relaxation, a fixed number of sweeps in a fixed order, so
 * that the result is deterministic and the same for the CPU and GPU
 * renders (both take the heights from here). Sources adjacent on the range
 * grid's torus count as neighbours, so that a surface of the sample's own
 * size, the identity map, is the measured range map unchanged.
 */
#include "model/model.h"
#include "model/range_code.h"

#include <math.h>
#include <stdlib.h>

/* How far from a join the heights may move (texels): a step s becomes a
 * ramp of about s / (2 SEAM_REACH + 1) per texel. */
#define SEAM_REACH 4
#define SEAM_SWEEPS 24 /* 96 sweeps moved no height by more than 0.022 texel more */
#define SEAM_OMEGA 1.7

typedef struct seam_grid {
    const float *range;      /* the model's range grid, sw x sh */
    int sw, sh;
    const uint16_t *map;     /* the quilting map */
    double unit;             /* heights are relaxed in units of the largest
                                magnitude: no float overflows near FLT_MAX */
} seam_grid;

/* The measured difference at source (x, y) towards (dx, dy) (one of them
 * 1), forward where the grid has the next texel, else backward. */
static double src_diff(const seam_grid *g, int x, int y, int dx, int dy)
{
    const float *r = g->range;
    size_t s = (size_t)y * g->sw + x;
    if (x + dx < g->sw && y + dy < g->sh)
        return ((double)r[s + (size_t)dy * g->sw + dx] - r[s]) / g->unit;
    if (x < dx || y < dy) /* a grid one texel across that way: flat */
        return 0.0;
    return ((double)r[s] - r[s - (size_t)dy * g->sw - dx]) / g->unit;
}

/* The wanted difference h[j] - h[i] for the torus neighbour j of i at
 * (dx, dy); *join set when their sources are not neighbours on the range
 * grid's torus. */
static double wanted(const seam_grid *g, size_t i, size_t j, int dx, int dy, int *join)
{
    int xi = g->map[2 * i], yi = g->map[2 * i + 1];
    int xj = g->map[2 * j], yj = g->map[2 * j + 1];
    int nx = xi + dx == g->sw ? 0 : xi + dx, ny = yi + dy == g->sh ? 0 : yi + dy;
    *join = !(xj == nx && yj == ny);
    if (!*join)
        return ((double)g->range[(size_t)yj * g->sw + xj] - g->range[(size_t)yi * g->sw + xi]) /
               g->unit;
    return 0.5 * (src_diff(g, xi, yi, dx, dy) + src_diff(g, xj, yj, dx, dy));
}

/* out[k] = whether any of in[k - SEAM_REACH .. k + SEAM_REACH] (indices
 * modulo len, stride apart) is set: a sliding count. */
static void dilate_line(const uint8_t *in, uint8_t *out, int len, size_t stride)
{
    int reach = SEAM_REACH < len / 2 ? SEAM_REACH : (len - 1) / 2, count = 0;
    for (int d = -reach; d <= reach; d++)
        count += in[(size_t)((d + len) % len) * stride];
    for (int k = 0; k < len; k++) {
        out[(size_t)k * stride] = count > 0;
        int leave = k - reach, enter = k + reach + 1;
        leave = leave < 0 ? leave + len : leave;
        enter = enter >= len ? enter - len : enter;
        count += in[(size_t)enter * stride] - in[(size_t)leave * stride];
    }
}

/* Marks the texels within SEAM_REACH (a square) of a join's texel, on the
 * torus: a row pass into tmp, then a column pass back. */
static void dilate(uint8_t *mark, uint8_t *tmp, int w, int h)
{
    for (int y = 0; y < h; y++)
        dilate_line(mark + (size_t)y * w, tmp + (size_t)y * w, w, 1);
    for (int x = 0; x < w; x++)
        dilate_line(tmp + x, mark + x, h, (size_t)w);
}

/* One texel's update: the mean of what its four neighbours say it should
 * be (h[j] less the wanted difference h[j] - h[i]), over-relaxed. */
static void relax_texel(double *h, const float *right, const float *down, size_t i, size_t l,
                        size_t r, size_t u, size_t d)
{
    double target = 0.25 * ((h[l] + right[l]) + (h[r] - right[i]) + (h[u] + down[u]) +
                            (h[d] - down[i]));
    h[i] += SEAM_OMEGA * (target - h[i]);
}

/* Successive over-relaxation on the marked texels, red-black (the texels
 * with x + y even, then the odd ones: no update in a pass reads another's,
 * but across the wrap of an odd period, so the passes run at the memory's
 * pace, not the additions' latency), a fixed number of sweeps in a fixed
 * order (deterministic); the marked runs of each row listed once. */
static btf_status relax(double *h, const float *right, const float *down, const uint8_t *mark,
                        int pw, int ph, btf_error *err)
{
    size_t n = (size_t)pw * ph, runs = 0;
    for (size_t i = 0; i < n; i++)
        runs += mark[i] && (i % (size_t)pw == 0 || !mark[i - 1]);
    size_t *run = btf__alloc(runs ? runs : 1, 2 * sizeof(size_t), err); /* start, end */
    if (!run)
        return BTF_E_NOMEM;
    size_t k = 0;
    for (size_t i = 0; i < n; i++)
        if (mark[i] && (i % (size_t)pw == 0 || !mark[i - 1])) {
            size_t e = i + 1;
            while (e % (size_t)pw != 0 && mark[e])
                e++;
            run[2 * k] = i, run[2 * k + 1] = e, k++;
        }
    for (int pass = 0; pass < 2 * SEAM_SWEEPS; pass++) /* red, black, red, ... */
        for (size_t q = 0; q < runs; q++) {
            size_t i0 = run[2 * q], i1 = run[2 * q + 1];
            size_t y = i0 / (size_t)pw, row = y * pw;
            size_t up = (y > 0 ? y - 1 : (size_t)ph - 1) * pw;
            size_t dn = (y + 1 < (size_t)ph ? y + 1 : 0) * pw;
            size_t first = i0 + (((i0 - row) + y + (size_t)pass) & 1);
            for (size_t i = first; i < i1; i += 2) {
                size_t x = i - row;
                size_t l = x > 0 ? i - 1 : row + pw - 1, r = x + 1 < (size_t)pw ? i + 1 : row;
                relax_texel(h, right, down, i, l, r, up + x, dn + x);
            }
        }
    free(run);
    return BTF_OK;
}

/* The range grid's extremes, and the unit the relaxation works in. */
static void extremes(const btf_model *m, float *lo, float *hi, double *unit)
{
    btf__range_extremes(m->range, (size_t)m->range_width * m->range_height, lo, hi);
    double big = fmax(fabs((double)*lo), fabs((double)*hi));
    *unit = big > 0.0 ? big : 1.0;
}

btf_status btf__structure_heights(const btf_model *m, const uint16_t *map, int pw, int ph,
                                  float *out, btf_error *err)
{
    seam_grid g = {m->range, m->range_width, m->range_height, map, 1.0};
    float lo, hi;
    extremes(m, &lo, &hi, &g.unit);
    size_t n = (size_t)pw * ph;
    double *h = btf__alloc(n, sizeof(double), err);
    float *right = h ? btf__alloc(n, 2 * sizeof(float), err) : NULL;
    uint8_t *mark = right ? btf__calloc(n, 2, err) : NULL; /* near a join; scratch */
    if (!mark) {
        BTF_FREE_ALL(h, right);
        return BTF_E_NOMEM;
    }
    float *down = right + n;
    int joins = 0;
    for (int y = 0; y < ph; y++)
        for (int x = 0; x < pw; x++) {
            size_t i = (size_t)y * pw + x;
            size_t r = (size_t)y * pw + (size_t)(x + 1 < pw ? x + 1 : 0);
            size_t d = (size_t)(y + 1 < ph ? y + 1 : 0) * pw + x;
            int jr, jd;
            h[i] = m->range[(size_t)map[2 * i + 1] * g.sw + map[2 * i]] / g.unit;
            right[i] = (float)wanted(&g, i, r, 1, 0, &jr);
            down[i] = (float)wanted(&g, i, d, 0, 1, &jd);
            if (jr)
                mark[i] = mark[r] = 1;
            if (jd)
                mark[i] = mark[d] = 1;
            joins |= jr || jd;
        }
    if (joins)
        dilate(mark, mark + n, pw, ph);
    btf_status rc = joins ? relax(h, right, down, mark, pw, ph, err) : BTF_OK;
    /* away from the joins the measured heights as they are; near them the
     * relaxed ones, within the measured range (over-relaxation may
     * overshoot, and no new extreme is measured) */
    for (size_t i = 0; i < n; i++) {
        float v = m->range[(size_t)map[2 * i + 1] * g.sw + map[2 * i]];
        if (mark[i]) {
            double r = h[i] * g.unit;
            v = r < lo ? lo : r > hi ? hi : (float)r;
        }
        out[i] = v;
    }
    BTF_FREE_ALL(h, right, mark);
    return rc;
}
