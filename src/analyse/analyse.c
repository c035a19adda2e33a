/*
 * analyse.c — the whole analysis of a BTF dataset into one model (paper
 * section II): stage 1 segments the (view, light) space into K subspace
 * images (II.A, segment/segment.c); stage 2 recovers the range map by
 * photometric stereo on the view closest to the normal (II.B,
 * range/photostereo.c) and keeps it as a small tile, averaged here; stage 3
 * models each subspace image with the multi-scale colour CAR model (II.C,
 * analyse/subspace_fit.c).
 */
#include <stdio.h>
#include "analyse/analyse.h"
#include "car/car.h"
#include "core/core.h"
#include "dataset/dataset.h"
#include "model/model.h"
#include "model/range_code.h"
#include "range/range.h"
#include "segment/segment.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Heights at the analysed resolution are kept to 1/RANGE_STEPS texel:
 * finer steps are below what photometric stereo recovers and cost a byte
 * a texel more in the model file (docs/model-format.md, "RANG"). */
#define RANGE_STEPS 32.0

/* The range tile's grid: one tile texel is p/q image pixels along both
 * axes (a rational, so that binning is exact integer arithmetic), and the
 * tile has tw x th texels. */
typedef struct tile_grid {
    long long p, q;
    int tw, th;
} tile_grid;

/* The longer side gets n texels (n <= that side), so a texel is L/n pixels;
 * the shorter side gets as many whole texels of that same size as fit. One
 * scale for both axes keeps the tile's texels square, like the image's. A
 * texel wider than the shorter side would cover pixels the image does not
 * have, so the scale is capped at that side (for aspect ratios beyond n : 1
 * the longer side then exceeds n). */
static tile_grid range_grid(int w, int h, int n)
{
    int lo = w < h ? w : h, hi = w < h ? h : w;
    if (n > hi)
        n = hi;
    tile_grid g = {hi, n, 0, 0};
    if ((long long)lo * n < hi)
        g.p = lo, g.q = 1;
    g.tw = (int)((long long)w * g.q / g.p);
    g.th = (int)((long long)h * g.q / g.p);
    return g;
}

/* Tile cell of pixel i's centre, i + 1/2, on a grid of p/q pixels: -1 for
 * the strip beyond the last whole cell (left out, so that every cell is the
 * same size). */
static int grid_cell(int i, const tile_grid *g, int cells)
{
    int c = (int)((2LL * i + 1) * g->q / (2 * g->p));
    return c < cells ? c : -1;
}

/* Area-averages the height map into the tile: each tile texel is the mean
 * of the source pixels whose centres fall in its cell. Heights stay in
 * image-pixel units. */
static btf_status range_tile(const btf_image *h, int n, btf_model *m, btf_error *err)
{
    tile_grid g = range_grid(h->width, h->height, n);
    size_t cells = (size_t)g.tw * g.th;
    m->range = btf__calloc(cells, sizeof(float), err);
    double *acc = btf__calloc(cells, sizeof(double), err);
    int *cnt = btf__calloc(cells, sizeof(int), err);
    if (!m->range || !acc || !cnt) {
        BTF_FREE_ALL(acc, cnt, m->range);
        m->range = NULL;
        return BTF_E_NOMEM;
    }
    for (int y = 0; y < h->height; y++) {
        int ty = grid_cell(y, &g, g.th);
        for (int x = 0; x < h->width && ty >= 0; x++) {
            int tx = grid_cell(x, &g, g.tw);
            if (tx < 0)
                continue;
            acc[(size_t)ty * g.tw + tx] += h->data[(size_t)y * h->width + x];
            cnt[(size_t)ty * g.tw + tx]++;
        }
    }
    for (size_t i = 0; i < cells; i++)
        m->range[i] = cnt[i] ? (float)(acc[i] / cnt[i]) : 0.0f;
    m->range_width = g.tw;
    m->range_height = g.th;
    m->range_texel = (float)((double)g.p / (double)g.q);
    free(acc);
    free(cnt);
    if (g.p == g.q) {
        /* At the analysed resolution the map is kept as measured (on the
         * file's grid) and quilted onto any surface (model/structure_map.c):
         * no cross-fade, whose half-shifted copy blurs the cells away. */
        for (size_t i = 0; i < cells; i++) /* 1/32 texel: 8 bits a texel in the file */
            m->range[i] = (float)(floor((double)m->range[i] * RANGE_STEPS + 0.5) / RANGE_STEPS);
        btf__range_snap(m->range, cells);
        return BTF_OK;
    }
    /* The tile must tile: its periodic component (Moisan's periodic-plus-
     * smooth decomposition, docs/render.md) keeps the detail and drops the
     * jumps between opposite edges that the area average keeps. */
    return btf_range_make_periodic(m->range, g.tw, g.th, err);
}

