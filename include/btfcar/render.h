/*
 * btfcar/render.h — rendering: hemisphere interpolation of the measured
 * directions, range and normal maps, scenes, and the renders of both model
 * families.
 * Part of the public C API of btfcar; include/btfcar.h includes every
 * topical header, and its conventions (docs/api.md) hold here too.
 */
#ifndef BTFCAR_RENDER_H
#define BTFCAR_RENDER_H

#include "base.h"
#include "image.h"
#include "model.h"

#include <stdint.h>

/* What this header declares is part of the ABI of libbtfcar.so: the library
 * is compiled with -fvisibility=hidden, and the declarations of the public
 * headers alone are exported (docs/install.md, "Shared library and soname"). */
#pragma GCC visibility push(default)

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------ hemisphere interpolation (render) */

/* Haindl & Filip 2007, section III and Fig. 1: a pixel's local view (or
 * light) direction is interpolated from the three measured directions that
 * enclose it, with barycentric weights, on a triangulation of the measured
 * set (src/render/hemisphere.c, docs/render.md). Local directions are in
 * the tangent frame: x along the texture's columns (phi = 0), y up the
 * image (phi = 90), z the surface normal. */
typedef struct btf_hemisphere btf_hemisphere; /* opaque */

/* Triangulates a direction set: the directions projected to the unit disk
 * (azimuthal equidistant, radius theta / 90 degrees, azimuth phi), then a
 * Delaunay triangulation of the points, ties between cocircular points
 * broken by the set's order, and a grid of cells over [-1, 1]^2 listing the
 * triangles that may cover each. Errors (BTF_E_ARG, naming the set): fewer
 * than 3 directions, more than BTF_HEMISPHERE_MAX_POINTS, a theta outside
 * [0, 90] or non-finite, two directions on the same projected point (e.g.
 * the pole twice), all directions on one line after the projection (one
 * great circle through the pole). */
#define BTF_HEMISPHERE_MAX_POINTS 1024
btf_status btf_hemisphere_build(const btf_dirset *set, btf_hemisphere **out, btf_error *err);
void btf_hemisphere_free(btf_hemisphere *h);

/* ------------------------------------------------- range and normal maps */

/* The model's range map (paper section II.B) and structure layer as
 * seamless width x height maps in analysed-image texels: each map wraps
 * (its right edge continues into its left, its bottom into its top) at any
 * size (docs/render.md says how). height: width x height x 1, heights in
 * analysed-image texels (multiply by a relief scale to exaggerate);
 * normal: width x height x 3 unit normals in the tangent frame (x right,
 * y up the image, z out), derived from the heights with wrap-around
 * differences. With the structure layer (docs/model.md, "Structure"): a
 * model whose range map is at the analysed resolution gets its heights,
 * normals and albedo pattern quilted onto the width x height torus by one
 * coordinate map drawn from seed (the seed of the synthesis they go with:
 * btf_synthesise multiplies the same pattern into its images), so the
 * layers are registered with each other and the map tiles without a seam.
 * A model with a small periodic tile gets that tile enlarged and an albedo
 * of 1; a model without a range map gives a flat map (heights 0, normals
 * (0, 0, 1)). The albedo has one channel, or three (RGB) when the model
 * has a colour layer (btf_model.chroma). Any output may be NULL. */
btf_status btf_structure_maps(const btf_model *m, int width, int height, uint64_t seed,
                              btf_image *height_out, btf_image *normal_out,
                              btf_image *albedo_out, btf_error *err);

/* ----------------------------------------------------------------- scenes */

/* A scene for btf_render_scene (src/scene/, docs/scene.md): a pinhole
 * camera, lights and objects, buildable by a program without a file.
 * World units are arbitrary; right-handed coordinates. */
typedef struct btf_camera {
    double position[3], target[3], up[3];
    double fov_deg;                 /* vertical field of view, (0, 180) */
} btf_camera;

typedef enum btf_light_kind { BTF_LIGHT_DIRECTIONAL = 0, BTF_LIGHT_POINT } btf_light_kind;

typedef struct btf_light {
    btf_light_kind kind;
    double direction[3];            /* directional: towards the light (unit) */
    double position[3];             /* point: its position; falls off as 1/d^2 */
    float rgb[3];                   /* intensity per channel */
} btf_light;

typedef enum btf_object_kind {
    BTF_OBJECT_PLANE = 0,           /* a square of side `size` around center, normal `axis` */
    BTF_OBJECT_SPHERE,              /* center, radius */
    BTF_OBJECT_CYLINDER,            /* center (of its axis), axis, radius, height; open ends */
    BTF_OBJECT_MESH                 /* triangles with UVs */
} btf_object_kind;

