/*
 * range_map.c — the model's range tile (Haindl & Filip 2007, section II.B:
 * the material's height field, kept in the model as a small periodic tile)
 * enlarged to a seamless map of any size, and the normal map derived from
 * it (docs/render.md, "Range and normal map").
 *
 * The rule: a width x height map holds a whole number of tile periods along
 * each axis, the number nearest width / (tile width x texel) (at least 1),
 * so the tile is stretched or squeezed slightly (by at most half a period
 * over the whole width) and the map wraps exactly. Samples are
 * Catmull-Rom bicubic with wrap-around (C1, so the normals have no creases
 * at texel boundaries, and the tile's own samples are reproduced where
 * they fall). Where one output pixel covers more than one tile texel (a map
 * smaller than a period), K x K sub-samples per pixel are averaged so that
 * the small map is the tile's average, not an alias of it. The filter is
 * separable: one pass along each axis, through a buffer of the smaller of
 * the two intermediate sizes.
 */
#include "core/core.h"
#include "model/model.h"
#include "render/render.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The weights of one output sample along one axis: count consecutive tile
 * indices from first (modulo the tile's length). */
typedef struct axis_taps {
    int count;         /* taps per output sample (the same for all) */
    long *first;       /* [out_len] */
    double *weight;    /* [out_len * count] */
} axis_taps;

static void taps_free(axis_taps *t)
{
    free(t->first);
    free(t->weight);
    t->first = NULL;
    t->weight = NULL;
}

/* Catmull-Rom weights of the samples at floor(c) - 1 .. floor(c) + 2 for
 * fraction f = c - floor(c): they sum to 1, and f = 0 gives (0, 1, 0, 0). */
static void catmull_rom(double f, double w[4])
{
    double f2 = f * f, f3 = f2 * f;
    w[0] = 0.5 * (-f3 + 2.0 * f2 - f);
    w[1] = 0.5 * (3.0 * f3 - 5.0 * f2 + 2.0);
    w[2] = 0.5 * (-3.0 * f3 + 4.0 * f2 + f);
    w[3] = 0.5 * (f3 - f2);
}

/* The number of whole tile periods along an axis of out_len analysed
 * texels: the nearest to out_len / period, at least 1. */
static double whole_periods(int out_len, double period)
{
    double p = floor((double)out_len / period + 0.5);
    /* at most one period per pixel (a tile of texel << 1): such a map is
     * the tile's average */
    return p < 1.0 ? 1.0 : p > out_len ? out_len : p;
}

/* The taps along an axis: out_len output pixels spanning `periods` whole
 * periods of a tile of tile_len texels. Output pixel i covers tile texels
 * [i s, (i + 1) s) with s = periods * tile_len / out_len (texel centres at
 * j + 1/2); k sub-samples at its k centres, each with 4 Catmull-Rom taps. */
static btf_status axis_taps_make(int out_len, int tile_len, double periods, axis_taps *t,
                                 btf_error *err)
{
    double s = periods * (double)tile_len / (double)out_len;
    double kd = ceil(s - 1e-9);
    int k = kd < 1.0 ? 1 : kd > tile_len ? tile_len : (int)kd;
    /* the sub-sample centres of one pixel span less than s, so their
     * floors differ by at most floor(s) + 1 and their taps fit in
     * floor(s) + 5 consecutive indices (4 for a single sample) */
    t->count = k == 1 ? 4 : (int)floor(s) + 5;
    t->first = btf__alloc((size_t)out_len, sizeof *t->first, err);
    t->weight = btf__calloc((size_t)out_len * (size_t)t->count, sizeof *t->weight, err);
    if (!t->first || !t->weight) {
        taps_free(t);
        return BTF_E_NOMEM;
    }
    for (int i = 0; i < out_len; i++) {
        double *w = t->weight + (size_t)i * t->count;
        long first = (long)floor((i + 0.5 / k) * s - 0.5) - 1;
        t->first[i] = first;
        for (int j = 0; j < k; j++) {
            double c = (i + (j + 0.5) / k) * s - 0.5, fl = floor(c), cw[4];
            catmull_rom(c - fl, cw);
            long at = (long)fl - 1 - first;
            for (int q = 0; q < 4; q++)
                if (at + q >= 0 && at + q < t->count) /* always, by the span */
                    w[at + q] += cw[q] / k;
        }
    }
    return BTF_OK;
}

/* One pass along an axis: `lines` lines of the source, each tile_len
 * samples `along` apart (lines `across` apart), into out_len samples per
 * line in dst (same strides form: dst_along, dst_across). */
typedef struct pass {
    const double *src;
    size_t src_along, src_across;
    double *dst;
    size_t dst_along, dst_across;
    int lines, tile_len, out_len;
} pass;

static void run_pass(const pass *p, const axis_taps *t)
{
    for (int l = 0; l < p->lines; l++) {
        const double *line = p->src + (size_t)l * p->src_across;
        double *out = p->dst + (size_t)l * p->dst_across;
        for (int i = 0; i < p->out_len; i++) {
            const double *w = t->weight + (size_t)i * t->count;
            long idx = t->first[i] % p->tile_len;
            idx = idx < 0 ? idx + p->tile_len : idx;
            double acc = 0.0;
            for (int q = 0; q < t->count; q++) {
                acc += w[q] * line[(size_t)idx * p->src_along];
                idx = idx + 1 == p->tile_len ? 0 : idx + 1;
            }
            out[(size_t)i * p->dst_along] = acc;
        }
    }
}

static float finite_float(double v)
{
    return v > FLT_MAX ? FLT_MAX : v < -FLT_MAX ? -FLT_MAX : (float)v;
}

/* The tile (tw x th) resampled to the w x h heights of out, x pass then y
 * pass or the other way round, whichever needs the smaller buffer. */
static btf_status resample(const btf_model *m, int w, int h, btf_image *out, btf_error *err)
{
    int tw = m->range_width, th = m->range_height;
    double texel = m->range_texel;
    axis_taps tx = {0}, ty = {0};
    btf_status rc = axis_taps_make(w, tw, whole_periods(w, tw * texel), &tx, err);
    if (rc == BTF_OK)
        rc = axis_taps_make(h, th, whole_periods(h, th * texel), &ty, err);
    size_t nt = (size_t)tw * th, nb = (size_t)w * th < (size_t)tw * h ? (size_t)w * th
                                                                        : (size_t)tw * h;
    double *tile = rc ? NULL : btf__alloc(nt + nb + (size_t)w * h, sizeof(double), err);
    if (rc || !tile) {
        taps_free(&tx);
        taps_free(&ty);
        return rc ? rc : BTF_E_NOMEM;
    }
    double *buf = tile + nt, *res = buf + nb;
    for (size_t i = 0; i < nt; i++)
        tile[i] = m->range[i];
    if ((size_t)w * th <= (size_t)tw * h) {
        /* rows first: th lines of tw -> w, then w columns of th -> h */
        run_pass(&(pass){tile, 1, (size_t)tw, buf, 1, (size_t)w, th, tw, w}, &tx);
        run_pass(&(pass){buf, (size_t)w, 1, res, (size_t)w, 1, w, th, h}, &ty);
    } else {
        /* columns first: tw lines of th -> h, then h rows of tw -> w */
        run_pass(&(pass){tile, (size_t)tw, 1, buf, (size_t)tw, 1, tw, th, h}, &ty);
        run_pass(&(pass){buf, 1, (size_t)tw, res, 1, (size_t)w, h, tw, w}, &tx);
    }
    for (size_t i = 0; i < (size_t)w * h; i++)
        out->data[i] = finite_float(res[i]);
    free(tile);
    taps_free(&tx);
    taps_free(&ty);
    return BTF_OK;
}

/* A hand-built model's tile is checked here (a model read from a file has
 * been validated already). */
static btf_status check_tile(const btf_model *m, btf_error *err)
{
    if (m->range_width < 1 || m->range_height < 1)
        return btf__fail(err, BTF_E_DATA, "range map: tile of %d x %d texels (expected at least "
                         "1 x 1)", m->range_width, m->range_height);
    if (!isfinite(m->range_texel) || m->range_texel <= 0.0f)
        return btf__fail(err, BTF_E_DATA, "range map: texel %g (expected finite and > 0)",
                         m->range_texel);
    size_t n = (size_t)m->range_width * m->range_height;
    for (size_t i = 0; i < n; i++)
        if (!isfinite(m->range[i]))
            return btf__fail(err, BTF_E_DATA, "range map: height %g at tile texel (%zu, %zu) "
                             "(expected finite heights)", m->range[i], i % (size_t)m->range_width,
                             i / (size_t)m->range_width);
    return BTF_OK;
}

btf_status btf__normal_map(const btf_image *height, double scale, btf_image *normal,
                           btf_error *err)
{
    if (!normal)
        return btf__fail(err, BTF_E_ARG, "normal map: no output image");
    normal->data = NULL;
    normal->width = normal->height = normal->channels = 0;
    if (!height || !height->data || height->channels != 1)
        return btf__fail(err, BTF_E_ARG, "normal map: expected a height map of 1 channel");
    if (!isfinite(scale))
        return btf__fail(err, BTF_E_ARG, "normal map: scale %g (expected finite)", scale);
    int w = height->width, h = height->height;
    for (size_t i = 0; i < (size_t)w * h; i++)
        if (!isfinite(height->data[i]))
            return btf__fail(err, BTF_E_DATA, "normal map: height %g at (%zu, %zu) (expected "
                             "finite heights)", height->data[i], i % (size_t)w, i / (size_t)w);
    btf_status rc = btf_image_alloc(normal, w, h, 3, err);
    if (rc)
        return rc;
    const float *hd = height->data;
    for (int y = 0; y < h; y++) {
        /* the row above (y up the image) and the row below, wrapping */
        const float *up = hd + (size_t)(y == 0 ? h - 1 : y - 1) * w;
        const float *down = hd + (size_t)(y == h - 1 ? 0 : y + 1) * w;
        const float *row = hd + (size_t)y * w;
        float *n = normal->data + (size_t)y * w * 3;
        for (int x = 0; x < w; x++) {
            int xl = x == 0 ? w - 1 : x - 1, xr = x == w - 1 ? 0 : x + 1;
            /* in double: differences of heights near FLT_MAX do not
             * overflow, nor do their squares */
            double dx = 0.5 * scale * ((double)row[xr] - (double)row[xl]);
            double dy = 0.5 * scale * ((double)up[x] - (double)down[x]);
            if (!isfinite(dx) || !isfinite(dy)) {
                /* scale x height beyond double: the steepest finite slope */
                dx = isfinite(dx) ? dx : copysign(DBL_MAX, dx);
                dy = isfinite(dy) ? dy : copysign(DBL_MAX, dy);
            }
            double big = fmax(1.0, fmax(fabs(dx), fabs(dy)));
            double a = -dx / big, b = -dy / big, c = 1.0 / big;
            double len = sqrt(a * a + b * b + c * c);
            n[3 * x] = (float)(a / len);
            n[3 * x + 1] = (float)(b / len);
            n[3 * x + 2] = (float)(c / len);
        }
    }
    return BTF_OK;
}

btf_status btf__structure_maps(const btf_model *m, int width, int height, uint64_t seed,
                               btf_image *height_out, btf_image *normal_out,
                               btf_image *albedo_out, int with_cells, btf_error *err)
{
    btf_image none = {0}, *hm = height_out ? height_out : &none;
    if (height_out)
        *height_out = none;
    if (normal_out)
        *normal_out = none;
    if (albedo_out)
        *albedo_out = none;
    if (!m)
        return btf__fail(err, BTF_E_ARG, "range map: no model");
    if (width < 1 || height < 1)
        return btf__fail(err, BTF_E_ARG, "range map: size %dx%d (expected at least 1x1)", width,
                         height);
    if (m->range) {
        btf_status rc = check_tile(m, err);
        if (rc)
            return rc;
    }
    if (!height_out && !normal_out && !albedo_out)
        return BTF_OK;
    btf_status rc = btf_image_alloc(hm, width, height, 1, err); /* zeros: flat */
    if (rc == BTF_OK && albedo_out)
        rc = btf__image_alloc_any(albedo_out, width, height,
                                  with_cells ? btf__structure_base_channels(m)
                                             : btf__structure_channels(m), err);
    int layers = btf__structure_quilted(m);
    if (rc == BTF_OK && layers) /* one quilting map places both layers */
        rc = btf__structure_layers(m, width, height, seed, hm->data,
                                   albedo_out ? albedo_out->data : NULL, with_cells, err);
    else if (rc == BTF_OK && m->range)
        rc = resample(m, width, height, hm, err);
    for (size_t i = 0; rc == BTF_OK && albedo_out && !layers &&
                       i < (size_t)width * height * albedo_out->channels; i++)
        albedo_out->data[i] = 1.0f; /* a small tile: no structure layer */
    if (rc == BTF_OK && normal_out)
        rc = btf__normal_map(hm, 1.0, normal_out, err);
    if (rc) {
        btf_image_free(hm);
        if (albedo_out)
            btf_image_free(albedo_out);
    }
    if (!height_out)
        btf_image_free(&none);
    return rc;
}

btf_status btf_structure_maps(const btf_model *m, int width, int height, uint64_t seed,
                              btf_image *height_out, btf_image *normal_out,
                              btf_image *albedo_out, btf_error *err)
{
    return btf__structure_maps(m, width, height, seed, height_out, normal_out, albedo_out, 0,
                               err);
}

btf_status btf__range_map(const btf_model *m, int width, int height, btf_image *height_out,
                          btf_image *normal_out, btf_error *err)
{
    return btf_structure_maps(m, width, height, 0, height_out, normal_out, NULL, err);
}