/* A pixel without enough usable samples gets the flat normal, so when most
 * do the range map is flat and the structure layer holds no relief: said
 * through the analysis' warnings (the fit's callback, which the command
 * prints), since the model is written all the same. */
static void warn_if_flat(const btf_dataset *ds, const btf_ps_result *ps,
                         const btf_car_fit_opts *car)
{
    if (!car->warn || !(2 * (long long)ps->fallback > ps->pixels))
        return;
    char msg[1024];
    snprintf(msg, sizeof msg, "%s: photometric stereo found fewer than 3 usable samples at %d "
             "of %d pixels (%.0f %%) of view theta %g phi %g, so %s: most samples are clipped "
             "(a raw value >= --saturation x full scale, default 0.99), shadowed or black; if "
             "the images are not clipped there, raise --saturation or turn the rule off with "
             "--saturation 0", btf_dataset_get_info(ds)->root, ps->fallback, ps->pixels,
             100.0 * ps->fallback / ps->pixels, ps->view_dir.theta, ps->view_dir.phi,
             BTF_RANGE_FLAT_TEXT);
    car->warn(car->warn_user, msg);
}

/* A set without a view under 3 lights (a flash capture: one light per
 * view) gives photometric stereo nothing to solve; its images are still
 * registered — every layout is rectified onto the sample plane, so a pixel
 * is one surface point in every image. The mean of the images it holds is
 * then the albedo's estimate over a flat range map (docs/model.md,
 * "Structure without photometric stereo"): the layout of the sample (a
 * mosaic's tiles and grout) is kept as the structure layer, and the CAR
 * fields model what varies around it. */
static btf_status registered_mean(const btf_dataset *ds, const btf_analyse_opts *o,
                                  btf_model *m, double *spread, btf_error *err)
{
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    btf_image height = {0}, mean = {0}, img = {0};
    btf_status rc = btf_image_alloc(&height, in->width, in->height, 1, err);
    if (rc == BTF_OK)
        rc = btf_image_alloc(&mean, in->width, in->height, 3, err);
    size_t n = (size_t)in->width * in->height * 3;
    double *acc = rc == BTF_OK ? btf__calloc(n, sizeof(double), err) : NULL;
    if (rc == BTF_OK && !acc)
        rc = BTF_E_NOMEM;
    int count = 0;
    for (int v = 0; rc == BTF_OK && v < in->n_views; v++)
        for (int l = 0; rc == BTF_OK && l < in->n_lights; l++) {
            if (!btf_dataset_has(ds, v, l))
                continue;
            if ((rc = btf_dataset_read(ds, v, l, &img, err)) == BTF_OK) {
                for (size_t i = 0; i < n; i++)
                    acc[i] += isfinite(img.data[i]) ? img.data[i] : 0.0;
                count++;
            }
            btf_image_free(&img);
        }
    if (rc == BTF_OK) {
        memset(height.data, 0, (size_t)in->width * in->height * sizeof(float));
        for (size_t i = 0; i < n; i++)
            mean.data[i] = (float)(acc[i] / (count > 0 ? count : 1));
        rc = range_tile(&height, o->range_size, m, err);
    }
    if (rc == BTF_OK && btf__structure_quilted(m) && !o->no_structure)
        rc = btf__structure_albedo_from(&mean, m, spread, err);
    free(acc);
    btf_image_free(&height);
    btf_image_free(&mean);
    return rc;
}

