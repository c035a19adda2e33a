/*
 * structure_map.c — the model's measured structure (the range map and the
 * albedo pattern at the analysed resolution, docs/model.md "Structure")
 * placed on a surface of any size by image quilting (Efros & Freeman 2001;
 * the paper's "image tiling" of the range map, Haindl & Filip 2007,
 * section III). One coordinate map per (size, seed) places every layer, so
 * the heights, the normals and the albedo pattern stay registered, and the
 * map is on a torus (src/rf/rf_quilt.c: the last block of a row overlaps
 * the first along a minimum-error cut), so the surface tiles without a
 * seam. The sample keeps its own place: a surface of the sample's size is
 * the measured structure itself, and a larger one holds it once, joined to
 * drawn blocks around it.
 */
#include "model/model.h"
#include "rf/rf_sample.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Blocks of at most this side (texels), overlapping by a sixth: large
 * enough to carry several cells of a leather, a few threads of a weave. */
#define STRUCT_BLOCK_MAX 48
/* Candidate positions drawn per block: the work per block is bounded, so a
 * 2048^2 surface quilts in well under a second. */
#define STRUCT_CANDIDATES 96
/* A surface side beyond this repeats a period of at most this many texels
 * (a divisor of the side, so a tileable image still wraps). */
#define STRUCT_PERIOD_MAX 2048
#define STRUCT_PERIOD_MIN 512
/* The quilting map's own seed stream, apart from the fields'. */
#define STRUCT_SEED_SALT 0x5354524355435455ull

int btf__structure_quilted(const btf_model *m)
{
    return m && m->range && m->range_texel == 1.0f && m->range_width > 0 &&
           m->range_height > 0;
}

int btf__structure_period(int n)
{
    if (n <= STRUCT_PERIOD_MAX)
        return n;
    for (int d = STRUCT_PERIOD_MAX; d >= STRUCT_PERIOD_MIN; d--)
        if (n % d == 0)
            return d;
    return n;
}

/* Mean and standard deviation of n values (sd 1 when flat). */
static void moments(const float *v, size_t n, size_t stride, double *mean, double *sd)
{
    double s = 0.0, ss = 0.0;
    for (size_t i = 0; i < n; i++)
        s += v[i * stride];
    *mean = n ? s / (double)n : 0.0;
    for (size_t i = 0; i < n; i++) {
        double d = v[i * stride] - *mean;
        ss += d * d;
    }
    *sd = n && ss > 0.0 ? sqrt(ss / (double)n) : 1.0;
    if (!(*sd > 1e-12) || !isfinite(*sd))
        *sd = 1.0;
}

/* The quilting features: normalised height, normalised log albedo, and the
 * height's local slope magnitude (the grooves' walls), each of unit
 * spread so that none dominates the overlap error. */
static btf_status features(const btf_model *m, float **out, btf_error *err)
{
    int w = m->range_width, h = m->range_height;
    size_t n = (size_t)w * h;
    float *f = btf__alloc(n, RF_FEATURES * sizeof(float), err);
    if (!f)
        return BTF_E_NOMEM;
    for (size_t i = 0; i < n; i++) {
        int x = (int)(i % (size_t)w), y = (int)(i / (size_t)w);
        const float *row = m->range + (size_t)y * w;
        float gx = row[x + 1 < w ? x + 1 : x] - row[x > 0 ? x - 1 : x];
        float gy = m->range[(size_t)(y + 1 < h ? y + 1 : y) * w + x] -
                   m->range[(size_t)(y > 0 ? y - 1 : y) * w + x];
        f[RF_FEATURES * i] = m->range[i];
        f[RF_FEATURES * i + 1] = m->albedo ? logf(m->albedo[i]) : 0.0f;
        f[RF_FEATURES * i + 2] = sqrtf(gx * gx + gy * gy);
    }
    for (int c = 0; c < RF_FEATURES; c++) {
        double mean, sd;
        moments(f + c, n, RF_FEATURES, &mean, &sd);
        for (size_t i = 0; i < n; i++)
            f[RF_FEATURES * i + c] = (float)((f[RF_FEATURES * i + c] - mean) / sd);
    }
    *out = f;
    return BTF_OK;
}

