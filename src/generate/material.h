/*
 * material.h — procedural materials' internals (src/generate/): the size
 * limit, and the per-view and per-light maps of rendering, shared by the
 * generator and the tests. Private to the library.
 */
#ifndef BTF_MATERIAL_H
#define BTF_MATERIAL_H

#include "btfcar.h"

#include <stdint.h>

/* Largest material side: keeps size*size*3 well inside int. */
#define BTF_MATERIAL_MAX_SIZE 16384

/* i mod n in [0, n), for any sign of i: textures are periodic. */
static inline int btf_wrap_int(int64_t i, int n)
{
    int64_t r = i % n;
    return (int)(r < 0 ? r + n : r);
}

/* Rendering (generate/render.c): precomputation for rendering many
 * (view, light) pairs. What a view sees depends only on the view, and what a
 * light shadows only on the light, so a generator builds one view map per
 * view and one light map per light and combines them per pair with
 * btf__material_render_maps (cheap: one shading per texel). All coordinates are
 * texture coordinates: u = column, w = row (row 0 at the top); the reference
 * plane is z = 0 (btf_procedural_make's heights have zero mean). Directions and
 * stored normals use the frame x right, y UP in the image (row index grows
 * towards -y), z towards the camera. The maps are read-only once made, so any
 * number of threads may share them. */
typedef struct btf_view_map {
    int size;
    float *hit;    /* size*size*2: (u, w) of the surface point the view ray
                      through texel (x, y) of the reference plane hits,
                      wrapped into [0, size) */
    float *normal; /* size*size*3: unit normal at the hit */
    float *albedo; /* size*size*3: albedo at the hit */
} btf_view_map;
btf_status btf__view_map_make(const btf_procedural *m, btf_dir view, btf_view_map **out,
                              btf_error *err);
void btf__view_map_free(btf_view_map *vm);

typedef struct btf_light_map {
    int size;
    float *vis;    /* size*size: visibility of the light from the surface point
                      above texel (x, y): 0 in cast shadow .. 1 lit (soft edge) */
} btf_light_map;
btf_status btf__light_map_make(const btf_procedural *m, btf_dir light, btf_light_map **out,
                               btf_error *err);
void btf__light_map_free(btf_light_map *lm);

/* Shades one (view, light) pair from its maps into out (allocated here, size x
 * size x 3; the caller frees it). view and light must be the directions the
 * maps were made for. */
btf_status btf__material_render_maps(const btf_procedural *m, const btf_view_map *vm,
                                     const btf_light_map *lm, btf_dir view, btf_dir light,
                                     btf_image *out, btf_error *err);
/* Recomputes m->normal from m->height (central differences, wrapping). */
void btf__material_normals_from_height(btf_procedural *m); /* generate/material.c */

#endif