static btf_status stage_range(const btf_dataset *ds, const btf_analyse_opts *o, btf_model *m,
                              double *spread, btf_error *err)
{
    if (o->range_from) { /* shared by a sweep: the range does not depend on its settings */
        const btf_model *r = o->range_from;
        if (!r->range || r->range_width < 1 || r->range_height < 1)
            return btf__fail(err, BTF_E_ARG, "analyse: the model to copy the range map from "
                             "has none");
        size_t cells = (size_t)r->range_width * (size_t)r->range_height;
        if (!(m->range = btf__alloc(cells, sizeof(float), err)))
            return BTF_E_NOMEM;
        memcpy(m->range, r->range, cells * sizeof(float));
        m->range_width = r->range_width;
        m->range_height = r->range_height;
        m->range_texel = r->range_texel;
        if (r->albedo && !o->no_structure) {
            if (!(m->albedo = btf__alloc(cells, sizeof(float), err)))
                return BTF_E_NOMEM;
            memcpy(m->albedo, r->albedo, cells * sizeof(float)); /* a: fitted per analysis */
            if (r->chroma) {
                if (!(m->chroma = btf__alloc(cells, 3 * sizeof(float), err)))
                    return BTF_E_NOMEM;
                memcpy(m->chroma, r->chroma, cells * 3 * sizeof(float));
            }
        }
        return BTF_OK;
    }
    btf_ps_result ps;
    btf_status rc = btf__photostereo_dataset(ds, &o->photostereo, &ps, err);
    if (rc)
        return rc;
    warn_if_flat(ds, &ps, &o->fit.car);
    rc = range_tile(&ps.height, o->range_size, m, err);
    if (rc == BTF_OK && btf__structure_quilted(m) && !o->no_structure)
        rc = btf__structure_albedo_from(&ps.albedo, m, spread, err);
    btf_ps_result_free(&ps);
    return rc;
}

/* Whether an exemplar lies on the range map's grid (the structure layer
 * divides it texel by texel). */
static int on_grid(const btf_image *img, const btf_model *m)
{
    return img->width == m->range_width && img->height == m->range_height &&
           img->channels == 3;
}

/* Every subspace's exemplar, read once: the ambient term of the structure
 * layer's shading is fitted to all of them (analyse/structure_fit.c)
 * before each is fitted on its own. */
static btf_status read_exemplars(const btf_dataset *ds, const btf_segmentation *seg,
                                 btf_image **out, btf_error *err)
{
    btf_image *imgs = btf__calloc((size_t)seg->k, sizeof *imgs, err);
    btf_status rc = imgs ? BTF_OK : BTF_E_NOMEM;
    for (int k = 0; rc == BTF_OK && k < seg->k; k++)
        rc = btf_dataset_read(ds, seg->rep_view[k], seg->rep_light[k], &imgs[k], err);
    *out = imgs;
    return rc;
}

static btf_status fit_ambient(const btf_image *imgs, const btf_segmentation *seg, btf_model *m,
                              const btf_structure_geom *geoms, btf_error *err)
{
    btf_image *on = btf__calloc((size_t)seg->k, sizeof *on, err);
    btf_dir *dirs = btf__calloc((size_t)seg->k, sizeof *dirs, err);
    btf_structure_geom *g = btf__calloc((size_t)seg->k, sizeof *g, err);
    btf_status rc = on && dirs && g ? BTF_OK : BTF_E_NOMEM;
    int n = 0;
    for (int k = 0; rc == BTF_OK && k < seg->k; k++)
        if (on_grid(&imgs[k], m)) { /* the others are not used */
            on[n] = imgs[k];
            g[n] = geoms[k];
            dirs[n++] = m->lights.dirs[seg->rep_light[k]];
        }
    if (rc == BTF_OK)
        m->ambient = (float)btf__structure_fit_ambient(on, dirs, g, n, m);
    BTF_FREE_ALL(on, dirs, g);
    return rc;
}

/* Per exemplar on the grid, the texels its pixels show (btf__structure_warp:
 * the renderer's parallax under the exemplar's view), so that the layers
 * divided out are registered with what the camera saw. */
static btf_status exemplar_geoms(const btf_image *imgs, const btf_segmentation *seg,
                                 const btf_model *m, const btf_image *normal,
                                 const uint32_t *horizon, btf_structure_geom **out,
                                 btf_error *err)
{
    btf_structure_geom *g = btf__calloc((size_t)seg->k, sizeof *g, err);
    if (!g)
        return BTF_E_NOMEM;
    *out = g;
    for (int k = 0; k < seg->k; k++) {
        g[k].normal = normal;
        g[k].horizon = horizon;
        btf_structure_tap *taps = NULL;
        if (on_grid(&imgs[k], m)) {
            btf_status rc = btf__structure_warp(m, m->views.dirs[seg->rep_view[k]], &taps, err);
            if (rc)
                return rc;
        }
        g[k].taps = taps;
    }
    return BTF_OK;
}

