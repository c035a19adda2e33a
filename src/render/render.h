/*
 * render.h -- private declarations of src/render/ (the hemisphere
 * triangulation behind btf_hemisphere_build; docs/render.md).
 */
#ifndef BTF_RENDER_H
#define BTF_RENDER_H

#include "btfcar.h"

#include <stdint.h>

/* Below this distance (in projected units, the unit disk's radius being 90
 * degrees) a point counts as on a line: far above the rounding of the
 * projection (~1e-16) and far below the spacing of any set
 * (btf_dirset_from_list merges directions within 1e-6 degree ~ 1e-8). */
#define BTF_DELAUNAY_LINE_EPS 1e-11
/* Two projected points closer than this are one point (an error). */
#define BTF_DELAUNAY_SAME_EPS 1e-9
/* A point is inside a circumcircle when the in-circle determinant exceeds
 * this fraction of its bound (the squared largest squared distance):
 * cocircular points (rings) are a tie, resolved by the insertion order. */
#define BTF_DELAUNAY_CIRCLE_EPS 1e-10

/* The in-circle determinant of d against counter-clockwise (a, b, c): > 0
 * when d is inside; *bound receives the bound its magnitude stays under. */
double btf_incircle(const double *a, const double *b, const double *c, const double *d,
                    double *bound);

/* Delaunay triangulation of n >= 3 distinct points xy[n][2], not all on
 * one line: incremental insertion with Lawson flips (Lawson 1977; Guibas &
 * Stolfi 1985), the first triangle spanning the set (its farthest pair and
 * the point farthest from their line), then the other points in set order.
 * Cocircular ties keep the earlier diagonal, so the result depends on the
 * set's order only. Writes *tris (malloc'd, [*n_tris][3], counter-clockwise)
 * and the hull: *hull and *hull_apex (malloc'd [*n_hull]), counter-clockwise
 * from its smallest point index, collinear boundary points included.
 * `name` prefixes error messages. */
btf_status btf_delaunay(const double *xy, int n, const char *name, int32_t **tris, int *n_tris,
                        int32_t **hull, int32_t **hull_apex, int *n_hull, btf_error *err);

#endif /* BTF_RENDER_H */
