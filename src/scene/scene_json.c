/*
 * scene_json.c — btf_scene_load: a scene file (JSON, docs/scene.md) read
 * with cJSON into a btf_scene. The parser here is strict: unknown and
 * repeated keys, wrong types and missing required keys are errors naming
 * the file and the key path (objects[2].radius), so that a typo is never
 * silently ignored; the value rules are scene_check.c's, under the file's
 * name. Meshes are read by mesh_load.c, relative to the file's folder.
 */
#include "scene/scene.h"
#include "core/core.h"

#include <cjson/cJSON.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DEFAULT_FOV 45.0
#define DEFAULT_TEXTURE_SCALE 256.0

typedef struct jctx {
    const char *name;  /* the scene file, for messages */
    char dir[4096];    /* its folder: meshes are relative to it */
    btf_error *err;
} jctx;

/* "objects[2].radius" from a parent path ("" at the top) and a key. */
static const char *join(char *buf, size_t n, const char *parent, const char *k)
{
    snprintf(buf, n, "%s%s%s", parent, *parent ? "." : "", k);
    return buf;
}

static const char *type_name(const cJSON *j)
{
    if (cJSON_IsNumber(j)) return "a number";
    if (cJSON_IsString(j)) return "a string";
    if (cJSON_IsBool(j)) return "a boolean";
    if (cJSON_IsNull(j)) return "null";
    if (cJSON_IsArray(j)) return "an array";
    if (cJSON_IsObject(j)) return "an object";
    return "an invalid value";
}

/* Every key of obj is one of `known` (NULL-terminated), and none repeats. */
static btf_status check_keys(jctx *c, const cJSON *obj, const char *path,
                             const char *const *known)
{
    char p[128];
    for (const cJSON *it = obj->child; it; it = it->next) {
        int ok = 0;
        for (int i = 0; known[i]; i++)
            ok |= strcmp(it->string, known[i]) == 0;
        if (!ok) {
            char list[512] = "";
            for (int i = 0; known[i]; i++)
                snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", i ? ", " : "",
                         known[i]);
            return btf__fail(c->err, BTF_E_FORMAT, "%s: %s: unknown key (known here: %s)",
                             c->name, join(p, sizeof p, path, it->string), list);
        }
        for (const cJSON *q = obj->child; q != it; q = q->next)
            if (strcmp(q->string, it->string) == 0)
                return btf__fail(c->err, BTF_E_FORMAT, "%s: %s: key given twice", c->name,
                                 join(p, sizeof p, path, it->string));
    }
    return BTF_OK;
}

/* The member k of obj; NULL when absent (an error when required). */
static btf_status member(jctx *c, const cJSON *obj, const char *path, const char *k,
                         int required, const cJSON **out)
{
    *out = cJSON_GetObjectItemCaseSensitive(obj, k);
    if (!*out && required) {
        char p[128];
        return btf__fail(c->err, BTF_E_FORMAT, "%s: %s: missing (required)", c->name,
                         join(p, sizeof p, path, k));
    }
    return BTF_OK;
}

static btf_status as_number(jctx *c, const cJSON *j, const char *k, double *out)
{
    if (!cJSON_IsNumber(j))
        return btf__fail(c->err, BTF_E_FORMAT, "%s: %s: expected a number, got %s", c->name, k,
                         type_name(j));
    if (!isfinite(j->valuedouble))
        return btf__fail(c->err, BTF_E_DATA, "%s: %s: not a finite number", c->name, k);
    *out = j->valuedouble;
    return BTF_OK;
}

static btf_status get_number(jctx *c, const cJSON *obj, const char *path, const char *k,
                             int required, double def, double *out)
{
    const cJSON *j;
    char p[128];
    btf_status rc = member(c, obj, path, k, required, &j);
    *out = def;
    if (rc || !j)
        return rc;
    return as_number(c, j, join(p, sizeof p, path, k), out);
}

static btf_status as_vec3(jctx *c, const cJSON *j, const char *k, double out[3])
{
    if (!cJSON_IsArray(j) || cJSON_GetArraySize(j) != 3)
        return btf__fail(c->err, BTF_E_FORMAT, "%s: %s: expected an array of 3 numbers, got %s%s",
                         c->name, k, type_name(j), cJSON_IsArray(j) ? " of another length" : "");
    int i = 0;
    for (const cJSON *e = j->child; e; e = e->next, i++) {
        char p[144];
        snprintf(p, sizeof p, "%s[%d]", k, i);
        btf_status rc = as_number(c, e, p, &out[i]);
        if (rc)
            return rc;
    }
    return BTF_OK;
}