btf_status btf__structure_coords(const btf_model *m, int pw, int ph, uint64_t seed,
                                 uint16_t **map, btf_error *err)
{
    *map = NULL;
    if (!btf__structure_quilted(m))
        return btf__fail(err, BTF_E_ARG, "structure map: the model has no range map at the "
                         "analysed resolution");
    if (pw < 1 || ph < 1)
        return btf__fail(err, BTF_E_ARG, "structure map: size %dx%d", pw, ph);
    int sw = m->range_width, sh = m->range_height;
    int side = sw < sh ? sw : sh;
    int block = side < STRUCT_BLOCK_MAX ? side : STRUCT_BLOCK_MAX;
    float *feat = NULL;
    btf_status rc = features(m, &feat, err);
    uint16_t *out = rc ? NULL : btf__alloc((size_t)pw * ph, 2 * sizeof(uint16_t), err);
    if (!rc && !out)
        rc = BTF_E_NOMEM;
    if (rc == BTF_OK) {
        rf_quilt_args q = {feat, sw, 0, 0, sw, sh, pw, ph, block, block / 6, 0.0,
                           seed ^ STRUCT_SEED_SALT, 1, STRUCT_CANDIDATES, {0, 0, 0, 0}};
        btf__structure_lattice(m, q.lattice); /* a weave's repeat, kept in step */
        rc = rf_quilt(&q, out, err);
    }
    free(feat);
    if (rc) {
        free(out);
        return rc;
    }
    *map = out;
    return BTF_OK;
}

int btf__structure_channels(const btf_model *m)
{
    return m && m->albedo && m->chroma ? 3 : 1;
}

/* The periodic cells a pattern carries: those of a model that keeps one. */
static const btf_cells *pattern_cells(const btf_model *m)
{
    const btf_cells *c = m && m->albedo ? btf__model_cells(m) : NULL;
    return btf__cells_any(c) ? c : NULL;
}

int btf__structure_base_channels(const btf_model *m)
{
    return pattern_cells(m) ? 4 : btf__structure_channels(m);
}

btf_status btf__structure_albedo(const btf_model *m, int width, int height, uint64_t seed,
                                 btf_image *out, btf_error *err)
{
    memset(out, 0, sizeof *out);
    /* the period's own map is the whole surface's (its period is itself) */
    int pw = btf__structure_period(width), ph = btf__structure_period(height);
    btf_status rc = btf__image_alloc_any(out, pw, ph, btf__structure_base_channels(m), err);
    if (rc == BTF_OK)
        rc = btf__structure_layers(m, pw, ph, seed, NULL, out->data, 1, err);
    if (rc)
        btf_image_free(out);
    return rc;
}

btf_status btf__structure_pattern(const btf_model *m, int width, int height, uint64_t seed,
                                  btf_image *cache, btf_error *err)
{
    if (cache->data && cache->width == btf__structure_period(width) &&
        cache->height == btf__structure_period(height))
        return BTF_OK;
    btf_image_free(cache); /* another size: another map */
    return btf__structure_albedo(m, width, height, seed, cache, err);
}

/* Row y of the periodic albedo pattern a (pw x ph, grey or RGB) over width
 * texels times the RGB row, in place: one multiply per channel, the same on every
 * path (the CPU's rows, the GPU's read-back). */
void btf__structure_apply_row(const btf_image *a, int y, float *rgb, int width)
{
    int ch = a->channels == 3 ? 3 : 1;
    const float *row = a->data + (size_t)(y % a->height) * a->width * ch;
    for (int x = 0, px = 0; x < width; x++, px = px + 1 == a->width ? 0 : px + 1) {
        const float *f = row + (size_t)px * ch;
        rgb[3 * x] = rgb[3 * x] * f[0];
        rgb[3 * x + 1] = rgb[3 * x + 1] * f[ch == 3 ? 1 : 0];
        rgb[3 * x + 2] = rgb[3 * x + 2] * f[ch == 3 ? 2 : 0];
    }
}

btf_status btf__structure_apply(const btf_model *m, int subspace, uint64_t seed, btf_image *img,
                                btf_image *cache, btf_error *err)
{
    if (!m->albedo || !btf__structure_quilted(m))
        return BTF_OK;
    btf_image own = {0}, *a = cache ? cache : &own;
    btf_status rc = btf__structure_pattern(m, img->width, img->height, seed, a, err);
    for (int y = 0; rc == BTF_OK && y < img->height; y++)
        btf__structure_apply_row_for(m, subspace, a, y, img->data + (size_t)y * img->width * 3,
                                     img->width);
    btf_image_free(&own);
    return rc;
}