static void free_geoms(btf_structure_geom *g, int k)
{
    for (int i = 0; g && i < k; i++)
        free((void *)g[i].taps);
    free(g);
}

/* An image's mean colour, in double (the pair gains' texture means). */
static void image_mean(const btf_image *img, double *mean)
{
    float f[3];
    btf__image_mean_rgb(img, f);
    for (int c = 0; c < 3; c++)
        mean[c] = f[c];
}

#define STRUCTURED_AUTO_LEVELS 2
#define STRUCTURED_COEFFICIENT_BITS 32.0 /* a float gamma in the file */

/* Pixel i's luminance, as the masking factor compares it: R + G + B. */
static double pixel_luminance(const btf_image *img, size_t i)
{
    return (double)img->data[3 * i] + img->data[3 * i + 1] + img->data[3 * i + 2];
}

/* What the render multiplies the remainder img by: the exemplar's
 * luminance (in factor, stored before the structure was divided out) over
 * the remainder's, into factor (1 where either is black). */
static void masking_factor(const btf_image *img, float *factor)
{
    size_t n = (size_t)img->width * img->height;
    for (size_t i = 0; i < n; i++) {
        double after = pixel_luminance(img, i);
        double r = after > 1e-12 && factor[i] > 0.0f ? factor[i] / after : 1.0;
        factor[i] = isfinite(r) && r < 1e6 ? (float)r : 1.0f;
    }
}

/* Subspace k's exemplar: with a structure layer, divided by what the
 * relief and the albedo explain (the CAR fields fit the rest), and the
 * colour matching's histogram taken of it divided by the relief's
 * shading only (what synthesis gives before matching). */
static btf_status fit_one(btf_image *img, const btf_analyse_opts *o, btf_model *m, int k,
                          const btf_structure_geom *g, btf_dir light, double *tex_mean,
                          btf_cells *cells, const btf_image *probe, double *explained,
                          btf_error *err)
{
    char what[64];
    snprintf(what, sizeof what, "subspace %d", k);
    btf_fit_opts fo = o->fit;
    fo.car.what = what;
    /* The structure layer holds the coarse pattern: a third pyramid level
     * measured no closer on the rendered material and cost 1-2 KB
     * (docs/model.md, "Choosing the levels"). */
    if (g && !fo.max_auto_levels)
        fo.max_auto_levels = STRUCTURED_AUTO_LEVELS;
    /* Beside a structure layer the remainder's extra neighbours bought
     * likelihood the render did not show: each must pay for its 32 bits
     * in the file (docs/model.md, "Choosing the neighbourhood"). */
    if (g && !fo.car.coefficient_bits)
        fo.car.coefficient_bits = STRUCTURED_COEFFICIENT_BITS;
    if (!g) {
        if (tex_mean) /* the texture is the exemplar itself */
            image_mean(img, tex_mean);
        btf_status rc = btf__fit_subspace(img, &fo, &m->subspaces[k], err);
        return rc ? rc : btf__fit_marginals(img, m, k, err);
    }
    btf_image shaded;
    btf_status rc = btf_image_alloc(&shaded, img->width, img->height, 3, err);
    if (rc)
        return rc;
    size_t n = (size_t)img->width * img->height;
    /* the levels' mask: only where they are chosen and none was given */
    float *factor = NULL;
    if (!fo.levels && !fo.masking && !(factor = btf__alloc(n, sizeof(float), err))) {
        btf_image_free(&shaded);
        return BTF_E_NOMEM;
    }
    memcpy(shaded.data, img->data, n * 3 * sizeof(float));
    btf__structure_divide(&shaded, m, g, light, 0, NULL);
    if (tex_mean) /* the texture is the shaded-out exemplar (colour matched to it) */
        image_mean(&shaded, tex_mean);
    for (size_t i = 0; factor && i < n; i++) /* the exemplar's luminance, before division */
        factor[i] = (float)pixel_luminance(img, i);
    btf__structure_divide(img, m, g, light, 1, NULL);
    /* what repeats on the lattice is the cell's, not the fields' */
    rc = cells ? btf__cells_fit(img, probe, cells, k, explained, err) : BTF_OK;
    if (rc) {
        free(factor);
        btf_image_free(&shaded);
        return rc;
    }
    if (factor) {
        masking_factor(img, factor);
        fo.masking = factor;
    }
    rc = btf__fit_subspace(img, &fo, &m->subspaces[k], err);
    free(factor);
    if (rc == BTF_OK)
        rc = btf__fit_marginals_lab(img, &shaded, m, k, err);
    btf_image_free(&shaded);
    return rc;
}