static btf_status get_vec3(jctx *c, const cJSON *obj, const char *path, const char *k,
                           int required, const double def[3], double out[3])
{
    const cJSON *j;
    char p[128];
    btf_status rc = member(c, obj, path, k, required, &j);
    for (int i = 0; i < 3 && def; i++)
        out[i] = def[i];
    if (rc || !j)
        return rc;
    return as_vec3(c, j, join(p, sizeof p, path, k), out);
}

/* A direction: normalised here; zero length is an error. */
static btf_status get_direction(jctx *c, const cJSON *obj, const char *path, const char *k,
                                int required, const double def[3], double out[3])
{
    btf_status rc = get_vec3(c, obj, path, k, required, def, out);
    if (rc)
        return rc;
    double l = v3_len(out);
    char p[128];
    if (!(l > 0.0))
        return btf__fail(c->err, BTF_E_DATA, "%s: %s: zero-length direction", c->name,
                         join(p, sizeof p, path, k));
    if (!isfinite(l))
        return btf__fail(c->err, BTF_E_DATA, "%s: %s: too long (%g)", c->name,
                         join(p, sizeof p, path, k), l);
    v3_scale(out, 1.0 / l);
    return BTF_OK;
}

/* An RGB triple, or one number for grey. */
static btf_status get_rgb(jctx *c, const cJSON *obj, const char *path, const char *k,
                          float def, float out[3])
{
    const cJSON *j;
    char p[128];
    btf_status rc = member(c, obj, path, k, 0, &j);
    out[0] = out[1] = out[2] = def;
    if (rc || !j)
        return rc;
    join(p, sizeof p, path, k);
    double v[3];
    if (cJSON_IsNumber(j)) {
        rc = as_number(c, j, p, &v[0]);
        v[1] = v[2] = v[0];
    } else if (cJSON_IsArray(j)) {
        rc = as_vec3(c, j, p, v);
    } else {
        return btf__fail(c->err, BTF_E_FORMAT, "%s: %s: expected [r, g, b] or a number, got %s",
                         c->name, p, type_name(j));
    }
    for (int i = 0; i < 3 && !rc; i++) {
        if (v[i] < 0.0 || v[i] > SCENE_MAX_COORD)
            return btf__fail(c->err, BTF_E_DATA, "%s: %s: %g is not in [0, %g]", c->name, p,
                             v[i], SCENE_MAX_COORD);
        out[i] = (float)v[i];
    }
    return rc;
}

static btf_status get_string(jctx *c, const cJSON *obj, const char *path, const char *k,
                             const char **out)
{
    const cJSON *j;
    char p[128];
    btf_status rc = member(c, obj, path, k, 1, &j);
    if (rc)
        return rc;
    if (!cJSON_IsString(j) || !j->valuestring)
        return btf__fail(c->err, BTF_E_FORMAT, "%s: %s: expected a string, got %s", c->name,
                         join(p, sizeof p, path, k), type_name(j));
    *out = j->valuestring;
    return BTF_OK;
}

static btf_status expect(jctx *c, const cJSON *j, const char *path, int object)
{
    if (object ? cJSON_IsObject(j) : cJSON_IsArray(j))
        return BTF_OK;
    return btf__fail(c->err, BTF_E_FORMAT, "%s: %s: expected %s, got %s", c->name, path,
                     object ? "an object" : "an array", type_name(j));
}

static btf_status parse_camera(jctx *c, const cJSON *root, btf_camera *cam)
{
    static const char *const known[] = {"position", "target", "up", "fov", NULL};
    static const double up[3] = {0.0, 1.0, 0.0};
    const cJSON *j;
    btf_status rc;
    if ((rc = member(c, root, "", "camera", 1, &j)) || (rc = expect(c, j, "camera", 1)) ||
        (rc = check_keys(c, j, "camera", known)) ||
        (rc = get_vec3(c, j, "camera", "position", 1, NULL, cam->position)) ||
        (rc = get_vec3(c, j, "camera", "target", 1, NULL, cam->target)) ||
        (rc = get_vec3(c, j, "camera", "up", 0, up, cam->up)) ||
        (rc = get_number(c, j, "camera", "fov", 0, DEFAULT_FOV, &cam->fov_deg)))
        return rc;
    return BTF_OK;
}

