/*
 * shade.h — the renderer's private parts (src/render/): the material ready
 * to shade with, and the C side of the shading text shared with the GPU
 * pass (btf_render_shared.h): the context its accessors read. The needed-
 * subspace walk and the shading both go through that text, so they take the
 * very same directions and weights (docs/render.md).
 */
#ifndef BTF_RENDER_SHADE_H
#define BTF_RENDER_SHADE_H

#include "btfcar.h"
#include "render/render.h"

#include <math.h>
#include <stdint.h>

struct btf_render_material {
    int n_views, n_lights, n_subspaces;
    uint8_t *index;          /* [view * n_lights + light] -> subspace (a copy) */
    btf_hemisphere *views;   /* triangulations of the two direction sets */
    btf_hemisphere *lights;
    float light_outer_z;     /* cos of the largest measured light theta */
    float ambient;           /* the model's ambient term (btf_model.ambient) */
    int size;                /* side of every image below */
    btf_image height;        /* size x size x 1, heights in texels */
    btf_image normal;        /* size x size x 3, unit tangent-frame normals */
    btf_image *tex;          /* [n_subspaces]; data NULL where not built */
    float *gain;             /* [pair * 3 + c]: the pair gains (1 without) */
    uint32_t *horizon;       /* size x size x 2 words (btf_horizon.h); NULL: no shadows */
    float hmin, hmax;        /* the height map's extremes */
};

/* What the shared shading reads on the CPU. */
#define BTF_SHADE_CTX_MAX_SUBSPACES 256
typedef struct btf_shade_ctx {
    btf_hemisphere_table views, lights;
    int size, n_lights_set;
    const uint8_t *index;
    const float *tex[BTF_SHADE_CTX_MAX_SUBSPACES]; /* NULL: not synthesised */
    const float *height, *normal;
    const float *gain;
    const uint32_t *horizon;
    float hmin, hmax;
    float light_outer_z, ambient;
    int n_lights;
    int kind[16];
    float vec[16][3], rgb[16][3];
} btf_shade_ctx;

#define BTF_SHADE_CTX const btf_shade_ctx *
#define BTF_SHADE_VIEWS(ctx) (&(ctx)->views)
#define BTF_SHADE_LIGHTS(ctx) (&(ctx)->lights)
#define BTF_SHADE_SIZE(ctx) ((ctx)->size)
#define BTF_SHADE_N_LIGHTS_SET(ctx) ((ctx)->n_lights_set)
#define BTF_SHADE_INDEX(ctx, i) ((int)(ctx)->index[i])
#define BTF_SHADE_HAVE(ctx, k) ((ctx)->tex[k] != NULL)
#define BTF_SHADE_TEX(ctx, k, i) ((ctx)->tex[k][i])
#define BTF_SHADE_HEIGHT(ctx, i) ((ctx)->height[i])
#define BTF_SHADE_NORMAL(ctx, i) ((ctx)->normal[i])
#define BTF_SHADE_LIGHT_OUTER_Z(ctx) ((ctx)->light_outer_z)
#define BTF_SHADE_AMBIENT(ctx) ((ctx)->ambient)
#define BTF_SHADE_GAIN(ctx, i, c) ((ctx)->gain[3 * (i) + (c)])
#define BTF_SHADE_HAS_HORIZON(ctx) ((ctx)->horizon != NULL)
#define BTF_SHADE_HORIZON(ctx, i) ((ctx)->horizon[i])
#define BTF_SHADE_HMIN(ctx) ((ctx)->hmin)
#define BTF_SHADE_HMAX(ctx) ((ctx)->hmax)
#define BTF_SHADE_N_LIGHTS(ctx) ((ctx)->n_lights)
#define BTF_SHADE_LIGHT_KIND(ctx, j) ((ctx)->kind[j])
#define BTF_SHADE_LIGHT_VEC(ctx, j, k) ((ctx)->vec[j][k])
#define BTF_SHADE_LIGHT_RGB(ctx, j, k) ((ctx)->rgb[j][k])
#include "render/btf_render_shared.h"

/* What the shading reads of the relief besides its heights and normals,
 * the same for both backends: the height map's extremes (bounds: lowest,
 * highest; the view march's span) and, for a model whose relief casts
 * shadows, its horizon map round the torus (*horizon, the caller frees it;
 * NULL without shadows). */
btf_status btf__render_relief(const btf_model *m, const btf_image *height, int threads,
                              uint32_t **horizon, float bounds[2], btf_error *err);

