/*
 * scene_check.c — the value rules of a scene (docs/scene.md, "Ranges"),
 * for scenes built in memory and, after parsing, for scene files: one
 * error naming the scene (file), the key path as the file spells it
 * (objects[2].radius) and the problem. Finite numbers within
 * SCENE_MAX_COORD, unit directions, a camera that defines a view.
 */
#include "scene/scene.h"
#include "core/core.h"

#include <stdio.h>

/* A key path for messages: "objects[2].radius". */
static const char *key(char *buf, size_t n, const char *list, int i, const char *field)
{
    if (i < 0)
        snprintf(buf, n, "%s.%s", list, field);
    else
        snprintf(buf, n, "%s[%d].%s", list, i, field);
    return buf;
}

static btf_status check_vec(const char *name, const char *k, const double v[3], btf_error *err)
{
    for (int i = 0; i < 3; i++) {
        if (!isfinite(v[i]))
            return btf__fail(err, BTF_E_DATA, "%s: %s: component %d is not finite", name, k, i);
        if (fabs(v[i]) > SCENE_MAX_COORD)
            return btf__fail(err, BTF_E_DATA, "%s: %s: component %d is %g, beyond +-%g", name,
                             k, i, v[i], SCENE_MAX_COORD);
    }
    return BTF_OK;
}

static btf_status check_unit(const char *name, const char *k, const double v[3], btf_error *err)
{
    btf_status rc = check_vec(name, k, v, err);
    if (rc)
        return rc;
    double l = v3_len(v);
    if (l == 0.0)
        return btf__fail(err, BTF_E_DATA, "%s: %s: zero-length direction", name, k);
    if (fabs(l - 1.0) > 1e-6)
        return btf__fail(err, BTF_E_DATA, "%s: %s: not a unit vector (length %g)", name, k, l);
    return BTF_OK;
}

/* A positive length within range. */
static btf_status check_length(const char *name, const char *k, double v, btf_error *err)
{
    if (!isfinite(v))
        return btf__fail(err, BTF_E_DATA, "%s: %s: not finite", name, k);
    if (!(v > 0.0) || v > SCENE_MAX_COORD)
        return btf__fail(err, BTF_E_DATA, "%s: %s: %g is out of range (0, %g]", name, k, v,
                         SCENE_MAX_COORD);
    return BTF_OK;
}

static btf_status check_rgb(const char *name, const char *k, const float c[3], btf_error *err)
{
    for (int i = 0; i < 3; i++)
        if (!isfinite(c[i]) || c[i] < 0.0f || c[i] > SCENE_MAX_COORD)
            return btf__fail(err, BTF_E_DATA, "%s: %s: component %d is %g, not in [0, %g]",
                             name, k, i, (double)c[i], SCENE_MAX_COORD);
    return BTF_OK;
}

static btf_status check_camera(const btf_camera *c, const char *name, btf_error *err)
{
    btf_status rc;
    if ((rc = check_vec(name, "camera.position", c->position, err)) ||
        (rc = check_vec(name, "camera.target", c->target, err)) ||
        (rc = check_vec(name, "camera.up", c->up, err)))
        return rc;
    if (!isfinite(c->fov_deg) || !(c->fov_deg > 0.0 && c->fov_deg < 180.0))
        return btf__fail(err, BTF_E_DATA, "%s: camera.fov: %g degrees is not in (0, 180)", name,
                         c->fov_deg);
    double f[3], u[3] = {c->up[0], c->up[1], c->up[2]}, x[3];
    v3_sub(c->target, c->position, f);
    if (!v3_normalize(f) || v3_len(f) == 0.0)
        return btf__fail(err, BTF_E_DATA, "%s: camera.target: equals camera.position (no view "
                         "direction)", name);
    if (!v3_normalize(u))
        return btf__fail(err, BTF_E_DATA, "%s: camera.up: zero-length direction", name);
    v3_cross(f, u, x);
    if (v3_len(x) < 1e-6)
        return btf__fail(err, BTF_E_DATA, "%s: camera.up: parallel to the view direction "
                         "(target - position)", name);
    return BTF_OK;
}

static btf_status check_light(const btf_light *l, int i, const char *name, btf_error *err)
{
    char k[64];
    if (l->kind == BTF_LIGHT_DIRECTIONAL) {
        btf_status rc = check_unit(name, key(k, sizeof k, "lights", i, "direction"),
                                   l->direction, err);
        if (rc)
            return rc;
    } else if (l->kind == BTF_LIGHT_POINT) {
        btf_status rc = check_vec(name, key(k, sizeof k, "lights", i, "position"), l->position,
                                  err);
        if (rc)
            return rc;
    } else {
        return btf__fail(err, BTF_E_DATA, "%s: %s: unknown light kind %d", name,
                         key(k, sizeof k, "lights", i, "type"), (int)l->kind);
    }
    return check_rgb(name, key(k, sizeof k, "lights", i, "intensity"), l->rgb, err);
}

