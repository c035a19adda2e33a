/*
 * shade.h — the renderer's private parts (src/render/): the material ready
 * to shade with, and the small vector and sampling helpers that the needed-
 * subspace walk and the shading share, so that both take the very same
 * directions and weights (docs/render.md).
 */
#ifndef BTF_RENDER_SHADE_H
#define BTF_RENDER_SHADE_H

#include "btfcar.h"

#include <math.h>
#include <stdint.h>

struct btf_render_material {
    int n_views, n_lights, n_subspaces;
    uint8_t *index;          /* [view * n_lights + light] -> subspace (a copy) */
    btf_hemisphere *views;   /* triangulations of the two direction sets */
    btf_hemisphere *lights;
    float light_outer_z;     /* cos of the largest measured light theta */
    int size;                /* side of every image below */
    btf_image height;        /* size x size x 1, heights in texels */
    btf_image normal;        /* size x size x 3, unit tangent-frame normals */
    btf_image *tex;          /* [n_subspaces]; data NULL where not built */
};

/* A model that can be rendered: subspaces, an index table, directions. */
btf_status btf_render_check_model(const btf_model *m, btf_error *err);

/* The tileable size nearest above `side` that every subspace's pyramid
 * divides (a multiple of 2^(levels - 1)), at least 8. */
int btf_render_texture_side(const btf_model *m, int side);

/* The light's direction from world point p (unit) and its intensity there:
 * a point light falls off as 1 / d^2. 0 when the light is at p. */
int btf_render_light_at(const btf_light *l, const float p[3], float dir[3], float rgb[3]);

/* A world vector in the pixel's tangent frame (frame: T, B, N rows). */
static inline void btf_render_to_local(const float *frame, const float w[3], float out[3])
{
    for (int i = 0; i < 3; i++)
        out[i] = frame[3 * i] * w[0] + frame[3 * i + 1] * w[1] + frame[3 * i + 2] * w[2];
}

/* The pairs of a pixel: three views x three lights with their weights, the
 * subspace of each (the same rule in the walk and the shading: a pair
 * counts when both its weights are > 0). */
typedef struct btf_render_pairs {
    int n;               /* distinct subspaces, <= 9 */
    int sub[9];
    float w[9];          /* summed weight per distinct subspace */
} btf_render_pairs;

void btf_render_pairs_of(const uint8_t *index, int n_lights, const int iv[3],
                         const float wv[3], const int il[3], const float wl[3],
                         btf_render_pairs *out);

/* The local view direction of a pixel, its z kept above the horizon by
 * BTF_RENDER_MIN_Z (an interpolated mesh normal can turn slightly away
 * from the eye). */
#define BTF_RENDER_MIN_Z 1e-3f
void btf_render_local_view(const float *frame, const float view[3], float out[3]);

#endif
