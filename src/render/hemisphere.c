/*
 * hemisphere.c -- interpolation over the hemisphere of measured directions
 * (Haindl & Filip 2007, section III, "BTF Interpolation": the three
 * measured view (or light) directions enclosing a direction and their
 * barycentric weights; the angles of Fig. 1). btf_hemisphere_build projects
 * a direction set to the unit disk, triangulates it (render/delaunay.c) and
 * grids the triangles; the lookup itself is the C/GLSL text of
 * render/btf__hemisphere_lookup.h. Rules: docs/render.md.
 */
#include "render/render.h"
#include "render/btf_hemisphere_lookup.h"
#include "core/core.h"

#include <math.h>
#include <stdlib.h>

#define BTF_PI 3.14159265358979323846
/* Triangles' boxes are widened by this before they are gridded, so that
 * the float cell index of any point in a triangle (rounded) is covered. */
#define GRID_MARGIN 1e-5

struct btf_hemisphere {
    int n_points, n_triangles, grid, n_cell_tris, n_hull;
    float *points;
    int32_t *triangles, *cell_start, *cell_tris, *hull, *hull_apex;
};

void btf_hemisphere_free(btf_hemisphere *h)
{
    if (!h)
        return;
    BTF_FREE_ALL(h->points, h->triangles, h->cell_start, h->cell_tris, h->hull, h->hull_apex, h);
}

/* The projection of the set, in double (the lookup's, btf_hemi_project):
 * Lambert's azimuthal equal-area projection scaled to the unit disk, radius
 * sqrt(1 - cos theta), angle phi. Keeps each ring of equal theta a circle
 * (so convex), the pole at the origin and the horizon on the unit circle;
 * equal solid angles get equal areas, so triangles of an even sampling are
 * evenly sized. */
static btf_status project_set(const btf_dirset *set, const char *name, double *xy,
                              btf_error *err)
{
    for (int i = 0; i < set->count; i++) {
        btf_dir d = set->dirs[i];
        if (!isfinite(d.theta) || !isfinite(d.phi) || d.theta < 0.0 || d.theta > 90.0)
            return btf__fail(err, BTF_E_ARG,
                             "%s: direction %d (theta %g, phi %g): theta must be in [0, 90]",
                             name, i, d.theta, d.phi);
        double r = sqrt(1.0 - cos(d.theta * (BTF_PI / 180.0))), p = d.phi * (BTF_PI / 180.0);
        xy[2 * i] = r * cos(p);
        xy[2 * i + 1] = r * sin(p);
    }
    for (int i = 0; i < set->count; i++)
        for (int j = i + 1; j < set->count; j++)
            if (hypot(xy[2 * i] - xy[2 * j], xy[2 * i + 1] - xy[2 * j + 1]) <
                BTF_DELAUNAY_SAME_EPS)
                return btf__fail(err, BTF_E_ARG,
                                 "%s: directions %d (theta %g, phi %g) and %d (theta %g, phi %g) "
                                 "are the same direction",
                                 name, i, set->dirs[i].theta, set->dirs[i].phi, j,
                                 set->dirs[j].theta, set->dirs[j].phi);
    return BTF_OK;
}

static int cell_of(double v, int g)
{
    int c = (int)floor((v + 1.0) * 0.5 * g);
    return c < 0 ? 0 : c >= g ? g - 1 : c;
}

/* The uniform grid over [-1, 1]^2: each cell lists, in triangle order, the
 * triangles whose (widened) bounding box meets it, so a point's cell holds
 * every triangle that contains it. About 32 cells per triangle, so that a
 * cell holds one or two. */
