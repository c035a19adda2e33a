/*
 * trace.c — btf__scene_trace: one primary ray per pixel centre through a
 * pinhole camera (row 0 at the top), the nearest hit over every object
 * (analytic shapes, meshes through their BVH, built here once per call),
 * written to the G-buffer the renderer shades (docs/scene.md, "G-buffer").
 * Rows are the thread pool's jobs; a pixel depends on its position alone,
 * so the result does not depend on the thread count.
 */
#include "scene/scene.h"
#include "core/core.h"

#include <stdlib.h>
#include <string.h>

typedef struct trace_ctx {
    const btf_scene *s;
    scene_bvh *bvh;          /* [n_objects]; used for meshes */
    double eye[3], right[3], up[3], forward[3];
    double tan_half, aspect;
    btf_gbuffer *g;
} trace_ctx;

/* The nearest hit of ray (o, d) over all objects; its object or -1. */
static int nearest(const trace_ctx *c, const double o[3], const double d[3], scene_hit *best)
{
    const btf_scene *s = c->s;
    double t_max = INFINITY;
    int hit = -1;
    int mesh_tri = -1;
    double mb1 = 0.0, mb2 = 0.0;
    for (int i = 0; i < s->n_objects; i++) {
        const btf_object *ob = &s->objects[i];
        scene_hit h;
        int found = 0;
        switch (ob->kind) {
        case BTF_OBJECT_PLANE: found = scene_hit_plane(ob, o, d, t_max, &h); break;
        case BTF_OBJECT_SPHERE: found = scene_hit_sphere(ob, o, d, t_max, &h); break;
        case BTF_OBJECT_CYLINDER: found = scene_hit_cylinder(ob, o, d, t_max, &h); break;
        case BTF_OBJECT_MESH: {
            /* The mesh's vertices are relative to its center. */
            double ol[3];
            v3_sub(o, ob->center, ol);
            int tri;
            double t, b1, b2;
            if (scene_bvh_hit(&c->bvh[i], ol, d, t_max, &tri, &t, &b1, &b2)) {
                t_max = t;
                hit = i;
                mesh_tri = tri, mb1 = b1, mb2 = b2;
                best->t = t;
            }
            continue;
        }
        }
        if (found) {
            t_max = h.t;
            hit = i;
            mesh_tri = -1;
            *best = h;
        }
    }
    if (hit >= 0 && mesh_tri >= 0) {
        /* The surface of the nearest mesh hit, computed once. */
        const btf_object *ob = &s->objects[hit];
        double t = best->t, view[3] = {-d[0], -d[1], -d[2]};
        scene_mesh_surface(ob, mesh_tri, mb1, mb2, view, best);
        best->t = t;
        for (int i = 0; i < 3; i++)
            best->position[i] = o[i] + t * d[i];
    }
    return hit;
}

static btf_status trace_row(void *user, int y, int worker, btf_error *err)
{
    (void)worker, (void)err;
    const trace_ctx *c = user;
    btf_gbuffer *g = c->g;
    int w = g->width, h = g->height;
    double sy = (1.0 - 2.0 * (y + 0.5) / h) * c->tan_half;
    for (int x = 0; x < w; x++) {
        size_t p = (size_t)y * (size_t)w + (size_t)x;
        double sx = (2.0 * (x + 0.5) / w - 1.0) * c->tan_half * c->aspect;
        double d[3];
        for (int i = 0; i < 3; i++)
            d[i] = c->forward[i] + sx * c->right[i] + sy * c->up[i];
        v3_normalize(d);
        scene_hit hit;
        int ob = nearest(c, c->eye, d, &hit);
        g->object[p] = ob;
        for (int i = 0; i < 3; i++)
            g->view[3 * p + i] = (float)-d[i];
        if (ob < 0) {
            /* Background: a fixed frame, nothing else to read. */
            static const float id[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
            memcpy(g->frame + 9 * p, id, sizeof id);
            g->uv[2 * p] = g->uv[2 * p + 1] = 0.0f;
            g->position[3 * p] = g->position[3 * p + 1] = g->position[3 * p + 2] = 0.0f;
            continue;
        }
        g->uv[2 * p] = (float)hit.uv[0];
        g->uv[2 * p + 1] = (float)hit.uv[1];
        for (int i = 0; i < 9; i++)
            g->frame[9 * p + i] = (float)hit.frame[i];
        for (int i = 0; i < 3; i++)
            g->position[3 * p + i] = (float)hit.position[i];
    }
    return BTF_OK;
}

void btf__gbuffer_free(btf_gbuffer *g)
{
    if (!g)
        return;
    BTF_FREE_ALL(g->object, g->uv, g->frame, g->position, g->view);
    memset(g, 0, sizeof *g);
}

static void camera_basis(const btf_camera *cam, trace_ctx *c)
{
    for (int i = 0; i < 3; i++)
        c->eye[i] = cam->position[i];
    v3_sub(cam->target, cam->position, c->forward);
    v3_normalize(c->forward);
    v3_cross(c->forward, cam->up, c->right);
    v3_normalize(c->right);
    v3_cross(c->right, c->forward, c->up);
    c->tan_half = tan(0.5 * cam->fov_deg * (M_PI / 180.0));
}

btf_status btf__scene_trace(const btf_scene *s, int width, int height, int threads,
                            btf_gbuffer *out, btf_error *err)
{
    if (!out)
        return btf__fail(err, BTF_E_ARG, "btf_scene_trace: no G-buffer given");
    memset(out, 0, sizeof *out);
    if (width < 1 || height < 1 || width > BTF_MAX_SIDE || height > BTF_MAX_SIDE)
        return btf__fail(err, BTF_E_ARG, "btf_scene_trace: size %dx%d is not within 1..%d",
                         width, height, BTF_MAX_SIDE);
    if (threads < 0)
        return btf__fail(err, BTF_E_ARG, "btf_scene_trace: threads %d < 0", threads);
    btf_status rc = scene_check_named(s, "scene", err);
    if (rc)
        return rc;
    trace_ctx c = {.s = s, .g = out, .aspect = (double)width / height};
    camera_basis(&s->camera, &c);
    c.bvh = btf__calloc(s->n_objects ? (size_t)s->n_objects : 1, sizeof *c.bvh, err);
    if (!c.bvh)
        return BTF_E_NOMEM;
    for (int i = 0; i < s->n_objects && !rc; i++)
        if (s->objects[i].kind == BTF_OBJECT_MESH)
            rc = scene_bvh_build(&s->objects[i].mesh, &c.bvh[i], err);
    size_t n = (size_t)width * (size_t)height;
    out->width = width, out->height = height;
    if (!rc) {
        out->object = btf__alloc(n, sizeof *out->object, err);
        out->uv = btf__alloc(n * 2, sizeof *out->uv, err);
        out->frame = btf__alloc(n * 9, sizeof *out->frame, err);
        out->position = btf__alloc(n * 3, sizeof *out->position, err);
        out->view = btf__alloc(n * 3, sizeof *out->view, err);
        if (!out->object || !out->uv || !out->frame || !out->position || !out->view)
            rc = btf__fail(err, BTF_E_NOMEM, "btf_scene_trace: out of memory for a %dx%d "
                           "G-buffer", width, height);
    }
    if (!rc)
        rc = btf__pool_run(height, threads, trace_row, &c, NULL, err);
    for (int i = 0; i < s->n_objects; i++)
        scene_bvh_free(&c.bvh[i]);
    free(c.bvh);
    if (rc)
        btf__gbuffer_free(out);
    return rc;
}