/* The pair gains from the images' mean colours (those of the
 * segmentation's pass, the caller's, or read now) against the renderer's,
 * made from each subspace texture's mean tex_mean[k * 3 + c]: with a
 * structure layer by btf__pair_predict_views (what each pair's view sees
 * under its light), without one the texture's mean itself. */
static btf_status stage_gains(const btf_dataset *ds, const btf_segmentation *seg,
                              const btf_analyse_opts *o, const double *tex_mean,
                              const btf_image *normal, const uint32_t *horizon, btf_model *m,
                              btf_error *err)
{
    size_t pairs = (size_t)m->views.count * m->lights.count;
    float *own = NULL;
    double *pp = btf__alloc(pairs * 3, sizeof(double), err);
    btf_status rc = pp ? BTF_OK : BTF_E_NOMEM;
    if (rc == BTF_OK && m->albedo && normal->data)
        rc = btf__pair_predict_views(m, tex_mean, normal, horizon, pp, err);
    else
        for (size_t i = 0; rc == BTF_OK && i < pairs; i++)
            for (int c = 0; c < 3; c++) /* a pair not measured: 0, gain 1 */
                pp[3 * i + c] = m->index[i] == BTF_PAIR_NONE ? 0.0
                                                             : tex_mean[3 * (size_t)m->index[i] + c];
    const float *means = seg->means ? seg->means : o->means;
    if (rc == BTF_OK && !means && (rc = btf__dataset_means(ds, o->segment.features.threads,
                                                           &own, err)) == BTF_OK)
        means = own;
    if (rc == BTF_OK)
        rc = btf__pair_gains(m, means, pp, err);
    free(own);
    free(pp);
    return rc;
}

/* The member of subspace k at its exemplar's view whose light is farthest
 * from the exemplar's (the pair there a cell fitted to the exemplar
 * serves worst), read and divided by the structure as the exemplar is,
 * into probe; nothing when the view has no other member. (Other views see
 * the cell shifted by their parallax, which no test of one member can
 * judge: docs/model.md, "Periodic cells".) */
static btf_status cell_probe(const btf_dataset *ds, const btf_segmentation *seg, int k,
                             const btf_model *m, const btf_structure_geom *exemplar,
                             btf_image *probe, btf_error *err)
{
    double l0[3], best = 2.0;
    btf_dir_to_vec(m->lights.dirs[seg->rep_light[k]], l0);
    int pv = -1, pl = -1, nl = m->lights.count;
    for (int v = 0; v < m->views.count; v++)
        for (int l = 0; l < nl; l++) {
            if (seg->index[(size_t)v * nl + l] != k || v != seg->rep_view[k])
                continue;
            double d[3];
            btf_dir_to_vec(m->lights.dirs[l], d);
            double c = d[0] * l0[0] + d[1] * l0[1] + d[2] * l0[2];
            if (c < best)
                best = c, pv = v, pl = l;
        }
    if (pv < 0 || (pv == seg->rep_view[k] && pl == seg->rep_light[k]))
        return BTF_OK;
    btf_status rc = btf_dataset_read(ds, pv, pl, probe, err);
    if (rc || !on_grid(probe, m)) {
        btf_image_free(probe);
        return rc;
    }
    btf__structure_divide(probe, m, exemplar, m->lights.dirs[pl], 1, NULL);
    return BTF_OK;
}

/* Cells of 1s on the lattice of m's structure layer (NULL where it does
 * not repeat, or its cell is too large to keep). */