static btf_status build_grid(btf_hemisphere *h, btf_error *err)
{
    int g = 16;
    while (g * g < 32 * h->n_triangles && g < 256)
        g *= 2;
    h->grid = g;
    h->cell_start = btf__calloc((size_t)g * g + 1, sizeof *h->cell_start, err);
    if (!h->cell_start)
        return BTF_E_NOMEM;
    for (int pass = 0; pass < 2; pass++) {
        for (int t = 0; t < h->n_triangles; t++) {
            double lo[2] = {2.0, 2.0}, hi[2] = {-2.0, -2.0};
            for (int k = 0; k < 3; k++)
                for (int a = 0; a < 2; a++) {
                    double v = h->points[2 * h->triangles[3 * t + k] + a];
                    lo[a] = fmin(lo[a], v);
                    hi[a] = fmax(hi[a], v);
                }
            int x0 = cell_of(lo[0] - GRID_MARGIN, g), x1 = cell_of(hi[0] + GRID_MARGIN, g);
            int y0 = cell_of(lo[1] - GRID_MARGIN, g), y1 = cell_of(hi[1] + GRID_MARGIN, g);
            for (int y = y0; y <= y1; y++)
                for (int x = x0; x <= x1; x++) {
                    int c = y * g + x;
                    if (pass == 0)
                        h->cell_start[c + 1]++;
                    else
                        h->cell_tris[h->cell_start[c]++] = t;
                }
        }
        if (pass == 0) {
            for (int c = 0; c < g * g; c++)
                h->cell_start[c + 1] += h->cell_start[c];
            h->n_cell_tris = h->cell_start[g * g];
            h->cell_tris = btf__alloc((size_t)(h->n_cell_tris ? h->n_cell_tris : 1),
                                      sizeof *h->cell_tris, err);
            if (!h->cell_tris)
                return BTF_E_NOMEM;
        }
    }
    /* The fill advanced each start to the next cell's: shift them back. */
    for (int c = g * g; c > 0; c--)
        h->cell_start[c] = h->cell_start[c - 1];
    h->cell_start[0] = 0;
    return BTF_OK;
}

btf_status btf_hemisphere_build(const btf_dirset *set, btf_hemisphere **out, btf_error *err)
{
    if (out)
        *out = NULL;
    if (!set || !out)
        return btf__fail(err, BTF_E_ARG, "hemisphere: no direction set");
    const char *name = set->name[0] ? set->name : "direction set";
    if (set->count < 3 || !set->dirs)
        return btf__fail(err, BTF_E_ARG,
                         "%s: %d directions; interpolation over the hemisphere needs at least 3",
                         name, set->count);
    if (set->count > BTF_HEMISPHERE_MAX_POINTS)
        return btf__fail(err, BTF_E_ARG, "%s: %d directions; at most %d are supported", name,
                         set->count, BTF_HEMISPHERE_MAX_POINTS);
    int n = set->count;
    double *xy = btf__alloc((size_t)n * 2, sizeof *xy, err);
    btf_hemisphere *h = btf__calloc(1, sizeof *h, err);
    btf_status st = (!xy || !h) ? BTF_E_NOMEM : project_set(set, name, xy, err);
    if (st == BTF_OK)
        st = btf__delaunay(xy, n, name, &h->triangles, &h->n_triangles, &h->hull, &h->hull_apex,
                           &h->n_hull, err);
    if (st == BTF_OK) {
        h->n_points = n;
        h->points = btf__alloc((size_t)n * 2, sizeof *h->points, err);
        if (!h->points)
            st = BTF_E_NOMEM;
    }
    if (st == BTF_OK) {
        for (int i = 0; i < 2 * n; i++)
            h->points[i] = (float)xy[i];
        st = build_grid(h, err);
    }
    free(xy);
    if (st != BTF_OK) {
        btf_hemisphere_free(h);
        return st;
    }
    *out = h;
    return BTF_OK;
}

void btf__hemisphere_get_table(const btf_hemisphere *h, btf_hemisphere_table *t)
{
    t->n_points = h->n_points;
    t->n_triangles = h->n_triangles;
    t->points = h->points;
    t->triangles = h->triangles;
    t->grid = h->grid;
    t->cell_start = h->cell_start;
    t->cell_tris = h->cell_tris;
    t->n_cell_tris = h->n_cell_tris;
    t->n_hull = h->n_hull;
    t->hull = h->hull;
    t->hull_apex = h->hull_apex;
}

void btf__hemisphere_lookup(const btf_hemisphere *h, const float v[3], int idx[3], float w[3])
{
    btf_hemisphere_table t;
    btf__hemisphere_get_table(h, &t);
    btf_hemi_weights r = btf_hemi_lookup(&t, v[0], v[1], v[2]);
    idx[0] = r.i0;
    idx[1] = r.i1;
    idx[2] = r.i2;
    w[0] = r.w0;
    w[1] = r.w1;
    w[2] = r.w2;
}