static btf_status check_mesh(const btf_mesh *m, const char *name, const char *k, btf_error *err)
{
    if (m->n_vertices < 3 || m->n_triangles < 1 || m->n_triangles > SCENE_MAX_TRIANGLES)
        return btf__fail(err, BTF_E_DATA, "%s: %s: %d vertices, %d triangles (at least 3 and "
                         "1, at most %d triangles)", name, k, m->n_vertices, m->n_triangles,
                         SCENE_MAX_TRIANGLES);
    if (!m->positions || !m->uvs || !m->indices)
        return btf__fail(err, BTF_E_DATA, "%s: %s: positions, uvs and indices are required",
                         name, k);
    for (size_t i = 0; i < 3 * (size_t)m->n_triangles; i++)
        if (m->indices[i] >= (uint32_t)m->n_vertices)
            return btf__fail(err, BTF_E_DATA, "%s: %s: index %zu is %u, beyond %d vertices",
                             name, k, i, m->indices[i], m->n_vertices);
    for (size_t i = 0; i < 3 * (size_t)m->n_vertices; i++)
        if (!isfinite(m->positions[i]) || fabsf(m->positions[i]) > SCENE_MAX_COORD ||
            (m->normals && !isfinite(m->normals[i])))
            return btf__fail(err, BTF_E_DATA, "%s: %s: vertex %zu: a position beyond +-%g or "
                             "a non-finite normal", name, k, i / 3, SCENE_MAX_COORD);
    for (size_t i = 0; i < 2 * (size_t)m->n_vertices; i++)
        if (!isfinite(m->uvs[i]) || fabsf(m->uvs[i]) > SCENE_MAX_COORD)
            return btf__fail(err, BTF_E_DATA, "%s: %s: vertex %zu: uv beyond +-%g", name, k,
                             i / 2, SCENE_MAX_COORD);
    return BTF_OK;
}

static btf_status check_object(const btf_object *o, int i, const char *name, btf_error *err)
{
    char k[64];
    btf_status rc;
    if (o->kind < BTF_OBJECT_PLANE || o->kind > BTF_OBJECT_MESH)
        return btf__fail(err, BTF_E_DATA, "%s: %s: unknown object kind %d", name,
                         key(k, sizeof k, "objects", i, "type"), (int)o->kind);
    if ((rc = check_vec(name, key(k, sizeof k, "objects", i, "center"), o->center, err)) ||
        (rc = check_length(name, key(k, sizeof k, "objects", i, "texture_scale"),
                           o->texture_scale, err)))
        return rc;
    if (!isfinite(o->rotation_deg) || fabs(o->rotation_deg) > SCENE_MAX_COORD)
        return btf__fail(err, BTF_E_DATA, "%s: %s: %g is not a finite angle within +-%g", name,
                         key(k, sizeof k, "objects", i, "rotation"), o->rotation_deg,
                         SCENE_MAX_COORD);
    if (o->kind == BTF_OBJECT_MESH)
        return check_mesh(&o->mesh, name, key(k, sizeof k, "objects", i, "file"), err);
    if ((rc = check_unit(name, key(k, sizeof k, "objects", i, "axis"), o->axis, err)))
        return rc;
    if (o->kind == BTF_OBJECT_PLANE)
        return check_length(name, key(k, sizeof k, "objects", i, "size"), o->size, err);
    if ((rc = check_length(name, key(k, sizeof k, "objects", i, "radius"), o->radius, err)))
        return rc;
    if (o->kind == BTF_OBJECT_CYLINDER)
        return check_length(name, key(k, sizeof k, "objects", i, "height"), o->height, err);
    return BTF_OK;
}

btf_status scene_check_named(const btf_scene *s, const char *name, btf_error *err)
{
    if (!s)
        return btf__fail(err, BTF_E_ARG, "%s: no scene given", name);
    btf_status rc = check_camera(&s->camera, name, err);
    if (rc)
        return rc;
    if ((rc = check_rgb(name, "background", s->background, err)))
        return rc;
    if (s->n_lights < 1 || !s->lights)
        return btf__fail(err, BTF_E_DATA, "%s: lights: at least one light is required", name);
    if (s->n_objects < 0 || (s->n_objects > 0 && !s->objects))
        return btf__fail(err, BTF_E_DATA, "%s: objects: %d objects and no array", name,
                         s->n_objects);
    for (int i = 0; i < s->n_lights; i++)
        if ((rc = check_light(&s->lights[i], i, name, err)))
            return rc;
    for (int i = 0; i < s->n_objects; i++)
        if ((rc = check_object(&s->objects[i], i, name, err)))
            return rc;
    return BTF_OK;
}

btf_status btf_scene_check(const btf_scene *s, btf_error *err)
{
    return scene_check_named(s, "scene", err);
}
