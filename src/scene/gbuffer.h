/*
 * gbuffer.h — ray casting a scene into a G-buffer (src/scene/trace.c),
 * which the CPU and GPU renderers of both model families shade. Private to
 * the library; the public entries are btf_render_scene, btf__rf_render_scene
 * and their GPU forms.
 */
#ifndef BTF_SCENE_GBUFFER_H
#define BTF_SCENE_GBUFFER_H

#include "btfcar.h"

#include <stdint.h>

/* What ray casting gives per pixel: the G-buffer the renderer shades (and
 * uploads for the GPU pass). Pixel (x, y), row y from the top; arrays are
 * row-major, p = y * width + x. frame rows: T (direction of increasing u),
 * B (decreasing v: up the texture image), N (shading normal towards the
 * eye); orthonormal, T x B = N. uv may be negative or beyond the texture
 * (the renderer wraps); a surface seen from behind has u negated so that
 * the material never reads mirrored (docs/scene.md). Background pixels:
 * object -1, uv 0, position 0, frame the identity, view still the ray's. */
typedef struct btf_gbuffer {
    int width, height;
    int32_t *object;                /* object index, -1: background */
    float *uv;                      /* [2] material texels: u along columns, v down rows */
    float *frame;                   /* [9] tangent (phi = 0), bitangent (phi = 90), normal; world */
    float *position;                /* [3] world hit point */
    float *view;                    /* [3] world unit vector from the hit towards the eye */
} btf_gbuffer;

/* Casts one ray per pixel centre (BVH over mesh triangles, built per call),
 * on `threads` threads (0: all CPUs); the result does not depend on the
 * thread count. Checks the scene first (btf_scene_check). width, height in
 * 1 .. 65536. */
btf_status btf__scene_trace(const btf_scene *s, int width, int height, int threads,
                            btf_gbuffer *out, btf_error *err);
void btf__gbuffer_free(btf_gbuffer *g);

#endif