static btf_status parse_light(jctx *c, const cJSON *j, const char *path, btf_light *l)
{
    static const char *const dir_keys[] = {"type", "direction", "intensity", NULL};
    static const char *const point_keys[] = {"type", "position", "intensity", NULL};
    const char *type;
    btf_status rc;
    char p[128];
    if ((rc = expect(c, j, path, 1)) || (rc = get_string(c, j, path, "type", &type)))
        return rc;
    if (strcmp(type, "directional") == 0) {
        l->kind = BTF_LIGHT_DIRECTIONAL;
        if ((rc = check_keys(c, j, path, dir_keys)) ||
            (rc = get_direction(c, j, path, "direction", 1, NULL, l->direction)))
            return rc;
    } else if (strcmp(type, "point") == 0) {
        l->kind = BTF_LIGHT_POINT;
        if ((rc = check_keys(c, j, path, point_keys)) ||
            (rc = get_vec3(c, j, path, "position", 1, NULL, l->position)))
            return rc;
    } else {
        return btf__fail(c->err, BTF_E_FORMAT, "%s: %s: \"%s\" is not a light type "
                         "(directional, point)", c->name, join(p, sizeof p, path, "type"), type);
    }
    return get_rgb(c, j, path, "intensity", 1.0f, l->rgb);
}

/* The mesh file's path: as given when absolute, else under the scene's folder. */
static btf_status mesh_path(jctx *c, const char *file, const char *k, char *out, size_t n)
{
    int len = file[0] == '/' || !c->dir[0] ? snprintf(out, n, "%s", file)
                                          : snprintf(out, n, "%s/%s", c->dir, file);
    if (len < 0 || (size_t)len >= n)
        return btf__fail(c->err, BTF_E_ARG, "%s: %s: path too long", c->name, k);
    return BTF_OK;
}

static btf_status parse_object(jctx *c, const cJSON *j, const char *path, btf_object *o)
{
    static const char *const plane_keys[] = {"type", "center", "axis", "size", "texture_scale",
                                             "rotation", NULL};
    static const char *const sphere_keys[] = {"type", "center", "axis", "radius",
                                              "texture_scale", "rotation", NULL};
    static const char *const cyl_keys[] = {"type", "center", "axis", "radius", "height",
                                           "texture_scale", "rotation", NULL};
    static const char *const mesh_keys[] = {"type", "file", "center", "texture_scale",
                                            "rotation", NULL};
    static const double zero[3] = {0.0, 0.0, 0.0}, up[3] = {0.0, 1.0, 0.0};
    const char *type;
    btf_status rc;
    char p[128];
    if ((rc = expect(c, j, path, 1)) || (rc = get_string(c, j, path, "type", &type)))
        return rc;
    const char *const *known;
    if (strcmp(type, "plane") == 0)
        o->kind = BTF_OBJECT_PLANE, known = plane_keys;
    else if (strcmp(type, "sphere") == 0)
        o->kind = BTF_OBJECT_SPHERE, known = sphere_keys;
    else if (strcmp(type, "cylinder") == 0)
        o->kind = BTF_OBJECT_CYLINDER, known = cyl_keys;
    else if (strcmp(type, "mesh") == 0)
        o->kind = BTF_OBJECT_MESH, known = mesh_keys;
    else
        return btf__fail(c->err, BTF_E_FORMAT, "%s: %s: \"%s\" is not an object type (plane, "
                         "sphere, cylinder, mesh)", c->name, join(p, sizeof p, path, "type"),
                         type);
    if ((rc = check_keys(c, j, path, known)) ||
        (rc = get_vec3(c, j, path, "center", 0, zero, o->center)) ||
        (rc = get_number(c, j, path, "texture_scale", 0, DEFAULT_TEXTURE_SCALE,
                         &o->texture_scale)) ||
        (rc = get_number(c, j, path, "rotation", 0, 0.0, &o->rotation_deg)))
        return rc;
    if (o->kind == BTF_OBJECT_MESH) {
        const char *file;
        char full[4096 + 256];
        if ((rc = get_string(c, j, path, "file", &file)) ||
            (rc = mesh_path(c, file, join(p, sizeof p, path, "file"), full, sizeof full)))
            return rc;
        return scene_mesh_load(full, c->name, join(p, sizeof p, path, "file"), &o->mesh, c->err);
    }
    if ((rc = get_direction(c, j, path, "axis", 0, up, o->axis)))
        return rc;
    if (o->kind == BTF_OBJECT_PLANE)
        return get_number(c, j, path, "size", 1, 0.0, &o->size);
    if ((rc = get_number(c, j, path, "radius", 1, 0.0, &o->radius)))
        return rc;
    if (o->kind == BTF_OBJECT_CYLINDER)
        return get_number(c, j, path, "height", 1, 0.0, &o->height);
    return BTF_OK;
}

