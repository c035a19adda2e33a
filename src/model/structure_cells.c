/*
 * structure_cells.c — the periodic cell of each subspace's remainder
 * (docs/model.md, "Periodic cells"; issue 28, point 4). Where the structure
 * layer's maps repeat on a lattice (a weave, model/structure_lattice.c),
 * the remainder the CAR fields would model after the relief's shading and
 * the albedo pattern are divided out still repeats with it: on the
 * generated fabric 78-90 % of its variance is the lattice's mean cell (the
 * shading the Lambertian fit misses at each thread's edge, the yarns' sheen).
 * A stationary CAR field cannot place that (Haindl & Filip 2007 model
 * textures, not lattices) and turned it into speckle over the weave. So the
 * analysis keeps, per subspace, the remainder's mean over the lattice's
 * cell as three factors per cell texel (mean 1 per channel), taken in the
 * exemplar's own pixels (registering it through the parallax measured
 * worse), where it holds (btf__cells_fit's two tests), divides them out
 * before the CAR fit, and synthesis multiplies them back through the same
 * quilting map as the albedo pattern: the quilting draws only blocks whose
 * offset from their own place is a lattice vector, so a cell texel stays in
 * step across every joint.
 *
 * The cell is the lattice's in Hermite normal form: a lattice of integer
 * vectors has a basis (w, 0), (shift, h) with 0 <= shift < w, so texel
 * (x, y) lies in cell texel ((x - t shift) mod w, y - t h), t = floor(y / h),
 * and the cell has w h = |det| texels.
 */
#include "model/model.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static long floor_mod(long a, long m)
{
    long r = a % m;
    return r < 0 ? r + m : r;
}

static long floor_div(long a, long m)
{
    return (a - floor_mod(a, m)) / m;
}

int btf__cells_from_lattice(const int lattice[4], int *w, int *h, int *shift)
{
    long a0 = lattice[0], a1 = lattice[1], b0 = lattice[2], b1 = lattice[3];
    long det = labs(a0 * b1 - a1 * b0);
    *w = *h = *shift = 0;
    if (det == 0 || det > BTF_CELLS_MAX_TEXELS)
        return 0;
    /* extended Euclid on the vectors' rows: s a1 + t b1 = g = gcd(a1, b1) */
    long r0 = a1, r1 = b1, s0 = 1, s1 = 0, t0 = 0, t1 = 1;
    while (r1 != 0) {
        long q = r0 / r1, tmp = r0 - q * r1;
        r0 = r1, r1 = tmp;
        tmp = s0 - q * s1, s0 = s1, s1 = tmp;
        tmp = t0 - q * t1, t0 = t1, t1 = tmp;
    }
    if (r0 < 0)
        r0 = -r0, s0 = -s0, t0 = -t0;
    long hh = r0, ww = det / hh; /* (ww, 0) is the shortest row-0 vector */
    *w = (int)ww, *h = (int)hh;
    *shift = (int)floor_mod(s0 * a0 + t0 * b0, ww);
    return 1;
}

int btf__cell_index(const btf_cells *c, int x, int y)
{
    long t = floor_div(y, c->h);
    long cx = floor_mod((long)x - t * c->shift, c->w), cy = (long)y - t * c->h;
    return (int)(cy * c->w + cx);
}

void btf__cells_free(btf_cells *c)
{
    if (c)
        BTF_FREE_ALL(c->kept, c->value, c);
}

btf_cells *btf__cells_new(int w, int h, int shift, int n_subspaces, btf_error *err)
{
    if (w < 1 || h < 1 || shift < 0 || shift >= w || (long)w * h > BTF_CELLS_MAX_TEXELS ||
        n_subspaces < 1 || n_subspaces > BTF_MODEL_MAX_SUBSPACES) {
        btf__fail(err, BTF_E_ARG, "periodic cells: %d x %d, shift %d, %d subspaces", w, h,
                  shift, n_subspaces);
        return NULL;
    }
    btf_cells *c = btf__calloc(1, sizeof *c, err);
    if (!c)
        return NULL;
    size_t n = (size_t)n_subspaces * w * h * 3;
    c->w = w, c->h = h, c->shift = shift, c->n_subspaces = n_subspaces;
    c->kept = btf__calloc((size_t)n_subspaces, 1, err);
    c->value = c->kept ? btf__alloc(n, sizeof(float), err) : NULL;
    if (!c->value) {
        btf__cells_free(c);
        return NULL;
    }
    for (size_t i = 0; i < n; i++)
        c->value[i] = 1.0f;
    return c;
}