/* A model that can be rendered: subspaces, an index table, directions. */
btf_status btf__render_check_model(const btf_model *m, btf_error *err);

/* The tileable size nearest above `side` that every subspace's pyramid
 * divides (a multiple of 2^(levels - 1)), at least 8. */
int btf__render_texture_side(const btf_model *m, int side);

/* cos of the largest measured light theta: below it a light is beyond the
 * outermost ring (btf_shade_bump's horizon fade). */
float btf__render_light_outer_z(const btf_model *m);
/* The shading's ambient term of m (btf_render_shared.h): -1 without a
 * structure layer (the plain bump factor). */
float btf__render_ambient(const btf_model *m);
/* The direction sets the renderer triangulates (docs/render.md, "Sparse
 * pair sets"): the model's; a set of 1 or 2 directions (one camera over a
 * light dome) gains ghost directions to make a triangle, each standing for
 * the set's direction nearest to it. view_of[i], light_of[j]: the model's
 * direction that the renderer's direction i, j stands for. */
typedef struct btf_render_sets {
    btf_dirset views, lights;
    int *view_of, *light_of;
} btf_render_sets;
btf_status btf__render_sets_make(const btf_model *m, btf_render_sets *s, btf_error *err);
void btf__render_sets_free(btf_render_sets *s);
/* The index table the shading reads (the renderer's views x lights, the
 * caller frees it): the model's, where a sparse model (BTF_PAIR_NONE
 * entries) lets each pair it did not measure stand for the measured pair
 * nearest in the space of pairs (docs/render.md, "Sparse pair sets"). */
uint8_t *btf__render_pair_index(const btf_model *m, const btf_render_sets *s, btf_error *err);
/* The pair gains the shading multiplies (views x lights x 3 floats, the
 * caller frees them): the model's, or 1 for a model without; a pair not
 * measured takes its stand-in's (btf__render_pair_index). */
float *btf__render_gains(const btf_model *m, const btf_render_sets *s, btf_error *err);
/* The factor subspace k's texture is scaled by before shading: 1 / (a +
 * l_z) of its representative light with a structure layer, else 1. */
float btf__render_reflectance(const btf_model *m, int k);
/* floats of a texture times g, in place (the same on both backends). */
void btf__render_scale_texture(float *data, size_t floats, float g);

/* The lights as the shared shading reads them (directions made unit);
 * BTF_E_ARG for more than BTF_RENDER_MAX_LIGHTS. */
btf_status btf__render_ctx_lights(btf_shade_ctx *ctx, const btf_light *lights, int n_lights,
                                  btf_error *err);

/* The context of a material (lights not set). */
void btf__render_ctx_material(btf_shade_ctx *ctx, const struct btf_render_material *rm);

/* What a render does before it synthesises and shades, the same for both
 * backends: the options resolved, the G-buffer traced (or the flat
 * patch's), the lights, the needed subspaces and the texture side. The
 * lights point into the scene (or at `sun`, the flat render's light). */
typedef struct btf_render_plan {
    btf_render_opts o;
    btf_gbuffer g;
    const btf_light *lights;
    int n_lights;
    btf_light sun;
    float background[3];
    uint8_t *needed;
    int count, side;
    double trace_s, needed_s;
} btf_render_plan;

btf_status btf__render_plan_scene(const btf_model *m, const btf_scene *s,
                                  const btf_render_opts *opts, btf_render_plan *p,
                                  btf_error *err);
btf_status btf__render_plan_flat(const btf_model *m, btf_dir view, btf_dir light,
                                 const btf_render_opts *opts, btf_render_plan *p,
                                 btf_error *err);
void btf__render_plan_free(btf_render_plan *p);
/* The CPU backend on a plan: synthesis of the needed subspaces, shading. */
btf_status btf__render_plan_cpu(const btf_model *m, const btf_render_plan *p, btf_image *out,
                                btf_render_info *info, btf_error *err);
/* The orthographic G-buffer of a flat patch (the flat render's): texel
 * (x, y) at pixel (x, y), the tangent frame the world's axes, the unit
 * vector view towards the eye for every pixel. */
btf_status btf__render_flat_gbuffer(int w, int h, const float view[3], btf_gbuffer *g,
                                    btf_error *err);
/* The counts and the trace time of a plan into info. */
void btf__render_plan_info(const btf_model *m, const btf_render_plan *p, btf_render_info *info);

#endif