btf_status btf__structure_layers(const btf_model *m, int width, int height, uint64_t seed,
                                 float *heights, float *albedo, int with_cells, btf_error *err)
{
    uint16_t *map;
    int pw = btf__structure_period(width), ph = btf__structure_period(height);
    const btf_cells *cells = with_cells ? pattern_cells(m) : NULL;
    int ch = btf__structure_channels(m);
    btf_status rc = btf__structure_coords(m, pw, ph, seed, &map, err);
    if (rc)
        return rc;
    /* the period's heights with the quilting's joins relaxed */
    float *period = heights ? btf__alloc((size_t)pw * ph, sizeof(float), err) : NULL;
    if (heights && (!period || (rc = btf__structure_heights(m, map, pw, ph, period, err)))) {
        BTF_FREE_ALL(map, period);
        return period ? rc : BTF_E_NOMEM;
    }
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++) {
            size_t i = (size_t)(y % ph) * pw + (size_t)(x % pw), o = (size_t)y * width + x;
            size_t src = (size_t)map[2 * i + 1] * m->range_width + map[2 * i];
            if (heights)
                heights[o] = period[i];
            if (albedo && cells) { /* RGB, then the cell index (exact in a float) */
                for (int c = 0; c < 3; c++)
                    albedo[4 * o + c] = ch == 3 ? m->albedo[src] * m->chroma[3 * src + c]
                                                : m->albedo[src];
                albedo[4 * o + 3] = (float)btf__cell_index(cells, map[2 * i], map[2 * i + 1]);
            } else if (albedo && ch == 3)
                for (int c = 0; c < 3; c++)
                    albedo[3 * o + c] = m->albedo[src] * m->chroma[3 * src + c];
            else if (albedo)
                albedo[o] = m->albedo ? m->albedo[src] : 1.0f;
        }
    BTF_FREE_ALL(map, period);
    return BTF_OK;
}

/* The factors of cell texel index (channel 3 of a base pattern) of subspace
 * k, or NULL (no cell, or an index outside the cell). */
static const float *cell_factor(const btf_cells *c, int k, float index)
{
    if (!c || k < 0 || k >= c->n_subspaces || !c->kept[k] || !(index >= 0.0f) ||
        index >= (float)c->w * (float)c->h)
        return NULL;
    return btf__cells_of(c, k) + 3 * (size_t)index;
}

void btf__structure_apply_row_for(const btf_model *m, int k, const btf_image *a, int y,
                                  float *rgb, int width)
{
    if (a->channels != 4) {
        btf__structure_apply_row(a, y, rgb, width);
        return;
    }
    const btf_cells *c = btf__model_cells(m);
    const float *row = a->data + (size_t)(y % a->height) * a->width * 4;
    for (int x = 0, px = 0; x < width; x++, px = px + 1 == a->width ? 0 : px + 1) {
        const float *b = row + (size_t)px * 4, *f = cell_factor(c, k, b[3]);
        for (int ch = 0; ch < 3; ch++) { /* the product first: btf__structure_for's bits */
            float p = f ? b[ch] * f[ch] : b[ch];
            rgb[3 * x + ch] = rgb[3 * x + ch] * p;
        }
    }
}

btf_status btf__structure_for(const btf_model *m, int k, const btf_image *base, btf_image *tmp,
                              const btf_image **use, btf_error *err)
{
    *use = base;
    if (!base || base->channels != 4)
        return BTF_OK;
    const btf_cells *c = btf__model_cells(m);
    btf_status rc = btf_image_alloc(tmp, base->width, base->height, 3, err);
    if (rc)
        return rc;
    size_t n = (size_t)base->width * base->height;
    for (size_t i = 0; i < n; i++) {
        const float *b = base->data + 4 * i, *f = cell_factor(c, k, b[3]);
        for (int ch = 0; ch < 3; ch++)
            tmp->data[3 * i + ch] = f ? b[ch] * f[ch] : b[ch];
    }
    *use = tmp;
    return BTF_OK;
}
