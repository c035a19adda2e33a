/*
 * render_scene.c — the whole render (Haindl & Filip 2007, section III):
 * trace the scene into a G-buffer (src/scene/), find the subspaces its
 * pixels need (render/needed.c), synthesise only those, tileable, at the
 * size the visible surface needs (render/render_material.c), and shade
 * (render/shade.c). Also the flat (view, light) render, the model's
 * counterpart of one measured image.
 */
#include "render/shade.h"
#include "core/core.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The auto texture size stops here: a surface that shows more texels than
 * this sees the tileable images repeat (docs/render.md). */
#define AUTO_TEXTURE_MAX 1024

btf_render_opts btf_render_defaults(void)
{
    btf_render_opts o;
    memset(&o, 0, sizeof o);
    o.struct_size = sizeof o;
    o.width = o.height = 512;
    o.relief = 1.0;
    return o;
}

static btf_status resolve_opts(const btf_render_opts *in, btf_render_opts *o, btf_error *err)
{
    btf_render_opts d = btf_render_defaults();
    if (btf__opts_take(o, sizeof *o, in, &d, "btf_render", err))
        return BTF_E_ARG;
    if (o->width == 0)
        o->width = d.width;
    if (o->height == 0)
        o->height = d.height;
    if (o->relief < 0.0)
        o->relief = d.relief;
    if (o->width < 1 || o->height < 1 || o->width > BTF_RENDER_MAX_SIDE ||
        o->height > BTF_RENDER_MAX_SIDE)
        return btf__fail(err, BTF_E_ARG, "frame %dx%d: each side must be 1..%d", o->width,
                         o->height, BTF_RENDER_MAX_SIDE);
    if (!isfinite(o->relief) || o->relief > 1e6)
        return btf__fail(err, BTF_E_ARG, "relief %g: expected 0..1e6", o->relief);
    if (o->texture_size < 0 || o->texture_size > BTF_RENDER_MAX_SIDE)
        return btf__fail(err, BTF_E_ARG, "texture size %d: expected 0 (auto) or 8..%d",
                         o->texture_size, BTF_RENDER_MAX_SIDE);
    return BTF_OK;
}

/* Host bytes per pixel every render holds: the G-buffer (object id 4, uv 8,
 * tangent frame 36, position 12, view 12) and the frame (RGB float, 12). */
#define RENDER_PIXEL_BYTES 84.0
/* Host bytes per texel of the texture side: the range map's height (4) and
 * normals (12), which both backends build on the host. */
#define RENDER_TEXEL_BYTES 16.0

/* Refuses a render whose memory cannot fit, before any of it is allocated
 * or traced: a 16384-pixel square frame would otherwise run for minutes
 * and then fail or be killed. The estimate is a lower bound (the subspace
 * images and synthesis' work come on top: 12 bytes a texel for each needed
 * subspace on the CPU), so nothing that fits is refused; a flat 16384^2
 * frame, about 30 GB at its measured peak, is refused at 26.8 GB. */
static btf_status check_memory(const btf_render_opts *o, int side, btf_error *err)
{
    double need = RENDER_PIXEL_BYTES * (double)o->width * (double)o->height +
                  RENDER_TEXEL_BYTES * (double)side * (double)side;
    uint64_t avail = btf__memory_available();
    if (avail == UINT64_MAX || need <= (double)avail)
        return BTF_OK;
    return btf__fail(err, BTF_E_NOMEM, "render %dx%d: needs at least %.1f GB of memory (%.0f "
                     "bytes a pixel, %.0f a texel of the %d-texel texture side), more than the "
                     "%.1f GB available", o->width, o->height, need * 1e-9, RENDER_PIXEL_BYTES,
                     RENDER_TEXEL_BYTES, side, (double)avail * 1e-9);
}

/* The texels the visible surface spans: the largest extent of the hit
 * pixels' texture coordinates along u or v, per object, over all objects
 * (at most AUTO_TEXTURE_MAX; 0 when nothing is hit). */