const float *btf__cells_of(const btf_cells *c, int k)
{
    return c->value + (size_t)k * c->w * c->h * 3;
}

/* The factor of channel ch at exemplar pixel i (its own cell texel). */
static double factor_at(const btf_cells *c, const float *v, int w, size_t i, int ch)
{
    return v[3 * (size_t)btf__cell_index(c, (int)(i % (size_t)w), (int)(i / (size_t)w)) + ch];
}

/* The cell's mean of each channel of img over the pixels in each cell
 * texel, over the channel's mean, each on the albedo pattern's one-byte
 * grid (what the file keeps); 1 where no pixel falls or the channel is
 * black. */
static btf_status cell_means(const btf_image *img, const btf_cells *c, float *v, btf_error *err)
{
    size_t cells = (size_t)c->w * c->h, n = (size_t)img->width * img->height;
    double *sum = btf__calloc(cells * 4, sizeof(double), err), *count = sum ? sum + 3 * cells : NULL;
    if (!sum)
        return BTF_E_NOMEM;
    double mean[3] = {0, 0, 0};
    for (size_t i = 0; i < n; i++) {
        size_t at = (size_t)btf__cell_index(c, (int)(i % (size_t)img->width),
                                            (int)(i / (size_t)img->width));
        count[at] += 1.0;
        for (int ch = 0; ch < 3; ch++) {
            sum[3 * at + ch] += img->data[3 * i + ch];
            mean[ch] += img->data[3 * i + ch];
        }
    }
    for (int ch = 0; ch < 3; ch++)
        mean[ch] /= (double)n;
    for (size_t at = 0; at < cells; at++)
        for (int ch = 0; ch < 3; ch++) {
            double f = count[at] > 0.0 && mean[ch] > 1e-12 ? sum[3 * at + ch] / count[at] / mean[ch]
                                                           : 1.0;
            v[3 * at + ch] = btf__albedo_value(btf__albedo_code((float)f));
        }
    free(sum);
    return BTF_OK;
}

/* The share of img's variance that the cell v explains: img's channel
 * means times the factor against the means alone. */
static double explained_by(const btf_image *img, const btf_cells *c, const float *v)
{
    size_t n = (size_t)img->width * img->height;
    double mean[3] = {0, 0, 0}, total = 0.0, left = 0.0;
    for (size_t i = 0; i < n; i++)
        for (int ch = 0; ch < 3; ch++)
            mean[ch] += img->data[3 * i + ch] / (double)n;
    for (size_t i = 0; i < n; i++)
        for (int ch = 0; ch < 3; ch++) {
            double x = img->data[3 * i + ch], d = x - mean[ch];
            double e = x - mean[ch] * factor_at(c, v, img->width, i, ch);
            total += d * d, left += e * e;
        }
    return total > 0.0 ? 1.0 - left / total : 0.0;
}

btf_status btf__cells_fit(btf_image *img, const btf_image *probe, btf_cells *c, int k,
                          double explained[2], btf_error *err)
{
    explained[0] = explained[1] = 0.0;
    size_t cells = (size_t)c->w * c->h, n = (size_t)img->width * img->height;
    float *v = btf__alloc(cells * 3, sizeof(float), err);
    if (!v)
        return BTF_E_NOMEM;
    btf_status rc = cell_means(img, c, v, err);
    if (rc) {
        free(v);
        return rc;
    }
    explained[0] = explained_by(img, c, v);
    /* a cell serves every pair of its subspace: it must not make the
     * member lit farthest from the exemplar (at the exemplar's view) worse */
    explained[1] = probe && probe->width == img->width && probe->height == img->height
                       ? explained_by(probe, c, v)
                       : explained[0];
    if (explained[0] >= BTF_CELLS_MIN_EXPLAINED && explained[1] >= BTF_CELLS_PROBE_MIN) {
        for (size_t i = 0; i < n; i++)
            for (int ch = 0; ch < 3; ch++)
                img->data[3 * i + ch] = (float)(img->data[3 * i + ch] /
                                                factor_at(c, v, img->width, i, ch));
        memcpy(c->value + (size_t)k * cells * 3, v, cells * 3 * sizeof(float));
        c->kept[k] = 1;
    }
    free(v);
    return BTF_OK;
}

int btf__cells_any(const btf_cells *c)
{
    for (int k = 0; c && k < c->n_subspaces; k++)
        if (c->kept[k])
            return 1;
    return 0;
}