typedef struct btf_mesh {
    int n_vertices, n_triangles;
    float *positions;               /* [n_vertices][3] */
    float *normals;                 /* [n_vertices][3] or NULL (face normals) */
    float *uvs;                     /* [n_vertices][2]: UV channel 0, top-left origin (v down
                                       the rows), in the file's units; the trace multiplies by
                                       texture_scale and turns by rotation_deg */
    uint32_t *indices;              /* [n_triangles][3] */
} btf_mesh;

typedef struct btf_object {
    btf_object_kind kind;
    double center[3];               /* mesh: added to its vertices */
    double axis[3];                 /* plane normal, sphere pole, cylinder axis; unit */
    double radius, height, size;
    double texture_scale;           /* texels of the material per world unit (mesh: per UV unit) */
    double rotation_deg;            /* the material turned on the surface */
    btf_mesh mesh;                  /* BTF_OBJECT_MESH: owned by the scene */
} btf_object;

typedef struct btf_scene {
    btf_camera camera;
    int n_lights;
    btf_light *lights;
    int n_objects;
    btf_object *objects;
    float background[3];            /* linear RGB */
} btf_scene;

/* Reads a JSON scene file (docs/scene.md; meshes through assimp): any bad
 * key, type, value, missing or UV-less mesh is one error naming the file
 * and the key. Every file read is a regular file, and the files a mesh
 * names (mtllib, glTF buffers) lie in the mesh's folder or below. */
btf_status btf_scene_load(const char *path, btf_scene *out, btf_error *err);
/* Checks a scene built in memory (degenerate camera, zero radius, ...). */
btf_status btf_scene_check(const btf_scene *s, btf_error *err);
void btf_scene_free(btf_scene *s);
/* The material preview scene (src/scene/scene_sphere.c): a unit sphere
 * filling most of the frame, seen along -z, under one white directional
 * light given as a direction in the camera's frame (theta 0: from the
 * camera), texture_scale texels per world unit, a dark background. Free
 * it with btf_scene_free. */
btf_status btf_scene_sphere(btf_dir light, double texture_scale, btf_scene *out, btf_error *err);

/* ---------------------------------------------------------------- render */

/* The paper's rendering stage (Haindl & Filip 2007, section III, Fig. 1;
 * src/render/, docs/render.md): per pixel, the local view and light
 * directions select the 3 nearest measured views x 3 nearest lights; the
 * nine (view, light) pairs select subspace images through the index table,
 * which are sampled at parallax-shifted texture coordinates and blended with
 * the barycentric weights; the result is relit by the range map's normals. */
typedef struct btf_render_opts {
    size_t struct_size; /* sizeof the struct (set by the defaults); 0: this header's */
    int width, height;   /* frame size, 1..BTF_RENDER_MAX_SIDE; 0: 512 */
    uint64_t seed;       /* synthesis seed of the subspace images */
    int threads;         /* 0: all CPUs */
    double relief;       /* range map height scale (parallax and bump); 0: off; < 0: 1 */
    int texture_size;    /* side of the synthesised tileable subspace images and
                            range map, in analysed texels; 0: what the visible
                            surface needs (docs/render.md) */
    int all_subspaces;   /* 1: synthesise every subspace, not only the needed ones */
} btf_render_opts;
#define BTF_RENDER_MAX_SIDE 16384
btf_render_opts btf_render_defaults(void);

/* What a render did (times in seconds). */
typedef struct btf_render_info {
    int needed, total;   /* subspaces synthesised, of the model's */
    int texture_size;
    double trace_s, synth_s, shade_s;
} btf_render_info;

/* The whole render of a scene: trace, the needed subspaces, synthesis, shade. */
btf_status btf_render_scene(const btf_model *m, const btf_scene *s, const btf_render_opts *opts,
                            btf_image *out, btf_render_info *info, btf_error *err);

/* The model's counterpart of one measured image: a flat patch seen from
 * `view` and lit (unit white directional light) from `light`,
 * orthographic, texel (x, y) of the frame at texture texel (x, y). */
btf_status btf_render_flat(const btf_model *m, btf_dir view, btf_dir light,
                           const btf_render_opts *opts, btf_image *out, btf_render_info *info,
                           btf_error *err);

#ifdef __cplusplus
}
#endif

#pragma GCC visibility pop
#endif /* BTFCAR_RENDER_H */