static int visible_extent(const btf_gbuffer *g, btf_error *err)
{
    size_t n = (size_t)g->width * (size_t)g->height;
    int objects = 0;
    for (size_t p = 0; p < n; p++)
        if (g->object[p] >= objects)
            objects = g->object[p] + 1;
    if (objects == 0)
        return 0;
    double *box = btf__alloc((size_t)objects, 4 * sizeof(double), err);
    if (!box)
        return -1;
    for (int k = 0; k < objects; k++) {
        box[4 * k] = box[4 * k + 1] = INFINITY;
        box[4 * k + 2] = box[4 * k + 3] = -INFINITY;
    }
    for (size_t p = 0; p < n; p++) {
        int k = g->object[p];
        for (int a = 0; a < 2 && k >= 0; a++) {
            double u = g->uv[2 * p + a];
            if (!isfinite(u))
                continue;
            box[4 * k + a] = u < box[4 * k + a] ? u : box[4 * k + a];
            box[4 * k + 2 + a] = u > box[4 * k + 2 + a] ? u : box[4 * k + 2 + a];
        }
    }
    double ext = 0.0;
    for (int k = 0; k < objects; k++)
        for (int a = 0; a < 2; a++)
            if (box[4 * k + 2 + a] - box[4 * k + a] > ext)
                ext = box[4 * k + 2 + a] - box[4 * k + a];
    free(box);
    return ext > AUTO_TEXTURE_MAX ? AUTO_TEXTURE_MAX : (int)ceil(ext);
}

/* The needed set and the texture side of a traced plan. */
static btf_status plan_needs(const btf_model *m, btf_render_plan *p, btf_error *err)
{
    double t0 = btf__now();
    p->needed = btf__alloc((size_t)m->n_subspaces, 1, err);
    if (!p->needed)
        return BTF_E_NOMEM;
    btf_status rc = btf__render_needed(m, &p->g, p->lights, p->n_lights, p->needed, &p->count,
                                       err);
    if (rc)
        return rc;
    if (p->o.all_subspaces) {
        memset(p->needed, 1, (size_t)m->n_subspaces);
        p->count = m->n_subspaces;
    }
    int want = p->o.texture_size;
    if (want == 0 && (want = visible_extent(&p->g, err)) < 0)
        return BTF_E_NOMEM;
    p->side = btf__render_texture_side(m, want);
    if (p->o.texture_size && p->side != p->o.texture_size)
        return btf__fail(err, BTF_E_ARG, "texture size %d: expected a multiple of the model's "
                         "pyramid step, e.g. %d", p->o.texture_size, p->side);
    p->needed_s = btf__now() - t0;
    return BTF_OK;
}

void btf__render_plan_free(btf_render_plan *p)
{
    if (!p)
        return;
    btf__gbuffer_free(&p->g);
    free(p->needed);
    memset(p, 0, sizeof *p);
}

btf_status btf__render_plan_scene(const btf_model *m, const btf_scene *s,
                                  const btf_render_opts *opts, btf_render_plan *p,
                                  btf_error *err)
{
    memset(p, 0, sizeof *p);
    btf_status rc = resolve_opts(opts, &p->o, err);
    /* the auto texture side is known only after tracing; at most 1024 */
    if (rc || (rc = btf__render_check_model(m, err)) ||
        (rc = check_memory(&p->o, p->o.texture_size, err)))
        return rc;
    if (!s)
        return btf__fail(err, BTF_E_ARG, "render: no scene given");
    if ((rc = btf_scene_check(s, err)))
        return rc;
    if (s->n_lights > BTF_RENDER_MAX_LIGHTS)
        return btf__fail(err, BTF_E_ARG, "scene: %d lights: the renderer takes at most %d",
                         s->n_lights, BTF_RENDER_MAX_LIGHTS);
    double t0 = btf__now();
    if ((rc = btf__scene_trace(s, p->o.width, p->o.height, p->o.threads, &p->g, err)))
        return rc;
    p->trace_s = btf__now() - t0;
    p->lights = s->lights;
    p->n_lights = s->n_lights;
    memcpy(p->background, s->background, sizeof p->background);
    if ((rc = plan_needs(m, p, err)))
        btf__render_plan_free(p);
    return rc;
}

void btf__render_plan_info(const btf_model *m, const btf_render_plan *p, btf_render_info *info)
{
    if (!info)
        return;
    info->needed = p->count;
    info->total = m->n_subspaces;
    info->texture_size = p->side;
    info->trace_s = p->trace_s;
}

btf_status btf_render_scene(const btf_model *m, const btf_scene *s, const btf_render_opts *opts,
                            btf_image *out, btf_render_info *info, btf_error *err)
{
    if (!out)
        return btf__fail(err, BTF_E_ARG, "render: no output given");
    if (info)
        memset(info, 0, sizeof *info);
    btf_render_plan p;
    btf_status rc = btf__render_plan_scene(m, s, opts, &p, err);
    if (rc == BTF_OK)
        rc = btf__render_plan_cpu(m, &p, out, info, err);
    btf__render_plan_free(&p);
    return rc;
}