static btf_status new_cells(const btf_model *m, int k, btf_cells **out, btf_error *err)
{
    int lattice[4], w, h, shift;
    *out = NULL;
    if (!btf__structure_lattice(m, lattice) || !btf__cells_from_lattice(lattice, &w, &h, &shift))
        return BTF_OK;
    *out = btf__cells_new(w, h, shift, k, err);
    return *out ? BTF_OK : BTF_E_NOMEM;
}

/* "; periodic cells ..." for the analysis' structure line. */
static void cells_note(const btf_cells *c, const double *explained, char *note, size_t n)
{
    int kept = 0;
    double lo = 1.0, hi = 0.0;
    for (int k = 0; k < c->n_subspaces; k++)
        if (c->kept[k]) {
            kept++;
            lo = explained[2 * k] < lo ? explained[2 * k] : lo;
            hi = explained[2 * k] > hi ? explained[2 * k] : hi;
        }
    snprintf(note, n, "; periodic cells of %d x %d texels for %d of %d subspaces (explaining "
             "%.0f-%.0f %%; kept where >= %.0f %% and no worse on the farthest-lit member)",
             c->w, c->h, kept, c->n_subspaces, 100.0 * lo, 100.0 * hi,
             100.0 * BTF_CELLS_MIN_EXPLAINED);
}

static btf_status stage_fit(const btf_dataset *ds, const btf_segmentation *seg,
                            const btf_analyse_opts *o, btf_model *m, char *note, size_t note_size,
                            btf_error *err)
{
    m->subspaces = btf__calloc((size_t)seg->k, sizeof(btf_subspace_model), err);
    if (!m->subspaces)
        return BTF_E_NOMEM;
    m->n_subspaces = seg->k;
    btf_image normal = {0};
    btf_image *imgs = NULL; /* with a structure layer: every exemplar, read once */
    btf_status rc = BTF_OK;
    double *tex_mean = NULL; /* [k][3]: each subspace texture's mean (the pair gains) */
    if (!o->no_gains && m->views.count > 0 &&
        !(tex_mean = btf__alloc((size_t)seg->k * 3, sizeof(double), err)))
        return BTF_E_NOMEM;
    uint32_t *horizon = NULL; /* the relief's shadows (btf_horizon.h), on the sample */
    btf_structure_geom *geoms = NULL; /* per exemplar: what its shading reads */
    btf_cells *cells = NULL; /* the remainders' periodic cells, where a lattice is */
    double *explained = NULL; /* [k]: the share of its remainder k's cell explains */
    m->shadows = m->albedo && !o->no_shadows;
    if (m->albedo && ((rc = btf__structure_normals(m, &normal, err)) ||
                      (m->shadows &&
                       (rc = btf__horizon_map(m->range, m->range_width, m->range_height, 0,
                                              o->segment.features.threads, &horizon, err))) ||
                      (rc = read_exemplars(ds, seg, &imgs, err)) ||
                      (rc = exemplar_geoms(imgs, seg, m, &normal, horizon, &geoms, err)) ||
                      (rc = fit_ambient(imgs, seg, m, geoms, err))))
        goto done;
    explained = btf__calloc((size_t)seg->k * 2, sizeof(double), err);
    if (!explained) {
        rc = BTF_E_NOMEM;
        goto done;
    }
    if (m->albedo && !o->no_cells && (rc = new_cells(m, seg->k, &cells, err)))
        goto done;
    for (int k = 0; k < seg->k; k++) {
        btf_image img = {0};
        if (imgs) /* taken over: freed below */
            img = imgs[k], imgs[k] = (btf_image){0};
        else if ((rc = btf_dataset_read(ds, seg->rep_view[k], seg->rep_light[k], &img, err)))
            break;
        int structured = normal.data && m->albedo && on_grid(&img, m);
        btf_image probe = {0};
        if (structured && cells)
            rc = cell_probe(ds, seg, k, m, &geoms[k], &probe, err);
        if (rc == BTF_OK)
            rc = fit_one(&img, o, m, k, structured ? &geoms[k] : NULL,
                         m->lights.dirs[seg->rep_light[k]], tex_mean ? tex_mean + 3 * k : NULL,
                         structured ? cells : NULL, probe.data ? &probe : NULL,
                         &explained[2 * k], err);
        btf_image_free(&probe);
        btf_image_free(&img);
        if (rc == BTF_OK && !structured && m->albedo) {
            free(m->albedo); /* an exemplar off the grid: the layer cannot hold */
            m->albedo = NULL;
            free(m->chroma);
            m->chroma = NULL;
            m->ambient = 0.0f;
            m->shadows = 0;
            btf__cells_free(cells);
            cells = NULL;
            rc = k ? btf__fail(err, BTF_E_DATA, "subspace %d: exemplar not on the range map's "
                               "grid", k) : BTF_OK;
        }
        if (rc)
            break;
        m->subspaces[k].view = seg->rep_view[k];
        m->subspaces[k].light = seg->rep_light[k];
        if (o->progress)
            o->progress(o->progress_user, (double)(k + 1) / seg->k, "fitting CAR models");
    }
    if (rc == BTF_OK && btf__cells_any(cells)) {
        cells_note(cells, explained, note, note_size);
        rc = btf__model_set_cells(m, cells, err); /* taken over */
        cells = NULL;
    } else if (rc == BTF_OK && cells) {
        snprintf(note, note_size, "; no periodic cells (none explains %.0f %% of its "
                 "exemplar's remainder without making its farthest-lit member worse)",
                 100.0 * BTF_CELLS_MIN_EXPLAINED);
    }
    if (rc == BTF_OK && tex_mean)
        rc = stage_gains(ds, seg, o, tex_mean, &normal, horizon, m, err);
done:
    btf__cells_free(cells);
    free(explained);
    free(tex_mean);
    free(horizon);
    free_geoms(geoms, seg->k);
    for (int k = 0; imgs && k < seg->k; k++)
        btf_image_free(&imgs[k]);
    free(imgs);
    btf_image_free(&normal);
    return rc;
}