static btf_status parse_list(jctx *c, const cJSON *root, const char *k, int required,
                             btf_scene *s)
{
    const cJSON *j;
    btf_status rc;
    if ((rc = member(c, root, "", k, required, &j)) || !j || (rc = expect(c, j, k, 0)))
        return rc;
    int n = cJSON_GetArraySize(j);
    int lights = k[0] == 'l';
    void *arr = n ? btf__calloc((size_t)n, lights ? sizeof(btf_light) : sizeof(btf_object),
                                c->err)
                  : NULL;
    if (n && !arr)
        return btf__error_name(c->err, c->name);
    if (lights)
        s->lights = arr;
    else
        s->objects = arr;
    int i = 0;
    for (const cJSON *e = j->child; e; e = e->next, i++) {
        char p[64];
        snprintf(p, sizeof p, "%s[%d]", k, i);
        if (lights) {
            s->n_lights = i + 1;
            rc = parse_light(c, e, p, &s->lights[i]);
        } else {
            s->n_objects = i + 1; /* so that btf_scene_free frees a half-read mesh too */
            rc = parse_object(c, e, p, &s->objects[i]);
        }
        if (rc)
            return rc;
    }
    return BTF_OK;
}

/* Line and column (from 1) of byte offset off in text. */
static void line_column(const char *text, size_t off, int *line, int *col)
{
    *line = 1, *col = 1;
    for (size_t i = 0; i < off && text[i]; i++) {
        if (text[i] == '\n')
            (*line)++, *col = 1;
        else
            (*col)++;
    }
}

static btf_status parse_text(jctx *c, const char *text, size_t n, btf_scene *s)
{
    if (memchr(text, '\0', n))
        return btf__fail(c->err, BTF_E_FORMAT, "%s: not a JSON text (contains a NUL byte)",
                         c->name);
    const char *end = NULL;
    /* n + 1: the terminating NUL is inside the buffer, so that cJSON's
     * trailing-garbage check can see it. */
    cJSON *root = cJSON_ParseWithLengthOpts(text, n + 1, &end, 1);
    if (!root) {
        size_t off = end && end >= text && end <= text + n ? (size_t)(end - text) : n;
        int line, col;
        line_column(text, off, &line, &col);
        return btf__fail(c->err, BTF_E_FORMAT, "%s: invalid JSON at line %d, column %d%s", c->name,
                         line, col, off >= n ? " (unexpected end of file)" : "");
    }
    static const char *const known[] = {"camera", "background", "lights", "objects", NULL};
    btf_status rc;
    if (!(rc = expect(c, root, "(top level)", 1)) && !(rc = check_keys(c, root, "", known)) &&
        !(rc = parse_camera(c, root, &s->camera)) &&
        !(rc = get_rgb(c, root, "", "background", 0.0f, s->background)) &&
        !(rc = parse_list(c, root, "lights", 1, s)))
        rc = parse_list(c, root, "objects", 1, s);
    cJSON_Delete(root);
    return rc;
}

btf_status btf_scene_load(const char *path, btf_scene *out, btf_error *err)
{
    if (!out)
        return btf__fail(err, BTF_E_ARG, "btf_scene_load: no output scene");
    memset(out, 0, sizeof *out);
    if (!path || !*path)
        return btf__fail(err, BTF_E_ARG, "btf_scene_load: no file name");
    jctx c = {.name = path, .err = err};
    const char *slash = strrchr(path, '/');
    if (slash) {
        size_t n = (size_t)(slash - path);
        if (n >= sizeof c.dir)
            return btf__fail(err, BTF_E_ARG, "%s: path too long", path);
        memcpy(c.dir, path, n);
        c.dir[n ? n : 1] = '\0';
        if (n == 0)
            c.dir[0] = '/', c.dir[1] = '\0';
    }
    unsigned char *data;
    size_t n;
    btf_status rc = btf__read_file(path, SCENE_MAX_FILE_BYTES, &data, &n, err);
    if (rc)
        return rc;
    char *text = malloc(n + 1);
    if (!text) {
        free(data);
        return btf__fail(err, BTF_E_NOMEM, "%s: out of memory", path);
    }
    memcpy(text, data, n);
    text[n] = '\0';
    free(data);
    rc = parse_text(&c, text, n, out);
    free(text);
    if (!rc)
        rc = scene_check_named(out, path, err);
    if (rc)
        btf_scene_free(out);
    return rc;
}