btf_status btf__render_plan_cpu(const btf_model *m, const btf_render_plan *p, btf_image *out,
                                btf_render_info *info, btf_error *err)
{
    btf_render_material *rm = NULL;
    double t0 = btf__now();
    btf_status rc = btf__render_material_build(m, p->needed, p->side, p->o.seed, p->o.threads,
                                               &rm, err);
    double t1 = btf__now();
    if (rc == BTF_OK)
        rc = btf__render_shade(rm, &p->g, p->lights, p->n_lights, p->background, p->o.relief,
                               p->o.threads, out, err);
    double t2 = btf__now();
    btf__render_plan_info(m, p, info);
    if (info) {
        info->synth_s = p->needed_s + (t1 - t0);
        info->shade_s = t2 - t1;
    }
    btf__render_material_free(rm);
    return rc;
}
/* The orthographic G-buffer of a flat patch: texel (x, y) at pixel (x, y),
 * the tangent frame the world's axes, one view for all pixels. */
btf_status btf__render_flat_gbuffer(int w, int h, const float view[3], btf_gbuffer *g,
                                  btf_error *err)
{
    size_t n = (size_t)w * (size_t)h;
    memset(g, 0, sizeof *g);
    g->width = w;
    g->height = h;
    g->object = btf__alloc(n, sizeof *g->object, err);
    g->uv = btf__alloc(n, 2 * sizeof(float), err);
    g->frame = btf__alloc(n, 9 * sizeof(float), err);
    g->position = btf__alloc(n, 3 * sizeof(float), err);
    g->view = btf__alloc(n, 3 * sizeof(float), err);
    if (!g->object || !g->uv || !g->frame || !g->position || !g->view) {
        btf__gbuffer_free(g);
        return BTF_E_NOMEM;
    }
    static const float identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            size_t p = (size_t)y * (size_t)w + (size_t)x;
            g->object[p] = 0;
            g->uv[2 * p] = (float)x + 0.5f;
            g->uv[2 * p + 1] = (float)y + 0.5f;
            memcpy(g->frame + 9 * p, identity, sizeof identity);
            g->position[3 * p] = g->uv[2 * p];
            g->position[3 * p + 1] = -g->uv[2 * p + 1];
            g->position[3 * p + 2] = 0.0f;
            memcpy(g->view + 3 * p, view, 3 * sizeof(float));
        }
    return BTF_OK;
}

static btf_status check_flat_dir(const char *what, btf_dir d, btf_error *err)
{
    if (!(d.theta >= 0.0 && d.theta <= 90.0) || !isfinite(d.phi))
        return btf__fail(err, BTF_E_ARG, "%s direction (theta %g, phi %g): theta must be in "
                         "[0, 90] degrees and phi finite", what, d.theta, d.phi);
    return BTF_OK;
}

btf_status btf__render_plan_flat(const btf_model *m, btf_dir view, btf_dir light,
                                 const btf_render_opts *opts, btf_render_plan *p,
                                 btf_error *err)
{
    memset(p, 0, sizeof *p);
    btf_status rc = resolve_opts(opts, &p->o, err);
    if (rc || (rc = btf__render_check_model(m, err)) ||
        (rc = check_flat_dir("view", view, err)) || (rc = check_flat_dir("light", light, err)))
        return rc;
    /* without a texture size, a frame-sized texture: one texel per pixel,
     * no repeat */
    int side = p->o.texture_size ? p->o.texture_size
                                 : btf__render_texture_side(m, p->o.width > p->o.height
                                                                  ? p->o.width : p->o.height);
    if ((rc = check_memory(&p->o, side, err)))
        return rc;
    double v[3], l[3];
    btf_dir_to_vec(view, v);
    btf_dir_to_vec(light, l);
    float vf[3] = {(float)v[0], (float)v[1], (float)v[2]};
    p->sun.kind = BTF_LIGHT_DIRECTIONAL;
    for (int i = 0; i < 3; i++) {
        p->sun.direction[i] = l[i];
        p->sun.rgb[i] = 1.0f;
    }
    p->lights = &p->sun;
    p->n_lights = 1;
    if ((rc = btf__render_flat_gbuffer(p->o.width, p->o.height, vf, &p->g, err)))
        return rc;
    p->o.texture_size = side;
    if ((rc = plan_needs(m, p, err)))
        btf__render_plan_free(p);
    return rc;
}

btf_status btf_render_flat(const btf_model *m, btf_dir view, btf_dir light,
                           const btf_render_opts *opts, btf_image *out, btf_render_info *info,
                           btf_error *err)
{
    if (!out)
        return btf__fail(err, BTF_E_ARG, "render: no output given");
    if (info)
        memset(info, 0, sizeof *info);
    btf_render_plan p;
    btf_status rc = btf__render_plan_flat(m, view, light, opts, &p, err);
    if (rc == BTF_OK)
        rc = btf__render_plan_cpu(m, &p, out, info, err);
    btf__render_plan_free(&p);
    return rc;
}