/* One line: which structure layers the model keeps, and why. */
static void structure_reason(const btf_model *m, const btf_analyse_opts *o, double spread,
                             char *buf, size_t n)
{
    if (!m->range) {
        snprintf(buf, n, "none: no range map (--no-range)");
        return;
    }
    if (!m->albedo) {
        snprintf(buf, n, "none: %s", o->no_structure ? "--no-structure"
                 : m->range_texel != 1.0f ? "a range tile below the analysed resolution holds "
                                            "no albedo (--range-size)"
                                          : "an exemplar is not on the range map's grid");
        return;
    }
    char colour[128];
    if (m->chroma)
        snprintf(colour, sizeof colour, "a colour layer (the colour's log2 spread %.3f >= %.2f)",
                 spread, BTF_CHROMA_MIN_SPREAD);
    else
        snprintf(colour, sizeof colour, "no colour layer (the colour's log2 spread %.3f < %.2f: "
                 "the luminance pattern holds it)", spread < 0.0 ? 0.0 : spread,
                 BTF_CHROMA_MIN_SPREAD);
    snprintf(buf, n, "range map %d x %d at texel 1, albedo pattern, %s, %s, ambient %.4f%s",
             m->range_width, m->range_height, colour,
             m->shadows ? "cast shadows" : "no shadows (--no-shadows)", m->ambient,
             m->gain ? "; pair gains" : "; no pair gains");
}

btf_analyse_opts btf_analyse_defaults(void)
{
    return (btf_analyse_opts){
        .struct_size = sizeof(btf_analyse_opts),
        .segment = btf_segment_defaults(),
        .photostereo = btf_photostereo_defaults(),
        .fit = btf_fit_defaults(),
        .no_range = 0,
        .range_size = 0,
    };
}

/* range_size zero (or negative) becomes its default; the stages' nested
 * options are resolved by the stages' own calls. */
static btf_status resolve_opts(const btf_analyse_opts *opts, btf_analyse_opts *o, btf_error *err)
{
    btf_analyse_opts d = btf_analyse_defaults();
    if (btf__opts_take(o, sizeof *o, opts, &d, "btf_analyse", err))
        return BTF_E_ARG;
    if (o->range_size <= 0)
        o->range_size = 1 << 30; /* the image's own size: texel 1 */
    return BTF_OK;
}

