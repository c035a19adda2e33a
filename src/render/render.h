/*
 * render.h -- private declarations of src/render/ (the hemisphere
 * triangulation behind btf_hemisphere_build, docs/render.md; the lookup
 * and its tables, the range and normal maps, and the render's stages,
 * which the GPU renderer, the report and the tests share).
 */
#ifndef BTF_RENDER_H
#define BTF_RENDER_H

#include "btfcar.h"
#include "scene/gbuffer.h"

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
double btf__incircle(const double *a, const double *b, const double *c, const double *d,
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
btf_status btf__delaunay(const double *xy, int n, const char *name, int32_t **tris, int *n_tris,
                         int32_t **hull, int32_t **hull_apex, int *n_hull, btf_error *err);

/* ------------------------------------- the parts the library shares */

/* The three set indices enclosing local direction v (any non-zero vector:
 * beyond the outermost ring and below the horizon too, by the rule in
 * docs/render.md) and their weights: w >= 0, summing to 1, continuous in
 * v, 1 at a measured direction. A zero or non-finite v is taken as the
 * pole. Beyond the hull the third weight is 0 (idx[2] then names the apex
 * of the triangle on that hull edge). */
void btf__hemisphere_lookup(const btf_hemisphere *h, const float v[3], int idx[3], float w[3]);

/* The flat tables the CPU and GPU lookups both read (the lookup itself is
 * src/render/btf__hemisphere_lookup.h, the same text for C and GLSL). The
 * pointers stay owned by h. */
typedef struct btf_hemisphere_table {
    int n_points, n_triangles;
    const float *points;        /* [n_points][2]: the projected directions, set order */
    const int32_t *triangles;   /* [n_triangles][3]: point indices, counter-clockwise */
    int grid;                   /* grid x grid cells over [-1, 1]^2, row-major from (-1, -1) */
    const int32_t *cell_start;  /* [grid * grid + 1]: cell c's triangles are */
    const int32_t *cell_tris;   /*   cell_tris[cell_start[c] .. cell_start[c + 1]) */
    int n_cell_tris;
    int n_hull;                 /* the outer boundary, counter-clockwise: */
    const int32_t *hull;        /*   [n_hull] point indices (collinear ones included) */
    const int32_t *hull_apex;   /* [n_hull]: the third vertex of the triangle on edge
                                   hull[i] -> hull[(i + 1) % n_hull] */
} btf_hemisphere_table;
void btf__hemisphere_get_table(const btf_hemisphere *h, btf_hemisphere_table *t);

/* The model's range tile (paper section II.B) enlarged to a seamless
 * width x height map in analysed-image texels: the map wraps (its right
 * edge continues into its left, its bottom into its top) at any size
 * (docs/render.md says how). height: width x height x 1, heights in
 * analysed-image texels (multiply by a relief scale to exaggerate);
 * normal: width x height x 3 unit normals in the tangent frame (x right,
 * y up the image, z out), derived from the heights with wrap-around
 * differences. Either output may be NULL. A model without a range map
 * gives a flat map (heights 0, normals (0, 0, 1)). */
btf_status btf__range_map(const btf_model *m, int width, int height, btf_image *height_out,
                          btf_image *normal_out, btf_error *err);
/* The unit normals of the height map scale * h (1 channel) into normal
 * (allocated here, 3 channels, same size): n = normalize(-dh/dx, -dh/dy, 1)
 * with x right and y up the image (rows grow downwards), from wrap-around
 * central differences, so a map that wraps gives normals that wrap. Finite
 * heights give finite unit normals (scale finite; huge slopes included). */
btf_status btf__normal_map(const btf_image *height, double scale, btf_image *normal,
                           btf_error *err);
/* The subspaces (needed[k] = 1) that the nine pairs of any pixel of g
 * select under any of the lights, and their count. needed has
 * m->n_subspaces entries. */
btf_status btf__render_needed(const btf_model *m, const btf_gbuffer *g, const btf_light *lights,
                              int n_lights, uint8_t *needed, int *count, btf_error *err);

/* A material ready to shade with: the model's hemisphere tables, its
 * range and normal map, and the synthesised (tileable) subspace images
 * (only those with needed[k] set; needed NULL: all), all of side
 * texture_size. Kept in memory; repeated renders reuse it. */
typedef struct btf_render_material btf_render_material;
btf_status btf__render_material_build(const btf_model *m, const uint8_t *needed,
                                      int texture_size, uint64_t seed, int threads,
                                      btf_render_material **out, btf_error *err);
void btf__render_material_free(btf_render_material *rm);

/* Shades a G-buffer into out (linear RGB, g's size; allocated here). A pixel
 * that needs a subspace the material was not built with is an error. */
btf_status btf__render_shade(const btf_render_material *rm, const btf_gbuffer *g,
                             const btf_light *lights, int n_lights, const float background[3],
                             double relief, int threads, btf_image *out, btf_error *err);

#endif /* BTF_RENDER_H */
