/*
 * scene.h — private to src/scene/: vector helpers, the per-hit record the
 * intersectors fill, and the stages of loading and ray casting a scene
 * (docs/scene.md). Conventions of the G-buffer frame (scene/gbuffer.h):
 * T along increasing u, B along decreasing v ("up" the texture image),
 * N = T x B towards the eye.
 */
#ifndef BTF_SCENE_H
#define BTF_SCENE_H

#include "btfcar.h"
#include "scene/gbuffer.h"

#include <math.h>
#include <stddef.h>

/* Coordinates, lengths, texture scales and intensities are refused beyond
 * this magnitude: products of them (r^2, uv = R phi scale) stay far from
 * overflow in double and keep float uv finite (docs/scene.md, "Ranges"). */
#define SCENE_MAX_COORD 1e6
/* The scene file is read whole; beyond this it is refused unread. */
#define SCENE_MAX_FILE_BYTES ((size_t)4 << 20)
/* A mesh file beyond this size is refused before assimp opens it. */
#define SCENE_MAX_MESH_BYTES ((long long)1 << 30)
/* A mesh with more triangles is refused (32-bit indices, BVH memory). */
#define SCENE_MAX_TRIANGLES 50000000

static inline double v3_dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static inline void v3_cross(const double a[3], const double b[3], double out[3])
{
    double x = a[1] * b[2] - a[2] * b[1];
    double y = a[2] * b[0] - a[0] * b[2];
    double z = a[0] * b[1] - a[1] * b[0];
    out[0] = x, out[1] = y, out[2] = z;
}
static inline double v3_len(const double a[3])
{
    return sqrt(v3_dot(a, a));
}
static inline void v3_sub(const double a[3], const double b[3], double out[3])
{
    out[0] = a[0] - b[0], out[1] = a[1] - b[1], out[2] = a[2] - b[2];
}
static inline void v3_scale(double a[3], double s)
{
    a[0] *= s, a[1] *= s, a[2] *= s;
}
/* Normalises a in place; returns 0 (a untouched) when it has no direction. */
static inline int v3_normalize(double a[3])
{
    double l = v3_len(a);
    if (!(l > 1e-300) || !isfinite(l))
        return 0;
    v3_scale(a, 1.0 / l);
    return 1;
}

/* The orientation of a material on a surface with unit normal (or axis) a,
 * before its rotation: up = world +y projected on the surface (world -z
 * where a is within ~25 degrees of +-y), right = up x a, so that right,
 * up, a are right-handed (docs/scene.md, "Material orientation"). */
void scene_basis(const double a[3], double right[3], double up[3]);

/* One ray's nearest hit: distance, world point, the material uv (texels)
 * and the frame T, B, N (rows of frame). */
typedef struct scene_hit {
    double t;
    double position[3];
    double uv[2];
    double frame[9];
} scene_hit;

/* Completes a hit's frame: n_out is the surface's outward unit normal,
 * tdir the (unnormalised) direction of increasing u, view the unit vector
 * towards the eye; mirrored: the uv layout is mirrored against n_out (a
 * mesh's UV island). A surface seen from behind, or a mirrored layout,
 * has u negated so that T, B, N stay right-handed with N towards the eye:
 * the material is never seen mirrored (docs/scene.md, "Back faces").
 * Never NaN: a tdir without direction in the tangent plane gives any
 * frame around N. */
void scene_finish_frame(const double n_out[3], const double tdir[3], const double view[3],
                        int mirrored, scene_hit *h);

/* The material rotation (degrees) applied to surface coordinates: s along
 * the unrotated right, t along the unrotated up; returns u = s' and
 * v = -t' of the rotated coordinates. */
void scene_rotate_uv(double rotation_deg, double s, double t, double *u, double *v);

/* Analytic intersections (shapes.c): the nearest hit with 0 < t < t_max
 * of the ray o + t d (d unit); 1 and *h filled when there is one. */
int scene_hit_plane(const btf_object *ob, const double o[3], const double d[3], double t_max,
                    scene_hit *h);
int scene_hit_sphere(const btf_object *ob, const double o[3], const double d[3], double t_max,
                     scene_hit *h);
int scene_hit_cylinder(const btf_object *ob, const double o[3], const double d[3],
                       double t_max, scene_hit *h);

/* A bounding volume hierarchy over one mesh's triangles (bvh.c): binned
 * SAH, leaves of at most 4 triangles; the triangles are copied in leaf
 * order as vertex 0 and two edges (Moller & Trumbore's form). */
typedef struct scene_bvh_node {
    float lo[3], hi[3];
    int32_t first;  /* leaf: first triangle; inner: the right child (left = this + 1) */
    int32_t count;  /* leaf: triangles (>= 1); inner: 0 */
    int32_t axis;   /* inner: the split axis (nearer child first) */
    int32_t pad;
} scene_bvh_node;

typedef struct scene_bvh {
    int n_nodes, n_triangles;
    scene_bvh_node *nodes;
    double *tris;        /* [n][9]: v0, e1 = v1 - v0, e2 = v2 - v0 */
    int32_t *tri_index;  /* [n]: the mesh's triangle of each slot */
} scene_bvh;

btf_status scene_bvh_build(const btf_mesh *m, scene_bvh *out, btf_error *err);
void scene_bvh_free(scene_bvh *b);
/* The nearest triangle hit with 0 < t < t_max: 1 with the mesh's triangle
 * index, t and the barycentrics (b1, b2) of vertices 1 and 2. */
int scene_bvh_hit(const scene_bvh *b, const double o[3], const double d[3], double t_max,
                  int *tri, double *t, double *b1, double *b2);

/* The surface of a mesh hit (mesh_frame.c): uv (texture_scale and
 * rotation applied), interpolated normal, tangent from the triangle's uv
 * derivatives. */
void scene_mesh_surface(const btf_object *ob, int tri, double b1, double b2,
                        const double view[3], scene_hit *h);

/* Reads a mesh with assimp (mesh_load.c): triangulated, UV channel 0 with
 * the top-left origin (v down), normals when the file has them. name and
 * key name the scene file and the key for the one-line error. */
btf_status scene_mesh_load(const char *path, const char *name, const char *key, btf_mesh *out,
                           btf_error *err);
void scene_mesh_free(btf_mesh *m);

/* btf_scene_check with the messages prefixed by name (the scene file). */
btf_status scene_check_named(const btf_scene *s, const char *name, btf_error *err);

#endif