btf_status btf_analyse(const btf_dataset *ds, const btf_analyse_opts *opts, btf_model *out,
                       btf_error *err)
{
    btf_analyse_opts o;
    if (resolve_opts(opts, &o, err))
        return BTF_E_ARG;
    memset(out, 0, sizeof *out);
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    if (o.segment.features.progress == NULL) {
        o.segment.features.progress = o.progress;
        o.segment.features.progress_user = o.progress_user;
    }
    unsigned char *present = NULL; /* a sparse set's pairs (precomputed features) */
    if (o.features && in->n_pairs < in->n_views * in->n_lights) {
        if (btf__dataset_present(ds, &present, err))
            return BTF_E_NOMEM;
        o.segment.present = present;
    }
    btf_segmentation seg;
    btf_status rc = o.features ? btf__segment_features(o.features, in->n_views, in->n_lights,
                                                       o.feature_dim, &o.segment, &seg, err)
                               : btf_segment(ds, &o.segment, &seg, err);
    free(present);
    o.segment.present = NULL;
    if (rc)
        return rc;
    rc = btf__dirset_copy(&out->views, in->views, err);
    if (rc == 0)
        rc = btf__dirset_copy(&out->lights, in->lights, err);
    if (rc == 0) {
        size_t n = (size_t)in->n_views * in->n_lights;
        out->index = btf__alloc(n, 1, err);
        if (out->index)
            memcpy(out->index, seg.index, n);
        else
            rc = BTF_E_NOMEM;
    }
    double spread = -1.0; /* the colour layer's measure; -1: not measured */
    char cells[200] = ""; /* the periodic cells' clause of the structure line */
    /* A sparse set may hold no view with the 3 lights photometric stereo
     * needs (a flash capture: one light per view): the model then has no
     * range map, and says why (docs/datasets.md, "Sparse pair sets"). */
    int no_ps = !o.no_range && !o.range_from && btf__photostereo_best_lights(ds) < 3;
    if (rc == 0 && !o.no_range && !no_ps)
        rc = stage_range(ds, &o, out, &spread, err);
    else if (rc == 0 && no_ps && !o.no_structure) /* a flat map holds nothing else */
        rc = registered_mean(ds, &o, out, &spread, err);
    if (rc == 0)
        rc = stage_fit(ds, &seg, &o, out, cells, sizeof cells, err);
    if (rc == 0 && btf__model_keep_margins(out, -1.0) != BTF_OK) /* for synthesis */
        rc = btf__fail(err, BTF_E_NOMEM, "out of memory");
    if (rc == 0 && o.report) {
        memset(o.report, 0, sizeof *o.report);
        snprintf(o.report->segment_reason, sizeof o.report->segment_reason, "%s", seg.reason);
        structure_reason(out, &o, spread, o.report->structure_reason,
                         sizeof o.report->structure_reason);
        size_t used = strlen(o.report->structure_reason);
        snprintf(o.report->structure_reason + used, sizeof o.report->structure_reason - used,
                 "%s", out->albedo ? cells : "");
        if (no_ps && o.no_structure)
            snprintf(o.report->structure_reason, sizeof o.report->structure_reason,
                     "none: no range map (photometric stereo needs one view with at least 3 "
                     "lights, and the set holds at most %d at any view) and --no-structure",
                     btf__photostereo_best_lights(ds));
        else if (no_ps) {
            char kept[200];
            snprintf(kept, sizeof kept, "%s", o.report->structure_reason);
            snprintf(o.report->structure_reason, sizeof o.report->structure_reason,
                     "a flat range map: photometric stereo needs one view with at least 3 "
                     "lights, and the set holds at most %d at any view; the albedo pattern is "
                     "the mean of the registered images (%s)", btf__photostereo_best_lights(ds),
                     kept);
        }
    }
    btf_segmentation_free(&seg);
    if (rc)
        btf_model_free(out);
    return rc;
}

btf_status btf__analyse_range(const btf_dataset *ds, const btf_analyse_opts *opts, btf_model *out,
                              btf_error *err)
{
    if (!ds || !out)
        return btf__fail(err, BTF_E_ARG, "analyse: no dataset or no output given");
    btf_analyse_opts o;
    if (resolve_opts(opts, &o, err))
        return BTF_E_ARG;
    o.range_from = NULL;
    out->range = NULL;
    return stage_range(ds, &o, out, NULL, err);
}
